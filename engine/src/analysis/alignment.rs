//! Field alignment (paper section 7.3.1): per face, the angle between the field's
//! major direction mapped into the segment's parameter domain and the parameter u axis,
//! along which the Hilbert cells' rows run.
//!
//! Input: the mesh, the field and the final segments' [`SegmentParam`]s (from
//! [`Preprocessed`](crate::surface::Preprocessed)). Output: one angle per mesh face in
//! degrees, in `[0, 90]` (NaN for faces no segment covers), to plot as a map. Cost:
//! O(F).
//!
//! The map of a face is the linear map of its corners from the surface to `uv`; the
//! major eigenvector of the field at the face's barycentre, expressed in the face's
//! edge basis, is carried through it. Since the field is a line field the angle is
//! folded into `[0, 90]`. Segments with the isotropic fallback have no meaningful
//! direction and are reported as 0.

use glam::{DMat2, DVec2};

use crate::field::TensorField;
use crate::mesh::TriMesh;
use crate::param::SegmentParam;

/// The per-face angle map (degrees), indexed by mesh face.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use strata_engine::{analysis::alignment, field::FieldSpec, mesh::shapes, surface};
/// let mesh = Arc::new(shapes::plane(1.0, 8)?);
/// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 };
/// let field = Arc::new(spec.build(&mesh)?);
/// let pre = surface::Preprocessed::build_surface(mesh.clone(), field.clone(), &Default::default())?;
/// let angles = alignment::face_angles(&mesh, &field, &pre.params);
/// assert!(angles.iter().all(|a| *a < 1e-6));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn face_angles(mesh: &TriMesh, field: &TensorField, params: &[SegmentParam]) -> Vec<f64> {
    let mut out = vec![f64::NAN; mesh.face_count()];
    for p in params {
        for (t, &f) in p.triangles.iter().zip(&p.faces) {
            out[f as usize] = if p.report.isotropic_fallback {
                0.0
            } else {
                face_angle(mesh, field, f, t.map(|v| p.uv[v as usize]))
            };
        }
    }
    out
}

/// The angle (degrees, `[0, 90]`) for face `f` with parameter corners `uv`.
pub fn face_angle(mesh: &TriMesh, field: &TensorField, f: u32, uv: [DVec2; 3]) -> f64 {
    let [a, b, c] = mesh.face_positions(f);
    let (e1, e2) = (b - a, c - a);
    let m1 = field.face_eigen(mesh, f, [1.0 / 3.0; 3]).major;
    // m1 = x e1 + y e2 in the face plane: solve the 2x2 Gram system.
    let gram = DMat2::from_cols_array(&[e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2)]);
    if gram.determinant().abs() < f64::MIN_POSITIVE {
        return f64::NAN;
    }
    let coef = gram.inverse() * DVec2::new(m1.dot(e1), m1.dot(e2));
    let image = (uv[1] - uv[0]) * coef.x + (uv[2] - uv[0]) * coef.y;
    if image == DVec2::ZERO {
        return 90.0;
    }
    image.y.abs().atan2(image.x.abs()).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::along_x_2to1_on;
    use crate::mesh::shapes;

    #[test]
    fn a_rotated_parameterization_gives_its_angle() {
        let mesh = shapes::plane(1.0, 2).expect("plane");
        let field = along_x_2to1_on(&mesh);
        let rot = glam::DMat2::from_angle(30f64.to_radians());
        for f in 0..mesh.face_count() as u32 {
            let uv = mesh.face_positions(f).map(|p| rot * p.truncate());
            assert!((face_angle(&mesh, &field, f, uv) - 30.0).abs() < 1e-9);
            // A mirrored map folds to the same line angle.
            let uv = uv.map(|q| DVec2::new(q.x, -q.y));
            assert!((face_angle(&mesh, &field, f, uv) - 30.0).abs() < 1e-9);
        }
    }
}
