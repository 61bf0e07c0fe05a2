//! Per-face data packed for the per-frame path: everything needed to turn a point of a
//! face into a [`Sample`](super::Sample), in one contiguous record per face.

use glam::{DVec3, Vec2, Vec3};

use crate::field::{TensorField, tangent_frame};
use crate::mesh::TriMesh;

/// One face's corners, normals and field, in single precision.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceRecord {
    positions: [Vec3; 3],
    normals: [Vec3; 3],
    /// Orthonormal frame of the face's plane (`e1 x e2` = face normal).
    e1: Vec3,
    e2: Vec3,
    /// Per corner, the tensor in the face frame as `(a, b, c)` of `[[a, b], [b, c]]`.
    tensor: [Vec3; 3],
}

/// What a face contributes to a sample at barycentric coordinates `b`.
pub(crate) struct FacePoint {
    pub position: Vec3,
    pub normal: Vec3,
    pub major: Vec3,
    /// Eigenvalues `l1 >= l2`.
    pub l1: f32,
    pub l2: f32,
}

impl FaceRecord {
    /// Packs every face of `mesh` with `field`.
    pub(crate) fn build_all(mesh: &TriMesh, field: &TensorField) -> Vec<FaceRecord> {
        let f32v = |v: DVec3| v.as_vec3();
        mesh.triangles()
            .iter()
            .zip(mesh.face_normals())
            .map(|(t, n)| {
                let (e1, e2) = tangent_frame(*n);
                let tensor = t.map(|v| {
                    let m = field.tensors()[v as usize];
                    let (me1, me2) = (m * e1, m * e2);
                    let ab = 0.5 * (e2.dot(me1) + e1.dot(me2));
                    Vec3::new(e1.dot(me1) as f32, ab as f32, e2.dot(me2) as f32)
                });
                FaceRecord {
                    positions: t.map(|v| f32v(mesh.positions()[v as usize])),
                    normals: t.map(|v| f32v(mesh.vertex_normals()[v as usize])),
                    e1: f32v(e1),
                    e2: f32v(e2),
                    tensor,
                }
            })
            .collect()
    }

    /// Interpolates position, normal and field at barycentric coordinates `b`.
    ///
    /// The major eigenvector of `[[a, b], [b, c]]` is taken without trigonometry as
    /// `(l1 - c, b)` or `(b, l1 - a)`, whichever is the longer (both are eigenvectors;
    /// the longer is the better conditioned); an isotropic tensor gets `e1`.
    #[inline]
    pub(crate) fn at(&self, b: [f32; 3]) -> FacePoint {
        let lerp = |v: &[Vec3; 3]| v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
        let position = lerp(&self.positions);
        let normal = lerp(&self.normals).normalize_or(self.e1.cross(self.e2));
        let t = lerp(&self.tensor);
        let (a, bb, c) = (t.x, t.y, t.z);
        let mean = 0.5 * (a + c);
        let h = 0.5 * (a - c);
        let r = (h * h + bb * bb).sqrt();
        let (l1, l2) = (mean + r, mean - r);
        let v = if a >= c {
            Vec2::new(l1 - c, bb)
        } else {
            Vec2::new(bb, l1 - a)
        };
        let v = v.try_normalize().unwrap_or(Vec2::X);
        FacePoint {
            position,
            normal,
            major: self.e1 * v.x + self.e2 * v.y,
            l1,
            l2,
        }
    }
}
