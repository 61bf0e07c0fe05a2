//! The line-field types shared by the solver (`solve.rs`) and its system
//! (`connection.rs`): the result [`LineField`], the choice of [`LinearSolver`] and the
//! solvers' constants. Kept below both so neither depends on the other.

use glam::DVec3;

use crate::field::{FieldError, TensorField};
use crate::mesh::TriMesh;

/// Floor of the cotangent edge weights (dimensionless) where the energy is built with
/// floored weights: with a smoothed connection, and on a piece whose energy under the
/// paper's weights is not positive definite (see the [module docs](super)).
pub const MIN_EDGE_WEIGHT: f64 = 1e-3;

/// Which cotangent edge weights a piece's energy is built with
/// ([`LineFieldOptions::weights`](crate::field::design::LineFieldOptions::weights); see
/// the [module docs](super)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum EdgeWeights {
    /// The paper's cotangent weights as they are (negative across obtuse corners) where
    /// the connection is not smoothed and the piece's energy stays positive definite
    /// under them; else the floored ones.
    #[default]
    Cotan,
    /// The cotangent weights floored at [`MIN_EDGE_WEIGHT`] on every piece: positive,
    /// so the energy is positive semi-definite under any connection.
    Floored,
}

impl EdgeWeights {
    /// The weights a piece's first solve uses when `self` is asked for: the floored
    /// ones with a smoothed connection (`smoothing > 0`) whatever is asked.
    pub(crate) fn first(self, smoothing: f64) -> Self {
        if smoothing > 0.0 { Self::Floored } else { self }
    }
}

/// Most conjugate-gradient iterations of one multigrid-preconditioned solve (a mesh
/// needs 10 to 25; more means the system is nearly singular).
pub(crate) const MAX_CG_ITERATIONS: usize = 500;

/// Relative shift of the inverse power iteration: `sigma = SHIFT * tr(A) / tr(M)`.
pub const SHIFT: f64 = 1e-8;

/// Vertices from which [`LinearSolver::Auto`] switches from sparse Cholesky to
/// multigrid. A factor's fill grows faster than the mesh while multigrid's setup is
/// linear, and the hierarchy built to estimate `lambda_1` also preconditions the
/// shifted solve. `cargo run --release -p strata-bench --bin field_solvers` (the
/// designed fields of the shared meshes and their Loop subdivisions): from 25k
/// vertices multigrid is the faster on every mesh (the bunny, 35k vertices: 0.19 s
/// direct, 0.16-0.17 s by multigrid); below, the direct solver mostly is, or they
/// tie (the wing subdivided once, 20k: 0.09 s against 0.16 s; homer subdivided once,
/// 24k: 0.11 s either way), with exceptions (the fandisk and the spot subdivided
/// once).
pub const MULTIGRID_VERTICES: usize = 25_000;

/// Relative residual `|b - A x| / |b|` at which a multigrid-preconditioned solve
/// ([`LinearSolver::Multigrid`]) stops. The designed bunny field Loop-subdivided once
/// and twice moves by at most 0.0017 and 0.0005 degrees against a solve to 1e-8, with
/// the same singularities, for 2 to 5 fewer iterations of 21 (bench/README.md,
/// "Solver tolerances").
pub const SOLVE_TOLERANCE: f64 = 1e-6;

/// How the line-field solvers solve their sparse Hermitian systems.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum LinearSolver {
    /// [`Direct`](Self::Direct) below [`MULTIGRID_VERTICES`] vertices,
    /// [`Multigrid`](Self::Multigrid) from there (chosen per connected piece, by the
    /// piece's vertices: a scan's crumbs are factored).
    #[default]
    Auto,
    /// faer's sparse Cholesky: exact, but its fill and time grow faster than the mesh.
    Direct,
    /// Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid
    /// ([`crate::linalg`]): linear in the mesh, to a relative residual of
    /// [`SOLVE_TOLERANCE`].
    Multigrid,
}

/// A line field, the output of the solvers in [`design`](super): per vertex, a unit tangent direction (world space; its negation is the
/// same line) and the magnitude `|z_v|` of the solution.
#[derive(Clone, Debug, PartialEq)]
pub struct LineField {
    /// Unit direction per vertex, in the vertex's tangent plane (the first axis of the
    /// tangent frame where the magnitude is 0): the smoothed normal's plane with
    /// [`LineFieldOptions::smoothing`](crate::field::design::LineFieldOptions::smoothing), the
    /// mesh's own with pair cancellation
    /// ([`LineFieldOptions::cancel_distance`](crate::field::design::LineFieldOptions::cancel_distance)).
    pub directions: Vec<DVec3>,
    /// `|z_v|` per vertex: for the smoothest field with `sum_v m_v |z_v|^2 = 1` over
    /// each connected piece (each is normalised on its own); for a
    /// guided field about 1 where it follows confident guidance or a constraint, smaller
    /// where guidance is contradictory (near singularities).
    pub magnitudes: Vec<f64>,
    /// The smoothness energy `E(z) = z^H A z` of the solution, under the connection of
    /// the frames its directions are given in.
    pub energy: f64,
    /// The Rayleigh quotient `E(z) / (z^H M z)` (0 for a zero field); for the smoothest
    /// field of a mesh of one piece, the estimate of the smallest eigenvalue (of
    /// several pieces, the quotient of the whole field, between the pieces' smallest
    /// eigenvalues).
    pub rayleigh: f64,
    /// Solves (direct) or V-cycles (multigrid, one per Davidson step) done for the
    /// smoothest field, summed over the connected pieces (0 for a guided field).
    pub iterations: usize,
}

impl LineField {
    /// A tensor field whose major direction is this field's, with the per-vertex
    /// eigenvalues `[l1, l2]` (`l1 >= l2 > 0`; see [`TensorField::from_frames`]).
    pub fn to_tensor_field(
        &self,
        mesh: &TriMesh,
        eigenvalues: &[[f64; 2]],
    ) -> Result<TensorField, FieldError> {
        TensorField::from_frames(mesh, &self.directions, eigenvalues)
    }
}
