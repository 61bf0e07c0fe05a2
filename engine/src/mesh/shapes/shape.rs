//! [`Shape`]: a built-in shape and its parameters as data (configs), with the serde
//! defaults of its fields. Cost: that of the generator it calls.

use super::{cylinder, genus2, plane, sphere, torus};
use crate::mesh::{MeshError, TriMesh};

/// A built-in shape and its parameters, as data (for configs); [`build`](Self::build)
/// makes the mesh.
///
/// With the `serde` feature it (de)serializes externally tagged, for example in RON
/// `Torus(major_radius: 2.0, minor_radius: 0.5)`; missing fields take the defaults
/// documented on each field, unknown fields are an error.
///
/// ```
/// use strata_engine::mesh::shapes::Shape;
/// let mesh = Shape::Sphere { radius: 1.0, resolution: 4 }.build()?;
/// assert_eq!(mesh.face_count(), 320);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub enum Shape {
    /// [`plane`]: a flat square in z = 0.
    Plane {
        /// Side length (world units, > 0). Default 1.
        #[cfg_attr(feature = "serde", serde(default = "default_one"))]
        size: f64,
        /// Quads per side (>= 1). Default 16.
        #[cfg_attr(feature = "serde", serde(default = "default_plane_resolution"))]
        resolution: u32,
    },
    /// [`sphere`]: a geodesic sphere centred at the origin.
    Sphere {
        /// Radius (world units, > 0). Default 1.
        #[cfg_attr(feature = "serde", serde(default = "default_one"))]
        radius: f64,
        /// Segments per icosahedron edge (>= 1; 20 n² faces). Default 8.
        #[cfg_attr(feature = "serde", serde(default = "default_sphere_resolution"))]
        resolution: u32,
    },
    /// [`cylinder`]: an open tube along z, centred at the origin.
    Cylinder {
        /// Radius (world units, > 0). Default 1.
        #[cfg_attr(feature = "serde", serde(default = "default_one"))]
        radius: f64,
        /// Length along z (world units, > 0). Default 2.
        #[cfg_attr(feature = "serde", serde(default = "default_two"))]
        height: f64,
        /// Segments around (>= 3). Default 32.
        #[cfg_attr(feature = "serde", serde(default = "default_cylinder_resolution"))]
        resolution: u32,
    },
    /// [`torus`]: a ring torus around z, centred at the origin.
    Torus {
        /// Radius of the tube's centre circle (world units, > minor_radius). Default 1.
        #[cfg_attr(feature = "serde", serde(default = "default_one"))]
        major_radius: f64,
        /// Radius of the tube (world units, > 0, < major_radius). Default 0.25.
        #[cfg_attr(feature = "serde", serde(default = "default_minor_radius"))]
        minor_radius: f64,
        /// Segments around the tube (>= 3). Default 16.
        #[cfg_attr(feature = "serde", serde(default = "default_torus_resolution"))]
        resolution: u32,
    },
    /// [`genus2`]: a closed double torus, centred at the origin.
    Genus2 {
        /// Length along x (world units, > 0). Default 2.
        #[cfg_attr(feature = "serde", serde(default = "default_two"))]
        size: f64,
        /// Catmull-Clark steps (1..=8; 156 · 4ⁿ faces). Default 3.
        #[cfg_attr(feature = "serde", serde(default = "default_genus2_resolution"))]
        resolution: u32,
    },
}

#[cfg(feature = "serde")]
fn default_one() -> f64 {
    1.0
}
#[cfg(feature = "serde")]
fn default_two() -> f64 {
    2.0
}
#[cfg(feature = "serde")]
fn default_minor_radius() -> f64 {
    0.25
}
#[cfg(feature = "serde")]
fn default_plane_resolution() -> u32 {
    16
}
#[cfg(feature = "serde")]
fn default_sphere_resolution() -> u32 {
    8
}
#[cfg(feature = "serde")]
fn default_cylinder_resolution() -> u32 {
    32
}
#[cfg(feature = "serde")]
fn default_torus_resolution() -> u32 {
    16
}
#[cfg(feature = "serde")]
fn default_genus2_resolution() -> u32 {
    3
}

impl Default for Shape {
    /// A unit sphere with 1280 faces.
    fn default() -> Self {
        Self::Sphere {
            radius: 1.0,
            resolution: 8,
        }
    }
}

impl Shape {
    /// Builds the mesh by calling the shape's generator; errors as the generator's.
    pub fn build(&self) -> Result<TriMesh, MeshError> {
        match *self {
            Self::Plane { size, resolution } => plane(size, resolution),
            Self::Sphere { radius, resolution } => sphere(radius, resolution),
            Self::Cylinder {
                radius,
                height,
                resolution,
            } => cylinder(radius, height, resolution),
            Self::Torus {
                major_radius,
                minor_radius,
                resolution,
            } => torus(major_radius, minor_radius, resolution),
            Self::Genus2 { size, resolution } => genus2(size, resolution),
        }
    }
}
