//! Building a [`SegmentCurve`] (paper section 6.1): validation of the [`CurveDomain`],
//! the affine density of each triangle, and the depth-first refinement of the adaptive
//! quadtree in Hilbert order, each leaf with its exact measure and its candidate
//! triangles (largest overlap first).
//!
//! Input: a [`CurveDomain`] and [`CurveOptions`]. Output: the leaves, their cumulative
//! measure and candidate lists. Cost: O(cells x triangles per cell), each overlap
//! exact (fast paths for a triangle inside a cell and a cell inside a triangle,
//! polygon clipping otherwise).

use glam::DVec2;

use super::clip::clip_triangle;
use super::hilbert::State;
use super::key::CellKey;
use super::segment_curve::SegmentCurve;
use super::{CurveError, CurveOptions};

/// A parameter domain in the unit square: triangles in `uv` with a density per corner.
///
/// The density is per unit *parameter* area, linear over each triangle; for a
/// parameterized surface triangle it is the surface density times the ratio of the
/// surface area to the parameter area, so that the measure of a region is the same in
/// both spaces.
#[derive(Clone, Copy, Debug)]
pub struct CurveDomain<'a> {
    /// Vertex positions in `[0, 1]^2`.
    pub uv: &'a [DVec2],
    /// Triangles (counter-clockwise in `uv`), indices into `uv`.
    pub triangles: &'a [[u32; 3]],
    /// Density at each triangle's three corners (non-negative, finite).
    pub corner_density: &'a [[f64; 3]],
}

impl SegmentCurve {
    /// Builds the adaptive cells of `domain`.
    ///
    /// A cell is refined while it holds more than `options.max_cell_share` of the total
    /// measure, or while the domain boundary crosses it and it is above
    /// `options.boundary_level`, never beyond `options.max_level`.
    pub fn build(domain: &CurveDomain<'_>, options: &CurveOptions) -> Result<Self, CurveError> {
        options.validate()?;
        validate_domain(domain)?;
        let density_planes: Vec<[f64; 3]> = domain
            .triangles
            .iter()
            .zip(domain.corner_density)
            .map(|(t, d)| density_plane(&t.map(|v| domain.uv[v as usize]), d))
            .collect();
        let mut curve = SegmentCurve {
            keys: Vec::new(),
            cumulative: vec![0.0],
            candidate_offsets: vec![0],
            candidates: Vec::new(),
            uv: domain.uv.to_vec(),
            triangles: domain.triangles.to_vec(),
            density_planes,
            options: *options,
        };
        let total: f64 = (0..curve.triangles.len())
            .map(|t| curve.triangle_measure(t))
            .sum();
        if !(total > 0.0) || !total.is_finite() {
            return Err(CurveError::ZeroMeasure);
        }
        curve.refine(total);
        // The cells are kept for the life of the sampler: drop the growth slack.
        curve.keys.shrink_to_fit();
        curve.cumulative.shrink_to_fit();
        curve.candidates.shrink_to_fit();
        curve.candidate_offsets.shrink_to_fit();
        Ok(curve)
    }

    fn triangle_measure(&self, t: usize) -> f64 {
        let p = self.triangle_corners(t);
        let area = 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
        area * self.density_at(t, (p[0] + p[1] + p[2]) / 3.0)
    }

    #[inline]
    fn density_at(&self, t: usize, p: DVec2) -> f64 {
        let [gx, gy, h] = self.density_planes[t];
        (gx * p.x + gy * p.y + h).max(0.0)
    }

    /// Measure and covered area of triangle `t` inside the square `[lo, lo + size]^2`.
    ///
    /// Two exact fast paths avoid clipping: a triangle inside the square counts whole,
    /// and a square inside the triangle counts whole (the density is linear, so its
    /// integral is the area times the value at the centre).
    #[inline]
    pub(super) fn overlap(&self, t: usize, lo: DVec2, size: f64) -> (f64, f64) {
        let tri = self.triangle_corners(t);
        let hi = lo + DVec2::splat(size);
        let (tmin, tmax) = (
            tri[0].min(tri[1]).min(tri[2]),
            tri[0].max(tri[1]).max(tri[2]),
        );
        if tmax.x <= lo.x || tmax.y <= lo.y || tmin.x >= hi.x || tmin.y >= hi.y {
            return (0.0, 0.0);
        }
        if tmin.x >= lo.x && tmin.y >= lo.y && tmax.x <= hi.x && tmax.y <= hi.y {
            let area = 0.5 * (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]);
            return (
                area * self.density_at(t, (tri[0] + tri[1] + tri[2]) / 3.0),
                area,
            );
        }
        let inside =
            |p: DVec2| (0..3).all(|k| (tri[(k + 1) % 3] - tri[k]).perp_dot(p - tri[k]) >= 0.0);
        if inside(lo)
            && inside(hi)
            && inside(DVec2::new(lo.x, hi.y))
            && inside(DVec2::new(hi.x, lo.y))
        {
            let area = size * size;
            return (
                area * self.density_at(t, lo + DVec2::splat(0.5 * size)),
                area,
            );
        }
        let (a, c) = clip_triangle(&tri, lo, size).area_centroid();
        if a <= 0.0 {
            (0.0, 0.0)
        } else {
            (a * self.density_at(t, c), a)
        }
    }

    /// Depth-first refinement in Hilbert order; leaves are appended in curve order.
    fn refine(&mut self, total: f64) {
        struct Node {
            x: u32,
            y: u32,
            level: u8,
            state: State,
            list_start: usize,
        }
        let opts = self.options;
        let share_limit = opts.max_cell_share * total;
        // Candidate lists of pending nodes, stacked; a node's list is on top when popped.
        let mut lists: Vec<u32> = (0..self.triangles.len() as u32).collect();
        let mut stack = vec![Node {
            x: 0,
            y: 0,
            level: 0,
            state: State::ROOT,
            list_start: 0,
        }];
        let mut kept: Vec<u32> = Vec::new();
        let mut kept_area: Vec<(f64, u32)> = Vec::new();
        while let Some(node) = stack.pop() {
            let size = 1.0 / (1u64 << node.level) as f64;
            let lo = DVec2::new(node.x as f64, node.y as f64) * size;
            kept.clear();
            kept_area.clear();
            let (mut measure, mut covered) = (0.0, 0.0);
            for &t in &lists[node.list_start..] {
                let (m, a) = self.overlap(t as usize, lo, size);
                if a > 0.0 {
                    kept.push(t);
                    kept_area.push((a, t));
                    measure += m;
                    covered += a;
                }
            }
            lists.truncate(node.list_start);
            if kept.is_empty() {
                continue;
            }
            let full = covered >= size * size * (1.0 - 1e-9);
            let refine = node.level < opts.max_level
                && (measure > share_limit || (!full && node.level < opts.boundary_level));
            if refine {
                // Push children in reverse visiting order so rank 0 is popped first.
                for rank in (0..4u8).rev() {
                    let (qx, qy, s) = node.state.child(rank);
                    stack.push(Node {
                        x: 2 * node.x + qx as u32,
                        y: 2 * node.y + qy as u32,
                        level: node.level + 1,
                        state: s,
                        list_start: lists.len(),
                    });
                    lists.extend_from_slice(&kept);
                }
            } else if measure > 0.0 {
                self.keys
                    .push(CellKey::new(node.x, node.y, node.level, node.state, full));
                let last = *self.cumulative.last().unwrap_or(&0.0);
                self.cumulative.push(last + measure);
                // Largest overlap first: point location tries candidates in this
                // order, so most points are found by the first one.
                kept_area.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
                self.candidates.extend(kept_area.iter().map(|&(_, t)| t));
                self.candidate_offsets.push(self.candidates.len() as u32);
            }
        }
    }
}

/// The affine density `g . p + h` that interpolates the corner densities.
fn density_plane(p: &[DVec2; 3], d: &[f64; 3]) -> [f64; 3] {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let det = e1.perp_dot(e2);
    let (d1, d2) = (d[1] - d[0], d[2] - d[0]);
    // Solve [e1; e2] g = [d1; d2].
    let gx = (d1 * e2.y - d2 * e1.y) / det;
    let gy = (e1.x * d2 - e2.x * d1) / det;
    [gx, gy, d[0] - gx * p[0].x - gy * p[0].y]
}

fn validate_domain(domain: &CurveDomain<'_>) -> Result<(), CurveError> {
    if domain.triangles.is_empty() {
        return Err(CurveError::ZeroMeasure);
    }
    if domain.corner_density.len() != domain.triangles.len() {
        return Err(CurveError::DensityCount {
            triangles: domain.triangles.len(),
            densities: domain.corner_density.len(),
        });
    }
    const SLACK: f64 = 1e-9;
    for (vertex, p) in domain.uv.iter().enumerate() {
        if !p.is_finite() || p.min_element() < -SLACK || p.max_element() > 1.0 + SLACK {
            return Err(CurveError::OutsideUnitSquare {
                vertex,
                u: p.x,
                v: p.y,
            });
        }
    }
    for (triangle, (t, d)) in domain
        .triangles
        .iter()
        .zip(domain.corner_density)
        .enumerate()
    {
        if t.iter().any(|&v| v as usize >= domain.uv.len()) {
            return Err(CurveError::BadTriangle { triangle });
        }
        let p = t.map(|v| domain.uv[v as usize]);
        if !((p[1] - p[0]).perp_dot(p[2] - p[0]) > 0.0) {
            return Err(CurveError::BadTriangle { triangle });
        }
        if d.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(CurveError::BadDensity { triangle });
        }
    }
    Ok(())
}
