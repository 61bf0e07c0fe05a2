use std::collections::HashMap;

use glam::DVec3;

use super::*;

fn tetrahedron() -> TriMesh {
    TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
    .expect("valid tetrahedron")
}

#[test]
fn tetrahedron_is_closed_sphere() {
    let m = tetrahedron();
    assert_eq!(m.edge_count(), 6);
    assert_eq!(m.euler_characteristic(), 2);
    assert!(m.boundary_loops().is_empty());
    assert_eq!(m.component_count(), 1);
    for f in 0..4 {
        assert!(m.face_neighbors()[f].iter().all(|&n| n != NONE));
    }
    // Outward normals: the centroid-to-face vector agrees with the face normal.
    let c = DVec3::splat(0.25);
    for f in 0..4u32 {
        let p = m.face_positions(f);
        assert!(
            (p[0] - c).dot(m.face_normals()[f as usize]) > 0.0,
            "face {f}"
        );
    }
}

#[test]
fn repairs_duplicates_and_degenerates() {
    // Two triangles of a square, the shared corner duplicated, plus a degenerate face.
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::ZERO,               // duplicate of 0
        DVec3::new(1.0, 1.0, 0.0), // duplicate of 2
        DVec3::Y,
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [3, 4, 5], [0, 1, 1]]).expect("repairable");
    assert_eq!(m.vertex_count(), 4);
    assert_eq!(m.face_count(), 2);
    assert_eq!(m.boundary_loops().len(), 1);
    assert_eq!(m.boundary_loops()[0].len(), 4);
    assert_eq!(m.euler_characteristic(), 1);
    assert_eq!(m.input_vertex_map(), &[0, 1, 2, 0, 2, 3]);
    assert!(
        m.warnings()
            .iter()
            .any(|w| matches!(w, MeshWarning::MergedDuplicateVertices { count: 2 }))
    );
    assert!(
        m.warnings()
            .iter()
            .any(|w| matches!(w, MeshWarning::RemovedDegenerateFaces { count: 1, .. }))
    );
}

#[test]
fn rejects_bad_input() {
    assert!(matches!(
        TriMesh::new(vec![], vec![]),
        Err(MeshError::Empty { .. })
    ));
    assert!(matches!(
        TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 3]]),
        Err(MeshError::IndexOutOfRange {
            face: 0,
            index: 3,
            ..
        })
    ));
    assert!(matches!(
        TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)],
            vec![[0, 1, 2]]
        ),
        Err(MeshError::NonFiniteVertex { vertex: 2, .. })
    ));
    // Only degenerate faces: nothing usable is left.
    assert!(matches!(
        TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0], vec![[0, 1, 2]]),
        Err(MeshError::Empty { .. })
    ));
}

#[test]
fn non_manifold_edge_is_reported_and_not_crossed() {
    // Three triangles sharing edge (0, 1).
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(0.5, -1.0, 0.0),
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).expect("valid");
    assert!(
        m.warnings()
            .iter()
            .any(|w| matches!(w, MeshWarning::NonManifoldEdges { count: 1, .. }))
    );
    assert!(m.face_neighbors().iter().flatten().all(|&n| n == NONE));
    assert_eq!(m.component_count(), 3);
}

// ---------------------------------------------------------------------------------------
// Boundary loops on meshes that cannot follow one orientation.

/// Every boundary loop is a closed cycle of valence-1 edges, and every valence-1 edge is
/// in exactly one loop, once.
fn assert_boundary_loops_partition_boundary_edges(m: &TriMesh) {
    let mut uses: HashMap<[u32; 2], usize> = m
        .edges()
        .iter()
        .zip(m.edge_valence())
        .filter(|(_, v)| **v == 1)
        .map(|(e, _)| (*e, 0))
        .collect();
    for lp in m.boundary_loops() {
        assert!(lp.len() >= 3, "loop {lp:?} is too short to be closed");
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            match uses.get_mut(&[a.min(b), a.max(b)]) {
                Some(n) => *n += 1,
                None => panic!("loop {lp:?} steps {a} -> {b}, which is not a boundary edge"),
            }
        }
    }
    for (e, n) in uses {
        assert_eq!(
            n, 1,
            "boundary edge {e:?} is in {n} loop steps, not exactly one"
        );
    }
}

#[test]
fn regression_boundary_loop_of_inconsistently_oriented_square() {
    // Two triangles of a square, the second wound the other way: the directed walk used to
    // return two open chains [[0, 1], [0, 3]] that missed vertex 2.
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    let m = TriMesh::new(p, vec![[0, 1, 2], [2, 0, 3]]).expect("valid");
    assert_eq!(m.boundary_loops().len(), 1);
    assert_eq!(m.boundary_loops()[0].len(), 4);
    assert_boundary_loops_partition_boundary_edges(&m);
}

#[test]
fn regression_boundary_loop_of_moebius_strip() {
    // A Möbius strip cannot be oriented consistently; its boundary is one circle.
    let n = 9u32;
    let mut positions = Vec::new();
    for i in 0..n {
        let phi = std::f64::consts::TAU * f64::from(i) / f64::from(n);
        let centre = DVec3::new(phi.cos(), phi.sin(), 0.0) * 2.0;
        let across = DVec3::new(phi.cos(), phi.sin(), 0.0) * (0.5 * phi).cos()
            + DVec3::Z * (0.5 * phi).sin();
        positions.push(centre - 0.5 * across); // bottom: 2 i
        positions.push(centre + 0.5 * across); // top: 2 i + 1
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        let (b0, t0) = (2 * i, 2 * i + 1);
        // The half twist: after the last segment, bottom continues as top.
        let (b1, t1) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        triangles.push([b0, b1, t1]);
        triangles.push([b0, t1, t0]);
    }
    let m = TriMesh::new(positions, triangles).expect("valid");
    assert!(m.warnings().is_empty(), "{:?}", m.warnings());
    assert_eq!(m.euler_characteristic(), 0);
    assert_eq!(m.boundary_loops().len(), 1);
    assert_eq!(m.boundary_loops()[0].len(), 2 * n as usize);
    assert_boundary_loops_partition_boundary_edges(&m);
}
