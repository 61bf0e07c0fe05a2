//! Built-in procedural shapes, so that strata runs and tests without external files.

use glam::DVec3;

use super::{MeshError, TriMesh};

/// A flat square grid in the z = 0 plane, `[0, size]^2`, with `resolution` quads per
/// side, each split into two triangles (normals along +z).
pub fn plane(size: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    let n = resolution.max(1);
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            positions.push(DVec3::new(
                size * i as f64 / n as f64,
                size * j as f64 / n as f64,
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
