//! Dense Hermitian Cholesky for the coarsest level of the multigrid hierarchy (a few
//! hundred unknowns).
//!
//! Input: the lower triangle of a Hermitian positive definite matrix. Output: its
//! factor, which solves one or several columns ([`Vector`]) in place. Cost: `n^3 / 3`
//! to factor, `n^2` per column to solve.
//!
//! Kept rather than faer's `llt`: on a 300 x 300 Hermitian positive definite matrix
//! (the size of a coarsest level) faer's solve agrees with this one to 4.9e-13 but only
//! 2 of the 300 entries have the same bits (`cargo run --release -p strata-bench --bin linalg_faer`),
//! so every multigrid-preconditioned field would change; and this one solves the
//! three-column vectors of [`pcg::solve_three`](super::pcg::solve_three) with the
//! same operations per column as a single column, which that solve's bits rest on.

use super::error::LinalgError;
use super::scalar::{Scalar, Vector};

/// The factor `L` (lower, row-major) of a Hermitian positive definite `A = L L^H`.
#[derive(Clone, Debug)]
pub struct DenseCholesky<S> {
    n: usize,
    l: Vec<S>,
}

impl<S: Scalar> DenseCholesky<S> {
    /// Factors the `n x n` Hermitian matrix given by its lower triangle `lower(i, j)`,
    /// `j <= i`. Errors: not positive definite (a pivot at or below zero, or not finite).
    pub fn new(n: usize, lower: impl Fn(usize, usize) -> S) -> Result<Self, LinalgError> {
        let mut l = vec![S::ZERO; n * n];
        for j in 0..n {
            let mut d = lower(j, j).re();
            for k in 0..j {
                d -= l[j * n + k].abs2();
            }
            if !(d > 0.0 && d.is_finite()) {
                return Err(LinalgError::NotPositiveDefinite { pivot: j });
            }
            let ljj = d.sqrt();
            l[j * n + j] = S::real(ljj);
            for i in j + 1..n {
                let mut s = lower(i, j);
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k].conj();
                }
                l[i * n + j] = s.scale(1.0 / ljj);
            }
        }
        Ok(Self { n, l })
    }

    /// Unknowns.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Solves `A x = b` in place (`x` of scalars or of several columns, [`Vector`]).
    pub fn solve<V: Vector<S>>(&self, x: &mut [V]) {
        let n = self.n;
        for i in 0..n {
            let row = &self.l[i * n..i * n + i];
            let s = row
                .iter()
                .zip(&x[..i])
                .fold(x[i], |s, (l, x)| s - V::times(*l, *x));
            x[i] = s.scaled(1.0 / self.l[i * n + i].re());
        }
        for i in (0..n).rev() {
            let s = (i + 1..n)
                .zip(&x[i + 1..])
                .fold(x[i], |s, (k, x)| s - V::times(self.l[k * n + i].conj(), *x));
            x[i] = s.scaled(1.0 / self.l[i * n + i].re());
        }
    }
}
