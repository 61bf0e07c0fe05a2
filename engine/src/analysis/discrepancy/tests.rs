//! Cross-checks of the fast discrepancy code against brute-force references, hand
//! computed answers and random lower bounds.

use super::*;
use crate::analysis::baseline;
use crate::rng::Rng;
use glam::DVec2;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_4, PI};

const TOL: f64 = 1e-12;

fn d(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn frac(count: usize, n: usize) -> f64 {
    count as f64 / n as f64
}

// ---------------------------------------------------------------- references

/// O(N^3) star discrepancy: every box whose corner is a point coordinate or 1, each
/// counted directly.
fn rect_brute(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return 1.0;
    }
    let xs: Vec<f64> = points.iter().map(|p| p.x).chain([1.0]).collect();
    let ys: Vec<f64> = points.iter().map(|p| p.y).chain([1.0]).collect();
    let mut best = 0.0f64;
    for &x in &xs {
        for &y in &ys {
            let open = points.iter().filter(|p| p.x < x && p.y < y).count();
            let closed = points.iter().filter(|p| p.x <= x && p.y <= y).count();
            best = best.max(x * y - frac(open, n)).max(frac(closed, n) - x * y);
        }
    }
    best
}

/// O(N^3) L2 star discrepancy by exact integration: the open-box count is constant on
/// each cell `(x_a, x_b] x (y_a, y_b]` of the coordinate grid, where
/// `(c - x y)^2` integrates in closed form.
fn l2_cells(points: &[DVec2]) -> f64 {
    let n = points.len();
    let grid = |f: fn(&DVec2) -> f64| {
        let mut v: Vec<f64> = points.iter().map(f).chain([0.0, 1.0]).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let xs = grid(|p| p.x);
    let ys = grid(|p| p.y);
    let mut total = 0.0;
    for xw in xs.windows(2) {
        for yw in ys.windows(2) {
            let (x0, x1, y0, y1) = (xw[0], xw[1], yw[0], yw[1]);
            let count = points.iter().filter(|p| p.x <= x0 && p.y <= y0).count();
            let c = if n == 0 { 0.0 } else { frac(count, n) };
            total += c * c * (x1 - x0) * (y1 - y0)
                - 2.0 * c * (x1 * x1 - x0 * x0) / 2.0 * (y1 * y1 - y0 * y0) / 2.0
                + (x1.powi(3) - x0.powi(3)) / 3.0 * (y1.powi(3) - y0.powi(3)) / 3.0;
        }
    }
    total.sqrt()
}

/// Which side of the line through `a` and `b` the point `r` lies on, relative to the
/// origin: `Less` inside (origin side), `Equal` on it, `Greater` outside. Exact for
/// coordinates with few significant bits.
fn side(a: DVec2, b: DVec2, r: DVec2) -> std::cmp::Ordering {
    let orient = |p: DVec2| (b - a).perp_dot(p - a);
    let origin = orient(DVec2::ZERO);
    let here = orient(r);
    if here == 0.0 {
        std::cmp::Ordering::Equal
    } else if (here > 0.0) == (origin > 0.0) {
        std::cmp::Ordering::Less
    } else {
        std::cmp::Ordering::Greater
    }
}

/// O(N^3) origin-triangle discrepancy, written independently of the sweep: candidate
/// triangles from intercepts (pairs of points, a point with a = 1 or b = 1, the
/// triangle with a point at the middle of its hypotenuse, and a = b = 1), every point
/// classified against the hypotenuse through two points known to lie on it.
fn tri_brute(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return 0.5;
    }
    // Candidates: two points spanning the hypotenuse, and the legs (a, b).
    let mut candidates: Vec<(DVec2, DVec2, f64, f64)> = vec![(DVec2::X, DVec2::Y, 1.0, 1.0)];
    let ok = |v: f64| v > 0.0 && v <= 1.0;
    for &p in points {
        if p.x < 1.0 && ok(p.y / (1.0 - p.x)) {
            candidates.push((DVec2::X, p, 1.0, p.y / (1.0 - p.x)));
        }
        if p.y < 1.0 && ok(p.x / (1.0 - p.y)) {
            candidates.push((DVec2::Y, p, p.x / (1.0 - p.y), 1.0));
        }
        if ok(2.0 * p.x) && ok(2.0 * p.y) {
            candidates.push((d(2.0 * p.x, 0.0), d(0.0, 2.0 * p.y), 2.0 * p.x, 2.0 * p.y));
        }
        for &q in points {
            let det = p.x * q.y - p.y * q.x;
            if det == 0.0 {
                continue;
            }
            let u = (q.y - p.y) / det;
            let v = (p.x - q.x) / det;
            if u >= 1.0 && v >= 1.0 {
                candidates.push((p, q, 1.0 / u, 1.0 / v));
            }
        }
    }
    let mut best = 0.0f64;
    for (a_pt, b_pt, a, b) in candidates {
        let (mut open, mut closed) = (0, 0);
        for &r in points {
            match side(a_pt, b_pt, r) {
                std::cmp::Ordering::Less => {
                    open += 1;
                    closed += 1;
                }
                std::cmp::Ordering::Equal => closed += 1,
                std::cmp::Ordering::Greater => {}
            }
        }
        let area = 0.5 * a * b;
        best = best.max(area - frac(open, n)).max(frac(closed, n) - area);
    }
    let on_x = points.iter().filter(|p| p.y == 0.0).count();
    let on_y = points.iter().filter(|p| p.x == 0.0).count();
    best.max(frac(on_x.max(on_y), n))
}

/// O(N^2) quarter-disc discrepancy: every point radius and the unit radius.
fn disc_brute(points: &[DVec2], scale: DVec2) -> f64 {
    let n = points.len();
    let r2_max = scale.min_element().powi(2);
    let area = |r2: f64| PI * r2 / (4.0 * scale.x * scale.y);
    if n == 0 {
        return area(r2_max);
    }
    let r2: Vec<f64> = points
        .iter()
        .map(|p| (*p * scale).length_squared())
        .collect();
    let mut best = 0.0f64;
    for &rho in r2.iter().filter(|&&r| r <= r2_max).chain([&r2_max]) {
        let open = r2.iter().filter(|&&r| r < rho).count();
        let closed = r2.iter().filter(|&&r| r <= rho).count();
        best = best
            .max(area(rho) - frac(open, n))
            .max(frac(closed, n) - area(rho));
    }
    best
}

/// The 1D star discrepancy of values in [0, 1): 1/(2N) + max |x_(i) - (2i-1)/(2N)|
/// (Niederreiter 1992, theorem 2.6).
fn star_1d(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    let worst = v
        .iter()
        .enumerate()
        .map(|(i, x)| (x - (2.0 * i as f64 + 1.0) / (2.0 * n)).abs())
        .fold(0.0, f64::max);
    0.5 / n + worst
}

fn triangles() -> Discrepancy {
    Discrepancy::new(ShapeFamily::OriginTriangles)
}

fn discs() -> Discrepancy {
    Discrepancy::new(ShapeFamily::QuarterDiscs)
}

// ---------------------------------------------------------------- property tests

/// A coordinate: often on the dyadic grid k/8 (ties, 0 and 1), otherwise uniform.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![(0u32..=8).prop_map(|k| k as f64 / 8.0), 0.0..=1.0f64]
}

fn point_set(max: usize) -> impl Strategy<Value = Vec<DVec2>> {
    prop::collection::vec(
        (coordinate(), coordinate()).prop_map(|(x, y)| d(x, y)),
        0..max,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn rect_sup_equals_brute_force(points in point_set(24)) {
        let fast = star_discrepancy_sup(&points);
        let slow = rect_brute(&points);
        prop_assert!((fast - slow).abs() < TOL, "fast {fast} brute {slow} for {points:?}");
    }

    #[test]
    fn rect_sup_bounds_the_1d_projections(points in point_set(24)) {
        // Boxes of full height (or width) see the 1D discrepancy of the projection.
        prop_assume!(!points.is_empty() && points.iter().all(|p| p.x < 1.0 && p.y < 1.0));
        let xs: Vec<f64> = points.iter().map(|p| p.x).collect();
        let ys: Vec<f64> = points.iter().map(|p| p.y).collect();
        let sup = star_discrepancy_sup(&points);
        prop_assert!(sup + TOL >= star_1d(&xs).max(star_1d(&ys)));
    }

    #[test]
    fn l2_equals_exact_integration(points in point_set(24)) {
        let fast = star_discrepancy_l2(&points);
        let slow = l2_cells(&points);
        prop_assert!((fast - slow).abs() < 1e-9, "warnock {fast} cells {slow}");
        // The L2 norm of the local discrepancy never exceeds its sup.
        prop_assert!(fast <= star_discrepancy_sup(&points) + TOL);
    }

    #[test]
    fn triangle_sup_equals_brute_force(points in point_set(16)) {
        let fast = triangles().sup(&points);
        let slow = tri_brute(&points);
        prop_assert!((fast - slow).abs() < TOL, "fast {fast} brute {slow} for {points:?}");
    }

    #[test]
    fn disc_sup_equals_brute_force(points in point_set(24), sy in 0.25..4.0f64) {
        for scale in [DVec2::ONE, d(1.0, sy)] {
            let fast = discs().with_axis_scale(scale).sup(&points);
            let slow = disc_brute(&points, scale);
            prop_assert!((fast - slow).abs() < TOL, "fast {fast} brute {slow}");
        }
    }

    #[test]
    fn axis_scale_leaves_boxes_and_triangles_unchanged(points in point_set(12), sy in 0.25..4.0f64) {
        for family in [ShapeFamily::Rectangles, ShapeFamily::OriginTriangles] {
            let plain = Discrepancy::new(family).sup(&points);
            let scaled = Discrepancy::new(family).with_axis_scale(d(1.0, sy)).sup(&points);
            prop_assert_eq!(plain, scaled);
        }
    }
}

/// Sets large enough to be swept in several parallel runs of x (256 critical x each),
/// with ties: a third of the coordinates on the grid k/64, duplicates included.
#[test]
fn rect_sup_in_parallel_runs_equals_brute_force() {
    for seed in 0..3 {
        let mut rng = Rng::new(seed, 1);
        let mut coordinate = || {
            if rng.below(3) == 0 {
                rng.below(65) as f64 / 64.0
            } else {
                rng.next_f64()
            }
        };
        let mut points: Vec<DVec2> = (0..600).map(|_| d(coordinate(), coordinate())).collect();
        points.extend_from_within(..20);
        let fast = star_discrepancy_sup(&points);
        let slow = rect_brute(&points);
        assert!(
            (fast - slow).abs() < TOL,
            "seed {seed}: fast {fast} brute {slow}"
        );
    }
}

// ---------------------------------------------------------------- random lower bounds

/// No shape of the family may beat the supremum: evaluate many random shapes directly.
#[test]
fn random_shapes_never_exceed_the_sup() {
    let mut rng = Rng::new(11, 0);
    for set in 0..20 {
        let mut points = baseline::uniform_random(12 + set, set as u64);
        // Add ties: shared coordinates and a duplicate.
        points.push(d(points[0].x, points[1].y));
        points.push(points[2]);
        let n = points.len();
        let rect = star_discrepancy_sup(&points);
        let tri = triangles().sup(&points);
        let disc = discs().sup(&points);
        let (mut rect_lb, mut tri_lb, mut disc_lb) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..4000 {
            let (x, y) = (1.0 - rng.next_f64(), 1.0 - rng.next_f64());
            let open = points.iter().filter(|p| p.x < x && p.y < y).count();
            let closed = points.iter().filter(|p| p.x <= x && p.y <= y).count();
            rect_lb = rect_lb
                .max(x * y - frac(open, n))
                .max(frac(closed, n) - x * y);
            let open = points.iter().filter(|p| p.x / x + p.y / y < 1.0).count();
            let closed = points.iter().filter(|p| p.x / x + p.y / y <= 1.0).count();
            tri_lb = tri_lb
                .max(0.5 * x * y - frac(open, n))
                .max(frac(closed, n) - 0.5 * x * y);
            let area = FRAC_PI_4 * x * x;
            let open = points.iter().filter(|p| p.length() < x).count();
            let closed = points.iter().filter(|p| p.length() <= x).count();
            disc_lb = disc_lb
                .max(area - frac(open, n))
                .max(frac(closed, n) - area);
        }
        assert!(
            rect_lb <= rect + TOL && rect_lb > 0.5 * rect,
            "{rect_lb} vs {rect}"
        );
        assert!(
            tri_lb <= tri + TOL && tri_lb > 0.5 * tri,
            "{tri_lb} vs {tri}"
        );
        assert!(
            disc_lb <= disc + TOL && disc_lb > 0.5 * disc,
            "{disc_lb} vs {disc}"
        );
    }
}

// ---------------------------------------------------------------- known answers

/// One point p: the closed box [0,p] has excess 1 - px py; the open boxes [0,px) x [0,1)
/// and [0,1) x [0,py) miss it (deficits px, py); every other critical box does worse.
#[test]
fn single_point_star_discrepancy() {
    assert!((star_discrepancy_sup(&[d(0.5, 0.5)]) - 0.75).abs() < TOL);
    assert_eq!(star_discrepancy_sup(&[DVec2::ZERO]), 1.0);
    for p in [d(0.9, 0.2), d(0.3, 0.95), d(0.1, 0.1), d(0.7, 0.7)] {
        let expected = (1.0 - p.x * p.y).max(p.x).max(p.y);
        assert!((star_discrepancy_sup(&[p]) - expected).abs() < TOL, "{p}");
    }
    // The optimal single point sits at (g, g), g = (sqrt 5 - 1)/2, where 1 - g^2 = g.
    let g = (5.0f64.sqrt() - 1.0) / 2.0;
    assert!((star_discrepancy_sup(&[d(g, g)]) - g).abs() < 1e-15);
}

/// The centred m x m grid: the worst box is the closed [0, 1 - 1/(2m)]^2 holding all
/// points, excess 1/m - 1/(4 m^2). The lattice {i/m} x {j/m}: the closed box
/// [0, (m-1)/m]^2 holds all points, excess (2m - 1)/m^2.
#[test]
fn regular_grids() {
    for m in [1usize, 2, 3, 7, 16] {
        let mf = m as f64;
        let centred: Vec<DVec2> = (0..m * m)
            .map(|k| d(((k % m) as f64 + 0.5) / mf, ((k / m) as f64 + 0.5) / mf))
            .collect();
        let expected = 1.0 / mf - 0.25 / (mf * mf);
        assert!(
            (star_discrepancy_sup(&centred) - expected).abs() < TOL,
            "m = {m}"
        );
        let lattice: Vec<DVec2> = (0..m * m)
            .map(|k| d((k % m) as f64 / mf, (k / m) as f64 / mf))
            .collect();
        let expected = (2.0 * mf - 1.0) / (mf * mf);
        assert!(
            (star_discrepancy_sup(&lattice) - expected).abs() < TOL,
            "m = {m}"
        );
    }
}

/// Half the points at (1/4, 1/4), half at (3/4, 3/4): the closed boxes [0, 1/4]^2 and
/// [0, 3/4]^2 both have excess 7/16; the best deficit is 1/4.
#[test]
fn duplicated_points() {
    let mut points = vec![d(0.25, 0.25); 5];
    points.extend(vec![d(0.75, 0.75); 5]);
    assert!((star_discrepancy_sup(&points) - 7.0 / 16.0).abs() < TOL);
    assert!((star_discrepancy_sup(&[d(0.5, 0.5); 9]) - 0.75).abs() < TOL);
}

/// T^2 for one point p: 1/9 - 2 (1 - px^2)(1 - py^2)/4 + (1 - px)(1 - py).
#[test]
fn single_point_l2() {
    assert!((star_discrepancy_l2(&[DVec2::ZERO]) - (11.0f64 / 18.0).sqrt()).abs() < TOL);
    for p in [d(0.5, 0.5), d(0.9, 0.2), d(0.0, 1.0)] {
        let t2 =
            1.0 / 9.0 - 0.5 * (1.0 - p.x * p.x) * (1.0 - p.y * p.y) + (1.0 - p.x) * (1.0 - p.y);
        assert!((star_discrepancy_l2(&[p]) - t2.sqrt()).abs() < TOL, "{p}");
    }
    // A point at (1, 1) lies in no box: T^2 = integral of (x y)^2 = 1/9.
    assert!((star_discrepancy_l2(&[DVec2::ONE]) - 1.0 / 3.0).abs() < TOL);
}

/// Warnock's formula against a plain midpoint-rule integration of the local discrepancy.
#[test]
fn l2_matches_midpoint_integration() {
    let points = baseline::uniform_random(7, 5);
    let cells = 600;
    let h = 1.0 / cells as f64;
    let mut sum = 0.0;
    for i in 0..cells {
        for j in 0..cells {
            let (x, y) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
            let count = points.iter().filter(|p| p.x < x && p.y < y).count();
            sum += (frac(count, 7) - x * y).powi(2) * h * h;
        }
    }
    let t = star_discrepancy_l2(&points);
    assert!(
        (t - sum.sqrt()).abs() < 2e-3,
        "warnock {t}, midpoint {}",
        sum.sqrt()
    );
}

/// One interior point p with px + py <= 1, px, py <= 1/2: the smallest closed triangle
/// holding it has p at the middle of its hypotenuse (area 2 px py).
#[test]
fn single_point_triangles() {
    let t = triangles().sup(&[d(0.25, 0.25)]);
    assert!((t - (1.0 - 2.0 * 0.25 * 0.25)).abs() < TOL, "{t}");
    assert_eq!(triangles().sup(&[DVec2::ZERO]), 1.0);
    // A point beyond every triangle: the whole triangle a = b = 1 is empty.
    assert!((triangles().sup(&[d(0.9, 0.9)]) - 0.5).abs() < TOL);
    assert_eq!(triangles().sup(&[]), 0.5);
}

#[test]
fn single_point_discs() {
    let t = discs().sup(&[d(0.3, 0.4)]);
    assert!((t - (1.0 - PI / 16.0)).abs() < TOL, "{t}");
    // With 4:1 anisotropy (0.3, 0.4) maps to (0.3, 1.6), outside every disc of radius
    // <= 1 in the domain [0,1] x [0,4]: the largest disc, empty, has area pi/16.
    let t = discs().with_axis_scale(d(1.0, 4.0)).sup(&[d(0.3, 0.4)]);
    assert!((t - PI / 16.0).abs() < TOL, "{t}");
    assert!((discs().sup(&[]) - FRAC_PI_4).abs() < TOL);
}

#[test]
fn empty_sets() {
    assert_eq!(star_discrepancy_sup(&[]), 1.0);
    assert!((star_discrepancy_l2(&[]) - 1.0 / 3.0).abs() < TOL);
}

// ---------------------------------------------------------------- errors, determinism

#[test]
fn points_outside_are_errors() {
    let bad = [d(0.5, 0.5), d(f64::NAN, 0.2)];
    let err = try_star_discrepancy_sup(&bad);
    assert!(matches!(
        err,
        Err(AnalysisError::PointOutsideUnitSquare { index: 1, .. })
    ));
    assert!(try_star_discrepancy_l2(&[d(1.5, 0.0)]).is_err());
    assert!(triangles().try_sup(&[d(-0.1, 0.0)]).is_err());
    assert!(matches!(
        discs().with_axis_scale(d(0.0, 1.0)).try_sup(&[]),
        Err(AnalysisError::InvalidAxisScale { .. })
    ));
}

#[test]
#[should_panic(expected = "not in the unit square")]
fn panicking_twin_panics() {
    star_discrepancy_sup(&[d(2.0, 0.0)]);
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let points = baseline::uniform_random(700, 3);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        pool.install(|| {
            (
                star_discrepancy_sup(&points).to_bits(),
                star_discrepancy_l2(&points).to_bits(),
                triangles().sup(&points).to_bits(),
            )
        })
    };
    assert_eq!(run(1), run(4));
}

#[test]
fn loglog_slope_recovers_power_laws() {
    let ns = [64.0, 96.0, 128.0, 1024.0];
    let values: Vec<f64> = ns.iter().map(|n: &f64| 0.3 * n.powf(-0.6)).collect();
    assert!((loglog_slope(&ns, &values) - 0.6).abs() < 1e-12);
    assert!(loglog_slope(&ns[..1], &values[..1]).is_nan());
    assert!(loglog_slope(&[2.0, 2.0], &[1.0, 0.5]).is_nan());
    assert!(loglog_slope(&[2.0, 4.0], &[1.0, 0.0]).is_nan());
}

#[test]
fn curve_rejects_bad_samplers() {
    let short = |n: usize, seed: u64| baseline::uniform_random(n.saturating_sub(1), seed);
    let err = DiscrepancyCurve::measure(&Discrepancy::default(), short, &[8], &[1]);
    assert!(matches!(
        err,
        Err(AnalysisError::WrongSampleCount { returned: 7, .. })
    ));
    let outside = |n: usize, _| vec![d(1.5, 0.5); n];
    let err = DiscrepancyCurve::measure(&Discrepancy::default(), outside, &[4], &[1]);
    assert!(matches!(err, Err(AnalysisError::SamplerPoint { .. })));
    let err =
        DiscrepancyCurve::measure(&Discrepancy::default(), baseline::uniform_random, &[4], &[]);
    assert!(matches!(err, Err(AnalysisError::EmptyCurve { .. })));
}
