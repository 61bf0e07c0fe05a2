//! Finer bins where a view asks for many ranks: the rule, its constants, and the cut
//! of a bin's cells into children.
//!
//! A pool's bins ([`LodPool`](super::LodPool)) are about 16,384 runs of cells of equal measure, each
//! with one bound of a view's multiplier. Close to the surface a bin is wider than the
//! view's distance to it, and its bound (the multiplier at its nearest point) lies far
//! above the multiplier over most of it: 0.012 bounding radii above the bunny the pool
//! held 9.5 times the ranks the view showed, and drawing them was most of a close
//! frame's update.
//!
//! A bin whose need asks for many ranks (`need x share` at least [`SPLIT_ENTRIES`]) and
//! whose bound is loose (at least [`SPLIT_LOOSE`] times the multiplier at its centre)
//! is therefore split into [`SPLIT_WAYS`] children: runs of its cells of about equal
//! measure, each with its own tight bound (the lesser of its own and its parent's:
//! both bound it), its own rank cover, and the parent's reach. From then on the
//! children hold the parent's ranks and the parent needs none; a child can split
//! again. A split is kept until the pool is rebuilt (merging children that reach
//! different ranks would list some ranks twice), and the bins stop splitting at
//! [`SPLIT_ROOM`] times the roots (or the limit
//! [`with_max_bins`](super::LodPool::with_max_bins) sets), so that the bounds of an update
//! stay within a few times their cost.
//!
//! Splits change which ranks the pool holds, never which are visible: the roots still
//! partition the surface (the point budget's refinement enumerates ranks in them), and
//! every bin still holds every rank below its reach. Which bins split depends on the
//! views and base counts of the updates only, in order, never on the thread count.
//!
//! Input: a curve's cumulative measure and a run of its leaves. Output: the runs of
//! the children. Cost: O(ways log leaves). The bins that split, and their bounds, are
//! the bins' own ([`Bins::split_for`](super::bins::Bins::split_for)).

use std::ops::Range;

/// A bin splits when its need asks for at least this many ranks in it (its need times
/// its share of the measure).
pub const SPLIT_ENTRIES: f64 = 1024.0;

/// A bin splits when its bound is at least this many times the multiplier at its
/// sphere's centre with its cone's axis for normal: a bin wide next to its distance
/// to the eye, cut by the frustum or turning away from the eye. Tighter bins are
/// left whole: with the whole bunny in view at 10^6 samples, splitting every bin that
/// asked for 256 ranks, tight or not, saved 3% of the entries and doubled the update,
/// whose bounds it quadrupled.
pub const SPLIT_LOOSE: f64 = 2.0;

/// The children of a split: runs of the parent's cells of about equal measure (fewer
/// when it has fewer cells).
pub const SPLIT_WAYS: usize = 8;

/// By default the bins stop splitting at this many times the roots
/// ([`LodPool::with_max_bins`](super::LodPool::with_max_bins)).
pub const SPLIT_ROOM: usize = 4;

/// The cuts of `leaves` into at most `ways` non-empty runs of about equal measure, by
/// the curve's cumulative measure `cumulative` (`cumulative[i]` before leaf `i`).
pub(super) fn cuts(cumulative: &[f64], leaves: Range<usize>, ways: usize) -> Vec<Range<usize>> {
    let ways = ways.min(leaves.len());
    let (lo, hi) = (cumulative[leaves.start], cumulative[leaves.end]);
    let mut runs = Vec::with_capacity(ways);
    let mut start = leaves.start;
    for j in 1..ways {
        let at = lo + (hi - lo) * j as f64 / ways as f64;
        // The first leaf boundary at or past `at`, or the one before it if nearer,
        // leaving a leaf for each run to come.
        let mut end = start + cumulative[start..leaves.end].partition_point(|&c| c < at);
        if end > start + 1 && at - cumulative[end - 1] < cumulative[end] - at {
            end -= 1;
        }
        let end = end.clamp(start + 1, leaves.end - (ways - j));
        runs.push(start..end);
        start = end;
    }
    runs.push(start..leaves.end);
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuts_are_runs_of_about_equal_measure() {
        // Leaves of measure 1, 1, 1, 5, 1, 1, 1, 1, 1, 1 (cumulative from 0).
        let measure = [1.0, 1.0, 1.0, 5.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let cumulative: Vec<f64> = std::iter::once(0.0)
            .chain(measure.iter().scan(0.0, |c, m| {
                *c += m;
                Some(*c)
            }))
            .collect();
        let runs = cuts(&cumulative, 0..10, 4);
        assert_eq!(runs, vec![0..3, 3..4, 4..7, 7..10]);
        // Within a range, and never an empty run: three leaves give three runs.
        assert_eq!(cuts(&cumulative, 2..5, 8), vec![2..3, 3..4, 4..5]);
        assert_eq!(cuts(&cumulative, 4..10, 2), vec![4..7, 7..10]);
        assert_eq!(cuts(&cumulative, 5..6, 8), vec![5..6]);
    }
}
