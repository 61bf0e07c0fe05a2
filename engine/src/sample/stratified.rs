//! 1D stratified values and the allocation of a sample count over segments.

use crate::rng;

/// Value `k` of `n` stratified values in `[0, 1)`: `(k + U) / n` with `U` uniform in
/// `[0, 1)` drawn from `(seed, stream, k)`: the evenly spaced value of stratum `k`
/// moved at random by up to half a stratum either way (section 6.2).
#[inline]
pub fn stratified_value(seed: u64, stream: u64, k: u64, n: u64) -> f64 {
    stratified_value_keyed(rng::stream_key(seed, stream), k, n)
}

/// [`stratified_value`] with the stream's part of the hash given
/// (`key = rng::stream_key(seed, stream)`, computed once per stream).
///
/// `k` and `n` are converted as signed integers: the same values for counts below
/// 2^63, in one instruction on x86-64 where an unsigned conversion takes about six.
#[inline]
pub(crate) fn stratified_value_keyed(key: u64, k: u64, n: u64) -> f64 {
    let u = rng::unit_f64(rng::keyed_hash(key, k));
    ((k as i64 as f64 + u) / n as i64 as f64).min(1.0 - f64::EPSILON)
}

/// Splits `n` samples over parts with the given measures: part `i` gets
/// `floor(n * share_i + carry)`, the carry being the remainder accumulated so far
/// (section 6.2); round-off that would leave the total short is given to the last part
/// with a positive measure. Calls `emit(i, count)` in order; the counts add up to `n`.
///
/// The counts are computed from cumulative shares, `floor(n P_i / T) - floor(n P_(i-1)
/// / T)` with `P_i` the measure of parts `0..=i` and `T` the total (the same numbers as
/// the carried remainder), a target within `1e-9 n` (at most `1e-3`) below an integer
/// counting as that integer: a share that is exact in theory (a part of half the
/// measure, `n` even) is often a few ulps short in floating point, and a plain `floor`
/// then took one sample from that part for every seed (a systematic deficit, not a
/// random remainder).
pub fn allocate(
    n: u64,
    measures: impl ExactSizeIterator<Item = f64> + Clone,
    mut emit: impl FnMut(usize, u64),
) {
    for (i, count) in Allocation::new(n, measures) {
        emit(i, count);
    }
}

/// [`allocate`] as an iterator of `(part, count)` in part order: what the sampler's
/// per-chunk loop walks (a plain loop, so that it is compiled with the caller's target
/// features rather than in a closure of its own).
#[derive(Clone, Debug)]
pub struct Allocation<I> {
    measures: std::iter::Enumerate<I>,
    n: u64,
    total: f64,
    last_positive: Option<usize>,
    slack: f64,
    prefix: f64,
    given: u64,
}

impl<I: ExactSizeIterator<Item = f64> + Clone> Allocation<I> {
    /// The allocation of `n` samples over parts with `measures`.
    pub fn new(n: u64, measures: I) -> Self {
        let total: f64 = measures.clone().sum();
        let last_positive = measures
            .clone()
            .enumerate()
            .filter(|(_, m)| *m > 0.0)
            .map(|(i, _)| i)
            .last();
        Self {
            measures: measures.enumerate(),
            n,
            total,
            last_positive,
            // Far above the round-off of the prefix sums, far below a sample.
            slack: (1e-9 * n as f64).min(1e-3),
            prefix: 0.0,
            given: 0,
        }
    }
}

impl<I: Iterator<Item = f64>> Iterator for Allocation<I> {
    type Item = (usize, u64);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, u64)> {
        let (i, m) = self.measures.next()?;
        self.prefix += m;
        let target = self.n as f64 * (self.prefix / self.total) + self.slack;
        let upto = (target.floor().max(0.0) as u64).min(self.n);
        let mut count = upto.saturating_sub(self.given);
        if Some(i) == self.last_positive {
            count = self.n - self.given;
        }
        self.given += count;
        Some((i, count))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_stay_in_their_strata() {
        for n in [1u64, 2, 7, 1000] {
            for k in 0..n {
                let v = stratified_value(9, 0, k, n);
                assert!(v >= k as f64 / n as f64 && v < (k + 1) as f64 / n as f64);
            }
        }
        assert_ne!(stratified_value(1, 0, 3, 10), stratified_value(2, 0, 3, 10));
    }

    /// Shares that are exact in theory get their exact count although the floating
    /// point share is a few ulps short (0.1 / (0.1 + 0.2) < 1/3).
    #[test]
    fn exact_shares_are_not_rounded_down() {
        for (measures, n, want) in [
            (vec![0.1, 0.2], 3u64, vec![1u64, 2]),
            (vec![0.1, 0.2], 300, vec![100, 200]),
            (vec![0.1, 0.2, 0.3], 6, vec![1, 2, 3]),
            (vec![0.7, 0.1, 0.2], 10, vec![7, 1, 2]),
        ] {
            let mut counts = vec![0u64; measures.len()];
            allocate(n, measures.iter().copied(), |i, c| counts[i] = c);
            assert_eq!(counts, want, "{measures:?}, n {n}");
        }
    }

    #[test]
    fn allocation_adds_up_and_follows_shares() {
        let measures = [0.1, 0.0, 2.5, 1.3, 0.7, 0.0];
        for n in [0u64, 1, 2, 3, 10, 997, 1_000_000] {
            let mut counts = vec![0u64; measures.len()];
            allocate(n, measures.iter().copied(), |i, c| counts[i] = c);
            assert_eq!(counts.iter().sum::<u64>(), n);
            assert_eq!(counts[1] + counts[5], 0, "empty parts get nothing");
            let total: f64 = measures.iter().sum();
            for (c, m) in counts.iter().zip(measures) {
                // Carried remainders keep every part within one sample of its share.
                assert!(
                    (*c as f64 - n as f64 * m / total).abs() <= 1.0 + 1e-9,
                    "n {n}: {counts:?}"
                );
            }
        }
    }
}
