//! Tubes of staggered rings: the open [`cylinder`] and the [`torus`]. Consecutive rings
//! are rotated by half a segment and stitched by [`stitch_rings`], so triangles are close
//! to equilateral. Cost O(faces).

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::limits::{MAX_SHAPE_FACES, check_length, check_resolution, invalid};
use crate::mesh::{MeshError, TriMesh};

/// Rows of a staggered strip are this fraction of the segment length apart, which makes
/// the triangles equilateral on a flat strip.
const ROW_SPACING: f64 = 0.866_025_403_784_438_6; // sqrt(3) / 2

/// Triangles between two rings of `n` vertices (`a`, `b`: index of each ring's first
/// vertex) that are offset by half a segment from each other. `a_shifted` tells which
/// ring is the shifted one. Outward is (direction of increasing vertex index) x
/// (direction from ring `a` to ring `b`).
fn stitch_rings(triangles: &mut Vec<[u32; 3]>, a: u32, a_shifted: bool, b: u32, n: u32) {
    for i in 0..n {
        let j = (i + 1) % n;
        let (ai, aj, bi, bj) = (a + i, a + j, b + i, b + j);
        if a_shifted {
            triangles.push([ai, bj, bi]);
            triangles.push([ai, aj, bj]);
        } else {
            triangles.push([ai, aj, bi]);
            triangles.push([bi, aj, bj]);
        }
    }
}

/// An open tube of `radius` around the z axis, from `z = -height / 2` to `height / 2`.
///
/// `resolution` vertices go around each ring; consecutive rings are rotated by half a
/// segment and spaced `sqrt(3) / 2` segment lengths apart (rounded so that a whole number
/// of rows fills the height, at least one row), so triangles are close to equilateral
/// unless the height is much smaller than a segment. `2 resolution rows` faces, two
/// boundary loops (the end rings, `resolution` vertices each), Euler characteristic 0.
///
/// `radius` and `height` are lengths in [1e-30, 1e30]; `resolution` is at least 3. The
/// mesh may have at most [`MAX_SHAPE_FACES`] faces (they grow like resolution² height /
/// radius): a height so large compared to the radius that even resolution 3 exceeds that
/// is rejected as `height`, otherwise a resolution too large as `resolution`.
///
/// ```
/// use strata_engine::mesh::shapes::cylinder;
/// let mesh = cylinder(1.0, 2.0, 32)?;
/// assert_eq!(mesh.boundary_loops().len(), 2);
/// assert_eq!(mesh.euler_characteristic(), 0);
/// assert!((mesh.area() - 4.0 * std::f64::consts::PI).abs() < 0.05);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn cylinder(radius: f64, height: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    check_length("cylinder", "radius", radius)?;
    check_length("cylinder", "height", height)?;
    // Faces grow like resolution^2 height / radius: blame the height only if even the
    // coarsest tube is too large.
    let rows_for = |n: u32| {
        let segment = 2.0 * radius * (PI / f64::from(n)).sin();
        (height / (segment * ROW_SPACING)).round().max(1.0)
    };
    if 2.0 * 3.0 * rows_for(3) > MAX_SHAPE_FACES as f64 {
        return Err(invalid(
            "cylinder",
            "height",
            height,
            "a length with at most 2^24 faces at resolution 3 (rows ~ 0.67 height / radius)",
        ));
    }
    let n = resolution;
    let rows = if n >= 3 { rows_for(n) } else { 1.0 };
    check_resolution(
        "cylinder",
        n,
        3,
        2.0 * f64::from(n) * rows,
        concat!(
            "an integer >= 3 with at most 2^24 faces",
            " (2 resolution rows, rows ~ 0.18 resolution height / radius)"
        ),
    )?;
    let rows = rows as u32;
    let mut positions = Vec::with_capacity(((rows + 1) * n) as usize);
    for j in 0..=rows {
        let z = height * (f64::from(j) / f64::from(rows) - 0.5);
        let shift = 0.5 * f64::from(j % 2);
        for i in 0..n {
            let angle = TAU * (f64::from(i) + shift) / f64::from(n);
            positions.push(DVec3::new(radius * angle.cos(), radius * angle.sin(), z));
        }
    }
    let mut triangles = Vec::with_capacity((2 * rows * n) as usize);
    for j in 0..rows {
        stitch_rings(&mut triangles, j * n, j % 2 == 1, (j + 1) * n, n);
    }
    TriMesh::new(positions, triangles)
}

/// A ring torus around the z axis, centred at the origin: the tube of `minor_radius`
/// around the circle of `major_radius` in the z = 0 plane.
///
/// `resolution` vertices go around the tube in each of `m` rings; `m` is the even number
/// nearest `2 resolution major_radius / (sqrt(3) minor_radius)` (at least 4) and
/// consecutive rings are rotated by half a segment, so triangles are close to equilateral
/// along the tube's centre line (stretched outside and squeezed inside it, more so the
/// fatter the torus). `2 resolution m` faces, closed, Euler characteristic 0.
///
/// `major_radius` and `minor_radius` are lengths in [1e-30, 1e30] with
/// `minor_radius < major_radius`; `resolution` is at least 3. The mesh may have at most
/// [`MAX_SHAPE_FACES`] faces (they grow like resolution² major_radius / minor_radius): a
/// minor radius so small that even resolution 3 exceeds that is rejected as
/// `minor_radius`, otherwise a resolution too large as `resolution`.
///
/// ```
/// use std::f64::consts::PI;
/// use strata_engine::mesh::shapes::torus;
/// let mesh = torus(2.0, 0.5, 16)?;
/// assert_eq!(mesh.euler_characteristic(), 0);
/// assert!(mesh.boundary_loops().is_empty());
/// assert!((mesh.area() - 4.0 * PI * PI * 2.0 * 0.5).abs() < 0.5);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn torus(major_radius: f64, minor_radius: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    check_length("torus", "major_radius", major_radius)?;
    check_length("torus", "minor_radius", minor_radius)?;
    if minor_radius >= major_radius {
        return Err(invalid(
            "torus",
            "minor_radius",
            minor_radius,
            "a length smaller than major_radius (a self-touching torus is not a manifold)",
        ));
    }
    // Faces grow like resolution^2 major_radius / minor_radius: blame the minor radius
    // only if even the coarsest torus is too large.
    let rings_for = |n: u32| {
        let rings = f64::from(n) * major_radius / (ROW_SPACING * minor_radius);
        (2.0 * (0.5 * rings).round()).max(4.0)
    };
    if 2.0 * 3.0 * rings_for(3) > MAX_SHAPE_FACES as f64 {
        return Err(invalid(
            "torus",
            "minor_radius",
            minor_radius,
            concat!(
                "a length with at most 2^24 faces at resolution 3",
                " (rings ~ 3.5 major_radius / minor_radius)"
            ),
        ));
    }
    let n = resolution;
    let rings = if n >= 3 { rings_for(n) } else { 4.0 };
    check_resolution(
        "torus",
        n,
        3,
        2.0 * f64::from(n) * rings,
        concat!(
            "an integer >= 3 with at most 2^24 faces",
            " (2 resolution rings, rings ~ 1.15 resolution major_radius / minor_radius)"
        ),
    )?;
    let m = rings as u32;
    let mut positions = Vec::with_capacity((m * n) as usize);
    for j in 0..m {
        let phi = TAU * f64::from(j) / f64::from(m);
        let shift = 0.5 * f64::from(j % 2);
        for i in 0..n {
            // Going around the tube clockwise (seen along +phi) makes (around the ring) x
            // (to the next ring) point outward, as `stitch_rings` needs.
            let theta = -TAU * (f64::from(i) + shift) / f64::from(n);
            let rho = major_radius + minor_radius * theta.cos();
            positions.push(DVec3::new(
                rho * phi.cos(),
                rho * phi.sin(),
                minor_radius * theta.sin(),
            ));
        }
    }
    let mut triangles = Vec::with_capacity((2 * m * n) as usize);
    for j in 0..m {
        // `m` is even, so the last ring (odd, shifted) meets ring 0 (not shifted).
        stitch_rings(&mut triangles, j * n, j % 2 == 1, ((j + 1) % m) * n, n);
    }
    TriMesh::new(positions, triangles)
}
