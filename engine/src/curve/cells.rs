//! Adaptive Hilbert cells with exact measures over a triangulated parameter domain.

use glam::DVec2;

use super::clip::{Poly, clip_triangle};
use super::hilbert::State;
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

/// Where a leaf cell lies and how the curve runs through it, packed into 8 bytes (the
/// cells are the largest per-face part of the preprocessed data).
///
/// Layout of the `u64`: bits 0..31 hold the column with a marker bit above it at bit
/// `level` (so the level is the position of the highest set bit and needs no field of
/// its own), bits 31..61 the row, bits 61..63 the Hilbert state and bit 63 whether the
/// domain covers the whole cell. Levels go up to 30 ([`CurveOptions::max_level`]).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CellKey(u64);

impl CellKey {
    /// Deepest level a key can hold.
    pub const MAX_LEVEL: u8 = 30;
    const LOW: u64 = (1 << 31) - 1;

    /// The cell at column `x` and row `y` of level `level` (`x, y < 2^level`, `level <=`
    /// [`MAX_LEVEL`](Self::MAX_LEVEL); out-of-range bits are dropped).
    #[inline]
    pub fn new(x: u32, y: u32, level: u8, state: State, full: bool) -> Self {
        debug_assert!(level <= Self::MAX_LEVEL);
        debug_assert!((x as u64) < 1 << level && (y as u64) < 1 << level);
        let level = level.min(Self::MAX_LEVEL);
        let mask = (1u64 << level) - 1;
        let low = (x as u64 & mask) | 1 << level;
        Self(low | (y as u64 & mask) << 31 | ((state.0 & 3) as u64) << 61 | (full as u64) << 63)
    }

    /// Quadtree level (the cell's side is `2^-level`).
    #[inline]
    pub fn level(&self) -> u8 {
        (31 - ((self.0 & Self::LOW) as u32).leading_zeros()) as u8
    }

    /// Cell column at its level.
    #[inline]
    pub fn x(&self) -> u32 {
        let low = (self.0 & Self::LOW) as u32;
        low ^ (1 << self.level())
    }

    /// Cell row at its level.
    #[inline]
    pub fn y(&self) -> u32 {
        ((self.0 >> 31) & ((1 << 30) - 1)) as u32
    }

    /// Hilbert orientation of the cell.
    #[inline]
    pub fn state(&self) -> State {
        State(((self.0 >> 61) & 3) as u8)
    }

    /// Whether the domain covers the whole cell.
    #[inline]
    pub fn full(&self) -> bool {
        self.0 >> 63 != 0
    }

    /// Side length.
    #[inline]
    pub fn size(&self) -> f64 {
        // 2^-level, built from its exponent (no integer conversion, no division).
        f64::from_bits((1023 - self.level() as u64) << 52)
    }

    /// Lower-left corner.
    #[inline]
    pub fn origin(&self) -> DVec2 {
        DVec2::new(self.x() as f64, self.y() as f64) * self.size()
    }
}

impl std::fmt::Debug for CellKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CellKey")
            .field("x", &self.x())
            .field("y", &self.y())
            .field("level", &self.level())
            .field("state", &self.state())
            .field("full", &self.full())
            .finish()
    }
}

/// The adaptive Hilbert cells of one parameterized segment.
///
/// Leaves are stored in Hilbert order with the cumulative measure, so a 1D value in
/// `[0, measure)` maps to a leaf by search and then to a point inside it by the
/// continuous Hilbert map ([`SegmentCurve::locate`]).
#[derive(Clone, Debug)]
pub struct SegmentCurve {
    keys: Vec<CellKey>,
    /// `cumulative[i]` is the measure of leaves `0..i`; length `keys.len() + 1`.
    cumulative: Vec<f64>,
    /// Per leaf, a range into `candidates`: the triangles overlapping it.
    candidate_offsets: Vec<u32>,
    candidates: Vec<u32>,
    uv: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    /// Per triangle, the density as an affine function `g . p + h`: `[gx, gy, h]`.
    density_planes: Vec<[f64; 3]>,
    options: CurveOptions,
    /// Identifies these cells for the leaf cache of [`LeafScratch`]: unique per build
    /// (a clone shares it, and the cells never change after the build).
    id: u64,
}

/// Source of [`SegmentCurve`] ids.
static NEXT_CURVE_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

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
            id: NEXT_CURVE_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
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

    fn triangle_corners(&self, t: usize) -> [DVec2; 3] {
        self.triangles[t].map(|v| self.uv[v as usize])
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
    fn overlap(&self, t: usize, lo: DVec2, size: f64) -> (f64, f64) {
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
    /// not depend on the scratch's previous contents. Always inlined: it is the
    /// sampler's per-sample path, compiled with the sampler's target features.
    #[inline(always)]
    pub fn point_in_leaf_with(
        &self,
        leaf: usize,
        t: f64,
        levels: u32,
        scratch: &mut LeafScratch,
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
        FullLeaf {
            cands: &self.candidates[off[0] as usize..off[1] as usize],
            state: key.state(),
            levels,
            gx: (key.x() as u64) << levels,
            gy: (key.y() as u64) << levels,
            inv: super::hilbert::pow2_neg(key.level() as u32 + levels),
        }
    }

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
    // Out of line: boundary leaves hold a few percent of the samples, and the full-leaf
    // path stays small (fewer registers saved per sample).
    #[inline(never)]
    fn descend_pieces(
        &self,
        leaf: usize,
        key: CellKey,
        cands: &[u32],
        t: f64,
        levels: u32,
        scratch: &mut LeafScratch,
    ) -> DomainPoint {
        let mut lo = key.origin();
        let mut size = key.size();
        let mut state = key.state();
        let mut node_measure = self.cumulative[leaf + 1] - self.cumulative[leaf];
        let mut target = t * node_measure;
        if levels == 0 && scratch.root_of != Some((self.id, leaf)) {
            // No descent and nothing cached (a leaf expecting at most one sample, the
            // usual boundary leaf at high counts): clip candidates only up to the piece
            // holding the target, the piece the cached path below picks from all of
            // them, in the same order and with the same measures.
            if let Some(p) = self.place_in_pieces(self.clipped_pieces(cands, lo, size), target) {
                return p;
            }
        }
        // The candidates clipped to the leaf and, once a descent needs it, the leaf's
        // first cut (between its first two and last two children in curve order), kept
        // in the scratch for the next sample: consecutive values often fall in the same
        // boundary leaf.
        if scratch.root_of != Some((self.id, leaf)) {
            scratch.root.clear();
            for &tri in cands {
                let poly = clip_triangle(&self.triangle_corners(tri as usize), lo, size);
                scratch.root.add(self, tri, poly);
            }
            scratch.root_of = Some((self.id, leaf));
            scratch.halves_ready = false;
        }
        if levels > 0 && !scratch.halves_ready {
            // The same cut as the loop's first at depth 0.
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
                let [below, above] = halves;
                let (m_first, m_second) = if upper_first {
                    (above.measure, below.measure)
                } else {
                    (below.measure, above.measure)
                };
                pick(&mut target, m_first, m_second).inspect(|&first| {
                    from_half = Some(if first == upper_first { above } else { below });
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
        // Depth exhausted inside a boundary sub-cell: the piece holding the target,
        // and the point at the rest of the target in it.
        let node = match (at_root, from_half) {
            (true, _) => root,
            (false, Some(half)) => half,
            (false, None) => &bufs[cur],
        };
        let pieces = node.pieces[..node.len]
            .iter()
            .map(|p| (p.tri, p.poly, p.measure));
        if let Some(p) = self.place_in_pieces(pieces, target) {
            return p;
        }
        let (ids, n) = node.triangles();
        let ids = if n > 0 { &ids[..n] } else { cands };
        self.point_location(ids, lo + DVec2::splat(0.5 * size))
    }

    /// Triangles `cands` clipped to the square `[lo, lo + size]^2`, lazily, as
    /// `(triangle, piece, measure of the piece)` for
    /// [`place_in_pieces`](Self::place_in_pieces).
    fn clipped_pieces<'a>(
        &'a self,
        cands: &'a [u32],
        lo: DVec2,
        size: f64,
    ) -> impl Iterator<Item = (u32, Poly, f64)> + 'a {
        cands.iter().map(move |&tri| {
            let poly = clip_triangle(&self.triangle_corners(tri as usize), lo, size);
            let (area, moment) = poly.area_moment();
            (tri, poly, self.part_measure(tri, area, moment))
        })
    }

    /// The point at `target` (in `[0, total)`) of a boundary sub-cell given as its
    /// pieces `(triangle, part of the triangle in the sub-cell, measure of the part)`
    /// in curve-independent but fixed order: the piece holding the target, then the
    /// point at the rest of the target as a fraction of that piece's area
    /// ([`Poly::point_at`]). Inside a piece the density is taken as uniform, as in a
    /// full leaf. `None` when no piece has measure.
    fn place_in_pieces(
        &self,
        pieces: impl Iterator<Item = (u32, Poly, f64)>,
        mut target: f64,
    ) -> Option<DomainPoint> {
        let mut chosen = None;
        for (tri, poly, m) in pieces {
            if !(m > 0.0) {
                continue;
            }
            chosen = Some((tri, poly, m, target));
            if target < m {
                break;
            }
            target -= m;
        }
        let (tri, poly, m, rest) = chosen?;
        let uv = poly.point_at(rest / m)?;
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
    fn descend_partial(
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

    /// Finds the candidate triangle containing `uv` (the most-inside one if round-off
    /// leaves it just outside all of them) and its barycentric coordinates.
    #[inline(always)]
    fn point_location(&self, cands: &[u32], uv: DVec2) -> DomainPoint {
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

    /// The rest of [`point_location`](Self::point_location), out of line (rare: a point
    /// on an edge up to round-off): the candidate with the largest smallest barycentric
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
    fn clamped_onto(&self, tri: u32, b: [f64; 3]) -> DomainPoint {
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

    /// The measure of the part of triangle `tri` with `area` and first `moment`: the
    /// exact integral of the triangle's affine density over it (zero without area).
    #[inline]
    fn part_measure(&self, tri: u32, area: f64, moment: DVec2) -> f64 {
        if !(area > 0.0) {
            return 0.0;
        }
        let [gx, gy, h] = self.density_planes[tri as usize];
        (gx * moment.x + gy * moment.y + h * area).max(0.0)
    }
}

/// A full leaf ready to place points ([`SegmentCurve::full_leaf`]).
pub(crate) struct FullLeaf<'a> {
    cands: &'a [u32],
    state: super::hilbert::State,
    levels: u32,
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
        let (x, y) = super::hilbert::cell_in_node(self.state, t, self.levels);
        // The sub-cell's centre on the grid of level `level + levels`: the same value
        // as `origin + (x + 0.5) 2^-levels size`, both exact before rounding.
        let gx = (self.gx | x) as f64 + 0.5;
        let gy = (self.gy | y) as f64 + 0.5;
        curve.point_location(self.cands, DVec2::new(gx, gy) * self.inv)
    }
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

/// Most candidate triangles of a boundary leaf that the polygon-splitting descent
/// handles (more take the general descent; 99.9% of the bunny's boundary leaves have
/// at most 6).
const PIECES: usize = 6;

/// Scratch memory of the exact descent through boundary leaves
/// ([`SegmentCurve::point_in_leaf_with`]).
#[derive(Clone)]
pub struct LeafScratch {
    bufs: [PieceSet; 3],
    /// The candidates of leaf `root_of.1` of the cells with id `root_of.0`, clipped to
    /// the leaf.
    root: PieceSet,
    /// `root` split by the leaf's first cut: below and above the midline.
    halves: [PieceSet; 2],
    /// Whether `halves` holds the cut of `root`.
    halves_ready: bool,
    root_of: Option<(u64, usize)>,
}

impl Default for LeafScratch {
    fn default() -> Self {
        Self {
            bufs: [PieceSet::EMPTY; 3],
            root: PieceSet::EMPTY,
            halves: [PieceSet::EMPTY; 2],
            halves_ready: false,
            root_of: None,
        }
    }
}

impl std::fmt::Debug for LeafScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LeafScratch")
    }
}

/// A candidate triangle's part of the current node in a boundary-leaf descent.
#[derive(Clone, Copy)]
struct Piece {
    tri: u32,
    poly: Poly,
    area: f64,
    measure: f64,
}

/// The non-empty pieces of one node, with their total measure and area.
#[derive(Clone, Copy)]
struct PieceSet {
    pieces: [Piece; PIECES],
    len: usize,
    measure: f64,
    area: f64,
}

impl PieceSet {
    const EMPTY: PieceSet = PieceSet {
        pieces: [Piece {
            tri: 0,
            poly: Poly::EMPTY,
            area: 0.0,
            measure: 0.0,
        }; PIECES],
        len: 0,
        measure: 0.0,
        area: 0.0,
    };

    fn clear(&mut self) {
        self.len = 0;
        self.measure = 0.0;
        self.area = 0.0;
    }

    /// Adds the part `poly` of triangle `tri` if it has positive area.
    #[inline]
    fn add(&mut self, curve: &SegmentCurve, tri: u32, poly: Poly) {
        if self.len < PIECES {
            self.pieces[self.len].poly = poly;
            let _ = self.commit(curve, tri);
        }
    }

    /// Keeps the polygon written into the next free piece if it has positive area;
    /// returns the area and measure kept (zero when not kept).
    #[inline]
    fn commit(&mut self, curve: &SegmentCurve, tri: u32) -> (f64, f64) {
        let piece = &mut self.pieces[self.len];
        let (area, moment) = piece.poly.area_moment();
        if area > 0.0 {
            let measure = curve.part_measure(tri, area, moment);
            piece.tri = tri;
            piece.area = area;
            piece.measure = measure;
            self.len += 1;
            self.measure += measure;
            self.area += area;
            (area, measure)
        } else {
            (0.0, 0.0)
        }
    }

    /// Keeps the polygon written into the next free piece, the rest of `whole` after a
    /// split, with the given area and measure, if both its polygon and its area are
    /// non-degenerate.
    #[inline]
    fn commit_rest(&mut self, whole: &Piece, area: f64, measure: f64) {
        let piece = &mut self.pieces[self.len];
        if area > 0.0 && piece.poly.points().len() >= 3 {
            let measure = measure.max(0.0);
            piece.tri = whole.tri;
            piece.area = area;
            piece.measure = measure;
            self.len += 1;
            self.measure += measure;
            self.area += area;
        }
    }

    #[inline]
    fn keep(&mut self, piece: &Piece) {
        // At most one piece per candidate, and candidates are at most PIECES.
        if self.len < PIECES {
            self.pieces[self.len] = *piece;
            self.len += 1;
            self.measure += piece.measure;
            self.area += piece.area;
        }
    }

    /// Splits every piece by the line where coordinate `AXIS` (0: x, 1: y) is `at`
    /// into `below` and `above`; pieces on one side move whole, keeping their measure.
    #[inline]
    fn split<const AXIS: usize>(
        &self,
        curve: &SegmentCurve,
        at: f64,
        below: &mut PieceSet,
        above: &mut PieceSet,
    ) {
        below.clear();
        above.clear();
        for piece in &self.pieces[..self.len] {
            let coord = |p: &DVec2| if AXIS == 0 { p.x } else { p.y };
            let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
            // Plain comparisons: `f64::min`/`max` pay for NaN handling the corners
            // (finite) do not need.
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
                below.keep(piece);
            } else if mn >= at {
                above.keep(piece);
            } else {
                // Both sets hold fewer pieces than this one: room for one more each.
                let (b, a) = (below.len, above.len);
                piece.poly.split_into::<AXIS>(
                    at,
                    &mut below.pieces[b].poly,
                    &mut above.pieces[a].poly,
                );
                // The part above gets the rest of the piece's area and measure (the
                // measure is linear in the polygon): one polygon integral, not two.
                let (area, measure) = below.commit(curve, piece.tri);
                above.commit_rest(piece, piece.area - area, piece.measure - measure);
            }
        }
    }

    /// The triangles of the pieces.
    fn triangles(&self) -> ([u32; PIECES], usize) {
        let mut ids = [0u32; PIECES];
        for (id, piece) in ids.iter_mut().zip(&self.pieces[..self.len]) {
            *id = piece.tri;
        }
        (ids, self.len)
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
