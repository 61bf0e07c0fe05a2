//! The frame's thread as a rayon worker: what the `strata` binary does at start-up, and
//! what an engine embedding the library should do on the thread that runs its frame (or
//! its ECS schedule, where [`update_lod_pools`](crate::ecs::update_lod_pools) runs).
//!
//! Parallel work started from a thread outside rayon's pool waits for a sleeping worker
//! to wake: 1-2 ms on a 2-core virtual machine, against tens of microseconds from a
//! worker (bench/README.md, *Level of detail*). A pool built with
//! `ThreadPoolBuilder::use_current_thread` makes the calling thread a worker, so its
//! work starts on it at once. The pool keeps as many other workers as cores beside it:
//! while that thread waits outside rayon (in bevy's scope, say), work that bevy's
//! threads start still finds a worker per core. With one fewer, `strata view`'s
//! resampling of 10^6 samples took 110 ms instead of 55 (the `lod_ecs` bench).

/// Makes the calling thread a worker of rayon's global pool, beside one worker per core
/// (or `RAYON_NUM_THREADS` workers, where that is set to a positive count), and returns
/// the pool's thread count. Call it once, before anything uses rayon: the global pool
/// is built once per process, and this fails when it exists already (then that pool
/// serves, unchanged).
pub fn join_rayon_pool() -> Result<usize, rayon::ThreadPoolBuildError> {
    let workers = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .num_threads(workers + 1)
        .build_global()?;
    Ok(workers + 1)
}
