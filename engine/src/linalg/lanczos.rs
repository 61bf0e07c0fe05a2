//! The smallest eigenpair of `A z = lambda M z` behind the designed fields: the estimate
//! of `lambda_1` for the smoothness shift, and the smoothest field. Rayleigh-Ritz on a
//! shift-and-invert Krylov space with a direct factor, on a Davidson space with a
//! multigrid preconditioner.
//!
//! With the factor of `P = A + sigma M`, the operator `T = P^-1 M` is self-adjoint in
//! the mass inner product `<x, y>_M = x^H M y`, and its dominant eigenvectors are the
//! smoothest fields. After `k` solves the Krylov space `span(q, T q, ..., T^k q)` gets an
//! `M`-orthonormal basis `Q` (fully re-orthogonalised: a handful of vectors), and the
//! smallest eigenvalue of the small Hermitian matrix `Q^H A Q` is the estimate. By the
//! Courant-Fischer theorem it is never below `lambda_1`, which the shifted solve needs
//! (a shift above `lambda_1` would make it indefinite). Inverse iteration keeps only
//! the last vector of the same space, so this converges much faster per solve: on the
//! bunny 4 solves give `lambda_1` to 0.3% (483.4 against 482.0), where 5 inverse
//! iterations were 0.8% off (bench/README "Field design").
//!
//! Without a factor (multigrid), the space grows instead by `B^-1 (A x - theta M x)`,
//! a V-cycle `B^-1 ~ P^-1` of the current Ritz pair's residual (the preconditioned
//! Davidson method), and restarts from its two newest Ritz vectors (as LOBPCG keeps
//! its previous iterate), so a small basis loses little. The bound from above holds
//! for any space.
//!
//! Input: the masses, a start vector, `x <- T x` (or `r -> B^-1 r`) and `x -> A x` as
//! closures. Output: the estimate, its vector and the solves taken. Cost per step `k`:
//! one solve (or V-cycle), one product with `A`, `O(k n)` orthogonalisation (in
//! parallel over fixed blocks of rows, so sums do not depend on the thread count) and
//! a `k x k` eigenvalue problem.
//!
//! Kept rather than faer 0.24's partial eigensolver (`partial_self_adjoint_eigen`,
//! Krylov-Schur): it builds a basis of at least 32 vectors and then extends it to at
//! least 64 before its first convergence test (`MIN_DIM` in faer-0.24.4's
//! `src/operator/eigen/mod.rs`, `partial_self_adjoint_eigen_imp`), one solve with the
//! factor each, where this loop stops after 4 solves for `lambda_1` and about 12 for
//! the smoothest field on the bunny (`field::design`'s docs); it works in the plain
//! inner product, not the mass's; and it needs the exact operator, where the
//! multigrid path grows its space by a V-cycle of the residual (Davidson), which it has
//! no form for. Bits: its restarts and small eigenproblems are faer's, so the fields
//! would change.

use std::ops::Range;

use faer::{Mat, Side, c64};
use rayon::prelude::*;

use super::error::LinalgError;

/// Rows per task of the vector kernels below. Fixed, so that every sum is made in the
/// same order whatever the thread count.
const BLOCK_ROWS: usize = 8192;

/// `f` of each block of [`BLOCK_ROWS`] rows of `0..n`, in parallel, in block order.
fn per_block<T: Send>(n: usize, f: impl Fn(Range<usize>) -> T + Sync) -> Vec<T> {
    (0..n.div_ceil(BLOCK_ROWS))
        .into_par_iter()
        .map(|b| f(b * BLOCK_ROWS..((b + 1) * BLOCK_ROWS).min(n)))
        .collect()
}

/// `[v_j^H W w for each v_j in vectors]` with `W = diag(weights)` (the identity for
/// `None`): one pass over `w` for all the vectors, summed block by block in order.
fn inners(weights: Option<&[f64]>, vectors: &[Vec<c64>], w: &[c64]) -> Vec<c64> {
    let parts = per_block(w.len(), |rows| {
        let w = &w[rows.clone()];
        let weights = weights.map(|m| &m[rows.clone()]);
        vectors
            .iter()
            .map(|v| block_inner(&v[rows.clone()], w, weights))
            .collect::<Vec<c64>>()
    });
    let mut total = vec![c64::new(0.0, 0.0); vectors.len()];
    for part in parts {
        total.iter_mut().zip(part).for_each(|(t, x)| *t += x);
    }
    total
}

/// `x^H W y` (`W` the identity for `None`).
fn block_inner(x: &[c64], y: &[c64], weights: Option<&[f64]>) -> c64 {
    match weights {
        Some(w) => w
            .iter()
            .zip(x.iter().zip(y))
            .map(|(m, (x, y))| x.conj() * y * *m)
            .sum(),
        None => x.iter().zip(y).map(|(x, y)| x.conj() * y).sum(),
    }
}

/// `<x, x>_W = x^H W x` for the positive diagonal `W = diag(weights)`, or with `W^-1`.
fn norm2(weights: &[f64], x: &[c64], inverse: bool) -> f64 {
    per_block(x.len(), |rows| {
        weights[rows.clone()]
            .iter()
            .zip(&x[rows])
            .map(|(m, z)| {
                if inverse {
                    z.norm_sqr() / m
                } else {
                    z.norm_sqr() * m
                }
            })
            .sum::<f64>()
    })
    .into_iter()
    .sum()
}

/// `x += sign sum_j y_j v_j`, each entry summed in the order of the vectors.
fn add_combination(x: &mut [c64], vectors: &[Vec<c64>], y: &[c64], sign: f64) {
    x.par_chunks_mut(BLOCK_ROWS)
        .enumerate()
        .for_each(|(b, chunk)| {
            let start = b * BLOCK_ROWS;
            for (v, y) in vectors.iter().zip(y) {
                let y = *y * sign;
                let v = &v[start..start + chunk.len()];
                chunk.iter_mut().zip(v).for_each(|(x, v)| *x += *v * y);
            }
        });
}

/// `sum_j y_j v_j`.
fn combination(vectors: &[Vec<c64>], y: &[c64]) -> Vec<c64> {
    let mut x = vec![c64::new(0.0, 0.0); vectors[0].len()];
    add_combination(&mut x, vectors, y, 1.0);
    x
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
    /// Most applications of `T` (or of the preconditioner).
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

/// The M-orthonormal basis of the search space, the products `A q_j`, and the
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
        let diagonal = c64::new(
            inners(None, std::slice::from_ref(&product), &first)[0].re,
            0.0,
        );
        Self {
            basis: vec![first],
            products: vec![product],
            h: vec![vec![diagonal]],
        }
    }

    /// Adds `w` (`M`-normalised, orthogonal to the basis) and its row of `h`.
    fn push(&mut self, w: Vec<c64>, apply_matrix: &impl Fn(&[c64]) -> Vec<c64>) {
        let aw = apply_matrix(&w);
        // The new column q_j^H A w = (A q_j)^H w, its mirror row, and the real
        // diagonal w^H A w.
        let column = inners(None, &self.products, &w);
        for (row, x) in self.h.iter_mut().zip(&column) {
            row.push(*x);
        }
        let mut last: Vec<c64> = column.iter().map(|x| x.conj()).collect();
        last.push(c64::new(
            inners(None, std::slice::from_ref(&w), &aw)[0].re,
            0.0,
        ));
        self.h.push(last);
        self.basis.push(w);
        self.products.push(aw);
    }

    /// `A x - lambda M x` for the Ritz vector `x = sum_j y_j q_j`, from the stored
    /// products.
    fn residual(&self, mass: &[f64], lambda: f64, y: &[c64]) -> Vec<c64> {
        let mut r = combination(&self.products, y);
        let x = self.combine(y);
        r.par_iter_mut()
            .zip(&x)
            .zip(mass)
            .for_each(|((r, x), m)| *r -= *x * (lambda * *m));
        r
    }

    /// `sum_j y_j q_j`.
    fn combine(&self, y: &[c64]) -> Vec<c64> {
        combination(&self.basis, y)
    }
}

/// How the search space grows.
enum Expansion<I, P> {
    /// By `T = (A + sigma M)^-1 M` applied to the newest basis vector (a Krylov space).
    Inverse(I),
    /// By a preconditioner `B^-1 ~ (A + sigma M)^-1` applied to the Ritz pair's
    /// residual (the Davidson method).
    Precondition(P),
}

/// The smallest eigenvalue of `A z = lambda M z` (`A` Hermitian positive semi-definite,
/// `M` the positive diagonal `mass`), estimated from above, and its Ritz vector
/// (`M`-normalised): Rayleigh-Ritz on `span(q, T q, ..., T^k q)` with
/// `T = (A + sigma M)^-1 M` (see the [module docs](self)), restarted from the Ritz
/// vector when the basis is full. `apply_inverse` replaces its argument `x` by `T x`;
/// `apply_matrix` returns `A x`. Returns the estimate, the vector and the solves made.
///
/// Errors: a zero or non-finite start or iterate (a failed solve).
pub(crate) fn smallest_eigenpair<E: From<LinalgError>>(
    mass: &[f64],
    start: Vec<c64>,
    options: KrylovOptions,
    apply_inverse: impl FnMut(&mut [c64]) -> Result<(), E>,
    apply_matrix: impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(f64, Vec<c64>, usize), E> {
    rayleigh_ritz(
        mass,
        start,
        options,
        Expansion::<_, fn(&[c64], &mut [c64])>::Inverse(apply_inverse),
        apply_matrix,
    )
}

/// [`smallest_eigenpair`] for a solver that only approximates `(A + sigma M)^-1`
/// (a multigrid cycle): the space grows by the preconditioned residual
/// `B^-1 (A x - theta M x)` of the current Ritz pair `(theta, x)` instead of by a
/// solve (the preconditioned Davidson method; preconditioned inverse iteration keeps
/// only the newest vector of the same space). Rayleigh-Ritz keeps the estimate above
/// `lambda_1` whatever `B` is; `B` only sets how fast it falls. `precondition(r, z)`
/// writes `z = B^-1 r`; `options.max_solves` counts its applications.
///
/// Errors: a zero or non-finite start or iterate.
pub(crate) fn smallest_eigenpair_preconditioned(
    mass: &[f64],
    start: Vec<c64>,
    options: KrylovOptions,
    precondition: impl FnMut(&[c64], &mut [c64]),
    apply_matrix: impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(f64, Vec<c64>, usize), LinalgError> {
    rayleigh_ritz(
        mass,
        start,
        options,
        Expansion::<fn(&mut [c64]) -> Result<(), LinalgError>, _>::Precondition(precondition),
        apply_matrix,
    )
}

/// The Rayleigh-Ritz loop behind [`smallest_eigenpair`] and
/// [`smallest_eigenpair_preconditioned`].
fn rayleigh_ritz<E: From<LinalgError>>(
    mass: &[f64],
    start: Vec<c64>,
    options: KrylovOptions,
    mut expansion: Expansion<
        impl FnMut(&mut [c64]) -> Result<(), E>,
        impl FnMut(&[c64], &mut [c64]),
    >,
    apply_matrix: impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(f64, Vec<c64>, usize), E> {
    let normalised = |mut x: Vec<c64>| -> Result<Vec<c64>, LinalgError> {
        let norm = norm2(mass, &x, false).sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(failed());
        }
        x.par_iter_mut().for_each(|z| *z /= norm);
        Ok(x)
    };
    let first = normalised(start)?;
    // An eigenvector's phase is free (`e^(i phi) x` rotates every line by `phi / 2`):
    // the one returned has `<start, x>_M` real and positive, the limit inverse
    // iteration from the same start reaches, so the result does not depend on the
    // small eigen-solver's sign conventions.
    let phased = |mut x: Vec<c64>| -> Vec<c64> {
        // <first, x>_M.
        let c = inners(Some(mass), std::slice::from_ref(&first), &x)[0];
        let norm = c.norm();
        if norm > 0.0 {
            let unit = c.conj() / norm;
            x.par_iter_mut().for_each(|z| *z *= unit);
        }
        x
    };
    let mut space = Space::new(first.clone(), &apply_matrix);
    let mut estimate = (space.h[0][0].re, vec![c64::new(1.0, 0.0)]);
    let max_solves = options.max_solves.max(1);
    let limit = options.basis_limit.max(2);
    let davidson = matches!(expansion, Expansion::Precondition(_));
    let mut solves = 0;
    // Set once a step changed the estimate by at most the tolerance while the residual
    // test was still to pass: the scale the residual is measured against.
    let mut settled_at: Option<f64> = None;
    // The Ritz pair's coordinates before the newest basis vector was added.
    let mut previous: Vec<c64> = Vec::new();
    loop {
        if solves >= max_solves {
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        }
        if space.basis.len() >= limit {
            let previous = std::mem::take(&mut previous);
            let x = normalised(space.combine(&estimate.1))?;
            (space, estimate) =
                restarted(&space, x, estimate, previous, davidson, mass, &apply_matrix)?;
        }
        // The Ritz pair's residual, when the value has settled or Davidson grows by it.
        let residual = (davidson || settled_at.is_some())
            .then(|| space.residual(mass, estimate.0, &estimate.1));
        if let (Some(scale), Some(r), Some(bound)) = (settled_at, &residual, options.residual)
            && norm2(mass, r, true).sqrt() <= bound * scale
        {
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        }
        let w = expansion.grow(&space, mass, &estimate, residual)?;
        solves += 1;
        let Some(w) = orthonormalised(mass, &space.basis, w)? else {
            // The space stopped growing: the estimate is exact for it.
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        };
        space.push(w, &apply_matrix);
        // The change of a step bounds the error of the step before; with the
        // superlinear convergence of Krylov methods the last step's error is much
        // smaller (see LAMBDA_TOLERANCE for the bunny's numbers).
        let next = smallest_pair(&space.h).ok_or_else(failed)?;
        let scale = next.0.abs().max(options.floor);
        let settled = (next.0 - estimate.0).abs() <= options.tolerance * scale;
        previous = std::mem::replace(&mut estimate, next).1;
        settled_at = settled.then_some(scale);
        if settled && options.residual.is_none() {
            return Ok((estimate.0, phased(space.combine(&estimate.1)), solves));
        }
    }
}

impl<I, P, E> Expansion<I, P>
where
    I: FnMut(&mut [c64]) -> Result<(), E>,
    P: FnMut(&[c64], &mut [c64]),
{
    /// The next direction of the space: `T` applied to the newest basis vector, or the
    /// preconditioned `residual` of the Ritz pair `estimate` (computed here when not
    /// given).
    fn grow(
        &mut self,
        space: &Space,
        mass: &[f64],
        estimate: &(f64, Vec<c64>),
        residual: Option<Vec<c64>>,
    ) -> Result<Vec<c64>, E> {
        Ok(match self {
            Expansion::Precondition(precondition) => {
                let r = residual.unwrap_or_else(|| space.residual(mass, estimate.0, &estimate.1));
                let mut w = vec![c64::new(0.0, 0.0); r.len()];
                precondition(&r, &mut w);
                w
            }
            Expansion::Inverse(apply_inverse) => {
                let mut w = space.basis[space.basis.len() - 1].clone();
                apply_inverse(&mut w)?;
                w
            }
        })
    }
}

/// The space restarted from the Ritz vector `x` (`M`-normalised; its estimate is
/// unchanged) of `space`; Davidson also keeps the Ritz vector before it (in the current
/// basis: `previous`, the Ritz pair's coordinates before the newest basis vector, and
/// a zero). Returns the new space and its Ritz pair.
fn restarted(
    space: &Space,
    x: Vec<c64>,
    mut estimate: (f64, Vec<c64>),
    mut previous: Vec<c64>,
    davidson: bool,
    mass: &[f64],
    apply_matrix: &impl Fn(&[c64]) -> Vec<c64>,
) -> Result<(Space, (f64, Vec<c64>)), LinalgError> {
    let older = (davidson && previous.len() + 1 == space.basis.len()).then(|| {
        previous.push(c64::new(0.0, 0.0));
        space.combine(&previous)
    });
    let mut space = Space::new(x, apply_matrix);
    estimate.1 = vec![c64::new(1.0, 0.0)];
    if let Some(w) = older.and_then(|w| orthonormalised(mass, &space.basis, w).ok()?) {
        space.push(w, apply_matrix);
        estimate = smallest_pair(&space.h).ok_or_else(failed)?;
    }
    Ok((space, estimate))
}

/// A zero or non-finite start or iterate (a failed solve).
fn failed() -> LinalgError {
    LinalgError::Iterate
}

/// `w` made `M`-orthogonal to the (`M`-orthonormal) `basis` by classical Gram-Schmidt
/// twice (enough for a few dozen vectors) and `M`-normalised; `None` when nothing of it
/// is left outside the basis.
///
/// Errors: a non-finite `w`.
fn orthonormalised(
    mass: &[f64],
    basis: &[Vec<c64>],
    mut w: Vec<c64>,
) -> Result<Option<Vec<c64>>, LinalgError> {
    let before = norm2(mass, &w, false).sqrt();
    for _ in 0..2 {
        let c = inners(Some(mass), basis, &w);
        add_combination(&mut w, basis, &c, -1.0);
    }
    let b = norm2(mass, &w, false).sqrt();
    if !(b.is_finite() && before.is_finite()) {
        return Err(failed());
    }
    if b <= 1e-10 * before {
        return Ok(None);
    }
    w.par_iter_mut().for_each(|z| *z /= b);
    Ok(Some(w))
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
                    Ok::<(), LinalgError>(())
                },
                |x| x.iter().zip(&self.a).map(|(x, a)| *x * *a).collect(),
            )
            .map(|(value, _, solves)| (value, solves))
            .expect("valid test input")
        }
    }

    impl Pencil {
        /// [`smallest_eigenpair_preconditioned`] with the diagonal preconditioner
        /// `B^-1 = diag(inverse)`.
        fn davidson(
            &self,
            start: Vec<c64>,
            options: KrylovOptions,
            inverse: &[f64],
        ) -> (f64, Vec<c64>, usize) {
            smallest_eigenpair_preconditioned(
                &self.m,
                start,
                options,
                |r, z| {
                    for ((z, r), b) in z.iter_mut().zip(r).zip(inverse) {
                        *z = *r * *b;
                    }
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
                    Ok::<(), LinalgError>(())
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
            let c = inners(Some(&pencil.m), std::slice::from_ref(&start), &x)[0];
            assert!(c.re > 0.0 && c.im.abs() < 1e-9 * c.re, "{basis_limit}: {c}");
            println!("basis {basis_limit}: {solves} solves");
        }
    }

    #[test]
    fn a_rough_preconditioner_finds_the_same_pair_from_above_across_thick_restarts() {
        let pencil = Pencil::new(400);
        let start: Vec<c64> = (0..400)
            .map(|k| c64::new(((k * 31) % 17) as f64 - 8.0, ((k * 11) % 7) as f64 - 3.0))
            .collect();
        // B^-1 off the exact inverse of A + sigma M by up to a factor of 3 per entry.
        let rough: Vec<f64> = (0..400)
            .map(|k| {
                (1.0 + 2.0 * ((k * 7919) % 100) as f64 / 99.0)
                    / (pencil.a[k] + pencil.sigma * pencil.m[k])
            })
            .collect();
        let mut counts = Vec::new();
        for basis_limit in [3, 8, 64] {
            let options = KrylovOptions {
                max_solves: 400,
                tolerance: 1e-12,
                floor: 0.0,
                basis_limit,
                residual: Some(1e-6),
            };
            let (value, x, solves) = pencil.davidson(start.clone(), options, &rough);
            assert!(solves < 400, "{basis_limit}: did not converge");
            assert!(
                value >= 2.0 - 1e-12 && value - 2.0 < 1e-9,
                "{basis_limit}: {value}"
            );
            let off: f64 = x[1..]
                .iter()
                .zip(&pencil.m[1..])
                .map(|(z, m)| z.norm_sqr() * m)
                .sum();
            assert!(off < 1e-10, "{basis_limit}: {off} off the eigenvector");
            let c = inners(Some(&pencil.m), std::slice::from_ref(&start), &x)[0];
            assert!(c.re > 0.0 && c.im.abs() < 1e-9 * c.re, "{basis_limit}: {c}");
            counts.push(solves);
        }
        println!("preconditioner applications for bases 3, 8, 64: {counts:?}");
        // Keeping the previous Ritz vector at a restart keeps even a basis of 3 close
        // to the unrestarted space.
        assert!(counts[0] <= 2 * counts[2], "{counts:?}");
    }

    #[test]
    fn the_estimates_fall_and_stay_above_with_a_rough_preconditioner() {
        let pencil = Pencil::new(300);
        let start: Vec<c64> = (0..300)
            .map(|k| c64::new(1.0 + (k % 5) as f64, (k % 3) as f64))
            .collect();
        let rough: Vec<f64> = (0..300)
            .map(|k| (0.5 + (k % 4) as f64 * 0.5) / pencil.a[k])
            .collect();
        let mut previous = f64::INFINITY;
        let mut values = Vec::new();
        for max in [1, 2, 4, 8, 16, 32] {
            let options = KrylovOptions {
                max_solves: max,
                tolerance: 0.0,
                floor: 0.0,
                basis_limit: 4,
                residual: None,
            };
            let (value, _, solves) = pencil.davidson(start.clone(), options, &rough);
            assert_eq!(solves, max);
            assert!(value >= 2.0 - 1e-12, "{max}: {value}");
            assert!(
                value <= previous + 1e-9,
                "{max}: {value} rose from {previous}"
            );
            previous = value;
            values.push(value);
        }
        println!("estimates after 1, 2, 4, 8, 16, 32 applications: {values:?}");
        assert!(previous - 2.0 < 1e-3, "32 applications: {previous}");
    }

    #[test]
    fn block_sums_do_not_depend_on_the_thread_count() {
        let n = 3 * BLOCK_ROWS + 17;
        let v: Vec<Vec<c64>> = (0..3)
            .map(|j| {
                (0..n)
                    .map(|i| c64::new(((i * (j + 3)) % 101) as f64 / 7.0, ((i + j) % 13) as f64))
                    .collect()
            })
            .collect();
        let w: Vec<c64> = (0..n)
            .map(|i| c64::new((i % 29) as f64, -((i % 31) as f64)))
            .collect();
        let m: Vec<f64> = (0..n).map(|i| 0.5 + (i % 3) as f64).collect();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| {
                    let mut x = w.clone();
                    add_combination(&mut x, &v, &inners(Some(&m), &v, &w), -1.0);
                    (inners(None, &v, &w), norm2(&m, &x, true), x)
                })
        };
        let one = run(1);
        assert_eq!(one, run(3));
        // And they are the sums they claim to be.
        for (j, vj) in v.iter().enumerate() {
            let direct: c64 = vj.iter().zip(&w).map(|(a, b)| a.conj() * b).sum();
            assert!((direct - one.0[j]).norm() < 1e-9 * direct.norm(), "{j}");
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
        let refused = smallest_eigenpair(
            &pencil.m,
            zero,
            options,
            |_| Ok::<(), LinalgError>(()),
            |x| x.to_vec(),
        );
        assert!(refused.is_err());
    }
}
