//! The sparse symmetric positive definite solve shared by the least-squares
//! parameterization ([`solve`](super::solve)) and the isotropic fallback frame
//! ([`comb`](super::comb)).
//!
//! Input: the lower triangle of a sparse SPD matrix and one or more right-hand-side
//! columns. Output: the solution columns, or [`ParamError::Solver`] naming the step that
//! failed. Cost: for the planar-like Laplacians of a segment (`n` unknowns) about
//! O(n^1.5) time and O(n log n) memory for the factorization, O(n log n) per column;
//! the ordering is approximate minimum degree, or from [`DISSECTION_UNKNOWNS`]
//! unknowns nested dissection by the unknowns' positions, which costs less to compute
//! on large segments.
//! Kept below `solve` and `comb` so neither depends on the other for it.

use std::sync::Arc;

use faer::perm::PermRef;
use faer::sparse::SparseColMat;
use faer::sparse::linalg::cholesky::{SymmetricOrdering, factorize_symbolic_cholesky};
use faer::{Mat, Side};
use glam::DVec3;

use super::ParamError;
use crate::linalg::LinalgError;
use crate::linalg::cholesky::Cholesky;
use crate::linalg::dissection::nested_dissection;

/// From this many unknowns a system whose unknowns have positions is ordered by nested
/// dissection ([`nested_dissection`]) rather than approximate minimum degree: on the
/// stiffness matrices of segments of the bunny Loop-subdivided twice the ordering and
/// symbolic factorization take 0.14 s against 0.37 s at 347k unknowns, with about 10%
/// more fill, and the whole solve is faster from about 10k unknowns (bench/README.md,
/// "Nested dissection"). Below it AMD's orderings are kept as they were.
pub(crate) const DISSECTION_UNKNOWNS: usize = 10_000;

/// Solves `A x = rhs` for a sparse symmetric positive definite `A` given by its lower
/// triangle (sparse Cholesky: symbolic then numeric factorization, one solve for all
/// right-hand-side columns; sequential). `points`, one per unknown, allow a nested
/// dissection ordering from [`DISSECTION_UNKNOWNS`] unknowns; otherwise the ordering
/// is approximate minimum degree.
pub(crate) fn solve_spd(
    matrix: &SparseColMat<usize, f64>,
    mut rhs: Mat<f64>,
    points: Option<&[DVec3]>,
) -> Result<Mat<f64>, ParamError> {
    let pattern = matrix.symbolic();
    let n = pattern.nrows();
    let dissection = points
        .filter(|p| n >= DISSECTION_UNKNOWNS && p.len() == n)
        .map(|p| nested_dissection(p, pattern.col_ptr(), pattern.row_idx()));
    let ordering = match &dissection {
        Some((forward, inverse)) => {
            SymmetricOrdering::Custom(PermRef::new_checked(forward, inverse, n))
        }
        None => SymmetricOrdering::Amd,
    };
    let symbolic = factorize_symbolic_cholesky(pattern, Side::Lower, ordering, Default::default())
        .map_err(|_| ParamError::Solver {
            stage: "symbolic factorization",
        })?;
    // The numeric factorization and the solve are the shared `linalg::cholesky`.
    let solver = |e: LinalgError| ParamError::Solver {
        stage: match e {
            LinalgError::Factorization { stage } => stage,
            _ => "numeric factorization",
        },
    };
    let mut factor = Cholesky::new(Arc::new(symbolic), matrix.as_ref(), None).map_err(solver)?;
    factor.solve(rhs.as_mut()).map_err(solver)?;
    Ok(rhs)
}

#[cfg(test)]
mod tests {
    use faer::sparse::Triplet;

    use super::*;

    fn lower(n: usize, entries: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let triplets: Vec<_> = entries
            .iter()
            .map(|&(r, c, v)| Triplet::new(r, c, v))
            .collect();
        SparseColMat::try_new_from_triplets(n, n, &triplets).expect("matrix")
    }

    #[test]
    fn solves_every_column_of_a_small_spd_system() {
        // A = [[4, 1], [1, 3]], A^-1 = [[3, -1], [-1, 4]] / 11.
        let matrix = lower(2, &[(0, 0, 4.0), (1, 0, 1.0), (1, 1, 3.0)]);
        let mut rhs = Mat::<f64>::zeros(2, 2);
        rhs[(0, 0)] = 1.0;
        rhs[(1, 0)] = 2.0;
        rhs[(0, 1)] = 4.0;
        rhs[(1, 1)] = 1.0;
        let x = solve_spd(&matrix, rhs, None).expect("solve");
        let expected = [[1.0 / 11.0, 7.0 / 11.0], [1.0, 0.0]];
        for (c, column) in expected.iter().enumerate() {
            for (r, want) in column.iter().enumerate() {
                assert!(
                    (x[(r, c)] - want).abs() < 1e-14,
                    "x[{r}, {c}] = {} != {want}",
                    x[(r, c)]
                );
            }
        }
    }

    #[test]
    fn indefinite_matrix_fails_in_the_numeric_factorization() {
        let matrix = lower(2, &[(0, 0, 1.0), (1, 1, -1.0)]);
        let err = solve_spd(&matrix, Mat::<f64>::zeros(2, 1), None).expect_err("indefinite");
        assert!(
            matches!(err, ParamError::Solver { stage } if stage.starts_with("numeric")),
            "{err:?}"
        );
    }
}
