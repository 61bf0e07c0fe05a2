//! The field inside a disc of the mesh with no singularity, given its values around
//! the disc (for pair cancellation, `cancel.rs`): the field's doubled angle is
//! lifted to real numbers along the boundary, where it winds zero times, and
//! interpolated inside by the cotangent Laplacian against the connection's angles,
//! themselves lifted so that around every face they sum to its holonomy.
//!
//! Input: a mesh, its [`Connection`], the doubled-angle field `z`, the disc's faces and
//! its free vertices. Output: the new values of the free vertices, or `None` where the
//! disc does not allow it. Cost: O(disc) plus one sparse Cholesky of the free vertices.

use std::f64::consts::TAU;

use faer::MatMut;
use faer::c64;
use faer::sparse::{SparseColMat, Triplet};

use super::connection::Connection;
use super::index::{angle, face_double_index};
use crate::field::LineFieldError;
use crate::linalg::cholesky::{self, Cholesky};
use crate::mesh::TriMesh;

/// The field on the `free` vertices (ascending; those whose faces all lie in the disc
/// `faces`, ascending) with no singularity: its doubled angle `theta` is lifted to
/// real numbers along the disc's boundary (the field winds zero times around it) and
/// interpolated inside by the connection Laplacian,
/// `sum_u w_uv (theta_v - theta_u - rho_uv) = 0`, and its magnitude likewise. Where
/// every edge turns the field by less than `pi` against the transport `rho`, each
/// face's index is 0. `None` where that cannot be set up: a held vertex inside the
/// disc, a face whose connection angles do not sum to its holonomy (a frame spinning
/// across it), a non-zero index sum in the disc, or a boundary not joined by edges.
pub(super) fn angles_inside(
    mesh: &TriMesh,
    system: &Connection,
    z: &[c64],
    held: &[bool],
    faces: &[u32],
    free: &[u32],
) -> Result<Option<Vec<c64>>, LineFieldError> {
    let edges = distinct(faces.iter().flat_map(|&f| mesh.face_edges()[f as usize]));
    let is_free = |v: u32| free.binary_search(&v).is_ok();
    // Interior vertices that are held would need the lift through them.
    let held_inside = corners(mesh, faces).any(|v| {
        held[v as usize]
            && !is_free(v)
            && mesh
                .vertex_faces(v)
                .iter()
                .all(|g| faces.binary_search(g).is_ok())
    });
    if held_inside {
        return Ok(None);
    }
    let index_sum: i32 = faces
        .iter()
        .map(|&f| {
            face_double_index(
                mesh,
                &system.edges,
                system.holonomy.as_deref(),
                z,
                f as usize,
            )
        })
        .sum();
    if index_sum != 0 {
        return Ok(None);
    }
    let Some(lifted_rotation) = lifted_rotations(mesh, system, faces, &edges) else {
        return Ok(None);
    };
    // The connection angle of disc edge e walked from u.
    let rho = |e: u32, u: u32| {
        let r = lifted_rotation[edges.binary_search(&e).expect("a disc edge")];
        if system.edges[e as usize].a == u as usize {
            r
        } else {
            -r
        }
    };
    let boundary = distinct(corners(mesh, faces).filter(|&v| !is_free(v)));
    let Some(lifted) = lift_boundary(mesh, z, &boundary, &edges, &rho) else {
        return Ok(None);
    };
    let disc = Disc {
        free,
        boundary: &boundary,
        lifted: &lifted,
    };
    solve_inside(mesh, system, z, disc, &rho).map(Some)
}

/// The doubled angles of the field at the disc's `boundary` vertices (ascending) lifted
/// to real numbers: breadth first along the disc's `edges` between boundary vertices,
/// each step taking the turn nearest the transport `rho(e, u)` (the connection angle of
/// edge `e` walked from `u`). `None` where the boundary is empty or not joined by edges.
fn lift_boundary(
    mesh: &TriMesh,
    z: &[c64],
    boundary: &[u32],
    edges: &[u32],
    rho: &impl Fn(u32, u32) -> f64,
) -> Option<Vec<f64>> {
    if boundary.is_empty() {
        return None;
    }
    let in_disc = |e: u32| edges.binary_search(&e).is_ok();
    let mut lifted = vec![f64::NAN; boundary.len()];
    lifted[0] = angle(z[boundary[0] as usize]);
    let mut queue = std::collections::VecDeque::from([0usize]);
    while let Some(i) = queue.pop_front() {
        let u = boundary[i];
        for &e in mesh.vertex_edges(u) {
            if !in_disc(e) {
                continue;
            }
            let [a, b] = mesh.edges()[e as usize];
            let v = if a == u { b } else { a };
            let Ok(j) = boundary.binary_search(&v) else {
                continue;
            };
            if lifted[j].is_nan() {
                let step = rho(e, u);
                let turn = angle(
                    z[v as usize] * (c64::new(step.cos(), step.sin()) * z[u as usize]).conj(),
                );
                lifted[j] = lifted[i] + step + turn;
                queue.push_back(j);
            }
        }
    }
    (!lifted.iter().any(|t| t.is_nan())).then_some(lifted)
}

/// A disc's vertices: the free ones (ascending), the held boundary (ascending) and the
/// boundary's lifted angles.
#[derive(Clone, Copy)]
struct Disc<'a> {
    free: &'a [u32],
    boundary: &'a [u32],
    lifted: &'a [f64],
}

/// The field on the disc's free vertices: angle and magnitude interpolated from the
/// boundary by the cotangent Laplacian on the free vertices (definite: the boundary is
/// held), one factorization for the two right-hand sides.
fn solve_inside(
    mesh: &TriMesh,
    system: &Connection,
    z: &[c64],
    disc: Disc<'_>,
    rho: &impl Fn(u32, u32) -> f64,
) -> Result<Vec<c64>, LineFieldError> {
    let Disc {
        free,
        boundary,
        lifted,
    } = disc;
    let k = free.len();
    let mut lower = Vec::with_capacity(4 * k);
    let mut rhs = vec![0.0; 2 * k];
    for (i, &v) in free.iter().enumerate() {
        let mut diagonal = 0.0;
        for &e in mesh.vertex_edges(v) {
            let [a, b] = mesh.edges()[e as usize];
            let u = if a == v { b } else { a };
            let w = system.edges[e as usize].weight;
            diagonal += w;
            // theta_v - theta_u = rho_uv at rest.
            rhs[i] += w * rho(e, u);
            match free.binary_search(&u) {
                Ok(j) if j < i => lower.push(Triplet::new(i, j, -w)),
                Ok(_) => {}
                Err(_) => {
                    let j = boundary
                        .binary_search(&u)
                        .expect("a free vertex's neighbour is in the disc");
                    rhs[i] += w * lifted[j];
                    rhs[k + i] += w * z[u as usize].norm();
                }
            }
        }
        lower.push(Triplet::new(i, i, diagonal));
    }
    let matrix = SparseColMat::try_new_from_triplets(k, k, &lower)
        .map_err(|_| LineFieldError::Factorization { stage: "assembly" })?;
    let mut llt = Cholesky::new(
        cholesky::symbolic(matrix.symbolic())?,
        matrix.as_ref(),
        None,
    )?;
    llt.solve(MatMut::from_column_major_slice_mut(&mut rhs, k, 2))?;
    if rhs.iter().any(|x| !x.is_finite()) {
        return Err(LineFieldError::Factorization {
            stage: "disc solve",
        });
    }
    Ok((0..k)
        .map(|i| {
            let (s, c) = rhs[i].sin_cos();
            c64::new(c, s) * rhs[k + i].max(0.0)
        })
        .collect())
}

/// Per edge of the disc `faces` (`edges`, ascending), the connection's rotation angle
/// from its first vertex to its second as a real number: `arg r` plus a multiple of
/// `2 pi`, chosen so that around every face the angles sum to the face's holonomy
/// (the connection's real one where it has one, else `arg` of the product of its
/// rotations). Near the pole of the tangent frames (where
/// they spin) `arg r` alone does not. A dual spanning tree from a face on the disc's
/// boundary sets each face's edge toward its parent, leaves first. `None` where the
/// disc's faces are not joined through edges or none lies on its boundary.
fn lifted_rotations(
    mesh: &TriMesh,
    system: &Connection,
    faces: &[u32],
    edges: &[u32],
) -> Option<Vec<f64>> {
    let in_disc = |f: u32| faces.binary_search(&f).is_ok();
    let across = |f: u32, e: u32| {
        let [g, h] = mesh.edge_faces()[e as usize];
        if g == f { h } else { g }
    };
    let root = faces.iter().position(|&f| {
        mesh.face_edges()[f as usize]
            .iter()
            .any(|&e| !in_disc(across(f, e)))
    })?;
    let f = faces[root];
    let root_edge = *mesh.face_edges()[f as usize]
        .iter()
        .find(|&&e| !in_disc(across(f, e)))?;
    let mut parent = vec![u32::MAX; faces.len()];
    parent[root] = root_edge;
    let mut order = vec![root];
    let mut next = 0;
    while next < order.len() {
        let f = faces[order[next]];
        next += 1;
        for &e in &mesh.face_edges()[f as usize] {
            if let Ok(j) = faces.binary_search(&across(f, e))
                && parent[j] == u32::MAX
            {
                parent[j] = e;
                order.push(j);
            }
        }
    }
    if order.len() != faces.len() {
        return None;
    }
    let mut lifted: Vec<f64> = edges
        .iter()
        .map(|&e| angle(system.edges[e as usize].rotation))
        .collect();
    let slot = |e: u32| edges.binary_search(&e).expect("a disc edge");
    for &i in order.iter().rev() {
        let f = faces[i];
        let t = mesh.triangles()[f as usize];
        let fe = mesh.face_edges()[f as usize];
        let mut holonomy = c64::new(1.0, 0.0);
        let mut sum = 0.0;
        let mut own = 1.0;
        for k in 0..3 {
            let term = &system.edges[fe[k] as usize];
            let sign = if term.a == t[k] as usize { 1.0 } else { -1.0 };
            holonomy *= if sign > 0.0 {
                term.rotation
            } else {
                term.rotation.conj()
            };
            sum += sign * lifted[slot(fe[k])];
            if fe[k] == parent[i] {
                own = sign;
            }
        }
        let turns = ((system
            .holonomy
            .as_ref()
            .map_or_else(|| angle(holonomy), |h| h[f as usize])
            - sum)
            / TAU)
            .round();
        lifted[slot(parent[i])] += own * turns * TAU;
    }
    Some(lifted)
}

/// Whether `faces` (ascending) form one topological disc: Euler characteristic 1
/// (`V - E + F`) and connected.
pub(super) fn is_disc(mesh: &TriMesh, faces: &[u32]) -> bool {
    let vertices = distinct(corners(mesh, faces));
    let edges = distinct(faces.iter().flat_map(|&f| mesh.face_edges()[f as usize]));
    let euler = vertices.len() as i64 - edges.len() as i64 + faces.len() as i64;
    if euler != 1 || faces.is_empty() {
        return false;
    }
    // Connected through shared edges.
    let mut seen = vec![false; faces.len()];
    let mut stack = vec![0usize];
    seen[0] = true;
    let mut reached = 1;
    while let Some(i) = stack.pop() {
        for &g in &mesh.face_neighbors()[faces[i] as usize] {
            if let Ok(k) = faces.binary_search(&g)
                && !seen[k]
            {
                seen[k] = true;
                reached += 1;
                stack.push(k);
            }
        }
    }
    reached == faces.len()
}

/// The corners of `faces`, with repeats.
pub(super) fn corners<'a>(mesh: &'a TriMesh, faces: &'a [u32]) -> impl Iterator<Item = u32> + 'a {
    faces.iter().flat_map(|&f| mesh.triangles()[f as usize])
}

/// The distinct values of `items`, ascending.
pub(super) fn distinct(items: impl Iterator<Item = u32>) -> Vec<u32> {
    let mut out: Vec<u32> = items.collect();
    out.sort_unstable();
    out.dedup();
    out
}
