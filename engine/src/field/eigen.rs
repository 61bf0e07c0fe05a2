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
