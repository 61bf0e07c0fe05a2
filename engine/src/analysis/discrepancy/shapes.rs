//! Exact sup discrepancies for origin triangles and quarter discs.
//!
//! Both follow the convention of the star discrepancy: a test shape `S` contributes
//! `area(S) - #(P in S) / N` with `S` open on its far side and `#(P in closure(S)) / N -
//! area(S)` with the closure, and degenerate shapes of zero area enter as limits.

use glam::DVec2;
use rayon::prelude::*;
use std::f64::consts::FRAC_PI_4;

/// Sup discrepancy over the triangles with vertices `(0,0)`, `(a,0)`, `(0,b)`,
/// `0 < a, b <= 1`. Points must be in `[0, 1]^2` (checked by the caller).
///
/// Write `u = 1/a`, `v = 1/b`. A point `q` lies in the open triangle iff
/// `q.x u + q.y v < 1`, so each point is a line in the `(u, v)` plane and the count is
/// constant on the cells of that line arrangement (with the boundary lines `u = 1`,
/// `v = 1`, i.e. the lines of the virtual points `(1,0)` and `(0,1)`). The area
/// `1 / (2 u v)` is convex there, so the deficit (area minus open count) peaks at
/// arrangement vertices, and the excess (closed count minus area) at vertices or at the
/// point of a line where the area is smallest: the triangle whose hypotenuse has `q` at
/// its midpoint (`a = 2 q.x`, `b = 2 q.y`). Zero-area limits (segments along an axis)
/// contribute the points on that axis. Every line is swept once with its crossings
/// sorted: O(N^2 log N) time, O(N) memory per thread.
pub(crate) fn origin_triangles_sup(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return 0.5;
    }
    let inv_n = 1.0 / n as f64;
    let on_y_axis = points.iter().filter(|p| p.x == 0.0).count();
    let on_x_axis = points.iter().filter(|p| p.y == 0.0).count();
    // Segments along an axis: zero area, holding every point on that axis.
    let degenerate = on_x_axis.max(on_y_axis) as f64 * inv_n;

    let mut lines: Vec<DVec2> = points
        .iter()
        .copied()
        .filter(|c| {
            // Interior points whose line misses a, b <= 1 have no critical triangle.
            (c.x > 0.0 || c.y > 0.0) && (c.x == 0.0 || c.y == 0.0 || c.x <= 1.0 - c.y)
        })
        .collect();
    lines.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    lines.dedup();
    // The boundaries a = 1 and b = 1 are the lines of the (uncounted) virtual points.
    lines.push(DVec2::X);
    lines.push(DVec2::Y);

    let best = lines
        .par_iter()
        .map(|&c| sweep_triangle_line(points, c, inv_n))
        .reduce(|| 0.0, f64::max);
    best.max(degenerate)
}

/// The largest deficit or excess over the critical triangles whose hypotenuse lies on
/// the line of `c` (`c.x u + c.y v = 1`).
fn sweep_triangle_line(points: &[DVec2], c: DVec2, inv_n: f64) -> f64 {
    let line = TriangleLine::new(c);
    line.crossings(points).sup(&line, inv_n)
}

/// The line of `c` parametrised by sigma in `[lo, hi]`. A point q crosses it at
/// sigma = num / den: with den < 0 it is inside the open triangle for sigma > root
/// (entering), with den > 0 for sigma < root (leaving); with den == 0 its status is
/// fixed. num and den are differences of products, exact for coordinates with up to
/// 26 significant bits, so tied crossings (collinear points on dyadic grids) round to
/// the same root.
struct TriangleLine {
    c: DVec2,
    lo: f64,
    hi: f64,
    /// The sigma of smallest triangle area, where there is one.
    tangent: Option<f64>,
}

impl TriangleLine {
    fn new(c: DVec2) -> Self {
        let (lo, hi, tangent) = if c.x > 0.0 && c.y > 0.0 {
            // sigma = c.x u, so a = c.x / sigma and b = c.y / (1 - sigma).
            (c.x, 1.0 - c.y, Some(0.5))
        } else {
            // Axis line: one leg is fixed, sigma is the other leg in (0, 1].
            (0.0, 1.0, None)
        };
        Self { c, lo, hi, tangent }
    }

    /// Point `q`'s crossing: (num, den, inside-open and inside-closed when den == 0).
    fn crossing(&self, q: DVec2) -> (f64, f64, bool, bool) {
        let c = self.c;
        if c.y == 0.0 {
            // a = c.x fixed, sigma = b: q.x / c.x + q.y / sigma < 1.
            (-q.y * c.x, q.x - c.x, false, q.y == 0.0)
        } else if c.x == 0.0 {
            // b = c.y fixed, sigma = a.
            (-q.x * c.y, q.y - c.y, false, q.x == 0.0)
        } else {
            // q.x sigma / c.x + q.y (1 - sigma) / c.y < 1; when q = lambda c it is
            // inside iff lambda < 1.
            let den = q.x * c.y - q.y * c.x;
            ((c.y - q.y) * c.x, den, q.y < c.y, q.y <= c.y)
        }
    }

    /// The triangle's area at `sigma`.
    fn area(&self, sigma: f64) -> f64 {
        let c = self.c;
        if c.y == 0.0 {
            0.5 * c.x * sigma
        } else if c.x == 0.0 {
            0.5 * c.y * sigma
        } else {
            0.5 * c.x * c.y / (sigma * (1.0 - sigma))
        }
    }

    /// The counts of `points` that do not change along `[lo, hi]`, then the crossings
    /// inside it, sorted, with the query-only positions (the ends, the tangent).
    fn crossings(&self, points: &[DVec2]) -> Crossings {
        let (lo, hi) = (self.lo, self.hi);
        let mut open_base = 0usize;
        let mut closed_base = 0usize;
        let mut events: Vec<(f64, Option<bool>)> = Vec::new();
        for &q in points {
            let (num, den, fixed_open, fixed_closed) = self.crossing(q);
            if den == 0.0 {
                open_base += usize::from(fixed_open);
                closed_base += usize::from(fixed_closed);
                continue;
            }
            let root = num / den;
            let entering = den < 0.0;
            if root < lo {
                let inside = usize::from(entering);
                open_base += inside;
                closed_base += inside;
            } else if root > hi {
                let inside = usize::from(!entering);
                open_base += inside;
                closed_base += inside;
            } else {
                events.push((root, Some(entering)));
            }
        }
        if lo > 0.0 {
            events.push((lo, None));
        }
        events.push((hi, None));
        if let Some(t) = self.tangent.filter(|t| (lo..=hi).contains(t)) {
            events.push((t, None));
        }
        events.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        Crossings {
            open_base,
            closed_base,
            events,
        }
    }
}

/// The points' crossings of one [`TriangleLine`].
struct Crossings {
    /// Points inside the open triangle all along the line.
    open_base: usize,
    /// Points inside the closed triangle all along the line.
    closed_base: usize,
    /// (root, entering), sorted by root: entering points are inside for sigma > root,
    /// leaving ones for sigma < root; query-only positions are `None`.
    events: Vec<(f64, Option<bool>)>,
}

impl Crossings {
    /// The largest deficit or excess at the events along `line`.
    fn sup(&self, line: &TriangleLine, inv_n: f64) -> f64 {
        let events = &self.events;
        let leaving_total = events.iter().filter(|e| e.1 == Some(false)).count();
        let mut best = 0.0f64;
        let mut entered = 0usize; // entering roots < sigma
        let mut left = 0usize; // leaving roots < sigma
        let mut k = 0;
        while k < events.len() {
            let sigma = events[k].0;
            let (mut enter_here, mut leave_here) = (0usize, 0usize);
            while k < events.len() && events[k].0 == sigma {
                match events[k].1 {
                    Some(true) => enter_here += 1,
                    Some(false) => leave_here += 1,
                    None => {}
                }
                k += 1;
            }
            // sigma = 0 is the zero-area limit; it is covered by the axis segments.
            if sigma > 0.0 {
                let still_in = leaving_total - left;
                let open = self.open_base + entered + (still_in - leave_here);
                let closed = self.closed_base + entered + enter_here + still_in;
                let a = line.area(sigma);
                best = best
                    .max(a - open as f64 * inv_n)
                    .max(closed as f64 * inv_n - a);
            }
            entered += enter_here;
            left += leave_here;
        }
        best
    }
}

/// Sup discrepancy over quarter discs `|q| < r` centred at the origin, measured in the
/// frame `q = scale * p` (componentwise) where the domain is `[0, sx] x [0, sy]` and
/// `0 < r <= min(sx, sy)` (the disc stays inside the domain); areas are normalised by
/// `sx * sy`. The count is a step function of `r`, so the critical radii are the point
/// radii and the largest radius: O(N log N).
pub(crate) fn quarter_discs_sup(points: &[DVec2], scale: DVec2) -> f64 {
    let r2_max = scale.min_element().powi(2);
    let area = |r2: f64| FRAC_PI_4 * r2 / (scale.x * scale.y);
    let n = points.len();
    if n == 0 {
        return area(r2_max);
    }
    let inv_n = 1.0 / n as f64;
    let mut r2: Vec<f64> = points
        .iter()
        .map(|p| (*p * scale).length_squared())
        .filter(|&r2| r2 <= r2_max)
        .collect();
    r2.sort_unstable_by(f64::total_cmp);

    let mut best = 0.0f64;
    let mut k = 0;
    while k < r2.len() {
        let radius2 = r2[k];
        let open = k;
        while k < r2.len() && r2[k] == radius2 {
            k += 1;
        }
        let a = area(radius2);
        best = best.max(a - open as f64 * inv_n).max(k as f64 * inv_n - a);
    }
    // The largest disc, open: every point strictly inside it.
    let open = r2.partition_point(|&r2| r2 < r2_max);
    best.max(area(r2_max) - open as f64 * inv_n)
}
