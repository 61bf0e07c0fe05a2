//! A progressive 1D sequence: an Owen-scrambled base-2 radical inverse, whose every
//! prefix is stratified, and the enumeration of its ranks inside a dyadic interval.
//!
//! Value `k` for a seed is `reverse_bits(P(k))` over 2^32 plus a jitter under 2^-32,
//! where `P` is a bijection of 32-bit words in which output bit `i` is input bit `i`
//! flipped by a function of the lower input bits only (a composition of adding a
//! constant, `x ^= x * even` and `x *= odd`, all with seed-derived constants). Read in
//! value order (bits reversed), digit `i` of the value is digit `i` of the radical
//! inverse flipped by a function of the more significant digits: Owen's nested
//! uniform scrambling (Owen 1995; the hash construction follows the idea of Laine and
//! Karras 2011 and Burley 2020, with its own constants). Hence:
//!
//! - **Stratified prefixes.** The top `m` bits of value `k` are a bijection of the low
//!   `m` bits of `k`, so ranks `0..2^m` put exactly one value in each interval
//!   `[j / 2^m, (j + 1) / 2^m)`, and any prefix of `N` ranks puts one or two values in
//!   each interval of length `2^-floor(log2 N)`.
//! - **Rank enumeration.** The ranks whose values fall in one such interval are
//!   `r, r + 2^m, r + 2 * 2^m, ...` for the one `r < 2^m` found digit by digit
//!   ([`Scramble::first_rank_in`]), so the next `k` samples of an interval cost O(k).
//!
//! Ranks are 32-bit: a sequence has 2^32 values.

use std::ops::Range;

use rayon::prelude::*;

use super::sampler::{CHUNK, Record, SegmentSampling};
use super::{Sample, SampleSite, Sampler};
use crate::curve::{DomainPoint, LeafScratch, SegmentCurve};
use crate::rng;

/// The seed-derived constants of one scramble.
#[derive(Clone, Copy, Debug)]
pub struct Scramble {
    add: u32,
    even: [u32; 2],
    odd: u32,
    /// Key of the jitter below the 32-bit resolution.
    jitter: u64,
}

impl Scramble {
    /// The scramble of `seed` (any 64-bit seed; different seeds give independent
    /// scrambles).
    pub fn new(seed: u64) -> Self {
        let word = |i: u64| rng::hash3(seed, 0x5052_4f47, i);
        Self {
            add: word(0) as u32,
            even: [(word(1) as u32) & !1, (word(2) as u32) & !1],
            odd: (word(3) as u32) | 1,
            jitter: rng::stream_key(seed, 0x4a49_5454),
        }
    }

    /// The bijection `P`: output bit `i` is input bit `i` flipped by a function of
    /// the input bits below `i`.
    #[inline]
    fn permute(&self, mut x: u32) -> u32 {
        x = x.wrapping_add(self.add);
        x ^= x.wrapping_mul(self.even[0]);
        x = x.wrapping_mul(self.odd);
        x ^= x.wrapping_mul(self.even[1]);
        x
    }

    /// The top 32 bits of value `rank`: `reverse_bits(P(rank))`.
    #[inline]
    pub fn bits(&self, rank: u32) -> u32 {
        self.permute(rank).reverse_bits()
    }

    /// Value `rank` of the sequence, in `[0, 1)`.
    #[inline]
    pub fn value(&self, rank: u32) -> f64 {
        let jitter = rng::unit_f64(rng::keyed_hash(self.jitter, u64::from(rank)));
        ((f64::from(self.bits(rank)) + jitter) / 4_294_967_296.0).min(1.0 - f64::EPSILON)
    }

    /// The lowest rank whose value lies in `[j / 2^m, (j + 1) / 2^m)`; the others are
    /// that rank plus multiples of `2^m`. O(m).
    ///
    /// # Panics
    /// If `m > 32` or `j >= 2^m`.
    pub fn first_rank_in(&self, m: u32, j: u32) -> u32 {
        assert!(m <= 32, "at most 32 levels, got {m}");
        assert!(
            m == 32 || j < (1u32 << m),
            "interval {j} out of range at level {m}"
        );
        if m == 0 {
            return 0;
        }
        // Low m bits of P(r) must be the m top value bits reversed.
        let target = j.reverse_bits() >> (32 - m);
        let mut r = 0u32;
        for i in 0..m {
            // P's bit i is r's bit i flipped by the bits below: with r's bit i at 0,
            // P(r)'s bit i is that flip.
            let flip = (self.permute(r) >> i) & 1;
            r |= (((target >> i) & 1) ^ flip) << i;
        }
        r
    }

    /// The ranks from `from` on (ascending, below 2^32) whose values lie in the
    /// dyadic interval `[j / 2^m, (j + 1) / 2^m)`.
    pub fn ranks_in(&self, m: u32, j: u32, from: u32) -> impl Iterator<Item = u32> {
        let first = u64::from(self.first_rank_in(m, j));
        let step = 1u64 << m;
        let start = if u64::from(from) <= first {
            first
        } else {
            first + (u64::from(from) - first).div_ceil(step) * step
        };
        (0..)
            .map(move |t| start + t * step)
            .take_while(|&r| r <= u64::from(u32::MAX))
            .map(|r| r as u32)
    }
}

/// Ranks a cover's placement groups by boundary leaf at a time
/// ([`Sampler::progressive_cover_sites_with`]): their keys fit on the stack (2 KiB),
/// so placing allocates nothing.
const WINDOW: usize = 256;

/// Levels of the continuous map inside a leaf for progressive samples: fixed, since a
/// sample's place may not depend on the count (4^12 sub-cells per leaf separate far
/// more samples than a leaf receives).
const PROGRESSIVE_LEVELS: u32 = 12;

/// Dyadic intervals in a [`RankCover`] at most.
const COVER: usize = 24;

/// The dyadic intervals covering a run of cells of one segment, for listing the
/// progressive ranks that fall there ([`Sampler::progressive_cover`]): a level `m`,
/// and the sorted residues modulo `2^m` of the ranks of each interval, marked where a
/// rank must be tested (the intervals at the run's ends).
#[derive(Clone, Debug)]
pub struct RankCover {
    scramble: Scramble,
    segment: u32,
    leaves: Range<u32>,
    whole: bool,
    level: u32,
    count: u32,
    offsets: [u32; COVER],
    /// Bit `i`: offset `i`'s interval reaches past the run's ends.
    checked: u32,
}

/// The progressive order of a [`Sampler`].
impl Sampler {
    /// Fills `out` with the progressive samples of ranks `first_rank..first_rank +
    /// out.len()` for `seed` (issue 19): sample `k` is value `k` of one
    /// [progressive sequence](self) over the curves of all segments
    /// concatenated in chain order, mapped through the cumulative measure to a leaf
    /// cell and along the continuous Hilbert curve to a point.
    ///
    /// A sample's place depends only on the seed and its rank, never on how many are
    /// drawn: the first `N` samples of any request are the samples of an `N`-sample
    /// request, bit for bit (only [`Sample::spacing`]'s scale, which follows the count
    /// `first_rank + out.len()`, differs). Every prefix of `2^m` ranks puts one sample
    /// in each `1/2^m` of the total measure along the curves; counts per segment come
    /// from the sequence, with nothing rounded per segment. [`sample_into`](Sampler::sample_into)
    /// places a fixed `N` more evenly (exactly stratified for every `N`), so use this
    /// where samples must persist as the count changes (level of detail), and that
    /// where one fixed count is drawn.
    ///
    /// # Panics
    /// If a rank reaches `2^32` (the sequence's length).
    pub fn progressive_into(&self, seed: u64, first_rank: u32, out: &mut [Sample]) {
        self.fill_progressive(seed, first_rank, out);
    }

    /// As [`progressive_into`](Self::progressive_into), writing only where each sample
    /// lies ([`SampleSite`]).
    ///
    /// # Panics
    /// As [`progressive_into`](Self::progressive_into).
    pub fn progressive_sites_into(&self, seed: u64, first_rank: u32, out: &mut [SampleSite]) {
        self.fill_progressive(seed, first_rank, out);
    }

    /// The records of progressive ranks `first_rank..first_rank + out.len()`.
    /// The sites of progressive ranks `ranks` (any ranks, in any order) for `seed`:
    /// `out[i]` is the site of rank `ranks[i]`, bit-identical to entry `ranks[i] - k`
    /// of a [`progressive_sites_into`](Self::progressive_sites_into) call starting at
    /// rank `k`. With [`progressive_ranks_in_segment`](Self::progressive_ranks_in_segment)
    /// it refines one region without drawing the rest. Panics when the two slices differ
    /// in length.
    pub fn progressive_sites_of(&self, seed: u64, ranks: &[u32], out: &mut [SampleSite]) {
        assert_eq!(ranks.len(), out.len(), "one site per rank");
        // Sites carry no spacing, so the count behind the scale does not matter.
        self.fill_ranks(seed, 1, |i| ranks[i], out);
    }

    fn fill_progressive<T: Record>(&self, seed: u64, first_rank: u32, out: &mut [T]) {
        let count = u64::from(first_rank) + out.len() as u64;
        assert!(
            count <= 1 << 32,
            "progressive ranks end at 2^32, asked up to {count}"
        );
        self.fill_ranks(seed, count, |i| first_rank + i as u32, out);
    }

    /// Writes the record of rank `rank_of(i)` into `out[i]`, with the spacings of a
    /// `count`-sample request, in parallel over fixed chunks: in two passes per chunk
    /// as [`Sampler::sample_into`] (the places, then the records in place), the second
    /// numbering a chunk's records from its first rank on, so a caller that writes full
    /// records gives consecutive ranks (sites carry no index).
    fn fill_ranks<T: Record>(
        &self,
        seed: u64,
        count: u64,
        rank_of: impl Fn(usize) -> u32 + Sync,
        out: &mut [T],
    ) {
        if out.is_empty() {
            return;
        }
        let scramble = Scramble::new(seed);
        let scale = (self.total_measure / count.max(1) as f64).sqrt();
        // One scratch per rayon task: the samples do not depend on what it holds.
        out.par_chunks_mut(CHUNK).enumerate().for_each_init(
            LeafScratch::default,
            |scratch, (chunk, dst)| {
                for (i, slot) in T::placed(dst).iter_mut().enumerate() {
                    let rank = rank_of(chunk * CHUNK + i);
                    let m = scramble.value(rank) * self.total_measure;
                    let (seg, p) = self.progressive_point(m, scratch);
                    *slot = Record::make(self, seg, &p, rank, scale);
                }
                T::finish(self, dst, u64::from(rank_of(chunk * CHUNK)), scale);
            },
        );
    }

    /// Appends to `out`, in increasing order, the progressive ranks in `from..to` whose
    /// samples lie in segment `segment` (an index into [`segments`](Self::segments)),
    /// and returns the rank below which every such rank is listed: `to`, or one past the
    /// last rank listed when `limit` ranks were listed first.
    ///
    /// Cost O(k + 1) for k ranks listed. The segment's share of the sequence is one
    /// interval of values; it is covered by at most 24 dyadic intervals of a level `m`
    /// at which it spans eight to sixteen of them, and the ranks of each are one residue
    /// modulo `2^m` ([`Scramble::first_rank_in`]), so every block of `2^m` consecutive
    /// ranks holds the same sorted offsets. Candidates in the cover's end intervals
    /// are kept only when their sample lies in the segment, by the very test the
    /// samplers use, so the list equals a filtered scan of the sequence. Panics when
    /// `segment` is out of range.
    pub fn progressive_ranks_in_segment(
        &self,
        seed: u64,
        segment: usize,
        from: u32,
        to: u32,
        limit: usize,
        out: &mut Vec<u32>,
    ) -> u32 {
        let leaves = self.segments[segment].curve.cell_count();
        self.progressive_ranks_in_leaves(seed, segment, 0..leaves, from, to, limit, out)
    }

    /// As [`progressive_ranks_in_segment`](Self::progressive_ranks_in_segment), for the
    /// samples in leaves `leaves` of the segment's curve (a run of consecutive cells,
    /// so one interval of values). Panics when `segment` or `leaves` is out of range.
    #[allow(clippy::too_many_arguments)]
    pub fn progressive_ranks_in_leaves(
        &self,
        seed: u64,
        segment: usize,
        leaves: Range<usize>,
        from: u32,
        to: u32,
        limit: usize,
        out: &mut Vec<u32>,
    ) -> u32 {
        let cover = self.progressive_cover(seed, segment, leaves);
        self.progressive_ranks_in_cover(&cover, from, to, limit, out)
    }

    /// The dyadic cover of leaves `leaves` of segment `segment`'s curve, for repeated
    /// [`progressive_ranks_in_cover`](Self::progressive_ranks_in_cover) calls (what
    /// [`progressive_ranks_in_leaves`](Self::progressive_ranks_in_leaves) computes per
    /// call: at most 24 digit-by-digit searches). Panics when `segment` or `leaves` is
    /// out of range.
    pub fn progressive_cover(&self, seed: u64, segment: usize, leaves: Range<usize>) -> RankCover {
        let chain = self.chain_slot[segment] as usize;
        let curve = &self.segments[segment].curve;
        assert!(
            leaves.start <= leaves.end && leaves.end <= curve.cell_count(),
            "leaves {leaves:?} of a curve of {} cells",
            curve.cell_count()
        );
        let scramble = Scramble::new(seed);
        let mut cover = RankCover {
            scramble,
            segment: segment as u32,
            leaves: leaves.start as u32..leaves.end as u32,
            whole: leaves.start == 0 && leaves.end == curve.cell_count(),
            level: 0,
            count: 0,
            offsets: [0; COVER],
            checked: 0,
        };
        let total = self.total_measure;
        let before = self.chain_cumulative[chain];
        let cells_measure = curve.cumulative();
        let (lo, hi) = (
            before + cells_measure[leaves.start],
            before + cells_measure[leaves.end],
        );
        let width = ((hi - lo) / total).max(0.0);
        if leaves.is_empty() || !(width > 0.0) {
            return cover;
        }
        // 2^-m in (width / 16, width / 8].
        let m = ((8.0 / width).log2().ceil().max(0.0) as u32).min(32);
        let cells = (1u64 << m) as f64;
        let last = (1u64 << m) - 1;
        // One interval more on each side: the membership test, not this rounding,
        // decides.
        let first_j = ((lo / total * cells).floor() as u64).saturating_sub(1);
        let last_j = (((hi / total * cells).ceil() as u64) + 1).min(last);
        let n = ((last_j - first_j + 1) as usize).min(COVER);
        debug_assert!(last_j - first_j < COVER as u64, "cover of {n} intervals");
        // Intervals whose values lie inside the run by far more than any rounding of
        // the measures need no test.
        let margin = 1e-9 * total;
        let mut entries = [(0u32, false); COVER];
        for (slot, j) in entries[..n].iter_mut().zip(first_j..) {
            let (start, end) = (j as f64 / cells * total, (j + 1) as f64 / cells * total);
            let inside = start >= lo + margin && end <= hi - margin;
            *slot = (scramble.first_rank_in(m, j as u32), !inside);
        }
        entries[..n].sort_unstable();
        for (i, &(offset, check)) in entries[..n].iter().enumerate() {
            cover.offsets[i] = offset;
            cover.checked |= u32::from(check) << i;
        }
        cover.level = m;
        cover.count = n as u32;
        cover
    }

    /// The ranks of [`progressive_ranks_in_leaves`](Self::progressive_ranks_in_leaves)
    /// for a cover made once: those in `from..to` in the cover's cells, appended in
    /// increasing order, at most `limit`; returns the rank below which all are listed.
    pub fn progressive_ranks_in_cover(
        &self,
        cover: &RankCover,
        from: u32,
        to: u32,
        limit: usize,
        out: &mut Vec<u32>,
    ) -> u32 {
        if from >= to || cover.count == 0 {
            return to;
        }
        let segment = cover.segment as usize;
        let chain = self.chain_slot[segment] as usize;
        let curve = &self.segments[segment].curve;
        let leaves = cover.leaves.start as usize..cover.leaves.end as usize;
        // Whether the samplers would put a value's sample in the cover's cells: the
        // same test as `chain_index` and `leaf_at`, without their searches (both count
        // the cumulative measures at or below the value, so comparing with the two
        // ends suffices).
        let last_chain = self.chains.order.len() - 1;
        let cum = &self.chain_cumulative;
        let cells = curve.cumulative();
        let last_leaf = curve.cell_count() - 1;
        let inside = |rank: u32| {
            let at = cover.scramble.value(rank) * self.total_measure;
            let in_chain =
                (chain == 0 || cum[chain] <= at) && (chain == last_chain || at < cum[chain + 1]);
            if !in_chain || cover.whole {
                return in_chain;
            }
            let ml = (at - cum[chain]).clamp(0.0, curve.measure() * (1.0 - f64::EPSILON));
            (leaves.start == 0 || cells[leaves.start] <= ml)
                && (leaves.end > last_leaf || ml < cells[leaves.end])
        };
        let m = cover.level;
        let offsets = &cover.offsets[..cover.count as usize];
        let (lo, hi) = (u64::from(from), u64::from(to));
        let mut listed = 0usize;
        for block in (lo >> m)..=((hi - 1) >> m) {
            for (i, &o) in offsets.iter().enumerate() {
                let r = (block << m) + u64::from(o);
                if r < lo {
                    continue;
                }
                if r >= hi {
                    break;
                }
                let rank = r as u32;
                if (cover.checked >> i) & 1 == 0 || inside(rank) {
                    if listed == limit {
                        return rank;
                    }
                    out.push(rank);
                    listed += 1;
                }
            }
        }
        to
    }

    /// The position in chain order of the segment holding measure `m` of the
    /// concatenated curves.
    #[inline]
    fn chain_index(&self, m: f64) -> usize {
        self.chain_cumulative[1..]
            .partition_point(|&c| c <= m)
            .min(self.chains.order.len() - 1)
    }

    #[inline]
    fn progressive_point<'a>(
        &'a self,
        m: f64,
        scratch: &mut LeafScratch<'a>,
    ) -> (&'a SegmentSampling, DomainPoint) {
        let k = self.chain_index(m);
        let seg = &self.segments[self.chains.order[k] as usize];
        let (leaf, t) = self.leaf_at(k, &seg.curve, m);
        let p = seg
            .curve
            .point_in_leaf_with(leaf, t, PROGRESSIVE_LEVELS, scratch);
        (seg, p)
    }

    /// The leaf of `curve` (the curve at chain position `k`) holding measure `m` of the
    /// concatenated curves, and the position in it as a fraction of its measure.
    #[inline]
    fn leaf_at(&self, k: usize, curve: &SegmentCurve, m: f64) -> (usize, f64) {
        self.leaf_among(k, curve, m, 0..curve.cell_count())
    }

    /// [`leaf_at`](Self::leaf_at) searching only `leaves`, which must hold the answer:
    /// then it is the same, bit for bit.
    #[inline]
    fn leaf_among(
        &self,
        k: usize,
        curve: &SegmentCurve,
        m: f64,
        leaves: Range<usize>,
    ) -> (usize, f64) {
        let cum = curve.cumulative();
        let ml = (m - self.chain_cumulative[k]).clamp(0.0, curve.measure() * (1.0 - f64::EPSILON));
        // Leaves before `leaves` end at or below ml, leaves after it above; the last
        // leaf takes what rounding leaves past the end.
        let ends = &cum[leaves.start + 1..leaves.end];
        // A bin's dozen cells: counting the ends at or below `ml` (the same number as
        // the binary search finds in sorted ends) has no branch to mispredict.
        let below = if ends.len() <= 32 {
            ends.iter().map(|&c| usize::from(c <= ml)).sum()
        } else {
            ends.partition_point(|&c| c <= ml)
        };
        let leaf = leaves.start + below;
        let (w0, w1) = (cum[leaf], cum[leaf + 1]);
        (leaf, if w1 > w0 { (ml - w0) / (w1 - w0) } else { 0.0 })
    }

    /// The sites of `ranks`, which must all fall in `cover`'s cells (as
    /// [`progressive_ranks_in_cover`](Self::progressive_ranks_in_cover) lists them):
    /// the same sites as [`progressive_sites_of`](Self::progressive_sites_of), bit for
    /// bit, found by searching the cover's cells only. Sequential: for callers that
    /// split work by cover. Panics when the slices differ in length.
    pub fn progressive_cover_sites_of(
        &self,
        cover: &RankCover,
        ranks: &[u32],
        out: &mut [SampleSite],
    ) {
        self.progressive_cover_sites_with(cover, ranks, out, &mut LeafScratch::default());
    }

    /// As [`progressive_cover_sites_of`](Self::progressive_cover_sites_of), with the
    /// scratch memory of the leaf descent given by the caller: a caller drawing a few
    /// ranks in each of many covers reuses one instead of initialising its kilobytes
    /// per cover (the sites do not depend on it, [`LeafScratch`]'s contract).
    ///
    /// Ranks in rank order scatter over the cover's cells. A rank in a boundary leaf
    /// (one the domain cuts) costs the clipping of the leaf's triangles unless the
    /// scratch holds that leaf from the rank before, so those ranks are placed after
    /// the others, grouped by leaf, per [`WINDOW`] ranks: a close frame on the
    /// `lod_budget` bench placed about 560 such ranks in 86 distinct leaves, and
    /// clipped 505 leaves in rank order.
    pub(crate) fn progressive_cover_sites_with<'a>(
        &'a self,
        cover: &RankCover,
        ranks: &[u32],
        out: &mut [SampleSite],
        scratch: &mut LeafScratch<'a>,
    ) {
        assert_eq!(ranks.len(), out.len(), "one site per rank");
        let seg = &self.segments[cover.segment as usize];
        let chain = self.chain_slot[cover.segment as usize] as usize;
        let leaves = cover.leaves.start as usize..cover.leaves.end as usize;
        let leaf_of = |rank: u32| {
            let m = cover.scramble.value(rank) * self.total_measure;
            self.leaf_among(chain, &seg.curve, m, leaves.clone())
        };
        let site = |rank: u32, (leaf, t): (usize, f64), scratch: &mut LeafScratch<'a>| {
            let p = seg
                .curve
                .point_in_leaf_with(leaf, t, PROGRESSIVE_LEVELS, scratch);
            SampleSite::make(self, seg, &p, rank, 1.0)
        };
        for (ranks, out) in ranks.chunks(WINDOW).zip(out.chunks_mut(WINDOW)) {
            // The ranks in boundary leaves other than the one the scratch holds, as
            // (leaf, index) keys, placed after the others grouped by leaf.
            let mut pending = [0u64; WINDOW];
            let mut n = 0;
            for (i, (slot, &rank)) in out.iter_mut().zip(ranks).enumerate() {
                let at = leaf_of(rank);
                if seg.curve.leaf_is_full(at.0) || scratch.holds(&seg.curve, at.0) {
                    *slot = site(rank, at, scratch);
                } else {
                    pending[n] = ((at.0 as u64) << 32) | i as u64;
                    n += 1;
                }
            }
            let pending = &mut pending[..n];
            pending.sort_unstable();
            for &key in pending.iter() {
                // The leaf found again: cheaper than keeping each rank's place in it.
                let i = (key & 0xffff_ffff) as usize;
                out[i] = site(ranks[i], leaf_of(ranks[i]), scratch);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_sites_equal_the_sequences_sites_bit_for_bit() {
        let s = crate::fixtures::torus_sampler();
        let seed = 9;
        let (mut checked, mut boundary) = (0, 0);
        for (segment, seg) in s.segments().iter().enumerate() {
            let curve = &seg.curve;
            let cells = curve.cell_count();
            // Runs of a dozen leaves (a pool's bins; every fifth), and the whole curve.
            let runs = (0..cells)
                .step_by(60)
                .map(|a| a..(a + 12).min(cells))
                .chain(std::iter::once(0..cells));
            for leaves in runs {
                let cover = s.progressive_cover(seed, segment, leaves.clone());
                let mut ranks = Vec::new();
                // Past a window of the grouping, by far.
                s.progressive_ranks_in_cover(&cover, 0, u32::MAX, 3 * WINDOW, &mut ranks);
                let mut expected = vec![SampleSite::default(); ranks.len()];
                s.progressive_sites_of(seed, &ranks, &mut expected);
                let mut sites = vec![SampleSite::default(); ranks.len()];
                s.progressive_cover_sites_of(&cover, &ranks, &mut sites);
                let bits = |v: &[SampleSite]| bytemuck::cast_slice::<_, u8>(v).to_vec();
                assert_eq!(
                    bits(&sites),
                    bits(&expected),
                    "segment {segment} {leaves:?}"
                );
                checked += ranks.len();
                // The ranks whose leaf is a boundary leaf: those the grouping reorders.
                boundary += ranks
                    .iter()
                    .filter(|&&k| {
                        let m = cover.scramble.value(k) * s.total_measure();
                        let k = s.chain_slot[segment] as usize;
                        !curve.leaf_is_full(s.leaf_at(k, curve, m).0)
                    })
                    .count();
            }
        }
        assert!(
            checked > 500_000 && boundary > 20_000,
            "{checked} {boundary}"
        );
    }

    #[test]
    fn permute_is_a_triangular_bijection() {
        let s = Scramble::new(11);
        // Bit i of P depends only on bits <= i: changing bit i of the input changes
        // bit i of the output and nothing below it.
        for x in [0u32, 1, 0xdead_beef, u32::MAX, 12345] {
            for i in 0..32 {
                let d = s.permute(x) ^ s.permute(x ^ (1 << i));
                assert_eq!(
                    d & ((1u32 << i) | ((1u32 << i) - 1)),
                    1 << i,
                    "x {x} bit {i}"
                );
            }
        }
        // A bijection on the low 12 bits (and so on all words).
        let mut seen = vec![false; 1 << 12];
        for x in 0..1u32 << 12 {
            let y = (s.permute(x) & 0xfff) as usize;
            assert!(!seen[y]);
            seen[y] = true;
        }
    }

    #[test]
    fn every_power_of_two_prefix_is_stratified() {
        for seed in [0, 1, 99] {
            let s = Scramble::new(seed);
            for m in 0..=14u32 {
                let n = 1u32 << m;
                let mut seen = vec![false; n as usize];
                for k in 0..n {
                    let v = s.value(k);
                    assert!((0.0..1.0).contains(&v));
                    let j = (v * f64::from(n)) as usize;
                    assert!(!seen[j], "seed {seed} m {m}: two values in interval {j}");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn any_prefix_puts_one_or_two_values_per_interval() {
        let s = Scramble::new(5);
        for n in [3u32, 100, 1000, 1500, 3000, 12_345] {
            let m = 31 - n.leading_zeros(); // floor(log2 n)
            let mut counts = vec![0u32; 1 << m];
            for k in 0..n {
                counts[(s.value(k) * f64::from(1u32 << m)) as usize] += 1;
            }
            assert!(counts.iter().all(|&c| c == 1 || c == 2), "n {n}");
        }
    }

    #[test]
    fn seeds_give_different_sequences() {
        let (a, b) = (Scramble::new(1), Scramble::new(2));
        let same = (0..1000).filter(|&k| a.bits(k) == b.bits(k)).count();
        assert!(same < 5, "{same}");
        assert_eq!(Scramble::new(1).value(77), a.value(77));
    }

    #[test]
    fn ranks_in_an_interval_equal_a_filtered_scan() {
        let s = Scramble::new(3);
        for (m, j) in [(0u32, 0u32), (1, 1), (4, 9), (7, 100), (10, 1023)] {
            let scan: Vec<u32> = (0..1u32 << 14)
                .filter(|&k| (s.value(k) * f64::from(1u32 << m)) as u32 == j)
                .collect();
            let listed: Vec<u32> = s.ranks_in(m, j, 0).take_while(|&k| k < 1 << 14).collect();
            assert_eq!(listed, scan, "m {m} j {j}");
            assert!(!scan.is_empty());
            // From a later rank: the same list, cut.
            let later: Vec<u32> = s
                .ranks_in(m, j, 5000)
                .take_while(|&k| k < 1 << 14)
                .collect();
            let cut: Vec<u32> = scan.into_iter().filter(|&k| k >= 5000).collect();
            assert_eq!(later, cut, "m {m} j {j} from 5000");
        }
    }

    #[test]
    fn ranks_stop_at_the_last_32_bit_rank() {
        let s = Scramble::new(8);
        // The last two ranks differ in their lowest bit, so one falls in each half.
        for j in 0..2 {
            let tail: Vec<u32> = s.ranks_in(1, j, u32::MAX - 1).collect();
            assert_eq!(tail.len(), 1, "half {j}");
            assert_eq!((s.value(tail[0]) * 2.0) as u32, j);
        }
        let tail: Vec<u32> = s.ranks_in(31, 0, u32::MAX - 10).collect();
        assert!(tail.len() <= 1);
        assert!(
            tail.iter()
                .all(|&r| (s.value(r) * 2f64.powi(31)) as u64 == 0)
        );
    }
}
