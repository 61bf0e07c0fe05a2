//! Built-in procedural shapes, so that strata runs and tests without external files.
//!
//! Input: a size and a `resolution`. Output: a [`TriMesh`] that is consistently oriented
//! (counter-clockwise seen from outside, so normals point out of closed shapes), has no
//! duplicated seam vertices (seams close by index wrapping, the shape is closed where
//! the surface is) and builds without [`MeshWarning`](super::MeshWarning)s.
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

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::{MeshError, NONE, TriMesh};

/// The most faces a built-in shape may have (2^24, about 2 GB of mesh with adjacency).
pub const MAX_SHAPE_FACES: u64 = 1 << 24;

/// The smallest length (size, radius, height) a built-in shape accepts.
///
/// Lengths are bounded so that squared edge lengths and cross products neither underflow
/// nor overflow `f64`.
pub const MIN_SHAPE_LENGTH: f64 = 1e-30;

/// The largest length (size, radius, height) a built-in shape accepts.
pub const MAX_SHAPE_LENGTH: f64 = 1e30;

const LENGTH_EXPECTED: &str = "a finite length in [1e-30, 1e30]";

/// Rows of a staggered strip are this fraction of the segment length apart, which makes
/// the triangles equilateral on a flat strip.
const ROW_SPACING: f64 = 0.866_025_403_784_438_6; // sqrt(3) / 2

fn invalid(
    shape: &'static str,
    parameter: &'static str,
    value: f64,
    expected: &'static str,
) -> MeshError {
    MeshError::InvalidShapeParameter {
        shape,
        parameter,
        value,
        expected,
    }
}

fn check_length(shape: &'static str, parameter: &'static str, value: f64) -> Result<(), MeshError> {
    if (MIN_SHAPE_LENGTH..=MAX_SHAPE_LENGTH).contains(&value) {
        Ok(())
    } else {
        Err(invalid(shape, parameter, value, LENGTH_EXPECTED))
    }
}

/// Accepts `resolution` if it is at least `min` and the shape has at most
/// [`MAX_SHAPE_FACES`] faces (`faces` is computed in `f64` so that it cannot overflow).
fn check_resolution(
    shape: &'static str,
    resolution: u32,
    min: u32,
    faces: f64,
    expected: &'static str,
) -> Result<(), MeshError> {
    if resolution < min || faces > MAX_SHAPE_FACES as f64 {
        Err(invalid(
            shape,
            "resolution",
            f64::from(resolution),
            expected,
        ))
    } else {
        Ok(())
    }
}

/// A flat square grid in the z = 0 plane, `[0, size]^2`, with `resolution` quads per
/// side, each split into two triangles (normals along +z).
///
/// `size` is a length in [1e-30, 1e30]; `resolution` is at least 1 with `2 resolution²` at most
/// [`MAX_SHAPE_FACES`]. The mesh is a disk: one boundary loop, Euler characteristic 1.
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

/// Corners of the regular icosahedron (before normalization), golden-ratio form.
const ICOSAHEDRON_VERTICES: [[f64; 3]; 12] = {
    const T: f64 = 1.618_033_988_749_895; // (1 + sqrt(5)) / 2
    [
        [-1.0, T, 0.0],
        [1.0, T, 0.0],
        [-1.0, -T, 0.0],
        [1.0, -T, 0.0],
        [0.0, -1.0, T],
        [0.0, 1.0, T],
        [0.0, -1.0, -T],
        [0.0, 1.0, -T],
        [T, 0.0, -1.0],
        [T, 0.0, 1.0],
        [-T, 0.0, -1.0],
        [-T, 0.0, 1.0],
    ]
};

/// Faces of the icosahedron, counter-clockwise seen from outside.
const ICOSAHEDRON_FACES: [[u32; 3]; 20] = [
    [0, 11, 5],
    [0, 5, 1],
    [0, 1, 7],
    [0, 7, 10],
    [0, 10, 11],
    [1, 5, 9],
    [5, 11, 4],
    [11, 10, 2],
    [10, 7, 6],
    [7, 1, 8],
    [3, 9, 4],
    [3, 4, 2],
    [3, 2, 6],
    [3, 6, 8],
    [3, 8, 9],
    [4, 9, 5],
    [2, 4, 11],
    [6, 2, 10],
    [8, 6, 7],
    [9, 8, 1],
];

/// A sphere of `radius` centred at the origin: a geodesic (icosahedral) sphere.
///
/// Each face of the icosahedron is cut into `resolution²` triangles (`resolution`
/// segments per edge, "frequency" subdivision) whose vertices are pushed out onto the
/// sphere; `resolution = 1` is the icosahedron itself. Every vertex lies on the sphere,
/// there are no poles and no seams, and triangles stay well shaped at every resolution
/// (smallest angle above 50°). `20 resolution²` faces, `10 resolution² + 2` vertices,
/// Euler characteristic 2.
///
/// `radius` is a length in [1e-30, 1e30]; `resolution` is at least 1 with `20 resolution²` at most
/// [`MAX_SHAPE_FACES`] (so at most 915).
///
/// ```
/// use strata_engine::mesh::shapes::sphere;
/// let mesh = sphere(1.0, 8)?;
/// assert_eq!(mesh.face_count(), 1280);
/// assert_eq!(mesh.euler_characteristic(), 2);
/// // An inscribed polyhedron: its area is 0.5 % short of 4 pi r^2 at resolution 8.
/// assert!((mesh.area() / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn sphere(radius: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    check_length("sphere", "radius", radius)?;
    let n = resolution;
    check_resolution(
        "sphere",
        n,
        1,
        20.0 * f64::from(n).powi(2),
        "an integer >= 1 with at most 2^24 faces (20 resolution^2)",
    )?;
    let corners = ICOSAHEDRON_VERTICES.map(|c| DVec3::from_array(c).normalize());
    let on_sphere = |p: DVec3| p.normalize() * radius;
    let mut positions: Vec<DVec3> = corners.iter().map(|&c| c * radius).collect();
    // The n - 1 points inside each icosahedron edge, keyed by the sorted corner pair and
    // stored from the lower corner, so that both faces of the edge share them.
    let mut edge_points: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edge_point = |positions: &mut Vec<DVec3>, from: u32, to: u32, steps: u32| -> u32 {
        let (lo, hi) = (from.min(to), from.max(to));
        let first = *edge_points.entry((lo, hi)).or_insert_with(|| {
            let first = positions.len() as u32;
            let (a, b) = (corners[lo as usize], corners[hi as usize]);
            for s in 1..n {
                positions.push(on_sphere(a.lerp(b, f64::from(s) / f64::from(n))));
            }
            first
        });
        if from == lo {
            first + steps - 1
        } else {
            first + n - steps - 1
        }
    };
    let mut triangles = Vec::with_capacity(20 * (n * n) as usize);
    // Row i of a face (a, b, c) holds the points (a (n - i) + b (i - j) + c j) / n.
    let mut rows: Vec<Vec<u32>> = (0..=n)
        .map(|i| Vec::with_capacity(i as usize + 1))
        .collect();
    for [a, b, c] in ICOSAHEDRON_FACES {
        let (pa, pb, pc) = (
            corners[a as usize],
            corners[b as usize],
            corners[c as usize],
        );
        for (i, row) in (0..=n).zip(rows.iter_mut()) {
            row.clear();
            for j in 0..=i {
                let id = match (i, j) {
                    (0, _) => a,
                    (i, 0) if i == n => b,
                    (i, j) if i == n && j == n => c,
                    (i, 0) => edge_point(&mut positions, a, b, i),
                    (i, j) if j == i => edge_point(&mut positions, a, c, i),
                    (i, j) if i == n => edge_point(&mut positions, b, c, j),
                    (i, j) => {
                        let (wa, wb, wc) = (f64::from(n - i), f64::from(i - j), f64::from(j));
                        positions.push(on_sphere(pa * wa + pb * wb + pc * wc));
                        positions.len() as u32 - 1
                    }
                };
                row.push(id);
            }
        }
        for i in 0..n as usize {
            let (top, bottom) = (&rows[i], &rows[i + 1]);
            for j in 0..=i {
                triangles.push([top[j], bottom[j], bottom[j + 1]]);
                if j < i {
                    triangles.push([top[j], bottom[j + 1], top[j + 1]]);
                }
            }
        }
    }
    TriMesh::new(positions, triangles)
}

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

/// The solid whose surface is the genus-2 control cage: one layer of unit voxels, a 7 x 4
/// slab with two 2 x 2 holes (`#` is solid), rows along +y.
const GENUS2_SLAB: [&[u8; 7]; 4] = [b"#######", b"#..#..#", b"#..#..#", b"#######"];

/// Quads of the cage: the boundary faces of the voxels of [`GENUS2_SLAB`], counter-clockwise
/// seen from outside. 76 vertices, 78 quads, 156 edges: Euler characteristic -2.
fn genus2_cage() -> (Vec<DVec3>, Vec<[u32; 4]>) {
    let solid = |v: [i32; 3]| {
        v[2] == 0
            && (0..GENUS2_SLAB.len() as i32).contains(&v[1])
            && (0..GENUS2_SLAB[0].len() as i32).contains(&v[0])
            && GENUS2_SLAB[v[1] as usize][v[0] as usize] == b'#'
    };
    let mut ids: HashMap<[i32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut quads = Vec::new();
    for (y, row) in GENUS2_SLAB.iter().enumerate() {
        for x in 0..row.len() {
            let voxel = [x as i32, y as i32, 0];
            if !solid(voxel) {
                continue;
            }
            for axis in 0..3 {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for side in [-1, 1] {
                    let mut beside = voxel;
                    beside[axis] += side;
                    if solid(beside) {
                        continue;
                    }
                    let mut base = voxel;
                    base[axis] += i32::from(side > 0);
                    let step = |mut p: [i32; 3], d: usize| {
                        p[d] += 1;
                        p
                    };
                    // e_u x e_v = e_axis, so this order faces +axis; reversed it faces -axis.
                    let mut corners = [base, step(base, u), step(step(base, u), v), step(base, v)];
                    if side < 0 {
                        corners.reverse();
                    }
                    quads.push(corners.map(|c| {
                        *ids.entry(c).or_insert_with(|| {
                            positions.push(DVec3::new(
                                f64::from(c[0]),
                                f64::from(c[1]),
                                f64::from(c[2]),
                            ));
                            positions.len() as u32 - 1
                        })
                    }));
                }
            }
        }
    }
    (positions, quads)
}

/// One Catmull-Clark step on a closed quad mesh (every edge shared by two quads).
///
/// Output vertices: the moved old vertices, then one per edge, then one per face. Each
/// quad `c0 c1 c2 c3` becomes four quads `c_k, edge(c_k c_k+1), face, edge(c_k-1 c_k)`,
/// which keeps its orientation. Catmull & Clark 1978.
fn catmull_clark(positions: &[DVec3], quads: &[[u32; 4]]) -> (Vec<DVec3>, Vec<[u32; 4]>) {
    let mut edge_ids: HashMap<(u32, u32), u32> = HashMap::with_capacity(2 * quads.len());
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(2 * quads.len());
    let mut edge_faces: Vec<[u32; 2]> = Vec::with_capacity(2 * quads.len());
    let mut quad_edges: Vec<[u32; 4]> = Vec::with_capacity(quads.len());
    for (f, q) in quads.iter().enumerate() {
        let mut qe = [0; 4];
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            let key = (a.min(b), a.max(b));
            qe[k] = match edge_ids.entry(key) {
                Entry::Occupied(o) => {
                    let e = *o.get();
                    edge_faces[e as usize][1] = f as u32;
                    e
                }
                Entry::Vacant(slot) => {
                    let e = edges.len() as u32;
                    slot.insert(e);
                    edges.push(key);
                    edge_faces.push([f as u32, NONE]);
                    e
                }
            };
        }
        quad_edges.push(qe);
    }
    debug_assert!(
        edge_faces.iter().all(|f| f[1] != NONE),
        "cage must be closed"
    );

    let face_points: Vec<DVec3> = quads
        .iter()
        .map(|q| q.iter().map(|&v| positions[v as usize]).sum::<DVec3>() * 0.25)
        .collect();
    let edge_points: Vec<DVec3> = edges
        .iter()
        .zip(&edge_faces)
        .map(|(&(a, b), &[f0, f1])| {
            (positions[a as usize]
                + positions[b as usize]
                + face_points[f0 as usize]
                + face_points[f1 as usize])
                * 0.25
        })
        .collect();
    // New vertex = (F + 2 R + (n - 3) P) / n with F the mean of the adjacent face points
    // and R the mean of the incident edge midpoints; on a closed mesh a vertex has as
    // many faces as edges (n).
    let mut face_sum = vec![DVec3::ZERO; positions.len()];
    let mut face_count = vec![0u32; positions.len()];
    for (q, fp) in quads.iter().zip(&face_points) {
        for &v in q {
            face_sum[v as usize] += *fp;
            face_count[v as usize] += 1;
        }
    }
    let mut mid_sum = vec![DVec3::ZERO; positions.len()];
    for &(a, b) in &edges {
        let mid = 0.5 * (positions[a as usize] + positions[b as usize]);
        mid_sum[a as usize] += mid;
        mid_sum[b as usize] += mid;
    }
    let mut new_positions = Vec::with_capacity(positions.len() + edges.len() + quads.len());
    for (v, p) in positions.iter().enumerate() {
        let n = f64::from(face_count[v]);
        new_positions.push((face_sum[v] / n + 2.0 * mid_sum[v] / n + (n - 3.0) * *p) / n);
    }
    new_positions.extend_from_slice(&edge_points);
    new_positions.extend_from_slice(&face_points);

    let edge_base = positions.len() as u32;
    let face_base = edge_base + edges.len() as u32;
    let mut new_quads = Vec::with_capacity(4 * quads.len());
    for (f, (q, qe)) in quads.iter().zip(&quad_edges).enumerate() {
        for k in 0..4 {
            new_quads.push([
                q[k],
                edge_base + qe[k],
                face_base + f as u32,
                edge_base + qe[(k + 3) % 4],
            ]);
        }
    }
    (new_positions, new_quads)
}

/// Splits each quad along its shorter diagonal (both splits keep the orientation).
fn triangulate_quads(positions: &[DVec3], quads: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let mut triangles = Vec::with_capacity(2 * quads.len());
    for &[a, b, c, d] in quads {
        let p = |v: u32| positions[v as usize];
        if p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d)) {
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        } else {
            triangles.push([a, b, d]);
            triangles.push([b, c, d]);
        }
    }
    triangles
}

/// A closed genus-2 surface (a smooth "double torus" / pretzel with two holes side by
/// side along x), centred at the origin, `size` long along x.
///
/// Made as the Catmull-Clark subdivision surface of a polycube cage: the surface of a
/// 7 x 4 x 1 slab of unit voxels with two 2 x 2 holes (78 quads, Euler characteristic
/// -2). `resolution` Catmull-Clark steps are applied (each multiplies the quad count by
/// 4 and keeps the mesh closed, manifold and oriented), quads are split along their
/// shorter diagonal, and the result is scaled so that its x extent is `size` (y extent
/// about 0.57 size, z extent about 0.14 size). `156 · 4^resolution` faces, Euler
/// characteristic -2. The surface converges to the smooth limit surface as the
/// resolution grows (curvature-continuous except at the cage's 24 extraordinary
/// vertices).
///
/// `size` is a length in [1e-30, 1e30]; `resolution` is in `1..=8` (8 gives 10.2 M faces).
///
/// ```
/// use strata_engine::mesh::shapes::genus2;
/// let mesh = genus2(2.0, 2)?;
/// assert_eq!(mesh.face_count(), 2496);
/// assert_eq!(mesh.euler_characteristic(), -2);
/// assert!(mesh.boundary_loops().is_empty());
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn genus2(size: f64, resolution: u32) -> Result<TriMesh, MeshError> {
    check_length("genus2", "size", size)?;
    check_resolution(
        "genus2",
        resolution,
        1,
        156.0 * 4f64.powi(resolution.min(64) as i32),
        "an integer in 1..=8 (Catmull-Clark steps; 156 * 4^resolution faces)",
    )?;
    let (mut positions, mut quads) = genus2_cage();
    for _ in 0..resolution {
        (positions, quads) = catmull_clark(&positions, &quads);
    }
    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let (centre, scale) = (0.5 * (lo + hi), size / (hi.x - lo.x));
    for p in &mut positions {
        *p = (*p - centre) * scale;
    }
    let triangles = triangulate_quads(&positions, &quads);
    TriMesh::new(positions, triangles)
}

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
