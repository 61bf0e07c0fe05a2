//! The estimate of the smallest eigenvalue `lambda_1` of `A z = lambda M z` behind the
//! designed fields' smoothness shift: Rayleigh-Ritz on a shift-and-invert Krylov space.
//!
//! With the factor of `P = A + sigma M`, the operator `T = P^-1 M` is self-adjoint in
//! the mass inner product `<x, y>_M = x^H M y`, and its dominant eigenvectors are the
//! smoothest fields. After `k` solves the Krylov space `span(q, T q, ..., T^k q)` gets an
//! `M`-orthonormal basis `Q` (fully re-orthogonalised: a handful of vectors), and the
//! smallest eigenvalue of the small Hermitian matrix `Q^H A Q` is the estimate. By the
//! Courant-Fischer theorem it is never below `lambda_1`, which the shifted solve needs
//! (a shift above `lambda_1` would make it indefinite). Inverse iteration keeps only
//! the last vector of the same space, so this converges much faster per solve: on the
//! bunny 4 solves give `lambda_1` to 0.1%, where 5 inverse iterations were 1% off
//! (bench/README "Field design").
//!
//! Input: the masses, a start vector, `x <- T x` and `x -> A x` as closures. Output:
//! the estimate and the solves taken. Cost per step `k`: one solve, one product with
//! `A`, `O(k n)` orthogonalisation and a `k x k` eigenvalue problem.

use faer::{Mat, Side, c64};

use super::line_field::LineFieldError;

/// `<x, y>_M`, the mass inner product.
fn inner(mass: &[f64], x: &[c64], y: &[c64]) -> c64 {
    mass.iter()
        .zip(x.iter().zip(y))
        .map(|(m, (x, y))| x.conj() * y * *m)
        .sum()
}

/// `x^H y`.
fn dot(x: &[c64], y: &[c64]) -> c64 {
    x.iter().zip(y).map(|(x, y)| x.conj() * y).sum()
}

/// The smallest eigenvalue of the Hermitian matrix `h` (rows of the full matrix).
fn smallest_eigenvalue(h: &[Vec<c64>]) -> Option<f64> {
    let k = h.len();
    let matrix = Mat::<c64>::from_fn(k, k, |i, j| h[i][j]);
    let values = matrix.self_adjoint_eigenvalues(Side::Lower).ok()?;
    values.first().copied().filter(|v| v.is_finite())
}

/// An estimate from above of the smallest eigenvalue of `A z = lambda M z` (`A`
/// Hermitian positive semi-definite, `M` the positive diagonal `mass`): Rayleigh-Ritz
/// on `span(q, T q, ..., T^k q)` with `T = (A + sigma M)^-1 M` (see the
/// [module docs](self)). It stops when a step changes the estimate by at most
/// `tolerance` of itself, after `max_solves` applications of `T`, or when the Krylov
/// space stops growing. `apply_inverse` replaces its argument `x` by `T x`;
/// `apply_matrix` returns `A x`. Returns the estimate and the solves made.
///
/// Errors: a zero or non-finite start or iterate (a failed solve).
pub(crate) fn smallest_eigenvalue_from_above(
    mass: &[f64],
    start: Vec<c64>,
    max_solves: usize,
    tolerance: f64,
    mut apply_inverse: impl FnMut(&mut [c64]) -> Result<(), LineFieldError>,
    apply_matrix: impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(f64, usize), LineFieldError> {
    let failed = || LineFieldError::Factorization {
        stage: "solve (eigenvalue estimate: zero or non-finite iterate)",
    };
    let norm = inner(mass, &start, &start).re.sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(failed());
    }
    let first: Vec<c64> = start.into_iter().map(|z| z / norm).collect();
    let mut products = vec![apply_matrix(&first)];
    let mut basis = vec![first];
    // h[i][j] = q_i^H A q_j.
    let mut h = vec![vec![c64::new(dot(&basis[0], &products[0]).re, 0.0)]];
    let mut estimate = dot(&basis[0], &products[0]).re;
    for solves in 1..=max_solves.max(1) {
        let mut w = basis[solves - 1].clone();
        apply_inverse(&mut w)?;
        let before = inner(mass, &w, &w).re.sqrt();
        // Classical Gram-Schmidt, twice: enough for a dozen vectors.
        for _ in 0..2 {
            for q in &basis {
                let c = inner(mass, q, &w);
                w.iter_mut().zip(q).for_each(|(w, q)| *w -= *q * c);
            }
        }
        let b = inner(mass, &w, &w).re.sqrt();
        if !b.is_finite() {
            return Err(failed());
        }
        // The space stopped growing: the estimate is exact for it.
        if b <= 1e-10 * before {
            return Ok((estimate, solves));
        }
        w.iter_mut().for_each(|z| *z /= b);
        let aw = apply_matrix(&w);
        // The new row w^H A q_j, its mirror column, and the real diagonal w^H A w.
        let mut last: Vec<c64> = products.iter().map(|aq| dot(&w, aq)).collect();
        for (row, x) in h.iter_mut().zip(&last) {
            row.push(x.conj());
        }
        last.push(c64::new(dot(&w, &aw).re, 0.0));
        h.push(last);
        basis.push(w);
        products.push(aw);
        // The change of a step bounds the error of the step before; with the
        // superlinear convergence of Krylov methods the last step's error is much
        // smaller (see LAMBDA_TOLERANCE for the bunny's numbers).
        let next = smallest_eigenvalue(&h).ok_or_else(failed)?;
        let settled = (next - estimate).abs() <= tolerance * next.abs();
        estimate = next;
        if settled {
            return Ok((estimate, solves));
        }
    }
    Ok((estimate, max_solves.max(1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A = diag(a)`, `M = diag(m)`, `sigma`: the operators of a diagonal pencil, whose
    /// eigenvalues are `a_i / m_i`.
    struct Pencil {
        a: Vec<f64>,
        m: Vec<f64>,
        sigma: f64,
    }

    impl Pencil {
        fn new(n: usize) -> Self {
            // Eigenvalues 2 + 0.1 k^1.2 times varying masses: a gap like a Laplacian's.
            let m: Vec<f64> = (0..n).map(|k| 0.5 + (k % 7) as f64 * 0.1).collect();
            let a = (0..n)
                .map(|k| (2.0 + 0.1 * (k as f64).powf(1.2)) * m[k])
                .collect();
            Self { a, m, sigma: 0.01 }
        }

        fn run(&self, max: usize, tolerance: f64) -> (f64, usize) {
            let start: Vec<c64> = (0..self.a.len())
                .map(|k| c64::new(((k * 37) % 11) as f64 - 5.0, ((k * 13) % 5) as f64 - 2.0))
                .collect();
            smallest_eigenvalue_from_above(
                &self.m,
                start,
                max,
                tolerance,
                |x| {
                    for ((x, a), m) in x.iter_mut().zip(&self.a).zip(&self.m) {
                        *x *= *m / (*a + self.sigma * *m);
                    }
                    Ok(())
                },
                |x| x.iter().zip(&self.a).map(|(x, a)| *x * *a).collect(),
            )
            .expect("valid test input")
        }
    }

    #[test]
    fn the_estimate_falls_toward_the_smallest_eigenvalue_and_stays_above_it() {
        let pencil = Pencil::new(500);
        let mut previous = f64::INFINITY;
        for max in [1, 2, 3, 5, 8, 12] {
            let (estimate, solves) = pencil.run(max, 0.0);
            assert_eq!(solves, max);
            assert!(
                estimate >= 2.0 - 1e-9,
                "{max}: {estimate} below lambda_1 = 2"
            );
            assert!(
                estimate <= previous + 1e-9,
                "{max}: {estimate} rose from {previous}"
            );
            previous = estimate;
        }
        assert!(previous - 2.0 < 1e-4, "12 solves: {previous}");
        // The tolerance stops it early, close to the answer.
        let (estimate, solves) = pencil.run(50, 1e-3);
        assert!(
            solves < 12 && estimate - 2.0 < 2e-2,
            "{solves} solves: {estimate}"
        );
    }

    #[test]
    fn a_small_space_is_found_exactly_and_zero_starts_are_refused() {
        // Two distinct eigenvalues (1 and 4): the space is exhausted after one solve.
        let pencil = Pencil {
            a: vec![1.0, 1.0, 4.0, 4.0],
            m: vec![1.0; 4],
            sigma: 0.0,
        };
        let (estimate, solves) = pencil.run(10, 0.0);
        assert!(
            (estimate - 1.0).abs() < 1e-12 && solves <= 2,
            "{estimate} {solves}"
        );
        let zero = vec![c64::new(0.0, 0.0); 4];
        let refused =
            smallest_eigenvalue_from_above(&pencil.m, zero, 3, 0.0, |_| Ok(()), |x| x.to_vec());
        assert!(refused.is_err());
    }
}
