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

    /// The density of domain triangle `t` as an affine function of the unit square's
    /// coordinates: `[gx, gy, h]` for `gx u + gy v + h`, the function whose integral
    /// over a piece of the triangle is the piece's exact measure (what a descent
    /// through a boundary leaf compares). Panics when `t` is out of range.
    pub fn density_plane(&self, t: usize) -> [f64; 3] {
        self.density_planes[t]
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

/// A part of a candidate triangle inside a node of the descent: what
/// `pieces::PieceSet` holds, in a vector (no candidate limit).
#[derive(Clone, Copy)]
struct Part {
    tri: u32,
    poly: Poly,
    area: f64,
    measure: f64,
}

/// The parts of one node with their summed area and measure, summed in the order of
/// `PieceSet` so the sums are the same bits.
#[derive(Clone, Default)]
struct Parts {
    parts: Vec<Part>,
    measure: f64,
    area: f64,
}

impl Parts {
    fn push(&mut self, part: Part) {
        self.measure += part.measure;
        self.area += part.area;
        self.parts.push(part);
    }
}

/// One node of a boundary leaf's descent tree ([`SegmentCurve::descent_tree`]): a
/// square of the quadtree below the leaf (a quarter) or one half of such a square
/// (the descent's first cut), with the measure the sequential descent carries into
/// it, its children in curve order and the triangle parts inside it.
#[derive(Clone, Debug)]
pub struct DescentNode {
    /// The square's corner on the grid of its level.
    pub x: u32,
    /// See `x`.
    pub y: u32,
    /// The square's level (a half has its parent square's).
    pub level: u8,
    /// The square's Hilbert state.
    pub state: u8,
    /// Whether the node is a square (the leaf or a quarter), not a half.
    pub square: bool,
    /// Whether the domain covers the square (a quarter placed by the continuous map).
    pub full: bool,
    /// The measure the descent carries into the node.
    pub measure: f64,
    /// The two children in curve order: their measures (zero: never chosen) and
    /// indices into the tree (`None` when not built: zero measure, a full quarter's
    /// children, or past the depth).
    pub children: [(f64, Option<u32>); 2],
    /// The triangle parts inside the node: `(triangle, part, measure of the part)`.
    pub parts: Vec<(u32, Poly, f64)>,
}

impl SegmentCurve {
    /// The polygon-splitting descent through boundary leaf `leaf` (a leaf the domain
    /// does not cover) unrolled into a tree, `depth` levels of quarters deep: every
    /// node the sequential descent may visit with its exact measures (the same
    /// operations in the same order, so the same bits as the descent for leaves of at
    /// most six candidates; more take the general descent there, which this equals up
    /// to round-off). Node 0 is the leaf, with the parts of
    /// [`leaf_pieces`](Self::leaf_pieces). Cost: two polygon splits per part and
    /// level, over about `2^depth` boundary squares per level.
    pub fn descent_tree(&self, leaf: usize, depth: u32) -> Vec<DescentNode> {
        self.descent_tree_to(leaf, depth, (0, 0))
    }

    /// [`descent_tree`](Self::descent_tree) expanded only where a sampler that
    /// continues the descent itself from a square (a GPU pass measuring the pieces of
    /// a node in `f32`) cannot: a square that is not full is expanded while it holds
    /// more than `max_parts` triangle parts with area or lies above level
    /// `min_level` (coarser), and `depth` levels of quarters at most. Its other
    /// squares are the tree's frontier: not full, no children built, their parts
    /// listed. The same nodes, measures and parts as `descent_tree` where both have
    /// them. Cost: as `descent_tree`, over the expanded squares only.
    pub fn descent_tree_to(
        &self,
        leaf: usize,
        depth: u32,
        (max_parts, min_level): (usize, u8),
    ) -> Vec<DescentNode> {
        let key = self.keys[leaf];
        let (lo, size) = (key.origin(), key.size());
        let mut root = Parts::default();
        let mut all = Vec::new();
        self.leaf_pieces(leaf, |tri, poly, m| all.push((tri, *poly, m)));
        for &(tri, poly, _) in &all {
            let (area, moment) = poly.area_moment();
            if area > 0.0 {
                let measure = self.part_measure(tri, area, moment);
                root.push(Part {
                    tri,
                    poly,
                    area,
                    measure,
                });
            }
        }
        let mut nodes = vec![DescentNode {
            x: key.x(),
            y: key.y(),
            level: key.level(),
            state: key.state().0,
            square: true,
            full: false,
            measure: self.cumulative[leaf + 1] - self.cumulative[leaf],
            children: [(0.0, None); 2],
            parts: all,
        }];
        let stop = (max_parts, min_level);
        self.expand(&mut nodes, 0, &root, (lo, size), (depth, stop));
        nodes
    }

    /// Adds the halves and quarters below square node `at` (its parts `parts`, its
    /// square `lo, size`), `depth` levels of quarters, squares of at most `stop.0`
    /// parts at level `stop.1` or finer left unexpanded.
    fn expand(
        &self,
        nodes: &mut Vec<DescentNode>,
        at: usize,
        parts: &Parts,
        (lo, size): (glam::DVec2, f64),
        (depth, stop): (u32, (usize, u8)),
    ) {
        let (x, y, level) = (nodes[at].x, nodes[at].y, nodes[at].level);
        if depth == 0 || (parts.parts.len() <= stop.0 && level >= stop.1) {
            return;
        }
        let state = super::hilbert::State(nodes[at].state);
        let half = 0.5 * size;
        let (x0, y0, _) = state.child(0);
        let (x1, _, _) = state.child(1);
        // The cuts of `descend_pieces`, in its order.
        let first_along_x = x0 == x1;
        let cut_at = |along_x: bool| if along_x { lo.x } else { lo.y } + half;
        let upper_first = if first_along_x { x0 == 1 } else { y0 == 1 };
        let (below, above) = self.split_parts(parts, first_along_x, cut_at(first_along_x));
        let halves = if upper_first {
            [above, below]
        } else {
            [below, above]
        };
        for (h, half_parts) in halves.iter().enumerate() {
            nodes[at].children[h].0 = half_parts.measure;
            if !(half_parts.measure > 0.0) {
                continue;
            }
            let hi = nodes.len();
            nodes[at].children[h].1 = Some(hi as u32);
            nodes.push(DescentNode {
                square: false,
                full: false,
                measure: half_parts.measure,
                children: [(0.0, None); 2],
                parts: Self::listed(half_parts),
                ..nodes[at].clone()
            });
            let rank0 = if h == 0 { 0 } else { 2 };
            let (qx, qy, _) = state.child(rank0);
            let upper = if first_along_x { qy == 1 } else { qx == 1 };
            let (b, a) = self.split_parts(half_parts, !first_along_x, cut_at(!first_along_x));
            let quarters = if upper { [a, b] } else { [b, a] };
            for (q, quarter) in quarters.iter().enumerate() {
                nodes[hi].children[q].0 = quarter.measure;
                if !(quarter.measure > 0.0) {
                    continue;
                }
                let (qx, qy, child_state) = state.child(rank0 + q as u8);
                let q_lo = lo + glam::DVec2::new(qx as f64, qy as f64) * half;
                let full = quarter.area >= half * half * (1.0 - 1e-9);
                let qi = nodes.len();
                nodes[hi].children[q].1 = Some(qi as u32);
                nodes.push(DescentNode {
                    x: 2 * x + u32::from(qx),
                    y: 2 * y + u32::from(qy),
                    level: level + 1,
                    state: child_state.0,
                    square: true,
                    full,
                    measure: quarter.measure,
                    children: [(0.0, None); 2],
                    parts: Self::listed(quarter),
                });
                if !full {
                    self.expand(nodes, qi, quarter, (q_lo, half), (depth - 1, stop));
                }
            }
        }
    }

    fn listed(parts: &Parts) -> Vec<(u32, Poly, f64)> {
        parts
            .parts
            .iter()
            .map(|p| (p.tri, p.poly, p.measure))
            .collect()
    }

    /// `pieces::PieceSet::split` on [`Parts`]: the same operations in the same order.
    fn split_parts(&self, from: &Parts, along_x: bool, at: f64) -> (Parts, Parts) {
        let (mut below, mut above) = (Parts::default(), Parts::default());
        for piece in &from.parts {
            let coord = |p: &glam::DVec2| if along_x { p.x } else { p.y };
            let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
            for p in piece.poly.points() {
                let c = coord(p);
                if c < mn {
                    mn = c;
                }
                if c > mx {
                    mx = c;
                }
            }
            if mx <= at {
                below.push(*piece);
            } else if mn >= at {
                above.push(*piece);
            } else {
                let (mut b, mut a) = (Poly::EMPTY, Poly::EMPTY);
                if along_x {
                    piece.poly.split_into::<0>(at, &mut b, &mut a);
                } else {
                    piece.poly.split_into::<1>(at, &mut b, &mut a);
                }
                let (area_b, moment) = b.area_moment();
                let (mut kept_area, mut kept_measure) = (0.0, 0.0);
                if area_b > 0.0 {
                    let measure = self.part_measure(piece.tri, area_b, moment);
                    below.push(Part {
                        tri: piece.tri,
                        poly: b,
                        area: area_b,
                        measure,
                    });
                    (kept_area, kept_measure) = (area_b, measure);
                }
                let (area_a, measure_a) = (piece.area - kept_area, piece.measure - kept_measure);
                if area_a > 0.0 && a.points().len() >= 3 {
                    above.push(Part {
                        tri: piece.tri,
                        poly: a,
                        area: area_a,
                        measure: measure_a.max(0.0),
                    });
                }
            }
        }
        (below, above)
    }
}
