//! Errors of the field stage: building a field ([`FieldError`]) and designing a line
//! field ([`LineFieldError`], which a designed field's error wraps).

use std::path::PathBuf;

use crate::linalg::LinalgError;

/// Everything that can go wrong building a [`TensorField`](super::TensorField).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FieldError {
    /// The number of tensors differs from the number of mesh vertices.
    #[error("field has {found} values but the mesh has {expected} vertices")]
    CountMismatch {
        /// Mesh vertex count.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A tensor has a NaN or infinite entry.
    #[error("tensor at vertex {vertex} has a non-finite entry")]
    NonFinite {
        /// Vertex index.
        vertex: usize,
    },
    /// A tensor is not symmetric.
    #[error("tensor at vertex {vertex} is not symmetric (largest asymmetry {asymmetry:e})")]
    NotSymmetric {
        /// Vertex index.
        vertex: usize,
        /// Largest |T_ij - T_ji|.
        asymmetry: f64,
    },
    /// A tensor is not positive definite in the tangent plane.
    #[error(
        "tensor at vertex {vertex} is not positive definite in its tangent plane (eigenvalues {l1}, {l2})"
    )]
    NotPositiveDefinite {
        /// Vertex index.
        vertex: usize,
        /// Largest eigenvalue in the plane.
        l1: f64,
        /// Smallest eigenvalue in the plane.
        l2: f64,
    },
    /// A tensor's eigenvalues lie outside [`EIGENVALUE_RANGE`](super::EIGENVALUE_RANGE).
    #[error(
        "tensor at vertex {vertex} has eigenvalues {l1:.3e} and {l2:.3e}, outside the supported \
         range [1e-100, 1e100]; densities are relative, so scale every density of the field \
         by one factor into it"
    )]
    OutOfRange {
        /// Vertex index.
        vertex: usize,
        /// Largest eigenvalue in the plane.
        l1: f64,
        /// Smallest eigenvalue in the plane.
        l2: f64,
    },
    /// A field parameter is out of its valid range.
    #[error("field parameter `{parameter}` = {value} is invalid: {expected}")]
    InvalidParameter {
        /// The parameter's name as in the config.
        parameter: &'static str,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// A field file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A field file is malformed.
    #[error("{path}:{line}: {what}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// A well-formed line of a field file holds a value that is not a valid tensor
    /// (NaN, a non-positive eigenvalue, a zero direction, a tensor that is not positive
    /// definite in the vertex's tangent plane).
    #[error("{path}:{line}: vertex {vertex}: {what}")]
    BadValue {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The vertex in the mesh file's order (0-based), i.e. the data line's rank.
        vertex: usize,
        /// What is wrong.
        what: String,
    },
    /// A vertex lies where an analytic field source is undefined (for example beyond
    /// the horizon of a perspective map).
    #[error("vertex {vertex} lies outside the domain of the field source: {what} (value {value})")]
    OutsideDomain {
        /// Mesh vertex index.
        vertex: usize,
        /// The offending quantity at that vertex.
        value: f64,
        /// What must hold, in words.
        what: &'static str,
    },
    /// The designed field's line-field solve failed (see [`LineFieldError`]).
    #[error("field design: {0}")]
    Design(#[from] LineFieldError),
}

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
        "constraint {index} at vertex {vertex}: the direction is not finite or lies within 1 degree of the surface normal there, so it gives no line along the surface; give a direction in the tangent plane"
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
    /// The smoothest field's eigenvalue came out negative: the energy is not positive
    /// semi-definite (the paper's cotangent weights are negative across obtuse
    /// corners). The solvers then solve the piece again with floored weights, so this
    /// is not returned by them.
    #[error("the line-field energy is not positive semi-definite (eigenvalue {eigenvalue:e})")]
    Indefinite {
        /// The negative Rayleigh quotient found.
        eigenvalue: f64,
    },
    /// The multigrid-preconditioned solve failed (see [`LinearSolver`](crate::field::LinearSolver)),
    /// or the eigenvalue iteration met a zero or non-finite iterate.
    #[error("line-field multigrid solve failed: {0}")]
    Multigrid(crate::linalg::LinalgError),
}

impl LineFieldError {
    /// Whether the error says a system of the energy was not positive definite: a
    /// failed numeric Cholesky factorization, conjugate gradients meeting negative
    /// curvature or not converging, a multigrid hierarchy's coarse factor failing, or
    /// a negative eigenvalue.
    pub(crate) fn not_definite(&self) -> bool {
        match self {
            Self::Factorization { stage } => stage.starts_with("numeric factorization"),
            Self::Indefinite { .. } => true,
            Self::Multigrid(e) => matches!(
                e,
                LinalgError::Indefinite { .. }
                    | LinalgError::NotPositiveDefinite { .. }
                    | LinalgError::NotConverged { .. }
            ),
            _ => false,
        }
    }
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
