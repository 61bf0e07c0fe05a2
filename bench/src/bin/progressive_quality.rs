//! Issue 19's quality check of the progressive order against the stratified one, on
//! the unit square (isotropic, and 4:1 with the 4:1 metric scale), at
//! `N = 2^l, 1.5 x 2^l` (l = 6..13) and `N = 1000, 1500, 3000`:
//! `cargo run --release -p strata-bench --bin progressive_quality [-- runs]`.
//!
//! Printed per field and order: the sup and L2 discrepancy slopes over origin
//! rectangles (least squares of log discrepancy against log N, seeds 1..=3), and at
//! each N of a few the low-frequency energy (mean RAPSD below 0.5 of the
//! normalised frequency) and the RAPSD peak over `runs` sets (default 8); for the
//! 4:1 field the sets are mapped to its metric (a `1/2 x 2` rectangle scaled by
//! `(2, 1/2)`), as in the 7.4 experiment.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::spectrum::periodogram;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, ShapeFamily};
use strata_engine::curve::CurveOptions;
use strata_engine::field::FieldSpec;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::planar;
use strata_engine::sample::{Sample, Sampler};

type BoxError = Box<dyn std::error::Error + Send + Sync>;

/// The planar sampler of `mesh` with a constant field along x.
fn sampler(mesh: TriMesh, anisotropy: f64) -> Result<Sampler, BoxError> {
    let mesh = Arc::new(mesh);
    let field = Arc::new(
        FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy,
            density: 1.0,
        }
        .build(&mesh)?,
    );
    Ok(planar::sampler(mesh, field, &CurveOptions::default())?.0)
}

/// `n` samples of `s` for `seed` in the given order.
fn draw(s: &Sampler, n: usize, seed: u64, progressive: bool) -> Vec<Sample> {
    let mut out = vec![Sample::default(); n];
    if progressive {
        s.progressive_into(seed, 0, &mut out);
    } else {
        s.sample_into(seed, &mut out);
    }
    out
}

/// The points' xy scaled by `scale` and clamped to the unit square.
fn points(samples: &[Sample], scale: DVec2) -> Vec<DVec2> {
    samples
        .iter()
        .map(|s| {
            (DVec2::new(f64::from(s.position[0]), f64::from(s.position[1])) * scale)
                .clamp(DVec2::ZERO, DVec2::ONE)
        })
        .collect()
}

fn main() -> Result<(), BoxError> {
    let runs = strata_bench::repeats_arg(8)? as u64;
    let mut ns: Vec<usize> = (6..=13)
        .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
        .chain([1000, 1500, 3000])
        .collect();
    ns.sort_unstable();
    let seeds = [1u64, 2, 3];
    let square_iso = sampler(shapes::plane(1.0, 16)?, 1.0)?;
    let square_aniso = sampler(shapes::plane(1.0, 16)?, 4.0)?;
    // 4:1 in a domain square in its metric, for the spectrum.
    let plane = shapes::plane(1.0, 32)?;
    let positions = plane
        .positions()
        .iter()
        .map(|p| glam::DVec3::new(0.5 * p.x, 2.0 * p.y, p.z))
        .collect();
    let rect = TriMesh::new(positions, plane.triangles().to_vec())?;
    let metric_aniso = sampler(rect, 4.0)?;
    let cases = [
        (
            "isotropic",
            &square_iso,
            DVec2::ONE,
            &square_iso,
            DVec2::ONE,
        ),
        (
            "4:1",
            &square_aniso,
            DVec2::new(4.0, 1.0),
            &metric_aniso,
            DVec2::new(2.0, 0.5),
        ),
    ];
    println!(
        "| field | order | sup slope | L2 slope | low-frequency energy / RAPSD peak at N = 1000, 1024, 1500, 2048, 3000, 4096 |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for (name, square, axis, metric, to_metric) in cases {
        for progressive in [false, true] {
            let d = Discrepancy::new(ShapeFamily::Rectangles).with_axis_scale(axis);
            let curve = DiscrepancyCurve::measure(
                &d,
                |n, seed| points(&draw(square, n, seed, progressive), DVec2::ONE),
                &ns,
                &seeds,
            )?;
            let mut spectra = Vec::new();
            for n in [1000usize, 1024, 1500, 2048, 3000, 4096] {
                let sets: Vec<Vec<DVec2>> = (1..=runs)
                    .map(|seed| points(&draw(metric, n, seed, progressive), to_metric))
                    .collect();
                let radial = periodogram(&sets, 2.5)?.radial();
                spectra.push(format!(
                    "{:.3} / {:.2}",
                    radial.mean_below(0.5),
                    radial.peak().1
                ));
            }
            println!(
                "| {name} | {} | {:.3} | {:.3} | {} |",
                if progressive {
                    "progressive"
                } else {
                    "stratified"
                },
                curve.sup_slope(),
                curve.l2_slope(),
                spectra.join(", ")
            );
        }
    }
    Ok(())
}
