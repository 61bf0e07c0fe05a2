//! What a data-parallel sampler (a GPU pass) reads of a segment's cells besides its
//! leaves and cumulative measures: the domain triangles' corners and, for a boundary
//! leaf, each candidate triangle clipped to the leaf with its exact measure, in the
//! order the sequential descent visits them.
//!
//! Input: a built [`SegmentCurve`]. Output: plain values handed to a callback, for a
//! caller that flattens them into tables. Cost: one clip per candidate of the leaf.

use glam::DVec2;

use super::clip::{Poly, clip_triangle};
use super::segment_curve::SegmentCurve;

impl SegmentCurve {
    /// Number of triangles of the curve's domain.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The corners of domain triangle `t` in the unit square (counter-clockwise).
    /// Panics when `t` is out of range.
    pub fn triangle_uv(&self, t: usize) -> [DVec2; 3] {
        self.triangle_corners(t)
    }

    /// Calls `f` with each candidate triangle of leaf `leaf`
    /// ([`leaf_triangles`](Self::leaf_triangles), in that order), its part inside the
    /// leaf's square and the exact measure of that part (the integral of the
    /// triangle's density over it; 0 without area): the pieces among which a boundary
    /// leaf that receives at most one sample places it. Panics when `leaf` is out of
    /// range.
    pub fn leaf_pieces(&self, leaf: usize, mut f: impl FnMut(u32, &Poly, f64)) {
        let key = self.keys[leaf];
        for &t in self.leaf_triangles(leaf) {
            let poly = clip_triangle(&self.triangle_corners(t as usize), key.origin(), key.size());
            let (area, moment) = poly.area_moment();
            f(t, &poly, self.part_measure(t, area, moment));
        }
    }
}
