//! Issue 18's scaling table: preprocessing of the shared bunny and the bunny
//! Loop-subdivided once and twice (278k and 1.1M faces, made in code, never stored)
//! for three fields, the bundled scenes `stanford-bunny-anisotropic.ron` (a constant
//! direction projected, 3:1), `stanford-bunny-smooth.ron` (the designed
//! curvature-aligned field, 3:1) and `stanford-bunny-isotropic.ron`:
//! `cargo run --release -p strata-bench --bin scaling [-- repeats [levels [seeds]]]`.
//!
//! Per mesh and field: the seconds of each stage (field build, smooth directions in
//! isotropic regions, segmentation, parameterization with splitting, cells), the
//! segments (and how many of them are isotropic), the singular faces, and the
//! preprocessed data's bytes per face (`Sampler::heap_bytes`). `levels` (default 2)
//! is how many subdivisions to run: 2 stops at 278k faces, 3 adds 1.1M. `seeds`
//! (default 1) preprocesses with the scene's segmentation seed and the next
//! `seeds - 1`: which segments fail and split depends on where the walk's first
//! seeds land, and one seed's time at 1.1M faces swings by 1.5x. Each field is built
//! `repeats` times (default 1) and preprocessed once per seed after each build; the
//! stage times are medians over all runs, the segments the median over seeds, and the
//! last column gives the totals' range. Rows print as they finish.

use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

use strata_bench::median;
use strata_engine::mesh::{TriMesh, loop_subdivide};
use strata_engine::surface::Preprocessed;
use strata_systems::config::SceneConfig;

const SCENES: [(&str, &str); 3] = [
    ("constant 3:1", "stanford-bunny-anisotropic.ron"),
    ("smooth curvature-aligned 3:1", "stanford-bunny-smooth.ron"),
    ("isotropic", "stanford-bunny-isotropic.ron"),
];

fn row(
    name: &str,
    mesh: &Arc<TriMesh>,
    config: &SceneConfig,
    repeats: usize,
    seeds: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let stage_names = [
        "isotropic directions",
        "segmentation",
        "parameterization",
        "cells",
    ];
    let mut field_times = Vec::new();
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); stage_names.len()];
    let mut totals = Vec::new();
    let mut segments = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let field = Arc::new(config.field.build(mesh)?);
        let field_time = t.elapsed().as_secs_f64();
        field_times.push(field_time);
        for k in 0..seeds as u64 {
            let mut options = config.surface_options();
            options.segment.seed = config.segment.seed.wrapping_add(k);
            let pre = Preprocessed::build(mesh.clone(), field.clone(), &options)?;
            let mut total = field_time;
            for (stage, list) in stage_names.iter().zip(&mut times) {
                let s = pre
                    .stages
                    .iter()
                    .filter(|(n, _)| n == stage)
                    .map(|(_, d)| d.as_secs_f64())
                    .sum();
                list.push(s);
                total += s;
            }
            totals.push(total);
            segments.push((pre.report.segments, pre.report.isotropic_segments));
            last = Some(pre);
        }
    }
    let pre = last.ok_or("no run")?;
    let field_median = median(field_times);
    let medians: Vec<f64> = times.into_iter().map(median).collect();
    let total: f64 = field_median + medians.iter().sum::<f64>();
    let (low, high) = totals
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &t| (l.min(t), h.max(t)));
    segments.sort_unstable();
    let (segments, isotropic) = segments[segments.len() / 2];
    let faces = mesh.face_count();
    println!(
        "| {name} | {faces} | {field_median:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {total:.2} | {low:.2}-{high:.2} | {segments} ({isotropic} isotropic) | {} | {:.0} |",
        medians[0],
        medians[1],
        medians[2],
        medians[3],
        pre.segmentation.singularities.len(),
        pre.sampler.heap_bytes() as f64 / faces as f64,
    );
    std::io::stdout().flush()?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(1)?;
    let levels = strata_bench::levels_arg(2)?;
    let seeds = strata_bench::seeds_arg(1)?.max(1);
    let scenes = strata_bench::bundled_scenes(&SCENES)?;
    let mut mesh = Arc::new(strata_systems::scene::load_mesh(&scenes[0].1)?);
    println!(
        "| field | faces | field (s) | isotropic directions (s) | segmentation (s) | parameterization (s) | cells (s) | total (s) | total, range (s) | segments | singular faces | bytes per face |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for level in 0..levels {
        if level > 0 {
            mesh = Arc::new(loop_subdivide(&mesh)?);
        }
        for (name, config) in &scenes {
            row(name, &mesh, config, repeats, seeds)?;
        }
    }
    Ok(())
}
