//! The [`SegmentCurve`] type: the adaptive Hilbert cells of one segment (leaf keys in
//! curve order, cumulative measures, candidate triangles per leaf, the domain's
//! triangles and affine densities) and its plain accessors.
//!
//! Built by [`SegmentCurve::build`] (`refine.rs`); values are mapped to points by
//! `locate.rs` (full leaves) and `boundary.rs` (boundary leaves). Memory:
//! [`SegmentCurve::heap_bytes`].

use glam::DVec2;

use super::CurveOptions;
use super::key::CellKey;

/// The adaptive Hilbert cells of one parameterized segment.
///
/// Leaves are stored in Hilbert order with the cumulative measure, so a 1D value in
/// `[0, measure)` maps to a leaf by search and then to a point inside it by the
/// continuous Hilbert map ([`SegmentCurve::locate`]).
#[derive(Clone, Debug)]
pub struct SegmentCurve {
    pub(super) keys: Vec<CellKey>,
    /// `cumulative[i]` is the measure of leaves `0..i`; length `keys.len() + 1`.
    pub(super) cumulative: Vec<f64>,
    /// Per leaf, a range into `candidates`: the triangles overlapping it.
    pub(super) candidate_offsets: Vec<u32>,
    pub(super) candidates: Vec<u32>,
    pub(super) uv: Vec<DVec2>,
    pub(super) triangles: Vec<[u32; 3]>,
    /// Per triangle, the density as an affine function `g . p + h`: `[gx, gy, h]`.
    pub(super) density_planes: Vec<[f64; 3]>,
    pub(super) options: CurveOptions,
}

/// A point of the domain: its triangle (index into the domain's triangles), parameter
/// position and barycentric coordinates in that triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DomainPoint {
    /// Triangle index in the domain.
    pub triangle: u32,
    /// Position in the unit square.
    pub uv: DVec2,
    /// Barycentric coordinates (non-negative, summing to 1).
    pub bary: [f64; 3],
}

impl SegmentCurve {
    pub(super) fn triangle_corners(&self, t: usize) -> [DVec2; 3] {
        self.triangles[t].map(|v| self.uv[v as usize])
    }

    /// Total measure (integral of density over the domain).
    pub fn measure(&self) -> f64 {
        *self.cumulative.last().unwrap_or(&0.0)
    }

    /// Number of leaf cells.
    pub fn cell_count(&self) -> usize {
        self.keys.len()
    }

    /// Leaf cells in Hilbert order.
    pub fn cells(&self) -> &[CellKey] {
        &self.keys
    }

    /// Cumulative measure: entry `i` is the measure of leaves `0..i`.
    pub fn cumulative(&self) -> &[f64] {
        &self.cumulative
    }

    /// The domain triangles overlapping leaf `leaf` (every point of the leaf in the
    /// domain lies in one of them). Panics when `leaf` is out of range.
    pub fn leaf_triangles(&self, leaf: usize) -> &[u32] {
        let off = &self.candidate_offsets[leaf..leaf + 2];
        &self.candidates[off[0] as usize..off[1] as usize]
    }

    /// Calls `f` with each triangle of leaf `leaf` ([`leaf_triangles`](Self::leaf_triangles))
    /// and the barycentric coordinates, in that triangle, of each corner of its part
    /// inside the leaf's square (the triangle clipped to the square, a convex polygon).
    /// Every point of the leaf in the domain has coordinates that are a convex
    /// combination of the corners of its triangle's part, up to round-off: what bounds
    /// a function that is convex or linear in them over the leaf (the level-of-detail
    /// pool's spheres and normal cones) more tightly than the triangles' own corners.
    /// Panics when `leaf` is out of range.
    pub fn leaf_part_corners(&self, leaf: usize, mut f: impl FnMut(u32, [f64; 3])) {
        let key = self.keys[leaf];
        for &t in self.leaf_triangles(leaf) {
            let corners = self.triangle_corners(t as usize);
            let part = super::clip::clip_triangle(&corners, key.origin(), key.size());
            for &p in part.points() {
                // On the triangle up to round-off: clamped into it.
                let b = super::clip::barycentric(&corners, p).map(|x| x.clamp(0.0, 1.0));
                let sum = b[0] + b[1] + b[2];
                f(t, b.map(|x| x / sum));
            }
        }
    }

    /// The options the cells were built with.
    pub fn options(&self) -> &CurveOptions {
        &self.options
    }

    /// Memory held, in bytes.
    pub fn heap_bytes(&self) -> usize {
        self.keys.capacity() * std::mem::size_of::<CellKey>()
            + self.cumulative.capacity() * 8
            + (self.candidate_offsets.capacity() + self.candidates.capacity()) * 4
            + self.uv.capacity() * 16
            + self.triangles.capacity() * 12
            + self.density_planes.capacity() * 24
    }
}
