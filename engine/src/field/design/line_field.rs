//! The line-field types shared by the solver ([`design`](super::design)) and its
//! system (`connection.rs`): the result [`LineField`], the error [`LineFieldError`]
//! and the floor of the edge weights. Kept below both so neither depends on the other.

use glam::DVec3;

use super::{FieldError, TensorField};
use crate::linalg::LinalgError;
use crate::mesh::TriMesh;

/// Floor of the cotangent edge weights (dimensionless).
pub const MIN_EDGE_WEIGHT: f64 = 1e-3;

/// Everything that can go wrong designing a line field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LineFieldError {
    /// The mesh has no vertices or no area.
    #[error("the mesh has no vertices or zero area")]
    EmptyMesh,
    /// The guidance has a different length from the mesh's vertex count.
    #[error("guidance has {found} values but the mesh has {expected} vertices")]
    GuidanceLength {
        /// Mesh vertex count.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A guidance vector has a NaN or infinite coordinate.
    #[error("guidance at vertex {vertex} is not finite")]
    NonFiniteGuidance {
        /// Vertex index.
        vertex: usize,
    },
    /// A constraint names a vertex the mesh does not have.
    #[error("constraint {index} names vertex {vertex}, but the mesh has {vertices} vertices")]
    ConstraintVertex {
        /// Position of the constraint in the list.
        index: usize,
        /// The vertex it names.
        vertex: u32,
        /// Mesh vertex count.
        vertices: usize,
    },
    /// A constraint's direction is not finite or has no part in the tangent plane.
    #[error(
        "constraint {index} at vertex {vertex}: the direction is not finite or is normal to the surface"
    )]
    ConstraintDirection {
        /// Position of the constraint in the list.
        index: usize,
        /// Its vertex.
        vertex: u32,
    },
    /// Two constraints fix the same vertex.
    #[error("constraints {first} and {second} both fix vertex {vertex}")]
    DuplicateConstraint {
        /// The earlier constraint.
        first: usize,
        /// The later one.
        second: usize,
        /// The vertex both fix.
        vertex: u32,
    },
    /// A setting is out of its range.
    #[error("line-field option `{option}` = {value} is invalid: {expected}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// The sparse solve failed.
    #[error("line-field solve failed in the {stage}")]
    Factorization {
        /// The step that failed.
        stage: &'static str,
    },
    /// The multigrid-preconditioned solve failed (see [`LinearSolver`](super::LinearSolver)),
    /// or the eigenvalue iteration met a zero or non-finite iterate.
    #[error("line-field multigrid solve failed: {0}")]
    Multigrid(crate::linalg::LinalgError),
}

impl From<LinalgError> for LineFieldError {
    /// A failed sparse Cholesky step is [`Factorization`](Self::Factorization) with its
    /// step; everything else (conjugate gradients, multigrid, the eigenvalue iteration)
    /// is [`Multigrid`](Self::Multigrid).
    fn from(e: LinalgError) -> Self {
        match e {
            LinalgError::Factorization { stage } => Self::Factorization { stage },
            LinalgError::Iterate => Self::Factorization {
                stage: "solve (eigenvalue estimate: zero or non-finite iterate)",
            },
            other => Self::Multigrid(other),
        }
    }
}

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
    /// [`Multigrid`](Self::Multigrid) from there.
    #[default]
    Auto,
    /// faer's sparse Cholesky: exact, but its fill and time grow faster than the mesh.
    Direct,
    /// Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid
    /// ([`crate::linalg`]): linear in the mesh, to a relative residual of
    /// [`SOLVE_TOLERANCE`].
    Multigrid,
}

/// A line field, the output of the solvers in [`design`](super::design): per vertex, a unit tangent direction (world space; its negation is the
/// same line) and the magnitude `|z_v|` of the solution.
#[derive(Clone, Debug, PartialEq)]
pub struct LineField {
    /// Unit direction per vertex, in the vertex's tangent plane (the first axis of the
    /// tangent frame where the magnitude is 0): the smoothed normal's plane with
    /// [`LineFieldOptions::smoothing`](super::LineFieldOptions::smoothing), the
    /// mesh's own with pair cancellation
    /// ([`LineFieldOptions::cancel_distance`](super::LineFieldOptions::cancel_distance)).
    pub directions: Vec<DVec3>,
    /// `|z_v|` per vertex: for the smoothest field with `sum_v m_v |z_v|^2 = 1`; for a
    /// guided field about 1 where it follows confident guidance or a constraint, smaller
    /// where guidance is contradictory (near singularities).
    pub magnitudes: Vec<f64>,
    /// The smoothness energy `E(z) = z^H A z` of the solution, under the connection of
    /// the frames its directions are given in.
    pub energy: f64,
    /// The Rayleigh quotient `E(z) / (z^H M z)` (0 for a zero field); for the smoothest
    /// field, the estimate of the smallest eigenvalue.
    pub rayleigh: f64,
    /// Solves (direct) or V-cycles (multigrid, one per Davidson step) done for the
    /// smoothest field (0 for a guided field).
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
