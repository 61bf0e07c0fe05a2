//! An orbit camera: a target, a distance, yaw and pitch; framing of a bounding box.
//!
//! Y is up. At yaw 0 and pitch 0 the camera sits on the +Z side of the target looking
//! towards -Z; positive yaw turns it towards +X, positive pitch raises it.

use glam::{Mat4, Vec3};
use strata_engine::mesh::TriMesh;

/// A perspective camera orbiting a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// The point looked at, world space.
    pub target: Vec3,
    /// Distance from the target, world units (> 0).
    pub distance: f32,
    /// Rotation about +Y, radians.
    pub yaw: f32,
    /// Elevation above the XZ plane, radians, kept within (-pi/2, pi/2).
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Radius of the scene around the target (sets the near and far planes).
    pub radius: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            target: Vec3::ZERO,
            distance: 3.0,
            yaw: 30f32.to_radians(),
            pitch: 20f32.to_radians(),
            fov_y: 35f32.to_radians(),
            radius: 1.0,
        }
    }
}

impl OrbitCamera {
    /// A camera at `yaw`, `pitch` (radians) that frames the box `min..max` at `aspect`
    /// (width / height): see [`fit_box`](Self::fit_box).
    pub fn framing(min: Vec3, max: Vec3, aspect: f32, yaw: f32, pitch: f32) -> Self {
        let mut camera = Self {
            yaw,
            pitch,
            ..Self::default()
        };
        camera.fit_box(min, max, aspect);
        camera
    }

    /// Looks at the centre of the box `min..max` from the smallest distance at which its
    /// eight corners project inside the central 90% of the view (found by bisection
    /// between the box's bounding sphere and a distance at which that sphere fits).
    pub fn fit_box(&mut self, min: Vec3, max: Vec3, aspect: f32) {
        self.target = 0.5 * (min + max);
        self.radius = (0.5 * (max - min).length()).max(1e-6);
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                )
            })
            .collect();
        let fits = |camera: &Self| {
            let vp = camera.view_proj(aspect);
            corners.iter().all(|&c| {
                let clip = vp * c.extend(1.0);
                clip.w > 0.0 && (clip.x.abs().max(clip.y.abs()) / clip.w) <= 0.9
            })
        };
        // At `sphere` the bounding sphere fits in 90% of the view, so the box does too.
        let half_v = 0.5 * self.fov_y;
        let half_h = (half_v.tan() * aspect.max(1e-3)).atan();
        let tan_half = 0.9 * half_v.tan().min(half_h.tan());
        let sphere = self.radius / tan_half.atan().sin();
        let (mut lo, mut hi) = (1.01 * self.radius, sphere.max(1.01 * self.radius));
        self.distance = hi;
        if !fits(self) {
            return;
        }
        for _ in 0..40 {
            self.distance = 0.5 * (lo + hi);
            if fits(self) {
                hi = self.distance;
            } else {
                lo = self.distance;
            }
        }
        self.distance = hi;
    }

    /// This camera's yaw, pitch and field of view, looking at `mesh`: its bounding box
    /// fitted at `aspect` ([`fit_box`](Self::fit_box)), then the distance multiplied by
    /// `zoom` (< 1 is closer).
    pub fn fitted_to_mesh(mut self, mesh: &TriMesh, aspect: f32, zoom: f32) -> Self {
        let (min, max) = mesh.bounds();
        self.fit_box(min.as_vec3(), max.as_vec3(), aspect);
        self.distance *= zoom;
        self
    }

    /// The camera position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// The clip-from-world matrix for a target of `aspect` (width / height), with depth
    /// in [0, 1] as wgpu expects.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y);
        let near = (self.distance - 1.5 * self.radius).max(self.distance * 1e-3);
        let far = self.distance + 2.0 * self.radius;
        // WebGPU's NDC: depth in [0, 1], Y up (glam's "directx" convention).
        glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-3), near, far) * view
    }

    /// Turns the camera by `d_yaw`, `d_pitch` radians (pitch kept off the poles).
    pub fn orbit(&mut self, d_yaw: f32, d_pitch: f32) {
        let limit = 89f32.to_radians();
        self.yaw += d_yaw;
        self.pitch = (self.pitch + d_pitch).clamp(-limit, limit);
    }

    /// Multiplies the distance by `factor` (> 0), within 1% to 100x of the radius.
    pub fn zoom(&mut self, factor: f32) {
        if factor > 0.0 && factor.is_finite() {
            self.distance = (self.distance * factor).clamp(0.01 * self.radius, 100.0 * self.radius);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_keeps_the_box_inside_the_view() {
        let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 2.5));
        for aspect in [0.5, 1.0, 2.0] {
            let camera = OrbitCamera::framing(min, max, aspect, 0.4, 0.3);
            let vp = camera.view_proj(aspect);
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let clip = vp * corner.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0, "{aspect} {ndc}");
                assert!((0.0..=1.0).contains(&ndc.z), "{ndc}");
            }
        }
    }

    #[test]
    fn fitting_to_a_mesh_keeps_the_orientation_and_scales_the_distance() {
        let mesh = strata_engine::mesh::shapes::plane(2.0, 2).expect("plane");
        let look = OrbitCamera {
            yaw: 0.25,
            pitch: -0.5,
            fov_y: 0.8,
            ..OrbitCamera::default()
        };
        let fitted = look.fitted_to_mesh(&mesh, 1.5, 1.0);
        let (min, max) = mesh.bounds();
        let mut boxed = look;
        boxed.fit_box(min.as_vec3(), max.as_vec3(), 1.5);
        assert_eq!(fitted, boxed);
        assert_eq!((fitted.yaw, fitted.pitch, fitted.fov_y), (0.25, -0.5, 0.8));
        assert_eq!(fitted.target, Vec3::new(1.0, 1.0, 0.0));
        let closer = look.fitted_to_mesh(&mesh, 1.5, 0.5);
        assert_eq!(closer.distance, 0.5 * fitted.distance);
    }

    #[test]
    fn yaw_zero_pitch_zero_looks_down_minus_z() {
        let camera = OrbitCamera {
            yaw: 0.0,
            pitch: 0.0,
            ..OrbitCamera::default()
        };
        let eye = camera.eye();
        assert!((eye - Vec3::new(0.0, 0.0, camera.distance)).length() < 1e-6);
    }
}
