//! Preconditioned conjugate gradients for Hermitian positive definite systems.

use super::amg::Amg;
use super::csr::Csr;
use super::error::LinalgError;
use super::scalar::{Scalar, dot, norm2};

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
    let mut bi = vec![S::ZERO; n];
    let mut xi = vec![S::ZERO; n];
    amg.to_internal(b, &mut bi);
    amg.to_internal(x, &mut xi);
    let report = solve_internal(amg.matrix(), amg, &bi, &mut xi, tolerance, max_iterations);
    amg.from_internal(&xi, x);
    report
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
    let mut bi = vec![S::ZERO; n];
    let mut xi = vec![S::ZERO; n];
    amg.to_internal(b, &mut bi);
    amg.to_internal(x, &mut xi);
    let report = solve_internal(&a, amg, &bi, &mut xi, tolerance, max_iterations);
    amg.from_internal(&xi, x);
    report
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
    let mut work = amg.workspace();
    let mut r = vec![S::ZERO; n];
    a.mul_into(x, &mut r);
    for (r, b) in r.iter_mut().zip(b) {
        *r = *b - *r;
    }
    let mut z = vec![S::ZERO; n];
    let mut q = vec![S::ZERO; n];
    amg.cycle(&r, &mut z, &mut work);
    let mut p = z.clone();
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
