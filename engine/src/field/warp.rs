//! Anisotropic planar test fields: the metric `J^T J` of a planar map (paper section
//! 7.5 after Wei and Wang 2011, "Differential domain analysis for non-uniform
//! sampling", whose anisotropic examples follow Li et al. 2010, "Anisotropic blue noise
//! sampling").

use glam::{DMat2, DMat3, DVec2};

use super::params::{finite_point, invalid};
use super::{FieldError, TensorField};
use crate::mesh::TriMesh;

/// The perspective map's `w` must exceed this at every vertex: at `w = 0` lies the
/// horizon, where the metric blows up.
const MIN_PERSPECTIVE_W: f64 = 1e-6;

/// A smooth planar map `f: (x, y) -> R^2` whose metric `J^T J` (with `J` the Jacobian
/// of `f`) is used as a tensor field by [`FieldSpec::Warp`](super::FieldSpec::Warp).
/// Each varies in direction and anisotropy across the plane.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub enum PlanarWarp {
    /// A shear whose amount grows along y:
    /// `f(x, y) = (x + shear y + shear_rate y^2 / 2, y)`, so
    /// `J = [[1, s], [0, 1]]` with `s = shear + shear_rate y` and
    /// `J^T J = [[1, s], [s, 1 + s^2]]`. Area-preserving (`det J = 1`, constant
    /// density); the spacing ratio is `(s + sqrt(4 + s^2)) / 2` squared, i.e. the
    /// ratio of `J`'s singular values `(sqrt(4 + s^2) +- s) / 2`, and the major
    /// direction turns from 45 degrees (small `s`) towards the y axis (large `s`).
    /// Isotropic where `s = 0`.
    Shear {
        /// Shear at `y = 0`, finite. Default 0.5.
        #[cfg_attr(feature = "serde", serde(default = "default_shear"))]
        shear: f64,
        /// Change of the shear per unit of y (1 / world unit), finite. Default 1 (on
        /// the paper's `[0, 2]^2`, `s` runs from 0.5 to 2.5).
        #[cfg_attr(feature = "serde", serde(default = "default_shear_rate"))]
        shear_rate: f64,
    },
    /// A projective map, as a plane seen in perspective:
    /// `f(p) = q / w` with `q = p - origin` and `w = 1 + tilt . q`, so
    /// `J = (w I - q tilt^T) / w^2` and `det J = 1 / w^3`: the density falls as
    /// `1 / w^3` towards the horizon `w = 0` (which must not cross the mesh) and
    /// the samples stretch along `tilt`: at `q` parallel to `tilt` the spacing
    /// ratio is `w`. `J = I` at `origin`.
    Perspective {
        /// The gradient of `w` (1 / world unit), finite. Default `[0, 0.5]` (on the
        /// paper's `[0, 4]^2`, `w` runs from 1 to 3).
        #[cfg_attr(feature = "serde", serde(default = "default_tilt"))]
        tilt: [f64; 2],
        /// Where `w = 1` and `J = I`. Default `[0, 0]`.
        #[cfg_attr(feature = "serde", serde(default))]
        origin: [f64; 2],
    },
}

#[cfg(feature = "serde")]
fn default_shear() -> f64 {
    0.5
}

#[cfg(feature = "serde")]
fn default_shear_rate() -> f64 {
    1.0
}

#[cfg(feature = "serde")]
fn default_tilt() -> [f64; 2] {
    [0.0, 0.5]
}

impl PlanarWarp {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), FieldError> {
        match *self {
            Self::Shear { shear, shear_rate } => {
                if !shear.is_finite() {
                    return Err(invalid("shear", shear, "a finite value"));
                }
                if !shear_rate.is_finite() {
                    return Err(invalid("shear_rate", shear_rate, "a finite value"));
                }
                Ok(())
            }
            Self::Perspective { tilt, origin } => {
                finite_point("tilt", tilt)?;
                finite_point("origin", origin)
            }
        }
    }

    /// The Jacobian `J` of the map at `p`, or `Err((value, what))` where the map is
    /// undefined (a perspective `w` at or beyond the horizon).
    pub fn jacobian(&self, p: DVec2) -> Result<DMat2, (f64, &'static str)> {
        match *self {
            Self::Shear { shear, shear_rate } => {
                let s = shear + shear_rate * p.y;
                Ok(DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(s, 1.0)))
            }
            Self::Perspective { tilt, origin } => {
                let t = DVec2::from(tilt);
                let q = p - DVec2::from(origin);
                let w = 1.0 + t.dot(q);
                if !(w > MIN_PERSPECTIVE_W) {
                    return Err((w, "perspective w = 1 + tilt . (p - origin) must be > 1e-6"));
                }
                // q t^T, column by column.
                let qt = DMat2::from_cols(q * t.x, q * t.y);
                Ok((DMat2::IDENTITY * w - qt) * (1.0 / (w * w)))
            }
        }
    }

    /// The planar tensor `density * J^T J` at `p`.
    pub fn metric(&self, p: DVec2, density: f64) -> Result<DMat2, (f64, &'static str)> {
        let j = self.jacobian(p)?;
        Ok(j.transpose() * j * density)
    }

    /// Per-vertex tensors on `mesh` (parameters assumed valid).
    pub(crate) fn build(&self, mesh: &TriMesh, density: f64) -> Result<TensorField, FieldError> {
        let mut tensors = Vec::with_capacity(mesh.vertex_count());
        for (vertex, p) in mesh.positions().iter().enumerate() {
            let m = self
                .metric(p.truncate(), density)
                .map_err(|(value, what)| FieldError::OutsideDomain {
                    vertex,
                    value,
                    what,
                })?;
            tensors.push(DMat3::from_cols(
                m.x_axis.extend(0.0),
                m.y_axis.extend(0.0),
                glam::DVec3::ZERO,
            ));
        }
        TensorField::new(mesh, tensors)
    }
}
