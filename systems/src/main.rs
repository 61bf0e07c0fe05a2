//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    // The main thread joins rayon's global pool, which keeps a worker per core beside
    // it. Parallel work the main thread starts (`render`'s frames; the level-of-detail
    // update, which runs on the schedule's thread in `view`) then begins on it at once
    // instead of waiting for a sleeping worker to wake (1-2 ms on a 2-core machine),
    // and work that bevy's threads start (`view`'s and `watch`'s resampling) still
    // finds a worker per core while the main thread waits outside rayon: with only the
    // cores' count, a 10^6-sample resampling took twice as long (bench/README.md).
    let cores = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    // Fails only if a global pool exists already; then that one serves.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .num_threads(cores + 1)
        .build_global();
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
