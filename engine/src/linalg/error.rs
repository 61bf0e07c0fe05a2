//! The one error type of the linear algebra ([`LinalgError`]): sparse Cholesky,
//! conjugate gradients, multigrid and the Rayleigh-Ritz eigensolver report it, and each
//! stage maps it into its own error.

/// Why a solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinalgError {
    /// The matrix (or the coarsest level of its hierarchy) is not positive definite.
    #[error("matrix not positive definite (pivot {pivot})")]
    NotPositiveDefinite {
        /// The row where it showed.
        pivot: usize,
    },
    /// Conjugate gradients met a direction of non-positive curvature: the matrix is
    /// not positive definite.
    #[error("conjugate gradients found the matrix indefinite at iteration {iteration}")]
    Indefinite {
        /// The iteration where it showed.
        iteration: usize,
    },
    /// The iteration budget ran out before the tolerance was met.
    #[error(
        "conjugate gradients reached relative residual {residual:.2e} after {iterations} iterations (asked {tolerance:.2e})"
    )]
    NotConverged {
        /// Iterations taken.
        iterations: usize,
        /// The relative residual reached.
        residual: f64,
        /// The relative residual asked for.
        tolerance: f64,
    },
    /// A non-finite value appeared (a non-finite input or an overflow).
    #[error("non-finite value in a solve")]
    NonFinite,
    /// A sparse Cholesky step failed (symbolic or numeric factorization, or its memory).
    #[error("sparse Cholesky failed in the {stage}")]
    Factorization {
        /// The step that failed, in words.
        stage: &'static str,
    },
    /// The eigensolver met a zero or non-finite start or iterate (a failed solve).
    #[error("eigenvalue iteration met a zero or non-finite iterate")]
    Iterate,
    /// The coarsening stopped with more unknowns than a dense factor can take.
    #[error("multigrid coarsening stalled at {unknowns} unknowns")]
    Coarsening {
        /// Unknowns at the level where it stalled.
        unknowns: usize,
    },
}
