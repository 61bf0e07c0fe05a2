use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::*;
use crate::analysis::baseline::uniform_random;
use crate::curve::CurveOptions;
use crate::fixtures;
use crate::mesh::shapes;
use crate::planar;

type TestResult = Result<(), Box<dyn std::error::Error>>;

fn isotropic(mesh: TriMesh) -> Result<Sampler, Box<dyn std::error::Error>> {
    let mesh = Arc::new(mesh);
    let spec = fixtures::isotropic();
    let field = Arc::new(spec.build(&mesh)?);
    Ok(planar::sampler(mesh, field, &CurveOptions::default())?.0)
}

/// The planar sampler of the unit square, one segment.
fn unit_square() -> Result<Sampler, Box<dyn std::error::Error>> {
    isotropic(shapes::plane(1.0, 16)?)
}

/// The unit square without its top right quadrant: the curve of its bounding square
/// leaves the domain there and re-enters it elsewhere.
fn l_shape() -> Result<Sampler, Box<dyn std::error::Error>> {
    let m = shapes::plane(1.0, 16)?;
    let keep: Vec<[u32; 3]> = m
        .triangles()
        .iter()
        .copied()
        .filter(|t| {
            let c = t.iter().map(|&v| m.positions()[v as usize]).sum::<DVec3>() / 3.0;
            !(c.x > 0.5 && c.y > 0.5)
        })
        .collect();
    isotropic(TriMesh::new(m.positions().to_vec(), keep)?)
}

fn cell(p: DVec2, side: f64) -> (i64, i64) {
    ((p.x * side).floor() as i64, (p.y * side).floor() as i64)
}

#[test]
fn strata_at_powers_of_four_are_the_grid_cells() -> TestResult {
    let s = unit_square()?;
    let seg = &s.segments()[0];
    for (n, side) in [(4usize, 2.0), (16, 4.0), (64, 8.0)] {
        let mut cells: Vec<(i64, i64)> = (0..n)
            .map(|k| {
                let pts = stratum_points(s.mesh(), seg, k, n);
                assert_eq!(pts.len(), STRATUM_POINTS);
                let c = cell(pts.iter().copied().sum::<DVec2>() / pts.len() as f64, side);
                for p in &pts {
                    assert_eq!(cell(*p, side), c, "n = {n}, stratum {k}, point {p}");
                }
                c
            })
            .collect();
        cells.sort_unstable();
        cells.dedup();
        assert_eq!(cells.len(), n, "n = {n}: every cell once");
    }
    Ok(())
}

#[test]
fn second_moment_of_square_strata_is_that_of_an_8_by_8_grid() -> TestResult {
    // At N = 4^k each stratum is a square cell whose 64 points are the centres of its
    // 8 x 8 sub-cells: per axis the variance of 8 evenly spaced centres is (s^2 / 12)
    // (1 - 1 / 64), so 6 N tr(Cov) = 63 / 64.
    let s = unit_square()?;
    for n in [1usize, 4, 16, 64, 256] {
        let m = strata_second_moment(&s, n);
        assert!((m - 63.0 / 64.0).abs() < 1e-8, "n = {n}: {m}");
    }
    Ok(())
}

#[test]
fn second_moment_grows_between_powers_of_four() -> TestResult {
    let s = unit_square()?;
    // At N = 2 4^k strata are pairs of cells (2:1 rectangles: 5 / 4 with continuous
    // strata); the Hilbert curve is self-similar, so the value does not depend on k.
    let pairs: Vec<f64> = [2usize, 8, 32, 128]
        .iter()
        .map(|&n| strata_second_moment(&s, n))
        .collect();
    for m in &pairs {
        assert!(*m > 1.2 && *m < 1.3, "{pairs:?}");
        assert!((m - pairs[0]).abs() < 1e-5, "{pairs:?}");
    }
    // Counts that are neither cut across the cells as well.
    for n in [24usize, 100] {
        let m = strata_second_moment(&s, n);
        assert!(m > 1.1 && m < 2.0, "n = {n}: {m}");
    }
    assert_eq!(strata_second_moment(&s, 0), 0.0);
    Ok(())
}

#[test]
fn results_do_not_depend_on_the_thread_count() -> TestResult {
    let s = l_shape()?;
    let boxes = uniform_random(50, 5);
    let seam = |p: DVec2| p.y > 0.45 && p.y < 0.55;
    let run = || {
        (
            strata_second_moment(&s, 37),
            strata_variance(&s, 37, &boxes, &seam),
        )
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()?
        .install(run);
    let four = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()?
        .install(run);
    assert_eq!(one.0.to_bits(), four.0.to_bits());
    assert_eq!(one.1?, four.1?);
    Ok(())
}

#[test]
fn variance_by_hand_on_four_square_strata() -> TestResult {
    // N = 4: strata are the quarters of the square. The box [0, 0.25) x [0, 0.75) holds
    // half of the bottom-left quarter (p = 1/2: 1/4), a quarter of the top-left one
    // (p = 1/4: 3/16) and nothing of the right ones: 7/16 in all.
    let s = unit_square()?;
    let none = |_: DVec2| false;
    let v = strata_variance(&s, 4, &[DVec2::new(0.25, 0.75)], &none)?;
    assert_eq!(v.total, 7.0 / 16.0);
    assert_eq!(v.elsewhere.strata, 4);
    // Boxes holding all or nothing of every stratum have no count variance; the mean is
    // over the boxes.
    let v = strata_variance(&s, 4, &[DVec2::ONE * 1.0001, DVec2::ZERO], &none)?;
    assert_eq!(v.total, 0.0);
    let v = strata_variance(
        &s,
        4,
        &[
            DVec2::new(0.25, 0.75),
            DVec2::ZERO,
            DVec2::ZERO,
            DVec2::ZERO,
        ],
        &none,
    )?;
    assert_eq!(v.total, 7.0 / 64.0);
    Ok(())
}

#[test]
fn stratified_variance_grows_like_sqrt_n_random_like_n() -> TestResult {
    let s = unit_square()?;
    let none = |_: DVec2| false;
    let boxes = uniform_random(500, 3);
    // N independent uniform points: a box of area A has count variance N A (1 - A).
    let random = |n: usize| {
        boxes
            .iter()
            .map(|b| {
                let a = b.x * b.y;
                a * (1.0 - a)
            })
            .sum::<f64>()
            / boxes.len() as f64
            * n as f64
    };
    // One stratum is one uniform point (up to the 8 x 8 resolution of the stratum).
    let one = strata_variance(&s, 1, &boxes, &none)?.total;
    assert!((one - random(1)).abs() < 0.01, "{one} vs {}", random(1));
    let v16 = strata_variance(&s, 16, &boxes, &none)?.total;
    let v64 = strata_variance(&s, 64, &boxes, &none)?.total;
    assert!(
        v16 < 0.35 * random(16) && v64 < 0.2 * random(64),
        "{v16} {v64}"
    );
    // Only strata cut by the box's edges count: 4 x the strata, 2 x the variance.
    let growth = v64 / v16;
    assert!(growth > 1.7 && growth < 2.4, "{growth}");
    Ok(())
}

#[test]
fn classes_split_the_total() -> TestResult {
    let s = unit_square()?;
    let boxes = uniform_random(100, 9);
    // A single square segment has no jumps: with the seam everywhere every stratum
    // touches it, with no seam none does.
    let all = strata_variance(&s, 32, &boxes, &|_| true)?;
    assert_eq!(
        (all.straddling.strata, all.seam.strata, all.elsewhere.strata),
        (0, 32, 0)
    );
    let none = strata_variance(&s, 32, &boxes, &|_| false)?;
    assert_eq!(
        (
            none.straddling.strata,
            none.seam.strata,
            none.elsewhere.strata
        ),
        (0, 0, 32)
    );
    assert_eq!(all.total, none.total);
    // A seam along x = 1/2 touches the strata on either side of it.
    let mid = strata_variance(&s, 16, &boxes, &|p| (p.x - 0.5).abs() < 0.07)?;
    assert_eq!((mid.seam.strata, mid.elsewhere.strata), (8, 8));
    let sum: f64 = mid.classes().iter().map(|c| c.variance).sum();
    assert!((sum - mid.total).abs() < 1e-12);
    Ok(())
}

#[test]
fn a_stratum_across_a_curve_jump_straddles() -> TestResult {
    // The L shape's curve jumps over the missing quadrant. With 16 strata per quadrant
    // (N = 48) strata end at the jump; at N = 50 and 100 exactly one stratum spans it.
    let l = l_shape()?;
    let boxes = uniform_random(100, 9);
    let count = |n: usize| -> Result<usize, AnalysisError> {
        Ok(strata_variance(&l, n, &boxes, &|_| true)?.straddling.strata)
    };
    assert_eq!(count(48)?, 0);
    assert_eq!(count(50)?, 1);
    assert_eq!(count(100)?, 1);
    Ok(())
}

#[test]
fn no_samples_no_strata_and_no_boxes_is_an_error() -> TestResult {
    let s = unit_square()?;
    let v = strata_variance(&s, 0, &[DVec2::splat(0.5)], &|_| true)?;
    assert_eq!(v, StrataVariance::default());
    assert_eq!(
        strata_variance(&s, 4, &[], &|_| true),
        Err(AnalysisError::NoBoxes)
    );
    Ok(())
}
