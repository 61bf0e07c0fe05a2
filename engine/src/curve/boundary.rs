//! The exact descent through the sub-cells of a boundary leaf (a leaf the domain's
//! boundary crosses), following the measures of the sub-cells in curve order down to a
//! fully covered one or to the last level, then placing the point by area in the
//! triangle piece its measure falls in, so every point lies in the domain.
//!
//! Two descents give the same points up to round-off: `descend_pieces` clips each
//! candidate once and splits the pieces along midlines (leaves with at most
//! `PIECES` candidates, with its leaf cache in [`LeafScratch`]), and
//! `descend_partial` clips every candidate to every sub-cell measured (the general
//! case and the tests' reference). Cost per level: two polygon splits per piece, or up
//! to four overlaps per candidate.

use glam::DVec2;

use super::clip::{Poly, barycentric, clip_triangle};
use super::key::CellKey;
use super::pieces::{LeafScratch, PieceSet};
use super::segment_curve::{DomainPoint, SegmentCurve};

impl SegmentCurve {
    /// [`point_in_leaf_to`](Self::point_in_leaf_to) with boundary leaves always taking
    /// the general descent that clips every candidate triangle to every sub-cell (the
    /// reference the polygon-splitting descent is tested against).
    #[cfg(test)]
    pub(crate) fn point_in_leaf_general(&self, leaf: usize, t: f64, levels: u32) -> DomainPoint {
        let key = self.keys[leaf];
        let off = &self.candidate_offsets[leaf..leaf + 2];
        let cands = &self.candidates[off[0] as usize..off[1] as usize];
        let t = t.clamp(0.0, 1.0 - f64::EPSILON);
        let levels = levels.min(self.options.leaf_levels as u32);
        if key.full() {
            return self.point_in_leaf_to(leaf, t, levels);
        }
        self.descend_partial(leaf, key, cands, t, levels)
    }

    /// Exact descent through the sub-cells of a boundary leaf by splitting polygons.
    ///
    /// Each candidate triangle is clipped to the leaf once; at each level its piece
    /// (a convex polygon) is split along the midline between the first two and the
    /// last two children in curve order, and the chosen half along the other
    /// midline, so a level costs two polygon splits per piece and no clipping. The
    /// measure of a piece is the exact integral of its triangle's affine density
    /// (`g . moment + h area`). The target measure is carried down as in
    /// [`descend_partial`](Self::descend_partial), which this equals up to round-off.
    #[inline(never)]
    pub(super) fn descend_pieces<'a>(
        &'a self,
        leaf: usize,
        key: CellKey,
        cands: &[u32],
        t: f64,
        levels: u32,
        scratch: &mut LeafScratch<'a>,
    ) -> DomainPoint {
        let mut lo = key.origin();
        let mut size = key.size();
        let mut state = key.state();
        let mut node_measure = self.cumulative[leaf + 1] - self.cumulative[leaf];
        let mut target = t * node_measure;
        if levels == 0 && !scratch.holds(self, leaf) {
            // No descent and nothing cached (a leaf expecting at most one sample, the
            // usual boundary leaf at high counts): clip candidates only up to the piece
            // holding the target, the piece the cached path below picks from all of
            // them, in the same order and with the same measures.
            if let Some(p) = self.place_in_pieces(self.clipped_pieces(cands, lo, size), target) {
                return p;
            }
        }
        self.cache_leaf(leaf, key, cands, levels, scratch);
        let root = &scratch.root;
        let halves = &scratch.halves;
        let bufs = &mut scratch.bufs;
        // The first level starts from the cached halves; its second split reads the
        // chosen half (`from_half`), so all of `bufs` is free.
        let mut cur = 0usize;
        let mut at_root = true;
        let mut from_half: Option<&PieceSet> = None;
        for depth in 0..levels {
            let half = 0.5 * size;
            let (x0, y0, _) = state.child(0);
            let (x1, _, _) = state.child(1);
            // Ranks 0 and 1 share a half of the node: cut between the halves first,
            // then between the two quarters of the chosen half along the other axis.
            let first_along_x = x0 == x1;
            let at = |along_x: bool| if along_x { lo.x } else { lo.y } + half;
            let upper_first = if first_along_x { x0 == 1 } else { y0 == 1 };
            let first = if depth == 0 {
                pick_half(halves, upper_first, &mut target).map(|(first, half)| {
                    from_half = Some(half);
                    first
                })
            } else {
                self.split_pick(
                    None,
                    bufs,
                    &mut cur,
                    (first_along_x, at(first_along_x)),
                    upper_first,
                    &mut target,
                )
            };
            let Some(first) = first else {
                break;
            };
            let rank0 = if first { 0 } else { 2 };
            let (qx, qy, _) = state.child(rank0);
            let upper_first = if first_along_x { qy == 1 } else { qx == 1 };
            at_root = false;
            let Some(first) = self.split_pick(
                from_half,
                bufs,
                &mut cur,
                (!first_along_x, at(!first_along_x)),
                upper_first,
                &mut target,
            ) else {
                break;
            };
            from_half = None;
            let rank = rank0 + if first { 0 } else { 1 };
            let (qx, qy, child_state) = state.child(rank);
            lo += DVec2::new(qx as f64, qy as f64) * half;
            size = half;
            state = child_state;
            let node = &bufs[cur];
            node_measure = node.measure;
            if node.area >= half * half * (1.0 - 1e-9) {
                let t = (target / node_measure).clamp(0.0, 1.0 - f64::EPSILON);
                let (x, y) = super::hilbert::point_in_node(state, t, levels - depth - 1);
                let (ids, n) = node.triangles();
                return self.point_location(&ids[..n], lo + DVec2::new(x, y) * size);
            }
        }
        // Depth exhausted inside a boundary sub-cell.
        let node = match (at_root, from_half) {
            (true, _) => root,
            (false, Some(half)) => half,
            (false, None) => &bufs[cur],
        };
        self.place_in_sub_cell(node, target, cands, lo, size)
    }

    /// Fills `scratch` for leaf `leaf` (of key `key`) unless it holds it already: the
    /// candidates clipped to the leaf and, once a descent needs it (`levels > 0`), the
    /// leaf's first cut (between its first two and last two children in curve order).
    /// Kept for the next sample: consecutive values often fall in the same boundary
    /// leaf.
    #[inline(always)]
    fn cache_leaf<'a>(
        &'a self,
        leaf: usize,
        key: CellKey,
        cands: &[u32],
        levels: u32,
        scratch: &mut LeafScratch<'a>,
    ) {
        let (lo, size, state) = (key.origin(), key.size(), key.state());
        if !scratch.holds(self, leaf) {
            scratch.root.clear();
            for &tri in cands {
                let poly = clip_triangle(&self.triangle_corners(tri as usize), lo, size);
                scratch.root.add(self, tri, poly);
            }
            scratch.root_of = Some((self, leaf));
            scratch.halves_ready = false;
        }
        if levels > 0 && !scratch.halves_ready {
            // The same cut as the descent's first at depth 0.
            let (x0, _, _) = state.child(0);
            let (x1, _, _) = state.child(1);
            let [below, above] = &mut scratch.halves;
            if x0 == x1 {
                scratch
                    .root
                    .split::<0>(self, lo.x + 0.5 * size, below, above);
            } else {
                scratch
                    .root
                    .split::<1>(self, lo.y + 0.5 * size, below, above);
            }
            scratch.halves_ready = true;
        }
    }

    /// The point at measure `target` in the pieces of `node`, the boundary sub-cell
    /// `[lo, lo + size]^2` a descent ended in: the piece holding the target and the
    /// point at the rest of the target in it; failing that (no piece with measure), the
    /// sub-cell's centre located among the node's triangles, or among `cands` when it
    /// has none.
    #[inline(always)]
    fn place_in_sub_cell(
        &self,
        node: &PieceSet,
        target: f64,
        cands: &[u32],
        lo: DVec2,
        size: f64,
    ) -> DomainPoint {
        // A piece's area is not always its polygon's bits (the part above a split
        // keeps the rest of its parent's): `point_at` recomputes it.
        let pieces = node.pieces[..node.len]
            .iter()
            .map(|p| (p.tri, p.poly, p.measure, None));
        if let Some(p) = self.place_in_pieces(pieces, target) {
            return p;
        }
        let (ids, n) = node.triangles();
        let ids = if n > 0 { &ids[..n] } else { cands };
        self.point_location(ids, lo + DVec2::splat(0.5 * size))
    }

    /// Triangles `cands` clipped to the square `[lo, lo + size]^2`, lazily, as
    /// `(triangle, piece, measure of the piece, area of the piece)` for
    /// [`place_in_pieces`](Self::place_in_pieces).
    fn clipped_pieces<'a>(
        &'a self,
        cands: &'a [u32],
        lo: DVec2,
        size: f64,
    ) -> impl Iterator<Item = (u32, Poly, f64, Option<f64>)> + 'a {
        cands.iter().map(move |&tri| {
            let poly = clip_triangle(&self.triangle_corners(tri as usize), lo, size);
            let (area, moment) = poly.area_moment();
            (
                tri,
                poly,
                self.part_measure(tri, area, moment),
                Some(area.abs()),
            )
        })
    }

    /// The point at `target` (in `[0, total)`) of a boundary sub-cell given as its
    /// pieces `(triangle, part of the triangle in the sub-cell, measure of the part,
    /// area of the part)` in curve-independent but fixed order (the area where the
    /// caller has it as `Poly::area_moment` gives it, made non-negative; `None`: it is
    /// computed here): the piece holding the target, then the point at the rest of the
    /// target as a fraction of that piece's area ([`Poly::point_at`]). Inside a piece
    /// the density is taken as uniform, as in a full leaf. `None` when no piece has
    /// measure.
    fn place_in_pieces(
        &self,
        pieces: impl Iterator<Item = (u32, Poly, f64, Option<f64>)>,
        mut target: f64,
    ) -> Option<DomainPoint> {
        let mut chosen = None;
        for (tri, poly, m, area) in pieces {
            if !(m > 0.0) {
                continue;
            }
            chosen = Some((tri, poly, m, area, target));
            if target < m {
                break;
            }
            target -= m;
        }
        let (tri, poly, m, area, rest) = chosen?;
        let uv = match area {
            Some(area) => poly.point_at_with_area(rest / m, area)?,
            None => poly.point_at(rest / m)?,
        };
        // The point is in the piece, so in the triangle up to round-off: clamp it on.
        let b = barycentric(&self.triangle_corners(tri as usize), uv);
        Some(self.clamped_onto(tri, b))
    }

    /// One step of [`descend_pieces`](Self::descend_pieces): splits the pieces in
    /// `source` (if given, else `bufs[*cur]`) at the midline `cut = (along_x, at)`:
    /// `x = at` (`along_x`) or `y = at`, picks the half
    /// holding `target` (`upper_first`: the half above the midline comes first in
    /// curve order) and makes it current. `Some(true)` when the first half in curve
    /// order was taken; `None` when both halves are empty.
    #[inline]
    fn split_pick(
        &self,
        source: Option<&PieceSet>,
        bufs: &mut [PieceSet; 3],
        cur: &mut usize,
        (along_x, at): (bool, f64),
        upper_first: bool,
        target: &mut f64,
    ) -> Option<bool> {
        let (from, below, above) = rotate3(bufs, *cur);
        let from = source.unwrap_or(from);
        if along_x {
            from.split::<0>(self, at, below, above);
        } else {
            from.split::<1>(self, at, below, above);
        }
        let (m_first, m_second) = if upper_first {
            (above.measure, below.measure)
        } else {
            (below.measure, above.measure)
        };
        let first = pick(target, m_first, m_second)?;
        *cur = (*cur + if first == upper_first { 2 } else { 1 }) % 3;
        Some(first)
    }

    /// Exact descent through the sub-cells of a boundary leaf.
    ///
    /// `t * measure(leaf)` is carried down as an absolute target, so at each level the
    /// children are measured in curve order only until the one holding the target (on
    /// average 2.5 of 4), and each child keeps only the candidate triangles that
    /// overlap it, so deeper levels clip fewer triangles.
    #[inline(never)]
    pub(super) fn descend_partial(
        &self,
        leaf: usize,
        key: CellKey,
        cands: &[u32],
        t: f64,
        levels: u32,
    ) -> DomainPoint {
        let mut lo = key.origin();
        let mut size = key.size();
        let mut state = key.state();
        let mut node_measure = self.cumulative[leaf + 1] - self.cumulative[leaf];
        let mut target = t * node_measure;
        // Candidates of the current node (`cur`) and of each child measured at this
        // level (`kept`); lists longer than the buffers keep the parent's list.
        let mut cur = Candidates::from_slice(cands);
        let mut kept = [Candidates::EMPTY; 4];
        for depth in 0..levels {
            let half = 0.5 * size;
            let mut chosen = None;
            let mut last = None;
            for rank in 0..4u8 {
                let (qx, qy, child_state) = state.child(rank);
                let c_lo = lo + DVec2::new(qx as f64, qy as f64) * half;
                let list = &mut kept[rank as usize];
                list.clear();
                let (mut m, mut covered) = (0.0, 0.0);
                for &tri in cur.as_slice(cands) {
                    let (mm, a) = self.overlap(tri as usize, c_lo, half);
                    if a > 0.0 {
                        m += mm;
                        covered += a;
                        list.push(tri);
                    }
                }
                if !(m > 0.0) {
                    continue;
                }
                let full = covered >= half * half * (1.0 - 1e-9);
                let child = (rank, c_lo, child_state, m, full);
                last = Some(child);
                if target < m {
                    chosen = Some(child);
                    break;
                }
                target -= m;
            }
            // Round-off past the last child falls back to its end.
            let Some((rank, c_lo, child_state, m, full)) =
                chosen.or_else(|| last.inspect(|c| target = c.3 * (1.0 - f64::EPSILON)))
            else {
                break;
            };
            cur = kept[rank as usize];
            lo = c_lo;
            size = half;
            state = child_state;
            node_measure = m;
            if full {
                let t = (target / node_measure).clamp(0.0, 1.0 - f64::EPSILON);
                let (x, y) = super::hilbert::point_in_node(state, t, levels - depth - 1);
                return self.point_location(cur.as_slice(cands), lo + DVec2::new(x, y) * size);
            }
        }
        // Depth exhausted inside a boundary sub-cell: the piece holding the target,
        // and the point at the rest of the target in it.
        let cands = cur.as_slice(cands);
        if let Some(p) = self.place_in_pieces(self.clipped_pieces(cands, lo, size), target) {
            return p;
        }
        self.point_location(cands, lo + DVec2::splat(0.5 * size))
    }

    /// The measure of the part of triangle `tri` with `area` and first `moment`: the
    /// exact integral of the triangle's affine density over it (zero without area).
    #[inline]
    pub(super) fn part_measure(&self, tri: u32, area: f64, moment: DVec2) -> f64 {
        if !(area > 0.0) {
            return 0.0;
        }
        let [gx, gy, h] = self.density_planes[tri as usize];
        (gx * moment.x + gy * moment.y + h * area).max(0.0)
    }
}

/// The buffer `i` of three and the two others, in rotating order.
#[inline]
fn rotate3<T>(b: &mut [T; 3], i: usize) -> (&T, &mut T, &mut T) {
    let [x, y, z] = b;
    match i {
        0 => (x, y, z),
        1 => (y, z, x),
        _ => (z, x, y),
    }
}

/// [`pick`] between the halves of a leaf's first cut (`[below, above]`; `upper_first`
/// when the upper half comes first in curve order), with the half chosen.
#[inline(always)]
fn pick_half<'h>(
    halves: &'h [PieceSet; 2],
    upper_first: bool,
    target: &mut f64,
) -> Option<(bool, &'h PieceSet)> {
    let [below, above] = halves;
    let (m_first, m_second) = if upper_first {
        (above.measure, below.measure)
    } else {
        (below.measure, above.measure)
    };
    pick(target, m_first, m_second)
        .map(|first| (first, if first == upper_first { above } else { below }))
}

/// Chooses between the first and the second part of a node (in curve order) for the
/// target measure, moving the target into the chosen part; round-off past the end
/// falls back to the end of the last non-empty part. `None` when both are empty.
#[inline]
fn pick(target: &mut f64, m_first: f64, m_second: f64) -> Option<bool> {
    if m_first > 0.0 && (*target < m_first || !(m_second > 0.0)) {
        *target = target.min(m_first * (1.0 - f64::EPSILON));
        Some(true)
    } else if m_second > 0.0 {
        *target = (*target - m_first).clamp(0.0, m_second * (1.0 - f64::EPSILON));
        Some(false)
    } else {
        None
    }
}

/// A short candidate list on the stack, or "all of the leaf's candidates" when the
/// leaf has more than fit (rare: leaves overlap a few triangles).
#[derive(Clone, Copy)]
struct Candidates {
    ids: [u32; Candidates::CAP],
    /// Number of ids, or `ALL` for the whole slice given to `as_slice`.
    len: usize,
}

impl Candidates {
    const CAP: usize = 12;
    const ALL: usize = usize::MAX;
    const EMPTY: Candidates = Candidates {
        ids: [0; Candidates::CAP],
        len: 0,
    };

    fn from_slice(s: &[u32]) -> Self {
        let mut c = Self::EMPTY;
        if s.len() > Self::CAP {
            c.len = Self::ALL;
        } else {
            c.ids[..s.len()].copy_from_slice(s);
            c.len = s.len();
        }
        c
    }

    fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends `id`; past the capacity the list becomes `ALL` (a superset, still exact:
    /// triangles that miss a cell contribute nothing to it).
    fn push(&mut self, id: u32) {
        if self.len == Self::ALL {
            return;
        }
        if self.len == Self::CAP {
            self.len = Self::ALL;
            return;
        }
        self.ids[self.len] = id;
        self.len += 1;
    }

    fn as_slice<'a>(&'a self, all: &'a [u32]) -> &'a [u32] {
        if self.len == Self::ALL {
            all
        } else {
            &self.ids[..self.len]
        }
    }
}
