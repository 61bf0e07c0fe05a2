//! Ratio of two measured curves over sample counts, with its error over the seeds:
//! how the boundary experiment of section 7.3.2 (Quinn et al., "Generalized Anisotropic
//! Stratified Surface Sampling") compares two samplings of the same domain.
//!
//! Input: per-seed measurements `a[seed][n]` and `b[seed][n]` (e.g. discrepancies at
//! each sample count `n`), with the same seeds and counts. Output: the geometric mean
//! over `n` of the ratio of the seed means, and its jackknife standard error (Efron and
//! Tibshirani, "An Introduction to the Bootstrap", 1993, chapter 11). Cost: O(S^2 N) for
//! `S` seeds and `N` counts.

/// Geometric mean over the counts `i` with `keep(i)` of `mean_s a[s][i] / mean_s
/// b[s][i]`, the means leaving out seed `skip` (`None`: all seeds).
///
/// Dimensionless (the units of `a` and `b` cancel). NaN if no count is kept or no seed
/// is left; `a` and `b` must have the same shape, with at least one seed.
///
/// # Example
/// ```
/// use strata_engine::analysis::seed_ratio::geometric_mean_ratio;
/// let a = [vec![2.0, 8.0]];
/// let b = [vec![1.0, 1.0]];
/// assert!((geometric_mean_ratio(&a, &b, |_| true, None) - 4.0).abs() < 1e-12);
/// ```
pub fn geometric_mean_ratio(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    keep: impl Fn(usize) -> bool,
    skip: Option<usize>,
) -> f64 {
    let ns = a[0].len();
    let mean = |x: &[Vec<f64>], i: usize| {
        let v: Vec<f64> = (0..x.len())
            .filter(|&s| Some(s) != skip)
            .map(|s| x[s][i])
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let logs: Vec<f64> = (0..ns)
        .filter(|&i| keep(i))
        .map(|i| (mean(a, i) / mean(b, i)).ln())
        .collect();
    (logs.iter().sum::<f64>() / logs.len() as f64).exp()
}

/// [`geometric_mean_ratio`] over all seeds and its jackknife standard error over the
/// seeds: `sqrt((S - 1) / S sum_s (r_s - mean r)^2)`, `r_s` the ratio leaving out seed
/// `s`. Returns `(ratio, standard_error)`; the error is NaN with a single seed.
///
/// # Example
/// ```
/// use strata_engine::analysis::seed_ratio::jackknife_ratio;
/// // Two seeds, one count: ratio 2; leaving out a seed gives 3 or 1, so the error is 1.
/// let (r, se) = jackknife_ratio(&[vec![1.0], vec![3.0]], &[vec![1.0], vec![1.0]], |_| true);
/// assert!((r - 2.0).abs() < 1e-12 && (se - 1.0).abs() < 1e-12);
/// ```
pub fn jackknife_ratio(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    keep: impl Fn(usize) -> bool + Copy,
) -> (f64, f64) {
    let r = geometric_mean_ratio(a, b, keep, None);
    let m = a.len();
    let jack: Vec<f64> = (0..m)
        .map(|s| geometric_mean_ratio(a, b, keep, Some(s)))
        .collect();
    let mj = jack.iter().sum::<f64>() / m as f64;
    let var = (m as f64 - 1.0) / m as f64 * jack.iter().map(|x| (x - mj).powi(2)).sum::<f64>();
    (r, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn constant_ratio_has_no_error() {
        let b = vec![
            vec![1.0, 2.0, 4.0],
            vec![3.0, 1.0, 5.0],
            vec![2.0, 2.0, 2.0],
        ];
        let a: Vec<Vec<f64>> = b
            .iter()
            .map(|s| s.iter().map(|x| 1.5 * x).collect())
            .collect();
        let (r, se) = jackknife_ratio(&a, &b, |_| true);
        assert!(close(r, 1.5), "{r}");
        assert!(se.abs() < 1e-12, "{se}");
    }

    #[test]
    fn ratio_is_of_seed_means_not_of_per_seed_ratios() {
        // Seed means 3 and 2.5: ratio 1.2. The per-seed ratios 2 and 1 would give 1.5
        // (arithmetic) or sqrt 2 (geometric).
        let a = [vec![2.0], vec![4.0]];
        let b = [vec![1.0], vec![4.0]];
        assert!(close(geometric_mean_ratio(&a, &b, |_| true, None), 1.2));
    }

    #[test]
    fn geometric_mean_over_kept_counts() {
        let a = [vec![2.0, 8.0, 100.0]];
        let b = [vec![1.0, 1.0, 1.0]];
        assert!(close(geometric_mean_ratio(&a, &b, |i| i < 2, None), 4.0));
        assert!(close(geometric_mean_ratio(&a, &b, |i| i == 1, None), 8.0));
        assert!(geometric_mean_ratio(&a, &b, |_| false, None).is_nan());
    }

    #[test]
    fn skip_leaves_out_one_seed() {
        let a = [vec![1.0], vec![3.0], vec![5.0]];
        let b = [vec![1.0], vec![1.0], vec![1.0]];
        assert!(close(geometric_mean_ratio(&a, &b, |_| true, Some(0)), 4.0));
        assert!(close(geometric_mean_ratio(&a, &b, |_| true, Some(2)), 2.0));
    }

    #[test]
    fn jackknife_error_by_hand() {
        // Three seeds, one count, b = 1: leave-one-out ratios 4, 3, 2 (mean 3);
        // variance (2 / 3) (1 + 0 + 1) = 4 / 3.
        let a = [vec![1.0], vec![3.0], vec![5.0]];
        let b = [vec![1.0], vec![1.0], vec![1.0]];
        let (r, se) = jackknife_ratio(&a, &b, |_| true);
        assert!(close(r, 3.0));
        assert!(close(se, (4.0f64 / 3.0).sqrt()), "{se}");
        let (_, se1) = jackknife_ratio(&a[..1], &b[..1], |_| true);
        assert!(se1.is_nan());
    }
}
