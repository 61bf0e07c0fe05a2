//! Closed-form eigen-decomposition of a tangent-plane tensor.

use glam::{DMat3, DVec3};

/// Eigen-decomposition of a symmetric tensor restricted to a plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eigen2 {
    /// Unit major eigenvector (largest eigenvalue), in the plane. Its sign is arbitrary:
    /// the field is a line field.
    pub major: DVec3,
    /// Unit minor eigenvector, `normal x major`.
    pub minor: DVec3,
    /// Largest eigenvalue.
    pub l1: f64,
    /// Smallest eigenvalue.
    pub l2: f64,
}

impl Eigen2 {
    /// Density `sqrt(l1 l2)` (zero if the tensor is not positive definite).
    pub fn density(&self) -> f64 {
        (self.l1 * self.l2).max(0.0).sqrt()
    }

    /// Spacing ratio `sqrt(l1 / l2)` (>= 1; infinite if `l2 <= 0`).
    pub fn anisotropy(&self) -> f64 {
        if self.l2 > 0.0 {
            (self.l1 / self.l2).sqrt()
        } else {
            f64::INFINITY
        }
    }
}

/// The [`tangent_frame`] of every vertex normal of `mesh`: the frames in which
/// per-vertex angles are measured (line fields, their transport along edges). O(V).
pub fn vertex_frames(mesh: &crate::mesh::TriMesh) -> Vec<(DVec3, DVec3)> {
    mesh.vertex_normals()
        .iter()
        .map(|n| tangent_frame(*n))
        .collect()
}

/// The angle of `d` projected into the tangent frame `(e1, e2)`, in `(-pi, pi]`.
pub fn frame_angle(d: DVec3, (e1, e2): (DVec3, DVec3)) -> f64 {
    d.dot(e2).atan2(d.dot(e1))
}

/// A deterministic orthonormal frame `(e1, e2)` of the plane with unit normal `n`,
/// with `e1 x e2 = n`. `e1` is the projection of the world axis least aligned with `n`.
pub fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let a = n.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        DVec3::X
    } else if a.y <= a.z {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let e1 = (axis - n * n.dot(axis)).normalize();
    (e1, n.cross(e1))
}

/// Eigenvalues `(l1 >= l2)` and the angle `theta` of the major eigenvector of the
/// symmetric 2x2 matrix `[[a, b], [b, c]]`, in closed form: `l = (a + c)/2 +- r` with
/// `r = hypot((a - c)/2, b)` and `theta = atan2(2b, a - c) / 2`. Stable for all
/// inputs (no division); `theta` is 0 for an isotropic matrix.
pub fn eigen_2x2(a: f64, b: f64, c: f64) -> (f64, f64, f64) {
    let mean = 0.5 * (a + c);
    let r = (0.5 * (a - c)).hypot(b);
    (mean + r, mean - r, 0.5 * (2.0 * b).atan2(a - c))
}

/// Eigen-decomposition of `t` restricted to the plane with unit normal `n`.
pub fn eigen_in_plane(t: &DMat3, n: DVec3) -> Eigen2 {
    let (e1, e2) = tangent_frame(n);
    let te1 = *t * e1;
    let te2 = *t * e2;
    // Symmetrise against round-off in the off-diagonal entry.
    let (l1, l2, theta) = eigen_2x2(e1.dot(te1), 0.5 * (e2.dot(te1) + e1.dot(te2)), e2.dot(te2));
    let (s, c) = theta.sin_cos();
    let major = e1 * c + e2 * s;
    Eigen2 {
        major,
        minor: n.cross(major),
        l1,
        l2,
    }
}

/// The unit eigenvector of the largest eigenvalue of a symmetric 3x3 matrix (power
/// iteration from the column of largest norm, 32 steps; enough to pick a seed
/// direction, not an accurate solver: eigenvalues close in size converge slowly).
/// Its sign is arbitrary; `X` for the zero matrix.
pub fn principal_axis(m: DMat3) -> DVec3 {
    let mut v = [m.x_axis, m.y_axis, m.z_axis]
        .into_iter()
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
        .unwrap_or(DVec3::X)
        .try_normalize()
        .unwrap_or(DVec3::X);
    for _ in 0..32 {
        v = (m * v).try_normalize().unwrap_or(v);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::outer;

    #[test]
    fn principal_axis_finds_the_largest_eigenvector() {
        // A diagonal matrix: the axis of the largest entry, whatever the column norms.
        let d = DMat3::from_diagonal(DVec3::new(1.0, 5.0, 2.0));
        assert!((principal_axis(d).abs() - DVec3::Y).length() < 1e-9);
        // A rotated one: l1 = 4 along a, l2 = 1 along b, 0 along a x b.
        let a = DVec3::new(1.0, 2.0, 2.0) / 3.0;
        let b = DVec3::new(2.0, 1.0, -2.0) / 3.0;
        let m = outer(a, a) * 4.0 + outer(b, b);
        let v = principal_axis(m);
        assert!((v.length() - 1.0).abs() < 1e-12);
        assert!(v.dot(a).abs() > 1.0 - 1e-9, "{v} against {a}");
        // The zero matrix has no direction: the fallback.
        assert_eq!(principal_axis(DMat3::ZERO), DVec3::X);
    }
}
