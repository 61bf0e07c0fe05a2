//! Repair of local folds: a parameterization that fails only because a few triangles
//! flip or the boundary folds over itself within a few edges is relaxed there, and
//! kept if it then passes the exact validity test.
//!
//! A field-aligned map stretches angles; where the border of a piece has a sharp
//! corner beside a reflex one, the least-squares map can fold the border over by a
//! few edges (bench/README.md, "Borders that fold"). The rest of the map is sound.
//! Instead of splitting the piece, the vertices around the defect (corners of flipped
//! triangles, vertices whose angles in the map add up to more than a full turn, ends
//! of crossing boundary edges) and their neighbours are moved towards the mean of
//! their neighbours, a few rounds, the region growing by a ring per round; the result is tested exactly as a fresh map is
//! ([`validity::report`](super::validity)), so a repair never passes an invalid map.
//! Vertices with more than one copy (on a cut) stay where they are, so seams that
//! close stay closed.
//!
//! Cost: O(F) per round for the angle sums and the validity test; only failed maps
//! pay it.

use glam::DVec2;

use super::comb::Frames;
use super::patch::Patch;
use super::predicates::orient2d;
use super::{ParamOptions, ParamReport, validity};
use crate::mesh::TriMesh;
use crate::mesh::topology::vertex_triangles;

/// The map `uv` of `patch` relaxed around its defects (see the module docs) and its
/// report, if that makes it valid; `None` when it has no local defect, folds in more
/// than [`MAX_CROSSINGS`] places, or stays invalid after [`ROUNDS`] rounds.
pub(crate) fn repair(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
    uv: &[DVec2],
    options: &ParamOptions,
) -> Option<(Vec<DVec2>, ParamReport)> {
    let mut region = defects(uv, &patch.triangles);
    let boundary =
        validity::with_closed_seams(uv, &validity::patch_boundary(patch), &patch.local_to_mesh);
    let crossings = validity::boundary_crossings(uv, &boundary, MAX_CROSSINGS + 1);
    if crossings.len() > MAX_CROSSINGS {
        return None;
    }
    for &v in crossings.iter().flatten().flatten() {
        region[v as usize] = true;
    }
    if !region.contains(&true) {
        return None;
    }
    // A mesh vertex with several local copies is on a cut: moving one copy would open
    // a seam that closes, so they stay. (Sorted, not a table over the mesh: a small
    // piece of a large mesh pays for its own size.)
    let mut sorted = patch.local_to_mesh.clone();
    sorted.sort_unstable();
    let copies = |m: u32| sorted.partition_point(|&x| x <= m) - sorted.partition_point(|&x| x < m);
    let movable: Vec<bool> = patch
        .local_to_mesh
        .iter()
        .map(|&m| copies(m) == 1)
        .collect();
    let incidence = vertex_triangles(&patch.triangles, uv.len());
    let mut trial = uv.to_vec();
    for _ in 0..ROUNDS {
        let moved = relax(
            &mut trial,
            &mut region,
            &patch.triangles,
            &incidence,
            &movable,
            STEPS_PER_ROUND,
        );
        // The exact test only once the relaxed region itself is clean.
        if defects_near(&trial, &patch.triangles, Some(&region)).contains(&true) {
            continue;
        }
        let mut report = validity::report(mesh, patch, frames, &trial, options);
        if report.valid {
            report.relaxed_vertices = moved;
            return Some((trial, report));
        }
    }
    None
}

/// Rounds of relaxation; each grows the region by one ring and runs
/// [`STEPS_PER_ROUND`] Jacobi steps.
pub(crate) const ROUNDS: usize = 4;

/// More crossing pairs of boundary edges than this are not a local fold: no repair.
pub(crate) const MAX_CROSSINGS: usize = 32;

/// Jacobi steps per round.
pub(crate) const STEPS_PER_ROUND: usize = 8;

/// The local vertices to relax: corners of triangles that are not counter-clockwise,
/// and vertices whose corner angles add up to more than a full turn (a fold of the
/// border there). Returns a flag per local vertex.
pub(crate) fn defects(uv: &[DVec2], triangles: &[[u32; 3]]) -> Vec<bool> {
    defects_near(uv, triangles, None)
}

/// [`defects`] among the triangles with a corner in `near` (all when `None`); vertices
/// outside `near` are left unflagged.
pub(crate) fn defects_near(
    uv: &[DVec2],
    triangles: &[[u32; 3]],
    near: Option<&[bool]>,
) -> Vec<bool> {
    let mut bad = vec![false; uv.len()];
    let mut turn = vec![0.0f64; uv.len()];
    for t in triangles {
        if let Some(near) = near
            && !t.iter().any(|&v| near[v as usize])
        {
            continue;
        }
        let p = t.map(|v| uv[v as usize]);
        if orient2d(p[0], p[1], p[2]) != std::cmp::Ordering::Greater {
            for &v in t {
                bad[v as usize] = true;
            }
        }
        for k in 0..3 {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            turn[t[k] as usize] += a.perp_dot(b).atan2(a.dot(b));
        }
    }
    let full = std::f64::consts::TAU * (1.0 + 1e-9);
    for (v, (b, &s)) in bad.iter_mut().zip(&turn).enumerate() {
        *b = (*b || s > full) && near.is_none_or(|near| near[v]);
    }
    bad
}

/// Relaxes `uv` around the flagged vertices `region` (grown by one ring first), moving
/// each movable vertex of the region to the mean of its neighbours, `steps` times
/// (Jacobi: every step reads the previous step's positions). `incidence` lists each
/// local vertex's triangles (`mesh::topology::vertex_triangles`); `movable` excludes
/// vertices on cuts. Returns how many vertices it moves.
pub(crate) fn relax(
    uv: &mut [DVec2],
    region: &mut [bool],
    triangles: &[[u32; 3]],
    incidence: &(Vec<u32>, Vec<u32>),
    movable: &[bool],
    steps: usize,
) -> usize {
    let (offsets, faces) = incidence;
    let ring = |v: usize, out: &mut Vec<u32>| {
        out.clear();
        for &t in &faces[offsets[v] as usize..offsets[v + 1] as usize] {
            out.extend(
                triangles[t as usize]
                    .iter()
                    .copied()
                    .filter(|&w| w as usize != v),
            );
        }
        out.sort_unstable();
        out.dedup();
    };
    let mut scratch = Vec::new();
    let flagged: Vec<usize> = (0..uv.len()).filter(|&v| region[v]).collect();
    for v in flagged {
        ring(v, &mut scratch);
        for &w in &scratch {
            region[w as usize] = true;
        }
    }
    let members: Vec<(usize, Vec<u32>)> = (0..uv.len())
        .filter(|&v| region[v] && movable[v])
        .map(|v| {
            ring(v, &mut scratch);
            (v, scratch.clone())
        })
        .collect();
    let mut next = vec![DVec2::ZERO; members.len()];
    for _ in 0..steps {
        for (slot, (_, around)) in next.iter_mut().zip(&members) {
            *slot = around.iter().map(|&w| uv[w as usize]).sum::<DVec2>() / around.len() as f64;
        }
        for (&p, (v, _)) in next.iter().zip(&members) {
            uv[*v] = p;
        }
    }
    members.len()
}
