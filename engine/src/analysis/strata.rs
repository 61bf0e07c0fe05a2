//! Shape measures of a sampler's 1D strata: where the `N` equal-measure intervals of a
//! segment's Hilbert curve lie in the plane, how compact they are, and how much count
//! variance they put into origin-anchored boxes. They explain two section 7 checks of
//! the paper (Quinn et al., "Generalized Anisotropic Stratified Surface Sampling"):
//! the low-frequency energy of 7.4 and the boundary error of 7.3.2.
//!
//! Input: a [`Sampler`] of a planar domain (positions' x and y are used; z is dropped)
//! and a sample count `n`. Output: plain numbers ([`strata_second_moment`]) or a small
//! struct ([`StrataVariance`]). Each stratum is represented by [`STRATUM_POINTS`] points
//! evenly spaced in measure along its stretch of the curve ([`stratum_points`]).
//!
//! Cost: `O(n * STRATUM_POINTS * log C)` curve look-ups (`C` leaf cells), plus
//! `O(n * STRATUM_POINTS * B)` for `B` boxes in [`strata_variance`]; strata run in
//! parallel with rayon and the result does not depend on the thread count (per-stratum
//! values are collected in order and summed in order).

use glam::DVec2;
use rayon::prelude::*;

use super::AnalysisError;
use crate::mesh::TriMesh;
use crate::sample::{Sampler, SegmentSampling, allocate};

/// Points per stratum in [`stratum_points`] (an 8 x 8 sub-grid of a square stratum).
pub const STRATUM_POINTS: usize = 64;

/// Stratum `k` of `count` equal-measure strata of `seg`'s curve, mapped to the plane by
/// [`STRATUM_POINTS`] points evenly spaced in measure along it (the midpoints of
/// `STRATUM_POINTS` equal sub-intervals), as the xy of their mesh positions.
///
/// `k < count` is expected; the last point is kept just inside the curve's measure.
pub fn stratum_points(mesh: &TriMesh, seg: &SegmentSampling, k: usize, count: usize) -> Vec<DVec2> {
    const M: usize = STRATUM_POINTS;
    let mu = seg.curve.measure();
    (0..M)
        .map(|j| {
            let t = (k as f64 + (j as f64 + 0.5) / M as f64) * mu / count as f64;
            let p = seg.curve.locate(t.min(mu * (1.0 - 1e-12)));
            let f = mesh.face_positions(seg.faces[p.triangle as usize]);
            let w = f[0] * p.bary[0] + f[1] * p.bary[1] + f[2] * p.bary[2];
            DVec2::new(w.x, w.y)
        })
        .collect()
}

/// Mean second moment of the 1D strata of a one-segment `sampler` of the unit square
/// for `n` samples, relative to that of a square of the same area: `6 N sum_k tr(Cov_k)
/// / N`, i.e. `6 sum_k tr(Cov_k)`, `Cov_k` the covariance of stratum `k`'s
/// [`stratum_points`] (a square of area `1 / N` has `tr(Cov) = 1 / (6 N)`).
///
/// Dimensionless: 1 for square strata (a jittered grid), `63 / 64` for square strata
/// resolved by an 8 x 8 sub-grid, more for strata that cut across the curve's cells.
/// Section 7.4: at `N = 4^k` the strata are the curve's square cells; in between they
/// are less compact, and the low-frequency energy grows with this moment. Only the
/// first segment is measured; `n = 0` gives 0.
pub fn strata_second_moment(sampler: &Sampler, n: usize) -> f64 {
    let seg = &sampler.segments()[0];
    let mesh = sampler.mesh();
    let per: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|k| {
            let pts = stratum_points(mesh, seg, k, n);
            let m = pts.len();
            let mean = pts.iter().copied().sum::<DVec2>() / m as f64;
            pts.iter()
                .map(|p| (*p - mean).length_squared())
                .sum::<f64>()
                / m as f64
        })
        .collect();
    6.0 * per.iter().sum::<f64>()
}

/// Strata of one class in [`StrataVariance`] and the count variance they carry.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClassVariance {
    /// Number of strata in the class.
    pub strata: usize,
    /// Their summed count variance, `sum E_box[p (1 - p)]` (samples^2 per box).
    pub variance: f64,
}

/// The count variance of a sampler's 1D strata over origin-anchored boxes, in total and
/// split into three classes of strata (see [`strata_variance`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataVariance {
    /// Sum over strata of `E_box[p (1 - p)]`: the variance of a box's sample count under
    /// independent jitter, averaged over the boxes (samples^2).
    pub total: f64,
    /// Strata whose extent exceeds three stratum sizes (`3 / sqrt(n)`): they straddle a
    /// jump of the curve, where it leaves the segment and re-enters it elsewhere.
    pub straddling: ClassVariance,
    /// The remaining strata with a point on the seam (the caller's predicate).
    pub seam: ClassVariance,
    /// All other strata.
    pub elsewhere: ClassVariance,
}

impl StrataVariance {
    /// The classes in a fixed order: straddling, seam, elsewhere.
    pub fn classes(&self) -> [ClassVariance; 3] {
        [self.straddling, self.seam, self.elsewhere]
    }
}

/// The count variance of `sampler`'s 1D strata for `n` samples over the origin-anchored
/// boxes `[0, b.x) x [0, b.y)` for each `b` in `boxes`: with independent jitter a box's
/// count has variance `sum_k p_k (1 - p_k)`, `p_k` the share of stratum `k` inside it
/// (the share of its [`stratum_points`]); this is averaged over the boxes and split by
/// class of stratum (straddling a curve jump, touching the `seam`, elsewhere).
///
/// Samples are allocated to segments as the sampler does ([`allocate`]); a segment that
/// gets no sample has no strata. Stratum size is `1 / sqrt(n)`, so the domain should
/// have unit area (the unit square). Section 7.3.2: its square root tracks the L2
/// discrepancy ratio of a two-segment over a one-segment square, and the classes say
/// where the excess comes from.
///
/// # Errors
/// [`AnalysisError::NoBoxes`] if `boxes` is empty.
pub fn strata_variance(
    sampler: &Sampler,
    n: usize,
    boxes: &[DVec2],
    seam: &(dyn Fn(DVec2) -> bool + Sync),
) -> Result<StrataVariance, AnalysisError> {
    if boxes.is_empty() {
        return Err(AnalysisError::NoBoxes);
    }
    let mesh = sampler.mesh();
    let mut counts = vec![0u64; sampler.segments().len()];
    allocate(
        n as u64,
        sampler.segments().iter().map(|s| s.curve.measure()),
        |i, c| counts[i] = c,
    );
    let h = 1.0 / (n as f64).sqrt();
    let mut classes = [ClassVariance::default(); 3];
    let mut total = 0.0;
    for (seg, &c) in sampler.segments().iter().zip(&counts) {
        let per: Vec<(f64, usize)> = (0..c)
            .into_par_iter()
            .map(|k| {
                let pts = stratum_points(mesh, seg, k as usize, c as usize);
                let m = pts.len();
                let var = boxes
                    .iter()
                    .map(|b| {
                        let q =
                            pts.iter().filter(|p| p.x < b.x && p.y < b.y).count() as f64 / m as f64;
                        q * (1.0 - q)
                    })
                    .sum::<f64>()
                    / boxes.len() as f64;
                let (lo, hi) = pts
                    .iter()
                    .fold((DVec2::MAX, DVec2::MIN), |(a, b), p| (a.min(*p), b.max(*p)));
                let class = if (hi - lo).max_element() > 3.0 * h {
                    0
                } else if pts.iter().any(|p| seam(*p)) {
                    1
                } else {
                    2
                };
                (var, class)
            })
            .collect();
        for (v, class) in per {
            total += v;
            classes[class].strata += 1;
            classes[class].variance += v;
        }
    }
    let [straddling, seam, elsewhere] = classes;
    Ok(StrataVariance {
        total,
        straddling,
        seam,
        elsewhere,
    })
}

#[cfg(test)]
#[path = "strata_tests.rs"]
mod tests;
