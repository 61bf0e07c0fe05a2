//! A pool's bins: runs of consecutive cells of one segment, each with a bound of a
//! view's multiplier, the rank it needs under that view, and the rank below which it
//! holds every rank that falls in it (its reach).
//!
//! The roots are about [`BINS`] runs of cells of equal measure (a bin never spans two
//! segments), and partition the surface. A bin that asks for many ranks under a close
//! view and whose bound is loose splits into finer children ([`split`](super::split)):
//! from then on they hold its ranks, until [`unsplit`](Bins::unsplit).
//!
//! Input: a [`Sampler`], a seed and a view. Output: per bin, its bound, need and reach,
//! read and raised by the pool's draws, and the lists of the bins that lack ranks and
//! of those that ask for a split. Cost: O(cells) to build; per update one pass over
//! the bins ([`Bins::survey`]: bounds, when the view moved, in a branch-free loop,
//! then needs and lists, chunk by chunk in parallel), then in proportion to the bins
//! listed.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::bounds::{BoundSet, Frustum, RegionBound, bin_bound};
use super::split::{SPLIT_ENTRIES, SPLIT_LOOSE, SPLIT_ROOM, SPLIT_WAYS, cuts};
use super::view::ViewLod;
use crate::sample::Sampler;
use crate::sample::progressive::RankCover;

/// The pool cuts the surface into about this many bins, each with its own bound of a
/// view's multiplier: finer bins bound more tightly (fewer ranks drawn that no view
/// shows) and cost more per update (one bound per bin).
pub const BINS: usize = 16384;

/// Bins bounded per task of an update.
const BOUND_CHUNK: usize = 2048;

/// The rank a bin needs under multiplier bound `bound` with base count `base`:
/// `(base * bound).ceil() as u32` (saturated at `u32::MAX`, 0 for NaN), without the
/// call to libm's `ceil` that the baseline x86-64 target makes for it: one call per
/// bin per update, 3% of the updates' instructions on the `lod_budget` bench.
#[inline]
fn need_of(base: f64, bound: f64) -> u32 {
    let x = base * bound;
    // `as` truncates towards zero and saturates; below zero `ceil` is at most 0 too.
    let t = x as u32;
    t.saturating_add(u32::from(f64::from(t) < x))
}

/// A run of consecutive cells of one segment's curve.
#[derive(Clone, Debug)]
struct Bin {
    /// Index into `Sampler::segments`.
    segment: u32,
    /// Leaves of the segment's curve.
    leaves: Range<u32>,
    /// The dyadic intervals over the bin's values.
    cover: RankCover,
}

/// The bins of a pool: see the module docs.
#[derive(Debug)]
pub(super) struct Bins {
    /// The roots, in segment order and cell order within a segment, then the children
    /// of split bins, in the order they were split.
    bins: Vec<Bin>,
    /// The number of roots: they partition the surface, and never change.
    roots: usize,
    /// Per bin, whether it is split (its children hold its ranks from then on).
    split: Vec<bool>,
    /// The split bins and their children, in the order they were split (a parent
    /// before its children's groups).
    groups: Vec<(u32, Range<u32>)>,
    /// The most bins split bins may make, the roots included (the roots alone: none
    /// splits).
    max_bins: usize,
    /// Per bin, its share of the total measure (of the sequence's values): a column
    /// of its own, read for every bin that lacks ranks before any of them is drawn.
    shares: Vec<f64>,
    /// Their bounds, as columns.
    bounds: BoundSet,
    /// Per bin: every rank below it that falls in the bin is held.
    reach: Vec<u32>,
    /// Per bin, the rank the view of the current update needs (0 for a split bin).
    needs: Vec<u32>,
    /// Per bin, the bound of the multiplier of the view `bounded` (kept, so that an
    /// update whose view has not moved, only its base count, skips the bounds).
    multipliers: Vec<f64>,
    /// The view `multipliers` bounds, if any.
    bounded: Option<ViewLod>,
    /// The bins' bounds on a new geometry (kept, so that a deforming mesh's
    /// [`set_geometry`](Self::set_geometry) stops allocating them).
    rebound: Vec<RegionBound>,
    /// The bins that lack ranks (need above reach), in order, as of the last
    /// [`survey`](Self::survey) and the splits after it.
    lacking: Vec<u32>,
    /// The bins whose need asks for a split ([`SPLIT_ENTRIES`] entries or more), in
    /// order, as of the last [`survey`](Self::survey).
    heavy: Vec<u32>,
    /// Per chunk of [`BOUND_CHUNK`] bins, what a survey listed there (kept, so that
    /// surveys stop allocating).
    listed: Vec<Listed>,
    /// Whether every survey and split scans all bins in separate passes, as a
    /// reference for the fused pass (tests only).
    #[cfg(test)]
    full_scans: bool,
}

/// The bins one chunk of a survey listed.
#[derive(Clone, Debug, Default)]
struct Listed {
    /// Those that lack ranks.
    lacking: Vec<u32>,
    /// Those whose need asks for a split.
    heavy: Vec<u32>,
}

impl Listed {
    /// Sets the needs `needs` of bins `first..` from their bounds `multipliers` under
    /// base count `base` (0 where `split`), and lists those whose need is above their
    /// `reach` and those whose need times their `share` asks for a split.
    fn survey(
        &mut self,
        first: usize,
        multipliers: &[f64],
        needs: &mut [u32],
        (split, reach, shares): (&[bool], &[u32], &[f64]),
        base: f64,
    ) {
        self.lacking.clear();
        self.heavy.clear();
        let n = multipliers.len();
        // Room for every bin of the chunk, so that listing never allocates once warm.
        self.lacking.reserve(n);
        self.heavy.reserve(n);
        let (split, reach, shares, needs) =
            (&split[..n], &reach[..n], &shares[..n], &mut needs[..n]);
        for i in 0..n {
            let need = if split[i] {
                0
            } else {
                need_of(base, multipliers[i])
            };
            needs[i] = need;
            let b = (first + i) as u32;
            if need > reach[i] {
                self.lacking.push(b);
            }
            if f64::from(need) * shares[i] >= SPLIT_ENTRIES {
                self.heavy.push(b);
            }
        }
    }
}

impl Clone for Bins {
    fn clone(&self) -> Self {
        Self {
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
            rebound: Vec::new(),
            lacking: self.lacking.clone(),
            heavy: self.heavy.clone(),
            listed: self.listed.clone(),
            #[cfg(test)]
            full_scans: self.full_scans,
        }
    }
}

impl Bins {
    /// The roots of `sampler`'s sequence for `seed`, bounded tightly on the sampler's
    /// mesh, each reaching `prefix`; splitting up to [`SPLIT_ROOM`] times the roots.
    pub(super) fn new(sampler: &Sampler, seed: u64, prefix: u32) -> Self {
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
            rebound: Vec::new(),
            lacking: Vec::new(),
            heavy: Vec::new(),
            listed: Vec::new(),
            #[cfg(test)]
            full_scans: false,
        }
    }

    /// Bounds every bin again on the vertex positions and normals `geometry` (a
    /// deformation of the sampler's mesh), with the quick bound of [`bin_bound`], and
    /// forgets the bounded view. Cost O(faces), in parallel.
    pub(super) fn set_geometry(&mut self, sampler: &Sampler, geometry: (&[DVec3], &[DVec3])) {
        // Into the kept list: a mesh deforming every frame calls this every frame.
        let mut bounds = std::mem::take(&mut self.rebound);
        self.bins
            .par_iter()
            .map_init(Default::default, |buffers, bin| {
                let leaves = bin.leaves.start as usize..bin.leaves.end as usize;
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
        for (i, bound) in bounds.iter().enumerate() {
            self.bounds.set(i, bound);
        }
        self.rebound = bounds;
        self.bounded = None;
    }

    /// The number of bins, the roots and their children.
    pub(super) fn len(&self) -> usize {
        self.bins.len()
    }

    /// The number of roots.
    pub(super) fn roots(&self) -> usize {
        self.roots
    }

    /// Bin `bin`'s segment and cells.
    pub(super) fn bin(&self, bin: usize) -> (usize, Range<usize>) {
        let b = &self.bins[bin];
        (
            b.segment as usize,
            b.leaves.start as usize..b.leaves.end as usize,
        )
    }

    /// Bin `bin`'s dyadic cover of its values.
    pub(super) fn cover(&self, bin: usize) -> &RankCover {
        &self.bins[bin].cover
    }

    /// Every bin's share of the total measure.
    pub(super) fn shares(&self) -> &[f64] {
        &self.shares
    }

    /// Bin `bin`'s reach.
    pub(super) fn reach(&self, bin: usize) -> u32 {
        self.reach[bin]
    }

    /// Sets bin `bin`'s reach: the pool drew its ranks up to `reach`.
    pub(super) fn set_reach(&mut self, bin: usize, reach: u32) {
        self.reach[bin] = reach;
    }

    /// The rank bin `bin` needs under the view and base count of the last
    /// [`survey`](Self::survey) (0 for a split bin).
    pub(super) fn need(&self, bin: usize) -> u32 {
        self.needs[bin]
    }

    /// The split bins and their children, in the order they were split (for tests of
    /// the splits).
    #[cfg(test)]
    pub(super) fn groups(&self) -> &[(u32, Range<u32>)] {
        &self.groups
    }

    /// Bin `bin`'s bound under the bounded view (for tests of the splits).
    #[cfg(test)]
    pub(super) fn bounded_multiplier(&self, bin: usize) -> f64 {
        self.multipliers[bin]
    }

    /// An upper bound of `view`'s multiplier over bin `bin`.
    pub(super) fn bound(&self, bin: usize, view: &ViewLod) -> f64 {
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

    /// Lowers each split bin's children's bounds in `out` to their parent's, parents
    /// first (both bound a child: it lies inside its parent).
    fn bound_by_parents(&self, out: &mut [f64]) {
        for (parent, children) in &self.groups {
            let bound = out[*parent as usize];
            for m in &mut out[children.start as usize..children.end as usize] {
                *m = m.min(bound);
            }
        }
    }

    /// Bounds every bin's multiplier under `view`, unless the bins hold its bounds
    /// already.
    pub(super) fn bound_view(&mut self, view: &ViewLod) {
        if self.bounded.as_ref() != Some(view) {
            let mut multipliers = std::mem::take(&mut self.multipliers);
            self.bound_bins(view, &mut multipliers);
            self.multipliers = multipliers;
            self.bounded = Some(*view);
        }
    }

    /// Writes into `out` the roots whose bound under the bounded view is above 0 (every
    /// root where a multiplier may be): what the point budget's refinement draws in.
    pub(super) fn live_roots_into(&self, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.multipliers[..self.roots]
                .iter()
                .enumerate()
                .filter(|&(_, &m)| m > 0.0)
                .map(|(b, _)| b as u32),
        );
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

    /// Bounds every bin under `view` (unless the bins hold its bounds already), sets
    /// each bin's need under base count `base`, and lists the bins that lack ranks
    /// ([`lacking`](Self::lacking)) and those whose need asks for a split: one pass
    /// over the bins, in parallel chunks (the roots' needs and lists in the same task
    /// as their bounds; split bins' children after their parents' bounds).
    pub(super) fn survey(&mut self, view: &ViewLod, base: f64) {
        #[cfg(test)]
        if self.full_scans {
            self.bound_view(view);
            self.rescan(base);
            return;
        }
        let rebound = self.bounded.as_ref() != Some(view);
        let frustum = Frustum::new(view);
        let (n, roots) = (self.bins.len(), self.roots);
        self.multipliers.resize(n, 0.0);
        self.needs.resize(n, 0);
        let chunks = n.div_ceil(BOUND_CHUNK);
        let children = (n - roots).div_ceil(BOUND_CHUNK);
        let mut listed = std::mem::take(&mut self.listed);
        if listed.len() < chunks + children {
            listed.resize_with(chunks + children, Default::default);
        }
        let (root_lists, child_lists) = listed.split_at_mut(chunks);
        let columns = (&self.split[..], &self.reach[..], &self.shares[..]);
        let bounds = &self.bounds;
        (self.multipliers.par_chunks_mut(BOUND_CHUNK))
            .zip(self.needs.par_chunks_mut(BOUND_CHUNK))
            .zip(root_lists.par_iter_mut())
            .enumerate()
            .for_each(|(c, ((multipliers, needs), list))| {
                let first = c * BOUND_CHUNK;
                if rebound {
                    bounds.multipliers_into(&frustum, first, multipliers);
                }
                let own = roots.saturating_sub(first).min(multipliers.len());
                let columns = (
                    &columns.0[first..],
                    &columns.1[first..],
                    &columns.2[first..],
                );
                list.survey(first, &multipliers[..own], needs, columns, base);
            });
        if rebound {
            let mut multipliers = std::mem::take(&mut self.multipliers);
            self.bound_by_parents(&mut multipliers);
            self.multipliers = multipliers;
            self.bounded = Some(*view);
        }
        // The children, now that their parents' bounds are final.
        (self.multipliers[roots..].par_chunks(BOUND_CHUNK))
            .zip(self.needs[roots..].par_chunks_mut(BOUND_CHUNK))
            .zip(child_lists[..children].par_iter_mut())
            .enumerate()
            .for_each(|(c, ((multipliers, needs), list))| {
                let first = roots + c * BOUND_CHUNK;
                let columns = (
                    &columns.0[first..],
                    &columns.1[first..],
                    &columns.2[first..],
                );
                list.survey(first, multipliers, needs, columns, base);
            });
        self.lacking.clear();
        self.heavy.clear();
        for list in root_lists.iter().chain(&child_lists[..children]) {
            self.lacking.extend_from_slice(&list.lacking);
            self.heavy.extend_from_slice(&list.heavy);
        }
        self.listed = listed;
    }

    /// The bins that lack ranks under the last [`survey`](Self::survey) and the
    /// splits after it, in order.
    pub(super) fn lacking(&self) -> &[u32] {
        &self.lacking
    }

    /// Makes every survey and split scan all bins in separate passes (bounds, needs,
    /// the bins that lack ranks, those that ask for a split), as the reference the
    /// fused pass is checked against.
    #[cfg(test)]
    pub(super) fn set_full_scans(&mut self, full: bool) {
        self.full_scans = full;
    }

    /// The reference's needs and lists: each in its own pass over all bins.
    #[cfg(test)]
    fn rescan(&mut self, base: f64) {
        let mut needs = std::mem::take(&mut self.needs);
        self.needs_from(&self.multipliers, base, &mut needs);
        self.needs = needs;
        self.lacking = (0..self.bins.len())
            .filter(|&b| self.needs[b] > self.reach[b])
            .map(|b| b as u32)
            .collect();
        self.heavy = (0..self.bins.len())
            .filter(|&b| f64::from(self.needs[b]) * self.shares[b] >= SPLIT_ENTRIES)
            .map(|b| b as u32)
            .collect();
    }

    /// Whether every bin reaches its need under `view` with base count `base`
    /// (computed afresh: the bounded view and needs are left as they are).
    pub(super) fn complete(&self, view: &ViewLod, base: f64) -> bool {
        let (mut multipliers, mut needs) = (Vec::new(), Vec::new());
        self.bound_bins(view, &mut multipliers);
        self.needs_from(&multipliers, base, &mut needs);
        needs
            .iter()
            .zip(&self.reach)
            .all(|(need, reach)| reach >= need)
    }

    /// Whether some bin that is not split reaches past both `prefix` and `limit` of its
    /// need: it holds ranks the current view does not need.
    pub(super) fn holds_past(&self, prefix: u32, limit: impl Fn(u32) -> u32) -> bool {
        (0..self.reach.len())
            .any(|b| !self.split[b] && self.reach[b] > prefix.max(limit(self.needs[b])))
    }

    /// Drops every split and sets every root's reach to `prefix`: the bins as they were
    /// made.
    pub(super) fn reset(&mut self, prefix: u32) {
        self.unsplit();
        self.reach.fill(prefix);
    }

    /// Sets the most bins splits may make, the roots included.
    pub(super) fn set_max_bins(&mut self, max_bins: usize) {
        self.max_bins = max_bins;
    }

    /// The most bins splits may make, the roots included.
    pub(super) fn max_bins(&self) -> usize {
        self.max_bins
    }

    /// Whether a bin, whose need asks for many ranks, splits under `view`.
    fn splits(&self, b: usize, view: &ViewLod) -> bool {
        !self.split[b] && self.bins[b].leaves.len() >= 2 && {
            let (centre, axis) = self.bounds.centre_axis(b);
            view.multiplier(centre, axis) * SPLIT_LOOSE <= self.multipliers[b]
        }
    }

    /// Splits the bins whose needs (of the bounded view, base count `base`) ask for
    /// many ranks, and their children that do, while there is room
    /// ([`split`](super::split)). The children are bounded on the vertex positions and
    /// normals `geometry`, tightly when `tight` (the sampler's mesh; quickly on a
    /// deformation, as [`set_geometry`](Self::set_geometry) bounds the other bins), in
    /// parallel, and their covers are of `seed`'s sequence.
    pub(super) fn split_for(
        &mut self,
        sampler: &Sampler,
        seed: u64,
        base: f64,
        (geometry, tight): ((&[DVec3], &[DVec3]), bool),
    ) {
        let Some(view) = self.bounded.filter(|_| self.max_bins > self.roots) else {
            return;
        };
        let first_child = self.bins.len();
        let mut from = None;
        loop {
            // Splits that fit however many children they make.
            let room = self.max_bins.saturating_sub(self.bins.len()) / SPLIT_WAYS;
            // The bins that ask for many ranks: listed by the survey, then among the
            // children of the last round. Most bins are far from it, and a bin's
            // record is a few cache lines.
            let wanted = match from {
                None => self.wanted(self.heavy.iter().map(|&b| b as usize), room, &view),
                Some(from) => {
                    let heavy = (self.needs[from..].iter())
                        .zip(&self.shares[from..])
                        .enumerate()
                        .filter(|(_, (need, share))| f64::from(**need) * **share >= SPLIT_ENTRIES)
                        .map(|(i, _)| from + i);
                    self.wanted(heavy, room, &view)
                }
            };
            if wanted.is_empty() {
                break;
            }
            from = Some(self.bins.len());
            let made = self.children(sampler, seed, &wanted, (geometry, tight));
            let frustum = Frustum::new(&view);
            for (&parent, children) in wanted.iter().zip(made) {
                self.adopt(parent, children, &frustum, base);
            }
        }
        if self.bins.len() > first_child {
            // Split bins need nothing now; their children may lack ranks.
            let (needs, reach) = (&self.needs, &self.reach);
            self.lacking
                .retain(|&b| needs[b as usize] > reach[b as usize]);
            let lacking = (first_child..self.bins.len()).filter(|&b| needs[b] > reach[b]);
            self.lacking.extend(lacking.map(|b| b as u32));
        }
        #[cfg(test)]
        if self.full_scans {
            self.rescan(base);
        }
    }

    /// The first `room` bins of `heavy` that split under `view`.
    fn wanted(
        &self,
        heavy: impl Iterator<Item = usize>,
        room: usize,
        view: &ViewLod,
    ) -> Vec<usize> {
        heavy.filter(|&b| self.splits(b, view)).take(room).collect()
    }

    /// The children of each bin of `wanted`: their bins, shares and bounds.
    fn children(
        &self,
        sampler: &Sampler,
        seed: u64,
        wanted: &[usize],
        (geometry, tight): ((&[DVec3], &[DVec3]), bool),
    ) -> Vec<Vec<(Bin, f64, RegionBound)>> {
        let bins = &self.bins;
        wanted
            .par_iter()
            .map_init(Default::default, |buffers, &b| {
                let (segment, leaves) = (bins[b].segment as usize, &bins[b].leaves);
                let cumulative = sampler.segments()[segment].curve.cumulative();
                let leaves = leaves.start as usize..leaves.end as usize;
                cuts(cumulative, leaves, SPLIT_WAYS)
                    .into_iter()
                    .map(|run| {
                        let bound =
                            bin_bound(sampler, geometry, segment, run.clone(), tight, buffers);
                        let share =
                            (cumulative[run.end] - cumulative[run.start]) / sampler.total_measure();
                        let cover = sampler.progressive_cover(seed, segment, run.clone());
                        let bin = Bin {
                            segment: segment as u32,
                            leaves: run.start as u32..run.end as u32,
                            cover,
                        };
                        (bin, share, bound)
                    })
                    .collect()
            })
            .collect()
    }

    /// Appends `children` as the children of bin `parent`, splits it, and bounds them
    /// under the bounded view (`frustum`) and base count `base`.
    fn adopt(
        &mut self,
        parent: usize,
        children: Vec<(Bin, f64, RegionBound)>,
        frustum: &Frustum,
        base: f64,
    ) {
        let first = self.bins.len();
        for (bin, share, bound) in children {
            self.bins.push(bin);
            self.shares.push(share);
            self.bounds.push(&bound);
            self.reach.push(self.reach[parent]);
            self.split.push(false);
        }
        let group = first as u32..self.bins.len() as u32;
        self.groups.push((parent as u32, group.clone()));
        self.split[parent] = true;
        self.needs[parent] = 0;
        // The children's bounds and needs under the bounded view.
        let bound = self.multipliers[parent];
        self.multipliers.resize(self.bins.len(), 0.0);
        let dst = &mut self.multipliers[first..];
        if bound > 0.0 {
            self.bounds.multipliers_into(frustum, first, dst);
            dst.iter_mut().for_each(|m| *m = m.min(bound));
        }
        let needs = self.multipliers[first..].iter().map(|&m| need_of(base, m));
        self.needs.extend(needs);
        debug_assert_eq!(group.end as usize, self.needs.len());
    }

    /// Drops every split: the roots alone, as the bins were made (their reaches kept).
    fn unsplit(&mut self) {
        let roots = self.roots;
        self.bins.truncate(roots);
        self.shares.truncate(roots);
        self.bounds.truncate(roots);
        self.reach.truncate(roots);
        self.needs.truncate(roots);
        self.multipliers.truncate(roots);
        self.split.clear();
        self.split.resize(roots, false);
        self.groups.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
