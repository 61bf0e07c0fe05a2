//! A density that follows tone, for stippling (paper Fig. 1): samples concentrate
//! where the surface turns away from a light, as an artist's dots gather in shadow.
//!
//! Input: a mesh, a direction toward the light and the densities where the surface
//! is fully lit and fully dark. Output: one density per vertex,
//!
//! `darkness = 1 - max(n . l, 0)`, `density = lit + (shadow - lit) darkness^exponent`,
//!
//! with `n` the vertex normal and `l` the unit light direction, both in the mesh's
//! coordinates: Lambert shading, so the side facing the light gets `lit`, the grazing
//! band and the back get `shadow`. A stipple renderer with dots of one size shows a tone
//! proportional to the density, hence the linear blend. Cost O(V).

use glam::DVec3;

use crate::mesh::TriMesh;

/// The renderer's default light (`strata render`'s splat and stroke styles), so that a
/// scene's shading density matches the picture's shading.
pub const DEFAULT_LIGHT: [f64; 3] = [0.4, 0.8, 0.45];

/// Per-vertex densities from Lambert shading (see the module docs).
///
/// `light` must be finite and non-zero (it is normalised), `lit` and `shadow` finite and
/// positive, `exponent` finite and positive: [`Design::validate`](super::Design::validate)
/// checks them.
///
/// ```
/// use strata_engine::{field::shading_densities, mesh::shapes};
/// let mesh = shapes::sphere(1.0, 8)?;
/// let d = shading_densities(&mesh, [0.0, 0.0, 1.0], 0.5, 4.0, 1.0);
/// let top = (0..mesh.vertex_count()).max_by(|&a, &b| {
///     mesh.positions()[a].z.total_cmp(&mesh.positions()[b].z)
/// }).expect("vertices");
/// assert!((d[top] - 0.5).abs() < 1e-2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn shading_densities(
    mesh: &TriMesh,
    light: [f64; 3],
    lit: f64,
    shadow: f64,
    exponent: f64,
) -> Vec<f64> {
    let l = DVec3::from(light).normalize_or_zero();
    mesh.vertex_normals()
        .iter()
        .map(|n| {
            let darkness = 1.0 - n.dot(l).clamp(0.0, 1.0);
            lit + (shadow - lit) * darkness.powf(exponent)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    #[test]
    fn sphere_densities_follow_lambert_shading() {
        // On a sphere the vertex normals are nearly radial: each vertex's density is the
        // formula at its angle to the light, within the normals' discretisation.
        let mesh = shapes::sphere(1.0, 16).expect("sphere");
        let light = DVec3::new(1.0, 2.0, 2.0);
        for exponent in [0.5, 1.0, 2.0] {
            let d = shading_densities(&mesh, light.to_array(), 0.25, 4.0, exponent);
            for (p, &di) in mesh.positions().iter().zip(&d) {
                let cos = p.normalize().dot(light.normalize());
                let want = 0.25 + 3.75 * (1.0 - cos.max(0.0)).powf(exponent);
                assert!((di - want).abs() < 0.05, "{cos}: {di} vs {want}");
                assert!((0.25..=4.0).contains(&di));
            }
        }
    }

    #[test]
    fn back_and_grazing_vertices_get_the_shadow_density() {
        let mesh = shapes::sphere(1.0, 12).expect("sphere");
        let d = shading_densities(&mesh, [0.0, 0.0, 3.0], 1.0, 5.0, 1.0);
        for (p, &di) in mesh.positions().iter().zip(&d) {
            if p.z < -0.05 {
                assert_eq!(di, 5.0, "{p}");
            }
        }
        // Lit brighter than shadow also works (a "highlight" density); the light's
        // length does not matter.
        let a = shading_densities(&mesh, [0.0, 0.0, 1.0], 5.0, 1.0, 1.0);
        let b = shading_densities(&mesh, [0.0, 0.0, 7.0], 5.0, 1.0, 1.0);
        assert_eq!(a, b);
        assert!(a.iter().all(|&x| (1.0..=5.0).contains(&x)));
    }
}
