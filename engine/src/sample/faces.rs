//! Turning a point of a face into the fields of a [`Sample`](super::Sample), read
//! straight from the mesh and the field (no per-face copy: the preprocessed data stays
//! small, and the mesh's arrays are already contiguous).

use glam::{DVec2, DVec3};

use crate::field::TensorField;
use crate::mesh::TriMesh;

/// What a face contributes to a sample at some barycentric coordinates.
pub(crate) struct FacePoint {
    pub position: DVec3,
    pub normal: DVec3,
    pub major: DVec3,
    /// Eigenvalues `l1 >= l2` of the interpolated tensor in the face's plane.
    pub l1: f64,
    pub l2: f64,
}

/// Interpolates position, normal and field on `face` at barycentric coordinates `b`.
///
/// The tensor is interpolated linearly (DESIGN.md: it has no sign ambiguity) and
/// restricted to the face's plane in the frame `e1 = (p1 - p0) / |p1 - p0|`,
/// `e2 = n x e1`. Its major eigenvector is taken without trigonometry as `(l1 - c, b)`
/// or `(b, l1 - a)` of `[[a, b], [b, c]]`, whichever is longer (both are eigenvectors;
/// the longer is better conditioned); an isotropic tensor gets `e1`.
#[inline]
pub(crate) fn face_point(mesh: &TriMesh, field: &TensorField, face: u32, b: [f64; 3]) -> FacePoint {
    let tri = mesh.triangles()[face as usize];
    let [i, j, k] = tri.map(|v| v as usize);
    let p = mesh.positions();
    let position = p[i] * b[0] + p[j] * b[1] + p[k] * b[2];
    let n = mesh.face_normals()[face as usize];
    let vn = mesh.vertex_normals();
    let normal = unit3(vn[i] * b[0] + vn[j] * b[1] + vn[k] * b[2]).unwrap_or(n);
    let e1 = unit3(p[j] - p[i]).unwrap_or_else(|| n.any_orthonormal_vector());
    let e2 = n.cross(e1);
    // The tensors are symmetric: interpolate the six entries of the upper triangle and
    // evaluate the quadratic forms from them (a third fewer operations than the full
    // matrix products).
    let t = field.tensors();
    let (ti, tj, tk) = (&t[i], &t[j], &t[k]);
    let lerp = |x: f64, y: f64, z: f64| x * b[0] + y * b[1] + z * b[2];
    let m00 = lerp(ti.x_axis.x, tj.x_axis.x, tk.x_axis.x);
    let m11 = lerp(ti.y_axis.y, tj.y_axis.y, tk.y_axis.y);
    let m22 = lerp(ti.z_axis.z, tj.z_axis.z, tk.z_axis.z);
    let m01 = lerp(ti.y_axis.x, tj.y_axis.x, tk.y_axis.x);
    let m02 = lerp(ti.z_axis.x, tj.z_axis.x, tk.z_axis.x);
    let m12 = lerp(ti.z_axis.y, tj.z_axis.y, tk.z_axis.y);
    let apply = |v: DVec3| {
        DVec3::new(
            m00 * v.x + m01 * v.y + m02 * v.z,
            m01 * v.x + m11 * v.y + m12 * v.z,
            m02 * v.x + m12 * v.y + m22 * v.z,
        )
    };
    let me1 = apply(e1);
    let (a, bb, c) = (e1.dot(me1), e2.dot(me1), e2.dot(apply(e2)));
    let mean = 0.5 * (a + c);
    let h = 0.5 * (a - c);
    let r = (h * h + bb * bb).sqrt();
    let (l1, l2) = (mean + r, mean - r);
    let v = if a >= c {
        DVec2::new(l1 - c, bb)
    } else {
        DVec2::new(bb, l1 - a)
    };
    let len2 = v.length_squared();
    let v = if usable(len2) {
        v * (1.0 / len2.sqrt())
    } else {
        DVec2::X
    };
    FacePoint {
        position,
        normal,
        major: e1 * v.x + e2 * v.y,
        l1,
        l2,
    }
}

/// Whether a squared length can be normalised: positive and finite (the condition of
/// glam's `try_normalize`, tested once on the square instead of on the reciprocal).
#[inline(always)]
fn usable(len2: f64) -> bool {
    (len2 > 0.0) & (len2 < f64::INFINITY)
}

/// `v / |v|` computed as glam does (`v * (1 / sqrt(v . v))`, the same bits), or `None`
/// for a zero or non-finite `v`.
#[inline(always)]
fn unit3(v: DVec3) -> Option<DVec3> {
    let len2 = v.length_squared();
    usable(len2).then(|| v * (1.0 / len2.sqrt()))
}

#[cfg(test)]
mod tests {
    use glam::{DVec2, DVec3};

    use super::{unit3, usable};

    #[test]
    fn unit_vectors_match_glam() {
        let mut rng = crate::rng::Rng::new(3, 1);
        for _ in 0..1000 {
            let v = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                (rng.next_f64() - 0.5) * 1e-3,
            );
            assert_eq!(unit3(v), v.try_normalize());
            let w = v.truncate();
            let len2 = w.length_squared();
            assert_eq!(
                usable(len2).then(|| w * (1.0 / len2.sqrt())),
                w.try_normalize()
            );
        }
        for v in [
            DVec3::ZERO,
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::new(f64::INFINITY, 0.0, 0.0),
            DVec3::splat(1e200),
        ] {
            assert_eq!(unit3(v), v.try_normalize(), "{v}");
        }
        assert!(!usable(DVec2::ZERO.length_squared()));
    }
}
