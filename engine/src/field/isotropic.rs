//! The isotropic copy of a field: the same density, no anisotropy.
//!
//! Input: a mesh and a [`TensorField`]. Output: the field whose tensor at each vertex
//! is its density `sqrt(l1 l2)` times the identity of the tangent plane. The surface
//! pipeline samples segments too small to split further with it (paper section 5.2's
//! fallback). Cost: O(V).

use glam::DVec3;

use super::{FieldError, TensorField, tangent_frame};
use crate::mesh::TriMesh;

/// The field with each tensor replaced by its density times the identity of the
/// tangent plane.
pub fn isotropic_copy(mesh: &TriMesh, field: &TensorField) -> Result<TensorField, FieldError> {
    let density = field.vertex_densities(mesh);
    let dirs: Vec<DVec3> = mesh
        .vertex_normals()
        .iter()
        .map(|n| tangent_frame(*n).0)
        .collect();
    let ev: Vec<[f64; 2]> = density.iter().map(|&d| [d, d]).collect();
    TensorField::from_frames(mesh, &dirs, &ev)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::shapes;

    #[test]
    fn the_isotropic_copy_keeps_the_density_and_drops_the_anisotropy() {
        let mesh = shapes::sphere(1.0, 4).expect("sphere");
        let field = FieldSpec::Constant {
            direction: [1.0, 0.3, 0.2],
            anisotropy: 4.0,
            density: 2.5,
        }
        .build(&mesh)
        .expect("field");
        let iso = isotropic_copy(&mesh, &field).expect("copy");
        let before = field.vertex_densities(&mesh);
        let after = iso.vertex_densities(&mesh);
        for (v, (a, b)) in before.iter().zip(&after).enumerate() {
            assert!((a - b).abs() <= 1e-12 * a, "vertex {v}: density {a} -> {b}");
        }
        // Each tensor is its density times the tangent plane's identity.
        for (v, (t, n)) in iso.tensors().iter().zip(mesh.vertex_normals()).enumerate() {
            let expected = (glam::DMat3::IDENTITY - crate::field::outer(*n, *n)) * before[v];
            let error = (*t - expected)
                .abs()
                .to_cols_array()
                .into_iter()
                .fold(0.0, f64::max);
            assert!(
                error < 1e-9 * before[v],
                "vertex {v}: {t} against {expected}"
            );
        }
    }
}
