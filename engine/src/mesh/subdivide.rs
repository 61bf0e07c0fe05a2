//! Loop subdivision (Loop 1987): each triangle becomes four, every vertex and edge
//! point is a fixed average of its neighbours, so the surface converges to a smooth
//! limit with the same shape. Used to make larger versions of real meshes in code (the
//! scaling tests and benchmarks never store them).
//!
//! Input: a [`TriMesh`]. Output: a [`TriMesh`] with `4 F` faces and `V + E` vertices
//! (vertices first, then one per edge in edge order). Cost: O(V + E + F).
//!
//! Rules, with creases wherever an edge is not shared by exactly two faces (boundary
//! and non-manifold edges):
//! - an interior edge `ab` with opposite vertices `c`, `d`: `3/8 (a + b) + 1/8 (c + d)`;
//!   a crease edge: its midpoint;
//! - a vertex with no crease edge and `n` neighbours: `(1 - n beta) v + beta sum`, with
//!   Loop's `beta = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n`;
//! - a vertex on exactly two crease edges: `3/4 v + 1/8 (a + b)` over their far ends
//!   (the boundary curve is subdivided as a cubic B-spline, independent of the inside);
//! - a vertex on one or more than two crease edges: kept in place (a corner).

use glam::DVec3;

use super::{MeshError, NONE, TriMesh};

/// One round of Loop subdivision of `mesh` (Loop 1987; crease rules on boundary and
/// non-manifold edges, corners kept).
///
/// ```
/// use strata_engine::mesh::{loop_subdivide, shapes};
/// let mesh = shapes::sphere(1.0, 2)?;
/// let fine = loop_subdivide(&mesh)?;
/// assert_eq!(fine.face_count(), 4 * mesh.face_count());
/// assert_eq!(fine.vertex_count(), mesh.vertex_count() + mesh.edge_count());
/// assert_eq!(fine.euler_characteristic(), 2);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
///
/// Errors: only those of [`TriMesh::new`] on the result, which cannot occur for a
/// valid input (the new faces have positive area where the old ones did).
pub fn loop_subdivide(mesh: &TriMesh) -> Result<TriMesh, MeshError> {
    let pos = mesh.positions();
    let v_count = mesh.vertex_count();
    let crease: Vec<bool> = mesh.edge_valence().iter().map(|&k| k != 2).collect();

    let mut positions = Vec::with_capacity(v_count + mesh.edge_count());
    for v in 0..v_count as u32 {
        positions.push(vertex_point(mesh, v, &crease));
    }
    for (e, &[a, b]) in mesh.edges().iter().enumerate() {
        let (pa, pb) = (pos[a as usize], pos[b as usize]);
        let point = if crease[e] {
            (pa + pb) * 0.5
        } else {
            let [c, d] = mesh.edge_faces()[e].map(|f| opposite(mesh, f, a, b));
            (pa + pb) * 0.375 + (pos[c as usize] + pos[d as usize]) * 0.125
        };
        positions.push(point);
    }

    let mut triangles = Vec::with_capacity(4 * mesh.face_count());
    for (t, fe) in mesh.triangles().iter().zip(mesh.face_edges()) {
        // Edge k joins corners k and k + 1.
        let m = fe.map(|e| v_count as u32 + e);
        triangles.push([t[0], m[0], m[2]]);
        triangles.push([m[0], t[1], m[1]]);
        triangles.push([m[2], m[1], t[2]]);
        triangles.push([m[0], m[1], m[2]]);
    }
    TriMesh::new(positions, triangles)
}

/// The vertex of face `f` that is neither `a` nor `b`.
fn opposite(mesh: &TriMesh, f: u32, a: u32, b: u32) -> u32 {
    debug_assert_ne!(f, NONE, "an interior edge has two faces");
    let t = mesh.triangles()[f as usize];
    t.into_iter()
        .find(|&v| v != a && v != b)
        .expect("a triangle has a third vertex")
}

/// The new position of vertex `v`.
fn vertex_point(mesh: &TriMesh, v: u32, crease: &[bool]) -> DVec3 {
    let pos = mesh.positions();
    let p = pos[v as usize];
    let neighbors = mesh.vertex_neighbors(v);
    let edges = mesh.vertex_edges(v);
    let crease_ends: Vec<u32> = neighbors
        .iter()
        .zip(edges)
        .filter(|&(_, &e)| crease[e as usize])
        .map(|(&u, _)| u)
        .collect();
    match crease_ends.len() {
        0 => {
            let n = neighbors.len() as f64;
            let c = 0.375 + 0.25 * (std::f64::consts::TAU / n).cos();
            let beta = (0.625 - c * c) / n;
            let sum: DVec3 = neighbors.iter().map(|&u| pos[u as usize]).sum();
            p * (1.0 - n * beta) + sum * beta
        }
        2 => p * 0.75 + (pos[crease_ends[0] as usize] + pos[crease_ends[1] as usize]) * 0.125,
        _ => p,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    #[test]
    fn counts_and_topology_are_those_of_four_to_one_splitting() {
        for mesh in [
            shapes::sphere(1.0, 3).expect("sphere"),
            shapes::torus(1.0, 0.3, 8).expect("torus"),
            shapes::plane(1.0, 4).expect("plane"),
        ] {
            let fine = loop_subdivide(&mesh).expect("subdivided");
            assert_eq!(fine.face_count(), 4 * mesh.face_count());
            assert_eq!(fine.vertex_count(), mesh.vertex_count() + mesh.edge_count());
            assert_eq!(fine.euler_characteristic(), mesh.euler_characteristic());
            assert_eq!(fine.boundary_loops().len(), mesh.boundary_loops().len());
            assert!(fine.warnings().is_empty(), "{:?}", fine.warnings());
        }
    }

    #[test]
    fn a_flat_square_stays_flat_and_inside_with_straight_boundary_edges() {
        // The interior rules are affine combinations, so a plane maps into itself; the
        // crease rules keep boundary edge points on the old boundary (midpoints) and
        // only round the four corners (cubic B-spline: 3/4 corner + 1/8 neighbours).
        let mesh = shapes::plane(2.0, 4).expect("plane");
        let fine = loop_subdivide(&mesh).expect("subdivided");
        let (lo, hi) = mesh.bounds();
        for p in fine.positions() {
            assert!(p.z.abs() < 1e-15, "{p}");
            assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "{p} outside");
        }
        for (e, &[a, b]) in mesh.edges().iter().enumerate() {
            if mesh.edge_valence()[e] == 1 {
                let mid = (mesh.positions()[a as usize] + mesh.positions()[b as usize]) * 0.5;
                assert_eq!(fine.positions()[mesh.vertex_count() + e], mid);
            }
        }
        // The corner at the origin: neighbours (0.5, 0) and (0, 0.5) on the boundary.
        assert!(
            fine.positions()
                .iter()
                .any(|p| p.distance(DVec3::new(0.0625, 0.0625, 0.0)) < 1e-15)
        );
    }

    #[test]
    fn interior_vertex_and_edge_weights_match_loop_by_hand() {
        // A regular hexagon fan around the origin lifted at the centre: valence 6,
        // beta = 1/16, so the centre moves to (1 - 6/16) h = 5/8 h.
        let mut positions = vec![DVec3::new(0.0, 0.0, 1.0)];
        for k in 0..6 {
            let a = std::f64::consts::TAU * k as f64 / 6.0;
            positions.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        // Close the fan into an octahedron-like cap with a bottom vertex so the
        // centre has no crease edge.
        positions.push(DVec3::new(0.0, 0.0, -1.0));
        let mut triangles = Vec::new();
        for k in 0..6u32 {
            triangles.push([0, 1 + k, 1 + (k + 1) % 6]);
            triangles.push([7, 1 + (k + 1) % 6, 1 + k]);
        }
        let mesh = TriMesh::new(positions, triangles).expect("mesh");
        let fine = loop_subdivide(&mesh).expect("subdivided");
        let top = fine.positions()[0];
        assert!(top.truncate().length() < 1e-15);
        assert!((top.z - 0.625).abs() < 1e-15, "{top}");
        // Edge from the top to the rim vertex at angle 0: 3/8 (top + rim) plus 1/8 of
        // the two rim neighbours at +-60 degrees.
        let e = mesh
            .edges()
            .iter()
            .position(|&[a, b]| [a, b] == [0, 1])
            .expect("edge 0-1");
        let got = fine.positions()[mesh.vertex_count() + e];
        let want = (DVec3::new(0.0, 0.0, 1.0) + DVec3::X) * 0.375
            + (mesh.positions()[2] + mesh.positions()[6]) * 0.125;
        assert!(got.distance(want) < 1e-15, "{got} vs {want}");
    }

    #[test]
    fn a_sphere_shrinks_slightly_toward_its_limit_surface() {
        let mesh = shapes::sphere(1.0, 4).expect("sphere");
        let fine = loop_subdivide(&mesh).expect("subdivided");
        let radii: Vec<f64> = fine.positions().iter().map(|p| p.length()).collect();
        let (min, max) = radii.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
            (lo.min(r), hi.max(r))
        });
        assert!(min > 0.97 && max <= 1.0 + 1e-12, "radii in [{min}, {max}]");
    }
}
