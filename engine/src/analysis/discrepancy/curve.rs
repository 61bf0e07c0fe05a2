//! Discrepancy against sample count on log-log axes, and its fitted slope.

use glam::DVec2;
use rayon::prelude::*;

use super::Discrepancy;
use crate::analysis::{AnalysisError, check_unit_square};

/// The least-squares slope of `ln(values)` against `ln(ns)`, negated, so that a curve
/// decaying like `n^-k` gives `k` (random points give about 0.5).
///
/// Returns NaN when the fit is undefined: fewer than two distinct `ns`, or a
/// non-positive or non-finite entry.
///
/// # Panics
/// If `ns` and `values` differ in length.
///
/// # Example
/// ```
/// use strata_engine::analysis::loglog_slope;
///
/// let ns = [100.0, 200.0, 400.0];
/// let values: Vec<f64> = ns.iter().map(|n: &f64| 3.0 * n.powf(-0.75)).collect();
/// assert!((loglog_slope(&ns, &values) - 0.75).abs() < 1e-12);
/// ```
pub fn loglog_slope(ns: &[f64], values: &[f64]) -> f64 {
    assert_eq!(
        ns.len(),
        values.len(),
        "loglog_slope: {} sample counts but {} values",
        ns.len(),
        values.len()
    );
    let valid = |v: f64| v.is_finite() && v > 0.0;
    if ns.len() < 2 || !ns.iter().chain(values).all(|&v| valid(v)) {
        return f64::NAN;
    }
    let m = ns.len() as f64;
    let lx: Vec<f64> = ns.iter().map(|n| n.ln()).collect();
    let ly: Vec<f64> = values.iter().map(|v| v.ln()).collect();
    let mx = lx.iter().sum::<f64>() / m;
    let my = ly.iter().sum::<f64>() / m;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (x, y) in lx.iter().zip(&ly) {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
    }
    if sxx == 0.0 {
        return f64::NAN;
    }
    -sxy / sxx
}

/// Mean discrepancies of a sampler over sample counts, with their log-log slopes: the
/// experiment of section 7.2 of the paper.
///
/// For each `n` the sampler runs once per seed; the sup and the L2 discrepancy (of the
/// chosen [`Discrepancy`]: its shape family and metric) of each run are averaged over
/// the seeds.
/// Runs execute in parallel with rayon; each result lands in its own slot and means are
/// taken in seed order, so the curve does not depend on the thread count.
///
/// # Example
/// ```
/// use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, baseline};
///
/// let curve = DiscrepancyCurve::measure(
///     &Discrepancy::default(),
///     baseline::uniform_random,
///     &[64, 128, 256, 512],
///     &[1, 2, 3],
/// )?;
/// assert_eq!(curve.sup.len(), 4);
/// assert!(curve.sup_slope() > 0.2 && curve.l2_slope() > 0.2);
/// # Ok::<(), strata_engine::analysis::AnalysisError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DiscrepancyCurve {
    /// Sample counts, in the order given.
    pub ns: Vec<usize>,
    /// Per count, the mean sup discrepancy over the seeds.
    pub sup: Vec<f64>,
    /// Per count, the mean L2 discrepancy over the seeds ([`Discrepancy::l2`]; for
    /// boxes the L2 star discrepancy).
    pub l2: Vec<f64>,
}

impl DiscrepancyCurve {
    /// Runs `sampler(n, seed)` for every `n` in `ns` and every seed in `seeds`.
    ///
    /// # Errors
    /// [`AnalysisError::EmptyCurve`] if `ns` or `seeds` is empty; the options' errors
    /// ([`Discrepancy::validate`]); [`AnalysisError::WrongSampleCount`] if the sampler
    /// returns other than `n` points; [`AnalysisError::SamplerPoint`] if it returns a
    /// point outside `[0, 1]^2`.
    pub fn measure<F>(
        discrepancy: &Discrepancy,
        sampler: F,
        ns: &[usize],
        seeds: &[u64],
    ) -> Result<Self, AnalysisError>
    where
        F: Fn(usize, u64) -> Vec<DVec2> + Sync,
    {
        if ns.is_empty() || seeds.is_empty() {
            return Err(AnalysisError::EmptyCurve {
                ns: ns.len(),
                seeds: seeds.len(),
            });
        }
        discrepancy.validate()?;
        let runs: Vec<(usize, u64)> = ns
            .iter()
            .flat_map(|&n| seeds.iter().map(move |&seed| (n, seed)))
            .collect();
        let results: Vec<Result<(f64, f64), AnalysisError>> = runs
            .par_iter()
            .map(|&(n, seed)| {
                let points = sampler(n, seed);
                if points.len() != n {
                    return Err(AnalysisError::WrongSampleCount {
                        n,
                        seed,
                        returned: points.len(),
                    });
                }
                check_unit_square(&points).map_err(|e| AnalysisError::SamplerPoint {
                    n,
                    seed,
                    source: Box::new(e),
                })?;
                Ok((discrepancy.try_sup(&points)?, discrepancy.try_l2(&points)?))
            })
            .collect();
        let results = results.into_iter().collect::<Result<Vec<_>, _>>()?;
        let per_n = seeds.len() as f64;
        let (sup, l2) = results
            .chunks(seeds.len())
            .map(|chunk| {
                let sup = chunk.iter().map(|r| r.0).sum::<f64>() / per_n;
                let l2 = chunk.iter().map(|r| r.1).sum::<f64>() / per_n;
                (sup, l2)
            })
            .unzip();
        Ok(Self {
            ns: ns.to_vec(),
            sup,
            l2,
        })
    }

    /// The sample counts as `f64`, for plotting and fitting.
    pub fn ns_f64(&self) -> Vec<f64> {
        self.ns.iter().map(|&n| n as f64).collect()
    }

    /// [`loglog_slope`] of the mean sup discrepancy.
    pub fn sup_slope(&self) -> f64 {
        loglog_slope(&self.ns_f64(), &self.sup)
    }

    /// [`loglog_slope`] of the mean L2 discrepancy.
    pub fn l2_slope(&self) -> f64 {
        loglog_slope(&self.ns_f64(), &self.l2)
    }
}
