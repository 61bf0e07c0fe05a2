use glam::DVec2;

use super::*;

/// A fan-triangulated disc of `k` segments inside the unit square, with density
/// `1 + 3 u` (linear, so cell measures are exact).
fn disc(k: usize) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>) {
    disc_with_slope(k, 3.0)
}

/// As [`disc`], with density `1 + slope u`.
fn disc_with_slope(k: usize, slope: f64) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>) {
    let c = DVec2::new(0.47, 0.52);
    let mut uv = vec![c];
    for i in 0..k {
        let a = std::f64::consts::TAU * i as f64 / k as f64;
        uv.push(c + DVec2::new(a.cos(), a.sin()) * 0.4);
    }
    let tris: Vec<[u32; 3]> = (0..k as u32)
        .map(|i| [0, 1 + i, 1 + (i + 1) % k as u32])
        .collect();
    let dens = tris
        .iter()
        .map(|t| t.map(|v| 1.0 + slope * uv[v as usize].x))
        .collect();
    (uv, tris, dens)
}

/// The curve of the domain `uv`, `t`, `d` with options `opts`, which must be valid.
fn curve(uv: &[DVec2], t: &[[u32; 3]], d: &[[f64; 3]], opts: &CurveOptions) -> SegmentCurve {
    SegmentCurve::build(
        &CurveDomain {
            uv,
            triangles: t,
            corner_density: d,
        },
        opts,
    )
    .expect("valid")
}

fn exact_measure(uv: &[DVec2], tris: &[[u32; 3]], dens: &[[f64; 3]]) -> f64 {
    tris.iter()
        .zip(dens)
        .map(|(t, d)| {
            let p = t.map(|v| uv[v as usize]);
            0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]) * (d[0] + d[1] + d[2]) / 3.0
        })
        .sum()
}

fn square() -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>) {
    (
        vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
        vec![[0, 1, 2], [0, 2, 3]],
        vec![[1.0; 3]; 2],
    )
}

#[test]
fn uniform_square_has_a_regular_grid_of_full_cells() {
    let (uv, t, d) = square();
    let opts = CurveOptions {
        max_cell_share: 1.0 / 4096.0,
        ..Default::default()
    };
    let c = curve(&uv, &t, &d, &opts);
    assert_eq!(c.cell_count(), 4096);
    assert!(c.cells().iter().all(|k| k.full() && k.level() == 6));
    assert!((c.measure() - 1.0).abs() < 1e-12);
    // Leaves come in Hilbert order: their indices at level 6 are 0, 1, 2, ...
    for (i, k) in c.cells().iter().enumerate() {
        assert_eq!(hilbert::xy2d(6, k.x(), k.y()), i as u64);
    }
}

#[test]
fn disc_measure_is_exact_and_leaves_are_consecutive_neighbours() {
    let (uv, t, d) = disc(64);
    let opts = CurveOptions {
        max_cell_share: 1e-3,
        boundary_level: 8,
        ..Default::default()
    };
    let c = curve(&uv, &t, &d, &opts);
    let exact = exact_measure(&uv, &t, &d);
    assert!(
        (c.measure() - exact).abs() < 1e-12 * exact,
        "{} vs {exact}",
        c.measure()
    );
    assert!(c.cells().iter().any(|k| !k.full()), "boundary cells exist");
    assert!(
        c.cells()
            .iter()
            .filter(|k| !k.full())
            .all(|k| k.level() >= 8)
    );
    let cum = c.cumulative();
    assert!(cum.windows(2).all(|w| w[1] > w[0]));
}

#[test]
fn adaptive_leaves_of_a_full_square_are_consecutive_neighbours() {
    // Density varying over two orders of magnitude: leaves at many levels, none empty.
    let (uv, t, _) = square();
    let d: Vec<[f64; 3]> = t
        .iter()
        .map(|tri| tri.map(|v| 0.01 + 4.0 * uv[v as usize].length_squared()))
        .collect();
    let opts = CurveOptions {
        max_cell_share: 1e-3,
        ..Default::default()
    };
    let c = curve(&uv, &t, &d, &opts);
    let levels: std::collections::BTreeSet<u8> = c.cells().iter().map(|k| k.level()).collect();
    assert!(levels.len() >= 3, "adaptive: {levels:?}");
    let area: f64 = c.cells().iter().map(|k| k.size() * k.size()).sum();
    assert!((area - 1.0).abs() < 1e-12, "leaves tile the square");
    // An adaptive Hilbert curve visits leaves so that consecutive ones touch along an
    // edge (closed squares intersect in a segment of positive length).
    for w in c.cells().windows(2) {
        let (a, b) = (w[0], w[1]);
        let (alo, ahi) = (a.origin(), a.origin() + DVec2::splat(a.size()));
        let (blo, bhi) = (b.origin(), b.origin() + DVec2::splat(b.size()));
        let ox = ahi.x.min(bhi.x) - alo.x.max(blo.x);
        let oy = ahi.y.min(bhi.y) - alo.y.max(blo.y);
        assert!(
            ox >= -1e-15 && oy >= -1e-15 && ox.max(oy) > 1e-15,
            "{a:?} {b:?}"
        );
    }
}

#[test]
fn located_points_lie_in_the_domain_and_follow_the_measure() {
    check_located_points(
        disc(48),
        CurveOptions {
            max_cell_share: 1e-3,
            boundary_level: 6,
            ..Default::default()
        },
        2.0,
    );
    // Few, large boundary leaves overlapping many triangles: the descent's candidate
    // lists overflow their stack buffers and fall back to the leaf's whole list. (The
    // density is constant: inside fully covered sub-cells the map is uniform, which
    // only a bounded cell share makes accurate for a varying density.)
    check_located_points(
        disc_with_slope(160, 0.0),
        CurveOptions {
            max_cell_share: 1.0,
            boundary_level: 1,
            ..Default::default()
        },
        // A half-plane count over points along a Hilbert curve errs by about N^(1/4)
        // (the cells the line crosses at the samples' resolution); small cells above
        // happen to do better.
        2.0 * 20_000f64.powf(0.25),
    );
}

fn check_located_points(
    (uv, t, d): (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>),
    opts: CurveOptions,
    tolerance: f64,
) {
    let c = curve(&uv, &t, &d, &opts);
    let n = 20_000;
    let mut left = 0usize;
    for k in 0..n {
        let m = (k as f64 + 0.5) / n as f64 * c.measure();
        let p = c.locate(m);
        assert!(
            p.bary.iter().all(|&b| (-1e-12..=1.0 + 1e-12).contains(&b)),
            "{p:?}"
        );
        let tri = t[p.triangle as usize].map(|v| uv[v as usize]);
        let back = tri[0] * p.bary[0] + tri[1] * p.bary[1] + tri[2] * p.bary[2];
        assert!((back - p.uv).length() < 1e-12);
        left += (p.uv.x < 0.47) as usize;
    }
    // Exact measure of the left half of the disc (x < cx) with density 1 + 3x: area
    // pi r^2 / 2 times the mean density there, 1 + 3 (cx - 4r / (3 pi)); for the
    // inscribed 48-gon use the polygon itself: integrate by clipping.
    let mut left_measure = 0.0;
    for (tri, dd) in t.iter().zip(&d) {
        let p = tri.map(|v| uv[v as usize]);
        let poly = clip_triangle(&p, DVec2::new(-1.53, -1.0), 2.0);
        let (a, cen) = poly.area_centroid();
        let dens = barycentric(&p, cen);
        left_measure += a * (dens[0] * dd[0] + dens[1] * dd[1] + dens[2] * dd[2]);
    }
    let expect = n as f64 * left_measure / c.measure();
    assert!(
        (left as f64 - expect).abs() <= tolerance,
        "left {left}, expected {expect}"
    );
}

#[test]
fn bad_domains_are_rejected() {
    let (uv, t, d) = square();
    let opts = CurveOptions::default();
    let flipped = vec![[0u32, 2, 1]];
    assert!(matches!(
        SegmentCurve::build(
            &CurveDomain {
                uv: &uv,
                triangles: &flipped,
                corner_density: &d[..1]
            },
            &opts
        ),
        Err(CurveError::BadTriangle { triangle: 0 })
    ));
    let outside = vec![DVec2::ZERO, DVec2::new(1.5, 0.0), DVec2::ONE, DVec2::Y];
    assert!(matches!(
        SegmentCurve::build(
            &CurveDomain {
                uv: &outside,
                triangles: &t,
                corner_density: &d
            },
            &opts
        ),
        Err(CurveError::OutsideUnitSquare { vertex: 1, .. })
    ));
    let nan = vec![[f64::NAN, 1.0, 1.0], [1.0; 3]];
    assert!(matches!(
        SegmentCurve::build(
            &CurveDomain {
                uv: &uv,
                triangles: &t,
                corner_density: &nan
            },
            &opts
        ),
        Err(CurveError::BadDensity { triangle: 0 })
    ));
    let zero = vec![[0.0; 3]; 2];
    assert!(matches!(
        SegmentCurve::build(
            &CurveDomain {
                uv: &uv,
                triangles: &t,
                corner_density: &zero
            },
            &opts
        ),
        Err(CurveError::ZeroMeasure)
    ));
    let bad = CurveOptions {
        max_cell_share: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        SegmentCurve::build(
            &CurveDomain {
                uv: &uv,
                triangles: &t,
                corner_density: &d
            },
            &bad
        ),
        Err(CurveError::InvalidOption {
            option: "max_cell_share",
            ..
        })
    ));
}

#[test]
fn cell_budgets_beyond_memory_are_refused_naming_the_option() {
    let at = |max_cell_share| CurveOptions {
        max_cell_share,
        ..Default::default()
    };
    assert!(at(CurveOptions::MIN_CELL_SHARE).validate().is_ok());
    let e = at(1e-9).validate().expect_err("1e-9 needs about 50 GB");
    assert!(
        matches!(e, CurveError::CellBudget { cells, bytes, .. } if (cells - 2e9).abs() < 1.0 && (bytes - 5e10).abs() < 100.0),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "curve option `max_cell_share` = 1e-9 asks for about 2.0e9 cells (50.0 GB); \
         the smallest allowed is 2^-24 = 5.96e-8 (about 34 million cells, 0.8 GB)"
    );
    // Just under the limit is refused too: the check is the budget, not a round number.
    assert!(at(CurveOptions::MIN_CELL_SHARE * 0.99).validate().is_err());
}

/// An annulus of `k` quads (two triangles each) around (0.5, 0.5), radii 0.12 and 0.45,
/// with density `1 + 2 u + v`: boundary leaves on both circles, several triangles each.
fn annulus(k: usize) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>) {
    let c = DVec2::splat(0.5);
    let mut uv = Vec::new();
    for i in 0..k {
        let a = std::f64::consts::TAU * i as f64 / k as f64;
        let d = DVec2::new(a.cos(), a.sin());
        uv.push(c + d * 0.12);
        uv.push(c + d * 0.45);
    }
    let k = k as u32;
    let mut tris = Vec::new();
    for i in 0..k {
        let j = (i + 1) % k;
        let (a, b, cc, d) = (2 * i, 2 * i + 1, 2 * j, 2 * j + 1);
        tris.push([a, b, d]);
        tris.push([a, d, cc]);
    }
    let dens = tris
        .iter()
        .map(|t| t.map(|v| 1.0 + 2.0 * uv[v as usize].x + uv[v as usize].y))
        .collect();
    (uv, tris, dens)
}

#[test]
fn splitting_descent_matches_the_clipping_descent() {
    let cases = [
        (
            disc(48),
            CurveOptions {
                max_cell_share: 1e-3,
                boundary_level: 6,
                ..Default::default()
            },
        ),
        (
            disc_with_slope(7, 2.0),
            CurveOptions {
                max_cell_share: 0.05,
                boundary_level: 2,
                ..Default::default()
            },
        ),
        (
            annulus(40),
            CurveOptions {
                max_cell_share: 2e-3,
                boundary_level: 5,
                ..Default::default()
            },
        ),
    ];
    for ((uv, t, d), opts) in cases {
        let c = curve(&uv, &t, &d, &opts);
        let (mut checked, mut differ) = (0usize, 0usize);
        for leaf in (0..c.cell_count()).filter(|&i| !c.cells()[i].full()) {
            for k in 0..23 {
                let f = (k as f64 + 0.37) / 23.0;
                for levels in [1, 3, 7, 12] {
                    let a = c.point_in_leaf_to(leaf, f, levels);
                    let b = c.point_in_leaf_general(leaf, f, levels);
                    let tri = t[a.triangle as usize].map(|v| uv[v as usize]);
                    assert!(a.bary.iter().all(|&x| (0.0..=1.0).contains(&x)), "{a:?}");
                    let back = tri[0] * a.bary[0] + tri[1] * a.bary[1] + tri[2] * a.bary[2];
                    assert!((back - a.uv).length() < 1e-12);
                    checked += 1;
                    // Round-off in the measures can only move a point whose target
                    // lies within about 1e-15 of a sub-cell's end to another sub-cell;
                    // inside the last sub-cell the placement is continuous, and the
                    // two descents' measures (split versus clipped pieces) move it by
                    // their round-off over the piece's measure, here below 1e-7.
                    if (a.uv - b.uv).length() > 1e-7 {
                        differ += 1;
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked} points in boundary leaves");
        assert!(
            differ * 1000 <= checked,
            "{differ} of {checked} points differ"
        );
    }
}

#[test]
fn a_reused_scratch_gives_the_points_of_a_fresh_one() {
    // The scratch caches the last boundary leaf's clipped candidates: interleaving two
    // curves (same leaf indices, different triangles) and revisiting leaves must give
    // exactly the points of a fresh scratch, with and without exact levels.
    let opts = CurveOptions {
        max_cell_share: 0.01,
        boundary_level: 4,
        ..Default::default()
    };
    let build = |(uv, t, d): (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>)| curve(&uv, &t, &d, &opts);
    let curves = [
        build(disc_with_slope(9, 1.0)),
        build(disc_with_slope(13, 4.0)),
    ];
    let mut scratch = LeafScratch::default();
    let mut checked = 0;
    for leaf in 0..curves[0].cell_count().min(curves[1].cell_count()) {
        // Consecutive values in one leaf (cache hits), then the curves interleaved
        // at the same leaf index (the cache must tell them apart).
        let visits = (0..2)
            .flat_map(|c| (0..3).map(move |k| (c, k)))
            .chain((0..3).flat_map(|k| (0..2).map(move |c| (c, k))));
        for (c, k) in visits {
            let c = &curves[c];
            if c.cells()[leaf].full() {
                continue;
            }
            let f = (k as f64 + 0.61) / 3.0;
            // Six levels fill the cache; no levels then read the cached pieces, where
            // a fresh scratch clips candidates only up to the chosen piece.
            for levels in [6, 0] {
                let reused = c.point_in_leaf_with(leaf, f, levels, &mut scratch);
                assert_eq!(
                    reused,
                    c.point_in_leaf_to(leaf, f, levels),
                    "leaf {leaf} k {k} levels {levels}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked} boundary points");
}

/// With no exact levels, a boundary leaf places a stratified set of fractions by the
/// measures of its triangle pieces: each triangle gets its share of the leaf's measure
/// within one point (the piece is chosen by measure, not by area or by order), and
/// every point lies in its triangle.
#[test]
fn boundary_leaf_without_levels_follows_the_piece_measures() {
    let (uv, t, d) = annulus(40);
    let c = curve(
        &uv,
        &t,
        &d,
        &CurveOptions {
            max_cell_share: 2e-3,
            boundary_level: 3,
            ..Default::default()
        },
    );
    let mut checked = 0;
    for leaf in (0..c.cell_count()).filter(|&i| !c.cells()[i].full()) {
        let key = c.cells()[leaf];
        let total = c.cumulative()[leaf + 1] - c.cumulative()[leaf];
        // Exact measure of each triangle in the leaf, by clipping.
        let mut want = std::collections::BTreeMap::new();
        for (i, tri) in t.iter().enumerate() {
            let corners = tri.map(|v| uv[v as usize]);
            let (area, centroid) =
                clip_triangle(&corners, key.origin(), key.size()).area_centroid();
            if area > 0.0 {
                let b = barycentric(&corners, centroid);
                let density: f64 = (0..3).map(|k| b[k] * d[i][k]).sum();
                want.insert(i as u32, area * density / total);
            }
        }
        if want.len() < 2 {
            continue;
        }
        let n = 400;
        let mut got = std::collections::BTreeMap::new();
        for k in 0..n {
            let p = c.point_in_leaf_to(leaf, (k as f64 + 0.5) / n as f64, 0);
            let corners = t[p.triangle as usize].map(|v| uv[v as usize]);
            let b = barycentric(&corners, p.uv);
            assert!(b.iter().all(|&x| x > -1e-9), "{p:?} outside its triangle");
            *got.entry(p.triangle).or_insert(0usize) += 1;
        }
        for (tri, share) in &want {
            let count = got.get(tri).copied().unwrap_or(0) as f64;
            assert!(
                (count - share * n as f64).abs() <= 1.0 + 1e-9,
                "leaf {leaf} triangle {tri}: {count} points for share {share}"
            );
        }
        checked += 1;
    }
    assert!(
        checked > 10,
        "{checked} boundary leaves with several triangles"
    );
}

#[test]
fn leaf_parts_cover_each_leaf_and_hold_its_points() {
    let (uv, t, d) = disc(48);
    let c = curve(
        &uv,
        &t,
        &d,
        &CurveOptions {
            max_cell_share: 1e-3,
            boundary_level: 6,
            ..Default::default()
        },
    );
    let corners = |tri: u32| t[tri as usize].map(|v| uv[v as usize]);
    let (mut full, mut boundary) = (0, 0);
    for leaf in 0..c.cell_count() {
        let key = c.cells()[leaf];
        let (lo, size) = (key.origin(), key.size());
        // Per triangle, its part's corners mapped back to the plane.
        let mut parts: Vec<(u32, Vec<DVec2>)> = Vec::new();
        c.leaf_part_corners(leaf, |tri, b| {
            assert!(b.iter().all(|&x| x >= 0.0) && (b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let p = corners(tri);
            let q = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
            assert!(
                q.cmpge(lo - 1e-12).all() && q.cmple(lo + size + 1e-12).all(),
                "leaf {leaf}: corner {q} outside the cell"
            );
            match parts.last_mut() {
                Some((last, pts)) if *last == tri => pts.push(q),
                _ => parts.push((tri, vec![q])),
            }
        });
        // The parts tile the leaf's share of the domain: the whole cell when full.
        let area: f64 = parts
            .iter()
            .map(|(_, pts)| {
                let n = pts.len();
                (0..n)
                    .map(|i| pts[i].perp_dot(pts[(i + 1) % n]))
                    .sum::<f64>()
                    / 2.0
            })
            .sum();
        if key.full() {
            assert!(
                (area - size * size).abs() < 1e-9 * size * size,
                "leaf {leaf}"
            );
            full += 1;
        } else {
            assert!(
                area > 0.0 && area < size * size * (1.0 + 1e-9),
                "leaf {leaf}"
            );
            boundary += 1;
        }
        // Points placed in the leaf are convex combinations of their part's corners:
        // inside the part's polygon.
        for k in 0..8 {
            let p = c.point_in_leaf(leaf, (k as f64 + 0.5) / 8.0);
            let (_, pts) = parts
                .iter()
                .find(|(tri, _)| *tri == p.triangle)
                .expect("a point's triangle has a part in its leaf");
            let n = pts.len();
            assert!(
                (0..n).all(|i| (pts[(i + 1) % n] - pts[i]).perp_dot(p.uv - pts[i]) >= -1e-12),
                "leaf {leaf}: point {} outside its part",
                p.uv
            );
        }
    }
    assert!(
        full > 10 && boundary > 10,
        "{full} full, {boundary} boundary"
    );
}
