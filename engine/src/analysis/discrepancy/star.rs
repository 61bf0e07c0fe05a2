//! Star discrepancy over origin-anchored boxes: the exact supremum and the L2 norm.

use glam::DVec2;
use rayon::prelude::*;

use crate::analysis::{AnalysisError, check_unit_square};

/// The exact supremum star discrepancy of `points` in `[0, 1]^2`.
///
/// `D* = sup max(x y - A([0,x) x [0,y)) / N, A([0,x] x [0,y]) / N - x y)` over
/// `x, y` in `[0, 1]`, where `A(B)` counts the points in `B` (duplicates counted with
/// multiplicity). For points in `[0, 1)^2` this is the classical star discrepancy
/// (Niederreiter 1992, section 2.1): the closed boxes are the limits of half-open ones.
/// The supremum is attained on the grid of critical boxes whose corners are point
/// coordinates or 1, which is searched completely in O(N^2) time and O(N) memory per
/// thread (a sweep in x over cumulative counts indexed by y rank, in parallel runs of
/// x); ties in either coordinate are handled exactly. About 0.1 s for 10^4 points. The empty set has `D* = 1` (nothing covers the full square).
///
/// # Panics
/// If a point is NaN or outside `[0, 1]^2` (see [`try_star_discrepancy_sup`]).
///
/// # Example
/// ```
/// use glam::DVec2;
/// use strata_engine::analysis::star_discrepancy_sup;
///
/// // The closed box [0, 0.5]^2 holds the single point but has area 1/4.
/// let d = star_discrepancy_sup(&[DVec2::new(0.5, 0.5)]);
/// assert!((d - 0.75).abs() < 1e-15);
/// ```
pub fn star_discrepancy_sup(points: &[DVec2]) -> f64 {
    match try_star_discrepancy_sup(points) {
        Ok(d) => d,
        Err(e) => panic!("star_discrepancy_sup: {e}"),
    }
}

/// [`star_discrepancy_sup`], returning an error instead of panicking.
///
/// # Errors
/// [`AnalysisError::PointOutsideUnitSquare`] if a point is NaN or outside `[0, 1]^2`.
pub fn try_star_discrepancy_sup(points: &[DVec2]) -> Result<f64, AnalysisError> {
    check_unit_square(points)?;
    Ok(star_sup_unchecked(points))
}

pub(crate) fn star_sup_unchecked(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return 1.0;
    }
    let inv_n = 1.0 / n as f64;

    // Critical y values: the distinct point ordinates, then 1 (the full-height box).
    let mut ys: Vec<f64> = points.iter().map(|p| p.y).collect();
    ys.sort_unstable_by(f64::total_cmp);
    ys.dedup();
    if ys.last().is_some_and(|&y| y < 1.0) {
        ys.push(1.0);
    }
    // Points by x, each with the rank of its y among `ys` (present by construction).
    let mut by_x: Vec<(f64, usize)> = points
        .iter()
        .map(|p| (p.x, ys.partition_point(|&y| y < p.y)))
        .collect();
    by_x.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));

    // Start of each run of equal x (a critical x), then one past the end.
    let mut groups: Vec<usize> = (0..n)
        .filter(|&i| i == 0 || by_x[i].0 != by_x[i - 1].0)
        .collect();
    groups.push(n);
    let group_count = groups.len() - 1;

    // Runs of critical x are swept in parallel tasks of fixed size; each task starts
    // from the counts of the points left of it. The maximum is exact in any order, so
    // the result does not depend on the thread count.
    const GROUPS_PER_TASK: usize = 256;
    let swept = (0..group_count.div_ceil(GROUPS_PER_TASK))
        .into_par_iter()
        .map(|task| {
            let first = task * GROUPS_PER_TASK;
            let last = (first + GROUPS_PER_TASK).min(group_count);
            // cum[j]: points with x' <= (current x) and y' <= ys[j]; shifted by one it
            // counts y' < ys[j], the open side.
            let mut cum = vec![0.0f64; ys.len() + 1];
            for &(_, rank) in &by_x[..groups[first]] {
                cum[rank + 1] += 1.0;
            }
            for j in 1..cum.len() {
                cum[j] += cum[j - 1];
            }
            let mut best = 0.0f64;
            for g in first..last {
                let x = by_x[groups[g]].0;
                for &(_, rank) in &by_x[groups[g]..groups[g + 1]] {
                    for c in &mut cum[rank + 1..] {
                        *c += 1.0;
                    }
                }
                // The next critical x: its open boxes hold exactly the points with
                // x' <= x, so one pass over `cum` serves both box kinds.
                let next_x = match groups.get(g + 1) {
                    Some(&i) if i < n => by_x[i].0,
                    _ if x < 1.0 => 1.0,
                    // x = 1: no open box beyond; a zero next_x makes its deficit -count.
                    _ => 0.0,
                };
                best = best.max(largest_gap(&ys, &cum, x, next_x, inv_n));
            }
            best
        })
        .reduce(|| 0.0, f64::max);
    // No point has x < x_0, so the open box [0, x_0) x [0, 1) is empty.
    swept.max(by_x[0].0)
}

/// `max_j max(cum[j+1] / N - x ys[j], next_x ys[j] - cum[j] / N)`: the closed-box excess
/// at `x` and the open-box deficit at `next_x`, over all critical y. Four independent
/// lanes let the compiler vectorise the loop.
fn largest_gap(ys: &[f64], cum: &[f64], x: f64, next_x: f64, inv_n: f64) -> f64 {
    let mut lanes = [0.0f64; 4];
    let gap = |j: usize| {
        let excess = cum[j + 1] * inv_n - x * ys[j];
        let deficit = next_x * ys[j] - cum[j] * inv_n;
        if excess > deficit { excess } else { deficit }
    };
    let whole = ys.len() / 4 * 4;
    for j in (0..whole).step_by(4) {
        for (l, lane) in lanes.iter_mut().enumerate() {
            let g = gap(j + l);
            *lane = if g > *lane { g } else { *lane };
        }
    }
    let tail = (whole..ys.len()).map(gap).fold(0.0, f64::max);
    lanes.iter().copied().fold(tail, f64::max)
}

/// The L2 star discrepancy of `points` in `[0, 1]^2`, by Warnock's closed form.
///
/// `T = (integral over [0,1]^2 of (A([0,x) x [0,y)) / N - x y)^2 dx dy)^(1/2)`, computed as
/// `T^2 = 1/9 - (2/N) sum_i prod_k (1 - x_ik^2)/2 + (1/N^2) sum_i sum_j prod_k (1 - max(x_ik, x_jk))`
/// (Warnock 1972; see also Matoušek, "Geometric Discrepancy", 1999). O(N^2) time, O(N) memory. The double
/// sum runs in parallel by rows, each row summed sequentially and the rows summed in
/// index order, so the result does not depend on the thread count. The empty set has
/// `T = 1/3`.
///
/// # Panics
/// If a point is NaN or outside `[0, 1]^2` (see [`try_star_discrepancy_l2`]).
///
/// # Example
/// ```
/// use glam::DVec2;
/// use strata_engine::analysis::star_discrepancy_l2;
///
/// // One point at the origin lies in every box: T^2 = integral of (1 - x y)^2 = 11/18.
/// let t = star_discrepancy_l2(&[DVec2::ZERO]);
/// assert!((t - (11.0f64 / 18.0).sqrt()).abs() < 1e-15);
/// ```
pub fn star_discrepancy_l2(points: &[DVec2]) -> f64 {
    match try_star_discrepancy_l2(points) {
        Ok(d) => d,
        Err(e) => panic!("star_discrepancy_l2: {e}"),
    }
}

/// [`star_discrepancy_l2`], returning an error instead of panicking.
///
/// # Errors
/// [`AnalysisError::PointOutsideUnitSquare`] if a point is NaN or outside `[0, 1]^2`.
pub fn try_star_discrepancy_l2(points: &[DVec2]) -> Result<f64, AnalysisError> {
    check_unit_square(points)?;
    Ok(star_l2_unchecked(points))
}

pub(crate) fn star_l2_unchecked(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return (1.0f64 / 9.0).sqrt();
    }
    let single = neumaier_sum(
        points
            .iter()
            .map(|p| 0.25 * (1.0 - p.x * p.x) * (1.0 - p.y * p.y)),
    );
    // The double sum is symmetric: half the diagonal plus the upper triangle, doubled.
    let rows: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| {
            let p = points[i];
            let mut row = 0.5 * (1.0 - p.x) * (1.0 - p.y);
            for q in &points[i + 1..] {
                row += (1.0 - p.x.max(q.x)) * (1.0 - p.y.max(q.y));
            }
            row
        })
        .collect();
    let double = 2.0 * neumaier_sum(rows.into_iter());
    let nf = n as f64;
    let t2 = 1.0 / 9.0 - 2.0 / nf * single + double / (nf * nf);
    // Rounding can push an exact zero slightly negative.
    t2.max(0.0).sqrt()
}

/// Compensated (Neumaier) summation, in iteration order.
fn neumaier_sum(values: impl Iterator<Item = f64>) -> f64 {
    let mut sum = 0.0f64;
    let mut comp = 0.0f64;
    for v in values {
        let t = sum + v;
        comp += if sum.abs() >= v.abs() {
            (sum - t) + v
        } else {
            (v - t) + sum
        };
        sum = t;
    }
    sum + comp
}
