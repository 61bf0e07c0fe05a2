//! A pool's entries: the sites and ranks it holds, a prefix of the sequence then the
//! ranks drawn per bin, and the draws that append them.
//!
//! Input: the [`Bins`] with their needs for the current view. Output: the missing
//! ranks of every bin (with draw-ahead), appended with their sites (with
//! [`Placement::Cpu`]; ranks alone with [`Placement::Elsewhere`]), and each bin's
//! reach raised. Cost: in proportion to the bins plus the ranks drawn (and placed);
//! no allocation while the extension stays within its budget.

use std::ops::Range;

use rayon::prelude::*;

use super::bins::Bins;
use crate::curve::LeafScratch;
use crate::sample::{SampleSite, Sampler};

/// The default draw-ahead fraction `a` (see [`LodPool`](super::LodPool)'s docs): a
/// bin that lacks ranks is filled to between `1 + a` and `1 + 2a` times its need. On
/// the `lod` bench, with the camera moving before the timed frames, 1/8 draws a growing
/// count 12% faster than 1/32 and orbits 10% faster, for 2-4% more entries held
/// (bench/README.md).
pub const DRAW_AHEAD: f64 = 1.0 / 8.0;

/// Bins drawn in per task of a parallel update.
const DRAW_CHUNK: usize = 16;

/// Ranks a bin may list beyond its share of a rank range (an estimate's slack: the
/// cover's end intervals).
const COVER_SLACK: f64 = 24.0;

/// Where a [`LodPool`](super::LodPool)'s entries are placed on the surface.
///
/// Which ranks a pool holds, in which order, and everything decided from ranks and
/// the bins' bounds (needs, reaches, splits, draw-ahead, the budget, rebuilds, the
/// point budget's estimate) are the same under both: only whether the pool computes
/// its entries' sites differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Placement {
    /// The pool places every entry it lists on the CPU
    /// ([`LodPool::sites`](super::LodPool::sites) holds one site per entry).
    #[default]
    Cpu,
    /// The pool lists ranks only and never places them
    /// ([`LodPool::sites`](super::LodPool::sites) is empty): whoever draws the samples
    /// places them from the ranks and the seed, as a GPU's progressive pass does. A
    /// frame's CPU cost is the bins' bookkeeping and the ranks' enumeration.
    Elsewhere,
}

/// What an update of a [`LodPool`](super::LodPool) changed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PoolChange {
    /// Nothing: the pool already held every rank the view needs (or the budget is
    /// spent on ranks the view still needs).
    Unchanged,
    /// Entries in this range were appended; the entries before it are as they were.
    Appended(Range<usize>),
    /// The extension was rebuilt: entries from
    /// [`LodPool::prefix`](super::LodPool::prefix) on changed.
    Rebuilt,
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

/// The entries of a pool: see the module docs.
#[derive(Debug)]
pub(super) struct Entries {
    seed: u64,
    prefix: u32,
    budget: usize,
    /// The draw-ahead fraction.
    ahead: f64,
    /// Whether the entries are placed here.
    placement: Placement,
    /// One site per entry with [`Placement::Cpu`]; empty with [`Placement::Elsewhere`].
    sites: Vec<SampleSite>,
    ranks: Vec<u32>,
    /// The bins a parallel update draws in, in order.
    todo: Vec<u32>,
    /// The ranks listed by a sequential update, as runs of one bin: (bin, end entry).
    runs: Vec<(u32, u32)>,
    /// Per chunk of [`DRAW_CHUNK`] bins drawn in, the lists of a parallel update
    /// (kept, so that updates stop allocating).
    lists: Vec<BinList>,
}

/// A clone keeps the original's room for more entries, its memory committed.
impl Clone for Entries {
    fn clone(&self) -> Self {
        Self {
            seed: self.seed,
            prefix: self.prefix,
            budget: self.budget,
            ahead: self.ahead,
            placement: self.placement,
            sites: with_room(&self.sites, self.sites.capacity()),
            ranks: with_room(&self.ranks, self.ranks.capacity()),
            todo: self.todo.clone(),
            runs: self.runs.clone(),
            lists: self.lists.clone(),
        }
    }
}

impl Entries {
    /// Ranks `0..prefix` of `sampler`'s sequence for `seed`, with room for `budget`
    /// more (`min(budget, prefix)` of it reserved and committed up front), drawing
    /// ahead by [`DRAW_AHEAD`], their sites placed by `placement`.
    pub(super) fn new(
        sampler: &Sampler,
        seed: u64,
        (prefix, budget): (u32, usize),
        placement: Placement,
    ) -> Self {
        let capacity = prefix as usize + budget.min(prefix as usize);
        let sites = match placement {
            Placement::Cpu => {
                let mut sites = with_room(&[], capacity);
                sites.resize(prefix as usize, SampleSite::default());
                sampler.progressive_sites_into(seed, 0, &mut sites);
                sites
            }
            Placement::Elsewhere => Vec::new(),
        };
        let mut ranks = with_room(&[], capacity);
        ranks.extend(0..prefix);
        Self {
            seed,
            prefix,
            budget,
            ahead: DRAW_AHEAD,
            placement,
            sites,
            ranks,
            todo: Vec::new(),
            runs: Vec::new(),
            lists: Vec::new(),
        }
    }

    /// Sets the draw-ahead fraction.
    pub(super) fn set_draw_ahead(&mut self, fraction: f64) {
        self.ahead = fraction;
    }

    /// The draw-ahead fraction.
    pub(super) fn draw_ahead(&self) -> f64 {
        self.ahead
    }

    /// Where the entries are placed.
    pub(super) fn placement(&self) -> Placement {
        self.placement
    }

    /// The seed of the sequence.
    pub(super) fn seed(&self) -> u64 {
        self.seed
    }

    /// Ranks `0..prefix` are the first entries.
    pub(super) fn prefix(&self) -> u32 {
        self.prefix
    }

    /// Every entry's site (none with [`Placement::Elsewhere`]).
    pub(super) fn sites(&self) -> &[SampleSite] {
        &self.sites
    }

    /// Every entry's rank.
    pub(super) fn ranks(&self) -> &[u32] {
        &self.ranks
    }

    /// Entries held.
    pub(super) fn len(&self) -> usize {
        self.ranks.len()
    }

    /// Drops every entry past the prefix and the runs listed.
    pub(super) fn truncate_to_prefix(&mut self) {
        self.sites
            .truncate(self.sites.len().min(self.prefix as usize));
        self.ranks.truncate(self.prefix as usize);
        self.runs.clear();
    }

    /// Starts a draw: no run listed yet.
    pub(super) fn begin(&mut self) {
        self.runs.clear();
    }

    /// The rank bin `bin` (of `bins`) is filled to when it needs `need`: past it by the
    /// draw-ahead, scaled by a factor in `[1, 2)` drawn per bin and per fill (a hash
    /// of the bin and its current reach). A factor fixed per bin would spread the
    /// refills' periods but not their phases: under a camera whose needs all grow at
    /// one rate, bins filled together in one frame come due together again, and
    /// the frames where several periods meet draw ten times the ranks of the others.
    pub(super) fn ahead_of(&self, bins: &Bins, bin: usize, need: u32) -> u32 {
        let key = (bin as u32) ^ bins.reach(bin).wrapping_mul(0x85eb_ca6b);
        let jitter = f64::from(key.wrapping_mul(0x9e37_79b9) >> 8) / 16_777_216.0;
        let more = f64::from(need) * self.ahead * (1.0 + jitter);
        (f64::from(need) + more).min(f64::from(u32::MAX)) as u32
    }

    /// The most any fill for `need` reaches: [`ahead_of`](Self::ahead_of) at its
    /// largest factor.
    pub(super) fn ahead_limit(&self, need: u32) -> u32 {
        let more = f64::from(need) * self.ahead * 2.0;
        (f64::from(need) + more).min(f64::from(u32::MAX)) as u32
    }

    /// Lists the missing ranks of every bin in order (with their sites when the
    /// parallel pass takes them, with [`finish`](Self::finish) to place them
    /// otherwise; never placed with [`Placement::Elsewhere`]), raising the bins' reach;
    /// false when the budget ran out first.
    pub(super) fn extend(&mut self, sampler: &Sampler, bins: &mut Bins) -> bool {
        if self.extend_parallel(sampler, bins) {
            return true;
        }
        // Within the budget only: every bin that lacks ranks up to its need, in order
        // (the parallel pass listed them).
        for &b in &self.todo {
            let b = b as usize;
            let need = bins.need(b);
            let listed = self.ranks.len();
            let room = self.budget - (listed - self.prefix as usize);
            let reach = sampler.progressive_ranks_in_cover(
                bins.cover(b),
                bins.reach(b),
                need,
                room,
                &mut self.ranks,
            );
            bins.set_reach(b, reach);
            if self.ranks.len() > listed {
                self.runs.push((b as u32, self.ranks.len() as u32));
            }
            if reach < need {
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
    fn extend_parallel(&mut self, sampler: &Sampler, bins: &mut Bins) -> bool {
        let room = self.budget - (self.ranks.len() - self.prefix as usize);
        self.todo.clear();
        self.todo.extend_from_slice(bins.lacking());
        let mut expected = 0.0;
        for &b in &self.todo {
            let b = b as usize;
            let target = self.ahead_of(bins, b, bins.need(b));
            expected += f64::from(target - bins.reach(b)) * bins.shares()[b] + COVER_SLACK;
        }
        if expected * 2.0 > room as f64 {
            return false;
        }
        let chunks = self.todo.len().div_ceil(DRAW_CHUNK);
        let mut lists = std::mem::take(&mut self.lists);
        if lists.len() < chunks {
            lists.resize_with(chunks, Default::default);
        }
        let (this, held) = (&*self, &*bins);
        let place = self.placement == Placement::Cpu;
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
                    let cover = held.cover(b);
                    let target = this.ahead_of(held, b, held.need(b));
                    list.reach.push(sampler.progressive_ranks_in_cover(
                        cover,
                        held.reach(b),
                        target,
                        usize::MAX,
                        &mut list.ranks,
                    ));
                    if !place {
                        continue;
                    }
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
                bins.set_reach(b as usize, reach);
            }
            self.ranks.extend_from_slice(&list.ranks);
            self.sites.extend_from_slice(&list.sites);
        }
        self.lists = lists;
        true
    }

    /// Places the ranks a sequential pass listed (the entries past the sites), in the
    /// cells of their bins (`bins`), unless they are placed elsewhere, and says what
    /// changed from entry `start` on.
    pub(super) fn finish(&mut self, sampler: &Sampler, bins: &Bins, start: usize) -> PoolChange {
        let (placed, end) = (self.sites.len(), self.ranks.len());
        if end == start {
            return PoolChange::Unchanged;
        }
        if self.placement == Placement::Elsewhere {
            return PoolChange::Appended(start..end);
        }
        self.sites.resize(end, SampleSite::default());
        let (runs, ranks) = (&self.runs, &self.ranks);
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
                        bins.cover(bin as usize),
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
}
