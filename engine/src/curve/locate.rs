//! From a measure to a domain point: the leaf holding it, the continuous Hilbert map
//! inside a fully covered leaf ([`FullLeaf`]), and point location, the search of the
//! leaf's candidate triangles for the one containing the point. Boundary leaves are
//! handed to `boundary.rs`.
//!
//! Cost per point: the leaf search (binary in [`SegmentCurve::locate`], the sampler
//! gallops instead), `levels` Hilbert steps, and an inside test per candidate tried
//! (usually the first: candidates are ordered by overlap). These functions are the
//! sampler's per-sample path; their inlining is part of the contract in `curve/mod.rs`.

use glam::DVec2;

use super::clip::barycentric;
use super::pieces::{LeafScratch, PIECES};
use super::segment_curve::{DomainPoint, SegmentCurve};

impl SegmentCurve {
    /// Index of the leaf holding cumulative measure `m` (clamped into range).
    pub fn leaf_at(&self, m: f64) -> usize {
        let i = self.cumulative.partition_point(|&c| c <= m);
        i.saturating_sub(1).min(self.keys.len() - 1)
    }

    /// Maps measure `m` in `[0, measure)` to a domain point: the leaf by binary search,
    /// then [`point_in_leaf`](Self::point_in_leaf).
    pub fn locate(&self, m: f64) -> DomainPoint {
        let leaf = self.leaf_at(m);
        let local =
            (m - self.cumulative[leaf]) / (self.cumulative[leaf + 1] - self.cumulative[leaf]);
        self.point_in_leaf(leaf, local)
    }

    /// Maps the fraction `t` in `[0, 1)` of leaf `leaf`'s measure to a domain point
    /// along the continuous Hilbert curve. In a leaf the domain covers fully, density
    /// is taken as uniform (leaves hold a bounded share of the measure); in a boundary
    /// leaf the exact measures of sub-cells are followed down until a sub-cell is
    /// fully covered or the levels run out; in a sub-cell the boundary still crosses,
    /// the point is placed by area in the triangle piece its measure falls in (a
    /// vertical sweep of the piece's area), so every point lies in the domain.
    pub fn point_in_leaf(&self, leaf: usize, t: f64) -> DomainPoint {
        self.point_in_leaf_to(leaf, t, self.options.leaf_levels as u32)
    }

    /// As [`point_in_leaf`](Self::point_in_leaf), resolving only `levels` levels of the
    /// continuous map in fully covered leaves (at most `leaf_levels`). A caller that
    /// draws `n` samples from `c` cells needs about `log4(n / c)` levels to separate
    /// them, and a few more to place them evenly.
    pub fn point_in_leaf_to(&self, leaf: usize, t: f64, levels: u32) -> DomainPoint {
        self.point_in_leaf_with(leaf, t, levels, &mut LeafScratch::default())
    }

    /// As [`point_in_leaf_to`](Self::point_in_leaf_to), with the scratch memory of the
    /// boundary-leaf descent given by the caller (a few kilobytes that would otherwise
    /// be initialised per call; reuse one per thread or chunk of work). The result does
    /// not depend on the scratch's previous contents ([`LeafScratch`]'s contract).
    #[inline(always)]
    pub fn point_in_leaf_with<'a>(
        &'a self,
        leaf: usize,
        t: f64,
        levels: u32,
        scratch: &mut LeafScratch<'a>,
    ) -> DomainPoint {
        let key = self.keys[leaf];
        if key.full() {
            return self.full_leaf(leaf, levels).point(self, t);
        }
        let off = &self.candidate_offsets[leaf..leaf + 2];
        let cands = &self.candidates[off[0] as usize..off[1] as usize];
        let t = t.clamp(0.0, 1.0 - f64::EPSILON);
        let levels = levels.min(self.options.leaf_levels as u32);
        if cands.len() <= PIECES {
            self.descend_pieces(leaf, key, cands, t, levels, scratch)
        } else {
            self.descend_partial(leaf, key, cands, t, levels)
        }
    }

    /// Whether leaf `leaf` lies wholly in the domain.
    #[inline(always)]
    pub(crate) fn leaf_is_full(&self, leaf: usize) -> bool {
        self.keys[leaf].full()
    }

    /// The full leaf `leaf` made ready to place several points resolved to `levels`
    /// levels ([`FullLeaf::point`]): what a caller drawing consecutive values from one
    /// leaf computes once instead of per point.
    #[inline(always)]
    pub(crate) fn full_leaf(&self, leaf: usize, levels: u32) -> FullLeaf<'_> {
        let key = self.keys[leaf];
        debug_assert!(key.full());
        let off = &self.candidate_offsets[leaf..leaf + 2];
        let levels = levels.min(self.options.leaf_levels as u32);
        // The walk reads `8 chunks` bits of `t`: those of the padding levels of the
        // last chunk only pick among sub-cells that are dropped. At most 48 bits
        // (`leaf_levels` is at most 24).
        let chunks = levels.div_ceil(4);
        debug_assert!(chunks <= 6);
        FullLeaf {
            cands: &self.candidates[off[0] as usize..off[1] as usize],
            state: key.state(),
            chunks,
            pad: 4 * chunks - levels,
            scale: super::hilbert::pow2(8 * chunks),
            gx: (key.x() as u64) << levels,
            gy: (key.y() as u64) << levels,
            inv: super::hilbert::pow2_neg(key.level() as u32 + levels),
        }
    }

    /// Finds the candidate triangle containing `uv` (the most-inside one if round-off
    /// leaves it just outside all of them) and its barycentric coordinates.
    #[inline(always)]
    pub(super) fn point_location(&self, cands: &[u32], uv: DVec2) -> DomainPoint {
        // Division-free inside test first; the coordinates of the triangle found are
        // those of `barycentric`.
        for &t in cands {
            let p = self.triangle_corners(t as usize);
            let (e1, e2, d) = (p[1] - p[0], p[2] - p[0], uv - p[0]);
            let det = e1.perp_dot(e2);
            let (s1, s2) = (d.perp_dot(e2), e1.perp_dot(d));
            if s1 >= 0.0 && s2 >= 0.0 && s1 + s2 <= det {
                let inv = 1.0 / det;
                let (b1, b2) = (s1 * inv, s2 * inv);
                let b = [1.0 - b1 - b2, b1, b2];
                if b[0] >= 0.0 {
                    return DomainPoint {
                        triangle: t,
                        uv,
                        bary: b,
                    };
                }
            }
        }
        self.point_location_nearest(cands, uv)
    }

    /// The rest of [`point_location`](Self::point_location) (rare: a point on an edge
    /// up to round-off): the candidate with the largest smallest barycentric
    /// coordinate, and the point clamped onto it.
    #[inline(never)]
    fn point_location_nearest(&self, cands: &[u32], uv: DVec2) -> DomainPoint {
        let mut best = (f64::NEG_INFINITY, 0u32, [1.0, 0.0, 0.0]);
        for &t in cands {
            let b = barycentric(&self.triangle_corners(t as usize), uv);
            let min = b[0].min(b[1]).min(b[2]);
            if min >= 0.0 {
                return DomainPoint {
                    triangle: t,
                    uv,
                    bary: b,
                };
            }
            if min > best.0 {
                best = (min, t, b);
            }
        }
        // Clamp onto the triangle so that the barycentric coordinates are valid.
        self.clamped_onto(best.1, best.2)
    }

    /// The point of triangle `tri` at barycentric coordinates `b` clamped onto the
    /// triangle (negative ones set to zero, the rest renormalised), for a point that is
    /// in it only up to round-off.
    pub(super) fn clamped_onto(&self, tri: u32, b: [f64; 3]) -> DomainPoint {
        let b = b.map(|x| x.max(0.0));
        let sum = b[0] + b[1] + b[2];
        let bary = b.map(|x| x / sum);
        let p = self.triangle_corners(tri as usize);
        DomainPoint {
            triangle: tri,
            uv: p[0] * bary[0] + p[1] * bary[1] + p[2] * bary[2],
            bary,
        }
    }
}

/// A full leaf ready to place points ([`SegmentCurve::full_leaf`]).
pub(crate) struct FullLeaf<'a> {
    cands: &'a [u32],
    state: super::hilbert::State,
    /// Groups of four levels the walk takes, and the padding levels of the last one.
    chunks: u32,
    pad: u32,
    /// `2^(8 chunks)`: `t` scaled to the walk's index.
    scale: f64,
    /// The leaf's corner on the grid of level `level + levels`.
    gx: u64,
    gy: u64,
    /// That grid's spacing, `2^-(level + levels)`.
    inv: f64,
}

impl FullLeaf<'_> {
    /// The point at fraction `t` of the leaf's measure along the continuous Hilbert
    /// map (density taken as uniform in the leaf), located in its triangle.
    #[inline(always)]
    pub(crate) fn point(&self, curve: &SegmentCurve, t: f64) -> DomainPoint {
        let t = t.clamp(0.0, 1.0 - f64::EPSILON);
        // The index `floor(t 2^(8 chunks))`, below 2^48 (t < 1, the scaling exact):
        // plus 2^52 it is the mantissa (a rounding, an add and an integer subtract,
        // where a float-to-integer conversion also checks for overflow and NaN). Its
        // leading `2 levels` bits are `cell_in_node`'s index; the bits below only pick
        // among the padding levels' sub-cells, which are dropped.
        let two52 = super::hilbert::pow2(52);
        let d = ((t * self.scale).floor() + two52).to_bits() - two52.to_bits();
        let (x, y) = super::hilbert::walk_chunks(self.state, d, self.chunks);
        let (x, y) = (x >> self.pad, y >> self.pad);
        // The sub-cell's centre on the grid of level `level + levels`: the same value
        // as `origin + (x + 0.5) 2^-levels size`, both exact before rounding.
        let gx = (self.gx | x) as f64 + 0.5;
        let gy = (self.gy | y) as f64 + 0.5;
        curve.point_location(self.cands, DVec2::new(gx, gy) * self.inv)
    }
}
