//! Time from a saved change to new samples in the streaming engine (`strata watch`'s
//! loop), on the bunny: a sample-count change at 100k samples, and a field-file change
//! on a cap of about 10% of the faces, against the full preprocessing time.
//!
//! `cargo run --release -p strata-bench --bin reload_latency -- [repeats]` (default 5).
//! For each change it reports the engine's update (from the parsed scene arriving to
//! new samples in the buffer) and the end-to-end time from the save to new samples,
//! which adds the watcher's debounce (100 ms) and file-system latency.

use std::io::Write;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use strata_engine::field::{FieldSpec, TensorField, format_field_file};
use strata_engine::mesh::TriMesh;
use strata_engine::surface::{Preprocessed, SurfaceOptions};
use strata_systems::ecs::Stage;
use strata_systems::hot_reload::StreamingEngine;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?;
    let src = strata_bench::shared_mesh_dir()?.join("stanford-bunny.obj");
    let dir = tempfile::tempdir()?;
    // The bunny as PLY, so that the field file's vertex order is the mesh's.
    let mesh = strata_engine::io::load(&src)?;
    let ply = dir.path().join("bunny.ply");
    strata_engine::io::write_mesh_ply(&ply, &mesh, None)?;
    let mesh = Arc::new(strata_engine::io::load(&ply)?);
    let field_path = dir.path().join("bunny.field");
    std::fs::write(
        &field_path,
        format_field_file(&cap_field(&mesh, f64::INFINITY, DVec3::Z)?),
    )?;
    let scene = dir.path().join("bunny.ron");
    let scene_text = |count: u64| {
        format!(
            "(mesh: File(\"bunny.ply\"), field: File(path: \"bunny.field\"), sampling: (count: {count}, seed: 1))"
        )
    };
    std::fs::write(&scene, scene_text(100_000))?;

    // Full preprocessing, directly, for reference.
    let field = Arc::new(
        FieldSpec::File {
            path: field_path.clone(),
        }
        .build(&mesh)?,
    );
    let mut full = Vec::new();
    for _ in 0..repeats.clamp(1, 3) {
        let t = Instant::now();
        Preprocessed::build(mesh.clone(), field.clone(), &SurfaceOptions::default())?;
        full.push(t.elapsed());
    }
    let full = median(&mut full);

    let mut engine = StreamingEngine::watch(&scene)?;
    let t = Instant::now();
    wait(&mut engine, |e| e.samples().len() == 100_000)?;
    println!(
        "bunny: {} faces; first update (load + preprocess + 100k samples) {:.1} ms; full preprocessing alone (median) {:.1} ms",
        mesh.face_count(),
        t.elapsed().as_secs_f64() * 1e3,
        ms(full)
    );

    // Sample count changes: 100 000 <-> 100 001.
    let (mut update, mut end_to_end) = (Vec::new(), Vec::new());
    for i in 0..repeats {
        let count = 100_000 + (i as u64 + 1) % 2;
        let (u, e, stats) = change(&mut engine, || std::fs::write(&scene, scene_text(count)))?;
        if i == 0 {
            print_stages(engine.stats());
        }
        if stats != vec![Stage::Scene, Stage::Sampling] {
            return Err(format!("a count change reran {stats:?}").into());
        }
        update.push(u);
        end_to_end.push(e);
    }
    println!(
        "sample count change (100k samples): update median {:.2} ms (min {:.2}), save to samples median {:.1} ms",
        ms(median(&mut update.clone())),
        ms(*update.iter().min().unwrap_or(&Duration::ZERO)),
        ms(median(&mut end_to_end))
    );

    // Field changes on a cap of about 10% of the faces, alternating two directions.
    let mut top: Vec<f64> = (0..mesh.face_count() as u32)
        .map(|f| {
            mesh.face_positions(f)
                .iter()
                .map(|p| p.y)
                .fold(f64::MIN, f64::max)
        })
        .collect();
    top.sort_by(f64::total_cmp);
    let cap = top[top.len() * 9 / 10];
    let (mut update, mut end_to_end, mut redone) = (Vec::new(), Vec::new(), Vec::new());
    let (mut full_runs, mut preprocess) = (Vec::new(), Vec::new());
    for i in 0..repeats {
        // Full preprocessing right before, so that both see the same machine load.
        let t = Instant::now();
        Preprocessed::build(mesh.clone(), field.clone(), &SurfaceOptions::default())?;
        full_runs.push(t.elapsed());
        let turned = if i % 2 == 0 { DVec3::Y } else { DVec3::Z };
        let text = format_field_file(&cap_field(&mesh, cap, turned)?);
        // Saved as editors do: a temporary file renamed over the field file.
        let (u, e, _) = change(&mut engine, || {
            strata_engine::io::write_atomically(&field_path, |w| w.write_all(text.as_bytes()))
        })?;
        let stats = engine.stats();
        if i == 0 {
            print_stages(stats);
        }
        preprocess.push(
            [
                Stage::Segmentation,
                Stage::Parameterization,
                Stage::Curves,
                Stage::Chains,
            ]
            .into_iter()
            .map(|s| stats.time_of(s))
            .sum::<Duration>(),
        );
        redone.push((
            stats.items_of(Stage::Parameterization),
            stats
                .runs
                .iter()
                .find(|r| r.stage == Stage::Segmentation)
                .map(|r| r.note.clone()),
        ));
        update.push(u);
        end_to_end.push(e);
    }
    let u = median(&mut update);
    let p = median(&mut preprocess);
    let f = median(&mut full_runs);
    println!(
        "field change on a 10% cap: update median {:.1} ms = {:.1}% of full preprocessing ({:.1} ms, interleaved median); its preprocessing stages (segmentation to chains) {:.1} ms = {:.1}%; save to samples median {:.1} ms",
        ms(u),
        100.0 * u.as_secs_f64() / f.as_secs_f64(),
        ms(f),
        ms(p),
        100.0 * p.as_secs_f64() / f.as_secs_f64(),
        ms(median(&mut end_to_end))
    );
    for (n, note) in &redone {
        println!(
            "  re-parameterized {n} segments; segmentation: {}",
            note.as_deref().unwrap_or("-")
        );
    }
    for e in engine.take_errors() {
        eprintln!("error: {e}");
    }
    Ok(())
}

/// Saves with `save`, then times: the update that applies the change (from the
/// moment the watcher's message is waiting) and save to new samples.
fn change(
    engine: &mut StreamingEngine,
    save: impl FnOnce() -> std::io::Result<()>,
) -> Result<(Duration, Duration, Vec<Stage>), Box<dyn std::error::Error>> {
    let generation = engine.sample_generation();
    engine.clear_stats();
    let saved = Instant::now();
    save()?;
    let limit = Instant::now() + Duration::from_secs(60);
    loop {
        if !engine.wait_for_change(Duration::from_secs(1)) {
            if Instant::now() > limit {
                return Err("no change arrived in 60 s".into());
            }
            continue;
        }
        let t = Instant::now();
        engine.update();
        let update = t.elapsed();
        if engine.sample_generation() != generation {
            return Ok((update, saved.elapsed(), engine.stats().stages_run()));
        }
    }
}

fn wait(
    engine: &mut StreamingEngine,
    mut done: impl FnMut(&StreamingEngine) -> bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let limit = Instant::now() + Duration::from_secs(120);
    while Instant::now() < limit {
        engine.update();
        if done(engine) {
            return Ok(());
        }
        engine.wait_for_change(Duration::from_millis(50));
    }
    Err(format!("timed out: {:?}", engine.take_errors()).into())
}

/// The field (1, 0.3, 0.2) 3:1, turned to `turned` above `y_min`.
fn cap_field(
    mesh: &TriMesh,
    y_min: f64,
    turned: DVec3,
) -> Result<TensorField, Box<dyn std::error::Error>> {
    let dirs: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            if p.y > y_min {
                turned
            } else {
                DVec3::new(1.0, 0.3, 0.2)
            }
        })
        .collect();
    let ev = vec![[3.0, 1.0 / 3.0]; mesh.vertex_count()];
    Ok(TensorField::from_frames(mesh, &dirs, &ev)?)
}

/// One line: each stage's wall time in the last change.
fn print_stages(stats: &strata_systems::ecs::StageStats) {
    let parts: Vec<String> = stats
        .stages_run()
        .into_iter()
        .map(|s| format!("{} {:.1} ms", s.name(), ms(stats.time_of(s))))
        .collect();
    println!("  stages: {}", parts.join(", "));
}

fn median(v: &mut [Duration]) -> Duration {
    v.sort();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
