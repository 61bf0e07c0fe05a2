//! Preconditioned conjugate gradients for Hermitian positive definite systems.
//!
//! Input: a multigrid hierarchy ([`Amg`]) of `A` (or of `A` minus a diagonal), one or
//! three right-hand sides and a start. Output: the solution in place and a
//! [`PcgReport`]. Cost per iteration: one product with `A`, one V-cycle and a few
//! vector sums, each summed in a fixed order, so the result does not depend on the
//! thread count.
//!
//! Kept rather than faer 0.24's matrix-free `conjugate_gradient` (which takes any
//! preconditioner). Measured with the same V-cycle as both preconditioners on a
//! connection-like system of the bunny Loop-subdivided once (139k unknowns, complex
//! Hermitian, relative tolerance 1e-6; `cargo run --release -p strata-bench --bin
//! linalg_faer`, 2 cores, medians of 5): both take 7 iterations and the same time
//! (275 against 273 ms on one thread, 286 against 291 on two: the V-cycle and the
//! products, ours in both, are the cost), and agree to 9e-16, but not bit for bit. So
//! faer's would buy no speed and would change every multigrid-solved field's bits; and
//! it is block conjugate gradients (the columns share one Krylov space), so it could
//! not give [`solve_three`]'s per-column results, which must equal three single solves
//! bit for bit. (faer 0.24.4 also leaves its residual unset when told the initial guess
//! is zero; the comparison passes a zeroed guess as `MaybeNonZero`.)

use glam::DVec3;
use rayon::prelude::*;

use super::amg::{Amg, Workspace};
use super::csr::{Csr, PARALLEL_ROWS};
use super::error::LinalgError;
use super::scalar::{Scalar, Vector, dot, norm2};

/// How a solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcgReport {
    /// Iterations taken.
    pub iterations: usize,
    /// `|b - A x| / |b|` at the end.
    pub residual: f64,
}

/// Solves `A x = b` (A the matrix `amg` was built from) by conjugate gradients
/// preconditioned with one V-cycle per iteration, from the `x` given, until
/// `|b - A x| <= tolerance |b|`. Errors: the budget spent first, an indefinite matrix, a
/// non-finite value.
pub fn solve<S: Scalar>(
    amg: &Amg<S>,
    b: &[S],
    x: &mut [S],
    tolerance: f64,
    max_iterations: usize,
) -> Result<PcgReport, LinalgError> {
    let n = amg.matrix().rows();
    assert!(
        b.len() == n && x.len() == n,
        "pcg: vector lengths differ from the matrix"
    );
    internally(amg, b, x, |b, x| {
        solve_internal(amg.matrix(), amg, b, x, tolerance, max_iterations)
    })
}

/// Solves `(A + diag(delta)) x = b` (`A` the matrix `amg` was built from, `delta` in
/// the caller's numbering) by conjugate gradients preconditioned with `amg`'s V-cycle
/// for `A`, from the `x` given, to the same tolerance as [`solve`]. For a system that
/// differs from an already built hierarchy's by its diagonal only: the iterations grow
/// with how far `A + diag(delta)` is from `A` (the ratio of the largest to the
/// smallest `z^H (A + diag(delta)) z / z^H A z`), so a caller gates it on a bound of
/// that ratio. Errors as [`solve`]; an indefinite sum is reported as such.
pub fn solve_with_diagonal<S: Scalar>(
    amg: &Amg<S>,
    delta: &[f64],
    b: &[S],
    x: &mut [S],
    tolerance: f64,
    max_iterations: usize,
) -> Result<PcgReport, LinalgError> {
    let mut a = amg.matrix().clone();
    let n = a.rows();
    assert!(
        delta.len() == n && b.len() == n && x.len() == n,
        "pcg: vector lengths differ from the matrix"
    );
    let mut d = vec![S::ZERO; n];
    amg.to_internal(
        &delta.iter().map(|&v| S::real(v)).collect::<Vec<S>>(),
        &mut d,
    );
    for (r, dr) in d.iter().enumerate() {
        let (cols, vals) = a.row_mut(r);
        match cols.binary_search(&(r as u32)) {
            Ok(k) => vals[k] += *dr,
            // Every row of a matrix `Amg` accepts has its (positive) diagonal.
            Err(_) => return Err(LinalgError::NotPositiveDefinite { pivot: r }),
        }
    }
    internally(amg, b, x, |b, x| {
        solve_internal(&a, amg, b, x, tolerance, max_iterations)
    })
}

/// Solves `A X = B` for three real right-hand sides at once (the columns of `b`'s
/// [`DVec3`]s), each by its own conjugate-gradient recurrence to `|b - A x| <= tolerance
/// |b|`, as [`solve`] would solve it alone, to the same bits. The products and
/// V-cycles read the matrices once for the three columns; a column that has
/// converged stops changing. Returns each column's report. Errors as [`solve`].
pub fn solve_three(
    amg: &Amg<f64>,
    b: &[DVec3],
    x: &mut [DVec3],
    tolerance: f64,
    max_iterations: usize,
) -> Result<[PcgReport; 3], LinalgError> {
    let a = amg.matrix();
    let n = a.rows();
    assert!(
        b.len() == n && x.len() == n,
        "pcg: vector lengths differ from the matrix"
    );
    internally(amg, b, x, |b, x| {
        three_internal(a, amg, b, x, tolerance, max_iterations)
    })
}

/// `sum x_k y_k` of column `k`, in [`dot`]'s order.
fn column_dot(x: &[DVec3], y: &[DVec3], k: usize) -> f64 {
    x.iter().zip(y).fold(0.0, |acc, (a, b)| acc + a[k] * b[k])
}

/// `sum x_k^2` of column `k`, in [`norm2`]'s order.
fn column_norm2(x: &[DVec3], k: usize) -> f64 {
    x.iter().map(|v| v[k] * v[k]).sum()
}

/// Rows per block of the element-wise updates of [`solve_three`] on every thread.
const UPDATE_BLOCK: usize = 8192;

/// `f(first_i, second_i, i)` over the rows of two equal-length slices, by fixed blocks on
/// every thread from [`PARALLEL_ROWS`] rows (each row's arithmetic is independent of the
/// cut).
fn each_row<T: Send + Sync>(
    first: &mut [DVec3],
    second: &mut [T],
    f: impl Fn(&mut DVec3, &mut T, usize) + Sync + Send,
) {
    if first.len() < PARALLEL_ROWS {
        for (i, (a, b)) in first.iter_mut().zip(second.iter_mut()).enumerate() {
            f(a, b, i);
        }
    } else {
        first
            .par_chunks_mut(UPDATE_BLOCK)
            .zip(second.par_chunks_mut(UPDATE_BLOCK))
            .enumerate()
            .for_each(|(block, (a, b))| {
                for (i, (a, b)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
                    f(a, b, block * UPDATE_BLOCK + i);
                }
            });
    }
}

fn three_internal(
    a: &Csr<f64>,
    amg: &Amg<f64>,
    b: &[DVec3],
    x: &mut [DVec3],
    tolerance: f64,
    max_iterations: usize,
) -> Result<[PcgReport; 3], LinalgError> {
    let b_norm: [f64; 3] = std::array::from_fn(|k| column_norm2(b, k).sqrt());
    if b_norm.iter().any(|v| !v.is_finite()) || x.iter().any(|v| !v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    for (k, norm) in b_norm.iter().enumerate() {
        if *norm == 0.0 {
            x.iter_mut().for_each(|v| v[k] = 0.0);
        }
    }
    let Start {
        mut work,
        mut r,
        mut z,
        mut q,
        mut p,
    } = start(a, amg, b, x);
    let mut rz: [f64; 3] = std::array::from_fn(|k| column_dot(&r, &z, k));
    let mut residual: [f64; 3] = std::array::from_fn(|k| {
        if b_norm[k] == 0.0 {
            0.0
        } else {
            column_norm2(&r, k).sqrt() / b_norm[k]
        }
    });
    let mut iterations = [0usize; 3];
    loop {
        let active: [bool; 3] = std::array::from_fn(|k| residual[k] > tolerance);
        if !active.contains(&true) {
            break;
        }
        for k in (0..3).filter(|&k| active[k]) {
            if iterations[k] >= max_iterations {
                return Err(LinalgError::NotConverged {
                    iterations: iterations[k],
                    residual: residual[k],
                    tolerance,
                });
            }
        }
        a.mul_into(&p, &mut q);
        let mut alpha = [0.0; 3];
        for k in (0..3).filter(|&k| active[k]) {
            let curvature = column_dot(&p, &q, k);
            if !(curvature > 0.0) {
                return Err(if curvature.is_finite() {
                    LinalgError::Indefinite {
                        iteration: iterations[k],
                    }
                } else {
                    LinalgError::NonFinite
                });
            }
            alpha[k] = rz[k] / curvature;
        }
        let (p_ref, q_ref) = (&p, &q);
        each_row(x, &mut r, |x, r, i| {
            for k in (0..3).filter(|&k| active[k]) {
                x[k] += p_ref[i][k] * alpha[k];
                r[k] -= q_ref[i][k] * alpha[k];
            }
        });
        for k in (0..3).filter(|&k| active[k]) {
            iterations[k] += 1;
            residual[k] = column_norm2(&r, k).sqrt() / b_norm[k];
            if !residual[k].is_finite() {
                return Err(LinalgError::NonFinite);
            }
        }
        // A column that just converged needs no new direction.
        let next: [bool; 3] = std::array::from_fn(|k| residual[k] > tolerance);
        if !next.contains(&true) {
            break;
        }
        amg.cycle(&r, &mut z, &mut work);
        let mut beta = [0.0; 3];
        for k in (0..3).filter(|&k| next[k]) {
            let rz_next = column_dot(&r, &z, k);
            beta[k] = rz_next / rz[k];
            rz[k] = rz_next;
        }
        each_row(&mut p, &mut z, |p, z, _| {
            for k in (0..3).filter(|&k| next[k]) {
                p[k] = z[k] + p[k] * beta[k];
            }
        });
    }
    Ok(std::array::from_fn(|k| PcgReport {
        iterations: iterations[k],
        residual: residual[k],
    }))
}

/// `solve(b, x)` on `b` and `x` moved into `amg`'s internal numbering, `x` moved back.
fn internally<S: Scalar, V: Vector<S>, R>(
    amg: &Amg<S>,
    b: &[V],
    x: &mut [V],
    solve: impl FnOnce(&[V], &mut [V]) -> R,
) -> R {
    let n = b.len();
    let mut bi = vec![V::zero(); n];
    let mut xi = vec![V::zero(); n];
    amg.to_internal(b, &mut bi);
    amg.to_internal(x, &mut xi);
    let out = solve(&bi, &mut xi);
    amg.from_internal(&xi, x);
    out
}

/// Conjugate gradients' first step from `x`: the residual `r = b - A x`, its
/// preconditioned `z` (one V-cycle), the first direction `p = z`, scratch `q` for
/// `A p`, and the cycle's workspace.
struct Start<V> {
    work: Workspace<V>,
    r: Vec<V>,
    z: Vec<V>,
    q: Vec<V>,
    p: Vec<V>,
}

fn start<S: Scalar, V: Vector<S>>(a: &Csr<S>, amg: &Amg<S>, b: &[V], x: &[V]) -> Start<V> {
    let n = a.rows();
    let mut work = amg.workspace();
    let mut r = vec![V::zero(); n];
    a.mul_into(x, &mut r);
    for (r, b) in r.iter_mut().zip(b) {
        *r = *b - *r;
    }
    let mut z = vec![V::zero(); n];
    amg.cycle(&r, &mut z, &mut work);
    Start {
        work,
        p: z.clone(),
        q: vec![V::zero(); n],
        r,
        z,
    }
}

fn solve_internal<S: Scalar>(
    a: &Csr<S>,
    amg: &Amg<S>,
    b: &[S],
    x: &mut [S],
    tolerance: f64,
    max_iterations: usize,
) -> Result<PcgReport, LinalgError> {
    let n = a.rows();
    assert!(
        b.len() == n && x.len() == n,
        "pcg: vector lengths differ from the matrix"
    );
    let b_norm = norm2(b).sqrt();
    if !b_norm.is_finite() || x.iter().any(|v| !v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    if b_norm == 0.0 {
        x.iter_mut().for_each(|v| *v = S::ZERO);
        return Ok(PcgReport {
            iterations: 0,
            residual: 0.0,
        });
    }
    let Start {
        mut work,
        mut r,
        mut z,
        mut q,
        mut p,
    } = start(a, amg, b, x);
    let mut rz = dot(&r, &z).re();
    let mut residual = norm2(&r).sqrt() / b_norm;
    let mut iterations = 0;
    while residual > tolerance {
        if iterations >= max_iterations {
            return Err(LinalgError::NotConverged {
                iterations,
                residual,
                tolerance,
            });
        }
        a.mul_into(&p, &mut q);
        let curvature = dot(&p, &q).re();
        if !(curvature > 0.0) {
            return Err(if curvature.is_finite() {
                LinalgError::Indefinite {
                    iteration: iterations,
                }
            } else {
                LinalgError::NonFinite
            });
        }
        let alpha = rz / curvature;
        for ((x, r), (p, q)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
            *x += p.scale(alpha);
            *r -= q.scale(alpha);
        }
        iterations += 1;
        residual = norm2(&r).sqrt() / b_norm;
        if !residual.is_finite() {
            return Err(LinalgError::NonFinite);
        }
        amg.cycle(&r, &mut z, &mut work);
        let rz_next = dot(&r, &z).re();
        let beta = rz_next / rz;
        rz = rz_next;
        for (p, z) in p.iter_mut().zip(&z) {
            *p = *z + p.scale(beta);
        }
    }
    Ok(PcgReport {
        iterations,
        residual,
    })
}
