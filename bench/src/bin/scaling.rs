//! Issue 18's scaling table: preprocessing of the shared bunny and the bunny
//! Loop-subdivided once and twice (278k and 1.1M faces, made in code, never stored)
//! for three fields, the bundled scenes `stanford-bunny-anisotropic.ron` (a constant
//! direction projected, 3:1), `stanford-bunny-smooth.ron` (the designed
//! curvature-aligned field, 3:1) and `stanford-bunny-isotropic.ron`:
//! `cargo run --release -p strata-bench --bin scaling [-- repeats [levels]]`.
//!
//! Per mesh and field: the seconds of each stage (field build, smooth directions in
//! isotropic regions, segmentation, parameterization with splitting, cells; medians of `repeats` runs, default 1), the
//! segments (and how many of them are isotropic), the singular faces, and the
//! preprocessed data's bytes per face (`Sampler::heap_bytes`). `levels` (default 2)
//! is how many subdivisions to run: 2 stops at 278k faces, 3 adds 1.1M (minutes per
//! field today). Rows print as they finish.

use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

use strata_engine::mesh::{TriMesh, loop_subdivide};
use strata_engine::surface::Preprocessed;
use strata_systems::config::SceneConfig;

const SCENES: [(&str, &str); 3] = [
    ("constant 3:1", "stanford-bunny-anisotropic.ron"),
    ("smooth curvature-aligned 3:1", "stanford-bunny-smooth.ron"),
    ("isotropic", "stanford-bunny-isotropic.ron"),
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn row(
    name: &str,
    mesh: &Arc<TriMesh>,
    config: &SceneConfig,
    repeats: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let stage_names = [
        "isotropic directions",
        "segmentation",
        "parameterization",
        "cells",
    ];
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); 1 + stage_names.len()];
    let mut last = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let field = Arc::new(config.field.build(mesh)?);
        times[0].push(t.elapsed().as_secs_f64());
        let pre = Preprocessed::build(mesh.clone(), field, &config.surface_options())?;
        for (k, stage) in stage_names.iter().enumerate() {
            let s = pre
                .stages
                .iter()
                .filter(|(n, _)| n == stage)
                .map(|(_, d)| d.as_secs_f64())
                .sum();
            times[k + 1].push(s);
        }
        last = Some(pre);
    }
    let pre = last.ok_or("no run")?;
    let medians: Vec<f64> = times.into_iter().map(median).collect();
    let total: f64 = medians.iter().sum();
    let faces = mesh.face_count();
    println!(
        "| {name} | {faces} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {total:.2} | {} ({} isotropic) | {} | {:.0} |",
        medians[0],
        medians[1],
        medians[2],
        medians[3],
        medians[4],
        pre.report.segments,
        pre.report.isotropic_segments,
        pre.segmentation.singularities.len(),
        pre.sampler.heap_bytes() as f64 / faces as f64,
    );
    std::io::stdout().flush()?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(1)?;
    let levels = strata_bench::levels_arg(2)?;
    let scenes = strata_bench::bundled_scenes(&SCENES)?;
    let mut mesh = Arc::new(strata_systems::scene::load_mesh(&scenes[0].1)?);
    println!(
        "| field | faces | field (s) | isotropic directions (s) | segmentation (s) | parameterization (s) | cells (s) | total (s) | segments | singular faces | bytes per face |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for level in 0..levels {
        if level > 0 {
            mesh = Arc::new(loop_subdivide(&mesh)?);
        }
        for (name, config) in &scenes {
            row(name, &mesh, config, repeats)?;
        }
    }
    Ok(())
}
