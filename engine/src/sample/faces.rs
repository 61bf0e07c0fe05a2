//! Turning a point of a face into the fields of a [`Sample`](super::Sample): position and
//! normal read straight from the mesh (its arrays are already contiguous), the field's
//! tensor from a small per-face table ([`FaceTensors`]) built once with the sampler.

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

/// Per mesh face, the field's tensor at each of its three corners restricted to the
/// face's frame `e1 = (p1 - p0) / |p1 - p0|`, `e2 = n x e1`: the entries `[a, b, c]` of
/// `[[a, b], [b, c]]` per corner, as `f32` (36 bytes per face).
///
/// Restriction to a fixed frame is linear, so interpolating these entries over the face
/// equals restricting the interpolated 3D tensor (DESIGN.md: the tensor is interpolated
/// linearly), and a sample pays nine multiply-adds instead of interpolating six entries
/// and evaluating three quadratic forms. `f32` keeps the eigenvalues to a relative
/// `1e-7` of the largest one, finer than the `f32` spacings written into samples.
#[derive(Clone, Debug, Default)]
pub(crate) struct FaceTensors {
    corners: Vec<[f32; 9]>,
}

impl FaceTensors {
    /// Restricts the field's corner tensors of every face of `mesh` to the face's frame.
    pub(crate) fn new(mesh: &TriMesh, field: &TensorField) -> Self {
        let p = mesh.positions();
        let t = field.tensors();
        let corners = mesh
            .triangles()
            .iter()
            .zip(mesh.face_normals())
            .map(|(tri, &n)| {
                let (e1, e2) = face_frame(p, tri, n);
                let mut out = [0.0f32; 9];
                for (k, &v) in tri.iter().enumerate() {
                    let m = &t[v as usize];
                    let me1 = *m * e1;
                    out[3 * k] = e1.dot(me1) as f32;
                    out[3 * k + 1] = e2.dot(me1) as f32;
                    out[3 * k + 2] = e2.dot(*m * e2) as f32;
                }
                out
            })
            .collect();
        Self { corners }
    }

    /// The table, one `[f32; 9]` per face.
    pub(crate) fn corners(&self) -> &[[f32; 9]] {
        &self.corners
    }

    /// Memory held, in bytes.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.corners.capacity() * std::mem::size_of::<[f32; 9]>()
    }
}

/// The face frame `e1 = (p1 - p0) / |p1 - p0|` (any unit vector orthogonal to `n` for a
/// degenerate first edge), `e2 = n x e1`.
#[inline(always)]
fn face_frame(p: &[DVec3], tri: &[u32; 3], n: DVec3) -> (DVec3, DVec3) {
    let e1 = unit3(p[tri[1] as usize] - p[tri[0] as usize])
        .unwrap_or_else(|| n.any_orthonormal_vector());
    (e1, n.cross(e1))
}

/// The position and unit normal (the vertex normals interpolated, the face's normal
/// where they cancel) on `face` at barycentric coordinates `b`: a sample's
/// [`position`](super::Sample::position) and [`normal`](super::Sample::normal) in `f64`.
#[inline(always)]
pub(crate) fn position_normal(mesh: &TriMesh, face: u32, b: [f64; 3]) -> (DVec3, DVec3) {
    let geometry = Geometry {
        positions: mesh.positions(),
        vertex_normals: mesh.vertex_normals(),
        face_normals: mesh.face_normals(),
    };
    geometry.position_normal(mesh.triangles()[face as usize], face, b)
}

/// The vertex positions and normals and the face normals of a mesh or of a deformation
/// of it (the same triangles), borrowed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Geometry<'a> {
    /// Per vertex, its position.
    pub positions: &'a [DVec3],
    /// Per vertex, its unit normal.
    pub vertex_normals: &'a [DVec3],
    /// Per face, its unit normal.
    pub face_normals: &'a [DVec3],
}

impl Geometry<'_> {
    /// [`position_normal`] on `face`, whose corners are `tri`.
    #[inline(always)]
    pub(crate) fn position_normal(&self, tri: [u32; 3], face: u32, b: [f64; 3]) -> (DVec3, DVec3) {
        let [i, j, k] = tri.map(|v| v as usize);
        let p = self.positions;
        let position = p[i] * b[0] + p[j] * b[1] + p[k] * b[2];
        let vn = self.vertex_normals;
        let normal = unit3(vn[i] * b[0] + vn[j] * b[1] + vn[k] * b[2])
            .unwrap_or(self.face_normals[face as usize]);
        (position, normal)
    }
}

/// Interpolates position, normal and field on `face` at barycentric coordinates `b`.
///
/// The tensor is interpolated linearly in the face's frame (see [`FaceTensors`]). Its
/// major eigenvector is taken without trigonometry as `(l1 - c, b)` or `(b, l1 - a)` of
/// `[[a, b], [b, c]]`, whichever is longer (both are eigenvectors; the longer is better
/// conditioned); an isotropic tensor gets `e1`.
#[inline(always)]
pub(crate) fn face_point(
    mesh: &TriMesh,
    tensors: &FaceTensors,
    face: u32,
    b: [f64; 3],
) -> FacePoint {
    let tri = &mesh.triangles()[face as usize];
    let [i, j, _] = tri.map(|v| v as usize);
    let p = mesh.positions();
    let (position, normal) = position_normal(mesh, face, b);
    let n = mesh.face_normals()[face as usize];
    let t = &tensors.corners[face as usize];
    let (b0, b1, b2) = (b[0] as f32, b[1] as f32, b[2] as f32);
    let lerp = |o: usize| (t[o] * b0 + t[3 + o] * b1 + t[6 + o] * b2) as f64;
    let (a, bb, c) = (lerp(0), lerp(1), lerp(2));
    let mean = 0.5 * (a + c);
    let h = 0.5 * (a - c);
    let r = (h * h + bb * bb).sqrt();
    let (l1, l2) = (mean + r, mean - r);
    let v = if a >= c {
        DVec2::new(l1 - c, bb)
    } else {
        DVec2::new(bb, l1 - a)
    };
    // The frame unnormalised: `u = p1 - p0` and `n x u` have the same length, so one
    // square root and one division normalise both the frame and `v`.
    let u = p[j] - p[i];
    let len2 = v.length_squared();
    let s = len2 * u.length_squared();
    let major = if usable(s) {
        (u * v.x + n.cross(u) * v.y) * (1.0 / s.sqrt())
    } else {
        major_degenerate(p, tri, n, v, len2)
    };
    FacePoint {
        position,
        normal,
        major,
        l1,
        l2,
    }
}

/// The major axis where the first edge or the eigenvector `v` (squared length `len2`)
/// cannot be normalised: a fallback frame or the frame's first axis.
#[cold]
#[inline(never)]
fn major_degenerate(p: &[DVec3], tri: &[u32; 3], n: DVec3, v: DVec2, len2: f64) -> DVec3 {
    let (e1, e2) = face_frame(p, tri, n);
    let v = if usable(len2) {
        v * (1.0 / len2.sqrt())
    } else {
        DVec2::X
    };
    e1 * v.x + e2 * v.y
}

/// Whether a squared length can be normalised: positive and finite (the condition of
/// glam's `try_normalize`, tested once on the square instead of on the reciprocal).
/// Written as two comparisons with `f64::MAX` rather than infinity (which differs only
/// at `MAX` itself, whose reciprocal square root is still finite and positive):
/// against infinity, LLVM turns the pair into a class test on the bits, a dozen
/// integer instructions per call instead of two compares.
#[inline(always)]
fn usable(len2: f64) -> bool {
    (len2 > 0.0) & (len2 < f64::MAX)
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
