//! The closed genus-2 surface: Catmull-Clark subdivision (Catmull & Clark 1978) of a
//! polycube cage, triangulated along the shorter diagonals. Cost O(faces) per step.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use glam::DVec3;

use super::limits::{check_length, check_resolution};
use crate::mesh::{MeshError, NONE, TriMesh};

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
