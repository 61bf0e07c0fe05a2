use std::collections::{BTreeSet, HashMap, HashSet};
use std::f64::consts::PI;

use glam::DVec3;
use proptest::collection::vec as pvec;
use proptest::prelude::*;

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
fn meshes_beyond_the_supported_scale_are_refused_with_the_limit() {
    let tri = |k: f64, at: DVec3| {
        TriMesh::new(
            vec![at, at + DVec3::X * k, at + DVec3::Y * k],
            vec![[0, 1, 2]],
        )
    };
    // The ends of the range work.
    assert!(tri(1e-50, DVec3::ZERO).is_ok());
    assert!(tri(5e49, DVec3::splat(5e49)).is_ok());
    // Beyond them: the vertex, its position and the limit (1e300 once failed in a
    // Cholesky factorization, 1e-100 as an empty mesh).
    let e = tri(1.0, DVec3::new(0.0, 0.0, 1e300)).expect_err("too far");
    assert!(
        matches!(e, MeshError::CoordinateOutOfRange { vertex: 0, z, .. } if z == 1e300),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "vertex 0 at (0.000e0, 0.000e0, 1.000e300) is beyond the supported coordinate \
         range of +-1e50; scale the mesh down"
    );
    assert!(matches!(
        tri(1e51, DVec3::ZERO),
        Err(MeshError::CoordinateOutOfRange { vertex: 1, .. })
    ));
    let e = tri(1e-100, DVec3::ZERO).expect_err("too small");
    assert!(matches!(e, MeshError::TooSmall { .. }), "{e:?}");
    assert!(
        e.to_string().contains("the smallest supported is 1e-50"),
        "{e}"
    );
    // A point (no extent at all) is reported as empty, as before.
    assert!(matches!(tri(0.0, DVec3::ONE), Err(MeshError::Empty { .. })));
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

// ---------------------------------------------------------------------------------------
// Built-in shapes.

/// What every built-in shape promises: Euler characteristic, boundary loop count, one
/// component, no warnings, only manifold edges, consistent orientation (each directed
/// half-edge used once; each interior edge once in each direction), positive areas.
fn assert_shape_topology(name: &str, m: &TriMesh, euler: i64, loops: usize) {
    assert_eq!(
        m.euler_characteristic(),
        euler,
        "{name}: Euler characteristic"
    );
    assert_eq!(m.boundary_loops().len(), loops, "{name}: boundary loops");
    assert_eq!(m.component_count(), 1, "{name}: components");
    assert!(
        m.warnings().is_empty(),
        "{name}: warnings {:?}",
        m.warnings()
    );
    assert!(
        m.edge_valence().iter().all(|&v| v == 1 || v == 2),
        "{name}: non-manifold edge"
    );
    let mut directed = HashSet::new();
    for t in m.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            assert!(
                directed.insert((a, b)),
                "{name}: half-edge {a} -> {b} used twice"
            );
        }
    }
    for (&[a, b], &v) in m.edges().iter().zip(m.edge_valence()) {
        if v == 2 {
            assert!(
                directed.contains(&(a, b)) && directed.contains(&(b, a)),
                "{name}: interior edge {a}-{b} not used once in each direction"
            );
        }
    }
    assert_boundary_loops_partition_boundary_edges(m);
    assert!(
        m.face_areas().iter().all(|&a| a > 0.0),
        "{name}: zero-area face"
    );
}

/// Volume enclosed by a closed mesh (divergence theorem); positive iff normals point out.
fn signed_volume(m: &TriMesh) -> f64 {
    (0..m.face_count() as u32)
        .map(|f| {
            let [a, b, c] = m.face_positions(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// The smallest interior angle of any triangle, in degrees.
fn min_angle_degrees(m: &TriMesh) -> f64 {
    let mut smallest = 180.0f64;
    for f in 0..m.face_count() as u32 {
        let p = m.face_positions(f);
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            smallest = smallest.min((b - a).angle_between(c - a).to_degrees());
        }
    }
    smallest
}

/// The largest angle, in degrees, between a vertex normal and the analytic normal.
fn max_normal_error_degrees(m: &TriMesh, normal: impl Fn(DVec3) -> DVec3) -> f64 {
    m.positions()
        .iter()
        .zip(m.vertex_normals())
        .map(|(p, n)| n.angle_between(normal(*p)).to_degrees())
        .fold(0.0, f64::max)
}

#[test]
fn plane_is_a_flat_disk() {
    for n in [1u32, 2, 7] {
        let m = shapes::plane(3.0, n).expect("valid plane");
        let name = format!("plane n={n}");
        assert_shape_topology(&name, &m, 1, 1);
        assert_eq!(m.face_count(), 2 * (n * n) as usize, "{name}");
        assert_eq!(m.boundary_loops()[0].len(), 4 * n as usize, "{name}");
        assert!((m.area() - 9.0).abs() < 1e-12, "{name}: area {}", m.area());
        let normal_error = max_normal_error_degrees(&m, |_| DVec3::Z);
        assert!(normal_error < 1e-12, "{name}: normal error {normal_error}°");
        assert!(min_angle_degrees(&m) > 44.9, "{name}");
    }
}

#[test]
fn sphere_is_closed_outward_and_converges() {
    let r = 2.5;
    for n in [1u32, 2, 3, 4, 8, 16, 32] {
        let m = shapes::sphere(r, n).expect("valid sphere");
        let name = format!("sphere n={n}");
        assert_shape_topology(&name, &m, 2, 0);
        assert_eq!(m.face_count(), 20 * (n * n) as usize, "{name}");
        assert_eq!(m.vertex_count(), 10 * (n * n) as usize + 2, "{name}");
        for p in m.positions() {
            assert!(
                (p.length() - r).abs() < 1e-12 * r,
                "{name}: vertex {p} off the sphere"
            );
        }
        // An inscribed polyhedron: volume and area approach the sphere's from below, the
        // area error is about 0.31 / n^2 (relative).
        let volume = signed_volume(&m);
        assert!(
            volume > 0.0 && volume < 4.0 / 3.0 * PI * r.powi(3),
            "{name}: volume {volume}"
        );
        let exact = 4.0 * PI * r * r;
        let error = (exact - m.area()) / exact;
        assert!(
            error > 0.0 && error < 0.35 / f64::from(n * n),
            "{name}: area error {error}"
        );
        let normal_error = max_normal_error_degrees(&m, |p| p.normalize());
        assert!(
            normal_error < 6.0 / f64::from(n),
            "{name}: normal error {normal_error}°"
        );
        let angle = min_angle_degrees(&m);
        assert!(angle > 50.0, "{name}: min angle {angle}°");
    }
}

#[test]
fn cylinder_is_an_open_tube_and_converges() {
    let (r, h) = (0.5, 1.5);
    for n in [3u32, 4, 8, 16, 64] {
        let m = shapes::cylinder(r, h, n).expect("valid cylinder");
        let name = format!("cylinder n={n}");
        assert_shape_topology(&name, &m, 0, 2);
        for lp in m.boundary_loops() {
            assert_eq!(lp.len(), n as usize, "{name}: loop length");
            let z = m.positions()[lp[0] as usize].z;
            assert!((z.abs() - 0.5 * h).abs() < 1e-12, "{name}: loop at z = {z}");
            assert!(
                lp.iter().all(|&v| m.positions()[v as usize].z == z),
                "{name}: loop not flat"
            );
        }
        for p in m.positions() {
            assert!(
                (p.truncate().length() - r).abs() < 1e-12,
                "{name}: vertex {p} off the tube"
            );
        }
        // Relative area error about 1.22 / n^2 (a polygon of chords, slightly tilted faces).
        let exact = 2.0 * PI * r * h;
        let error = (exact - m.area()) / exact;
        assert!(
            error > 0.0 && error < 1.5 / f64::from(n * n),
            "{name}: area error {error}"
        );
        // Vertices on the end rings see only one side: their normals tilt by O(1/n)
        // (measured 28/n at n = 3, 17/n for n >= 16).
        let normal_error = max_normal_error_degrees(&m, |p| DVec3::new(p.x, p.y, 0.0).normalize());
        assert!(
            normal_error < 30.0 / f64::from(n),
            "{name}: normal error {normal_error}°"
        );
        let angle = min_angle_degrees(&m);
        assert!(angle > 45.0, "{name}: min angle {angle}°");
    }
    // Extreme aspect ratios stay valid: one row of flat triangles, or many rows.
    for (r, h, n) in [(1.0, 0.01, 3u32), (0.01, 10.0, 8), (1.0, 1e-6, 400)] {
        let m = shapes::cylinder(r, h, n).expect("valid cylinder");
        assert_shape_topology(&format!("cylinder r={r} h={h} n={n}"), &m, 0, 2);
    }
}

#[test]
fn torus_is_closed_outward_and_converges() {
    // (major, minor, area error * n^2 bound, normal error (degrees) * n^2 bound, min angle).
    // The fat torus (1, 0.9) has uniform rings crowded on the inside: thin triangles there.
    for (big, small, area_bound, normal_bound, min_angle) in [
        (2.0, 0.5, 1.5, 80.0, 43.0),
        (3.0, 1.0, 1.7, 110.0, 40.0),
        (1.0, 0.9, 3.6, 650.0, 9.0),
    ] {
        for n in [3u32, 4, 8, 16, 32] {
            let m = shapes::torus(big, small, n).expect("valid torus");
            let name = format!("torus R={big} r={small} n={n}");
            assert_shape_topology(&name, &m, 0, 0);
            let on_circle = |p: DVec3| DVec3::new(p.x, p.y, 0.0).normalize() * big;
            for p in m.positions() {
                let d = (*p - on_circle(*p)).length();
                assert!(
                    (d - small).abs() < 1e-12,
                    "{name}: vertex {p} off the torus"
                );
            }
            let volume = signed_volume(&m);
            assert!(volume > 0.0, "{name}: volume {volume}");
            let exact = 4.0 * PI * PI * big * small;
            let error = (exact - m.area()) / exact;
            let n2 = f64::from(n * n);
            assert!(
                error > 0.0 && error < area_bound / n2,
                "{name}: area error {error}"
            );
            let normal_error = max_normal_error_degrees(&m, |p| (p - on_circle(p)).normalize());
            assert!(
                normal_error < normal_bound / n2,
                "{name}: normal error {normal_error}°"
            );
            let angle = min_angle_degrees(&m);
            assert!(angle > min_angle, "{name}: min angle {angle}°");
        }
    }
}

#[test]
fn genus2_is_closed_manifold_oriented_and_smooth() {
    let size = 3.0;
    let mut previous_area: Option<f64> = None;
    for level in 1..=5u32 {
        let m = shapes::genus2(size, level).expect("valid genus-2 surface");
        let name = format!("genus2 resolution={level}");
        assert_shape_topology(&name, &m, -2, 0);
        assert_eq!(m.face_count(), 156 << (2 * level), "{name}");
        let volume = signed_volume(&m);
        assert!(volume > 0.0, "{name}: volume {volume}");
        // Catmull-Clark quads split along the shorter diagonal: no slivers (measured 35.3°).
        let angle = min_angle_degrees(&m);
        assert!(angle > 30.0, "{name}: min angle {angle}°");
        let (lo, hi) = m.bounds();
        assert!(
            ((hi.x - lo.x) - size).abs() < 1e-12,
            "{name}: x extent {}",
            hi.x - lo.x
        );
        assert!((lo + hi).length() < 1e-12, "{name}: not centred");
        // The cage is symmetric under x -> -x, y -> -y and z -> -z; so is its subdivision.
        let key = |p: DVec3| (p * 1e9).round().to_array().map(|c| c as i64);
        let vertices: HashSet<[i64; 3]> = m.positions().iter().map(|&p| key(p)).collect();
        for &p in m.positions() {
            for mirror in [
                DVec3::new(-1.0, 1.0, 1.0),
                DVec3::new(1.0, -1.0, 1.0),
                DVec3::new(1.0, 1.0, -1.0),
            ] {
                assert!(
                    vertices.contains(&key(p * mirror)),
                    "{name}: {p} has no mirror image"
                );
            }
        }
        // Smoothness: the vertex normal is close to each incident face's normal, closer
        // with each step (about 0.6x per step, measured 44.6° at 1 to 6.1° at 5).
        let bound = 80.0 * 0.63f64.powi(level as i32);
        for v in 0..m.vertex_count() as u32 {
            for &f in m.vertex_faces(v) {
                let angle = m.vertex_normals()[v as usize]
                    .angle_between(m.face_normals()[f as usize])
                    .to_degrees();
                assert!(
                    angle < bound,
                    "{name}: vertex {v} face {f} normals {angle}° apart"
                );
            }
        }
        // The area converges (differences shrink about 4x per step).
        let area = m.area();
        if let Some(previous) = previous_area {
            let change = (area - previous) / previous;
            let bound = 0.25 / 4f64.powi(level as i32 - 1);
            assert!(
                change.abs() < bound,
                "{name}: area changed by {change} (bound {bound})"
            );
        }
        previous_area = Some(area);
    }
}

#[test]
fn shapes_reject_invalid_parameters() {
    let cases: Vec<(Result<TriMesh, MeshError>, &str, &str)> = vec![
        (shapes::plane(1.0, 0), "plane", "resolution"),
        (shapes::plane(-1.0, 4), "plane", "size"),
        (shapes::plane(f64::NAN, 4), "plane", "size"),
        (shapes::plane(1.0, u32::MAX), "plane", "resolution"),
        (shapes::sphere(1.0, 0), "sphere", "resolution"),
        (shapes::sphere(0.0, 4), "sphere", "radius"),
        (shapes::sphere(f64::INFINITY, 4), "sphere", "radius"),
        (shapes::sphere(1e40, 4), "sphere", "radius"),
        (shapes::sphere(1.0, 916), "sphere", "resolution"),
        (shapes::cylinder(1.0, 1.0, 2), "cylinder", "resolution"),
        (shapes::cylinder(1.0, 1.0, 0), "cylinder", "resolution"),
        (shapes::cylinder(1.0, -2.0, 8), "cylinder", "height"),
        (shapes::cylinder(f64::NAN, 1.0, 8), "cylinder", "radius"),
        (shapes::cylinder(1e-9, 1.0, 8), "cylinder", "height"),
        (
            shapes::cylinder(1.0, 1.0, u32::MAX),
            "cylinder",
            "resolution",
        ),
        (shapes::torus(1.0, 1.0, 8), "torus", "minor_radius"),
        (shapes::torus(1.0, 2.0, 8), "torus", "minor_radius"),
        (shapes::torus(1.0, 0.0, 8), "torus", "minor_radius"),
        (shapes::torus(-1.0, 0.5, 8), "torus", "major_radius"),
        (shapes::torus(1.0, 0.5, 2), "torus", "resolution"),
        (shapes::torus(1.0, 1e-9, 8), "torus", "minor_radius"),
        (shapes::torus(1.0, 0.5, u32::MAX), "torus", "resolution"),
        (shapes::torus(1.0, 0.5, 100_000), "torus", "resolution"),
        (
            shapes::cylinder(1.0, 1.0, 1_000_000),
            "cylinder",
            "resolution",
        ),
        (shapes::genus2(1.0, 0), "genus2", "resolution"),
        (shapes::genus2(1.0, 9), "genus2", "resolution"),
        (shapes::genus2(1.0, u32::MAX), "genus2", "resolution"),
        (shapes::genus2(f64::NEG_INFINITY, 2), "genus2", "size"),
    ];
    for (i, (result, shape, parameter)) in cases.into_iter().enumerate() {
        match result {
            Err(MeshError::InvalidShapeParameter {
                shape: s,
                parameter: p,
                ..
            }) => {
                assert_eq!((s, p), (shape, parameter), "case {i}");
            }
            other => panic!("case {i} ({shape} {parameter}): expected an error, got {other:?}"),
        }
    }
    // The message names the shape, the parameter, the value and the valid range.
    let message = shapes::sphere(1.0, 0)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        message.contains("sphere") && message.contains("resolution = 0"),
        "{message}"
    );
    assert!(message.contains(">= 1"), "{message}");
}

#[test]
fn shape_build_matches_the_generators() {
    let cases = [
        (
            shapes::Shape::Plane {
                size: 2.0,
                resolution: 3,
            },
            shapes::plane(2.0, 3),
        ),
        (
            shapes::Shape::Sphere {
                radius: 1.5,
                resolution: 3,
            },
            shapes::sphere(1.5, 3),
        ),
        (
            shapes::Shape::Cylinder {
                radius: 1.0,
                height: 3.0,
                resolution: 12,
            },
            shapes::cylinder(1.0, 3.0, 12),
        ),
        (
            shapes::Shape::Torus {
                major_radius: 2.0,
                minor_radius: 0.5,
                resolution: 6,
            },
            shapes::torus(2.0, 0.5, 6),
        ),
        (
            shapes::Shape::Genus2 {
                size: 2.0,
                resolution: 2,
            },
            shapes::genus2(2.0, 2),
        ),
    ];
    for (shape, direct) in cases {
        let built = shape.build().expect("valid shape");
        let direct = direct.expect("valid shape");
        // Same call, same bits: the generators are deterministic.
        assert_eq!(built.positions(), direct.positions(), "{shape:?}");
        assert_eq!(built.triangles(), direct.triangles(), "{shape:?}");
    }
    assert!(shapes::Shape::default().build().is_ok());
    assert!(matches!(
        shapes::Shape::Sphere {
            radius: 1.0,
            resolution: 0
        }
        .build(),
        Err(MeshError::InvalidShapeParameter {
            shape: "sphere",
            ..
        })
    ));
}

// ---------------------------------------------------------------------------------------
// Adjacency invariants on random small meshes.

/// A triangle soup cut from a (w x h) grid with random heights: a random subset of its
/// triangles (some flipped if asked), its vertices permuted, some vertices duplicated
/// (and used by some corners), some faces repeated.
#[derive(Clone, Debug)]
struct Soup {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// No face was flipped: the soup is consistently oriented.
    oriented: bool,
}

fn soup(flips: bool) -> impl Strategy<Value = Soup> {
    (1u32..=4, 1u32..=4)
        .prop_flat_map(|(w, h)| {
            let v = ((w + 1) * (h + 1)) as usize;
            let f = (2 * w * h) as usize;
            (
                Just((w, h)),
                pvec(prop::bool::weighted(0.7), f),
                pvec(any::<bool>(), f),
                Just((0..v as u32).collect::<Vec<u32>>()).prop_shuffle(),
                pvec(-1i32..=1, v),
                pvec(0..v, 0..4),
                pvec(any::<bool>(), 3 * f),
                pvec((any::<prop::sample::Index>(), any::<bool>()), 0..3),
            )
        })
        .prop_map(
            move |((w, h), keep, flip, perm, heights, dups, use_dup, repeats)| {
                let grid = |i: u32, j: u32| j * (w + 1) + i;
                let mut positions = vec![DVec3::ZERO; perm.len()];
                for j in 0..=h {
                    for i in 0..=w {
                        let g = grid(i, j) as usize;
                        positions[perm[g] as usize] =
                            DVec3::new(f64::from(i), f64::from(j), 0.5 * f64::from(heights[g]));
                    }
                }
                let mut dup_of = vec![None; positions.len()];
                for &g in &dups {
                    dup_of[perm[g] as usize] = Some(positions.len() as u32);
                    positions.push(positions[perm[g] as usize]);
                }
                let mut triangles = Vec::new();
                let mut oriented = true;
                let mut t_index = 0;
                for j in 0..h {
                    for i in 0..w {
                        let (a, b, c, d) = (
                            grid(i, j),
                            grid(i + 1, j),
                            grid(i + 1, j + 1),
                            grid(i, j + 1),
                        );
                        for t in [[a, b, c], [a, c, d]] {
                            let k = t_index;
                            t_index += 1;
                            if !keep[k] {
                                continue;
                            }
                            let mut t = t.map(|g| perm[g as usize]);
                            for (c, corner) in t.iter_mut().enumerate() {
                                if let (true, Some(d)) =
                                    (use_dup[3 * k + c], dup_of[*corner as usize])
                                {
                                    *corner = d;
                                }
                            }
                            if flips && flip[k] {
                                t.swap(1, 2);
                                oriented = false;
                            }
                            triangles.push(t);
                        }
                    }
                }
                if !triangles.is_empty() {
                    for (index, reverse) in repeats {
                        let [a, b, c] = *index.get(&triangles);
                        // A rotated copy keeps the orientation; a reversed one only when flipping.
                        triangles.push(if reverse && flips {
                            [c, b, a]
                        } else {
                            [b, c, a]
                        });
                    }
                }
                Soup {
                    positions,
                    triangles,
                    oriented,
                }
            },
        )
}

/// Bitwise key of a position (the builder merges bitwise-equal positions).
fn position_key(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

/// Checks every adjacency array of `m` against quantities recomputed naively here, and
/// against the input soup `s` it was built from.
fn assert_adjacency_invariants(m: &TriMesh, s: &Soup) {
    let tris = m.triangles();
    let sorted = |a: u32, b: u32| [a.min(b), a.max(b)];

    // Faces: the distinct input faces (by position), with the input's orientation.
    let rotate_min_first = |t: [[u64; 3]; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let as_keys =
        |positions: &[DVec3], t: &[u32; 3]| t.map(|v| position_key(positions[v as usize]));
    let mut input_faces: HashMap<[[u64; 3]; 3], [[u64; 3]; 3]> = HashMap::new();
    for t in &s.triangles {
        let keys = as_keys(&s.positions, t);
        let mut set = keys;
        set.sort_unstable();
        input_faces.entry(set).or_insert(rotate_min_first(keys));
    }
    assert_eq!(m.face_count(), input_faces.len(), "face count");
    for t in tris {
        let keys = as_keys(m.positions(), t);
        let mut set = keys;
        set.sort_unstable();
        let first = input_faces.get(&set).expect("output face is an input face");
        assert_eq!(
            *first,
            rotate_min_first(keys),
            "face {t:?} changed orientation"
        );
    }

    // Edges: each face's three edges are in edges(), at the index face_edges() gives.
    let expected_edges: HashSet<[u32; 2]> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| sorted(t[k], t[(k + 1) % 3])))
        .collect();
    assert_eq!(m.edge_count(), expected_edges.len(), "edge count");
    assert!(
        m.edges()
            .iter()
            .all(|e| e[0] < e[1] && expected_edges.contains(e))
    );
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let e = m.face_edges()[f][k] as usize;
            assert_eq!(
                m.edges()[e],
                sorted(t[k], t[(k + 1) % 3]),
                "face {f} edge {k}"
            );
        }
    }

    // edge_faces and edge_valence agree with face_edges.
    let mut faces_of_edge = vec![Vec::new(); m.edge_count()];
    for (f, fe) in m.face_edges().iter().enumerate() {
        for &e in fe {
            faces_of_edge[e as usize].push(f as u32);
        }
    }
    for (e, faces) in faces_of_edge.iter().enumerate() {
        assert_eq!(
            m.edge_valence()[e] as usize,
            faces.len(),
            "edge {e} valence"
        );
        assert!(faces.len() <= 2, "a grid has no non-manifold edge");
        let [f0, f1] = m.edge_faces()[e];
        assert!(
            faces.contains(&f0),
            "edge {e}: first face {f0} does not use it"
        );
        if faces.len() == 2 {
            assert!(
                faces.contains(&f1) && f1 != f0,
                "edge {e}: second face {f1}"
            );
        } else {
            assert_eq!(f1, NONE, "boundary edge {e} has a second face");
        }
    }

    // face_neighbors: across every interior edge, symmetric and through the same edge.
    for f in 0..m.face_count() {
        for k in 0..3 {
            let (e, g) = (m.face_edges()[f][k], m.face_neighbors()[f][k]);
            if m.edge_valence()[e as usize] == 2 {
                assert!(
                    g != NONE && g as usize != f,
                    "face {f} edge {k}: neighbour {g}"
                );
                let back = (0..3).find(|&k2| m.face_edges()[g as usize][k2] == e);
                let back = back.expect("neighbour shares the edge");
                assert_eq!(
                    m.face_neighbors()[g as usize][back],
                    f as u32,
                    "not symmetric"
                );
            } else {
                assert_eq!(g, NONE, "face {f}: neighbour across a boundary edge");
            }
        }
    }

    // Vertex rings: faces around, neighbours (sorted, symmetric), against a naive count.
    let mut ring: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); m.vertex_count()];
    let mut faces_around: Vec<Vec<u32>> = vec![Vec::new(); m.vertex_count()];
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            ring[a as usize].insert(b);
            ring[b as usize].insert(a);
            faces_around[a as usize].push(f as u32);
        }
    }
    for v in 0..m.vertex_count() as u32 {
        let expected: Vec<u32> = ring[v as usize].iter().copied().collect();
        assert_eq!(
            m.vertex_neighbors(v),
            expected.as_slice(),
            "one-ring of {v}"
        );
        for &u in m.vertex_neighbors(v) {
            assert!(
                m.vertex_neighbors(u).contains(&v),
                "one-ring not symmetric: {u} {v}"
            );
        }
        let mut faces = m.vertex_faces(v).to_vec();
        faces.sort_unstable();
        assert_eq!(faces, faces_around[v as usize], "faces around {v}");
    }

    // Boundary loops: closed cycles partitioning the boundary edges; on an oriented
    // mesh each step follows its face's direction.
    assert_boundary_loops_partition_boundary_edges(m);
    if s.oriented {
        let directed: HashSet<(u32, u32)> = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .collect();
        for lp in m.boundary_loops() {
            for i in 0..lp.len() {
                let step = (lp[i], lp[(i + 1) % lp.len()]);
                assert!(
                    directed.contains(&step),
                    "loop {lp:?} steps against its face"
                );
            }
        }
    }

    // Components: the classes of faces joined across interior edges (union-find), each
    // numbered in order of its lowest face; the face counts sum to the face count.
    let mut parent: Vec<usize> = (0..m.face_count()).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for faces in faces_of_edge.iter().filter(|f| f.len() == 2) {
        let (a, b) = (
            root(&mut parent, faces[0] as usize),
            root(&mut parent, faces[1] as usize),
        );
        parent[a.max(b)] = a.min(b);
    }
    let mut component_of_root = HashMap::new();
    let mut sizes = vec![0usize; m.component_count()];
    for f in 0..m.face_count() {
        let next = component_of_root.len() as u32;
        let expected = *component_of_root
            .entry(root(&mut parent, f))
            .or_insert(next);
        assert_eq!(m.face_components()[f], expected, "component of face {f}");
        sizes[expected as usize] += 1;
    }
    assert_eq!(
        component_of_root.len(),
        m.component_count(),
        "component count"
    );
    assert!(sizes.iter().all(|&n| n > 0));
    assert_eq!(sizes.iter().sum::<usize>(), m.face_count());
    let several = m
        .warnings()
        .iter()
        .any(|w| matches!(w, MeshWarning::SeveralComponents { .. }));
    assert_eq!(
        several,
        m.component_count() > 1,
        "SeveralComponents warning"
    );

    // Euler characteristic, recomputed from the input alone (distinct positions, edges
    // and faces by position).
    let used: HashSet<[u64; 3]> = s
        .triangles
        .iter()
        .flat_map(|t| as_keys(&s.positions, t))
        .collect();
    let edges: HashSet<[[u64; 3]; 2]> = s
        .triangles
        .iter()
        .flat_map(|t| {
            let k = as_keys(&s.positions, t);
            (0..3).map(move |i| {
                let (a, b) = (k[i], k[(i + 1) % 3]);
                [a.min(b), a.max(b)]
            })
        })
        .collect();
    let euler = used.len() as i64 - edges.len() as i64 + input_faces.len() as i64;
    assert_eq!(m.euler_characteristic(), euler, "Euler characteristic");
    assert_eq!(m.vertex_count(), used.len(), "vertex count");

    // input_vertex_map: input positions land on equal output positions; exactly the
    // positions no face uses are dropped.
    assert_eq!(m.input_vertex_map().len(), s.positions.len());
    for (i, (&out, &p)) in m.input_vertex_map().iter().zip(&s.positions).enumerate() {
        if out == NONE {
            assert!(
                !used.contains(&position_key(p)),
                "input vertex {i} dropped but used"
            );
        } else {
            assert_eq!(
                position_key(m.positions()[out as usize]),
                position_key(p),
                "vertex {i}"
            );
        }
    }
}

fn check_soup(s: &Soup) {
    match TriMesh::new(s.positions.clone(), s.triangles.clone()) {
        Ok(m) => assert_adjacency_invariants(&m, s),
        Err(MeshError::Empty { .. }) => assert!(s.triangles.is_empty(), "spurious Empty"),
        Err(e) => panic!("unexpected error {e}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn adjacency_invariants_hold_on_oriented_soups(s in soup(false)) {
        check_soup(&s);
    }

    #[test]
    fn adjacency_invariants_hold_with_flipped_faces(s in soup(true)) {
        check_soup(&s);
    }
}

/// FNV-1a over a stream of 64-bit words.
fn fnv1a(words: impl IntoIterator<Item = u64>) -> u64 {
    words.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, w| {
        w.to_le_bytes()
            .into_iter()
            .fold(h, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
    })
}

/// Vertex count, face count, a hash of the triangles and a hash of the positions.
/// `exact` hashes the positions' bits; otherwise they are rounded to multiples of
/// 2^-32 first (for shapes built with `sin`/`cos`, whose last bit may differ between
/// platform math libraries).
fn shape_fingerprint(m: &TriMesh, exact: bool) -> (usize, usize, u64, u64) {
    let triangles = fnv1a(m.triangles().iter().flatten().map(|&i| u64::from(i)));
    let coordinates = m.positions().iter().flat_map(|p| p.to_array());
    let positions = if exact {
        fnv1a(coordinates.map(f64::to_bits))
    } else {
        fnv1a(coordinates.map(|c| (c * 2f64.powi(32)).round() as i64 as u64))
    };
    (m.vertex_count(), m.face_count(), triangles, positions)
}

/// Pins every shape's output (vertex order, triangle order and positions: to the bit for
/// the shapes built with exact IEEE operations only, to 2^-32 for the cylinder and the
/// torus), so that moving or restructuring the generators cannot change a mesh
/// unnoticed.
#[test]
fn shapes_output_is_pinned() {
    let cases = [
        (
            "plane",
            shapes::plane(2.0, 3),
            true,
            (16, 18, 8768988574591504554, 13630828428892066725),
        ),
        (
            "sphere",
            shapes::sphere(1.5, 3),
            true,
            (92, 180, 5007315612167448933, 9237639699685329993),
        ),
        (
            "cylinder",
            shapes::cylinder(1.0, 3.0, 7),
            false,
            (35, 56, 3138054801315937537, 7695830547614967733),
        ),
        (
            "torus",
            shapes::torus(2.0, 0.5, 5),
            false,
            (120, 240, 12355808689526310693, 6971154538144274253),
        ),
        (
            "genus2",
            shapes::genus2(2.0, 1),
            true,
            (310, 624, 8550149304235969809, 7403005205942891305),
        ),
    ];
    let mut changed = Vec::new();
    for (name, mesh, exact, expected) in cases {
        let mesh = mesh.expect(name);
        let got = shape_fingerprint(&mesh, exact);
        if got != expected {
            changed.push((name, got));
        }
    }
    assert!(changed.is_empty(), "output changed: {changed:?}");
}
