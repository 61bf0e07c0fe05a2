//! Isotropic fields and regions.
//!
//! - [`isotropic_copy`]: the field whose tensor at each vertex is its density
//!   `sqrt(l1 l2)` times the identity of the tangent plane. The surface pipeline
//!   samples segments too small to split further with it (paper section 5.2's
//!   fallback). Cost: O(V).
//! - [`smooth_isotropic_directions`]: where a tensor is (nearly) isotropic its
//!   eigenvectors are undefined, and whatever the eigen-solver returns is noise that the
//!   segmentation would read as thousands of singularities. The paper leaves isotropic
//!   regions to "previous methods" (section 3) and names their over-segmentation as a
//!   limitation (section 8). Here they take the smoothest line field through the
//!   anisotropic vertices' directions ([`constrained_line_field`], over the solver of
//!   [`design`](super::design)), which keeps each density and changes each tensor by
//!   at most its small anisotropy (or [`ISOTROPIC_DIRECTION_RATIO`]): the segmentation then
//!   sees only the singularities the surface's topology and the anisotropic field
//!   force. Cost: one sparse solve (the smoothest field's eigen-solve on a fully
//!   isotropic field), nothing when no vertex is isotropic.

use glam::DVec3;

use super::design::{
    LineConstraint, LineFieldOptions, constrained_line_field, smoothest_line_field,
};
use super::{Eigen2, FieldError, TensorField, eigen_in_plane, tangent_frame};
use crate::mesh::TriMesh;

/// Relative change of the Rayleigh quotient at which the smoothest field of a fully
/// isotropic field stops iterating: any smooth field will do there, so the smoothest
/// one need not be converged to the solver's default 1e-8.
const ISOTROPIC_TOLERANCE: f64 = 1e-4;

/// The spacing ratio `sqrt(l1 / l2)` that [`smooth_isotropic_directions`] gives a
/// vertex less anisotropic than it, along the smooth direction, with its density
/// `sqrt(l1 l2)` unchanged. An exactly isotropic tensor cannot hold a direction, and
/// the tensors interpolated across a face mix tangent planes a few degrees apart,
/// which alone makes them slightly anisotropic along the mesh's creases (of the order
/// of the squared angle between neighbouring normals; an estimate, not measured). The
/// floor must beat that, measured on the isotropic bunny: 17,791 singular faces and
/// 3,506 segments without it, 7 and 36 with 1.01, 7 and 42 with 1.03; 1.02 leaves
/// margin for rougher meshes. Sample spacing then differs by 2% between the two
/// directions.
pub const ISOTROPIC_DIRECTION_RATIO: f64 = 1.02;

/// Per vertex, whether its tensor's spacing ratio `sqrt(l1 / l2)` is under
/// `threshold` (a degenerate tensor counts as isotropic): the vertices
/// [`smooth_isotropic_directions`] gives a smooth direction.
pub fn isotropic_vertices(mesh: &TriMesh, field: &TensorField, threshold: f64) -> Vec<bool> {
    is_isotropic(&eigens(mesh, field), threshold)
}

/// Whether every vertex's spacing ratio `sqrt(l1 / l2)` is under `threshold` (as
/// [`isotropic_vertices`] would say of each), stopping at the first vertex that is not:
/// nearly free for an anisotropic field.
pub fn all_isotropic(mesh: &TriMesh, field: &TensorField, threshold: f64) -> bool {
    let ratio2 = threshold * threshold;
    field
        .tensors()
        .iter()
        .zip(mesh.vertex_normals())
        .all(|(t, n)| {
            let e = eigen_in_plane(t, *n);
            !(e.l1 >= ratio2 * e.l2)
        })
}

/// The in-plane eigen-decomposition of every vertex tensor.
pub(super) fn eigens(mesh: &TriMesh, field: &TensorField) -> Vec<Eigen2> {
    field
        .tensors()
        .iter()
        .zip(mesh.vertex_normals())
        .map(|(t, n)| eigen_in_plane(t, *n))
        .collect()
}

/// Per decomposition, whether its spacing ratio is under `threshold` (NaN-safe: a
/// degenerate tensor counts as isotropic).
fn is_isotropic(eigen: &[Eigen2], threshold: f64) -> Vec<bool> {
    let ratio2 = threshold * threshold;
    eigen.iter().map(|e| !(e.l1 >= ratio2 * e.l2)).collect()
}

/// `field` with the directions of its vertices of anisotropy `sqrt(l1 / l2)` below
/// `threshold` replaced by a smooth line field through the other vertices' major
/// directions (the smoothest line field through them, with `weight` 0), and how many
/// vertices changed; `None`
/// when no vertex is below the threshold (or `threshold <= 1`). Densities are kept;
/// a tensor less anisotropic than [`ISOTROPIC_DIRECTION_RATIO`] gets that ratio along the smooth
/// direction, and a nearly isotropic one keeps its eigenvalues and turns by an amount
/// bounded by its anisotropy. A connected part with no anisotropic vertex
/// gets its smoothest field (on a one-part mesh, the eigenvector; otherwise through its
/// lowest vertex's frame axis).
///
/// Errors: a failed line-field solve.
pub fn smooth_isotropic_directions(
    mesh: &TriMesh,
    field: &TensorField,
    threshold: f64,
) -> Result<Option<(TensorField, usize)>, FieldError> {
    let n = mesh.vertex_count();
    let normals = mesh.vertex_normals();
    let eigen = eigens(mesh, field);
    let isotropic = is_isotropic(&eigen, threshold);
    let count = isotropic.iter().filter(|&&i| i).count();
    if threshold <= 1.0 || count == 0 || n == 0 {
        return Ok(None);
    }
    let options = LineFieldOptions {
        weight: 0.0,
        smoothing: 0.3,
        tolerance: ISOTROPIC_TOLERANCE,
        ..LineFieldOptions::default()
    };
    let lines = if count == n && mesh.component_count() == 1 {
        smoothest_line_field(mesh, &options)?
    } else {
        let mut constraints: Vec<LineConstraint> = (0..n)
            .filter(|&v| !isotropic[v])
            .map(|v| LineConstraint {
                vertex: v as u32,
                direction: eigen[v].major,
            })
            .collect();
        // A part with no anisotropic vertex: pin its lowest vertex to its frame axis.
        let components = mesh.face_components();
        let mut pinned = vec![false; mesh.component_count()];
        for c in &constraints {
            let faces = mesh.vertex_faces(c.vertex);
            if let Some(&f) = faces.first() {
                pinned[components[f as usize] as usize] = true;
            }
        }
        for (v, normal) in normals.iter().enumerate() {
            let Some(&f) = mesh.vertex_faces(v as u32).first() else {
                continue;
            };
            let part = components[f as usize] as usize;
            if !pinned[part] {
                pinned[part] = true;
                constraints.push(LineConstraint {
                    vertex: v as u32,
                    direction: tangent_frame(*normal).0,
                });
            }
        }
        constraints.sort_by_key(|c| c.vertex);
        constrained_line_field(mesh, &[], &constraints, &options)?
    };
    let directions: Vec<DVec3> = (0..n)
        .map(|v| {
            if isotropic[v] {
                lines.directions[v]
            } else {
                eigen[v].major
            }
        })
        .collect();
    let floor = ISOTROPIC_DIRECTION_RATIO;
    let eigenvalues: Vec<[f64; 2]> = eigen
        .iter()
        .zip(&isotropic)
        .map(|(e, &iso)| {
            if iso && e.l1 < floor * floor * e.l2 {
                let d = (e.l1 * e.l2).sqrt();
                [d * floor, d / floor]
            } else {
                [e.l1, e.l2]
            }
        })
        .collect();
    Ok(Some((
        TensorField::from_frames(mesh, &directions, &eigenvalues)?,
        count,
    )))
}

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
    use crate::segment::detect_singularities;

    fn constant(anisotropy: f64) -> FieldSpec {
        FieldSpec::Constant {
            direction: [1.0, 0.3, 0.2],
            anisotropy,
            density: 2.0,
        }
    }

    #[test]
    fn all_isotropic_agrees_with_the_per_vertex_test() {
        let mesh = shapes::sphere(1.0, 8).expect("sphere");
        // A constant direction projected onto a sphere is isotropic only where it is
        // normal to the surface: some vertices, not all, for a ratio above 1.
        for (anisotropy, threshold) in [(1.0, 1.1), (1.05, 1.1), (3.0, 1.1), (1.05, 1.01)] {
            let field = constant(anisotropy).build(&mesh).expect("field");
            let each = isotropic_vertices(&mesh, &field, threshold);
            assert_eq!(
                all_isotropic(&mesh, &field, threshold),
                each.iter().all(|&i| i),
                "anisotropy {anisotropy}, threshold {threshold}"
            );
        }
        let field = constant(1.0).build(&mesh).expect("field");
        assert!(all_isotropic(&mesh, &field, 1.1));
        let field = constant(3.0).build(&mesh).expect("field");
        assert!(!all_isotropic(&mesh, &field, 1.1));
    }

    #[test]
    fn an_isotropic_sphere_gets_the_smoothest_field_and_keeps_its_density() {
        let mesh = shapes::sphere(1.0, 8).expect("sphere");
        let field = constant(1.0).build(&mesh).expect("field");
        // The raw isotropic field's directions are noise from the tangent planes.
        let raw = detect_singularities(&mesh, &field).len();
        let (smooth, changed) = smooth_isotropic_directions(&mesh, &field, 1.1)
            .expect("solve")
            .expect("isotropic vertices");
        assert_eq!(changed, mesh.vertex_count());
        let found = detect_singularities(&mesh, &smooth);
        let sum: f64 = found.iter().map(|s| s.index).sum();
        println!(
            "isotropic sphere: {raw} singular faces raw, {} smoothed",
            found.len()
        );
        // The smoothest line field of a sphere: four +1/2 singularities.
        assert_eq!(found.len(), 4);
        assert!((sum - 2.0).abs() < 1e-9);
        assert!(raw > 4);
        let before = field.vertex_densities(&mesh);
        let after = smooth.vertex_densities(&mesh);
        for (v, (t, n)) in smooth
            .tensors()
            .iter()
            .zip(mesh.vertex_normals())
            .enumerate()
        {
            assert!(
                (before[v] - after[v]).abs() < 1e-12 * before[v],
                "vertex {v}"
            );
            let e = eigen_in_plane(t, *n);
            let ratio = (e.l1 / e.l2).sqrt();
            assert!(
                (ratio - ISOTROPIC_DIRECTION_RATIO).abs() < 1e-9,
                "vertex {v}: ratio {ratio}"
            );
        }
    }

    #[test]
    fn anisotropic_fields_and_a_threshold_of_one_change_nothing() {
        let mesh = shapes::sphere(1.0, 5).expect("sphere");
        let field = constant(3.0).build(&mesh).expect("field");
        assert!(
            smooth_isotropic_directions(&mesh, &field, 1.1)
                .expect("ok")
                .is_none()
        );
        let iso = constant(1.0).build(&mesh).expect("field");
        assert!(
            smooth_isotropic_directions(&mesh, &iso, 1.0)
                .expect("ok")
                .is_none()
        );
    }

    #[test]
    fn isotropic_regions_continue_the_anisotropic_directions() {
        // A flat square, anisotropic along a diagonal on its left half, isotropic on its
        // right half: the smoothest continuation of a constant line is that constant.
        let mesh = shapes::plane(2.0, 16).expect("plane");
        let diagonal = DVec3::new(1.0, 1.0, 0.0).normalize();
        let left: Vec<bool> = mesh.positions().iter().map(|p| p.x < 1.0).collect();
        let directions: Vec<DVec3> = left
            .iter()
            .map(|&l| if l { diagonal } else { DVec3::X })
            .collect();
        let eigenvalues: Vec<[f64; 2]> = left
            .iter()
            .map(|&l| if l { [4.0, 1.0] } else { [2.0, 2.0] })
            .collect();
        let field = TensorField::from_frames(&mesh, &directions, &eigenvalues).expect("field");
        let (smooth, changed) = smooth_isotropic_directions(&mesh, &field, 1.1)
            .expect("solve")
            .expect("isotropic vertices");
        assert_eq!(changed, left.iter().filter(|&&l| !l).count());
        for (v, (t, n)) in smooth
            .tensors()
            .iter()
            .zip(mesh.vertex_normals())
            .enumerate()
        {
            if left[v] {
                // Unchanged up to the round-off of the eigen-decomposition round trip.
                let error = (*t - field.tensors()[v])
                    .abs()
                    .to_cols_array()
                    .into_iter()
                    .fold(0.0, f64::max);
                assert!(error < 1e-12, "anisotropic vertex {v} changed by {error}");
            } else {
                let e = eigen_in_plane(t, *n);
                assert!(
                    e.major.dot(diagonal).abs() > 1.0 - 1e-9,
                    "vertex {v}: {}",
                    e.major
                );
            }
        }
    }

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
