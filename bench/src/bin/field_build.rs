//! The smoothest line field's build time with the paper's cotangent weights against the
//! floored ones: `cargo run --release -p strata-bench --bin field_build [-- repeats
//! [levels]]`.
//!
//! On the shared bunny and the bunny Loop-subdivided up to `levels` times (default 2,
//! made in code), the unsmoothed smoothest field (`smoothing` 0, no cancellation, the
//! default solver) is built with [`EdgeWeights::Cotan`] and [`EdgeWeights::Floored`],
//! alternated `repeats` times (default 3) in one process, after one untimed build per
//! mesh, each going first every other time. A Markdown table: vertices,
//! the median seconds of each, their ratio, and each field's iterations (V-cycles or
//! solves) and Rayleigh quotient. Needs the shared meshes (`STRATA_MESH_DIR` or
//! `../shared/meshes`).

use std::time::Instant;

use strata_bench::median;
use strata_engine::field::{EdgeWeights, LineField, LineFieldOptions, smoothest_line_field};
use strata_engine::mesh::{TriMesh, loop_subdivide};

/// Seconds of one build and its field.
fn timed(
    mesh: &TriMesh,
    weights: EdgeWeights,
) -> Result<(f64, LineField), Box<dyn std::error::Error>> {
    let options = LineFieldOptions {
        smoothing: 0.0,
        cancel_distance: 0.0,
        weights,
        ..LineFieldOptions::default()
    };
    let t = Instant::now();
    let field = smoothest_line_field(mesh, &options)?;
    Ok((t.elapsed().as_secs_f64(), field))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(3)?.max(1);
    let levels = strata_bench::levels_arg(2)?;
    let dir = strata_bench::shared_mesh_dir()?;
    let mut mesh = strata_engine::io::load(&dir.join("stanford-bunny.obj"))?;
    println!(
        "| mesh | vertices | paper's weights (s) | floored (s) | ratio | iterations (paper's, floored) | Rayleigh quotient (paper's, floored) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for level in 0..=levels {
        if level > 0 {
            mesh = loop_subdivide(&mesh)?;
        }
        let (mut paper, mut floored) = (Vec::new(), Vec::new());
        let mut fields = None;
        // One untimed build first (the thread pool's start, the first allocations).
        timed(&mesh, EdgeWeights::Floored)?;
        for run in 0..repeats {
            // Each goes first every other run, so neither always gets the warmer caches.
            let (tp, fp, tf, ff) = if run % 2 == 0 {
                let (tp, fp) = timed(&mesh, EdgeWeights::Cotan)?;
                let (tf, ff) = timed(&mesh, EdgeWeights::Floored)?;
                (tp, fp, tf, ff)
            } else {
                let (tf, ff) = timed(&mesh, EdgeWeights::Floored)?;
                let (tp, fp) = timed(&mesh, EdgeWeights::Cotan)?;
                (tp, fp, tf, ff)
            };
            paper.push(tp);
            floored.push(tf);
            fields = Some((fp, ff));
        }
        let (p, f) = (median(paper), median(floored));
        let Some((fp, ff)) = fields else {
            continue;
        };
        let label = match level {
            0 => "bunny".to_string(),
            1 => "bunny, subdivided once".to_string(),
            2 => "bunny, subdivided twice".to_string(),
            n => format!("bunny, subdivided {n} times"),
        };
        println!(
            "| {label} | {} | {p:.3} | {f:.3} | {:.2} | {}, {} | {:.6e}, {:.6e} |",
            mesh.vertex_count(),
            p / f,
            fp.iterations,
            ff.iterations,
            fp.rayleigh,
            ff.rayleigh,
        );
    }
    Ok(())
}
