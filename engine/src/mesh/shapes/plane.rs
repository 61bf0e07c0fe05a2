//! The flat square grid: `2 resolution²` triangles in z = 0. Cost O(faces).

use glam::DVec3;

use super::limits::{check_length, check_resolution};
use crate::mesh::{MeshError, TriMesh};

/// A flat square grid in the z = 0 plane, `[0, size]^2`, with `resolution` quads per
/// side, each split into two triangles (normals along +z).
///
/// `size` is a length in [1e-30, 1e30]; `resolution` is at least 1 with `2 resolution²` at most
/// [`MAX_SHAPE_FACES`](super::MAX_SHAPE_FACES). The mesh is a disk: one boundary loop,
/// Euler characteristic 1.
///
/// ```
/// use strata_engine::mesh::shapes::plane;
/// let mesh = plane(2.0, 4)?;
/// assert_eq!(mesh.face_count(), 32);
/// assert_eq!(mesh.boundary_loops().len(), 1);
/// assert!((mesh.area() - 4.0).abs() < 1e-12);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn plane(size: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    check_length("plane", "size", size)?;
    let n = resolution;
    check_resolution(
        "plane",
        n,
        1,
        2.0 * f64::from(n).powi(2),
        "an integer >= 1 with at most 2^24 faces (2 resolution^2)",
    )?;
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            positions.push(DVec3::new(
                size * f64::from(i) / f64::from(n),
                size * f64::from(j) / f64::from(n),
                0.0,
            ));
        }
    }
    let idx = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::with_capacity((2 * n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles)
}
