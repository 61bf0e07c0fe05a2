//! Exact triangle-square overlap: Sutherland-Hodgman clipping of a triangle against an
//! axis-aligned square, and the integral of a linear function over the result.

use glam::DVec2;

/// A convex polygon of at most 7 corners (a triangle clipped by 4 half-planes).
#[derive(Clone, Copy, Debug)]
pub struct Poly {
    pts: [DVec2; 8],
    len: usize,
}

impl Poly {
    /// The polygon with no corners.
    pub(crate) const EMPTY: Poly = Poly {
        pts: [DVec2::ZERO; 8],
        len: 0,
    };

    /// The corners.
    pub fn points(&self) -> &[DVec2] {
        &self.pts[..self.len]
    }

    /// Area (non-negative for counter-clockwise input) and area centroid.
    pub fn area_centroid(&self) -> (f64, DVec2) {
        let (area, moment) = self.area_moment();
        if area.abs() <= 0.0 {
            return (0.0, self.points().first().copied().unwrap_or(DVec2::ZERO));
        }
        (area, moment / area)
    }
}

impl Poly {
    /// Area and first moment (integral of `p` over the polygon): the exact integral of
    /// an affine function `g . p + h` over it is `g . moment + h area`. No division.
    #[inline]
    pub(crate) fn area_moment(&self) -> (f64, DVec2) {
        let p = self.points();
        if p.len() < 3 {
            return (0.0, DVec2::ZERO);
        }
        let mut a2 = 0.0;
        let mut c = DVec2::ZERO;
        for k in 1..p.len() - 1 {
            let cross = (p[k] - p[0]).perp_dot(p[k + 1] - p[0]);
            a2 += cross;
            c += (p[0] + p[k] + p[k + 1]) * cross;
        }
        (0.5 * a2, c * (1.0 / 6.0))
    }

    /// Splits the polygon (convex) by the line where coordinate `AXIS` (0: x, 1: y)
    /// equals `at` into `below` (the part at or below `at`) and `above`, overwriting
    /// both. Corners on the line go to both; crossing points are put exactly on it.
    #[inline]
    pub(crate) fn split_into<const AXIS: usize>(
        &self,
        at: f64,
        below: &mut Poly,
        above: &mut Poly,
    ) {
        let coord = |p: DVec2| if AXIS == 0 { p.x } else { p.y };
        // Corner counts in locals (not through the two `&mut`), written back at the end.
        let (mut nb, mut na) = (0usize, 0usize);
        // A convex polygon cut by a line gains at most one corner; the bound of 8 only
        // guards against round-off duplicates.
        let p = self.points();
        if let Some(&last) = p.last() {
            let mut prev = last;
            let mut dp = coord(prev) - at;
            for &q in p {
                let dq = coord(q) - at;
                if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                    let mut x = prev + (q - prev) * (dp / (dp - dq));
                    if AXIS == 0 {
                        x.x = at;
                    } else {
                        x.y = at;
                    }
                    if nb < 8 {
                        below.pts[nb] = x;
                        nb += 1;
                    }
                    if na < 8 {
                        above.pts[na] = x;
                        na += 1;
                    }
                }
                if dq <= 0.0 && nb < 8 {
                    below.pts[nb] = q;
                    nb += 1;
                }
                if dq >= 0.0 && na < 8 {
                    above.pts[na] = q;
                    na += 1;
                }
                prev = q;
                dp = dq;
            }
        }
        below.len = nb;
        above.len = na;
    }
}

/// Clips triangle `tri` (counter-clockwise) to the square `[lo, lo + size]^2`.
///
/// Sutherland-Hodgman against the four sides, each side a specialised pass, and a side
/// that the polygon lies entirely inside of is skipped (most triangles cross one or two
/// sides of a cell).
pub fn clip_triangle(tri: &[DVec2; 3], lo: DVec2, size: f64) -> Poly {
    let hi = lo + DVec2::splat(size);
    let mut bufs = [[DVec2::ZERO; 8]; 2];
    bufs[0][..3].copy_from_slice(tri);
    let mut len = 3;
    // Index of the buffer holding the current polygon; a pass that clips nothing
    // leaves it in place (no copy).
    let mut cur = 0;
    // One pass per side: clip the current buffer into the other one and switch.
    macro_rules! pass {
        ($axis:literal, $ge:literal, $bound:expr) => {{
            let [b0, b1] = &mut bufs;
            let (from, to) = if cur == 0 { (&*b0, b1) } else { (&*b1, b0) };
            if let Some(n) = clip_side::<$axis, $ge>(&from[..len], to, $bound) {
                len = n;
                cur ^= 1;
            }
        }};
    }
    pass!(0, true, lo.x);
    pass!(0, false, hi.x);
    pass!(1, true, lo.y);
    pass!(1, false, hi.y);
    Poly {
        pts: bufs[cur],
        len,
    }
}

/// One Sutherland-Hodgman pass: keeps the part of `from` with coordinate `AXIS` at least
/// (`GE`) or at most (`!GE`) `bound`, writing it to `to`; `None` when all of `from` is
/// kept (nothing written).
#[inline(always)]
fn clip_side<const AXIS: usize, const GE: bool>(
    from: &[DVec2],
    to: &mut [DVec2; 8],
    bound: f64,
) -> Option<usize> {
    let signed = |p: DVec2| {
        let c = if AXIS == 0 { p.x } else { p.y };
        if GE { c - bound } else { bound - c }
    };
    if from.iter().all(|&p| signed(p) >= 0.0) {
        return None;
    }
    let mut out = 0;
    let &last = from.last()?;
    let mut p = last;
    let mut dp = signed(p);
    for &q in from {
        let dq = signed(q);
        if (dp >= 0.0) != (dq >= 0.0) && out < 8 {
            let t = dp / (dp - dq);
            let mut x = p + (q - p) * t;
            // Exact on the clipping line.
            if AXIS == 0 {
                x.x = bound;
            } else {
                x.y = bound;
            }
            to[out] = x;
            out += 1;
        }
        if dq >= 0.0 && out < 8 {
            to[out] = q;
            out += 1;
        }
        p = q;
        dp = dq;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> [DVec2; 3] {
        [DVec2::from(a), DVec2::from(b), DVec2::from(c)]
    }

    #[test]
    fn inside_outside_and_half() {
        let t = tri((0.1, 0.1), (0.9, 0.1), (0.1, 0.9));
        let (a, c) = clip_triangle(&t, DVec2::ZERO, 1.0).area_centroid();
        assert!((a - 0.32).abs() < 1e-15);
        assert!((c - DVec2::new(1.1 / 3.0, 1.1 / 3.0)).length() < 1e-15);
        let (a, _) = clip_triangle(&t, DVec2::new(2.0, 2.0), 1.0).area_centroid();
        assert_eq!(a, 0.0);
        // The right-angled triangle (0,0),(2,0),(0,2) clipped to the unit square is the
        // whole square.
        let t = tri((0.0, 0.0), (2.0, 0.0), (0.0, 2.0));
        let (a, c) = clip_triangle(&t, DVec2::ZERO, 1.0).area_centroid();
        assert!((a - 1.0).abs() < 1e-15 && (c - DVec2::splat(0.5)).length() < 1e-15);
        // Clipped to [1,2]^2 it is the half-square below the diagonal x + y = 2.
        let (a, c) = clip_triangle(&t, DVec2::ONE, 1.0).area_centroid();
        assert_eq!(a, 0.0, "only touches a corner");
        let (a, c2) = clip_triangle(&t, DVec2::new(0.0, 1.0), 1.0).area_centroid();
        assert!((a - 0.5).abs() < 1e-15, "{a}");
        assert!((c2 - DVec2::new(1.0 / 3.0, 1.0 + 1.0 / 3.0)).length() < 1e-15);
        let _ = c;
    }

    #[test]
    fn tiling_squares_partition_the_triangle() {
        // The clipped areas over a grid of squares add up to the triangle's area.
        let t = tri((0.13, 0.07), (0.91, 0.33), (0.29, 0.97));
        let full = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]);
        let n = 17;
        let s = 1.0 / n as f64;
        let mut sum = 0.0;
        let mut moment = DVec2::ZERO;
        for j in 0..n {
            for i in 0..n {
                let (a, c) =
                    clip_triangle(&t, DVec2::new(i as f64 * s, j as f64 * s), s).area_centroid();
                sum += a;
                moment += c * a;
            }
        }
        assert!((sum - full).abs() < 1e-14, "{sum} vs {full}");
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        assert!((moment / sum - centroid).length() < 1e-14);
    }
}
