//! Exact triangle-square overlap: Sutherland-Hodgman clipping of a triangle against an
//! axis-aligned square, the integral of a linear function over the result, and the
//! barycentric coordinates of a point in a triangle. The plane geometry below the
//! curve's types: it uses no other module of `curve/`.

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

    /// The point of the polygon (convex) at fraction `f` in `[0, 1)`, uniform in area
    /// for a uniform `f`: `f`'s bits are split (even and odd, a Z-order decode) into
    /// `g1` and `g2`; `x` is where the area left of it is `g1` of the whole, and `y`
    /// is at `g2` along the vertical chord there. It depends on the polygon as a point
    /// set only, not on its first corner or on repeated or collinear corners, so two
    /// descents that cut the same piece in different ways place a sample at the same
    /// point up to round-off. `None` for a polygon without area.
    pub(crate) fn point_at(&self, f: f64) -> Option<DVec2> {
        self.point_at_with_area(f, self.area_moment().0.abs())
    }

    /// [`point_at`](Self::point_at) with the polygon's area given (`area_moment`'s,
    /// made non-negative), for a caller that has computed it already.
    #[inline]
    pub(crate) fn point_at_with_area(&self, f: f64, total: f64) -> Option<DVec2> {
        let p = self.points();
        let n = p.len();
        if n < 3 {
            return None;
        }
        if !(total > 0.0) {
            return None;
        }
        let (g1, g2) = split_fraction(f);
        // The corners of least and greatest x split the boundary into two chains, one
        // walked forward and one backward from the least; between consecutive corner
        // abscissas the chord between them is linear.
        let (mut lo, mut hi) = (0, 0);
        for k in 1..n {
            if p[k].x < p[lo].x {
                lo = k;
            }
            if p[k].x > p[hi].x {
                hi = k;
            }
        }
        let y_on = |e: (usize, usize), x: f64| {
            let (u, v) = (p[e.0], p[e.1]);
            if v.x > u.x {
                u.y + (x - u.x) / (v.x - u.x) * (v.y - u.y)
            } else {
                v.y
            }
        };
        let (mut a, mut b) = ((lo, (lo + 1) % n), (lo, (lo + n - 1) % n));
        // Moves both chains to their edges that end beyond `x` (or at the end).
        let advance = |a: &mut (usize, usize), b: &mut (usize, usize), x: f64| {
            while a.0 != hi && p[a.1].x <= x {
                *a = (a.1, (a.1 + 1) % n);
            }
            while b.0 != hi && p[b.1].x <= x {
                *b = (b.1, (b.1 + n - 1) % n);
            }
        };
        let mut x = p[lo].x;
        advance(&mut a, &mut b, x);
        let mut c0 = (y_on(a, x) - y_on(b, x)).abs();
        let mut rest = g1 * total;
        // Each step passes a corner: at most n steps.
        for _ in 0..n {
            let next = p[a.1].x.min(p[b.1].x).min(p[hi].x).max(x);
            let c1 = (y_on(a, next) - y_on(b, next)).abs();
            let area = 0.5 * (c0 + c1) * (next - x);
            if rest < area || next >= p[hi].x || a.0 == hi || b.0 == hi {
                // Within the step the chord is c0 + k t and the area up to t is
                // c0 t + k t^2 / 2: solved in the cancellation-free form.
                let dx = next - x;
                if dx > 0.0 {
                    let k = (c1 - c0) / dx;
                    let denom = c0 + (c0 * c0 + 2.0 * k * rest).max(0.0).sqrt();
                    let t = if denom > 0.0 { 2.0 * rest / denom } else { 0.0 };
                    x += t.clamp(0.0, dx);
                }
                break;
            }
            rest -= area;
            x = next;
            c0 = c1;
            advance(&mut a, &mut b, x);
        }
        let (ya, yb) = (y_on(a, x), y_on(b, x));
        Some(DVec2::new(x, ya.min(yb) + g2 * (ya - yb).abs()))
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

/// Two values in `[0, 1)` from one: the even and the odd bits of the first 52 bits of
/// `f` (a Z-order decode), so a dyadic interval of `f` becomes a dyadic rectangle.
fn split_fraction(f: f64) -> (f64, f64) {
    let d = ((f.clamp(0.0, 1.0) * (1u64 << 52) as f64) as u64).min((1 << 52) - 1);
    // Compacts every second bit of `v` (bit 2i to bit i).
    let compact = |mut v: u64| {
        v &= 0x5555_5555_5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333_3333_3333;
        v = (v | (v >> 2)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v >> 4)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v >> 8)) & 0x0000_ffff_0000_ffff;
        (v | (v >> 16)) & 0x0000_0000_ffff_ffff
    };
    let scale = 1.0 / (1u64 << 26) as f64;
    (
        compact(d >> 1) as f64 * scale + 0.5 * scale,
        compact(d) as f64 * scale + 0.5 * scale,
    )
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

/// Barycentric coordinates of `p` in triangle `t`.
#[inline]
pub fn barycentric(t: &[DVec2; 3], p: DVec2) -> [f64; 3] {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let d = p - t[0];
    let inv = 1.0 / e1.perp_dot(e2);
    let b1 = d.perp_dot(e2) * inv;
    let b2 = e1.perp_dot(d) * inv;
    [1.0 - b1 - b2, b1, b2]
}

#[cfg(test)]
mod tests {

    /// `point_at` keeps every point in the polygon and spreads a stratified set of
    /// fractions evenly: each of the 16 sub-squares of a unit square gets its share of
    /// 4096 points within 10%, and a pentagon's points all lie inside it.
    #[test]
    fn point_at_is_inside_and_even() {
        let square = clip_triangle(
            &[
                DVec2::new(-1.0, -1.0),
                DVec2::new(4.0, -1.0),
                DVec2::new(-1.0, 4.0),
            ],
            DVec2::ZERO,
            1.0,
        );
        assert_eq!(square.points().len(), 4);
        let mut counts = [0usize; 16];
        for k in 0..4096 {
            let p = square.point_at((k as f64 + 0.5) / 4096.0).expect("area");
            assert!(
                (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y),
                "{p}"
            );
            counts[((p.y * 4.0) as usize).min(3) * 4 + ((p.x * 4.0) as usize).min(3)] += 1;
        }
        assert!(counts.iter().all(|&c| c.abs_diff(256) <= 26), "{counts:?}");
        let pentagon = clip_triangle(
            &[
                DVec2::new(0.1, -0.5),
                DVec2::new(1.4, 0.5),
                DVec2::new(-0.2, 0.9),
            ],
            DVec2::ZERO,
            1.0,
        );
        let pts = pentagon.points();
        assert!(pts.len() >= 5, "{pts:?}");
        for k in 0..1000 {
            let p = pentagon.point_at(k as f64 / 1000.0).expect("area");
            for i in 0..pts.len() {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                assert!((b - a).perp_dot(p - a) >= -1e-12, "{p} outside");
            }
        }
        assert!(Poly::EMPTY.point_at(0.5).is_none());
    }

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
