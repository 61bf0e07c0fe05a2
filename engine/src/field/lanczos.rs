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
//! bunny 4 solves give `lambda_1` to 0.3% (483.4 against 482.0), where 5 inverse iterations were 0.8% off
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

/// The smallest eigenvalue of the Hermitian matrix `h` (rows of the full matrix) and
/// its unit eigenvector.
fn smallest_pair(h: &[Vec<c64>]) -> Option<(f64, Vec<c64>)> {
    let k = h.len();
    let matrix = Mat::<c64>::from_fn(k, k, |i, j| h[i][j]);
    let evd = matrix.self_adjoint_eigen(Side::Lower).ok()?;
    let value = evd.S().column_vector()[0].re;
    let vector: Vec<c64> = (0..k).map(|i| evd.U()[(i, 0)]).collect();
    (value.is_finite() && vector.iter().all(|y| y.re.is_finite() && y.im.is_finite()))
        .then_some((value, vector))
}

/// Settings of [`smallest_eigenpair`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct KrylovOptions {
    /// Most applications of `T`.
    pub(crate) max_solves: usize,
    /// It stops when a step changes the estimate by at most `tolerance` times the
    /// larger of its magnitude and `floor`.
    pub(crate) tolerance: f64,
    /// See `tolerance` (a shift: estimates near 0 then stop at an absolute change).
    pub(crate) floor: f64,
    /// Most basis vectors kept: when full, the space restarts from the current Ritz
    /// vector (memory stays `basis_limit` vectors).
    pub(crate) basis_limit: usize,
    /// When the vector matters too: it also stops only once the Ritz pair's relative
    /// residual `|A x - lambda M x|_(M^-1) / max(lambda, floor)` is at most this. An
    /// eigenvalue settles long before its vector where the low spectrum is clustered
    /// (its error is the square of the vector's).
    pub(crate) residual: Option<f64>,
}

/// The M-orthonormal basis of the Krylov space, the products `A q_j`, and the
/// projected matrix `h[i][j] = q_i^H A q_j`.
struct Space {
    basis: Vec<Vec<c64>>,
    products: Vec<Vec<c64>>,
    h: Vec<Vec<c64>>,
}

impl Space {
    /// The space of the single vector `first` (`M`-normalised).
    fn new(first: Vec<c64>, apply_matrix: &impl Fn(&[c64]) -> Vec<c64>) -> Self {
        let product = apply_matrix(&first);
        let diagonal = c64::new(dot(&first, &product).re, 0.0);
        Self {
            basis: vec![first],
            products: vec![product],
            h: vec![vec![diagonal]],
        }
    }

    /// Adds `w` (`M`-normalised, orthogonal to the basis) and its row of `h`.
    fn push(&mut self, w: Vec<c64>, apply_matrix: &impl Fn(&[c64]) -> Vec<c64>) {
        let aw = apply_matrix(&w);
        // The new row w^H A q_j, its mirror column, and the real diagonal w^H A w.
        let mut last: Vec<c64> = self.products.iter().map(|aq| dot(&w, aq)).collect();
        for (row, x) in self.h.iter_mut().zip(&last) {
            row.push(x.conj());
        }
        last.push(c64::new(dot(&w, &aw).re, 0.0));
        self.h.push(last);
        self.basis.push(w);
        self.products.push(aw);
    }

    /// `|A x - lambda M x|_(M^-1)` for the Ritz vector `x = sum_j y_j q_j`, from the
    /// stored products.
    fn residual(&self, mass: &[f64], lambda: f64, y: &[c64]) -> f64 {
        let mut sum = 0.0;
        for (i, m) in mass.iter().enumerate() {
            let (mut x, mut ax) = (c64::new(0.0, 0.0), c64::new(0.0, 0.0));
            for ((q, aq), y) in self.basis.iter().zip(&self.products).zip(y) {
                x += q[i] * *y;
                ax += aq[i] * *y;
            }
            sum += (ax - x * (lambda * *m)).norm_sqr() / *m;
        }
        sum.sqrt()
    }

    /// `sum_j y_j q_j`.
    fn combine(&self, y: &[c64]) -> Vec<c64> {
        let mut x = vec![c64::new(0.0, 0.0); self.basis[0].len()];
        for (q, y) in self.basis.iter().zip(y) {
            x.iter_mut().zip(q).for_each(|(x, q)| *x += *q * *y);
        }
        x
    }
}

/// The smallest eigenvalue of `A z = lambda M z` (`A` Hermitian positive semi-definite,
/// `M` the positive diagonal `mass`), estimated from above, and its Ritz vector
/// (`M`-normalised): Rayleigh-Ritz on `span(q, T q, ..., T^k q)` with
/// `T = (A + sigma M)^-1 M` (see the [module docs](self)), restarted from the Ritz
/// vector when the basis is full. `apply_inverse` replaces its argument `x` by `T x`;
/// `apply_matrix` returns `A x`. Returns the estimate, the vector and the solves made.
///
/// Errors: a zero or non-finite start or iterate (a failed solve).
pub(crate) fn smallest_eigenpair(
    mass: &[f64],
    start: Vec<c64>,
    options: KrylovOptions,
    mut apply_inverse: impl FnMut(&mut [c64]) -> Result<(), LineFieldError>,
    apply_matrix: impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(f64, Vec<c64>, usize), LineFieldError> {
    let failed = || LineFieldError::Factorization {
        stage: "solve (eigenvalue estimate: zero or non-finite iterate)",
    };
    let normalised = |x: Vec<c64>| -> Result<Vec<c64>, LineFieldError> {
        let norm = inner(mass, &x, &x).re.sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(failed());
        }
        Ok(x.into_iter().map(|z| z / norm).collect())
    };
    let first = normalised(start)?;
    // An eigenvector's phase is free (`e^(i phi) x` rotates every line by `phi / 2`):
    // the one returned has `<start, x>_M` real and positive, the limit inverse
    // iteration from the same start reaches, so the result does not depend on the
    // small eigen-solver's sign conventions.
    let phased = |x: Vec<c64>| -> Vec<c64> {
        let c = inner(mass, &first, &x);
        let norm = c.norm();
        if norm > 0.0 {
            let unit = c.conj() / norm;
            x.into_iter().map(|z| z * unit).collect()
        } else {
            x
        }
    };
    let mut space = Space::new(first.clone(), &apply_matrix);
    let mut estimate = (space.h[0][0].re, vec![c64::new(1.0, 0.0)]);
    let max_solves = options.max_solves.max(1);
    let limit = options.basis_limit.max(2);
    let mut solves = 0;
    loop {
        if space.basis.len() >= limit {
            // Restart from the Ritz vector (its estimate is unchanged).
            let x = normalised(space.combine(&estimate.1))?;
            space = Space::new(x, &apply_matrix);
            estimate.1 = vec![c64::new(1.0, 0.0)];
        }
        let mut w = space.basis[space.basis.len() - 1].clone();
        apply_inverse(&mut w)?;
        solves += 1;
        let before = inner(mass, &w, &w).re.sqrt();
        // Classical Gram-Schmidt, twice: enough for a few dozen vectors.
        for _ in 0..2 {
            for q in &space.basis {
                let c = inner(mass, q, &w);
                w.iter_mut().zip(q).for_each(|(w, q)| *w -= *q * c);
            }
        }
        let b = inner(mass, &w, &w).re.sqrt();
        if !(b.is_finite() && before.is_finite()) {
            return Err(failed());
        }
        // The space stopped growing: the estimate is exact for it.
        if b <= 1e-10 * before {
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        }
        w.iter_mut().for_each(|z| *z /= b);
        space.push(w, &apply_matrix);
        // The change of a step bounds the error of the step before; with the
        // superlinear convergence of Krylov methods the last step's error is much
        // smaller (see LAMBDA_TOLERANCE for the bunny's numbers).
        let next = smallest_pair(&space.h).ok_or_else(failed)?;
        let scale = next.0.abs().max(options.floor);
        let mut settled = (next.0 - estimate.0).abs() <= options.tolerance * scale;
        if let Some(bound) = options.residual.filter(|_| settled) {
            settled = space.residual(mass, next.0, &next.1) <= bound * scale;
        }
        estimate = next;
        if settled || solves >= max_solves {
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        }
    }
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
            let options = KrylovOptions {
                max_solves: max,
                tolerance,
                floor: 0.0,
                basis_limit: usize::MAX,
                residual: None,
            };
            smallest_eigenpair(
                &self.m,
                start,
                options,
                |x| {
                    for ((x, a), m) in x.iter_mut().zip(&self.a).zip(&self.m) {
                        *x *= *m / (*a + self.sigma * *m);
                    }
                    Ok(())
                },
                |x| x.iter().zip(&self.a).map(|(x, a)| *x * *a).collect(),
            )
            .map(|(value, _, solves)| (value, solves))
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
    fn the_vector_is_the_eigenvector_with_the_start_s_phase_across_restarts() {
        let pencil = Pencil::new(300);
        let start: Vec<c64> = (0..300)
            .map(|k| c64::new(((k * 29) % 13) as f64 - 6.0, ((k * 7) % 3) as f64 - 1.0))
            .collect();
        for basis_limit in [4, 64] {
            let options = KrylovOptions {
                max_solves: 200,
                tolerance: 1e-12,
                floor: 0.0,
                basis_limit,
                residual: Some(1e-6),
            };
            let (value, x, solves) = smallest_eigenpair(
                &pencil.m,
                start.clone(),
                options,
                |x| {
                    for ((x, a), m) in x.iter_mut().zip(&pencil.a).zip(&pencil.m) {
                        *x *= *m / (*a + pencil.sigma * *m);
                    }
                    Ok(())
                },
                |x| x.iter().zip(&pencil.a).map(|(x, a)| *x * *a).collect(),
            )
            .expect("valid test input");
            // The smallest eigenvalue 2 sits at index 0: x is M-normalised there.
            assert!((value - 2.0).abs() < 1e-9, "{basis_limit}: {value}");
            let off: f64 = x[1..].iter().map(|z| z.norm_sqr()).sum();
            assert!(off < 1e-10, "{basis_limit}: {off} off the eigenvector");
            assert!((x[0].norm() * pencil.m[0].sqrt() - 1.0).abs() < 1e-9);
            // Its phase is the start's: <start, x>_M real and positive.
            let c = inner(&pencil.m, &start, &x);
            assert!(c.re > 0.0 && c.im.abs() < 1e-9 * c.re, "{basis_limit}: {c}");
            println!("basis {basis_limit}: {solves} solves");
        }
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
        let options = KrylovOptions {
            max_solves: 3,
            tolerance: 0.0,
            floor: 0.0,
            basis_limit: 8,
            residual: None,
        };
        let refused = smallest_eigenpair(&pencil.m, zero, options, |_| Ok(()), |x| x.to_vec());
        assert!(refused.is_err());
    }
}
