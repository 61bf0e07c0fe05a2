//! Turning a point of a face into the fields of a [`Sample`]: position and normal read
//! straight from the mesh (its arrays are already contiguous), the field's tensor from a
//! small per-face table ([`FaceTensors`]) built once with the sampler.
//!
//! The sampler writes full records in two passes over each chunk of its output: the
//! per-sample loop leaves each sample's place ([`Staged`]) in the record's own slot,
//! then [`expand_staged`] turns the slots into records in place. The second pass is a
//! short loop with few live values, so neither pass spills the other's state to the
//! stack, and it reads the mesh's tables with one bounds check per table and face.

use glam::{DVec2, DVec3};

use super::types::Sample;
use crate::field::TensorField;
use crate::mesh::TriMesh;

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

/// Where a sample lies, as the sampler's per-sample loop leaves it in the slot of the
/// [`Sample`] it becomes (`#[repr(C)]`, 64 bytes, the size of a `Sample`, alignment 1,
/// so an output buffer of samples is viewed as one of these without copying): the
/// barycentric coordinates in `f64` (the record interpolates with them), the mesh face
/// and the segment. [`expand_staged`] reads it back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Staged {
    /// The three barycentric coordinates, `f64::to_le_bytes` each.
    bary: [[u8; 8]; 3],
    face: u32,
    segment: u32,
    /// Unused: the rest of the slot.
    rest: [u32; 8],
}

const _: () = assert!(std::mem::size_of::<Staged>() == std::mem::size_of::<Sample>());

impl Staged {
    /// The place of a sample on mesh face `face` of segment `segment` at barycentric
    /// coordinates `bary`.
    #[inline(always)]
    pub(crate) fn new(face: u32, segment: u32, bary: [f64; 3]) -> Self {
        Self {
            bary: bary.map(f64::to_le_bytes),
            face,
            segment,
            rest: [0; 8],
        }
    }
}

/// Turns the staged places in `slots` into the records of samples `start..start +
/// slots.len()` of a request with spacing scale `scale`, in place: slot `k` becomes
/// [`face_record`] of its place with index `start + k`. Every face is one of `mesh`'s.
#[inline(always)]
pub(crate) fn expand_staged(
    mesh: &TriMesh,
    tensors: &FaceTensors,
    slots: &mut [Sample],
    start: u64,
    scale: f64,
) {
    let tables = Tables::new(mesh, tensors);
    for (slot, g) in slots.iter_mut().zip(start..) {
        let st: Staged = bytemuck::cast(*slot);
        let bary = st.bary.map(f64::from_le_bytes);
        *slot = tables.record(st.face, bary, st.segment, g as u32, scale);
    }
}

/// The [`Sample`] on `face` at barycentric coordinates `bary`, with `segment` and
/// `index` copied in.
///
/// Position and normal as [`position_normal`]. The tensor is interpolated linearly in
/// the face's frame (see [`FaceTensors`]) and decomposed into eigenvalues `l1 >= l2`,
/// which give the spacings `scale / sqrt(l_k)`. Its major eigenvector is taken without
/// trigonometry as `(l1 - c, b)` or `(b, l1 - a)` of `[[a, b], [b, c]]`, whichever is
/// longer (both are eigenvectors; the longer is better conditioned), in the frame left
/// unnormalised: `u = p1 - p0` and `n x u` have the same length, so one square root and
/// one division normalise both the frame and the eigenvector. An isotropic tensor gets
/// the frame's first axis.
#[inline(always)]
pub(crate) fn face_record(
    mesh: &TriMesh,
    tensors: &FaceTensors,
    face: u32,
    bary: [f64; 3],
    segment: u32,
    index: u32,
    scale: f64,
) -> Sample {
    Tables::new(mesh, tensors).record(face, bary, segment, index, scale)
}

/// Four `f64` lanes: `x`, `y`, `z` of a vector and a fourth lane whose value is never
/// read, so that a vector operation is one instruction on four lanes (or two on two)
/// instead of a two-lane and a one-lane one. Each lane is computed with the same
/// operations in the same order as `glam`'s `DVec3` would, so the bits are the same.
type Lanes = [f64; 4];

/// `v` as [`Lanes`].
#[inline(always)]
fn lanes(v: DVec3) -> Lanes {
    [v.x, v.y, v.z, 0.0]
}

/// `a * x + b * y + c * z`, lane by lane, summed left to right.
#[inline(always)]
fn combine(a: &Lanes, b: &Lanes, c: &Lanes, [x, y, z]: [f64; 3]) -> Lanes {
    std::array::from_fn(|l| a[l] * x + b[l] * y + c[l] * z)
}

/// The squared length of the first three lanes, summed as `DVec3::length_squared`.
#[inline(always)]
fn length_squared(v: &Lanes) -> f64 {
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
}

/// `v * s`, lane by lane.
#[inline(always)]
fn scaled(v: &Lanes, s: f64) -> Lanes {
    v.map(|x| x * s)
}

/// `a x b` on the first three lanes, as `DVec3::cross`.
#[inline(always)]
fn cross(a: &Lanes, b: &Lanes) -> Lanes {
    [
        a[1] * b[2] - b[1] * a[2],
        a[2] * b[0] - b[2] * a[0],
        a[0] * b[1] - b[0] * a[1],
        0.0,
    ]
}

/// The first three lanes rounded to `f32`, as bits, with `last` as the fourth: one
/// 16-byte group of a [`Sample`].
#[inline(always)]
fn group(v: &Lanes, last: u32) -> [u32; 4] {
    [
        (v[0] as f32).to_bits(),
        (v[1] as f32).to_bits(),
        (v[2] as f32).to_bits(),
        last,
    ]
}

/// The mesh's and the field table's arrays a record reads, cut to common lengths (the
/// vertex arrays to one length, the face arrays to another), so that one bounds check
/// per index covers every array it indexes.
struct Tables<'a> {
    positions: &'a [DVec3],
    vertex_normals: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    face_normals: &'a [DVec3],
    tensors: &'a [[f32; 9]],
}

impl<'a> Tables<'a> {
    #[inline(always)]
    fn new(mesh: &'a TriMesh, tensors: &'a FaceTensors) -> Self {
        let (p, vn) = (mesh.positions(), mesh.vertex_normals());
        let (t, fnorm, ft) = (mesh.triangles(), mesh.face_normals(), tensors.corners());
        let v = p.len().min(vn.len());
        let f = t.len().min(fnorm.len()).min(ft.len());
        Self {
            positions: &p[..v],
            vertex_normals: &vn[..v],
            triangles: &t[..f],
            face_normals: &fnorm[..f],
            tensors: &ft[..f],
        }
    }

    /// [`face_record`] over these tables, in [`Lanes`].
    #[inline(always)]
    fn record(&self, face: u32, b: [f64; 3], segment: u32, index: u32, scale: f64) -> Sample {
        let f = face as usize;
        let tri = self.triangles[f];
        let [i, j, k] = tri.map(|v| v as usize);
        let p = self.positions;
        let (p0, p1, p2) = (lanes(p[i]), lanes(p[j]), lanes(p[k]));
        let vn = self.vertex_normals;
        let (n0, n1, n2) = (lanes(vn[i]), lanes(vn[j]), lanes(vn[k]));
        let n = lanes(self.face_normals[f]);
        let t = &self.tensors[f];
        let position = combine(&p0, &p1, &p2, b);
        let vnormal = combine(&n0, &n1, &n2, b);
        let len2 = length_squared(&vnormal);
        // The tensor in the face's frame and its eigenpairs.
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
        let u: Lanes = std::array::from_fn(|l| p1[l] - p0[l]);
        let vlen2 = v.length_squared();
        let s = vlen2 * length_squared(&u);
        let normal = if usable(len2) {
            scaled(&vnormal, 1.0 / len2.sqrt())
        } else {
            n
        };
        let major = if usable(s) {
            let nu = cross(&n, &u);
            let m: Lanes = std::array::from_fn(|l| u[l] * v.x + nu[l] * v.y);
            scaled(&m, 1.0 / s.sqrt())
        } else {
            let n = DVec3::new(n[0], n[1], n[2]);
            lanes(major_degenerate(p, tri, n, v, vlen2))
        };
        let spacing = [
            (scale / l1.sqrt()) as f32,
            (scale / l2.max(f64::MIN_POSITIVE).sqrt()) as f32,
        ];
        bytemuck::cast([
            group(&position, face),
            group(&normal, segment),
            group(&major, index),
            [
                b1.to_bits(),
                b2.to_bits(),
                spacing[0].to_bits(),
                spacing[1].to_bits(),
            ],
        ])
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

/// The major axis where the first edge or the eigenvector `v` (squared length `len2`)
/// cannot be normalised: a fallback frame or the frame's first axis.
#[cold]
#[inline(never)]
fn major_degenerate(p: &[DVec3], tri: [u32; 3], n: DVec3, v: DVec2, len2: f64) -> DVec3 {
    let (e1, e2) = face_frame(p, &tri, n);
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

    use super::{
        FaceTensors, Sample, Staged, TriMesh, expand_staged, face_frame, face_record,
        major_degenerate, position_normal, unit3, usable,
    };

    /// The record as `DVec3` arithmetic, one sample at a time: the reference that
    /// [`face_record`] must match bit for bit.
    fn reference_record(
        mesh: &TriMesh,
        tensors: &FaceTensors,
        face: u32,
        b: [f64; 3],
        segment: u32,
        index: u32,
        scale: f64,
    ) -> Sample {
        let tri = &mesh.triangles()[face as usize];
        let [i, j, _] = tri.map(|v| v as usize);
        let p = mesh.positions();
        let (position, normal) = position_normal(mesh, face, b);
        let n = mesh.face_normals()[face as usize];
        let t = &tensors.corners()[face as usize];
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
        let u = p[j] - p[i];
        let len2 = v.length_squared();
        let s = len2 * u.length_squared();
        let major = if usable(s) {
            (u * v.x + n.cross(u) * v.y) * (1.0 / s.sqrt())
        } else {
            major_degenerate(p, *tri, n, v, len2)
        };
        Sample {
            position: position.as_vec3().to_array(),
            face,
            normal: normal.as_vec3().to_array(),
            segment,
            major_axis: major.as_vec3().to_array(),
            index,
            bary: [b1, b2],
            spacing: [
                (scale / l1.sqrt()) as f32,
                (scale / l2.max(f64::MIN_POSITIVE).sqrt()) as f32,
            ],
        }
    }

    /// The lane arithmetic of [`face_record`] and the staged two-pass expansion give
    /// the reference's bits, on an anisotropic field over a curved mesh, at random
    /// points, on edges and corners, and where the tensor is isotropic (a zero field
    /// on a degenerate frame goes through `major_degenerate`).
    #[test]
    fn records_match_the_reference_bit_for_bit() {
        let (mesh, field) = crate::fixtures::torus_case();
        let tensors = FaceTensors::new(&mesh, &field);
        let mut rng = crate::rng::Rng::new(9, 2);
        let mut places = vec![];
        for face in 0..mesh.face_count() as u32 {
            let (x, y) = (rng.next_f64(), rng.next_f64());
            let (x, y) = if x + y > 1.0 {
                (1.0 - x, 1.0 - y)
            } else {
                (x, y)
            };
            places.push((face, [1.0 - x - y, x, y]));
            places.push((face, [0.0, 1.0, 0.0]));
            places.push((face, [0.5, 0.0, 0.5]));
        }
        let mut slots = vec![Sample::default(); places.len()];
        for (slot, &(face, b)) in slots.iter_mut().zip(&places) {
            *slot = bytemuck::cast(Staged::new(face, face % 7, b));
        }
        let (start, scale) = (1000u64, 0.37);
        expand_staged(&mesh, &tensors, &mut slots, start, scale);
        for (k, (&(face, b), got)) in places.iter().zip(&slots).enumerate() {
            let index = (start + k as u64) as u32;
            let want = reference_record(&mesh, &tensors, face, b, face % 7, index, scale);
            let direct = face_record(&mesh, &tensors, face, b, face % 7, index, scale);
            let bits = |s: &Sample| bytemuck::cast::<Sample, [u32; 16]>(*s);
            assert_eq!(bits(got), bits(&want), "face {face} at {b:?}");
            assert_eq!(bits(&direct), bits(&want), "face {face} at {b:?}");
        }
        // A zero tensor: the eigenvector is zero and the frame's first axis is taken.
        let zero = FaceTensors {
            corners: vec![[0.0; 9]; mesh.face_count()],
        };
        let got = face_record(&mesh, &zero, 3, [0.2, 0.3, 0.5], 0, 0, 1.0);
        let want = reference_record(&mesh, &zero, 3, [0.2, 0.3, 0.5], 0, 0, 1.0);
        assert_eq!(got, want);
        let (e1, _) = face_frame(
            mesh.positions(),
            &mesh.triangles()[3],
            mesh.face_normals()[3],
        );
        assert_eq!(got.major_axis, e1.as_vec3().to_array());
    }

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
