use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::*;
use crate::fixtures::creased::{capped_cylinder, cube};
use crate::mesh::shapes;

/// A deterministic pseudo-random number in [0, 1) per index.
fn noise(i: usize) -> f64 {
    let x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    ((x ^ (x >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9) >> 11) as f64 / (1u64 << 53) as f64
}

fn closed_meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("cube", cube(3)),
        ("capped cylinder", capped_cylinder(12)),
        ("sphere", shapes::sphere(1.0, 10).expect("sphere")),
        ("torus", shapes::torus(1.0, 0.4, 16).expect("torus")),
        ("genus 2", shapes::genus2(1.0, 1).expect("genus2")),
    ]
}

#[test]
fn holonomy_is_the_intrinsic_angle_defect_per_face() {
    for (name, mesh) in closed_meshes() {
        let spaces = TangentSpaces::new(&mesh);
        for (f, (h, d)) in spaces
            .face_holonomy()
            .iter()
            .zip(spaces.face_defect())
            .enumerate()
        {
            assert!(
                (h - d).abs() < 1e-12,
                "{name} face {f}: holonomy {h} defect {d}"
            );
        }
        // The transports around each face agree with the holonomy modulo 2 pi.
        for f in 0..mesh.face_count() {
            let t = mesh.triangles()[f];
            let mut sum = 0.0;
            for (&v, &e) in t.iter().zip(&mesh.face_edges()[f]) {
                let rho = spaces.transport(e as usize);
                sum += if mesh.edges()[e as usize][0] == v {
                    rho
                } else {
                    -rho
                };
            }
            let h = spaces.face_holonomy()[f];
            assert!(
                wrap_pi(sum - h).abs() < 1e-12,
                "{name} face {f}: {sum} vs {h}"
            );
        }
        let total: f64 = spaces.face_holonomy().iter().sum();
        let chi = mesh.euler_characteristic() as f64;
        assert!(
            (total - TAU * chi).abs() < 1e-9,
            "{name}: {total} vs 2 pi {chi}"
        );
    }
}

#[test]
fn cube_holonomy_sits_at_the_corners_only() {
    let mesh = cube(4);
    let spaces = TangentSpaces::new(&mesh);
    let corner = |p: DVec3| (p.abs() - DVec3::ONE).abs().max_element() < 1e-12;
    for (f, h) in spaces.face_holonomy().iter().enumerate() {
        let touches = mesh.triangles()[f]
            .iter()
            .any(|&v| corner(mesh.positions()[v as usize]));
        if !touches {
            assert!(h.abs() < 1e-12, "face {f} away from corners turns by {h}");
        }
    }
}

#[test]
fn poincare_hopf_holds_exactly_for_any_line_field() {
    for (name, mesh) in closed_meshes() {
        let spaces = TangentSpaces::new(&mesh);
        let doubled: Vec<f64> = (0..mesh.vertex_count())
            .map(|v| TAU * noise(v) - PI)
            .collect();
        let mut sum = 0;
        for f in 0..mesh.face_count() {
            // The unrounded winding is an integer.
            let t = mesh.triangles()[f];
            let mut w = 2.0 * spaces.face_holonomy()[f];
            for (&v, &e) in t.iter().zip(&mesh.face_edges()[f]) {
                let e = e as usize;
                let [a, b] = mesh.edges()[e];
                let [pa, pb] = spaces.edge_angles()[e];
                let turn =
                    wrap_pi((doubled[b as usize] - 2.0 * pb) - (doubled[a as usize] - 2.0 * pa));
                w += if a == v { turn } else { -turn };
            }
            let n = w / TAU;
            assert!((n - n.round()).abs() < 1e-9, "{name} face {f}: winding {n}");
            sum += spaces.face_double_index(&mesh, &doubled, f);
        }
        assert_eq!(sum, 2 * mesh.euler_characteristic(), "{name}");
    }
}

#[test]
fn world_directions_round_trip_exactly() {
    for (name, mesh) in closed_meshes()
        .into_iter()
        .chain([("plane", shapes::plane(1.0, 6).expect("plane"))])
    {
        let spaces = TangentSpaces::new(&mesh);
        for v in 0..mesh.vertex_count() {
            for j in 0..8 {
                let phi = TAU * noise(8 * v + j) - PI;
                let d = spaces.direction(v, phi);
                let (back, len) = spaces.doubled_angle(v, d).expect("tangent");
                assert!((len - 1.0).abs() < 1e-12);
                assert!(
                    wrap_pi(back - phi).abs() < 1e-9,
                    "{name} vertex {v}: {phi} -> {back}"
                );
                // A line has no sign.
                let (flipped, _) = spaces.doubled_angle(v, -d).expect("tangent");
                assert!(wrap_pi(flipped - phi).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn on_a_plane_transport_keeps_world_directions() {
    let mesh = shapes::plane(1.0, 6).expect("plane");
    let spaces = TangentSpaces::new(&mesh);
    // The square's corners open a quarter turn to a half plane; every other vertex is
    // flat (a full turn inside, a straight half turn on the sides).
    let angle_sum = |v: u32| -> f64 {
        mesh.vertex_faces(v)
            .iter()
            .map(|&f| {
                let t = mesh.triangles()[f as usize];
                let k = t.iter().position(|&u| u == v).expect("corner");
                let p = mesh.positions()[v as usize];
                let u = mesh.positions()[t[(k + 1) % 3] as usize] - p;
                let w = mesh.positions()[t[(k + 2) % 3] as usize] - p;
                u.angle_between(w)
            })
            .sum()
    };
    let flat = |v: u32| (angle_sum(v) - PI).abs() < 1e-9 || (angle_sum(v) - TAU).abs() < 1e-9;
    let mut checked = 0;
    for (e, &[a, b]) in mesh.edges().iter().enumerate() {
        if !flat(a) || !flat(b) {
            continue;
        }
        checked += 1;
        for d in [DVec3::X, DVec3::new(0.3, -0.8, 0.0)] {
            let (pa, _) = spaces.doubled_angle(a as usize, d).expect("tangent");
            let (pb, _) = spaces.doubled_angle(b as usize, d).expect("tangent");
            let rho = spaces.transport(e);
            assert!(wrap_pi(pb - pa - 2.0 * rho).abs() < 1e-9, "edge {e}");
        }
    }
    assert!(checked > mesh.edge_count() / 2);
}

#[test]
fn the_cube_smoothest_field_is_singular_only_at_corners_at_every_resolution() {
    use crate::field::design::{LineFieldOptions, smoothest_line_field};
    use crate::segment::detect_singularities;
    let corner = |p: DVec3| (p.abs() - DVec3::ONE).abs().max_element() < 1e-12;
    let options = LineFieldOptions {
        cancel_distance: 0.0,
        ..LineFieldOptions::default()
    };
    let mut places: Vec<Vec<[i64; 3]>> = Vec::new();
    for n in [2, 4] {
        let mesh = cube(n);
        let field = smoothest_line_field(&mesh, &options)
            .expect("field")
            .to_tensor_field(&mesh, &vec![[4.0, 1.0]; mesh.vertex_count()])
            .expect("tensor field");
        let found = detect_singularities(&mesh, &field);
        let total: f64 = found.iter().map(|s| s.index).sum();
        assert_eq!(total, 2.0, "cube {n}: {found:?}");
        assert!(found.iter().all(|s| s.index == 0.5), "cube {n}: {found:?}");
        let mut at: Vec<[i64; 3]> = Vec::new();
        for s in &found {
            let t = mesh.triangles()[s.face as usize];
            let c = t
                .iter()
                .map(|&v| mesh.positions()[v as usize])
                .find(|&p| corner(p));
            let c = c.unwrap_or_else(|| panic!("cube {n}: face {} away from the corners", s.face));
            at.push(c.to_array().map(|x| x.round() as i64));
        }
        at.sort_unstable();
        at.dedup();
        places.push(at);
    }
    // Four corners of +1/2 at both resolutions (which four is a free choice: the
    // cube's symmetries make several fields equally smooth).
    assert_eq!(places[0].len(), 4, "{places:?}");
    assert_eq!(places[1].len(), 4, "{places:?}");
}

/// Two octahedra touching at one vertex (a pinch: two closed fans there). Their
/// surface with the pinch split is two spheres, so the holonomy sums to `2 pi * 4`,
/// not `2 pi` times the mesh's `V - E + F = 3`, and every face's holonomy is its
/// defect.
#[test]
fn a_pinched_vertex_counts_the_defect_of_each_cone() {
    let octahedron = |c: DVec3| -> (Vec<DVec3>, Vec<[usize; 3]>) {
        let p = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ]
        .map(|d| c + d);
        let mut faces = Vec::new();
        for (x, y, z) in [0, 1].into_iter().flat_map(|x| {
            [2, 3]
                .into_iter()
                .flat_map(move |y| [4, 5].into_iter().map(move |z| (x, y, z)))
        }) {
            // Outward: the normal points away from the centre.
            let n = (p[y] - p[x]).cross(p[z] - p[x]);
            faces.push(if n.dot(p[x] - c) > 0.0 {
                [x, y, z]
            } else {
                [x, z, y]
            });
        }
        (p.to_vec(), faces)
    };
    let (a, fa) = octahedron(DVec3::ZERO);
    let (b, fb) = octahedron(DVec3::new(0.0, 0.0, 2.0));
    // b's -z vertex (index 5) is a's +z vertex (index 4).
    let mut positions = a.clone();
    let remap: Vec<u32> = (0..6)
        .map(|i| {
            if i == 5 {
                4
            } else {
                positions.push(b[i]);
                (positions.len() - 1) as u32
            }
        })
        .collect();
    let mut triangles: Vec<[u32; 3]> = fa.iter().map(|t| t.map(|i| i as u32)).collect();
    triangles.extend(fb.iter().map(|t| t.map(|i| remap[i])));
    let mesh = TriMesh::new(positions, triangles).expect("two octahedra");
    assert_eq!(mesh.euler_characteristic(), 3);
    assert_eq!(split_euler_characteristic(&mesh), 4, "two spheres");
    for (name, manifold) in closed_meshes() {
        assert_eq!(
            split_euler_characteristic(&manifold),
            manifold.euler_characteristic(),
            "{name} has no pinch"
        );
    }
    let spaces = TangentSpaces::new(&mesh);
    let total: f64 = spaces.face_holonomy().iter().sum();
    assert!((total - TAU * 4.0).abs() < 1e-9, "total holonomy {total}");
    for (h, d) in spaces.face_holonomy().iter().zip(spaces.face_defect()) {
        assert!((h - d).abs() < 1e-12, "holonomy {h} defect {d}");
    }
}
