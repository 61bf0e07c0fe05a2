//! The `lod` bench's camera paths with the pool's new entries placed on the GPU:
//! `cargo run --release -p strata-bench --bin lod_gpu [-- frames]`.
//!
//! The scene, camera, base count and paths of the `lod` bench (bunny, 3:1 field,
//! seed 3; the default scene without the shared meshes; the first frame shows about
//! 10^6 samples; `count +1%`, `dolly in 1%`, `dolly out 1%`, `orbit 1 degree`, each
//! `frames` steps, default 10, after 30 untimed ones). Per frame the CPU runs
//! `LodPool::update` on a pool that lists ranks only (`Placement::Elsewhere`) and
//! `GpuLodPool::sync_placed`: the ranks the update appended are uploaded (4 bytes
//! each) and the GPU's progressive pass places them, then expands them into the sample
//! buffer. A pool that places its entries on the CPU (the default) is updated along the
//! same path, for comparison and as the reference of the GPU's sites. Per path it
//! prints the medians over the frames of the CPU time of the placing pool's update, of
//! the listing pool's update, of the sync (writing the ranks and recording the passes;
//! the GPU's work is not waited for, as in a frame loop) and of the last two together
//! (a frame's CPU cost with GPU placement), the bytes uploaded per frame, and how the
//! GPU copy's sites differ from the placing pool's at the end of the path (faces,
//! largest deviation over the bounding-box diagonal, samples beyond 1e-5); it fails
//! when the two pools list other ranks. It also counts the heap allocations each
//! pool's update and the sync make per frame (mean over the timed frames). On the software
//! adapter the GPU's own time is not representative, and the device is waited for
//! after every frame so frames do not pile up. `LOD_GPU_SHOWN=n` sets the samples the
//! first frame shows (default 10^6; the software adapter's 128 MiB binding limit holds
//! the records of about 2 * 10^6 pool entries, so use 2 * 10^5 there). As in the
//! `lod` bench, the frame loop runs on a worker of rayon's global pool
//! (`use_current_thread`); `LOD_OUTSIDE_POOL=1` calls from outside the pool.
//!
//! `LOD_GPU_CPU_ONLY=1` opens no adapter and runs the ranks-only pool's updates
//! alone, printing each path's update times: the CPU side of a frame with GPU
//! placement, for instruction counts under `valgrind --tool=callgrind` (with
//! `RAYON_NUM_THREADS=1`: one run with `frames` steps less one with none, over the
//! frames, is the instructions per timed frame). `LOD_GPU_PATH=name` runs only the
//! paths whose name contains `name`.

use std::alloc::System;
use std::time::Instant;

use stats_alloc::{INSTRUMENTED_SYSTEM, StatsAlloc};
use strata_bench::lod_camera::{LodCamera, lod_scene};
use strata_bench::median;
use strata_engine::sample::lod::{Budget, Placement, ViewLod};
use strata_engine::sample::{LodPool, Sampler};
use strata_systems::gpu::{GpuContext, GpuLodPool, GpuSampleBuffer, GpuSampler};

/// The system allocator, counting allocations (all threads).
#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Allocations so far, reallocations included.
fn allocations() -> usize {
    let stats = GLOBAL.stats();
    stats.allocations + stats.reallocations
}

const SEED: u64 = 3;
const WARM_UP: i32 = 30;

type Path<'a> = Box<dyn Fn(i32) -> (ViewLod, f64) + 'a>;

/// The base count whose first frame shows about `shown` samples (the `lod` bench's
/// calibration).
fn calibrate_base(s: &Sampler, first: &ViewLod, shown_target: f64) -> f64 {
    let probe = 100_000.0;
    let pool = LodPool::new(s, SEED, probe as u32, 1_000_000);
    let mut fades = vec![0.0f32; pool.len()];
    pool.fades_into(s, first, probe, &mut fades);
    let shown = fades.iter().filter(|&&f| f > 0.0).count().max(1) as f64;
    probe * shown_target / shown
}

/// The `lod` bench's paths (view and base count at frame `t`) from base count `base`.
fn paths(camera: &LodCamera, base: f64) -> [(&'static str, Path<'_>); 4] {
    let (centre, start, first) = (camera.centre, camera.start, camera.view(camera.start));
    let dolly = |factor: f64| -> Path { Box::new(move |t| (camera.dolly(factor, t), base)) };
    let orbit = Box::new(move |t| {
        let turn = glam::DQuat::from_rotation_y(f64::from(t).to_radians());
        (camera.view(centre + turn * (start - centre)), base)
    });
    [
        (
            "count +1%",
            Box::new(move |t| (first, base * 1.01f64.powi(t))),
        ),
        ("dolly in 1%", dolly(0.99)),
        ("dolly out 1%", dolly(1.01)),
        ("orbit 1 degree", orbit),
    ]
}

/// `LOD_GPU_CPU_ONLY`: the ranks-only pool's updates along the paths named `chosen`,
/// without an adapter; prints each path's median update time.
fn cpu_only(s: &Sampler, frames: usize, chosen: &str) -> Result<(), Box<dyn std::error::Error>> {
    let camera = LodCamera::around(s.mesh().positions());
    let shown: f64 = match std::env::var("LOD_GPU_SHOWN") {
        Ok(v) => v.parse()?,
        Err(_) => 1e6,
    };
    let base = calibrate_base(s, &camera.view(camera.start), shown);
    let listing = LodPool::new_with(s, SEED, (base as u32, 8_000_000), Placement::Elsewhere);
    println!("base count {base:.0}; {frames} frames per path, ranks only, no adapter.\n");
    println!("| path | update, ranks only, ms | entries at end |");
    println!("| --- | --- | --- |");
    for (name, path) in paths(&camera, base)
        .iter()
        .filter(|(n, _)| n.contains(chosen))
    {
        let mut pool = listing.clone();
        let mut times = Vec::new();
        for t in -WARM_UP..=frames as i32 {
            let (v, b) = path(t);
            let clock = Instant::now();
            pool.update(s, &v, Budget::Base(b))?;
            if t > 0 {
                times.push(clock.elapsed().as_secs_f64() * 1e3);
            }
        }
        println!("| {name} | {:.3} | {} |", median(times), pool.len());
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames = strata_bench::repeats_arg(10)?.max(1);
    if std::env::var_os("LOD_OUTSIDE_POOL").is_none() {
        rayon::ThreadPoolBuilder::new()
            .use_current_thread()
            .build_global()?;
    }
    let (file, scene) = lod_scene(SEED)?;
    let s = &scene.sampler;
    let chosen = std::env::var("LOD_GPU_PATH").unwrap_or_default();
    if std::env::var_os("LOD_GPU_CPU_ONLY").is_some() {
        return cpu_only(s, frames, &chosen);
    }
    let ctx = GpuContext::headless(&Default::default())?;
    let (device, queue) = (&ctx.device, &ctx.queue);
    let gpu = GpuSampler::new(device, s)?;
    let camera = LodCamera::around(scene.mesh.positions());
    let first = camera.view(camera.start);
    let shown: f64 = match std::env::var("LOD_GPU_SHOWN") {
        Ok(v) => v.parse()?,
        Err(_) => 1e6,
    };
    let base = calibrate_base(s, &first, shown);
    let prefix = LodPool::new(s, SEED, base as u32, 8_000_000);
    let listing = LodPool::new_with(s, SEED, (base as u32, 8_000_000), Placement::Elsewhere);
    println!(
        "scene `{file}`: {} faces; base count {base:.0}; adapter {}; {frames} frames per path.\n",
        scene.mesh.face_count(),
        ctx.adapter_summary(),
    );
    println!(
        "| path | update, CPU placement, ms | update, ranks only, ms | sync (GPU placement) ms | CPU per frame with GPU placement, ms | upload KB per frame, mean | allocations per update, placing / ranks only, mean | allocations per sync, mean | entries at end | differ in face | largest deviation | beyond 1e-5 |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let paths = paths(&camera, base);
    let (lo, hi) = s.mesh().bounds();
    let diagonal = (hi - lo).length();
    for (name, path) in paths.iter().filter(|(name, _)| name.contains(&chosen)) {
        let (mut pool, mut ranks_only) = (prefix.clone(), listing.clone());
        let mut gpu_pool = GpuLodPool::new(device, base)?;
        let mut samples = GpuSampleBuffer::new(device)?;
        let mut times: [Vec<f64>; 4] = Default::default();
        let (mut bytes, mut allocated) = (vec![], [0; 3]);
        for t in -WARM_UP..=frames as i32 {
            let (v, b) = path(t);
            let (clock, before) = (Instant::now(), allocations());
            pool.update(s, &v, Budget::Base(b))?;
            let placed = clock.elapsed().as_secs_f64();
            let (clock, between) = (Instant::now(), allocations());
            let update = ranks_only.update(s, &v, Budget::Base(b))?;
            let listed = clock.elapsed().as_secs_f64();
            if t > 0 {
                allocated[0] += between - before;
                allocated[1] += allocations() - between;
            }
            let (clock, before) = (Instant::now(), allocations());
            let sent = gpu_pool.sync_placed(
                device,
                queue,
                (&ranks_only, &update.change),
                &gpu,
                &mut samples,
            )?;
            let synced = clock.elapsed().as_secs_f64();
            if t > 0 {
                allocated[2] += allocations() - before;
            }
            ctx.wait_idle("placing the pool's entries")?;
            if pool.ranks() != ranks_only.ranks() {
                return Err(format!("{name}, frame {t}: the pools list other ranks").into());
            }
            if t > 0 {
                for (row, ms) in times
                    .iter_mut()
                    .zip([placed, listed, synced, listed + synced])
                {
                    row.push(ms * 1e3);
                }
                bytes.push(sent as f64 / 1e3);
            }
        }
        let sites = gpu_pool.read_sites(device, queue)?;
        let (mut faces, mut beyond, mut worst) = (0, 0, 0.0f64);
        for (g, c) in sites.iter().zip(pool.sites()) {
            faces += usize::from(g.face != c.face || g.segment != c.segment);
            let d = (g.position_on(s.mesh()).zip(c.position_on(s.mesh())))
                .map_or(f64::INFINITY, |(p, q)| p.distance(q) / diagonal);
            worst = worst.max(d);
            beyond += usize::from(d > 1e-5);
        }
        let [placed, listed, synced, total] = times.map(median);
        println!(
            "| {name} | {placed:.3} | {listed:.3} | {synced:.3} | {total:.3} | {:.1} | {:.1} / {:.1} | {:.1} | {} | {faces} | {worst:.2e} | {beyond} |",
            bytes.iter().sum::<f64>() / bytes.len() as f64,
            allocated[0] as f64 / frames as f64,
            allocated[1] as f64 / frames as f64,
            allocated[2] as f64 / frames as f64,
            pool.len(),
        );
    }
    Ok(())
}
