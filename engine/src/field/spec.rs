//! Field sources: how a user describes a tensor field (in a config file or in code).

use glam::{DVec2, DVec3};

use super::{FieldError, TensorField};
use crate::mesh::TriMesh;

/// A tensor field description, turned into per-vertex tensors by [`FieldSpec::build`].
///
/// `anisotropy` is always the spacing ratio `sqrt(l1 / l2) >= 1`: samples are
/// `anisotropy` times closer along the major direction than along the minor one.
/// `density` is `delta = sqrt(l1 l2)` (samples per unit area, up to the global count).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum FieldSpec {
    /// A constant direction projected into each tangent plane, with constant
    /// anisotropy and density. Where the direction is parallel to the normal a
    /// deterministic tangent is used instead.
    Constant {
        /// World-space major direction (need not be unit length).
        direction: [f64; 3],
        /// Spacing ratio `sqrt(l1 / l2)`, at least 1. Default 1 (isotropic).
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        anisotropy: f64,
        /// Density `sqrt(l1 l2)`, positive. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        density: f64,
    },
    /// A planar isotropic density function of the vertices' (x, y) coordinates, with a
    /// constant direction and anisotropy on top (paper section 7.5's test fields).
    Planar {
        /// The density function.
        density: PlanarDensity,
        /// World-space major direction. Default +x.
        #[cfg_attr(feature = "serde", serde(default = "x_axis"))]
        direction: [f64; 3],
        /// Spacing ratio `sqrt(l1 / l2)`, at least 1. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        anisotropy: f64,
    },
}

#[cfg(feature = "serde")]
fn one() -> f64 {
    1.0
}

#[cfg(feature = "serde")]
fn x_axis() -> [f64; 3] {
    [1.0, 0.0, 0.0]
}

/// Density functions of planar position `p = (x, y)`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum PlanarDensity {
    /// `delta(p) = base + peak * exp(-|p - center|^2 / (2 sigma^2))`.
    Gaussian {
        /// Centre of the blob.
        center: [f64; 2],
        /// Standard deviation (world units), positive.
        sigma: f64,
        /// Added density at the centre, non-negative.
        peak: f64,
        /// Density far from the centre, positive.
        base: f64,
    },
}

impl PlanarDensity {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), FieldError> {
        match *self {
            Self::Gaussian {
                center,
                sigma,
                peak,
                base,
            } => {
                positive("sigma", sigma)?;
                positive("base", base)?;
                if !(peak >= 0.0) || !peak.is_finite() {
                    return Err(invalid("peak", peak, "a finite value >= 0"));
                }
                for c in center {
                    if !c.is_finite() {
                        return Err(invalid("center", c, "finite coordinates"));
                    }
                }
                Ok(())
            }
        }
    }

    /// The density at `p`.
    pub fn eval(&self, p: DVec2) -> f64 {
        match *self {
            Self::Gaussian {
                center,
                sigma,
                peak,
                base,
            } => {
                let d2 = (p - DVec2::from(center)).length_squared();
                base + peak * (-d2 / (2.0 * sigma * sigma)).exp()
            }
        }
    }
}

impl FieldSpec {
    /// Checks the parameters without building anything.
    pub fn validate(&self) -> Result<(), FieldError> {
        match self {
            Self::Constant {
                direction,
                anisotropy,
                density,
            } => {
                direction_ok(direction)?;
                anisotropy_ok(*anisotropy)?;
                positive("density", *density)
            }
            Self::Planar {
                density,
                direction,
                anisotropy,
            } => {
                direction_ok(direction)?;
                anisotropy_ok(*anisotropy)?;
                density.validate()
            }
        }
    }

    /// Builds the per-vertex tensors on `mesh`.
    ///
    /// ```
    /// use strata_engine::{field::FieldSpec, mesh::shapes};
    /// let mesh = shapes::plane(1.0, 4)?;
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 4.0, density: 2.0 };
    /// let field = spec.build(&mesh)?;
    /// let e = field.face_eigen(&mesh, 0, [1.0 / 3.0; 3]);
    /// assert!((e.anisotropy() - 4.0).abs() < 1e-12 && (e.density() - 2.0).abs() < 1e-12);
    /// assert!(e.major.x.abs() > 0.999_999);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(&self, mesh: &TriMesh) -> Result<TensorField, FieldError> {
        self.validate()?;
        match self {
            Self::Constant {
                direction,
                anisotropy,
                density,
            } => {
                let n = mesh.vertex_count();
                let ev = eigenvalues(*density, *anisotropy);
                TensorField::from_frames(mesh, &vec![DVec3::from(*direction); n], &vec![ev; n])
            }
            Self::Planar {
                density,
                direction,
                anisotropy,
            } => {
                let n = mesh.vertex_count();
                let ev: Vec<[f64; 2]> = mesh
                    .positions()
                    .iter()
                    .map(|p| eigenvalues(density.eval(p.truncate()), *anisotropy))
                    .collect();
                TensorField::from_frames(mesh, &vec![DVec3::from(*direction); n], &ev)
            }
        }
    }
}

/// Eigenvalues `(l1, l2)` for density `sqrt(l1 l2)` and spacing ratio `sqrt(l1 / l2)`.
pub(crate) fn eigenvalues(density: f64, anisotropy: f64) -> [f64; 2] {
    [density * anisotropy, density / anisotropy]
}

fn invalid(parameter: &'static str, value: f64, expected: &'static str) -> FieldError {
    FieldError::InvalidParameter {
        parameter,
        value,
        expected,
    }
}

fn positive(parameter: &'static str, value: f64) -> Result<(), FieldError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(parameter, value, "a finite value > 0"))
    }
}

fn anisotropy_ok(a: f64) -> Result<(), FieldError> {
    if a >= 1.0 && a.is_finite() {
        Ok(())
    } else {
        Err(invalid("anisotropy", a, "a finite spacing ratio >= 1"))
    }
}

fn direction_ok(d: &[f64; 3]) -> Result<(), FieldError> {
    let v = DVec3::from(*d);
    if v.is_finite() && v.length_squared() > 0.0 {
        Ok(())
    } else {
        Err(invalid("direction", v.length(), "a finite non-zero vector"))
    }
}
