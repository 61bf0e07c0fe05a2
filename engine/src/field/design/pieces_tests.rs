//! Tests of the solves per connected piece: copies of a sphere, a sphere beside other
//! pieces, and a scan-like soup with every solver.

use glam::DVec3;

use super::*;
use crate::field::design::LinearSolver;
use crate::field::design::connection::Connection;
use crate::fixtures::creased::{cube, scan_soup, spheres};
use crate::mesh::shapes;
use crate::segment::detect_singularities;

/// The singularities of `field` on `mesh` (as a tensor field with eigenvalues
/// `[4, 1]`): per component, the indices of its singular faces.
fn indices_per_piece(mesh: &TriMesh, field: &LineField) -> Vec<Vec<f64>> {
    let tensors = field
        .to_tensor_field(mesh, &vec![[4.0, 1.0]; mesh.vertex_count()])
        .expect("tensor field");
    let mut out = vec![Vec::new(); mesh.component_count()];
    for s in detect_singularities(mesh, &tensors) {
        out[mesh.face_components()[s.face as usize] as usize].push(s.index);
    }
    out
}

/// The Rayleigh quotient `E(z) / z^H M z` of each piece of `field` (directions and
/// magnitudes per vertex of `mesh`), each piece measured on its own mesh.
fn rayleigh_per_piece(mesh: &TriMesh, field: &LineField) -> Vec<f64> {
    split(mesh)
        .expect("pieces")
        .iter()
        .map(|piece| {
            let system = Connection::build(&piece.mesh, 0.0, LinearSolver::Direct, false)
                .expect("connection");
            let mut z = vec![faer::c64::new(0.0, 0.0); piece.mesh.vertex_count()];
            for (&global, &own) in piece.vertices.iter().zip(piece.mesh.input_vertex_map()) {
                let (g, own) = (global as usize, own as usize);
                let (_, u) = system
                    .frames
                    .doubled(own, field.directions[g])
                    .expect("tangent direction");
                z[own] = u * field.magnitudes[g];
            }
            system.energy(&z) / system.mass_norm2(&z)
        })
        .collect()
}

/// Mesh `b` appended to mesh `a` (its vertices numbered after `a`'s).
fn joined(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let base = a.vertex_count() as u32;
    let mut positions = a.positions().to_vec();
    positions.extend_from_slice(b.positions());
    let mut triangles = a.triangles().to_vec();
    triangles.extend(b.triangles().iter().map(|t| t.map(|v| v + base)));
    TriMesh::new(positions, triangles).expect("joined")
}

/// Largest angle (radians) between the lines of `a` and `b` over their first
/// `count` vertices.
fn largest_angle(a: &LineField, b: &LineField, count: usize) -> f64 {
    (0..count)
        .map(|v| {
            let (x, y) = (a.directions[v], b.directions[v]);
            x.cross(y).length().atan2(x.dot(y).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn copies_of_a_sphere_each_get_the_smoothest_field_of_one_sphere() {
    let one = shapes::sphere(1.0, 8).expect("sphere");
    for solver in [LinearSolver::Direct, LinearSolver::Multigrid] {
        let options = LineFieldOptions {
            solver,
            ..LineFieldOptions::default()
        };
        let alone = smoothest_line_field(&one, &options).expect("one sphere");
        for copies in [1, 3, 7] {
            let mesh = spheres(copies, 8);
            assert_eq!(mesh.component_count(), copies as usize);
            let field = smoothest_line_field(&mesh, &options).expect("spheres");
            // 4 x K singularities of +1/2: four on each piece.
            for (k, indices) in indices_per_piece(&mesh, &field).iter().enumerate() {
                assert_eq!(
                    indices,
                    &vec![0.5; 4],
                    "{solver:?}, {copies} copies, piece {k}"
                );
            }
            // Each piece is the smoothest field of one sphere: its quotient is the
            // single solve's, and it is normalised on its own. (The round sphere's
            // smallest eigenvalue is repeated, so which field of that eigenspace a
            // moved copy gets may differ by round-off; the sphere beside other pieces
            // below, not moved, gets exactly the single solve's.)
            for (k, r) in rayleigh_per_piece(&mesh, &field).iter().enumerate() {
                assert!(
                    (r - alone.rayleigh).abs() < 1e-6 * alone.rayleigh,
                    "{solver:?}, {copies} copies, piece {k}: {r} against {}",
                    alone.rayleigh
                );
            }
            for (k, piece) in split(&mesh).expect("pieces").iter().enumerate() {
                let magnitudes: Vec<f64> = piece
                    .vertices
                    .iter()
                    .map(|&g| field.magnitudes[g as usize])
                    .collect();
                let norm = lumped_norm(&piece.mesh, &magnitudes);
                assert!(
                    (norm - 1.0).abs() < 1e-9,
                    "{solver:?}, piece {k}: norm {norm}"
                );
            }
            let c = f64::from(copies);
            assert!((field.rayleigh - alone.rayleigh).abs() < 1e-6 * alone.rayleigh);
            assert!((field.energy - c * alone.energy).abs() < 1e-6 * c * alone.energy);
        }
    }
}

#[test]
fn a_sphere_s_field_does_not_depend_on_the_pieces_beside_it() {
    let sphere = shapes::sphere(1.0, 8).expect("sphere");
    let n = sphere.vertex_count();
    // A flat square (smallest eigenvalue 0: one eigenproblem over every piece would
    // gather its eigenvector there), a cube with creases, a lone triangle.
    let square = crate::fixtures::lod::moved(&shapes::plane(1.0, 6).expect("plane"), |p| {
        *p + DVec3::new(4.0, 0.0, 0.0)
    });
    let boxed = crate::fixtures::lod::moved(&cube(2), |p| *p + DVec3::new(8.0, 0.0, 0.0));
    let triangle = TriMesh::new(
        vec![
            DVec3::new(0.0, 5.0, 0.0),
            DVec3::new(1.0, 5.0, 0.0),
            DVec3::new(0.0, 6.0, 0.3),
        ],
        vec![[0, 1, 2]],
    )
    .expect("triangle");
    let mesh = joined(&joined(&joined(&sphere, &square), &boxed), &triangle);
    assert_eq!(mesh.component_count(), 4);
    for solver in [LinearSolver::Direct, LinearSolver::Multigrid] {
        let options = LineFieldOptions {
            solver,
            ..LineFieldOptions::default()
        };
        let alone = smoothest_line_field(&sphere, &options).expect("sphere");
        let field = smoothest_line_field(&mesh, &options).expect("pieces");
        let angle = largest_angle(&field, &alone, n);
        assert!(
            angle < 1e-6,
            "{solver:?}: the sphere's lines moved by {angle} rad"
        );
        let rayleigh = rayleigh_per_piece(&mesh, &field);
        assert!((rayleigh[0] - alone.rayleigh).abs() < 1e-6 * alone.rayleigh);
        // The flat pieces' fields are flat (quotient 0); the cube's is its own
        // smoothest, with its eight corners' defects of pi / 2 (index 1/4 each would
        // need a 4-direction field: a line field puts +1/2 at some corners).
        assert!(rayleigh[1] < 1e-9 && rayleigh[3] < 1e-9, "{rayleigh:?}");
        let cube_alone = smoothest_line_field(&cube(2), &options).expect("cube");
        assert!((rayleigh[2] - cube_alone.rayleigh).abs() < 1e-6 * cube_alone.rayleigh);
        let indices = indices_per_piece(&mesh, &field);
        assert_eq!(indices[0], vec![0.5; 4], "{solver:?}");
        assert!(
            indices[1].is_empty() && indices[3].is_empty(),
            "{indices:?}"
        );
        assert_eq!(indices[2].iter().sum::<f64>(), 2.0, "{indices:?}");
    }
}

#[test]
fn the_scan_soup_builds_with_every_solver_and_guidance_and_is_the_same_each_time() {
    use crate::field::{Design, FieldSpec, Guidance};
    let mesh = scan_soup(300);
    assert!(mesh.component_count() >= 300, "{}", mesh.component_count());
    for solver in [
        LinearSolver::Direct,
        LinearSolver::Multigrid,
        LinearSolver::Auto,
    ] {
        let options = LineFieldOptions {
            solver,
            ..LineFieldOptions::default()
        };
        let field = smoothest_line_field(&mesh, &options).expect("smoothest");
        // Every piece carries a field normalised on it (none left near zero by
        // another piece's smaller eigenvalue).
        let pieces = split(&mesh).expect("pieces");
        let mut holders = vec![0; mesh.vertex_count()];
        for piece in &pieces {
            piece
                .vertices
                .iter()
                .for_each(|&v| holders[v as usize] += 1);
        }
        let apart = pieces
            .iter()
            .filter(|p| p.vertices.iter().all(|&v| holders[v as usize] == 1));
        assert!(apart.clone().count() >= 90);
        for piece in apart {
            let magnitudes: Vec<f64> = piece
                .mesh
                .input_vertex_map()
                .iter()
                .zip(&piece.vertices)
                .map(|(_, &g)| field.magnitudes[g as usize])
                .collect();
            let norm = lumped_norm(&piece.mesh, &magnitudes);
            assert!(
                (norm - 1.0).abs() < 1e-6,
                "{solver:?}: a piece's norm {norm}"
            );
        }
        assert_eq!(
            field,
            smoothest_line_field(&mesh, &options).expect("again"),
            "{solver:?}"
        );
        for guidance in [
            Guidance::Smoothest,
            Guidance::Curvature {
                smoothing_iterations: 2,
            },
            Guidance::Direction([1.0, 0.3, 0.2]),
        ] {
            let design = Design {
                guidance,
                solver,
                ..Design::default()
            };
            FieldSpec::Designed(design)
                .build(&mesh)
                .unwrap_or_else(|e| panic!("{solver:?}: {e}"));
        }
    }
}

#[test]
fn a_scan_of_hundreds_of_crumbs_gets_a_designed_field_with_every_solver_and_samples() {
    use std::sync::Arc;

    use crate::field::{Design, FieldSpec, Guidance};
    use crate::sample::Sample;
    use crate::surface::{Preprocessed, SurfaceOptions};
    let text = crate::fixtures::messy::scan(400);
    let mesh =
        crate::io::parse_obj(text.as_bytes(), std::path::Path::new("scan.obj")).expect("scan");
    assert!(mesh.component_count() >= 400, "{}", mesh.component_count());
    let warned = |what: &str| {
        mesh.warnings()
            .iter()
            .any(|w| format!("{w:?}").starts_with(what))
    };
    assert!(warned("NonManifoldEdges") && warned("RemovedDuplicateFaces"));
    let mesh = Arc::new(mesh);
    for solver in [
        LinearSolver::Direct,
        LinearSolver::Multigrid,
        LinearSolver::Auto,
    ] {
        for guidance in [
            Guidance::Smoothest,
            Guidance::Curvature {
                smoothing_iterations: 2,
            },
            Guidance::Direction([1.0, 0.3, 0.2]),
        ] {
            let design = Design {
                guidance: guidance.clone(),
                solver,
                ..Design::default()
            };
            let field = FieldSpec::Designed(design)
                .build(&mesh)
                .unwrap_or_else(|e| panic!("{solver:?}, {guidance:?}: {e}"));
            if solver != LinearSolver::Auto {
                continue;
            }
            let pre = Preprocessed::build(
                Arc::clone(&mesh),
                Arc::new(field),
                &SurfaceOptions::default(),
            )
            .unwrap_or_else(|e| panic!("{guidance:?}: {e}"));
            let mut samples = vec![Sample::default(); 2000];
            pre.sampler.sample_into(7, &mut samples);
            assert!(
                samples
                    .iter()
                    .all(|s| s.position.iter().chain(&s.spacing).all(|v| v.is_finite())),
                "{guidance:?}"
            );
        }
    }
}
