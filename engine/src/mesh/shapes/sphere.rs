//! The geodesic sphere: icosahedron faces cut into `resolution²` triangles each, pushed
//! out onto the sphere. Cost O(faces).

use std::collections::HashMap;

use glam::DVec3;

use super::limits::{check_length, check_resolution};
use crate::mesh::{MeshError, TriMesh};

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
/// [`MAX_SHAPE_FACES`](super::MAX_SHAPE_FACES) (so at most 915).
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
