//! Tests of singularity pair cancellation: the index agrees with the segmentation's,
//! a planted pair is removed exactly when it is close enough, the index sum never
//! changes, held vertices keep their values.

use faer::c64;
use glam::DVec3;

use super::*;
use crate::field::design::{LineFieldOptions, LinearSolver, smoothest_line_field};
use crate::field::tangent_frame;
use crate::mesh::shapes;
use crate::segment::detect_singularities;

/// The doubled-angle values of `directions` in the connection's frames.
fn doubled(system: &Connection, directions: &[DVec3]) -> Vec<c64> {
    directions
        .iter()
        .enumerate()
        .map(|(v, d)| {
            system
                .frames
                .doubled(v, *d)
                .map_or(c64::new(0.0, 0.0), |(_, u)| u)
        })
        .collect()
}

/// On the flat square `[0, 2]^2`: a `+1/2` singularity at `p` and a `-1/2` one at `q`, as doubled
/// angles `(x - p) conj(x - q)` in the plane's frame, taken to the connection's frames.
fn planted_pair(mesh: &TriMesh, system: &Connection, p: DVec3, q: DVec3) -> Vec<c64> {
    let (e1, e2) = tangent_frame(mesh.vertex_normals()[0]);
    mesh.positions()
        .iter()
        .enumerate()
        .map(|(v, x)| {
            let a = c64::new((*x - p).dot(e1), (*x - p).dot(e2));
            let b = c64::new((*x - q).dot(e1), (*x - q).dot(e2));
            let z = a * b.conj();
            let (s, c) = (0.5 * z.im.atan2(z.re)).sin_cos();
            let (_, u) = system.frames.doubled(v, e1 * c + e2 * s).expect("tangent");
            u * z.norm()
        })
        .collect()
}

/// A smooth field on `mesh` (angle `3x + 2yz` in the vertex-normal frames) with
/// uniform angle noise of width `noise` radians from a fixed seed, in the
/// connection's frames: singularities in pairs, close together.
fn noisy_field(mesh: &TriMesh, system: &Connection, seed: u64, noise: f64) -> Vec<c64> {
    let mut state = seed;
    (0..mesh.vertex_count())
        .map(|v| {
            let p = mesh.positions()[v];
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let angle = 3.0 * p.x + 2.0 * p.y * p.z + noise * u;
            let (e1, e2) = tangent_frame(mesh.vertex_normals()[v]);
            let (s, c) = (0.5 * angle).sin_cos();
            let (_, z) = system.frames.doubled(v, e1 * c + e2 * s).expect("tangent");
            z
        })
        .collect()
}

/// The flat square `[0, 2]^2` (40 x 40 quads), its system, and a planted pair 0.3
/// apart away from the border (off-vertex positions): the `+1/2` singularity's
/// position and the field.
fn planted() -> (TriMesh, Connection, DVec3, Vec<c64>) {
    let mesh = shapes::plane(2.0, 40).expect("plane");
    let system = Connection::build(&mesh, 0.0, LinearSolver::Direct, false).expect("system");
    let (p, q) = (
        DVec3::new(0.8487, 1.0217, 0.0),
        DVec3::new(1.1487, 1.0191, 0.0),
    );
    let z0 = planted_pair(&mesh, &system, p, q);
    (mesh, system, p, z0)
}

fn singular(double: &[i32]) -> Vec<(usize, i32)> {
    double
        .iter()
        .enumerate()
        .filter(|&(_, &n)| n != 0)
        .map(|(f, &n)| (f, n))
        .collect()
}

#[test]
fn face_indices_agree_with_the_segmentation_and_sum_to_twice_the_euler_characteristic() {
    let mesh = shapes::sphere(1.0, 5).expect("sphere");
    let field = smoothest_line_field(&mesh, &LineFieldOptions::default()).expect("field");
    let system = Connection::build(&mesh, 0.0, LinearSolver::Direct, false).expect("system");
    let double = face_double_indices(&mesh, &system, &doubled(&system, &field.directions));
    assert_eq!(double.iter().sum::<i32>(), 4, "sphere: 2 chi");
    let tensors = field
        .to_tensor_field(&mesh, &vec![[4.0, 1.0]; mesh.vertex_count()])
        .expect("tensors");
    let theirs: Vec<(usize, i32)> = detect_singularities(&mesh, &tensors)
        .iter()
        .map(|s| (s.face as usize, (2.0 * s.index) as i32))
        .collect();
    assert_eq!(singular(&double), theirs);
    assert_eq!(
        theirs.len(),
        4,
        "the smoothest field on a sphere: four +1/2"
    );
}

#[test]
fn a_planted_pair_is_cancelled_only_when_close_enough() {
    let (mesh, system, _, z0) = planted();
    let before = singular(&face_double_indices(&mesh, &system, &z0));
    assert_eq!(before.len(), 2, "{before:?}");
    assert_eq!(before.iter().map(|s| s.1).sum::<i32>(), 0);
    let held = vec![false; mesh.vertex_count()];

    let mut z = z0.clone();
    assert_eq!(
        cancel_pairs(&mesh, &system, &mut z, &held, 0.25).expect("cancel"),
        0
    );
    assert_eq!(z, z0, "a pair farther apart than the distance stays");

    let mut z = z0.clone();
    assert_eq!(
        cancel_pairs(&mesh, &system, &mut z, &held, 0.35).expect("cancel"),
        2
    );
    let after = singular(&face_double_indices(&mesh, &system, &z));
    assert!(after.is_empty(), "{after:?}");
    // Only a disc around the pair changed: the border keeps its values.
    for (v, x) in mesh.positions().iter().enumerate() {
        if (x.x - 1.0).abs().max((x.y - 1.0).abs()) > 0.9 {
            assert_eq!(z[v], z0[v], "vertex {v} at {x}");
        }
    }
    let changed = z.iter().zip(&z0).filter(|(a, b)| a != b).count();
    assert!(
        changed > 0 && changed < mesh.vertex_count() / 2,
        "{changed} changed"
    );
}

#[test]
fn held_vertices_keep_their_values_and_can_keep_a_pair() {
    let (mesh, system, p, z0) = planted();
    // Hold a ring around the +1/2 singularity: the smoothest field inside the disc
    // must still wind around it, so the pair stays.
    let held: Vec<bool> = mesh
        .positions()
        .iter()
        .map(|x| {
            let r = x.distance(p);
            (0.05..0.08).contains(&r)
        })
        .collect();
    let mut z = z0.clone();
    assert_eq!(
        cancel_pairs(&mesh, &system, &mut z, &held, 0.35).expect("cancel"),
        0
    );
    assert_eq!(z, z0, "a rejected disc is restored");
}

#[test]
fn cancelling_on_a_closed_surface_keeps_the_index_sum() {
    // A noisy field on a sphere: many pairs, whatever is cancelled the sum stays 2 chi.
    let mesh = shapes::sphere(1.0, 12).expect("sphere");
    let system = Connection::build(&mesh, 0.0, LinearSolver::Direct, false).expect("system");
    let z0 = noisy_field(&mesh, &system, 7, 1.5);
    let before = singular(&face_double_indices(&mesh, &system, &z0));
    assert!(before.len() > 6, "{} singular faces", before.len());
    let held = vec![false; mesh.vertex_count()];
    let mut z = z0.clone();
    let cancelled = cancel_pairs(&mesh, &system, &mut z, &held, 0.5).expect("cancel");
    let after = face_double_indices(&mesh, &system, &z);
    assert_eq!(after.iter().sum::<i32>(), 4);
    assert!(cancelled > 0);
    let net_before = net_clusters(&mesh, &face_double_indices(&mesh, &system, &z0)).len();
    let net_after = net_clusters(&mesh, &after).len();
    assert!(
        net_after == net_before - cancelled,
        "{net_before} -> {net_after} net clusters, {cancelled} cancelled"
    );
    // Deterministic.
    let mut again = z0.clone();
    cancel_pairs(&mesh, &system, &mut again, &held, 0.5).expect("cancel");
    assert_eq!(again, z);
}

#[test]
fn many_close_singularities_stay_bounded_and_do_not_depend_on_the_thread_count() {
    // A noisy field: 54 net singularities (34 cancel), most within the distance of many
    // others; every one is tried with at most MAX_PARTNERS partners.
    let mesh = shapes::sphere(1.0, 24).expect("sphere");
    let system = Connection::build(&mesh, 0.0, LinearSolver::Direct, false).expect("system");
    let z0 = noisy_field(&mesh, &system, 11, 2.5);
    let before = net_clusters(&mesh, &face_double_indices(&mesh, &system, &z0)).len();
    assert!(before > 40, "{before} net clusters");
    let held = vec![false; mesh.vertex_count()];
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            // The system is not Sync: each pool builds its own (the same values).
            let system =
                Connection::build(&mesh, 0.0, LinearSolver::Direct, false).expect("system");
            let mut z = z0.clone();
            let removed = cancel_pairs(&mesh, &system, &mut z, &held, 1.0).expect("cancel");
            (z, removed)
        })
    };
    let (z1, removed) = run(1);
    let (z4, removed4) = run(4);
    assert_eq!(removed, removed4);
    assert!(removed > 0);
    assert!(z1 == z4, "the thread count changed the field");
    let after = face_double_indices(&mesh, &system, &z1);
    assert_eq!(after.iter().sum::<i32>(), 4);
    assert_eq!(net_clusters(&mesh, &after).len(), before - removed);
    println!("noisy sphere: {before} net singularities, {removed} cancelled");
}
