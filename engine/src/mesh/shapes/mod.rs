//! Built-in procedural shapes, so that strata runs and tests without external files.
//!
//! Input: a size and a `resolution`. Output: a [`TriMesh`] that is consistently oriented
//! (counter-clockwise seen from outside, so normals point out of closed shapes), has no
//! duplicated seam vertices (seams close by index wrapping, the shape is closed where
//! the surface is) and builds without [`MeshWarning`]s.
//!
//! | shape | `resolution` is | faces | Euler | boundary loops |
//! | --- | --- | --- | --- | --- |
//! | [`plane`] | quads per side, >= 1 | 2 n² | 1 | 1 |
//! | [`sphere`] | segments per icosahedron edge, >= 1 | 20 n² | 2 | 0 |
//! | [`cylinder`] | segments around, >= 3 | 2 n rows | 0 | 2 |
//! | [`torus`] | segments around the tube, >= 3 | 2 n m | 0 | 0 |
//! | [`genus2`] | Catmull-Clark steps, 1..=8 | 156 · 4ⁿ | -2 | 0 |
//!
//! Parameters are checked first: a length (size, radius, height) that is not finite or
//! not in [1e-30, 1e30] ([`MIN_SHAPE_LENGTH`], [`MAX_SHAPE_LENGTH`]), a resolution below
//! the minimum, or one that would need more than [`MAX_SHAPE_FACES`] faces is a
//! [`MeshError::InvalidShapeParameter`], never a panic. [`Shape`] names a shape and its
//! parameters as data (for configs) and builds it.
//!
//! Cost: O(faces) to generate, then the O(F log F) of [`TriMesh::new`].
//!
//! One file per family: `plane`, `sphere` (geodesic), `tube` (the staggered-ring
//! cylinder and torus), `genus2` (Catmull-Clark of a polycube cage); `shape` holds the
//! [`Shape`] data type and `limits` the parameter checks they all share.
//!
//! [`TriMesh`]: crate::mesh::TriMesh
//! [`TriMesh::new`]: crate::mesh::TriMesh::new
//! [`MeshWarning`]: crate::mesh::MeshWarning
//! [`MeshError::InvalidShapeParameter`]: crate::mesh::MeshError::InvalidShapeParameter

mod genus2;
mod limits;
mod plane;
mod shape;
mod sphere;
mod tube;

pub use genus2::genus2;
pub use limits::{MAX_SHAPE_FACES, MAX_SHAPE_LENGTH, MIN_SHAPE_LENGTH};
pub use plane::plane;
pub use shape::Shape;
pub use sphere::sphere;
pub use tube::{cylinder, torus};
