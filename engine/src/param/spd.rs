//! The sparse symmetric positive definite solve shared by the least-squares
//! parameterization ([`solve`](super::solve)) and the isotropic fallback frame
//! ([`comb`](super::comb)).
//!
//! Input: the lower triangle of a sparse SPD matrix and one or more right-hand-side
//! columns. Output: the solution columns, or [`ParamError::Solver`] naming the step that
//! failed. Cost: for the planar-like Laplacians of a segment (`n` unknowns) about
//! O(n^1.5) time and O(n log n) memory for the factorization, O(n log n) per column.
//! Kept below `solve` and `comb` so neither depends on the other for it.

use faer::Mat;
use faer::Side;
use faer::prelude::*;
use faer::sparse::SparseColMat;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};

use super::ParamError;

/// Solves `A x = rhs` for a sparse symmetric positive definite `A` given by its lower
/// triangle (sparse Cholesky: AMD ordering, symbolic then numeric factorization, one
/// solve for all right-hand-side columns; sequential).
pub(crate) fn solve_spd(
    matrix: &SparseColMat<usize, f64>,
    mut rhs: Mat<f64>,
) -> Result<Mat<f64>, ParamError> {
    let symbolic =
        SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).map_err(|_| ParamError::Solver {
            stage: "symbolic factorization",
        })?;
    let llt = Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower).map_err(|_| {
        ParamError::Solver {
            stage: "numeric factorization (matrix not positive definite)",
        }
    })?;
    llt.solve_in_place(rhs.as_mut());
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
        let x = solve_spd(&matrix, rhs).expect("solve");
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
        let err = solve_spd(&matrix, Mat::<f64>::zeros(2, 1)).expect_err("indefinite");
        assert!(
            matches!(err, ParamError::Solver { stage } if stage.starts_with("numeric")),
            "{err:?}"
        );
    }
}
