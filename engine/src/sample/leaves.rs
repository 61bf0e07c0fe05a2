//! The sampler's leaf search and boundary-leaf depth: the leaf holding a cumulative
//! measure, searched forward from the current leaf ([`advance`]), and the exact levels
//! of the descent through a boundary leaf for the samples it expects
//! ([`boundary_levels`]).
//!
//! Input: a segment curve's cumulative measures, or an expected sample count. Output: a
//! leaf index, or a level count. Cost: O(log d) for a jump of `d` leaves; O(1).

/// Exact levels of the descent through a boundary leaf expected to receive
/// `expected` samples: until a sub-cell expects at most one sample (log4 of the
/// expectation, none for a leaf that expects at most one). There a sample is placed
/// by area in the triangle piece of the sub-cell that its measure falls in
/// ([`SegmentCurve::point_in_leaf_with`](crate::curve::SegmentCurve::point_in_leaf_with)), which costs one pass over the pieces
/// instead of two polygon splits per piece and level. At 10^6 samples on the bunny,
/// boundary leaves expect about one sample each.
///
/// A leaf expecting at most one sample takes no level without calling `log2` (the
/// same 0 that `log2(1) = 0` gives), the usual case at high counts.
#[inline]
pub(super) fn boundary_levels(expected: f64) -> u32 {
    if expected <= 1.0 {
        return 0;
    }
    (expected.max(1.0).log2() * 0.5).ceil() as u32
}

/// The leaf holding cumulative measure `m`, searching forward from `leaf`: the first
/// leaf `l >= leaf` with `cum[l + 1] > m` (the last leaf if none). A few linear steps
/// first (consecutive samples are usually in the same or the next leaf), then a
/// galloping search (probes at doubling distances, then a binary search between the
/// last two), so that a jump of `d` leaves reads about `2 log2 d` entries near the
/// current leaf, not `log2` of the whole segment's entries spread over it: at small
/// counts, where consecutive samples are many leaves apart, each of those reads is a
/// cache miss.
#[inline]
pub(super) fn advance(cum: &[f64], mut leaf: usize, m: f64) -> usize {
    let last = cum.len() - 2;
    for _ in 0..8 {
        if leaf >= last || cum[leaf + 1] > m {
            return leaf.min(last);
        }
        leaf += 1;
    }
    // Every leaf before `lo` ends at or below `m`.
    let mut lo = leaf;
    let mut step = 8;
    let hi = loop {
        let probe = lo + step;
        if probe >= last || cum[probe + 1] > m {
            break probe.min(last);
        }
        lo = probe + 1;
        step *= 2;
    };
    // The answer is in `lo..=hi` (`hi` if no entry there exceeds `m`).
    let ends = &cum[lo + 1..=hi + 1];
    (lo + ends.partition_point(|&c| c <= m)).min(last)
}
