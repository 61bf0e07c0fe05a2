//! Tensor fields on meshes: per-vertex symmetric tensors in the tangent plane.
//!
//! A tensor `T = l1 m1 m1^T + l2 m2 m2^T` (world space, restricted to the tangent plane)
//! says how samples are spaced: the spacing along the unit eigenvector `m_k` is
//! proportional to `1 / sqrt(l_k)`, the density is `delta = sqrt(l1 l2)` (paper section
//! 3). Stored as full 3x3 matrices the field has no sign ambiguity and interpolates
//! linearly; eigenvectors are computed per use, in the plane of a triangle, by a
//! closed-form 2x2 decomposition ([`eigen_in_plane`]).
//!
//! Input: a mesh and a [`FieldSpec`] (or raw tensors). Output: a validated
//! [`TensorField`]. Cost: O(V) to build and validate, plus the source's own cost
//! (a file: its length; curvature: O(F + V * valence * smoothing)).
//!
//! Sources: constant, planar test functions (Gaussian blob, ramp, Balzer et al.'s
//! density; shear and perspective metrics via [`PlanarWarp`]), per-vertex tensors from
//! a file ([`read_field_file`]) and principal curvatures ([`principal_curvatures`]).
//! Field design ([`smoothest_line_field`], [`guided_line_field`]): smooth line fields
//! with few singularities (Knöppel et al. 2013).

mod curvature;
pub mod design;
mod eigen;
mod error;
mod file;
mod guidance;
mod isotropic;
mod params;
mod shading;
mod spec;
pub mod tangent_space;
#[cfg(feature = "serde")]
mod vec3_serde;
mod warp;

pub use curvature::{
    CurvatureMeasure, CurvatureNormalization, PrincipalCurvatures, principal_curvatures,
};
pub use design::{
    Anisotropy, Constraint, Density, Design, EdgeWeights, Guidance, LineConstraint, LineField,
    LineFieldOptions, LinearSolver, MULTIGRID_VERTICES, SOLVE_TOLERANCE, Site,
    constrained_line_field, guided_line_field, line_field_energy, smoothest_line_field,
};
pub use eigen::{
    Eigen2, eigen_2x2, eigen_in_plane, frame_angle, principal_axis, tangent_frame, vertex_frames,
};
pub use error::{FieldError, LineFieldError};
pub use file::{format_field_file, parse_field_file, read_field_file};
pub use guidance::{curvature_guidance, direction_guidance};
pub use isotropic::{
    ISOTROPIC_DIRECTION_RATIO, all_isotropic, isotropic_copy, isotropic_vertices,
    smooth_isotropic_directions,
};
pub use shading::{DEFAULT_LIGHT, shading_densities};
pub use spec::{FieldSpec, PlanarDensity};
pub use warp::PlanarWarp;

use glam::{DMat3, DVec3};

use crate::mesh::TriMesh;

/// Relative tolerance for the symmetry check of input tensors.
const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// Eigenvalues a field may have: [1e-100, 1e100]. Products of two eigenvalues (the
/// squared density) and their scaling by element areas must stay normal `f64`s through
/// preprocessing (a density of 1e300 overflowed the cells' measure, 1e-300 vanished).
/// Only relative densities matter to the samples, so any field scales into it.
pub const EIGENVALUE_RANGE: [f64; 2] = [1e-100, 1e100];

/// Whether eigenvalues `l1 >= l2` leave [`EIGENVALUE_RANGE`].
fn out_of_range(l1: f64, l2: f64) -> bool {
    let [lo, hi] = EIGENVALUE_RANGE;
    l1 > hi || l2 < lo
}

/// Checks a vertex's in-plane eigenvalues against [`EIGENVALUE_RANGE`] (`l2 > 0`
/// already holds).
fn check_range(vertex: usize, l1: f64, l2: f64) -> Result<(), FieldError> {
    if out_of_range(l1, l2) {
        return Err(FieldError::OutOfRange { vertex, l1, l2 });
    }
    Ok(())
}

/// Per-vertex symmetric tensors in each vertex's tangent plane, validated: finite,
/// symmetric and positive definite in the plane.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorField {
    tensors: Vec<DMat3>,
}

impl TensorField {
    /// Validates raw per-vertex tensors and restricts each to its vertex's tangent plane
    /// (`P T P` with `P = I - n n^T`).
    ///
    /// Errors name the first offending vertex: a count that differs from the mesh's
    /// vertex count, a non-finite entry, a non-symmetric tensor, one that is not
    /// positive definite in the tangent plane, or eigenvalues outside
    /// [`EIGENVALUE_RANGE`].
    pub fn new(mesh: &TriMesh, tensors: Vec<DMat3>) -> Result<Self, FieldError> {
        if tensors.len() != mesh.vertex_count() {
            return Err(FieldError::CountMismatch {
                expected: mesh.vertex_count(),
                found: tensors.len(),
            });
        }
        let mut out = Vec::with_capacity(tensors.len());
        for (vertex, (t, n)) in tensors.iter().zip(mesh.vertex_normals()).enumerate() {
            if !t.is_finite() {
                return Err(FieldError::NonFinite { vertex });
            }
            let asym = (*t - t.transpose())
                .abs()
                .to_cols_array()
                .into_iter()
                .fold(0.0, f64::max);
            let scale = t.abs().to_cols_array().into_iter().fold(0.0, f64::max);
            if asym > SYMMETRY_TOLERANCE * scale.max(f64::MIN_POSITIVE) {
                return Err(FieldError::NotSymmetric {
                    vertex,
                    asymmetry: asym,
                });
            }
            let p = DMat3::IDENTITY - outer(*n, *n);
            let restricted = p * *t * p;
            let e = eigen_in_plane(&restricted, *n);
            if !(e.l2 > 0.0) {
                return Err(FieldError::NotPositiveDefinite {
                    vertex,
                    l1: e.l1,
                    l2: e.l2,
                });
            }
            check_range(vertex, e.l1, e.l2)?;
            out.push(restricted);
        }
        Ok(Self { tensors: out })
    }

    /// Builds a field from a major direction per vertex (projected into the tangent
    /// plane) and the two eigenvalues per vertex (`l1 >= l2 > 0`).
    pub fn from_frames(
        mesh: &TriMesh,
        directions: &[DVec3],
        eigenvalues: &[[f64; 2]],
    ) -> Result<Self, FieldError> {
        if directions.len() != mesh.vertex_count() || eigenvalues.len() != mesh.vertex_count() {
            return Err(FieldError::CountMismatch {
                expected: mesh.vertex_count(),
                found: directions.len().min(eigenvalues.len()),
            });
        }
        let mut tensors = Vec::with_capacity(directions.len());
        for (vertex, ((d, [l1, l2]), n)) in directions
            .iter()
            .zip(eigenvalues)
            .zip(mesh.vertex_normals())
            .enumerate()
        {
            if !d.is_finite() || !l1.is_finite() || !l2.is_finite() {
                return Err(FieldError::NonFinite { vertex });
            }
            if !(*l1 > 0.0 && *l2 > 0.0) {
                return Err(FieldError::NotPositiveDefinite {
                    vertex,
                    l1: *l1,
                    l2: *l2,
                });
            }
            check_range(vertex, l1.max(*l2), l1.min(*l2))?;
            let m1 = project_direction(*d, *n);
            let m2 = n.cross(m1);
            tensors.push(outer(m1, m1) * *l1 + outer(m2, m2) * *l2);
        }
        Ok(Self { tensors })
    }

    /// The tensors, one per vertex.
    pub fn tensors(&self) -> &[DMat3] {
        &self.tensors
    }

    /// Density `sqrt(l1 l2)` at vertex `v`, computed in the vertex's tangent plane.
    pub fn vertex_density(&self, mesh: &TriMesh, v: u32) -> f64 {
        let e = eigen_in_plane(&self.tensors[v as usize], mesh.vertex_normals()[v as usize]);
        e.density()
    }

    /// Densities of all vertices.
    pub fn vertex_densities(&self, mesh: &TriMesh) -> Vec<f64> {
        (0..mesh.vertex_count() as u32)
            .map(|v| self.vertex_density(mesh, v))
            .collect()
    }

    /// The tensor linearly interpolated at barycentric coordinates `bary` of face `f`.
    pub fn interpolate(&self, mesh: &TriMesh, f: u32, bary: [f64; 3]) -> DMat3 {
        let t = mesh.triangles()[f as usize];
        self.tensors[t[0] as usize] * bary[0]
            + self.tensors[t[1] as usize] * bary[1]
            + self.tensors[t[2] as usize] * bary[2]
    }

    /// Eigen-decomposition of the interpolated tensor in the plane of face `f`.
    pub fn face_eigen(&self, mesh: &TriMesh, f: u32, bary: [f64; 3]) -> Eigen2 {
        eigen_in_plane(
            &self.interpolate(mesh, f, bary),
            mesh.face_normals()[f as usize],
        )
    }
}

/// The outer product `a b^T`.
pub fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Projects `d` into the plane with unit normal `n` and normalises it; where `d` is
/// (nearly) parallel to `n`, falls back to the first axis of [`tangent_frame`], so the
/// result is always a unit tangent.
pub fn project_direction(d: DVec3, n: DVec3) -> DVec3 {
    let t = d - n * d.dot(n);
    if t.length_squared() > 1e-12 * d.length_squared().max(f64::MIN_POSITIVE) {
        t.normalize()
    } else {
        tangent_frame(n).0
    }
}

#[cfg(test)]
mod tests;
