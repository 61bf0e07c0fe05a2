//! Exact 2D orientation predicate and the closed-segment intersection test built on it.
//!
//! [`orient2d`] is the sign of the `robust` crate's port of Shewchuk's adaptive
//! predicate: a floating-point evaluation with a forward error bound decides almost all
//! calls, and the rare close calls are refined in exact expansion arithmetic. Exact for
//! all finite inputs whose products neither overflow nor underflow (|coordinates|
//! between about 1e-145 and 1e145, or zero). Only the sign is used here (no caller
//! reads the determinant's magnitude), so any exact predicate gives the same results.
//! Cost: a few flops; a close call a few hundred.
//!
//! Reference: J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast
//! robust geometric predicates", Discrete & Computational Geometry 18, 1997.

use std::cmp::Ordering;

use glam::DVec2;

/// The exact orientation of the triangle `(a, b, c)`: `Greater` if counter-clockwise
/// (positive signed area), `Less` if clockwise, `Equal` if the points are collinear.
/// Non-finite input gives `Equal`.
///
/// ```
/// use std::cmp::Ordering;
/// use glam::DVec2;
/// use strata_engine::param::predicates::orient2d;
/// let (a, b) = (DVec2::new(0.5, 0.5), DVec2::new(12.0, 12.0));
/// // 24 + 2^-48 (one ulp) is a hair above the line y = x through a and b.
/// let c = DVec2::new(24.0, 24.0 + 2f64.powi(-48));
/// assert_eq!(orient2d(a, b, c), Ordering::Greater);
/// assert_eq!(orient2d(a, b, DVec2::new(24.0, 24.0)), Ordering::Equal);
/// ```
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> Ordering {
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return Ordering::Equal;
    }
    let coord = |p: DVec2| robust::Coord { x: p.x, y: p.y };
    robust::orient2d(coord(a), coord(b), coord(c))
        .partial_cmp(&0.0)
        .unwrap_or(Ordering::Equal)
}

/// Whether point `q`, known to be collinear with `a` and `b`, lies on the closed
/// segment `[a, b]` (exact: coordinate comparisons only).
fn on_segment(a: DVec2, b: DVec2, q: DVec2) -> bool {
    a.x.min(b.x) <= q.x && q.x <= a.x.max(b.x) && a.y.min(b.y) <= q.y && q.y <= a.y.max(b.y)
}

/// Whether the closed segments `[p1, p2]` and `[q1, q2]` share at least one point
/// (touching and collinear overlap included), decided exactly.
pub fn segments_intersect(p1: DVec2, p2: DVec2, q1: DVec2, q2: DVec2) -> bool {
    let o1 = orient2d(p1, p2, q1);
    let o2 = orient2d(p1, p2, q2);
    let o3 = orient2d(q1, q2, p1);
    let o4 = orient2d(q1, q2, p2);
    let opposite = |x: Ordering, y: Ordering| x != Ordering::Equal && y == x.reverse();
    if opposite(o1, o2) && opposite(o3, o4) {
        return true;
    }
    (o1 == Ordering::Equal && on_segment(p1, p2, q1))
        || (o2 == Ordering::Equal && on_segment(p1, p2, q2))
        || (o3 == Ordering::Equal && on_segment(q1, q2, p1))
        || (o4 == Ordering::Equal && on_segment(q1, q2, p2))
}

/// Whether the segments `[s, a]` and `[s, b]`, which share the endpoint `s`, have
/// another point in common: they are collinear and leave `s` on the same side (exact).
pub fn segments_overlap_from(s: DVec2, a: DVec2, b: DVec2) -> bool {
    if a == s || b == s || orient2d(s, a, b) != Ordering::Equal {
        return false;
    }
    // Collinear: compare the direction from s along x, or along y for a vertical line.
    if a.x != s.x {
        (a.x > s.x) == (b.x > s.x)
    } else {
        (a.y > s.y) == (b.y > s.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact orientation of points whose coordinates are integers times 2^-53, in i128.
    fn exact_sign(a: DVec2, b: DVec2, c: DVec2) -> Ordering {
        let k = 2f64.powi(53);
        let i = |x: f64| {
            let s = x * k;
            assert_eq!(s, s.trunc());
            s as i128
        };
        let (ax, ay, bx, by, cx, cy) = (i(a.x), i(a.y), i(b.x), i(b.y), i(c.x), i(c.y));
        ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)).cmp(&0)
    }

    #[test]
    fn orient2d_is_exact_near_a_line_where_naive_is_not() {
        // Shewchuk's classic: points within a few ulps of the line through (12, 12) and
        // (24, 24), where the naive determinant gets many signs wrong.
        let ulp = 2f64.powi(-53);
        let (b, c) = (DVec2::new(12.0, 12.0), DVec2::new(24.0, 24.0));
        let (mut naive_wrong, mut total) = (0, 0);
        for i in 0..64 {
            for j in 0..64 {
                let a = DVec2::new(0.5 + i as f64 * ulp, 0.5 + j as f64 * ulp);
                let expected = exact_sign(a, b, c);
                assert_eq!(orient2d(a, b, c), expected, "a = {a:?}");
                assert_eq!(orient2d(b, c, a), expected);
                assert_eq!(orient2d(c, b, a), expected.reverse());
                let naive = (b - a).perp_dot(c - a).partial_cmp(&0.0);
                naive_wrong += usize::from(naive != Some(expected));
                total += 1;
            }
        }
        // The test would prove nothing if the naive formula were right everywhere.
        assert!(naive_wrong > total / 10, "{naive_wrong} of {total}");
    }

    #[test]
    fn orient2d_signs_and_degenerate_cases() {
        let o = DVec2::ZERO;
        assert_eq!(orient2d(o, DVec2::X, DVec2::Y), Ordering::Greater);
        assert_eq!(orient2d(o, DVec2::Y, DVec2::X), Ordering::Less);
        assert_eq!(orient2d(o, o, DVec2::X), Ordering::Equal);
        assert_eq!(
            orient2d(o, DVec2::X, DVec2::new(f64::NAN, 1.0)),
            Ordering::Equal
        );
        // Tiny but representable area, far from the origin.
        let big = 1e15;
        let a = DVec2::new(big, big);
        let b = DVec2::new(big + 1.0, big);
        let c = DVec2::new(big, big + 0.125);
        assert_eq!(orient2d(a, b, c), Ordering::Greater);
    }

    #[test]
    fn segment_intersection_cases() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        // Proper crossing, touching at an endpoint, T-junction, disjoint, collinear.
        assert!(segments_intersect(
            p(0., 0.),
            p(1., 1.),
            p(0., 1.),
            p(1., 0.)
        ));
        assert!(segments_intersect(
            p(0., 0.),
            p(1., 0.),
            p(1., 0.),
            p(2., 5.)
        ));
        assert!(segments_intersect(
            p(0., 0.),
            p(2., 0.),
            p(1., 0.),
            p(1., 3.)
        ));
        assert!(!segments_intersect(
            p(0., 0.),
            p(1., 0.),
            p(0., 1.),
            p(1., 1.)
        ));
        assert!(segments_intersect(
            p(0., 0.),
            p(2., 0.),
            p(1., 0.),
            p(3., 0.)
        ));
        assert!(!segments_intersect(
            p(0., 0.),
            p(1., 0.),
            p(2., 0.),
            p(3., 0.)
        ));
        // Shared endpoint: only a collinear fold-back counts.
        assert!(segments_overlap_from(p(0., 0.), p(1., 1.), p(2., 2.)));
        assert!(!segments_overlap_from(p(0., 0.), p(1., 1.), p(-2., -2.)));
        assert!(!segments_overlap_from(p(0., 0.), p(1., 1.), p(1., 0.)));
        assert!(segments_overlap_from(p(0., 0.), p(0., 1.), p(0., 2.)));
    }
}
