//! A pool of progressive sample sites that grows where a view asks for more (issue 19).
//!
//! A renderer that thresholds progressive ranks against a view's multiplier
//! ([`lod`](super::lod)) needs every rank `k < N lod(p_k)` at hand. The pool holds the
//! sites of ranks `0..P` (a prefix of the sequence, computed once: the rank of entry
//! `k < P` is `k`) and, beyond them, an extension of higher ranks drawn only where the
//! multiplier asks for them. The surface is cut into bins, about [`BINS`] runs of
//! consecutive cells of equal measure (a bin never spans two segments). For each bin
//! an upper bound of the multiplier, from a sphere around the parts of the faces
//! inside its cells and a cone around their normals (`bin_bound`; `lod_bounds.rs`,
//! evaluated for all bins in one branch-free loop, and skipped when only the base
//! count changed), gives the rank it needs, `ceil(N bound)`, and
//! the ranks it lacks are enumerated in that bin alone
//! ([`Sampler::progressive_ranks_in_leaves`]) and placed there, so an update costs in
//! proportion to the bins plus the new ranks. Bin `b` holds every rank below
//! `reach[b]` that falls in it.
//!
//! **Draw-ahead.** A moving camera raises the needed rank of thousands of bins by a
//! few ranks each per frame, and a rank drawn alone in its bin costs two to three
//! times one drawn among others (its cells are cold). A bin that lacks ranks is
//! therefore filled past its need, to `need (1 + a (1 + j))` with `a` the draw-ahead
//! fraction ([`DRAW_AHEAD`], [`LodPool::with_draw_ahead`]) and `j` in `[0, 1)` drawn
//! per bin and per fill (so that bins filled in one frame run dry in different ones,
//! and stay apart): it is refilled every few frames, in batches. This changes which
//! ranks the pool holds, never which are visible: a renderer thresholds by rank.
//!
//! **Splits.** Close to the surface a bin is wider than its distance to the eye and its
//! bound far above the multiplier over most of it, so a bin that asks for many ranks
//! and whose bound is loose is split into finer bins, each with its own bound and
//! cover ([`lod_split`](super::lod_split)).
//!
//! Entries are only ever appended, so a GPU copy of the pool is extended by streaming
//! the new tail ([`PoolChange::Appended`]). When the extension would outgrow its budget
//! and holds ranks the view no longer needs, even with its draw-ahead, it is rebuilt
//! for the current view ([`PoolChange::Rebuilt`]); when the current view alone needs
//! more than the budget, bins are served in order, without draw-ahead, until it is
//! spent and the rest keep the ranks they have ([`LodPool::complete`] says whether
//! every visible rank is held).
//!
//! Which ranks are visible, and where each lies, depend only on the seed, the view and
//! the ranks held, never on the path that led there: the pool's order of entries
//! differs with the path, the samples do not.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::view::{LodError, ViewLod, check_deformation, fade};
use super::bounds::{BoundSet, Frustum, RegionBound, bin_bound};
use super::estimate::ShownEstimate;
use super::bins::SPLIT_ROOM;
use crate::sample::progressive::RankCover;
use crate::sample::{SampleSite, Sampler};
use crate::curve::LeafScratch;
use crate::mesh::TriMesh;

/// The pool cuts the surface into about this many bins, each with its own bound of a
/// view's multiplier: finer bins bound more tightly (fewer ranks drawn that no view
/// shows) and cost more per update (one bound per bin).
pub const BINS: usize = 16384;

/// The default draw-ahead fraction `a` (see the module docs): a bin that lacks ranks
/// is filled to between `1 + a` and `1 + 2a` times its need. On the `lod` bench, with
/// the camera moving before the timed frames, 1/8 draws a growing count 12% faster
/// than 1/32 and orbits 10% faster, for 2-4% more entries held (bench/README.md).
pub const DRAW_AHEAD: f64 = 1.0 / 8.0;

/// What an [`LodPool::update`] changed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PoolChange {
    /// Nothing: the pool already held every rank the view needs (or the budget is
    /// spent on ranks the view still needs).
    Unchanged,
    /// Entries in this range were appended; the entries before it are as they were.
    Appended(Range<usize>),
    /// The extension was rebuilt: entries from [`LodPool::prefix`] on changed.
    Rebuilt,
}

/// The rank a bin needs under multiplier bound `bound` with base count `base`:
/// `(base * bound).ceil() as u32` (saturated at `u32::MAX`, 0 for NaN), without the
/// call to libm's `ceil` that the baseline x86-64 target makes for it: one call per
/// bin per update, 3% of the updates' instructions on the `lod_budget` bench.
#[inline]
pub(super) fn need_of(base: f64, bound: f64) -> u32 {
    let x = base * bound;
    // `as` truncates towards zero and saturates; below zero `ceil` is at most 0 too.
    let t = x as u32;
    t.saturating_add(u32::from(f64::from(t) < x))
}

/// A copy of `items` with room for `capacity` entries, the room written once so that
/// its memory is committed: appending into it later takes no page fault. On the test
/// machine (2 cores, a virtual machine) the faults of an update appending 15k
/// entries took about 0.17 ms of its 1.2 to 2.4 ms.
fn with_room<T: Copy + Default>(items: &[T], capacity: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(capacity.max(items.len()));
    v.resize(v.capacity(), T::default());
    v.truncate(0);
    v.extend_from_slice(items);
    v
}

/// Progressive sample sites for one sampler and seed: a prefix of the sequence plus
/// ranks drawn per segment where views need them. See the module docs.
///
/// A clone keeps the original's room for more entries, its memory committed (as
/// [`new`](Self::new) commits it), so that it updates as the original would.
#[derive(Debug)]
pub struct LodPool {
    seed: u64,
    prefix: u32,
    budget: usize,
    /// The draw-ahead fraction.
    ahead: f64,
    sites: Vec<SampleSite>,
    ranks: Vec<u32>,
    /// The bins: the roots, in segment order and cell order within a segment, then
    /// the children of split bins, in the order they were split
    /// ([`lod_split`](super::lod_split)).
    pub(super) bins: Vec<Bin>,
    /// The number of roots: they partition the surface, and never change.
    pub(super) roots: usize,
    /// Per bin, whether it is split (its children hold its ranks from then on).
    pub(super) split: Vec<bool>,
    /// The split bins and their children, in the order they were split (a parent
    /// before its children's groups).
    pub(super) groups: Vec<(u32, Range<u32>)>,
    /// The most bins split bins may make, the roots included (the roots alone: none
    /// splits).
    pub(super) max_bins: usize,
    /// Per bin, its share of the total measure (of the sequence's values): a column
    /// of its own, read for every bin that lacks ranks before any of them is drawn.
    pub(super) shares: Vec<f64>,
    /// Their bounds, as columns.
    pub(super) bounds: BoundSet,
    /// Per bin: every rank below it that falls in the bin is held.
    pub(super) reach: Vec<u32>,
    /// Per bin, the rank the view of the current update needs (0 for a split bin).
    pub(super) needs: Vec<u32>,
    /// Per bin, the bound of the multiplier of the view `bounded` (kept, so that an
    /// update whose view has not moved, only its base count, skips the bounds).
    pub(super) multipliers: Vec<f64>,
    /// The view `multipliers` bounds, if any.
    pub(super) bounded: Option<ViewLod>,
    /// The bins a parallel update draws in, in order.
    todo: Vec<u32>,
    /// The ranks listed by a sequential update, as runs of one bin: (bin, end entry).
    runs: Vec<(u32, u32)>,
    /// Per chunk of [`DRAW_CHUNK`] bins drawn in, the lists of a parallel update
    /// (kept, so that updates stop allocating).
    lists: Vec<BinList>,
    /// The point budget's estimator, on the current geometry.
    pub(super) estimate: ShownEstimate,
    /// The bins a refinement of the estimate draws in (kept, so that refinements stop
    /// allocating).
    pub(super) live: Vec<u32>,
    /// The bins' bounds on a new geometry (kept, so that a deforming mesh's
    /// [`set_geometry`](Self::set_geometry) stops allocating them).
    rebound: Vec<RegionBound>,
}

impl Clone for LodPool {
    fn clone(&self) -> Self {
        Self {
            seed: self.seed,
            prefix: self.prefix,
            budget: self.budget,
            ahead: self.ahead,
            sites: with_room(&self.sites, self.sites.capacity()),
            ranks: with_room(&self.ranks, self.ranks.capacity()),
            bins: self.bins.clone(),
            roots: self.roots,
            split: self.split.clone(),
            groups: self.groups.clone(),
            max_bins: self.max_bins,
            shares: self.shares.clone(),
            bounds: self.bounds.clone(),
            reach: self.reach.clone(),
            needs: self.needs.clone(),
            multipliers: self.multipliers.clone(),
            bounded: self.bounded,
            todo: self.todo.clone(),
            runs: self.runs.clone(),
            lists: self.lists.clone(),
            estimate: self.estimate.clone(),
            live: self.live.clone(),
            rebound: Vec::new(),
        }
    }
}

/// Bins drawn in per task of a parallel update.
const DRAW_CHUNK: usize = 16;

/// Bins bounded per task of an update.
const BOUND_CHUNK: usize = 2048;

/// Ranks a bin may list beyond its share of a rank range (an estimate's slack: the
/// cover's end intervals).
const COVER_SLACK: f64 = 24.0;

/// One chunk's part of a parallel update.
#[derive(Clone, Debug, Default)]
struct BinList {
    /// The ranks listed, bin after bin.
    ranks: Vec<u32>,
    /// Their sites.
    sites: Vec<SampleSite>,
    /// Each bin's reach after listing.
    reach: Vec<u32>,
}

/// A run of consecutive cells of one segment's curve.
#[derive(Clone, Debug)]
pub(super) struct Bin {
    /// Index into `Sampler::segments`.
    pub(super) segment: u32,
    /// Leaves of the segment's curve.
    pub(super) leaves: Range<u32>,
    /// The dyadic intervals over the bin's values.
    pub(super) cover: RankCover,
}

impl LodPool {
    /// Bounds the bins on `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles, moved): a deforming mesh keeps its samples (sites are
    /// face and barycentric coordinates) and the pool keeps serving every visible rank
    /// of views of the deformed surface. The bins are bounded around their triangles'
    /// corners, the quick bound of `bin_bound` (an eighth of the time of the tight one
    /// [`new`](Self::new) makes, so that it can follow a mesh deforming every frame;
    /// about 15% more ranks drawn for a view). Cost O(faces); an error, and nothing
    /// changed, when `mesh` has other vertices or triangles.
    pub fn set_geometry(&mut self, sampler: &Sampler, mesh: &TriMesh) -> Result<(), LodError> {
        check_deformation(sampler.mesh(), mesh)?;
        // Into the kept list: a mesh deforming every frame calls this every frame.
        let mut bounds = std::mem::take(&mut self.rebound);
        self.bins
            .par_iter()
            .map_init(Default::default, |buffers, bin| {
                let leaves = bin.leaves.start as usize..bin.leaves.end as usize;
                let geometry = (mesh.positions(), mesh.vertex_normals());
                bin_bound(
                    sampler,
                    geometry,
                    bin.segment as usize,
                    leaves,
                    false,
                    buffers,
                )
            })
            .collect_into_vec(&mut bounds);
        self.estimate.move_to(mesh);
        for (i, bound) in bounds.iter().enumerate() {
            self.bounds.set(i, bound);
        }
        self.rebound = bounds;
        self.bounded = None;
        Ok(())
    }

    /// The pool of `sampler`'s progressive sequence for `seed` holding ranks
    /// `0..prefix`, with room for `budget` more ranks drawn per segment, drawing ahead
    /// by [`DRAW_AHEAD`]. Memory: 20 bytes per entry. Room for `min(budget, prefix)`
    /// more entries is reserved and committed up front (written once, so that
    /// appending into it takes no page fault), and the pool grows geometrically
    /// beyond, so that updates soon stop allocating.
    pub fn new(sampler: &Sampler, seed: u64, prefix: u32, budget: usize) -> Self {
        let capacity = prefix as usize + budget.min(prefix as usize);
        let mut sites = with_room(&[], capacity);
        sites.resize(prefix as usize, SampleSite::default());
        sampler.progressive_sites_into(seed, 0, &mut sites);
        let mut ranks = with_room(&[], capacity);
        ranks.extend(0..prefix);
        let made: Vec<(Bin, f64, RegionBound)> = sampler
            .segments()
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, seg)| {
                let target = sampler.total_measure() / BINS as f64;
                let cumulative = seg.curve.cumulative();
                let cells = seg.curve.cell_count();
                let mut runs = Vec::new();
                let mut start = 0;
                for leaf in 0..cells {
                    if cumulative[leaf + 1] - cumulative[start] >= target || leaf + 1 == cells {
                        runs.push(start..leaf + 1);
                        start = leaf + 1;
                    }
                }
                let mut buffers = Default::default();
                runs.into_iter().map(move |leaves| {
                    let mesh = sampler.mesh();
                    let geometry = (mesh.positions(), mesh.vertex_normals());
                    let bound = bin_bound(sampler, geometry, i, leaves.clone(), true, &mut buffers);
                    let share = (cumulative[leaves.end] - cumulative[leaves.start])
                        / sampler.total_measure();
                    let bin = Bin {
                        segment: i as u32,
                        leaves: leaves.start as u32..leaves.end as u32,
                        cover: sampler.progressive_cover(seed, i, leaves),
                    };
                    (bin, share, bound)
                })
            })
            .collect();
        let mut bounds = BoundSet::default();
        for (_, _, bound) in &made {
            bounds.push(bound);
        }
        let shares = made.iter().map(|&(_, share, _)| share).collect();
        let bins: Vec<Bin> = made.into_iter().map(|(bin, _, _)| bin).collect();
        Self {
            seed,
            prefix,
            budget,
            ahead: DRAW_AHEAD,
            sites,
            ranks,
            reach: vec![prefix; bins.len()],
            shares,
            needs: vec![0; bins.len()],
            multipliers: Vec::new(),
            bounded: None,
            roots: bins.len(),
            split: vec![false; bins.len()],
            groups: Vec::new(),
            max_bins: bins.len() * SPLIT_ROOM,
            bins,
            bounds,
            todo: Vec::new(),
            runs: Vec::new(),
            lists: Vec::new(),
            estimate: ShownEstimate::new(sampler, seed),
            live: Vec::new(),
            rebound: Vec::new(),
        }
    }

    /// The same pool drawing ahead by `fraction` (see the module docs; 0: a bin is
    /// filled to its need exactly). Panics unless `fraction` is in `[0, 1]`.
    pub fn with_draw_ahead(mut self, fraction: f64) -> Self {
        assert!(
            (0.0..=1.0).contains(&fraction),
            "draw-ahead fraction {fraction} out of [0, 1]"
        );
        self.ahead = fraction;
        self
    }

    /// The draw-ahead fraction.
    pub fn draw_ahead(&self) -> f64 {
        self.ahead
    }

    /// The seed of the sequence.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Ranks `0..prefix` are the first `prefix` entries.
    pub fn prefix(&self) -> u32 {
        self.prefix
    }

    /// Every entry's site.
    pub fn sites(&self) -> &[SampleSite] {
        &self.sites
    }

    /// Every entry's rank (entry `k < prefix` has rank `k`).
    pub fn ranks(&self) -> &[u32] {
        &self.ranks
    }

    /// Entries held.
    pub fn len(&self) -> usize {
        self.sites.len()
    }

    /// Whether the pool holds no entry.
    pub fn is_empty(&self) -> bool {
        self.sites.is_empty()
    }

    /// The number of bins: about [`BINS`] roots, and the children of the bins split
    /// for close views ([`lod_split`](super::lod_split)), which only grow in number
    /// until the pool is rebuilt.
    pub fn bins(&self) -> usize {
        self.bins.len()
    }

    /// Bin `bin`'s segment (an index into [`Sampler::segments`]) and cells (leaves of
    /// the segment's curve).
    pub fn bin(&self, bin: usize) -> (usize, Range<usize>) {
        let b = &self.bins[bin];
        (
            b.segment as usize,
            b.leaves.start as usize..b.leaves.end as usize,
        )
    }

    /// The rank below which bin `bin` holds every rank that falls in it (for a split
    /// bin, its reach when it was split: its children reach further).
    pub fn reach(&self, bin: usize) -> u32 {
        self.reach[bin]
    }

    /// An upper bound of `view`'s multiplier over bin `bin`, from a sphere around the
    /// parts of the faces inside its cells and a cone around their normals (around
    /// the faces' corners after [`set_geometry`](Self::set_geometry)): 0 when the sphere lies
    /// outside the frustum or (back faces culled) every normal faces away; `view.max`
    /// when the sphere reaches the eye's plane.
    pub fn bound(&self, bin: usize, view: &ViewLod) -> f64 {
        self.bounds.multiplier(bin, &Frustum::new(view))
    }

    /// Bounds every bin's multiplier under `view` into `out`, in parallel (then each
    /// split bin's children by their parent's bound too).
    fn bound_bins(&self, view: &ViewLod, out: &mut Vec<f64>) {
        let frustum = Frustum::new(view);
        out.resize(self.bins.len(), 0.0);
        out.par_chunks_mut(BOUND_CHUNK)
            .enumerate()
            .for_each(|(c, dst)| self.bounds.multipliers_into(&frustum, c * BOUND_CHUNK, dst));
        self.bound_by_parents(out);
    }

    /// Bounds every bin's multiplier under `view` into `multipliers`, unless they hold
    /// its bounds already.
    pub(super) fn bound_view(&mut self, view: &ViewLod) {
        if self.bounded.as_ref() != Some(view) {
            let mut multipliers = std::mem::take(&mut self.multipliers);
            self.bound_bins(view, &mut multipliers);
            self.multipliers = multipliers;
            self.bounded = Some(*view);
        }
    }

    /// Writes into `needs` each bin's needed rank under multiplier bounds
    /// `multipliers` with base count `base`: `ceil(base * bound)`, saturated at
    /// `u32::MAX`, and 0 for a split bin (its children hold its ranks).
    fn needs_from(&self, multipliers: &[f64], base: f64, needs: &mut Vec<u32>) {
        needs.clear();
        needs.extend(multipliers.iter().map(|&b| need_of(base, b)));
        for &(parent, _) in &self.groups {
            needs[parent as usize] = 0;
        }
    }

    /// [`needs_from`](Self::needs_from) the bounds of the last view into `needs`.
    fn need(&mut self, base: f64) {
        let mut needs = std::mem::take(&mut self.needs);
        self.needs_from(&self.multipliers, base, &mut needs);
        self.needs = needs;
    }

    /// The rank bin `bin` is filled to when it needs `need`: past it by the
    /// draw-ahead, scaled by a factor in `[1, 2)` drawn per bin and per fill (a hash
    /// of the bin and its current reach). A factor fixed per bin would spread the
    /// refills' periods but not their phases: under a camera whose needs all grow at
    /// one rate, bins filled together in one frame come due together again, and
    /// the frames where several periods meet draw ten times the ranks of the others.
    fn ahead_of(&self, bin: usize, need: u32) -> u32 {
        let key = (bin as u32) ^ self.reach[bin].wrapping_mul(0x85eb_ca6b);
        let jitter = f64::from(key.wrapping_mul(0x9e37_79b9) >> 8) / 16_777_216.0;
        let more = f64::from(need) * self.ahead * (1.0 + jitter);
        (f64::from(need) + more).min(f64::from(u32::MAX)) as u32
    }

    /// The most any fill for `need` reaches: [`ahead_of`](Self::ahead_of) at its
    /// largest factor.
    fn ahead_limit(&self, need: u32) -> u32 {
        let more = f64::from(need) * self.ahead * 2.0;
        (f64::from(need) + more).min(f64::from(u32::MAX)) as u32
    }

    /// Whether every rank visible under `view` with base count `base` is held.
    pub fn complete(&self, view: &ViewLod, base: f64) -> bool {
        let (mut multipliers, mut needs) = (Vec::new(), Vec::new());
        self.bound_bins(view, &mut multipliers);
        self.needs_from(&multipliers, base, &mut needs);
        needs
            .iter()
            .zip(&self.reach)
            .all(|(need, reach)| reach >= need)
    }

    /// Draws the ranks `view` with base count `base` needs and the pool lacks (and,
    /// in bins that lack some, the draw-ahead). Cost in proportion to the bins plus the
    /// ranks drawn (a view equal to the last update's, with only the base count
    /// changed, reuses its bounds); no allocation while the extension stays within its
    /// budget.
    pub fn update(&mut self, sampler: &Sampler, view: &ViewLod, base: f64) -> PoolChange {
        let start = self.sites.len();
        self.runs.clear();
        self.bound_view(view);
        self.need(base);
        self.split_for(sampler, base);
        if self.extend(sampler) {
            return self.finish(sampler, start);
        }
        // The budget ran out. Rebuild if the extension holds ranks the view does not
        // need, even drawing ahead; otherwise keep what is there.
        let stale = (0..self.reach.len()).any(|b| {
            !self.split[b] && self.reach[b] > self.prefix.max(self.ahead_limit(self.needs[b]))
        });
        if !stale {
            return self.finish(sampler, start);
        }
        self.sites.truncate(self.prefix as usize);
        self.ranks.truncate(self.prefix as usize);
        self.unsplit();
        self.reach.fill(self.prefix);
        self.need(base);
        self.split_for(sampler, base);
        self.runs.clear();
        self.extend(sampler);
        self.finish(sampler, self.prefix as usize);
        PoolChange::Rebuilt
    }

    /// Lists the missing ranks of every bin in order (with their sites when the
    /// parallel pass takes them, with [`finish`](Self::finish) to place them
    /// otherwise); false when the budget ran out first.
    fn extend(&mut self, sampler: &Sampler) -> bool {
        if self.extend_parallel(sampler) {
            return true;
        }
        // Within the budget only: every bin up to its need, in order.
        for b in 0..self.reach.len() {
            let need = self.needs[b];
            if need <= self.reach[b] {
                continue;
            }
            let listed = self.ranks.len();
            let room = self.budget - (listed - self.prefix as usize);
            self.reach[b] = sampler.progressive_ranks_in_cover(
                &self.bins[b].cover,
                self.reach[b],
                need,
                room,
                &mut self.ranks,
            );
            if self.ranks.len() > listed {
                self.runs.push((b as u32, self.ranks.len() as u32));
            }
            if self.reach[b] < need {
                return false;
            }
        }
        true
    }

    /// [`extend`](Self::extend) with draw-ahead, over fixed chunks of the bins that
    /// lack ranks, in parallel, when the ranks expected fit the budget twice over:
    /// each chunk lists its ranks and places them into its own reused lists, and the
    /// lists are appended in chunk order, so the result is the same for any thread
    /// count. False (nothing changed) when they might not fit.
    fn extend_parallel(&mut self, sampler: &Sampler) -> bool {
        let room = self.budget - (self.ranks.len() - self.prefix as usize);
        self.todo.clear();
        let mut expected = 0.0;
        for b in 0..self.bins.len() {
            if self.needs[b] > self.reach[b] {
                let target = self.ahead_of(b, self.needs[b]);
                expected += f64::from(target - self.reach[b]) * self.shares[b] + COVER_SLACK;
                self.todo.push(b as u32);
            }
        }
        if expected * 2.0 > room as f64 {
            return false;
        }
        let chunks = self.todo.len().div_ceil(DRAW_CHUNK);
        let mut lists = std::mem::take(&mut self.lists);
        if lists.len() < chunks {
            lists.resize_with(chunks, Default::default);
        }
        let this = &*self;
        let total: usize = lists[..chunks]
            .par_iter_mut()
            .zip(this.todo.par_chunks(DRAW_CHUNK))
            // One scratch per task split, not per chunk: it is kilobytes to initialise.
            .map_init(LeafScratch::default, |scratch, (list, todo)| {
                list.ranks.clear();
                list.sites.clear();
                list.reach.clear();
                for &b in todo {
                    let (b, first) = (b as usize, list.ranks.len());
                    let cover = &this.bins[b].cover;
                    let target = this.ahead_of(b, this.needs[b]);
                    list.reach.push(sampler.progressive_ranks_in_cover(
                        cover,
                        this.reach[b],
                        target,
                        usize::MAX,
                        &mut list.ranks,
                    ));
                    list.sites.resize(list.ranks.len(), SampleSite::default());
                    sampler.progressive_cover_sites_with(
                        cover,
                        &list.ranks[first..],
                        &mut list.sites[first..],
                        scratch,
                    );
                }
                list.ranks.len()
            })
            .sum();
        if total > room {
            // Far more than expected: let the sequential pass spend the budget.
            self.lists = lists;
            return false;
        }
        for (list, todo) in lists.iter().zip(self.todo.chunks(DRAW_CHUNK)) {
            for (&b, &reach) in todo.iter().zip(&list.reach) {
                self.reach[b as usize] = reach;
            }
            self.ranks.extend_from_slice(&list.ranks);
            self.sites.extend_from_slice(&list.sites);
        }
        self.lists = lists;
        true
    }

    /// Places the ranks a sequential pass listed (the entries past the sites), and
    /// says what changed from entry `start` on.
    fn finish(&mut self, sampler: &Sampler, start: usize) -> PoolChange {
        let (placed, end) = (self.sites.len(), self.ranks.len());
        if end == start {
            return PoolChange::Unchanged;
        }
        self.sites.resize(end, SampleSite::default());
        let (runs, bins, ranks) = (&self.runs, &self.bins, &self.ranks);
        // Fixed chunks of entries, each split at the bins' runs: a bin's cells are
        // searched alone, and the work split does not depend on the thread count.
        self.sites[placed..]
            .par_chunks_mut(1024)
            .enumerate()
            .for_each(|(c, dst)| {
                let (first, last) = (placed + c * 1024, placed + c * 1024 + dst.len());
                let mut run = runs.partition_point(|&(_, end)| end as usize <= first);
                let mut at = first;
                let mut scratch = LeafScratch::default();
                while at < last {
                    let (bin, end) = runs[run];
                    let stop = (end as usize).min(last);
                    sampler.progressive_cover_sites_with(
                        &bins[bin as usize].cover,
                        &ranks[at..stop],
                        &mut dst[at - first..stop - first],
                        &mut scratch,
                    );
                    at = stop;
                    run += 1;
                }
            });
        PoolChange::Appended(start..end)
    }

    /// Writes each entry's fade weight under `view` with base count `base` into `out`
    /// (0 for an entry that is not visible), computing positions and normals on the
    /// CPU as [`Sampler::record`] does: the reference a GPU cull is checked against.
    /// Panics when `out` is not one weight per entry.
    pub fn fades_into(&self, sampler: &Sampler, view: &ViewLod, base: f64, out: &mut [f32]) {
        assert_eq!(out.len(), self.len(), "one weight per entry");
        out.par_chunks_mut(4096)
            .zip(self.sites.par_chunks(4096))
            .zip(self.ranks.par_chunks(4096))
            .for_each(|((dst, sites), ranks)| {
                for ((slot, site), &rank) in dst.iter_mut().zip(sites).zip(ranks) {
                    let b = site.barycentric().map(f64::from);
                    *slot = sampler
                        .record(site.face, b, site.segment, rank, 1)
                        .map_or(0.0, |s| {
                            let p = DVec3::from(s.position.map(f64::from));
                            let n = DVec3::from(s.normal.map(f64::from));
                            fade(rank, base, view.multiplier(p, n)) as f32
                        });
                }
            });
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::TriMesh;
    use crate::surface::tests::torus_sampler;
    use crate::surface::{Preprocessed, SurfaceOptions};
    use std::sync::Arc;

    fn view(eye: DVec3, max: f64) -> ViewLod {
        view_at(eye, DVec3::ZERO, max)
    }

    fn view_at(eye: DVec3, target: DVec3, max: f64) -> ViewLod {
        let fov = 50f64.to_radians();
        let proj = glam::camera::rh::proj::directx::perspective(fov as f32, 1.0, 0.01, 100.0);
        let look =
            glam::camera::rh::view::look_at_mat4(eye.as_vec3(), target.as_vec3(), glam::Vec3::Y);
        ViewLod {
            clip_from_world: (proj * look).as_dmat4(),
            eye,
            focal_pixels: 500.0 / (2.0 * (fov / 2.0).tan()),
            reference: 5000.0,
            max,
            cull_back_faces: false,
        }
    }

    /// The visible ranks and their sites, by a scan of the whole sequence up to `end`.
    fn scan(s: &Sampler, seed: u64, end: u32, v: &ViewLod, base: f64) -> Vec<(u32, SampleSite)> {
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(seed, 0, &mut sites);
        (0..end)
            .zip(sites)
            .filter(|&(k, site)| {
                let r = s
                    .record(site.face, site.barycentric().map(f64::from), 0, k, 1)
                    .expect("record");
                let p = DVec3::from(r.position.map(f64::from));
                let n = DVec3::from(r.normal.map(f64::from));
                fade(k, base, v.multiplier(p, n)) > 0.0
            })
            .collect()
    }

    /// The visible entries (rank and site), in rank order.
    pub(in crate::sample) fn held_visible(
        pool: &LodPool,
        s: &Sampler,
        v: &ViewLod,
        base: f64,
    ) -> Vec<(u32, SampleSite)> {
        let mut fades = vec![0.0; pool.len()];
        pool.fades_into(s, v, base, &mut fades);
        let mut shown: Vec<(u32, SampleSite)> = (0..pool.len())
            .filter(|&i| fades[i] > 0.0)
            .map(|i| (pool.ranks()[i], pool.sites()[i]))
            .collect();
        shown.sort_by_key(|e| e.0);
        shown
    }

    #[test]
    fn need_of_is_the_ceiling_saturated() {
        let reference = |base: f64, bound: f64| (base * bound).ceil() as u32;
        let edges = [
            0.0,
            -0.0,
            -0.5,
            -7.0,
            0.25,
            1.0,
            1.0 + f64::EPSILON,
            4_294_967_294.5,
            4_294_967_295.0,
            4_294_967_295.5,
            4_294_967_296.0,
            1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for x in edges {
            assert_eq!(need_of(1.0, x), reference(1.0, x), "{x}");
        }
        // Bounds and base counts of every magnitude, as a pool's views give them.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let bound = 10f64.powf(12.0 * u - 8.0);
            let base = f64::from((state >> 40) as u32 % 2_000_000);
            assert_eq!(
                need_of(base, bound),
                reference(base, bound),
                "{base} {bound}"
            );
        }
    }

    #[test]
    fn room_for_a_point_budget_covers_close_views() {
        assert_eq!(LodPool::room_for(1000, None, 4.0), 4000);
        // A budget below the count: the count's room still.
        assert_eq!(LodPool::room_for(100_000, Some(1000), 4.0), 400_000);
        // A budget: CLOSE_ROOM times its shown x max.
        assert_eq!(LodPool::room_for(1000, Some(1000), 4.0), 16_000);
        assert_eq!(
            LodPool::room_for(u32::MAX, Some(u32::MAX), 1e30),
            usize::MAX / 2
        );
    }

    /// A frame's base count: the given one without a budget or with nothing in view,
    /// else the budget's, rounded to `f32`.
    #[test]
    fn a_frames_base_count_follows_the_budget() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 3, 2_000, 10_000);
        let v = view(DVec3::new(0.0, 3.0, 3.0), 4.0);
        assert_eq!(pool.frame_base(&s, &v, 2_000.0, None), 2_000.0);
        let budget = pool.frame_base(&s, &v, 2_000.0, Some(5_000));
        let exact = pool.base_for_shown(&s, &v, 5_000.0).expect("in view");
        assert_eq!(budget, f64::from(exact as f32));
        assert!(budget != 2_000.0 && (budget / exact - 1.0).abs() < 1e-6);
        let away = view_at(DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 0.0, 6.0), 4.0);
        assert_eq!(pool.frame_base(&s, &away, 2_000.0, Some(5_000)), 2_000.0);
    }

    #[test]
    fn segment_ranks_equal_a_filtered_scan() {
        let s = torus_sampler();
        assert!(s.segments().len() > 3, "{}", s.segments().len());
        let seed = 7;
        let end = 40_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(seed, 0, &mut sites);
        for (i, seg) in s.segments().iter().enumerate() {
            let scan: Vec<u32> = (0..end)
                .filter(|&k| sites[k as usize].segment == seg.segment)
                .collect();
            let mut listed = Vec::new();
            let reach = s.progressive_ranks_in_segment(seed, i, 0, end, usize::MAX, &mut listed);
            assert_eq!(reach, end);
            assert_eq!(listed, scan, "segment {i}");
            // From the middle, and cut short by a limit.
            let mut part = Vec::new();
            let reach = s.progressive_ranks_in_segment(seed, i, 1234, end, 10, &mut part);
            let expected: Vec<u32> = scan.iter().copied().filter(|&k| k >= 1234).collect();
            assert_eq!(part, expected[..10]);
            assert_eq!(reach, expected[10]);
        }
    }

    #[test]
    fn sites_of_listed_ranks_equal_the_sequence() {
        let s = torus_sampler();
        let ranks = [5u32, 99_999, 3, 70_000, 0];
        let mut out = [SampleSite::default(); 5];
        s.progressive_sites_of(4, &ranks, &mut out);
        for (site, &k) in out.iter().zip(&ranks) {
            let mut one = [SampleSite::default()];
            s.progressive_sites_into(4, k, &mut one);
            assert_eq!(*site, one[0], "rank {k}");
        }
    }

    #[test]
    fn bins_partition_every_segment_and_bound_its_samples() {
        let s = torus_sampler();
        let pool = LodPool::new(&s, 1, 0, 0);
        assert!(pool.bins() > 2 * s.segments().len(), "{} bins", pool.bins());
        let end = 20_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(1, 0, &mut sites);
        // The bins' ranks are the segments' ranks, each exactly once.
        let mut by_bin: Vec<Vec<u32>> = Vec::new();
        for b in 0..pool.bins() {
            let (segment, leaves) = pool.bin(b);
            let mut ranks = Vec::new();
            s.progressive_ranks_in_leaves(1, segment, leaves, 0, end, usize::MAX, &mut ranks);
            by_bin.push(ranks);
        }
        for (i, seg) in s.segments().iter().enumerate() {
            let mut union: Vec<u32> = (0..pool.bins())
                .filter(|&b| pool.bin(b).0 == i)
                .flat_map(|b| by_bin[b].iter().copied())
                .collect();
            union.sort_unstable();
            let scan: Vec<u32> = (0..end)
                .filter(|&k| sites[k as usize].segment == seg.segment)
                .collect();
            assert_eq!(union, scan, "segment {i}");
        }
        for (eye, cull) in [
            (DVec3::new(0.0, 0.2, 3.0), false),
            (DVec3::new(0.0, 0.2, 3.0), true),
            (DVec3::new(1.2, 0.4, 0.9), false),
            (DVec3::new(1.2, 0.4, 0.9), true),
        ] {
            let v = ViewLod {
                cull_back_faces: cull,
                ..view(eye, f64::INFINITY)
            };
            if cull {
                // Seen from outside, some bins face away entirely.
                let hidden = (0..pool.bins()).filter(|&b| pool.bound(b, &v) == 0.0);
                assert!(hidden.count() > 0, "{eye}");
            }
            let mut checked = 0;
            for (b, ranks) in by_bin.iter().enumerate() {
                for &k in ranks {
                    let site = sites[k as usize];
                    let r = s
                        .record(site.face, site.barycentric().map(f64::from), 0, k, 1)
                        .expect("record");
                    let m = v.multiplier(
                        DVec3::from(r.position.map(f64::from)),
                        DVec3::from(r.normal.map(f64::from)),
                    );
                    assert!(m <= pool.bound(b, &v) * (1.0 + 1e-9), "{eye} rank {k}");
                    checked += usize::from(m > 0.0);
                }
            }
            assert!(checked > 1000, "{checked}");
        }
    }

    #[test]
    fn the_pool_holds_every_visible_rank_of_a_moving_view() {
        let s = torus_sampler();
        let base = 20_000.0;
        let mut pool = LodPool::new(&s, 3, 20_000, 400_000);
        // Zoom in on one side of the sphere: the view asks for far more than the prefix.
        for (t, d) in [8.0, 5.0, 3.5, 2.5].into_iter().enumerate() {
            let v = view(DVec3::new(0.3, 0.1, d), 10.0);
            let before = pool.len();
            let change = pool.update(&s, &v, base);
            assert!(pool.complete(&v, base));
            if t > 0 {
                assert_eq!(change, PoolChange::Appended(before..pool.len()), "step {t}");
            }
            let end = pool.ranks().iter().copied().max().unwrap_or(0) + 1;
            assert_eq!(
                held_visible(&pool, &s, &v, base),
                scan(&s, 3, end, &v, base)
            );
        }
        let v = view(DVec3::new(0.3, 0.1, 2.5), 10.0);
        assert_eq!(pool.update(&s, &v, base), PoolChange::Unchanged);
    }

    #[test]
    fn a_clone_updates_as_the_original() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 5, 10_000, 200_000).with_draw_ahead(0.1);
        pool.update(&s, &view(DVec3::new(0.3, 0.1, 3.0), 10.0), 10_000.0);
        let mut twin = pool.clone();
        let closer = view(DVec3::new(0.3, 0.1, 2.0), 10.0);
        assert_eq!(
            pool.update(&s, &closer, 10_000.0),
            twin.update(&s, &closer, 10_000.0)
        );
        assert_eq!((pool.ranks(), pool.sites()), (twin.ranks(), twin.sites()));
        assert_eq!(
            (twin.seed(), twin.prefix(), twin.draw_ahead()),
            (5, 10_000, 0.1)
        );
        assert!(twin.len() > pool.prefix() as usize);
    }

    #[test]
    fn a_still_view_keeps_its_bounds_until_the_mesh_moves() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.3, 0.1, 3.0), 10.0);
        // The base count grows under a still camera: the bounds of the first update
        // serve the next, and the pool matches one built for the last count alone.
        let mut pool = LodPool::new(&s, 3, 10_000, 1_000_000);
        for base in [10_000.0, 14_000.0, 20_000.0] {
            pool.update(&s, &v, base);
            assert!(pool.complete(&v, base));
        }
        let mut fresh = LodPool::new(&s, 3, 10_000, 1_000_000);
        fresh.update(&s, &v, 20_000.0);
        assert_eq!(
            held_visible(&pool, &s, &v, 20_000.0),
            held_visible(&fresh, &s, &v, 20_000.0)
        );
        // Deformed under the same view: the kept bounds are dropped, and the pool
        // holds every rank visible on the stretched surface (longer along z, so it
        // needs more ranks there).
        let stretched = moved(s.mesh(), |p| DVec3::new(p.x, p.y, 2.0 * p.z));
        let mean = pool.shown_estimate().mean_multiplier(&v);
        pool.set_geometry(&s, &stretched).expect("same topology");
        // The point budget's probes moved with the surface.
        let mut probes = crate::sample::lod::ShownEstimate::new(&s, pool.seed());
        probes.set_geometry(&s, &stretched).expect("same topology");
        let stretched_mean = pool.shown_estimate().mean_multiplier(&v);
        assert_eq!(stretched_mean, probes.mean_multiplier(&v));
        assert_ne!(stretched_mean, mean);
        let wanted = pool.complete(&v, 20_000.0);
        pool.update(&s, &v, 20_000.0);
        assert!(!wanted && pool.complete(&v, 20_000.0));
    }

    #[test]
    fn an_outgrown_budget_rebuilds_for_the_view_and_caps_in_segment_order() {
        let s = torus_sampler();
        let base = 20_000.0;
        // Two close-ups of opposite sides of the ring.
        let near = view_at(DVec3::new(1.0, 0.0, 1.2), DVec3::X, 50.0);
        let other = view_at(DVec3::new(-1.0, 0.0, 1.2), -DVec3::X, 50.0);
        let mut probe = LodPool::new(&s, 3, 20_000, usize::MAX / 2);
        probe.update(&s, &near, base);
        let needed = probe.len() - 20_000;
        // Room for one view's ranks, not two.
        let mut pool = LodPool::new(&s, 3, 20_000, needed + needed / 4);
        assert!(matches!(
            pool.update(&s, &near, base),
            PoolChange::Appended(_)
        ));
        assert_eq!(pool.update(&s, &other, base), PoolChange::Rebuilt);
        assert!(pool.complete(&other, base));
        let end = pool.ranks().iter().copied().max().unwrap_or(0) + 1;
        assert_eq!(
            held_visible(&pool, &s, &other, base),
            scan(&s, 3, end, &other, base)
        );
        // A view needing more than the budget gets what fits, and no rebuild loop.
        let greedy = view_at(DVec3::new(1.0, 0.0, 0.7), DVec3::X, 1e6);
        pool.update(&s, &greedy, base);
        assert!(!pool.complete(&greedy, base));
        assert!(pool.len() - 20_000 <= needed + needed / 4);
        assert_eq!(pool.update(&s, &greedy, base), PoolChange::Unchanged);
    }

    #[test]
    fn parallel_and_sequential_updates_list_the_same_entries() {
        let s = torus_sampler();
        let v = view_at(DVec3::new(1.0, 0.2, 1.3), DVec3::X, 30.0);
        // A roomy budget takes the parallel path; one that the ranks exactly fill is
        // refused by its estimate and takes the sequential one.
        // Without draw-ahead: the sequential pass, which spends a budget, has none.
        let mut roomy = LodPool::new(&s, 4, 10_000, 10_000_000).with_draw_ahead(0.0);
        roomy.update(&s, &v, 10_000.0);
        let added = roomy.len() - 10_000;
        assert!(added > 1000, "{added}");
        let mut tight = LodPool::new(&s, 4, 10_000, added);
        tight.update(&s, &v, 10_000.0);
        assert!(tight.complete(&v, 10_000.0));
        assert_eq!(tight.ranks(), roomy.ranks());
        assert_eq!(tight.sites(), roomy.sites());
    }

    #[test]
    fn drawing_ahead_holds_more_ranks_refills_less_and_shows_the_same_samples() {
        let s = torus_sampler();
        let (seed, base) = (5, 20_000.0);
        assert_eq!(LodPool::new(&s, seed, 0, 0).draw_ahead(), DRAW_AHEAD);
        let mut exact = LodPool::new(&s, seed, 20_000, 2_000_000).with_draw_ahead(0.0);
        let mut ahead = LodPool::new(&s, seed, 20_000, 2_000_000).with_draw_ahead(0.25);
        // Bins whose reach an update raised, summed over the updates.
        let mut refills = [0, 0];
        let mut v = view(DVec3::ZERO, 10.0);
        // A dolly in small steps.
        for t in 0..8 {
            v = view(DVec3::new(0.3, 0.1, 4.0 * 0.97f64.powi(t)), 10.0);
            for (pool, count) in [&mut exact, &mut ahead].into_iter().zip(&mut refills) {
                let before: Vec<u32> = (0..pool.bins()).map(|b| pool.reach(b)).collect();
                pool.update(&s, &v, base);
                assert!(pool.complete(&v, base), "step {t}");
                *count += (0..pool.bins())
                    .filter(|&b| pool.reach(b) > before[b])
                    .count();
            }
            assert!((0..ahead.bins()).all(|b| ahead.reach(b) >= exact.reach(b)));
            assert_eq!(
                held_visible(&ahead, &s, &v, base),
                held_visible(&exact, &s, &v, base),
                "step {t}"
            );
        }
        assert!(refills[1] * 2 < refills[0], "{refills:?}");
        assert!(ahead.len() > exact.len());
        let end = ahead.ranks().iter().copied().max().unwrap_or(0) + 1;
        assert_eq!(
            held_visible(&ahead, &s, &v, base),
            scan(&s, seed, end, &v, base)
        );
        // A superset of the exact pool's ranks.
        let held = check_held(&ahead, &s, 5);
        assert!(exact.ranks().iter().all(|k| held.binary_search(k).is_ok()));
    }

    /// Checks that each rank is held once, and that every `step`-th bin (split or not,
    /// children too) holds every rank below its reach that falls in it; the ranks
    /// held, sorted.
    pub(in crate::sample) fn check_held(pool: &LodPool, s: &Sampler, step: usize) -> Vec<u32> {
        let mut held = pool.ranks().to_vec();
        held.sort_unstable();
        held.dedup();
        assert_eq!(held.len(), pool.len(), "a rank held twice");
        let mut listed = Vec::new();
        for b in (0..pool.bins()).step_by(step) {
            let (segment, leaves) = pool.bin(b);
            listed.clear();
            let (seed, reach) = (pool.seed(), pool.reach(b));
            s.progressive_ranks_in_leaves(seed, segment, leaves, 0, reach, usize::MAX, &mut listed);
            assert!(
                listed.iter().all(|k| held.binary_search(k).is_ok()),
                "bin {b}"
            );
        }
        held
    }

    /// `mesh` with every vertex moved by `f` (the same triangles).
    pub(in crate::sample) fn moved(mesh: &TriMesh, f: impl Fn(&DVec3) -> DVec3) -> TriMesh {
        let positions = mesh.positions().iter().map(f).collect();
        TriMesh::new(positions, mesh.triangles().to_vec()).expect("mesh")
    }

    #[test]
    fn bounds_follow_a_deformed_mesh() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 1, 0, 0);
        // Stretched along z and bent: the bounds of the rest mesh no longer hold.
        let bent = moved(s.mesh(), |p| {
            DVec3::new(p.x, p.y + 0.5 * p.x * p.x, 3.0 * p.z)
        });
        pool.set_geometry(&s, &bent).expect("same topology");
        let v = view(DVec3::new(0.3, 0.8, 2.5), f64::INFINITY);
        let end = 20_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(1, 0, &mut sites);
        let mut checked = 0;
        for b in 0..pool.bins() {
            let (segment, leaves) = pool.bin(b);
            let mut ranks = Vec::new();
            s.progressive_ranks_in_leaves(1, segment, leaves, 0, end, usize::MAX, &mut ranks);
            for k in ranks {
                let site = sites[k as usize];
                let w = site.barycentric().map(f64::from);
                let [i, j, l] = bent.triangles()[site.face as usize].map(|x| x as usize);
                let p = bent.positions()[i] * w[0]
                    + bent.positions()[j] * w[1]
                    + bent.positions()[l] * w[2];
                let n = (bent.vertex_normals()[i] * w[0]
                    + bent.vertex_normals()[j] * w[1]
                    + bent.vertex_normals()[l] * w[2])
                    .normalize();
                let m = v.multiplier(p, n);
                assert!(m <= pool.bound(b, &v) * (1.0 + 1e-9), "rank {k}");
                checked += usize::from(m > 0.0);
            }
        }
        assert!(checked > 1000, "{checked}");
        let other =
            TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("triangle");
        let e = pool.set_geometry(&s, &other).expect_err("mismatch");
        assert!(
            e.to_string().contains("must keep the sampler's vertices"),
            "{e}"
        );
    }

    #[test]
    fn each_fill_draws_its_own_factor() {
        // A factor fixed per bin keeps bins filled in one frame in step: under needs
        // that all grow at one rate they come due together again and again.
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 9, 1_000, 100_000);
        let need = 1_000_000;
        let lo = f64::from(need) * (1.0 + pool.ahead);
        let hi = f64::from(need) * (1.0 + 2.0 * pool.ahead);
        let mut targets = Vec::new();
        for reach in [1_000, 1_031, 1_066, 1_100] {
            pool.reach[0] = reach;
            let t = pool.ahead_of(0, need);
            assert!(
                (lo..=hi).contains(&f64::from(t)),
                "{t} outside [{lo}, {hi}]"
            );
            assert!(pool.ahead_limit(need) >= t);
            targets.push(t);
        }
        targets.sort_unstable();
        targets.dedup();
        assert_eq!(targets.len(), 4, "one factor for every fill: {targets:?}");
    }

    #[test]
    fn the_pool_is_the_same_for_any_thread_count() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.5, 0.0, 1.6), 100.0);
        let run = || {
            let mut pool = LodPool::new(&s, 9, 10_000, 200_000);
            pool.update(&s, &v, 10_000.0);
            (pool.sites().to_vec(), pool.ranks().to_vec())
        };
        assert_eq!(crate::on_threads(1, run), crate::on_threads(2, run));
    }

    #[test]
    fn a_single_segment_sampler_enumerates_every_rank() {
        let mesh = Arc::new(crate::mesh::shapes::plane(1.0, 4).expect("plane"));
        let field = FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy: 2.0,
            density: 1.0,
        }
        .build(&mesh)
        .expect("field");
        let pre =
            Preprocessed::build(mesh, Arc::new(field), &SurfaceOptions::default()).expect("built");
        let s = pre.sampler;
        assert_eq!(s.segments().len(), 1);
        let mut all = Vec::new();
        s.progressive_ranks_in_segment(2, 0, 10, 300, usize::MAX, &mut all);
        assert_eq!(all, (10..300).collect::<Vec<_>>());
    }
}
