//! Guidance for the line-field solver ([`constrained_line_field`](super::constrained_line_field)):
//! per-vertex tangent vectors whose direction is the wished line and whose length is
//! the confidence in it.
//!
//! Input: a [`TriMesh`] (and principal curvatures or a world direction). Output: one
//! tangent vector per vertex. Cost: O(V).

use glam::DVec3;

use super::{PrincipalCurvatures, tangent_frame};
use crate::mesh::TriMesh;

/// Guidance along the direction of largest *signed* principal curvature, with
/// confidence `|k1 - k2| R` (`R = sqrt(area / 4 pi)`, the radius of the sphere of the
/// mesh's area, so the confidence is dimensionless and independent of scale).
///
/// This is the traceless part of the second fundamental form `II`, the guidance of
/// Knöppel et al. 2013: as a doubled-angle number it is `(k_max - k_min) / 2
/// e^(2 i theta_max)`, continuous over the surface (the direction of largest
/// *magnitude* would jump by 90 degrees wherever the curvatures change sign across a
/// parabolic line), and zero at umbilics, where principal directions are noise, so
/// umbilic regions follow their neighbours. Where the two principal curvatures agree
/// exactly the vector is zero (no guidance).
pub fn curvature_guidance(mesh: &TriMesh, k: &PrincipalCurvatures) -> Vec<DVec3> {
    let radius = (mesh.area() / (4.0 * std::f64::consts::PI)).sqrt();
    k.tensors
        .iter()
        .zip(mesh.vertex_normals())
        .map(|(t, n)| {
            let (e1, e2) = tangent_frame(*n);
            let (te1, te2) = (*t * e1, *t * e2);
            let a = e1.dot(te1);
            let c = e2.dot(te2);
            let b = 0.5 * (e2.dot(te1) + e1.dot(te2));
            // Traceless part z = (a - c) / 2 + i b = (k_max - k_min) / 2 e^(2 i theta).
            let (re, im) = (0.5 * (a - c), b);
            let spread = 2.0 * re.hypot(im);
            if !(spread > 0.0) || !spread.is_finite() {
                return DVec3::ZERO;
            }
            let (s, co) = (0.5 * im.atan2(re)).sin_cos();
            (e1 * co + e2 * s) * (spread * radius)
        })
        .collect()
}

/// Guidance along a world direction projected into each tangent plane, with
/// confidence `|sin|` of its angle to the normal: full where the direction lies in the
/// surface, fading to none where the surface faces it (where a projected direction
/// flips, which is what makes [`FieldSpec::Constant`](super::FieldSpec::Constant)
/// singular on bumpy meshes).
pub fn direction_guidance(mesh: &TriMesh, direction: DVec3) -> Vec<DVec3> {
    let d = direction.normalize_or_zero();
    mesh.vertex_normals()
        .iter()
        .map(|n| d - *n * d.dot(*n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::principal_curvatures;
    use crate::mesh::shapes;

    #[test]
    fn sphere_curvature_guidance_is_nearly_zero_and_cylinder_guidance_goes_around() {
        // Umbilic everywhere: k_max = k_min, so (up to discretisation) no guidance.
        let sphere = shapes::sphere(1.0, 6).expect("sphere");
        let k = principal_curvatures(&sphere, 0);
        let g = curvature_guidance(&sphere, &k);
        let largest = g.iter().map(|v| v.length()).fold(0.0, f64::max);
        assert!(largest < 0.05, "largest confidence {largest}");

        // A cylinder of radius 1 and height 2 along z: k = 1 around, 0 along, so the
        // guidance goes around (perpendicular to z), with confidence |k1 - k2| R.
        let cylinder = shapes::cylinder(1.0, 2.0, 48).expect("cylinder");
        let k = principal_curvatures(&cylinder, 0);
        let g = curvature_guidance(&cylinder, &k);
        let radius = (cylinder.area() / (4.0 * std::f64::consts::PI)).sqrt();
        let mut checked = 0;
        for (p, v) in cylinder.positions().iter().zip(&g) {
            if p.z.abs() < 0.5 && (p.truncate().length() - 1.0).abs() < 1e-9 {
                let along = v.normalize().dot(DVec3::Z).abs();
                assert!(along < 0.02, "guidance at {p} has {along} along the axis");
                assert!((v.length() / radius - 1.0).abs() < 0.05, "{}", v.length());
                checked += 1;
            }
        }
        assert!(checked > 20, "{checked} side vertices checked");
    }

    #[test]
    fn direction_guidance_fades_where_the_surface_faces_the_direction() {
        let sphere = shapes::sphere(1.0, 4).expect("sphere");
        let g = direction_guidance(&sphere, DVec3::new(0.0, 0.0, 5.0));
        for (n, v) in sphere.vertex_normals().iter().zip(&g) {
            assert!(v.dot(*n).abs() < 1e-12);
            let sin = n.cross(DVec3::Z).length();
            assert!((v.length() - sin).abs() < 1e-12);
        }
    }
}
