//! Paper section 7.2 on the planar sampler: star discrepancy slopes over N.
//!
//! N = 2^l and 2^l + 2^(l-1) from 64 to 8192, three seeds each, as in the paper; the
//! same code measures uniform random sampling as a reference.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, baseline};
use strata_engine::curve::CurveOptions;
use strata_engine::fixtures::{along_x, isotropic};
use strata_engine::mesh::shapes;
use strata_engine::planar;
use strata_engine::sample::Sampler;

fn ns() -> Vec<usize> {
    (6..=13)
        .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
        .filter(|&n| n <= 8192)
        .collect()
}

fn isotropic_sampler() -> Sampler {
    let mesh = Arc::new(shapes::plane(1.0, 16).expect("plane"));
    let spec = isotropic();
    let field = Arc::new(spec.build(&mesh).expect("field"));
    planar::sampler(mesh, field, &CurveOptions::default())
        .expect("sampler")
        .0
}

fn points(sampler: &Sampler, n: usize, seed: u64) -> Vec<DVec2> {
    sampler
        .sample(n, seed)
        .iter()
        .map(|s| {
            DVec2::new(s.position[0] as f64, s.position[1] as f64)
                .clamp(DVec2::ZERO, DVec2::splat(1.0 - 1e-9))
        })
        .collect()
}

#[test]
fn isotropic_sampling_is_low_discrepancy() {
    let sampler = isotropic_sampler();
    let seeds = [1, 2, 3];
    let boxes = Discrepancy::default();
    let ours = DiscrepancyCurve::measure(&boxes, |n, s| points(&sampler, n, s), &ns(), &seeds)
        .expect("measure");
    let random = DiscrepancyCurve::measure(&boxes, baseline::uniform_random, &ns(), &seeds)
        .expect("measure");
    let (l2, sup) = (ours.l2_slope(), ours.sup_slope());
    println!(
        "strata: L2 slope {l2:.3}, sup slope {sup:.3}; random: L2 {:.3}, sup {:.3}",
        random.l2_slope(),
        random.sup_slope()
    );
    assert!(l2 >= 0.72, "L2 star discrepancy slope {l2} (paper: 0.74)");
    assert!(
        sup >= 0.63,
        "sup star discrepancy slope {sup} (jittered grid: about 0.67)"
    );
    assert!(
        (0.38..=0.62).contains(&random.l2_slope()),
        "random L2 slope {}",
        random.l2_slope()
    );
    assert!(
        (0.38..=0.62).contains(&random.sup_slope()),
        "random sup slope {}",
        random.sup_slope()
    );
    // And lower discrepancy than random at every N.
    for (k, n) in ours.ns.iter().enumerate() {
        assert!(
            ours.l2[k] < random.l2[k],
            "N {n}: {} vs {}",
            ours.l2[k],
            random.l2[k]
        );
    }
}

#[test]
fn four_to_one_sampling_is_low_discrepancy() {
    // Axis-aligned boxes map to boxes of the same relative area under the field's
    // axis-aligned linear map, so the world-space box discrepancy is the metric one.
    let mesh = Arc::new(shapes::plane(1.0, 16).expect("plane"));
    let spec = along_x(4.0);
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let sampler = planar::sampler(mesh, field, &CurveOptions::default())
        .expect("sampler")
        .0;
    let curve = DiscrepancyCurve::measure(
        &Discrepancy::default(),
        |n, s| points(&sampler, n, s),
        &ns(),
        &[1, 2, 3],
    )
    .expect("measure");
    println!(
        "strata 4:1: L2 slope {:.3}, sup slope {:.3}",
        curve.l2_slope(),
        curve.sup_slope()
    );
    assert!(
        curve.l2_slope() >= 0.72,
        "L2 slope {} (paper: 0.72)",
        curve.l2_slope()
    );
    assert!(curve.sup_slope() >= 0.63, "sup slope {}", curve.sup_slope());
}
