//! Discrepancy decay of the planar baselines: the experiment of section 7.2 of the
//! paper, run on the reference samplers with known asymptotics.
//!
//! Sizes `N = 2^l` and `1.5 * 2^l` from 64 to 4096, three seeds each (as in the paper).
//! The bands below come from ten disjoint seed triples (seeds 1..=30) of this exact
//! set-up: each band is the measured mean plus or minus about three standard deviations
//! of a triple's slope, and agrees with theory where theory is known:
//!
//! | sampler | measure | mean +- sd (10 triples) | theory | band |
//! | --- | --- | --- | --- | --- |
//! | uniform | sup, boxes | 0.494 +- 0.036 | 1/2 | 0.40..0.60 |
//! | uniform | L2, boxes | 0.495 +- 0.055 | 1/2 (E T^2 = (1/4 - 1/9) / N) | 0.40..0.60 |
//! | jittered | sup, boxes | 0.669 +- 0.013 | 3/4 - 1/(2 ln N) = 0.67 here (N^-3/4 sqrt(log N)) | 0.62..0.72 |
//! | jittered | L2, boxes | 0.751 +- 0.006 | 3/4 | 0.70..0.80 |
//! | Poisson disk | sup, boxes | 0.548 +- 0.014 | 1/2 asymptotically, steeper at small N | 0.50..0.60 |
//! | Poisson disk | L2, boxes | 0.545 +- 0.022 | as above | 0.48..0.62 |
//! | jittered | sup, triangles | 0.660 +- 0.011 (6 triples) | as boxes | 0.62..0.71 |
//! | Poisson disk | sup, triangles | 0.561 +- 0.013 (6 triples) | | 0.50..0.62 |
//! | jittered | sup, quarter discs | 0.679 +- 0.013 | as boxes | 0.63..0.73 |
//! | Poisson disk | sup, quarter discs | 0.564 +- 0.015 | | 0.50..0.63 |
//!
//! The seeds are fixed, so the tests are deterministic; the bands say how far the
//! slopes of a correct implementation spread, so that a change in a sampler or a
//! measure that moves a slope out of its band is a real regression.

use std::collections::HashMap;

use glam::DVec2;
use rayon::prelude::*;

use super::*;

const SEEDS: [u64; 3] = [1, 2, 3];

/// 64, 96, 128, 192, ..., 3072, 4096.
fn sizes() -> Vec<usize> {
    (6..=12)
        .flat_map(|l| [1usize << l, 3usize << (l - 1)])
        .filter(|&n| n <= 4096)
        .collect()
}

/// Runs `sampler` once per (n, seed) so that several curves can share the point sets.
fn cached(sampler: fn(usize, u64) -> Vec<DVec2>) -> impl Fn(usize, u64) -> Vec<DVec2> + Sync {
    let runs: Vec<(usize, u64)> = sizes()
        .into_iter()
        .flat_map(|n| SEEDS.map(|seed| (n, seed)))
        .collect();
    let sets: HashMap<(usize, u64), Vec<DVec2>> = runs
        .into_par_iter()
        .map(|(n, seed)| ((n, seed), sampler(n, seed)))
        .collect();
    move |n, seed| sets.get(&(n, seed)).cloned().unwrap_or_default()
}

fn curve(
    family: ShapeFamily,
    sampler: &(impl Fn(usize, u64) -> Vec<DVec2> + Sync),
) -> DiscrepancyCurve {
    DiscrepancyCurve::measure(&Discrepancy::new(family), sampler, &sizes(), &SEEDS)
        .expect("baselines return n points in the unit square")
}

fn assert_band(what: &str, slope: f64, lo: f64, hi: f64) {
    eprintln!("{what}: slope {slope:.3} (band {lo}..{hi})");
    assert!(
        (lo..=hi).contains(&slope),
        "{what}: slope {slope:.3} outside {lo}..{hi}"
    );
}

#[test]
fn box_discrepancy_slopes_of_baselines() {
    let uniform = curve(ShapeFamily::Rectangles, &uniform_random);
    let jittered = curve(ShapeFamily::Rectangles, &jittered_grid);
    let poisson = curve(ShapeFamily::Rectangles, &cached(poisson_disk));

    assert_band("uniform sup", uniform.sup_slope(), 0.40, 0.60);
    assert_band("uniform L2", uniform.l2_slope(), 0.40, 0.60);
    assert_band("jittered sup", jittered.sup_slope(), 0.62, 0.72);
    assert_band("jittered L2", jittered.l2_slope(), 0.70, 0.80);
    assert_band("poisson sup", poisson.sup_slope(), 0.50, 0.60);
    assert_band("poisson L2", poisson.l2_slope(), 0.48, 0.62);

    // Not only the slopes: at the largest sizes the levels are ordered too.
    for k in uniform.ns.len() - 3..uniform.ns.len() {
        let n = uniform.ns[k];
        assert!(
            jittered.l2[k] < poisson.l2[k] && poisson.l2[k] < uniform.l2[k],
            "L2 at n = {n}"
        );
        assert!(
            jittered.sup[k] < poisson.sup[k] && poisson.sup[k] < uniform.sup[k],
            "sup at n = {n}"
        );
    }
}

#[test]
fn triangle_and_disc_discrepancy_slopes_of_baselines() {
    let poisson = cached(poisson_disk);
    let jittered_tri = curve(ShapeFamily::OriginTriangles, &jittered_grid);
    let poisson_tri = curve(ShapeFamily::OriginTriangles, &poisson);
    let jittered_disc = curve(ShapeFamily::QuarterDiscs, &jittered_grid);
    let poisson_disc = curve(ShapeFamily::QuarterDiscs, &poisson);

    assert_band("jittered triangles", jittered_tri.sup_slope(), 0.62, 0.71);
    assert_band("poisson triangles", poisson_tri.sup_slope(), 0.50, 0.62);
    assert_band("jittered discs", jittered_disc.sup_slope(), 0.63, 0.73);
    assert_band("poisson discs", poisson_disc.sup_slope(), 0.50, 0.63);
}
