//! A view's level of detail: a density multiplier over the surface from a camera,
//! and the rank threshold that turns it into a visible set.
//!
//! **Multiplier.** For a pinhole camera with focal length `f` in pixels, a surface
//! element of area `dA` at point `p` with unit normal `n` covers on screen
//!
//! ```text
//! a(p) dA = f^2 |cos theta| d / z^3 dA     (pixels^2)
//! ```
//!
//! with `d = |p - eye|`, `z` the depth of `p` along the view axis (the clip-space
//! `w`) and `cos theta = n . (eye - p) / d` (the solid angle `dA cos theta / d^2`,
//! times `f^2 / cos^3 alpha` for a direction `alpha` off the axis, `cos alpha = z / d`).
//! The multiplier is `lod(p) = min(a(p) / reference, max)`: 1 where a unit of surface
//! covers `reference` pixels^2, 0 outside the view frustum (clip space `|x|, |y| <= w`,
//! `0 <= z <= w`, `w > 0`: wgpu's convention) and, when asked, on faces turned away
//! from the eye.
//!
//! **Visible set.** With progressive samples (rank `k` at `p_k`, [`Sampler::progressive_into`](crate::sample::Sampler::progressive_into))
//! and a base count `N` (the samples of the whole surface at multiplier 1), rank `k`
//! is visible when `k < N lod(p_k)`, and its fade weight is
//! `clamp(N lod(p_k) - k, 0, 1)`: a renderer scales or blends samples by it so that
//! they appear and vanish smoothly as the multiplier changes (rank thresholding as in
//! Kopf et al., "Recursive Wang tiles for real-time blue noise", 2006). Where the
//! multiplier is `m`, the visible samples are the first `N m` ranks of the sequence
//! restricted there, so their density is `m` times the base density and stays
//! stratified, and a larger multiplier only adds samples: none moves.

use glam::{DAffine3, DMat4, DVec3, DVec4};

#[cfg(target_arch = "x86_64")]
use crate::cpu::Level;
use crate::mesh::TriMesh;

/// A camera's level-of-detail request, in plain numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewLod {
    /// Clip-from-world matrix of a perspective camera (clip `w` is the view depth).
    pub clip_from_world: DMat4,
    /// The camera position, world space.
    pub eye: DVec3,
    /// Focal length in pixels: `height / (2 tan(fov_y / 2))` for a viewport `height`
    /// pixels tall.
    pub focal_pixels: f64,
    /// Screen area (pixels^2) that a unit of surface area covers where the multiplier
    /// is 1. Positive.
    pub reference: f64,
    /// Largest multiplier (`f64::INFINITY`: none).
    pub max: f64,
    /// Whether faces turned away from the eye get 0.
    pub cull_back_faces: bool,
}

/// A [`ViewLod`] setting out of its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LodError {
    /// A setting with a value out of range.
    #[error("level of detail: {setting} = {value} must be {expected}")]
    Invalid {
        /// The setting's name.
        setting: &'static str,
        /// The value given (for vectors and matrices: their first non-finite entry).
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A deformed mesh whose vertices or triangles are not the sampler's.
    #[error(
        "level of detail: a deformed mesh must keep the sampler's vertices and triangles \
         ({expected_vertices} vertices, {expected_faces} faces), got {vertices} and {faces}"
    )]
    Mismatch {
        /// Vertices given.
        vertices: usize,
        /// Faces given.
        faces: usize,
        /// The sampler's mesh's vertices.
        expected_vertices: usize,
        /// Its faces.
        expected_faces: usize,
    },
    /// A sampler other than the one a pool was built from
    /// ([`LodPool::drawn_from`](super::LodPool::drawn_from)): the pool's entries are
    /// sites of its own sampler's sequence.
    #[error(
        "level of detail: the pool was built from another sampler (a pool is updated \
         with the sampler it was built from, or a clone of it)"
    )]
    OtherSampler,
    /// A mesh placed by a transform that is not a similarity (uniform positive scale,
    /// rotation, translation): its multiplier would vary per point in a way the pool's
    /// bounds do not follow.
    #[error(
        "level of detail: the mesh's transform must be a similarity (uniform positive \
         scale, rotation, translation); its linear part is {deviation:.3e} away from one \
         (relative), determinant {determinant}"
    )]
    NotSimilarity {
        /// `max |L^T L - s^2 I| / s^2`, `s^3 = det L`.
        deviation: f64,
        /// `det L`.
        determinant: f64,
    },
}

/// Checks that `mesh` is a deformation of `rest`: the same vertex count and triangles.
pub(crate) fn check_deformation(rest: &TriMesh, mesh: &TriMesh) -> Result<(), LodError> {
    if mesh.vertex_count() != rest.vertex_count() || mesh.triangles() != rest.triangles() {
        return Err(LodError::Mismatch {
            vertices: mesh.vertex_count(),
            faces: mesh.face_count(),
            expected_vertices: rest.vertex_count(),
            expected_faces: rest.face_count(),
        });
    }
    Ok(())
}

/// Largest relative deviation of a transform's linear part from a similarity that
/// [`ViewLod::in_local_frame`] accepts (round-off of composed rotations).
pub const SIMILARITY_TOLERANCE: f64 = 1e-9;

impl ViewLod {
    /// Checks every setting: a finite matrix and eye, a positive finite focal length
    /// and reference, a positive `max` (infinity allowed). [`multiplier`](Self::multiplier)
    /// assumes them.
    pub fn validate(&self) -> Result<(), LodError> {
        let bad = |setting, value, expected| {
            Err(LodError::Invalid {
                setting,
                value,
                expected,
            })
        };
        if let Some(&v) = self
            .clip_from_world
            .to_cols_array()
            .iter()
            .find(|v| !v.is_finite())
        {
            return bad("clip_from_world", v, "finite");
        }
        if let Some(&v) = self.eye.to_array().iter().find(|v| !v.is_finite()) {
            return bad("eye", v, "finite");
        }
        if !(self.focal_pixels > 0.0 && self.focal_pixels.is_finite()) {
            return bad("focal_pixels", self.focal_pixels, "finite and > 0");
        }
        if !(self.reference > 0.0 && self.reference.is_finite()) {
            return bad("reference", self.reference, "finite and > 0");
        }
        if !(self.max > 0.0) {
            return bad("max", self.max, "> 0 (infinity for no clamp)");
        }
        Ok(())
    }

    /// The same view for a mesh placed in the world by the similarity `transform`
    /// (local to world): the settings whose [`multiplier`](Self::multiplier) at a local
    /// point and normal equals this view's at their images, so a pool of the local
    /// mesh's samples selects what a renderer of the placed mesh shows. The clip matrix
    /// takes `transform` in, the eye is taken back to local space, and the reference
    /// area is divided by the scale `s` (distances to the eye shrink by `s`; angles and
    /// view depths do not change).
    ///
    /// Errors: a transform that is not a similarity with positive scale
    /// ([`SIMILARITY_TOLERANCE`]).
    pub fn in_local_frame(&self, transform: &DAffine3) -> Result<Self, LodError> {
        let linear = transform.matrix3;
        let determinant = linear.determinant();
        let s2 = determinant.cbrt().powi(2);
        let gram = linear.transpose() * linear;
        let deviation = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let identity = if i == j { s2 } else { 0.0 };
                (gram.col(j)[i] - identity).abs()
            })
            .fold(0.0, f64::max)
            / s2;
        if !(determinant > 0.0 && determinant.is_finite() && deviation <= SIMILARITY_TOLERANCE) {
            return Err(LodError::NotSimilarity {
                deviation,
                determinant,
            });
        }
        Ok(Self {
            clip_from_world: self.clip_from_world * DMat4::from(*transform),
            eye: transform.inverse().transform_point3(self.eye),
            reference: self.reference / determinant.cbrt(),
            ..*self
        })
    }

    /// The density multiplier at point `p` with unit normal `normal` (module docs), for
    /// settings that pass [`validate`](Self::validate).
    pub fn multiplier(&self, p: DVec3, normal: DVec3) -> f64 {
        let clip = self.clip_from_world * DVec4::new(p.x, p.y, p.z, 1.0);
        let w = clip.w;
        if !(w > 0.0 && clip.x.abs() <= w && clip.y.abs() <= w && (0.0..=w).contains(&clip.z)) {
            return 0.0;
        }
        let to_eye = self.eye - p;
        let d = to_eye.length();
        if !(d > 0.0) {
            return 0.0;
        }
        let cos = normal.dot(to_eye) / d;
        if self.cull_back_faces && cos < 0.0 {
            return 0.0;
        }
        let area = self.focal_pixels * self.focal_pixels * cos.abs() * d / (w * w * w);
        (area / self.reference).min(self.max)
    }

    /// [`multiplier`](Self::multiplier) of each point `(p[0][i], p[1][i], p[2][i])` with
    /// normal `(n[0][i], n[1][i], n[2][i])` into `out[i]`, the same bits, with the loop
    /// compiled for AVX2 where the CPU has it. Without branches: the point budget's
    /// probes are in view and turned away in no order a branch predictor learns, and
    /// 4096 of them took 0.15 ms one at a time. Panics when a column is shorter than
    /// `out`.
    pub(crate) fn multipliers_into(&self, p: [&[f64]; 3], n: [&[f64]; 3], out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if Level::detected() >= Level::Avx2 {
            // SAFETY: the CPU has every feature of `Level::Avx2`, which is what the
            // function is compiled with.
            #[allow(unsafe_code)]
            unsafe {
                self.multipliers_v3(p, n, out);
            }
            return;
        }
        self.multipliers_body(p, n, out);
    }

    /// [`multipliers_body`](Self::multipliers_body) compiled with AVX2 (no fused
    /// multiply-add enabled, so the same operations round the same).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    fn multipliers_v3(&self, p: [&[f64]; 3], n: [&[f64]; 3], out: &mut [f64]) {
        self.multipliers_body(p, n, out);
    }

    /// [`multiplier`](Self::multiplier)'s operations in its order (glam's
    /// matrix-vector product by columns, its dot products left to right), all
    /// computed and the result selected. Always inlined, so that each caller's target
    /// features apply to it.
    #[inline(always)]
    fn multipliers_body(&self, p: [&[f64]; 3], n: [&[f64]; 3], out: &mut [f64]) {
        let len = out.len();
        let [px, py, pz] = p.map(|c| &c[..len]);
        let [nx, ny, nz] = n.map(|c| &c[..len]);
        let m = &self.clip_from_world;
        let row = |r: usize| {
            let [a, b, c, d] = [m.x_axis, m.y_axis, m.z_axis, m.w_axis].map(|v| v[r]);
            move |x: f64, y: f64, z: f64| a * x + b * y + c * z + d * 1.0
        };
        let (cx, cy, cz, cw) = (row(0), row(1), row(2), row(3));
        let (eye, ff) = (self.eye, self.focal_pixels * self.focal_pixels);
        let (reference, max, cull) = (self.reference, self.max, self.cull_back_faces);
        for i in 0..len {
            let (x, y, z) = (px[i], py[i], pz[i]);
            let w = cw(x, y, z);
            let (qx, qy, qz) = (cx(x, y, z), cy(x, y, z), cz(x, y, z));
            let inside = (w > 0.0) & (qx.abs() <= w) & (qy.abs() <= w) & (0.0 <= qz) & (qz <= w);
            let (ex, ey, ez) = (eye.x - x, eye.y - y, eye.z - z);
            let d = (ex * ex + ey * ey + ez * ez).sqrt();
            let cos = (nx[i] * ex + ny[i] * ey + nz[i] * ez) / d;
            let area = ff * cos.abs() * d / (w * w * w);
            let value = (area / reference).min(max);
            let shown = inside & (d > 0.0) & !(cull & (cos < 0.0));
            out[i] = if shown { value } else { 0.0 };
        }
    }
}

/// Whether rank `rank` is visible under base count `base` and multiplier `lod`:
/// `rank < base lod`.
pub fn visible(rank: u32, base: f64, lod: f64) -> bool {
    f64::from(rank) < base * lod
}

/// The fade weight of rank `rank`: `clamp(base lod - rank, 0, 1)`; positive exactly
/// when the rank is [`visible`].
pub fn fade(rank: u32, base: f64, lod: f64) -> f64 {
    (base * lod - f64::from(rank)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera at `eye` looking at the origin, 60 degrees tall, 800 x 600 pixels.
    fn view(eye: DVec3, cull: bool) -> ViewLod {
        let fov = 60f64.to_radians();
        let proj =
            glam::camera::rh::proj::directx::perspective(fov as f32, 800.0 / 600.0, 0.01, 100.0);
        let look =
            glam::camera::rh::view::look_at_mat4(eye.as_vec3(), glam::Vec3::ZERO, glam::Vec3::Y);
        ViewLod {
            clip_from_world: (proj * look).as_dmat4(),
            eye,
            focal_pixels: 600.0 / (2.0 * (fov / 2.0).tan()),
            reference: 1000.0,
            max: f64::INFINITY,
            cull_back_faces: cull,
        }
    }

    /// The pixel area of the small square `p + s (a u + b v)`, `a, b in [0, 1]`,
    /// projected by `view` onto its 800 x 600 viewport.
    fn projected_area(view: &ViewLod, p: DVec3, u: DVec3, v: DVec3, s: f64) -> f64 {
        let pixel = |q: DVec3| {
            let c = view.clip_from_world * DVec4::new(q.x, q.y, q.z, 1.0);
            glam::DVec2::new(c.x / c.w * 400.0, c.y / c.w * 300.0)
        };
        let [a, b, c, d] = [p, p + s * u, p + s * (u + v), p + s * v].map(pixel);
        // Shoelace formula.
        0.5 * ((a.perp_dot(b) + b.perp_dot(c) + c.perp_dot(d) + d.perp_dot(a)).abs())
    }

    #[test]
    fn a_placed_mesh_gets_the_world_multiplier_in_local_space() {
        let world = view(DVec3::new(0.5, 1.0, 4.0), true);
        let transform = DAffine3::from_scale_rotation_translation(
            DVec3::splat(0.7),
            glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.4),
            DVec3::new(0.2, -0.3, 0.5),
        );
        let local = world.in_local_frame(&transform).expect("a similarity");
        local.validate().expect("valid settings");
        let rotation = transform.matrix3 / 0.7;
        let mut shown = 0;
        for k in 0..200 {
            let t = k as f64 * 0.37;
            let p = DVec3::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin()) * 1.5;
            let n = DVec3::new((2.1 * t).cos(), t.cos(), (0.3 * t).sin()).normalize();
            let expected = world.multiplier(transform.transform_point3(p), rotation * n);
            let found = local.multiplier(p, n);
            assert!(
                (found - expected).abs() <= 1e-9 * expected.max(1e-12),
                "{k}: {found} vs {expected}"
            );
            shown += usize::from(expected > 0.0);
        }
        // The check covered points in view and out of it, facing and turned away.
        assert!(shown > 20 && shown < 180, "{shown} of 200 in view");
        // Shear, non-uniform scale and reflection are refused.
        for linear in [
            glam::DMat3::from_cols(DVec3::X, DVec3::new(0.3, 1.0, 0.0), DVec3::Z),
            glam::DMat3::from_diagonal(DVec3::new(1.0, 2.0, 1.0)),
            glam::DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0)),
        ] {
            let t = DAffine3::from_mat3(linear);
            assert!(matches!(
                world.in_local_frame(&t),
                Err(LodError::NotSimilarity { .. })
            ));
        }
    }

    #[test]
    fn batch_multipliers_equal_the_multiplier_bit_for_bit() {
        let mut rng = crate::rng::Rng::new(19, 0);
        for (k, eye) in [DVec3::new(0.3, 0.8, 4.0), DVec3::new(-2.0, 0.5, -1.0)]
            .into_iter()
            .enumerate()
        {
            for cull in [false, true] {
                let mut v = view(eye, cull);
                v.max = if k == 0 { f64::INFINITY } else { 3.0 };
                let len = 1001;
                let mut cols = [(); 6].map(|_| Vec::with_capacity(len));
                for i in 0..len {
                    // Points around the origin, some behind the camera and far off,
                    // one at the eye; unit normals in every direction.
                    let p = if i == 0 {
                        eye
                    } else {
                        DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 12.0 - 6.0
                    };
                    let n = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
                    let n = n.normalize_or(DVec3::Z);
                    for (c, x) in cols
                        .iter_mut()
                        .zip(p.to_array().into_iter().chain(n.to_array()))
                    {
                        c.push(x);
                    }
                }
                let mut out = vec![f64::NAN; len];
                let [px, py, pz, nx, ny, nz] = cols.each_ref().map(Vec::as_slice);
                v.multipliers_into([px, py, pz], [nx, ny, nz], &mut out);
                let mut seen = [0usize; 2];
                for i in 0..len {
                    let (p, n) = (
                        DVec3::new(px[i], py[i], pz[i]),
                        DVec3::new(nx[i], ny[i], nz[i]),
                    );
                    let one = v.multiplier(p, n);
                    assert_eq!(
                        out[i].to_bits(),
                        one.to_bits(),
                        "point {i}: {p}, normal {n}"
                    );
                    seen[usize::from(one > 0.0)] += 1;
                }
                // Points in view and out of it (or turned away) were both checked.
                assert!(seen[0] > 100 && seen[1] > 50, "{seen:?}");
            }
        }
    }

    #[test]
    fn the_multiplier_is_the_projected_area_per_unit_area() {
        let lod = view(DVec3::new(0.3, 0.8, 4.0), false);
        let s = 1e-4;
        for (p, n) in [
            (DVec3::ZERO, DVec3::Z),
            (
                DVec3::new(0.9, -0.4, 0.2),
                DVec3::new(0.3, 0.2, 1.0).normalize(),
            ),
            (
                DVec3::new(-1.1, 0.6, -0.5),
                DVec3::new(-0.6, 0.1, 0.4).normalize(),
            ),
        ] {
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            let pixels = projected_area(&lod, p, u, v, s) / (s * s);
            let m = lod.multiplier(p, n);
            assert!(
                (m * lod.reference - pixels).abs() <= 1e-3 * pixels,
                "{p}: {} against {pixels}",
                m * lod.reference
            );
        }
    }

    #[test]
    fn facing_the_camera_on_its_axis_falls_with_the_square_of_the_distance() {
        for d in [1.0, 2.0, 4.0] {
            let lod = view(DVec3::new(0.0, 0.0, d), false);
            let expected = lod.focal_pixels * lod.focal_pixels / (d * d) / lod.reference;
            let m = lod.multiplier(DVec3::ZERO, DVec3::Z);
            assert!((m - expected).abs() <= 1e-9 * expected, "{m} {expected}");
        }
    }

    #[test]
    fn outside_the_frustum_behind_the_eye_and_on_back_faces_is_zero() {
        let lod = view(DVec3::new(0.0, 0.0, 4.0), true);
        assert_eq!(lod.multiplier(DVec3::new(30.0, 0.0, 0.0), DVec3::Z), 0.0);
        assert_eq!(lod.multiplier(DVec3::new(0.0, 0.0, 9.0), DVec3::Z), 0.0);
        assert_eq!(lod.multiplier(DVec3::new(0.0, 0.0, -200.0), DVec3::Z), 0.0);
        assert_eq!(lod.multiplier(DVec3::ZERO, -DVec3::Z), 0.0);
        let both = view(DVec3::new(0.0, 0.0, 4.0), false);
        assert_eq!(
            both.multiplier(DVec3::ZERO, -DVec3::Z),
            both.multiplier(DVec3::ZERO, DVec3::Z)
        );
        let clamped = ViewLod { max: 0.5, ..both };
        assert_eq!(clamped.multiplier(DVec3::ZERO, DVec3::Z), 0.5);
    }

    #[test]
    fn settings_out_of_range_are_named() {
        let good = view(DVec3::new(0.0, 0.0, 4.0), false);
        assert_eq!(good.validate(), Ok(()));
        let named = |lod: ViewLod| match lod.validate() {
            Err(LodError::Invalid { setting, .. }) => setting,
            Err(e) => panic!("{e}"),
            Ok(()) => "accepted",
        };
        assert_eq!(
            named(ViewLod {
                reference: 0.0,
                ..good
            }),
            "reference"
        );
        assert_eq!(
            named(ViewLod {
                reference: f64::NAN,
                ..good
            }),
            "reference"
        );
        assert_eq!(
            named(ViewLod {
                focal_pixels: -1.0,
                ..good
            }),
            "focal_pixels"
        );
        assert_eq!(named(ViewLod { max: 0.0, ..good }), "max");
        assert_eq!(
            named(ViewLod {
                eye: DVec3::new(f64::INFINITY, 0.0, 0.0),
                ..good
            }),
            "eye"
        );
        let mut m = good.clip_from_world;
        m.w_axis.x = f64::NAN;
        assert_eq!(
            named(ViewLod {
                clip_from_world: m,
                ..good
            }),
            "clip_from_world"
        );
        let e = ViewLod {
            reference: -2.0,
            ..good
        }
        .validate()
        .expect_err("bad");
        assert_eq!(
            e.to_string(),
            "level of detail: reference = -2 must be finite and > 0"
        );
    }

    #[test]
    fn visible_ranks_and_fades_follow_their_definition() {
        let (base, lod) = (1000.0, 0.25);
        let shown: Vec<u32> = (0..2000).filter(|&k| visible(k, base, lod)).collect();
        assert_eq!(shown, (0..250).collect::<Vec<_>>());
        for k in 0..2000 {
            assert_eq!(fade(k, base, lod) > 0.0, visible(k, base, lod), "{k}");
        }
        assert_eq!(fade(100, base, lod), 1.0);
        assert!((fade(249, 1000.0, 0.2495) - 0.5).abs() < 1e-9);
        // A larger multiplier only adds ranks.
        for k in 0..2000 {
            if visible(k, base, lod) {
                assert!(visible(k, base, lod * 1.01));
            }
        }
    }
}
