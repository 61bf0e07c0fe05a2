//! The least-squares solve of section 5.1.
//!
//! Minimising `sum_i A_i (|grad u - g1_i|^2 + |grad v - g2_i|^2)` over piecewise-linear
//! `u`, `v` gives the normal equations `K u = b1`, `K v = b2` with the stiffness matrix
//! (cotangent Laplacian) `K_jk = sum_i A_i grad phi_j . grad phi_k` and
//! `b_j = sum_i A_i grad phi_j . g_i` (the discrete divergence of the target field).
//! Local vertex 0 is pinned at the origin, which makes `K` positive definite on a
//! connected patch; one sparse Cholesky factorization then serves both right-hand
//! sides, solved together. Cost: O(F) assembly, factorization and solves as in the
//! module header.

use faer::Mat;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use glam::{DVec2, DVec3};

use crate::mesh::TriMesh;

use super::ParamError;
use super::comb::Frames;
use super::patch::Patch;
use super::spd::solve_spd;

/// Gradients (in the face's plane) of the three hat functions of a triangle with unit
/// normal `n` and area `area`: `grad phi_i = n x (p_{i+2} - p_{i+1}) / (2 area)`.
pub(crate) fn hat_gradients(p: [DVec3; 3], n: DVec3, area: f64) -> [DVec3; 3] {
    let s = 0.5 / area;
    [
        n.cross(p[2] - p[1]) * s,
        n.cross(p[0] - p[2]) * s,
        n.cross(p[1] - p[0]) * s,
    ]
}

/// The lower triangle's pattern of the stiffness matrix of `triangles` (`unknowns`
/// unknowns; local vertex `v` is unknown `v - 1`, vertex 0 pinned): column `c` holds the
/// diagonal and then, ascending, every unknown sharing a triangle with it. Made by a
/// counting sort over the triangles' sides (O(F), no global sort): per column the
/// larger ends of its sides, sorted and deduplicated in place.
fn stiffness_pattern(triangles: &[[u32; 3]], unknowns: usize) -> (Vec<usize>, Vec<usize>) {
    // Each side below the diagonal, as (column, row): both ends unknowns, row > column.
    let sides = |t: &[u32; 3]| {
        let t = *t;
        (0..3).filter_map(move |k| {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let (c, r) = (a.min(b).checked_sub(1)?, a.max(b) - 1);
            (r != c).then_some((c, r))
        })
    };
    // Column starts with room for the diagonal and every side (an interior side twice).
    let mut start = vec![0usize; unknowns + 1];
    for t in triangles {
        for (c, _) in sides(t) {
            start[c + 1] += 1;
        }
    }
    for c in 0..unknowns {
        start[c + 1] += start[c] + 1;
    }
    let mut rows = vec![0usize; start[unknowns]];
    let mut fill: Vec<usize> = start[..unknowns].iter().map(|&s| s + 1).collect();
    for (c, &s) in start[..unknowns].iter().enumerate() {
        rows[s] = c;
    }
    for t in triangles {
        for (c, r) in sides(t) {
            rows[fill[c]] = r;
            fill[c] += 1;
        }
    }
    // Sort and deduplicate each column's sides, compacting as we go.
    let mut col_ptr = Vec::with_capacity(unknowns + 1);
    let mut kept = 0;
    for c in 0..unknowns {
        col_ptr.push(kept);
        let (from, to) = (start[c], start[c + 1]);
        rows[from + 1..to].sort_unstable();
        let mut last = usize::MAX;
        for i in from..to {
            let r = rows[i];
            if r != last {
                rows[kept] = r;
                kept += 1;
                last = r;
            }
        }
    }
    col_ptr.push(kept);
    rows.truncate(kept);
    (col_ptr, rows)
}

/// The normal equations: the lower triangle of `K` (local vertex 0 pinned, unknown
/// `v - 1` for local vertex `v`) and the two right-hand sides as columns. The matrix is
/// filled into its pattern ([`stiffness_pattern`]) face by face, so each entry sums
/// its faces' terms in face order, as an assembly from triplets would.
pub(crate) fn assemble(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
) -> Result<(SparseColMat<usize, f64>, Mat<f64>), ParamError> {
    let vertex_count = patch.local_to_mesh.len();
    // Unknown of local vertex v is v - 1; vertex 0 is pinned at (0, 0).
    let unknowns = vertex_count - 1;
    let (col_ptr, row_idx) = stiffness_pattern(&patch.triangles, unknowns);
    let mut values = vec![0.0; row_idx.len()];
    let mut rhs = Mat::<f64>::zeros(unknowns, 2);
    for (i, (&f, t)) in patch.faces.iter().zip(&patch.triangles).enumerate() {
        let n = mesh.face_normals()[f as usize];
        let area = mesh.face_areas()[f as usize];
        let grads = hat_gradients(mesh.face_positions(f), n, area);
        let [s1, s2] = frames.sqrt_l[i];
        let m1 = frames.m1[i];
        let g1 = m1 * s1;
        let g2 = n.cross(m1) * s2;
        for a in 0..3 {
            let Some(ra) = (t[a] as usize).checked_sub(1) else {
                continue;
            };
            rhs[(ra, 0)] += area * grads[a].dot(g1);
            rhs[(ra, 1)] += area * grads[a].dot(g2);
            for b in 0..3 {
                let Some(rb) = (t[b] as usize).checked_sub(1) else {
                    continue;
                };
                // Lower triangle only: the factorization reads Side::Lower.
                if ra >= rb {
                    let column = col_ptr[rb]..col_ptr[rb + 1];
                    let slot = row_idx[column.clone()]
                        .iter()
                        .position(|&r| r == ra)
                        .ok_or(ParamError::Solver { stage: "assembly" })?;
                    values[column.start + slot] += area * grads[a].dot(grads[b]);
                }
            }
        }
    }
    let symbolic = SymbolicSparseColMat::new_checked(unknowns, unknowns, col_ptr, None, row_idx);
    Ok((SparseColMat::new(symbolic, values), rhs))
}

/// Solves for `(u, v)` per local vertex.
pub(crate) fn solve(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
) -> Result<Vec<DVec2>, ParamError> {
    let (matrix, rhs) = assemble(mesh, patch, frames)?;
    let unknowns = rhs.nrows();
    // Unknown r is local vertex r + 1.
    let points: Vec<DVec3> = patch.local_to_mesh[1..]
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    let rhs = solve_spd(&matrix, rhs, Some(&points))?;
    let mut uv = Vec::with_capacity(unknowns + 1);
    uv.push(DVec2::ZERO);
    for r in 0..unknowns {
        let p = DVec2::new(rhs[(r, 0)], rhs[(r, 1)]);
        if !p.is_finite() {
            return Err(ParamError::Solver {
                stage: "solution (not finite)",
            });
        }
        uv.push(p);
    }
    Ok(uv)
}
