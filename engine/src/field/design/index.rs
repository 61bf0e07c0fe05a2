//! The index of a line field at the faces of the mesh, in the connection's frames:
//! what pair cancellation (`cancel.rs`) looks for and what the disc re-solve
//! (`disc_angles.rs`) must not create. Kept below both so neither depends on the other.
//!
//! Input: a mesh, the connection's edge terms and a doubled-angle field `z` per vertex.
//! Output: twice the index per face. Cost: O(1) per face, one `atan2` per corner only
//! where the field turns by more than `pi / 4` along an edge. The face's holonomy is
//! the connection's real one (intrinsic frames: the spread angle defect of
//! [`TangentSpaces`](crate::field::tangent_space::TangentSpaces)), else the angle of
//! the product of its rotations.

use std::f64::consts::{FRAC_PI_4, TAU};

use faer::c64;
use rayon::prelude::*;

use super::connection::{Connection, EdgeTerm};
use crate::mesh::TriMesh;

/// The angle of `z`, in `(-pi, pi]`.
pub(super) fn angle(z: c64) -> f64 {
    z.im.atan2(z.re)
}

/// Twice the index of every face of the line field `z` (doubled angles in the
/// connection's vertex frames): the turn of the field against the connection's
/// transport around the face, plus the face's holonomy, over `2 pi`. In the
/// intrinsic frames it is the segmentation's index.
pub(crate) fn face_double_indices(mesh: &TriMesh, system: &Connection, z: &[c64]) -> Vec<i32> {
    let (edges, holonomy) = (&system.edges, system.holonomy.as_deref());
    (0..mesh.face_count())
        .into_par_iter()
        .map(|f| face_double_index(mesh, edges, holonomy, z, f))
        .collect()
}

/// Twice the index of face `f` (see [`face_double_indices`]), with `edges` and
/// `holonomy` the connection's edge terms and doubled face holonomies (`None`: the
/// angle of the product of the face's rotations).
pub(super) fn face_double_index(
    mesh: &TriMesh,
    edges: &[EdgeTerm],
    holonomy: Option<&[f64]>,
    z: &[c64],
    f: usize,
) -> i32 {
    let t = mesh.triangles()[f];
    let fe = mesh.face_edges()[f];
    let mut turns = [c64::new(1.0, 0.0); 3];
    let mut product = c64::new(1.0, 0.0);
    for k in 0..3 {
        let (u, v) = (t[k] as usize, t[(k + 1) % 3] as usize);
        let e = &edges[fe[k] as usize];
        // The stored rotation transports a -> b; walking b -> a takes its inverse.
        let r = if e.a == u {
            e.rotation
        } else {
            e.rotation.conj()
        };
        product *= r;
        turns[k] = z[v] * (r * z[u]).conj();
    }
    let holonomy = holonomy.map_or_else(|| angle(product), |h| h[f]);
    // Three angles and the holonomy under pi/4 each sum to less than pi: index 0
    // without any arctangent (most faces of a smooth field).
    if holonomy.abs() < FRAC_PI_4 && turns.iter().all(|c| c.re > c.im.abs()) {
        return 0;
    }
    ((turns.iter().map(|&c| angle(c)).sum::<f64>() + holonomy) / TAU).round() as i32
}
