//! Edits while frames run (issue 20): the bunny in `strata watch`'s engine, resampled
//! every frame at 10^5 samples as `strata view` does, paced at 60 frames per second.
//!
//! `cargo run --release -p strata-bench --bin reload_latency -- [repeats]` (default 5).
//! Scenarios, each timed per frame:
//! - a field-file save on a cap of about 10% of the faces (a region rebuild), and a
//!   scene save with a new segmentation seed (a whole rebuild): the longest frame
//!   beyond its own sampling while the build runs, and the time from the save to the
//!   first frame that draws the new result, against the watcher's debounce plus the
//!   scene load plus the build plus two frames;
//! - 100 field edits in one second through the world (no debounce): builds launched,
//!   completed and cancelled, and the longest wait from a cancel to its build's end;
//! - eight meshes in one world, one edited: the stage runs of the other seven.
//!
//! Prints a table and writes `bench/results/reload_latency.json` (keys documented in
//! bench/README.md, "Edits off the frame").

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use serde_json::json;
use strata_engine::field::{FieldSpec, format_field_file};
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::surface::SurfaceOptions;
use strata_systems::ecs::{EngineSettings, FieldData, MeshBundle, MeshSampler, Stage};
use strata_systems::hot_reload::StreamingEngine;

/// The frame period the loop paces to (60 Hz).
const FRAME: Duration = Duration::from_micros(16_667);
/// Samples per frame, as `strata view` at 10^5.
const COUNT: u64 = 100_000;

/// Frames from a change to the first frame that draws its result.
#[derive(Debug, Default)]
struct Reload {
    /// Per frame: wall time of the update beyond its sampling.
    beyond_sampling: Vec<Duration>,
    /// Save (or edit) to the end of the first frame with the new sampler.
    first_new_frame: Duration,
    /// The world applying the change (the frame that started the build) to the end of
    /// the first frame with the new sampler.
    after_apply: Duration,
    /// Time the build's stages took (segmentation to chains), as recorded.
    build: Duration,
    /// Time the watcher took to load the scene (mesh, field).
    load: Duration,
    /// The two frame periods before the new result was drawn (the frame that saw the
    /// build end, and the one before).
    two_frames: Duration,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?;
    let dir = tempfile::tempdir()?;
    let Bunny {
        mesh,
        field_path,
        scene,
    } = write_bunny(dir.path())?;
    let mut engine = StreamingEngine::watch(&scene)?;
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = true;
    first_build(&mut engine, &mesh)?;

    // Field saves on a ~10% cap, alternating two directions: region rebuilds.
    let cap = strata_bench::cap_height(&mesh, 0.1);
    let mut region = Vec::new();
    for i in 0..repeats {
        let turned = if i % 2 == 0 { DVec3::Y } else { DVec3::Z };
        let text = format_field_file(&strata_bench::cap_field(&mesh, cap, turned)?);
        region.push(reload(&mut engine, || {
            strata_engine::io::write_atomically(&field_path, |w| w.write_all(text.as_bytes()))
        })?);
    }
    // Scene saves with a new segmentation seed: whole rebuilds.
    let mut whole = Vec::new();
    for i in 0..repeats {
        let text = scene_text(i as u64 + 1);
        whole.push(reload(&mut engine, || std::fs::write(&scene, &text))?);
    }
    let burst = burst(&mut engine, &mesh, cap)?;
    let others = eight_meshes(&mut engine, &mesh)?;
    for e in engine.take_errors() {
        eprintln!("error: {e}");
    }

    println!(
        "\n| change | frames | max frame beyond sampling (ms) | save to first new frame, median (ms) | load (watcher), median (ms) | build, median (ms) | applied to new frame minus build, median (ms) | every run within build + 2 frames (as they ran) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let max_frame = region
        .iter()
        .chain(&whole)
        .flat_map(|r| r.beyond_sampling.iter().copied())
        .max()
        .unwrap_or_default()
        .max(burst.2);
    let region_json = summary("field on a 10% cap (region rebuild)", &region);
    let whole_json = summary("segmentation seed (whole rebuild)", &whole);
    println!(
        "\n100 field edits in {:.2} s: {} builds launched, {} completed, {} cancelled (cancel to end at most {:.0} ms); max frame beyond sampling {:.1} ms",
        burst.0.as_secs_f64(),
        burst.1.launched,
        burst.1.completed,
        burst.1.cancelled,
        ms(burst.1.max_cancel_wait),
        ms(burst.2)
    );
    println!("eight meshes, one edited: stage runs of the other seven: {others}");
    let report = json!({
        "mesh": "stanford-bunny",
        "faces": mesh.face_count(),
        "samples_per_frame": COUNT,
        "repeats": repeats,
        "region_rebuild": region_json,
        "whole_rebuild": whole_json,
        "max_frame_ms_during_reload": ms(max_frame),
        "first_new_frame_ms": region_json["first_new_frame_ms"],
        "burst": {
            "edits": 100,
            "seconds": burst.0.as_secs_f64(),
            "launched": burst.1.launched,
            "completed": burst.1.completed,
            "max_cancel_wait_ms": ms(burst.1.max_cancel_wait),
            "max_frame_ms": ms(burst.2),
        },
        "cancelled_jobs": burst.1.cancelled,
        "eight_meshes_other_runs": others,
    });
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results/reload_latency.json");
    std::fs::write(&out, serde_json::to_string_pretty(&report)? + "\n")?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The bunny's scene in a temporary folder: its mesh, the field file and the scene.
struct Bunny {
    mesh: Arc<TriMesh>,
    field_path: PathBuf,
    scene: PathBuf,
}

/// Writes the bunny as PLY (so that the field file's vertex order is the mesh's), a
/// field file and a scene with segmentation seed 0 into `dir`.
fn write_bunny(dir: &Path) -> Result<Bunny, Box<dyn std::error::Error>> {
    let src = strata_bench::shared_mesh_dir()?.join("stanford-bunny.obj");
    let mesh = strata_engine::io::load(&src)?;
    let ply = dir.join("bunny.ply");
    strata_engine::io::write_mesh_ply(&ply, &mesh, None)?;
    let mesh = Arc::new(strata_engine::io::load(&ply)?);
    let field_path = dir.join("bunny.field");
    std::fs::write(
        &field_path,
        format_field_file(&strata_bench::cap_field(&mesh, f64::INFINITY, DVec3::Z)?),
    )?;
    let scene = dir.join("bunny.ron");
    std::fs::write(&scene, scene_text(0))?;
    Ok(Bunny {
        mesh,
        field_path,
        scene,
    })
}

/// The bunny's scene file with segmentation seed `seed`.
fn scene_text(seed: u64) -> String {
    format!(
        "(mesh: File(\"bunny.ply\"), field: File(path: \"bunny.field\"), sampling: (count: {COUNT}, seed: 1), segment: (seed: {seed}))"
    )
}

/// Updates `engine` until its first build is done and a frame drew its samples (at
/// most 300 s), and prints how long that took.
fn first_build(
    engine: &mut StreamingEngine,
    mesh: &TriMesh,
) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    while engine.samples().len() != COUNT as usize || !engine.is_idle() {
        if t.elapsed() > Duration::from_secs(300) {
            return Err(format!("first build: {:?}", engine.take_errors()).into());
        }
        engine.wait(Duration::from_millis(50));
        engine.update();
    }
    println!(
        "bunny: {} faces, {COUNT} samples per frame; first build and samples {:.0} ms",
        mesh.face_count(),
        ms(t.elapsed())
    );
    Ok(())
}

/// Prints the table row of one scenario's `runs` and returns its JSON entry.
fn summary(name: &str, runs: &[Reload]) -> serde_json::Value {
    let max_frame = runs
        .iter()
        .flat_map(|r| r.beyond_sampling.iter().copied())
        .max()
        .unwrap_or_default();
    let mut first: Vec<Duration> = runs.iter().map(|r| r.first_new_frame).collect();
    let mut build: Vec<Duration> = runs.iter().map(|r| r.build).collect();
    let mut load: Vec<Duration> = runs.iter().map(|r| r.load).collect();
    // The frame that applies the change starts the build; the build's result is
    // drawn by the frame after it ends: build + 2 frames after that first frame
    // started.
    let bound_met = runs
        .iter()
        .all(|r| r.after_apply <= r.build + r.two_frames.max(2 * FRAME));
    let mut slack: Vec<Duration> = runs
        .iter()
        .map(|r| r.after_apply.saturating_sub(r.build))
        .collect();
    let worst = slack.iter().copied().max().unwrap_or_default();
    let frames: usize = runs.iter().map(|r| r.beyond_sampling.len()).sum();
    println!(
        "| {name} | {frames} | {:.1} | {:.0} | {:.0} | {:.0} | {:.0} | {} |",
        ms(max_frame),
        ms(median(&mut first)),
        ms(median(&mut load)),
        ms(median(&mut build)),
        ms(median(&mut slack)),
        if bound_met {
            "yes".to_owned()
        } else {
            format!("no (worst {:.0} ms)", ms(worst))
        }
    );
    json!({
        "frames": frames,
        "max_frame_ms_during_reload": ms(max_frame),
        "first_new_frame_ms": ms(median(&mut first)),
        "load_ms": ms(median(&mut load)),
        "build_ms": ms(median(&mut build)),
        "apply_to_new_frame_minus_build_ms": ms(median(&mut slack)),
        "apply_to_new_frame_minus_build_max_ms": ms(worst),
        "within_build_plus_2_frames": bound_met,
    })
}

/// Saves with `save`, then runs paced frames until the first frame that draws the new
/// build's sampler.
fn reload(
    engine: &mut StreamingEngine,
    save: impl FnOnce() -> std::io::Result<()>,
) -> Result<Reload, Box<dyn std::error::Error>> {
    let completed = engine.builds().completed;
    engine.clear_stats();
    let saved = Instant::now();
    save()?;
    let mut out = Reload::default();
    let mut applied = None;
    let mut period = Duration::ZERO;
    loop {
        let start = Instant::now();
        let (beyond, update) = frame(engine);
        out.beyond_sampling.push(beyond);
        if applied.is_none() && engine.stats().runs_of(Stage::Scene) > 0 {
            applied = Some(start);
        }
        if engine.builds().completed > completed && engine.is_idle() {
            // The frame is drawn when its update ends (before the pacing sleep).
            let drawn = start + update;
            out.first_new_frame = drawn - saved;
            out.after_apply = applied.map_or(Duration::ZERO, |t| drawn - t);
            out.two_frames = period + update;
            break;
        }
        period = start.elapsed();
        if saved.elapsed() > Duration::from_secs(120) {
            return Err(format!("no new result in 120 s: {:?}", engine.take_errors()).into());
        }
    }
    let stats = engine.stats();
    out.load = stats.time_of(Stage::Scene);
    out.build = [
        Stage::Segmentation,
        Stage::Parameterization,
        Stage::Curves,
        Stage::Chains,
    ]
    .into_iter()
    .map(|s| stats.time_of(s))
    .sum();
    // A few more frames, as a view would run.
    for _ in 0..3 {
        out.beyond_sampling.push(frame(engine).0);
    }
    Ok(out)
}

/// One paced frame: the update, then sleep to the next frame. Returns the update's
/// wall time beyond its sampling, and the whole update.
fn frame(engine: &mut StreamingEngine) -> (Duration, Duration) {
    let start = Instant::now();
    let before = engine.stats().time_of(Stage::Sampling);
    engine.update();
    let update = start.elapsed();
    let sampling = engine
        .stats()
        .time_of(Stage::Sampling)
        .saturating_sub(before);
    if let Some(left) = FRAME.checked_sub(start.elapsed()) {
        std::thread::sleep(left);
    }
    (update.saturating_sub(sampling), update)
}

/// 100 field edits in one second straight into the world, frames running; then frames
/// until every build is applied. Returns the burst's length, the build counts over it,
/// and the longest frame beyond sampling.
fn burst(
    engine: &mut StreamingEngine,
    mesh: &TriMesh,
    cap: f64,
) -> Result<(Duration, strata_systems::ecs::JobCounts, Duration), Box<dyn std::error::Error>> {
    let entity = engine.mesh_entity().ok_or("no mesh entity")?;
    let fields = [
        Arc::new(strata_bench::cap_field(mesh, cap, DVec3::Y)?),
        Arc::new(strata_bench::cap_field(
            mesh,
            cap,
            DVec3::new(0.3, 0.2, 1.0),
        )?),
    ];
    let before = engine.builds();
    let mut longest = Duration::ZERO;
    let (mut made, mut seen) = (0u64, 0u64);
    let start = Instant::now();
    // An editor making an edit every 10 ms while the view runs its frames: each frame
    // applies the edits due by then (the engine sees the newest).
    while made < 100 {
        let due = (start.elapsed().as_millis() / 10 + 1).min(100) as u64;
        if due > made {
            made = due;
            seen += 1;
            let mut field = engine
                .world
                .get_mut::<FieldData>(entity)
                .ok_or("no field")?;
            field.0 = fields[made as usize % 2].clone();
        }
        longest = longest.max(frame(engine).0);
    }
    let took = start.elapsed();
    while !engine.is_idle() {
        longest = longest.max(frame(engine).0);
        if start.elapsed() > Duration::from_secs(120) {
            return Err("the burst's builds did not finish in 120 s".into());
        }
    }
    let after = engine.builds();
    let counts = strata_systems::ecs::JobCounts {
        launched: after.launched - before.launched,
        completed: after.completed - before.completed,
        cancelled: after.cancelled - before.cancelled,
        failed: after.failed - before.failed,
        max_cancel_wait: after.max_cancel_wait,
    };
    println!("burst: 100 edits, {seen} of them seen by a frame");
    Ok((took, counts, longest))
}

/// Seven more meshes in the bunny's world, then one bunny edit: the stage runs recorded
/// for the other seven (the target is none).
fn eight_meshes(
    engine: &mut StreamingEngine,
    mesh: &TriMesh,
) -> Result<usize, Box<dyn std::error::Error>> {
    let bunny = engine.mesh_entity().ok_or("no mesh entity")?;
    let mut others = Vec::new();
    for i in 0..7u32 {
        let m = Arc::new(match i % 3 {
            0 => shapes::sphere(1.0, 20 + i)?,
            1 => shapes::torus(1.0, 0.35, 24 + i)?,
            _ => shapes::genus2(1.0, 2)?,
        });
        let spec = FieldSpec::Constant {
            direction: [1.0, 0.2 * f64::from(i), 0.3],
            anisotropy: 3.0,
            density: 1.0,
        };
        let f = Arc::new(spec.build(&m)?);
        others.push(
            engine
                .world
                .spawn(MeshBundle::new(
                    m,
                    f,
                    SurfaceOptions::default(),
                    20_000,
                    u64::from(i),
                ))
                .id(),
        );
    }
    if !engine.settle(Duration::from_secs(300)) {
        return Err("the eight meshes did not build in 300 s".into());
    }
    engine.clear_stats();
    let f = Arc::new(strata_bench::cap_field(
        mesh,
        strata_bench::cap_height(mesh, 0.1),
        DVec3::new(1.0, 1.0, 0.0),
    )?);
    engine
        .world
        .get_mut::<FieldData>(bunny)
        .ok_or("no field")?
        .0 = f;
    if !engine.settle(Duration::from_secs(300)) {
        return Err("the edit did not build in 300 s".into());
    }
    if engine.stats().runs_of(Stage::Segmentation) == 0 {
        return Err("the edited mesh was not rebuilt".into());
    }
    let other_runs = engine
        .stats()
        .runs
        .iter()
        .filter(|r| others.contains(&r.entity) && r.stage != Stage::Sampling)
        .count();
    // Samplers of the others are the same objects as before the edit.
    for &e in &others {
        if engine
            .world
            .get::<MeshSampler>(e)
            .and_then(|s| s.0.as_ref())
            .is_none()
        {
            return Err("a mesh lost its sampler".into());
        }
    }
    Ok(other_runs)
}

fn median(v: &mut [Duration]) -> Duration {
    v.sort();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
