//! The vertex frames a line field's doubled angles are measured in: the mesh's
//! intrinsic tangent spaces ([`TangentSpaces`], the default), or the tangent planes
//! of smoothed vertex normals (with a smoothing length).
//!
//! Input: doubled angles or world directions per vertex. Output: the other. Cost:
//! O(valence) per vertex (intrinsic) or O(1) (planes).

use std::sync::Arc;

use faer::c64;
use glam::DVec3;

use crate::field::tangent_space::TangentSpaces;

/// Per vertex, how a line's doubled angle relates to a world direction.
pub(crate) enum Frames {
    /// The intrinsic, angle-rescaled tangent spaces of the mesh.
    Intrinsic(Arc<TangentSpaces>),
    /// Orthonormal frames `(e1, e2)` of (smoothed) vertex-normal planes.
    Planes(Vec<(DVec3, DVec3)>),
}

impl Frames {
    /// The line along the world direction `d` at `v` (its part in the vertex's
    /// plane) as a unit doubled-angle complex number, with the length of that part;
    /// `None` where it has none.
    pub(crate) fn doubled(&self, v: usize, d: DVec3) -> Option<(f64, c64)> {
        match self {
            Self::Intrinsic(spaces) => spaces.doubled_angle(v, d).map(|(angle, len)| {
                let (s, c) = angle.sin_cos();
                (len, c64::new(c, s))
            }),
            Self::Planes(frames) => {
                let (e1, e2) = frames[v];
                let (c, s) = (d.dot(e1), d.dot(e2));
                let len2 = c * c + s * s;
                (len2 > 0.0).then(|| {
                    (
                        len2.sqrt(),
                        c64::new((c * c - s * s) / len2, 2.0 * c * s / len2),
                    )
                })
            }
        }
    }

    /// The unit world direction (sign arbitrary) of the line with doubled-angle value
    /// `z` at `v` (the frame's reference direction where `z` is 0).
    pub(crate) fn direction(&self, v: usize, z: c64) -> DVec3 {
        let doubled = z.im.atan2(z.re);
        match self {
            Self::Intrinsic(spaces) => spaces.direction(v, doubled),
            Self::Planes(frames) => {
                let (e1, e2) = frames[v];
                let (s, c) = (0.5 * doubled).sin_cos();
                e1 * c + e2 * s
            }
        }
    }
}
