//! The sampler flattened into plain tables for a data-parallel sampler (a GPU compute
//! pass) that draws the same samples as [`Sampler::sample_sites_into`], and the small
//! per-request table of its groups.
//!
//! Input: a built [`Sampler`]. Output: [`FlatSampler`] (built once per preprocessing):
//! every segment's leaves in chain order with their cumulative measures as 64-bit
//! fixed-point fractions of the total, their keys, candidate triangles, the domain
//! triangles' corners and faces, and per boundary leaf its descent unrolled into a
//! tree ([`SegmentCurve::descent_tree`](crate::curve::SegmentCurve::descent_tree):
//! the sub-cells' exact measures and clipped pieces), as deep as the largest request
//! so far needs ([`FlatSampler::deepen`]); and per request ([`FlatSampler::request`])
//! the groups that receive samples with their counts, first outputs, leaf ranges,
//! random-stream keys and fixed-point extents, the levels of the continuous map per
//! segment, and per group the leaf measures from which a boundary leaf descends one
//! more level. Cost: O(cells + candidates) once, O(boundary leaves 2^depth) per
//! deepening; O(segments) per request. The engine stays GPU-free: these are plain
//! vectors.
//!
//! The progressive order ([`Sampler::progressive_sites_into`]) reads the same leaves
//! and pieces, plus [`FlatProgressive`] (per domain triangle its density plane, per
//! slot the levels; built once), and per request only the scramble's six words
//! ([`progressive_scramble`], O(1)).
//!
//! Fixed point: the measure before leaf `l` in chain order, over the total `T`, is
//! stored as `floor(C_l / T 2^64)`. A group's value `v` in `[0, 1)` then maps to
//! `G_lo + floor(v G_len)`, the same leaf as the sequential sampler's `v M_group` in
//! `f64` except within about `2^-52` of the group's measure of a leaf boundary.

use super::sampler::Sampler;
use super::stratified::Allocation;
use crate::curve::DescentNode;

/// One leaf: `[x, y, meta, first, len]` where `meta` holds the level (bits 0..5), the
/// Hilbert state (5..7), whether the leaf is full (bit 7) and the segment's slot in
/// chain order (8..32); `first`/`len` index [`FlatSampler::candidates`] for a full
/// leaf and [`FlatSampler::nodes`] (its descent tree, the leaf first) for a boundary
/// leaf.
pub type FlatLeaf = [u32; 5];

/// A node of a boundary leaf's descent tree ([`DescentNode`]): `[meta, x, y, first
/// piece, pieces, share lo, share hi, share lo, share hi, child, child, measure lo,
/// measure hi]`. `meta` holds the square's level (bits 0..5) and Hilbert state
/// (5..7), whether it is full (bit 7) and whether it is a square rather than a half
/// (bit 8); the pieces ([`FlatSampler::pieces`], in the square's unit square, their
/// measures as fractions of the node's) are where a descent that ends in the node
/// places its point; the children in curve order have their measures as 64-bit
/// fractions of the node's (0: never chosen) and their node indices (`u32::MAX`: not
/// built); the measure is the node's as `f64` bits (read for a leaf's root: the
/// levels of its descent).
pub type FlatNode = [u32; 13];

/// A clipped piece of a node of a boundary leaf's descent tree: `[triangle, corners,
/// measure lo, measure hi, x0, y0, ...]` with the triangle a global domain-triangle
/// index, the measure as a fraction of the node's measure in 2^62 fixed point (the
/// pieces' exact measures sum to the node's up to round-off), and up to 8 corners in
/// the node's own unit square (`f32`).
pub type FlatPiece = [u32; 20];

/// A domain triangle: its corners' `u, v` in the unit square (`f32` bits) and its mesh
/// face.
pub type FlatTriangle = [u32; 7];

/// A group that receives samples in one request: `[first output, count, first leaf,
/// leaf end, key lo, key hi, G_lo lo, G_lo hi, G_len lo, G_len hi]`.
pub type FlatGroup = [u32; 10];

/// Why a request cannot be drawn from the flat tables.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FlatError {
    /// The descent trees of the boundary leaves are not deep enough for the request
    /// ([`FlatSampler::deepen`] makes them so).
    #[error("{count} samples need boundary descent trees deeper than the tables hold")]
    Shallow {
        /// The request.
        count: u64,
    },
    /// The request or the tables exceed 32-bit indices.
    #[error("{what} ({value}) exceeds 32-bit indices")]
    TooLarge {
        /// What.
        what: &'static str,
        /// How many.
        value: u64,
    },
}

/// Per segment slot (chain order), what a request needs.
#[derive(Clone, Debug)]
struct Slot {
    segment_index: usize,
    leaf_lo: u32,
    leaf_hi: u32,
    /// Per descent depth `k` (index `k - 1`), the largest measure of a boundary leaf
    /// whose tree is shallower than `k` (0 when none).
    shallow: [f64; MAX_DEPTH],
}

/// The deepest descent tree the tables hold (the sampler caps descents at its
/// `leaf_levels`, at most 24).
const MAX_DEPTH: usize = 24;

/// The sampler's cells as flat tables ([module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct FlatSampler {
    /// Per leaf (and one past the last), the measure before it over the total, in
    /// 64-bit fixed point.
    pub cumulative: Vec<u64>,
    /// The leaves in chain order ([`FlatLeaf`]).
    pub leaves: Vec<FlatLeaf>,
    /// Candidate triangles of full leaves (global domain-triangle indices).
    pub candidates: Vec<u32>,
    /// The descent trees of boundary leaves ([`FlatNode`]), each leaf's in one run.
    pub nodes: Vec<FlatNode>,
    /// Clipped pieces of the descent trees' nodes ([`FlatPiece`]).
    pub pieces: Vec<FlatPiece>,
    /// Domain triangles of every segment ([`FlatTriangle`]).
    pub triangles: Vec<FlatTriangle>,
    /// Per slot, the segment id written into samples.
    pub slot_segments: Vec<u32>,
    slots: Vec<Slot>,
    /// Per leaf, the depth of its descent tree (0 for full leaves).
    depths: Vec<u8>,
}

/// One request's groups and levels ([`FlatSampler::request`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatRequest {
    /// The groups with at least one sample, in output order ([`FlatGroup`]).
    pub groups: Vec<FlatGroup>,
    /// Per slot, the levels of the continuous map in its full leaves.
    pub levels: Vec<u32>,
    /// How many descent levels the thresholds give (`depth`).
    pub depth: u32,
    /// Per group, `depth` thresholds as `f64` bits: a boundary leaf of measure `w`
    /// descends through as many levels as there are thresholds at most `w` (the
    /// sequential sampler's levels, exactly; compare the bits as integers).
    pub thresholds: Vec<u64>,
}

fn split(v: u64) -> [u32; 2] {
    [v as u32, (v >> 32) as u32]
}

fn f32_bits(x: f64) -> u32 {
    (x as f32).to_bits()
}

/// The 64-bit fraction `m / whole` (0 for no measure, at least 1 for some; saturated).
fn share64(m: f64, whole: f64) -> u64 {
    if !(m > 0.0) {
        return 0;
    }
    ((m / whole * 18_446_744_073_709_551_616.0) as u64).max(1)
}

/// The sequential sampler's levels of descent through a boundary leaf expecting
/// `expected` samples (`leaves.rs`'s `boundary_levels`; the tests compare the two
/// samplers, so a change there shows here).
fn descent_levels(expected: f64) -> u32 {
    (expected.max(1.0).log2() * 0.5).ceil() as u32
}

/// The smallest leaf measure `w` whose descent has at least `k` levels at `per_sample`
/// samples per unit measure (at most `cap` levels), as `f64` bits; `u64::MAX` for
/// none.
fn threshold(per_sample: f64, k: u32, cap: u32) -> u64 {
    if k > cap || !(per_sample > 0.0) {
        return u64::MAX;
    }
    let levels = |w: f64| descent_levels(w * per_sample);
    let mut w = 4f64.powi(k as i32 - 1) / per_sample;
    if !w.is_finite() {
        return u64::MAX;
    }
    // The estimate is within a few ulps of the answer: step to it.
    for _ in 0..256 {
        if levels(w) >= k {
            let down = w.next_down();
            if down >= 0.0 && levels(down) >= k {
                w = down;
            } else {
                break;
            }
        } else {
            w = w.next_up();
        }
    }
    w.to_bits()
}

/// Appends `node` of a tree whose root is node `root` to `nodes`, with its pieces to
/// `pieces` ([`FlatNode`], [`FlatPiece`]); domain triangles are numbered from
/// `tri_base`.
fn push_node(
    (nodes, pieces): (&mut Vec<FlatNode>, &mut Vec<FlatPiece>),
    node: &DescentNode,
    root: u32,
    tri_base: u32,
) {
    let size = (-f64::from(node.level)).exp2();
    let origin = glam::DVec2::new(f64::from(node.x), f64::from(node.y)) * size;
    let first = pieces.len() as u32;
    for (tri, poly, m) in &node.parts {
        let mut row = [0u32; 20];
        row[0] = tri_base + tri;
        let pts = poly.points();
        row[1] = pts.len().min(8) as u32;
        let share = if node.measure > 0.0 {
            m / node.measure
        } else {
            0.0
        };
        [row[2], row[3]] = split((share * 4_611_686_018_427_387_904.0) as u64);
        for (k, p) in pts.iter().take(8).enumerate() {
            let q = (*p - origin) / size;
            row[4 + 2 * k] = f32_bits(q.x);
            row[5 + 2 * k] = f32_bits(q.y);
        }
        pieces.push(row);
    }
    let meta = u32::from(node.level)
        | u32::from(node.state) << 5
        | u32::from(node.full) << 7
        | u32::from(node.square) << 8;
    let [(m0, c0), (m1, c1)] = node.children;
    let child = |c: Option<u32>| c.map_or(u32::MAX, |c| root + c);
    let (a, b) = (
        split(share64(m0, node.measure)),
        split(share64(m1, node.measure)),
    );
    let w = split(node.measure.to_bits());
    let len = pieces.len() as u32 - first;
    nodes.push([
        meta,
        node.x,
        node.y,
        first,
        len,
        a[0],
        a[1],
        b[0],
        b[1],
        child(c0),
        child(c1),
        w[0],
        w[1],
    ]);
}

impl FlatSampler {
    /// Flattens `sampler`'s cells, with descent trees of depth 0 (requests that put at
    /// most one sample in a boundary leaf; [`deepen`](Self::deepen) for more).
    pub fn new(sampler: &Sampler) -> Result<Self, FlatError> {
        let mut flat = FlatSampler::default();
        let total = sampler.chain_cumulative.last().copied().unwrap_or(0.0);
        let fixed = |c: f64| (c / total * 18_446_744_073_709_551_616.0) as u64;
        for (slot, &si) in sampler.chains.order.iter().enumerate() {
            let seg = &sampler.segments[si as usize];
            let curve = &seg.curve;
            let base = sampler.chain_cumulative[slot];
            let tri_base = flat.triangles.len() as u64;
            if tri_base + curve.triangle_count() as u64 > u64::from(u32::MAX) {
                return Err(FlatError::TooLarge {
                    what: "domain triangles",
                    value: tri_base + curve.triangle_count() as u64,
                });
            }
            for t in 0..curve.triangle_count() {
                let c = curve.triangle_uv(t);
                let mut row = [0u32; 7];
                for (k, p) in c.iter().enumerate() {
                    row[2 * k] = f32_bits(p.x);
                    row[2 * k + 1] = f32_bits(p.y);
                }
                row[6] = seg.faces[t];
                flat.triangles.push(row);
            }
            let leaf_lo = flat.leaves.len() as u32;
            let cum = curve.cumulative();
            for (l, key) in curve.cells().iter().enumerate() {
                flat.cumulative.push(fixed(base + cum[l]));
                let meta = u32::from(key.level())
                    | u32::from(key.state().0) << 5
                    | u32::from(key.full()) << 7
                    | (slot as u32) << 8;
                let (first, len) = if key.full() {
                    let first = flat.candidates.len() as u32;
                    for &t in curve.leaf_triangles(l) {
                        flat.candidates.push((tri_base + u64::from(t)) as u32);
                    }
                    (first, flat.candidates.len() as u32 - first)
                } else {
                    (0, 0)
                };
                flat.leaves.push([key.x(), key.y(), meta, first, len]);
            }
            flat.slot_segments.push(seg.segment);
            flat.slots.push(Slot {
                segment_index: si as usize,
                leaf_lo,
                leaf_hi: flat.leaves.len() as u32,
                shallow: [0.0; MAX_DEPTH],
            });
        }
        flat.cumulative.push(u64::MAX);
        if flat.leaves.len() as u64 >= 1 << 31 || flat.slots.len() >= 1 << 24 {
            return Err(FlatError::TooLarge {
                what: "leaves",
                value: flat.leaves.len() as u64,
            });
        }
        flat.depths = vec![0; flat.leaves.len()];
        flat.build_trees(sampler)?;
        Ok(flat)
    }

    /// Rebuilds the descent trees of every boundary leaf to its depth in `depths`,
    /// and the slots' shallowness.
    fn build_trees(&mut self, sampler: &Sampler) -> Result<(), FlatError> {
        self.nodes.clear();
        self.pieces.clear();
        let mut tri_base = 0u32;
        for s in 0..self.slots.len() {
            let slot = &self.slots[s];
            let curve = &sampler.segments[slot.segment_index].curve;
            let (leaf_lo, leaf_hi) = (slot.leaf_lo as usize, slot.leaf_hi as usize);
            let cum = curve.cumulative();
            let mut shallow = [0.0f64; MAX_DEPTH];
            for l in leaf_lo..leaf_hi {
                if self.leaves[l][2] & 128 != 0 {
                    continue;
                }
                let local = l - leaf_lo;
                let depth = self.depths[l];
                let w = cum[local + 1] - cum[local];
                for s in &mut shallow[depth as usize..] {
                    *s = s.max(w);
                }
                let root = self.nodes.len() as u32;
                let tree = curve.descent_tree(local, u32::from(depth));
                for node in &tree {
                    self.push_node(node, root, tri_base);
                }
                self.leaves[l][3] = root;
                self.leaves[l][4] = tree.len() as u32;
            }
            self.slots[s].shallow = shallow;
            tri_base += curve.triangle_count() as u32;
        }
        if self.nodes.len() as u64 >= u64::from(u32::MAX) || self.pieces.len() >= 1 << 31 {
            return Err(FlatError::TooLarge {
                what: "descent tree nodes",
                value: self.nodes.len() as u64,
            });
        }
        Ok(())
    }

    /// Appends `node` of a tree whose root is node `root`, with its pieces; domain
    /// triangles are numbered from `tri_base`.
    fn push_node(&mut self, node: &DescentNode, root: u32, tri_base: u32) {
        push_node((&mut self.nodes, &mut self.pieces), node, root, tri_base);
    }

    /// Deepens the descent trees so that an `n`-sample request of `sampler` (the one
    /// these tables were built from) can be drawn: each boundary leaf's tree as deep as
    /// the sequential sampler descends in it for `n` samples. `true` when the tables
    /// changed (upload them again). Cost: O(cells) to check, and the trees of every
    /// boundary leaf rebuilt when any must grow.
    pub fn deepen(&mut self, sampler: &Sampler, n: u64) -> Result<bool, FlatError> {
        let mut changed = false;
        let (slots, leaves, depths) = (&self.slots, &self.leaves, &mut self.depths);
        for_each_run(sampler, n, |_, slot_lo, slot_hi, count, group_measure| {
            let per_sample = count as f64 / group_measure;
            for slot in &slots[slot_lo as usize..slot_hi as usize] {
                let curve = &sampler.segments[slot.segment_index].curve;
                let cap = u32::from(curve.options().leaf_levels).min(MAX_DEPTH as u32);
                let cum = curve.cumulative();
                for l in slot.leaf_lo as usize..slot.leaf_hi as usize {
                    if leaves[l][2] & 128 != 0 {
                        continue;
                    }
                    let local = l - slot.leaf_lo as usize;
                    let w = cum[local + 1] - cum[local];
                    let need = descent_levels(w * per_sample).min(cap) as u8;
                    if need > depths[l] {
                        depths[l] = need;
                        changed = true;
                    }
                }
            }
            Ok(())
        })?;
        if changed {
            self.build_trees(sampler)?;
        }
        Ok(changed)
    }

    /// Bytes of the tables (what a GPU holds of them).
    pub fn bytes(&self) -> usize {
        self.cumulative.len() * 8
            + self.leaves.len() * 20
            + self.candidates.len() * 4
            + self.nodes.len() * 52
            + self.pieces.len() * 80
            + self.triangles.len() * 28
            + self.slot_segments.len() * 4
    }

    /// The groups, levels and descent thresholds of an `n`-sample stratified request
    /// for `seed` of `sampler` (the one these tables were built from): the allocation
    /// of [`Sampler::sample_sites_into`] over segments or chains, O(segments).
    /// [`FlatError::Shallow`] when a boundary leaf's tree is shallower than the
    /// request's descent in it ([`deepen`](Self::deepen) first).
    pub fn request(&self, sampler: &Sampler, n: u64, seed: u64) -> Result<FlatRequest, FlatError> {
        let mut request = FlatRequest::default();
        self.request_into(sampler, n, seed, &mut request)?;
        Ok(request)
    }

    /// [`request`](Self::request) written into `request`, whose vectors are reused:
    /// the same table, and no allocation once they have grown to the largest request
    /// (what a per-frame caller keeps). On an error `request` is left unspecified.
    pub fn request_into(
        &self,
        sampler: &Sampler,
        n: u64,
        seed: u64,
        request: &mut FlatRequest,
    ) -> Result<(), FlatError> {
        if n > u64::from(u32::MAX) {
            return Err(FlatError::TooLarge {
                what: "samples per request",
                value: n,
            });
        }
        let segments = sampler.segments();
        let depth = u32::from(self.depths.iter().copied().max().unwrap_or(0));
        request.groups.clear();
        request.levels.clear();
        request.levels.resize(self.slots.len(), 0);
        request.depth = depth;
        request.thresholds.clear();
        let mut first = 0u64;
        for_each_run(sampler, n, |i, slot_lo, slot_hi, count, group_measure| {
            let start = first;
            first += count;
            if count == 0 {
                return Ok(());
            }
            let per_sample = count as f64 / group_measure;
            for slot in slot_lo..slot_hi {
                let s = &self.slots[slot as usize];
                let curve = &segments[s.segment_index].curve;
                let cap = u32::from(curve.options().leaf_levels).min(MAX_DEPTH as u32);
                for (k, &w) in s.shallow.iter().enumerate() {
                    if w > 0.0 && descent_levels(w * per_sample).min(cap) > k as u32 {
                        return Err(FlatError::Shallow { count: n });
                    }
                }
                let share = curve.measure() / group_measure;
                let per_leaf = count as f64 * share / curve.cell_count() as f64;
                let levels = (per_leaf.max(1.0).log2() * 0.5).ceil() as u32 + 5;
                request.levels[slot as usize] = levels.min(u32::from(curve.options().leaf_levels));
            }
            let curve = &segments[self.slots[slot_lo as usize].segment_index].curve;
            let cap = u32::from(curve.options().leaf_levels).min(MAX_DEPTH as u32);
            request
                .thresholds
                .extend((1..=depth).map(|k| threshold(per_sample, k, cap)));
            let (lo, hi) = (
                self.slots[slot_lo as usize].leaf_lo,
                self.slots[slot_hi as usize - 1].leaf_hi,
            );
            let g_lo = self.cumulative[lo as usize];
            let g_len = self.cumulative[hi as usize].wrapping_sub(g_lo);
            let key = split(crate::rng::stream_key(seed, i as u64));
            let (g_lo, g_len) = (split(g_lo), split(g_len));
            request.groups.push([
                start as u32,
                count as u32,
                lo,
                hi,
                key[0],
                key[1],
                g_lo[0],
                g_lo[1],
                g_len[0],
                g_len[1],
            ]);
            Ok(())
        })
    }
}

/// Calls `f(group, first slot, slot end, count, measure)` for every group of an
/// `n`-sample request in output order (segments, or chains where the sampler links
/// them), its count from the sampler's allocation and its measure summed as the
/// sampler sums it; stops at `f`'s first error. Allocates nothing.
fn for_each_run(
    sampler: &Sampler,
    n: u64,
    mut f: impl FnMut(usize, u32, u32, u64, f64) -> Result<(), FlatError>,
) -> Result<(), FlatError> {
    let segments = sampler.segments();
    let measure = |i: u32| segments[i as usize].curve.measure();
    if sampler.uses_chains(n as usize) {
        let chains = &sampler.chains;
        let group = move |i: usize| chains.members(i).iter().map(|&s| measure(s)).sum::<f64>();
        let groups = (0..sampler.chains_iter().len()).map(group);
        let mut at = 0u32;
        for (i, count) in Allocation::new(n, groups) {
            let lo = at;
            at += chains.members(i).len() as u32;
            f(i, lo, at, count, group(i))?;
        }
    } else {
        let groups = (0..segments.len() as u32).map(measure);
        for (i, count) in Allocation::new(n, groups) {
            let slot = sampler.chain_slot[i];
            f(i, slot, slot + 1, count, measure(i as u32))?;
        }
    }
    Ok(())
}

/// Levels of the continuous map and of the boundary descent for progressive samples:
/// the progressive sampler's fixed resolution (`progressive.rs`; the GPU tests compare
/// the two samplers, so a change there shows).
pub const PROGRESSIVE_LEVELS: u32 = 12;

/// What a data-parallel sampler reads besides [`FlatSampler`]'s tables to draw the
/// progressive order ([`Sampler::progressive_sites_into`]): per domain triangle its
/// density plane, from which a boundary leaf's descent measures its sub-cells' pieces
/// at every level (the descent is [`PROGRESSIVE_LEVELS`] deep whatever the count, too
/// deep to unroll into trees), and per slot the levels of the descent. Built once per
/// preprocessing, O(triangles + segments); nothing depends on the request.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatProgressive {
    /// Per domain triangle (the order of [`FlatSampler::triangles`]), its density
    /// plane ([`SegmentCurve::density_plane`](crate::curve::SegmentCurve::density_plane))
    /// as `f32` bits: `[gx, gy, d0]` with `d0` the density at the triangle's first
    /// corner (as stored in [`FlatSampler::triangles`]), so the density at `p` is
    /// `d0 + g . (p - corner)`.
    pub planes: Vec<[u32; 3]>,
    /// Per slot (chain order), the levels of the continuous map in full leaves and of
    /// the descent in boundary leaves: [`PROGRESSIVE_LEVELS`] capped at the segment's
    /// `leaf_levels`.
    pub levels: Vec<u32>,
    /// The top of the descent through the boundary leaves that a pass measuring
    /// pieces in `f32` cannot descend as the CPU does (more than
    /// [`PROGRESSIVE_PIECES`] triangle parts, or coarser than
    /// [`PROGRESSIVE_TREE_LEVEL`]), unrolled in `f64` as in the stratified order's
    /// trees ([`FlatNode`], each leaf's in one run, child indices global within these
    /// nodes) until a square is full, holds at most [`PROGRESSIVE_PIECES`] parts at
    /// [`PROGRESSIVE_FRONTIER_LEVEL`] or finer (the frontier, from which the pass
    /// descends itself), or the levels run out. Only full and frontier squares keep
    /// their pieces.
    pub nodes: Vec<FlatNode>,
    /// Clipped pieces of [`nodes`](Self::nodes) ([`FlatPiece`]).
    pub pieces: Vec<FlatPiece>,
    /// Per leaf with such a tree, in increasing leaf order: `[leaf, root]`, the leaf's
    /// index in [`FlatSampler::leaves`] and its root in [`nodes`](Self::nodes).
    pub trees: Vec<[u32; 2]>,
}

/// Triangle parts of a node that the progressive pass measures itself in `f32` at
/// most (`MAX_PIECES` in `shaders/progressive.wgsl`).
pub const PROGRESSIVE_PIECES: usize = 12;

/// Boundary leaves coarser than this level get a progressive tree whatever their
/// pieces: the pass's `f32` descent was measured to place the CPU's points within
/// 1e-5 of the diagonal from leaves of this level and finer (the default scene, the
/// bunny), not from coarser ones.
pub const PROGRESSIVE_TREE_LEVEL: u8 = 4;

/// The coarsest level at which the progressive pass continues a descent of a leaf with
/// a tree itself in `f32`. Each `f32` level risks a choice of sub-cell, or a test of
/// whether one is full (the CPU's is 1e-9 of its area), that differs from the CPU's:
/// on coarse cells (boundary leaves at level 3, up to 255 pieces) continuing from
/// level 5 put 16 of 4096 samples beyond 1e-5 of the diagonal (up to 5e-5), from
/// level 8 one of 10^5, from level 9 none (largest deviation 7e-7). Each level more
/// about doubles the trees.
pub const PROGRESSIVE_FRONTIER_LEVEL: u8 = 9;

impl FlatProgressive {
    /// The planes and levels of `sampler` (the sampler [`FlatSampler::new`] flattened).
    pub fn new(sampler: &Sampler) -> Self {
        let mut flat = FlatProgressive::default();
        for &si in &sampler.chains.order {
            let curve = &sampler.segments[si as usize].curve;
            for t in 0..curve.triangle_count() {
                // The density at the first corner as stored (`f32`), not at the
                // origin: no cancellation when a far origin's terms are large.
                let [gx, gy, h] = curve.density_plane(t);
                let c = curve.triangle_uv(t)[0];
                let (x, y) = (f64::from(c.x as f32), f64::from(c.y as f32));
                flat.planes
                    .push([f32_bits(gx), f32_bits(gy), f32_bits(gx * x + gy * y + h)]);
            }
            let cap = u32::from(curve.options().leaf_levels);
            flat.levels.push(PROGRESSIVE_LEVELS.min(cap));
        }
        flat.build_trees(sampler);
        flat
    }

    /// The trees of [`nodes`](Self::nodes): per boundary leaf in chain order, its
    /// descent tree to the frontier when the leaf itself lies beyond it. O(boundary
    /// leaves' candidates) plus the expanded squares.
    fn build_trees(&mut self, sampler: &Sampler) {
        let (mut leaf_base, mut tri_base) = (0u32, 0u32);
        for (slot, &si) in sampler.chains.order.iter().enumerate() {
            let curve = &sampler.segments[si as usize].curve;
            let stop = (PROGRESSIVE_PIECES, PROGRESSIVE_FRONTIER_LEVEL);
            for (l, key) in curve.cells().iter().enumerate() {
                if key.full() {
                    continue;
                }
                if key.level() >= PROGRESSIVE_TREE_LEVEL {
                    let mut parts = 0;
                    curve.leaf_pieces(l, |_, poly, _| {
                        parts += usize::from(poly.area_moment().0 > 0.0)
                    });
                    if parts <= PROGRESSIVE_PIECES {
                        continue;
                    }
                }
                let tree = curve.descent_tree_to(l, self.levels[slot], stop);
                let root = self.nodes.len() as u32;
                self.trees.push([leaf_base + l as u32, root]);
                for mut node in tree {
                    // A descent passes through a node with children (a half, or a
                    // square not full and above the frontier) without reading its
                    // pieces: only full and frontier squares keep theirs.
                    if !node.full && node.children.iter().any(|c| c.1.is_some()) {
                        node.parts.clear();
                    }
                    push_node((&mut self.nodes, &mut self.pieces), &node, root, tri_base);
                }
            }
            leaf_base += curve.cell_count() as u32;
            tri_base += curve.triangle_count() as u32;
        }
    }

    /// Bytes of the tables.
    pub fn bytes(&self) -> usize {
        self.planes.len() * 12
            + self.levels.len() * 4
            + self.nodes.len() * 52
            + self.pieces.len() * 80
            + self.trees.len() * 8
    }
}

/// The per-request words of the progressive order for `seed`: the constants of its
/// scramble ([`Scramble`](crate::sample::progressive::Scramble)) as `[add, even 0,
/// even 1, odd, jitter key lo, jitter key hi]`. Value `k` of the sequence is then
/// `reverse_bits(P(k))` in the top 32 bits of a 64-bit fraction and the top 32 bits of
/// `keyed_hash(jitter key, k)` below them, with `P(x)` = `x + add`, `x ^= x * even 0`,
/// `x *= odd`, `x ^= x * even 1` (wrapping). O(1).
pub fn progressive_scramble(seed: u64) -> [u32; 6] {
    let word = |i: u64| crate::rng::hash3(seed, 0x5052_4f47, i) as u32;
    let jitter = split(crate::rng::stream_key(seed, 0x4a49_5454));
    [
        word(0),
        word(1) & !1,
        word(2) & !1,
        word(3) | 1,
        jitter[0],
        jitter[1],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::SampleSite;

    fn torus() -> crate::surface::Preprocessed {
        let (mesh, field) = crate::fixtures::torus_case();
        crate::surface::Preprocessed::build(mesh, field, &Default::default()).expect("preprocessed")
    }

    /// The tables hold every leaf once with non-decreasing fixed-point cumulative
    /// measures, candidates and pieces in range, and a request's groups cover the
    /// outputs in order with the counts of the sequential sampler's allocation: the
    /// per-segment counts of its sites.
    #[test]
    fn tables_and_requests_follow_the_sampler() {
        let pre = torus();
        let sampler = &pre.sampler;
        let flat = FlatSampler::new(sampler).expect("flat");
        let cells: usize = sampler
            .segments()
            .iter()
            .map(|s| s.curve.cell_count())
            .sum();
        assert_eq!(flat.leaves.len(), cells);
        assert_eq!(flat.cumulative.len(), cells + 1);
        assert!(flat.cumulative.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(flat.cumulative[0], 0);
        for leaf in &flat.leaves {
            let (first, len) = (leaf[3] as usize, leaf[4] as usize);
            assert!(len > 0, "{leaf:?}");
            if leaf[2] & 128 != 0 {
                assert!(first + len <= flat.candidates.len());
            } else {
                assert!(first + len <= flat.nodes.len());
                let root = flat.nodes[first];
                let (p0, pn) = (root[3] as usize, root[4] as usize);
                assert!(p0 + pn <= flat.pieces.len());
                let sum: f64 = flat.pieces[p0..p0 + pn]
                    .iter()
                    .map(|p| (u64::from(p[2]) | u64::from(p[3]) << 32) as f64 / 2f64.powi(62))
                    .sum();
                assert!((sum - 1.0).abs() < 1e-3, "pieces sum to {sum}");
            }
        }
        assert!(
            flat.candidates
                .iter()
                .all(|&t| (t as usize) < flat.triangles.len())
        );
        assert!(flat.bytes() > 0);
        for n in [1u64, 7, 5000] {
            let request = flat.request(sampler, n, 3).expect("request");
            let mut sites = vec![SampleSite::default(); n as usize];
            sampler.sample_sites_into(3, &mut sites);
            let mut next = 0u32;
            for g in &request.groups {
                assert_eq!(g[0], next, "n {n}: groups in output order");
                assert!(g[1] > 0 && g[2] < g[3] && g[3] as usize <= cells);
                next += g[1];
                // Every sample of the group lies in a segment of its leaves.
                let slots: Vec<u32> = (g[2]..g[3])
                    .map(|l| flat.slot_segments[(flat.leaves[l as usize][2] >> 8) as usize])
                    .collect();
                for s in &sites[g[0] as usize..(g[0] + g[1]) as usize] {
                    assert!(slots.contains(&s.segment), "n {n}: {s:?}");
                }
            }
            assert_eq!(u64::from(next), n);
            assert!(request.levels.iter().all(|&l| l <= 12));
        }
        assert!(matches!(
            flat.request(sampler, 1 << 33, 3),
            Err(FlatError::TooLarge { .. })
        ));
    }

    /// A request written into a reused table is the fresh request, whatever came
    /// before it (larger and smaller counts, segments and chains, other seeds), and
    /// once the table has grown to the largest request it is not reallocated.
    #[test]
    fn requests_into_a_reused_table_are_fresh_requests() {
        let pre = torus();
        let sampler = &pre.sampler;
        let mut flat = FlatSampler::new(sampler).expect("flat");
        flat.deepen(sampler, 200_000).expect("deepen");
        let counts = [1u64, 2, 5, 200_000, 3, 4096, 7, 100, 0, 99_999, 1];
        assert!(counts.iter().any(|&n| sampler.uses_chains(n as usize)));
        assert!(counts.iter().any(|&n| !sampler.uses_chains(n as usize)));
        let mut reused = FlatRequest::default();
        let mut held = None;
        for round in 0..2 {
            for (k, &n) in counts.iter().enumerate() {
                let seed = (round * 31 + k as u64) ^ 0x5eed;
                flat.request_into(sampler, n, seed, &mut reused)
                    .expect("request");
                let fresh = flat.request(sampler, n, seed).expect("request");
                assert_eq!(reused, fresh, "n {n}, seed {seed}");
            }
            let buffers = [
                reused.groups.as_ptr() as usize,
                reused.levels.as_ptr() as usize,
                reused.thresholds.as_ptr() as usize,
            ];
            if round == 1 {
                assert_eq!(Some(buffers), held, "the table was reallocated");
            }
            held = Some(buffers);
        }
    }

    /// The scramble words give the progressive sequence's values: the top 32 bits of
    /// each as `Scramble::bits`, and with the jitter's top bits below them the value
    /// of `Scramble::value` to within 2^-52.
    #[test]
    fn scramble_words_give_the_progressive_values() {
        use crate::sample::progressive::Scramble;
        for seed in [0u64, 1, 77, u64::MAX] {
            let [add, e0, e1, odd, lo, hi] = progressive_scramble(seed);
            let scramble = Scramble::new(seed);
            let key = u64::from(lo) | u64::from(hi) << 32;
            for rank in [0u32, 1, 2, 3, 1000, 123_456, u32::MAX] {
                let mut x = rank.wrapping_add(add);
                x ^= x.wrapping_mul(e0);
                x = x.wrapping_mul(odd);
                x ^= x.wrapping_mul(e1);
                let bits = x.reverse_bits();
                assert_eq!(bits, scramble.bits(rank), "seed {seed} rank {rank}");
                let low = (crate::rng::keyed_hash(key, u64::from(rank)) >> 32) as u32;
                let v = (f64::from(bits) + f64::from(low) / 4_294_967_296.0) / 4_294_967_296.0;
                assert!(
                    (v - scramble.value(rank)).abs() < 2f64.powi(-52),
                    "seed {seed}"
                );
            }
        }
    }

    /// One plane per domain triangle and levels per slot, capped at the leaf levels.
    #[test]
    fn progressive_tables_cover_every_triangle() {
        let pre = torus();
        let flat = FlatSampler::new(&pre.sampler).expect("flat");
        let prog = FlatProgressive::new(&pre.sampler);
        assert_eq!(prog.planes.len(), flat.triangles.len());
        assert_eq!(prog.levels.len(), flat.slot_segments.len());
        assert!(
            prog.levels
                .iter()
                .all(|&l| (1..=PROGRESSIVE_LEVELS).contains(&l))
        );
        // Densities are positive somewhere in every triangle: not all planes vanish.
        assert!(prog.planes.iter().all(|p| p.iter().any(|&w| w != 0)));
        assert!(prog.bytes() > 0);
    }

    /// A request that descends into boundary leaves is refused until the trees are
    /// deepened; the deepened trees' children carry shares of their node's measure
    /// that sum to about one, and the thresholds give every boundary leaf the
    /// sequential sampler's levels.
    #[test]
    fn deepened_trees_serve_large_requests() {
        let pre = torus();
        let sampler = &pre.sampler;
        let mut flat = FlatSampler::new(sampler).expect("flat");
        let n = 400_000;
        assert!(matches!(
            flat.request(sampler, n, 1),
            Err(FlatError::Shallow { .. })
        ));
        assert!(flat.deepen(sampler, n).expect("deepen"));
        assert!(!flat.deepen(sampler, n).expect("again"));
        let request = flat.request(sampler, n, 1).expect("request");
        assert!(request.depth >= 1);
        assert_eq!(
            request.thresholds.len(),
            request.groups.len() * request.depth as usize
        );
        let inner: Vec<&FlatNode> = flat
            .nodes
            .iter()
            .filter(|n| n[9] != u32::MAX || n[10] != u32::MAX)
            .collect();
        assert!(!inner.is_empty());
        for node in inner {
            let share =
                |lo: u32, hi: u32| (u64::from(lo) | u64::from(hi) << 32) as f64 / 2f64.powi(64);
            let sum = share(node[5], node[6]) + share(node[7], node[8]);
            assert!((sum - 1.0).abs() < 1e-6, "children share {sum}");
        }
        // Thresholds: a leaf of measure w descends through the levels the sampler's
        // formula gives.
        let per_sample = request.groups[0][1] as f64 / sampler.segments()[0].curve.measure();
        for (k, &t) in request.thresholds[..request.depth as usize]
            .iter()
            .enumerate()
        {
            let w = f64::from_bits(t);
            assert!(descent_levels(w * per_sample) > k as u32);
            assert!(descent_levels(w.next_down() * per_sample) <= k as u32);
        }
    }
}
