//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel and Brezina 1996) for
//! Hermitian positive definite matrices, real or complex, used as the preconditioner
//! of conjugate gradients ([`pcg`](super::pcg)).
//!
//! # Setup
//! Each level groups its unknowns into aggregates of strongly coupled neighbours
//! (`|a_ij|^2 >= theta^2 a_ii a_jj`): first whole neighbourhoods of untouched unknowns,
//! then the rest join their strongest aggregated neighbour, then leftovers form their
//! own. The tentative prolongator maps an aggregate's coarse unknown to the
//! *near-null vector* restricted to it, normalised. For a connection Laplacian
//! (`a_ji = -w r_ij`, the energy `sum w |z_j - r_ij z_i|^2`) the near-null vector is a
//! locally parallel field, `z_j = phase(-a_ji) z_i`: it is built along the aggregate's
//! tree from its root, so holonomy around larger loops does not matter. For a real
//! matrix it is the constant vector ([`Scalar::transport`]), even where a cotangent
//! Laplacian's obtuse corners make a coupling positive. One damped Jacobi step
//! smooths the prolongator, `P = (I - omega D^-1 A) P_t` with
//! `omega = 4 / (3 rho)` and `rho` the Gershgorin bound of `D^-1 A`. The coarse matrix
//! is the Galerkin product `P^H A P`. Unknowns with no strong neighbour are left to the
//! smoother (their prolongator row comes only from the smoothing step). Coarsening
//! stops at [`AmgOptions::coarsest`] unknowns, which a dense Cholesky solves.
//!
//! # Cycle
//! A V-cycle with one forward Gauss-Seidel sweep before the coarse correction and one
//! backward sweep after it: a symmetric preconditioner, as conjugate gradients needs.
//! On levels of more than [`PARALLEL_ROWS`] unknowns the sweeps run by fixed blocks of
//! rows on every thread (each block sequential inside, the blocks Jacobi-coupled: see
//! `gauss_seidel`). On a 300 x 300 complex grid (three blocks) conjugate gradients
//! take 16 iterations to 1e-10 with them and 16 with one sequential sweep (measured
//! once with the block size raised above the grid; the unit test bounds it at 17).
//!
//! Cost: setup and each cycle are linear in the non-zeros (operator complexity, the
//! non-zeros of all levels over the finest's, is about 1.5 to 2 on meshes).
//! Deterministic: aggregation and vector updates run in a fixed order on one thread; the
//! sweeps' blocks have a fixed size; the sparse products and renumbering run on every
//! thread by blocks of whole rows ([`Csr`]), each row as on one thread; so the hierarchy
//! and every cycle are the same for any thread count.

use rayon::prelude::*;

use super::csr::{Csr, PARALLEL_ROWS};
use super::dense::DenseCholesky;
use super::error::LinalgError;
use super::scalar::{Scalar, Vector};

/// Settings of the hierarchy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmgOptions {
    /// Strength threshold `theta` in `[0, 1)`: a coupling is strong when
    /// `|a_ij| >= theta sqrt(a_ii a_jj)`. Default 0.08.
    pub strength: f64,
    /// Coarsening stops at or below this many unknowns (solved densely). Default 300.
    pub coarsest: usize,
    /// Most levels. Default 30.
    pub max_levels: usize,
}

impl Default for AmgOptions {
    fn default() -> Self {
        Self {
            strength: 0.08,
            coarsest: 300,
            max_levels: 30,
        }
    }
}

/// Largest coarsest level the dense factor accepts when coarsening stalls.
const MAX_DENSE: usize = 3000;

struct Level<S> {
    a: Csr<S>,
    inverse_diagonal: Vec<f64>,
    /// Prolongator to the next level and its adjoint (absent on the coarsest).
    transfer: Option<(Csr<S>, Csr<S>)>,
}

/// A multigrid hierarchy of one matrix, ready to precondition. It works on the matrix
/// renumbered in [breadth-first order](Csr::breadth_first_order) for memory locality;
/// [`to_internal`](Self::to_internal) and [`from_internal`](Self::from_internal) move
/// vectors between the two numberings.
pub struct Amg<S> {
    levels: Vec<Level<S>>,
    coarse: DenseCholesky<S>,
    /// `order[k]`: the caller's index of internal unknown `k`.
    order: Vec<u32>,
}

impl<S: Scalar> Amg<S> {
    /// The hierarchy of the Hermitian positive definite `a`, with `near_null` the
    /// magnitudes of its near-null vector (`None`: all 1, right for Laplacians and
    /// connection Laplacians). Errors: a non-positive diagonal, a coarsest level that is
    /// not positive definite, coarsening that stalls above a dense size.
    pub fn new(
        a: Csr<S>,
        near_null: Option<&[f64]>,
        options: &AmgOptions,
    ) -> Result<Self, LinalgError> {
        let order = a.breadth_first_order();
        let mut position = vec![0u32; order.len()];
        for (k, &old) in order.iter().enumerate() {
            position[old as usize] = k as u32;
        }
        Self::ordered(a.permuted(&order, &position), order, near_null, options)
    }

    /// The hierarchy [`new`](Self::new) makes, from the matrix already renumbered:
    /// `a`'s row `k` is the caller's unknown `order[k]`, with `order` the
    /// [breadth-first order](Csr::breadth_first_order) of the matrix in the caller's
    /// numbering (any permutation works; that one keeps memory accesses local).
    /// `near_null` is in the caller's numbering. Panics if `order` is not a permutation
    /// of `a`'s rows (a caller bug). Errors as [`new`](Self::new).
    pub fn ordered(
        a: Csr<S>,
        order: Vec<u32>,
        near_null: Option<&[f64]>,
        options: &AmgOptions,
    ) -> Result<Self, LinalgError> {
        let mut seen = vec![false; a.rows()];
        assert!(
            order.len() == a.rows()
                && order.iter().all(|&k| seen
                    .get_mut(k as usize)
                    .is_some_and(|s| !std::mem::replace(s, true))),
            "multigrid: the order is not a permutation of the rows"
        );
        let mut a = a;
        let mut b: Vec<f64> = match near_null {
            Some(b) => order.iter().map(|&old| b[old as usize]).collect(),
            None => vec![1.0; a.rows()],
        };
        let mut levels = Vec::new();
        let (levels, coarse) = loop {
            let inverse_diagonal = inverse_diagonal(&a)?;
            let n = a.rows();
            if n <= options.coarsest || levels.len() + 1 >= options.max_levels {
                break levels_with_coarse(levels, a, inverse_diagonal)?;
            }
            let (tentative, coarse_b) = tentative_prolongator(&a, &b, options.strength);
            if tentative.cols() == 0 || tentative.cols() * 10 > n * 9 {
                // No real coarsening left (e.g. only isolated unknowns).
                if n > MAX_DENSE {
                    return Err(LinalgError::Coarsening { unknowns: n });
                }
                break levels_with_coarse(levels, a, inverse_diagonal)?;
            }
            let p = smooth_prolongator(&a, &inverse_diagonal, &tentative);
            let r = p.adjoint();
            // P^H A P is Hermitian up to round-off, which neither the smoother nor
            // the dense factor (it reads the lower triangle) notices.
            let coarse = r.matmul(&a.matmul(&p));
            levels.push(Level {
                a,
                inverse_diagonal,
                transfer: Some((p, r)),
            });
            a = coarse;
            b = coarse_b;
        };
        Ok(Self {
            levels,
            coarse,
            order,
        })
    }

    /// One V-cycle for `A x = b` in the caller's numbering (see [`cycle`](Self::cycle)):
    /// an approximate inverse of `A`, the preconditioner of eigenvalue iterations.
    pub fn apply<V: Vector<S>>(&self, b: &[V], x: &mut [V], work: &mut Workspace<V>) {
        // The finest level's scratch holds the renumbered vectors: no allocation.
        self.to_internal(b, &mut work.levels[0][0]);
        self.descend(0, work);
        self.from_internal(&work.levels[0][1], x);
    }

    /// `x` in the internal numbering, into `out`.
    pub fn to_internal<V: Copy>(&self, x: &[V], out: &mut [V]) {
        for (o, &old) in out.iter_mut().zip(&self.order) {
            *o = x[old as usize];
        }
    }

    /// `x` from the internal numbering back to the caller's, into `out`.
    pub fn from_internal<V: Copy>(&self, x: &[V], out: &mut [V]) {
        for (v, &old) in x.iter().zip(&self.order) {
            out[old as usize] = *v;
        }
    }

    /// Unknowns per level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.a.rows()).collect()
    }

    /// Non-zeros of all levels over the finest's.
    pub fn operator_complexity(&self) -> f64 {
        let all: usize = self.levels.iter().map(|l| l.a.nnz()).sum();
        all as f64 / self.levels[0].a.nnz().max(1) as f64
    }

    /// The finest matrix, in the internal numbering.
    pub fn matrix(&self) -> &Csr<S> {
        &self.levels[0].a
    }

    /// A workspace for [`cycle`](Self::cycle), allocated once per solve.
    pub fn workspace<V: Vector<S>>(&self) -> Workspace<V> {
        Workspace {
            levels: self
                .levels
                .iter()
                .map(|l| {
                    let n = l.a.rows();
                    [vec![V::zero(); n], vec![V::zero(); n], vec![V::zero(); n]]
                })
                .collect(),
        }
    }

    /// One V-cycle from zero for `A x = b`: `x ~ A^-1 b` (a symmetric positive
    /// definite linear map of `b`; each column of a [`Vector`] as if alone).
    pub fn cycle<V: Vector<S>>(&self, b: &[V], x: &mut [V], work: &mut Workspace<V>) {
        work.levels[0][0].copy_from_slice(b);
        self.descend(0, work);
        x.copy_from_slice(&work.levels[0][1]);
    }

    /// V-cycle on level `l`: right-hand side in `work[l][0]`, solution to `work[l][1]`.
    fn descend<V: Vector<S>>(&self, l: usize, work: &mut Workspace<V>) {
        let level = &self.levels[l];
        let Some((p, r)) = &level.transfer else {
            let [b, x, _] = &mut work.levels[l];
            x.copy_from_slice(b);
            self.coarse.solve(x);
            return;
        };
        {
            let [b, x, _] = &mut work.levels[l];
            x.iter_mut().for_each(|v| *v = V::zero());
            gauss_seidel(&level.a, &level.inverse_diagonal, b, x, None, false);
        }
        {
            let (fine, coarse) = work.levels.split_at_mut(l + 1);
            let [b, x, residual] = &mut fine[l];
            level.a.mul_into(x, residual);
            for (res, b) in residual.iter_mut().zip(b.iter()) {
                *res = *b - *res;
            }
            r.mul_into(residual, &mut coarse[0][0]);
        }
        self.descend(l + 1, work);
        let (fine, coarse) = work.levels.split_at_mut(l + 1);
        let [b, x, correction] = &mut fine[l];
        p.mul_into(&coarse[0][1], correction);
        for (x, c) in x.iter_mut().zip(correction.iter()) {
            *x += *c;
        }
        // The correction is spent: it holds the values from before the sweep.
        gauss_seidel(
            &level.a,
            &level.inverse_diagonal,
            b,
            x,
            Some(correction),
            true,
        );
    }
}

/// Scratch vectors of a V-cycle: per level the right-hand side, the solution and a
/// residual or correction.
pub struct Workspace<V> {
    levels: Vec<[Vec<V>; 3]>,
}

fn levels_with_coarse<S: Scalar>(
    mut levels: Vec<Level<S>>,
    a: Csr<S>,
    inverse_diagonal: Vec<f64>,
) -> Result<(Vec<Level<S>>, DenseCholesky<S>), LinalgError> {
    let n = a.rows();
    let mut dense = vec![S::ZERO; n * n];
    for r in 0..n {
        let (cols, vals) = a.row(r);
        for (&c, &v) in cols.iter().zip(vals) {
            dense[r * n + c as usize] = v;
        }
    }
    let coarse = DenseCholesky::new(n, |i, j| dense[i * n + j])?;
    levels.push(Level {
        a,
        inverse_diagonal,
        transfer: None,
    });
    Ok((levels, coarse))
}

fn inverse_diagonal<S: Scalar>(a: &Csr<S>) -> Result<Vec<f64>, LinalgError> {
    (0..a.rows())
        .map(|r| {
            let d = a.diagonal(r).re();
            if d > 0.0 && d.is_finite() {
                Ok(1.0 / d)
            } else {
                Err(LinalgError::NotPositiveDefinite { pivot: r })
            }
        })
        .collect()
}

/// Rows per block of a Gauss-Seidel sweep. A fixed size, never the thread count, so a
/// sweep is the same on any number of threads; a level with fewer rows is one block,
/// an exact sweep.
const SWEEP_BLOCK_ROWS: usize = PARALLEL_ROWS;

/// One Gauss-Seidel sweep on `A x = b`, forward or backward, by blocks of
/// [`SWEEP_BLOCK_ROWS`] rows on every thread ("hybrid" Gauss-Seidel, as hypre's
/// smoothers run in parallel): inside a block each row uses the block's newest values,
/// across blocks the values from before the sweep (`before`: scratch for a copy of `x`
/// made here; `None` when `x` is zero, so they are zero). The blocks of a forward and a backward
/// sweep are the same, so the two are adjoint and the V-cycle stays symmetric. The
/// unknowns are in breadth-first order, so few couplings cross a block's edge and the
/// sweep smooths almost as a sequential one.
fn gauss_seidel<S: Scalar, V: Vector<S>>(
    a: &Csr<S>,
    inverse_diagonal: &[f64],
    b: &[V],
    x: &mut [V],
    before: Option<&mut [V]>,
    backward: bool,
) {
    // One block reads no value from outside itself: no copy needed.
    let before: &[V] = match before {
        Some(copy) if x.len() > SWEEP_BLOCK_ROWS => {
            copy.copy_from_slice(x);
            copy
        }
        _ => &[],
    };
    let sweep = |block: usize, xs: &mut [V]| {
        let first = block * SWEEP_BLOCK_ROWS;
        let len = xs.len();
        let mut relax = |k: usize| {
            let (cols, vals) = a.row(first + k);
            let mut sum = b[first + k];
            for (&c, &v) in cols.iter().zip(vals) {
                let c = c as usize;
                // One unsigned comparison: is column `c` inside this block?
                let inside = c.wrapping_sub(first);
                if inside < len {
                    sum -= V::times(v, xs[inside]);
                } else if let Some(&old) = before.get(c) {
                    sum -= V::times(v, old);
                }
            }
            xs[k] += sum.scaled(inverse_diagonal[first + k]);
        };
        if backward {
            (0..len).rev().for_each(&mut relax);
        } else {
            (0..len).for_each(&mut relax);
        }
    };
    if x.len() <= SWEEP_BLOCK_ROWS {
        sweep(0, x);
    } else {
        x.par_chunks_mut(SWEEP_BLOCK_ROWS)
            .enumerate()
            .for_each(|(block, xs)| sweep(block, xs));
    }
}

const UNSET: u32 = u32::MAX;

/// The tentative prolongator (one entry per aggregated row) and the coarse near-null
/// magnitudes (see the [module docs](self)).
fn tentative_prolongator<S: Scalar>(a: &Csr<S>, b: &[f64], theta: f64) -> (Csr<S>, Vec<f64>) {
    let n = a.rows();
    let diagonal: Vec<f64> = (0..n).map(|r| a.diagonal(r).re()).collect();
    let diagonal = &diagonal;
    let theta2 = theta * theta;
    let strong = |r: usize| {
        let (cols, vals) = a.row(r);
        cols.iter().zip(vals).filter_map(move |(&c, &v)| {
            let c = c as usize;
            (c != r && v.abs2() >= theta2 * diagonal[r] * diagonal[c]).then_some((c, v))
        })
    };
    // The transported phase of `child` from `parent` along the coupling `a[child][parent]`.
    let step = S::transport;
    let mut aggregate = vec![UNSET; n];
    let mut phase = vec![S::real(1.0); n];
    let mut count = 0u32;
    // Pass 1: whole neighbourhoods of untouched unknowns.
    for r in 0..n {
        if aggregate[r] != UNSET {
            continue;
        }
        let mut any = false;
        let mut free = true;
        for (c, _) in strong(r) {
            any = true;
            free &= aggregate[c] == UNSET;
        }
        if any && free {
            aggregate[r] = count;
            for (c, v) in strong(r) {
                aggregate[c] = count;
                // a[c][r] = conj(a[r][c]).
                phase[c] = step(v.conj());
            }
            count += 1;
        }
    }
    // Pass 2: join the strongest neighbour aggregated in pass 1.
    let first = aggregate.clone();
    for r in 0..n {
        if aggregate[r] != UNSET {
            continue;
        }
        let best = strong(r).filter(|&(c, _)| first[c] != UNSET).fold(
            None,
            |best: Option<(usize, S)>, (c, v)| match best {
                Some((_, w)) if w.abs2() >= v.abs2() => best,
                _ => Some((c, v)),
            },
        );
        if let Some((c, v)) = best {
            aggregate[r] = first[c];
            phase[r] = step(v) * phase[c];
        }
    }
    // Pass 3: leftovers with strong neighbours start aggregates of their own.
    for r in 0..n {
        if aggregate[r] != UNSET || strong(r).next().is_none() {
            continue;
        }
        aggregate[r] = count;
        phase[r] = S::real(1.0);
        for (c, v) in strong(r) {
            if aggregate[c] == UNSET {
                aggregate[c] = count;
                phase[c] = step(v.conj());
            }
        }
        count += 1;
    }
    let mut norms = vec![0.0; count as usize];
    for r in 0..n {
        if aggregate[r] != UNSET {
            norms[aggregate[r] as usize] += b[r] * b[r];
        }
    }
    norms.iter_mut().for_each(|s| *s = s.sqrt());
    let triplets: Vec<(usize, usize, S)> = (0..n)
        .filter(|&r| aggregate[r] != UNSET)
        .map(|r| {
            let k = aggregate[r] as usize;
            (r, k, phase[r].scale(b[r] / norms[k]))
        })
        .collect();
    (Csr::from_triplets(n, count as usize, &triplets), norms)
}

/// `P = (I - omega D^-1 A) P_t`, `omega = 4 / (3 rho)`, `rho` the Gershgorin bound of
/// `D^-1 A`.
fn smooth_prolongator<S: Scalar>(
    a: &Csr<S>,
    inverse_diagonal: &[f64],
    tentative: &Csr<S>,
) -> Csr<S> {
    let rho = (0..a.rows())
        .map(|r| a.row(r).1.iter().map(|v| v.abs2().sqrt()).sum::<f64>() * inverse_diagonal[r])
        .fold(0.0, f64::max);
    let omega = 4.0 / (3.0 * rho.max(f64::MIN_POSITIVE));
    // A P_t has every column of P_t's row (through the diagonal of A), so the sum is
    // A P_t's pattern with P_t's entry added in place.
    let mut p = a.matmul(tentative);
    for (r, d) in inverse_diagonal.iter().enumerate() {
        let s = -omega * d;
        let (tc, tv) = tentative.row(r);
        let (cols, vals) = p.row_mut(r);
        vals.iter_mut().for_each(|v| *v = v.scale(s));
        for (c, v) in tc.iter().zip(tv) {
            match cols.binary_search(c) {
                Ok(k) => vals[k] += *v,
                Err(_) => unreachable!("A P_t lacks a column of P_t: zero diagonal"),
            }
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use faer::c64;

    use super::*;

    /// A path `0 - 1 - 2` with couplings `a01`, `a12` and a diagonal of 2.
    fn path<S: Scalar>(a01: S, a12: S) -> Csr<S> {
        let two = S::real(2.0);
        Csr::from_triplets(
            3,
            3,
            &[
                (0, 0, two),
                (1, 1, two),
                (2, 2, two),
                (1, 0, a01),
                (0, 1, a01.conj()),
                (2, 1, a12),
                (1, 2, a12.conj()),
            ],
        )
    }

    #[test]
    fn real_aggregates_carry_the_constant_whatever_the_coupling_signs() {
        // A positive coupling (an obtuse corner of a cotangent Laplacian) must not flip
        // the sign of the near-null vector inside an aggregate.
        let (p, b) = tentative_prolongator(&path(-1.0, 0.8), &[1.0; 3], 0.08);
        assert_eq!((p.cols(), b.len()), (1, 1));
        let s = 1.0 / 3f64.sqrt();
        for r in 0..3 {
            assert_eq!(p.row(r), (&[0u32][..], &[s][..]), "row {r}");
        }
    }

    #[test]
    fn complex_aggregates_transport_the_phase_of_each_coupling() {
        // a_10 = -e^(i 0.3): z_1 = e^(i 0.3) z_0; a_21 = -e^(-i 1.1): z_2 = e^(-i 1.1) z_1.
        let a01 = -c64::from_polar(1.0, 0.3);
        let a12 = -c64::from_polar(1.0, -1.1);
        let (p, _) = tentative_prolongator(&path(a01, a12), &[1.0; 3], 0.08);
        let s = 1.0 / 3f64.sqrt();
        // Vertex 1 is the root (the first with all strong neighbours free is 0, whose
        // neighbour is 1; then 0's aggregate holds 0 and 1, and 2 joins through 1).
        let z: Vec<c64> = (0..3).map(|r| p.row(r).1[0] / s).collect();
        assert!(
            (z[1] / z[0] - c64::from_polar(1.0, 0.3)).norm() < 1e-12,
            "{z:?}"
        );
        assert!(
            (z[2] / z[1] - c64::from_polar(1.0, -1.1)).norm() < 1e-12,
            "{z:?}"
        );
    }
}
