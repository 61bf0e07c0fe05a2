//! The ECS engine's level of detail and per-frame resampling, paced like a renderer's
//! frames, with the frame's thread in or out of rayon's pool:
//! `cargo run --release -p strata-bench --bin lod_ecs [-- frames]`.
//!
//! The streaming engine (`hot_reload::StreamingEngine`, what `strata view` runs) loads
//! the bunny scene (3:1 field); updates run 8 ms apart, as frames that wait for the
//! display do (rayon's workers fall asleep between them).
//!
//! - `lod`: a [`Lod`] component on the mesh follows the `lod` bench's dolly in (the same
//!   camera and base count, 30 untimed frames, then `frames` timed ones, default 20);
//!   the time is the update's own (`LodState::update`, `update_lod_pools`).
//!   `LOD_ECS_SHOWN=S` gives the component a point budget of `S` samples shown.
//! - `resample`: 10^6 samples drawn every update (`sample_every_update`, the
//!   `sample_meshes` system, on bevy's threads); median and 90th percentile of 40.
//!
//! `LOD_ECS_POOL` chooses rayon's global pool: `cores+1` (the default,
//! `frame_thread::join_rayon_pool` as the `strata` binary calls it: the main thread,
//! which runs the schedule and with it `update_lod_pools`, plus a worker per core), `cores` (the main thread and one worker
//! fewer) or `outside` (rayon's default pool; the main thread is not in it).

use std::time::{Duration, Instant};

use bevy_ecs::entity::Entity;

use strata_bench::lod_camera::LodCamera;
use strata_systems::ecs::{EngineSettings, Lod, LodState, MeshSampler, SamplingSettings, Stage};
use strata_systems::hot_reload::StreamingEngine;

/// The `lod` bench's base count: the first frame of its dolly shows about 10^6 samples.
const BASE: u32 = 3_123_048;
/// Time between the starts of two updates.
const FRAME: Duration = Duration::from_millis(8);
/// Untimed frames before the timed ones, as in the `lod` bench.
const WARM_UP: i32 = 30;
/// Updates in the resampling run.
const RESAMPLES: usize = 40;

fn median(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[v.len() * 9 / 10])
}

/// One paced update; returns the time of its `Sampling` stage in ms.
fn frame(engine: &mut StreamingEngine) -> f64 {
    let start = Instant::now();
    engine.clear_stats();
    engine.update();
    let took = engine.stats().time_of(Stage::Sampling).as_secs_f64() * 1e3;
    if let Some(left) = FRAME.checked_sub(start.elapsed()) {
        std::thread::sleep(left);
    }
    took
}

/// The time of a mesh's last level-of-detail update in ms (also when it drew nothing,
/// which records no `Sampling` stage), and the base count it used.
fn lod_update(state: Option<&LodState>) -> (f64, f64) {
    state.map_or((0.0, 0.0), |s| (s.update.as_secs_f64() * 1e3, s.base))
}

/// Sets rayon's global pool as `LOD_ECS_POOL` asks (see the module docs); whether the
/// main thread is in it.
fn join_pool(pool: &str) -> Result<bool, Box<dyn std::error::Error>> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match pool {
        "cores+1" => {
            strata_systems::frame_thread::join_rayon_pool()?;
            Ok(true)
        }
        "cores" => {
            rayon::ThreadPoolBuilder::new()
                .use_current_thread()
                .num_threads(cores)
                .build_global()?;
            Ok(true)
        }
        "outside" => Ok(false),
        other => Err(format!("LOD_ECS_POOL={other}: cores+1, cores or outside").into()),
    }
}

/// Updates `engine` until its mesh entity has a sampler (at most 300 s from
/// `started`); the entity.
fn built_mesh(
    engine: &mut StreamingEngine,
    started: Instant,
) -> Result<Entity, Box<dyn std::error::Error>> {
    loop {
        engine.update();
        engine.settle(Duration::from_secs(300));
        let built = engine.mesh_entity().filter(|&e| {
            engine
                .world
                .get::<MeshSampler>(e)
                .is_some_and(|s| s.0.is_some())
        });
        if let Some(e) = built {
            return Ok(e);
        }
        if started.elapsed() > Duration::from_secs(300) {
            return Err("the scene did not build in 300 s".into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The `lod` bench's dolly in on `mesh` through the ECS engine, with a point budget of
/// `shown`: [`WARM_UP`] untimed frames, then `frames` timed ones; each timed frame's
/// update time (ms) and base count. Waits for the pool to build (at most 600 s from
/// `started`) before the first frame.
fn dolly(
    engine: &mut StreamingEngine,
    mesh: Entity,
    camera: &LodCamera,
    (shown, frames): (Option<u32>, usize),
    started: Instant,
) -> Result<(Vec<f64>, Vec<f64>), Box<dyn std::error::Error>> {
    engine.world.entity_mut(mesh).insert((
        Lod {
            view: camera.dolly(0.99, -WARM_UP),
            base: BASE,
            budget: 8_000_000,
            shown,
        },
        LodState::default(),
    ));
    while engine
        .world
        .get::<LodState>(mesh)
        .is_some_and(|s| s.pool.is_none())
    {
        frame(engine);
        if started.elapsed() > Duration::from_secs(600) {
            return Err("the level-of-detail pool did not build".into());
        }
    }
    let (mut lod, mut bases) = (vec![], vec![]);
    for t in -WARM_UP..=frames as i32 {
        if let Some(mut l) = engine.world.get_mut::<Lod>(mesh) {
            l.view = camera.dolly(0.99, t);
        }
        frame(engine);
        let (took, base) = lod_update(engine.world.get::<LodState>(mesh));
        if t > 0 {
            lod.push(took);
            bases.push(base);
        }
    }
    engine.world.entity_mut(mesh).remove::<(Lod, LodState)>();
    Ok((lod, bases))
}

/// 10^6 samples drawn every update on `mesh`: the median and 90th percentile of
/// [`RESAMPLES`] updates' sampling, ms.
fn resample(engine: &mut StreamingEngine, mesh: Entity) -> (f64, f64) {
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = true;
    if let Some(mut s) = engine.world.get_mut::<SamplingSettings>(mesh) {
        s.count = 1_000_000;
    }
    frame(engine);
    let resample: Vec<f64> = (0..RESAMPLES).map(|_| frame(engine)).collect();
    median(resample)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames = strata_bench::repeats_arg(20)?.max(1);
    let pool = std::env::var("LOD_ECS_POOL").unwrap_or_else(|_| "cores+1".into());
    let shown: Option<u32> = match std::env::var("LOD_ECS_SHOWN") {
        Ok(s) => Some(s.parse()?),
        Err(_) => None,
    };
    let inside = join_pool(&pool)?;
    strata_bench::shared_mesh_dir()?;
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/stanford-bunny-anisotropic.ron");
    let mut engine = StreamingEngine::watch(&scene)?;
    let started = Instant::now();
    let mesh = built_mesh(&mut engine, started)?;
    let positions = engine
        .world
        .get::<MeshSampler>(mesh)
        .and_then(|s| s.0.as_ref())
        .map(|s| s.mesh().positions().to_vec())
        .ok_or("no sampler")?;
    let camera = LodCamera::around(&positions);
    let (lod, bases) = dolly(&mut engine, mesh, &camera, (shown, frames), started)?;
    let mean = lod.iter().sum::<f64>() / lod.len() as f64;
    let (lod_median, _) = median(lod);
    let (r_median, r_p90) = resample(&mut engine, mesh);
    println!(
        "rayon pool `{pool}` ({} threads, main thread {}):",
        rayon::current_num_threads(),
        if inside { "in it" } else { "outside" }
    );
    let budget = shown.map_or(String::new(), |s| {
        let (lo, hi) = bases.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &b| {
            (lo.min(b), hi.max(b))
        });
        format!(", point budget {s} (base count {lo:.0} to {hi:.0})")
    });
    println!(
        "- lod, dolly in 1%{budget}: update {mean:.3} ms mean, {lod_median:.3} ms median over {frames} frames"
    );
    println!(
        "- resample 10^6 every update: {r_median:.1} ms median, {r_p90:.1} ms 90th percentile"
    );
    Ok(())
}
