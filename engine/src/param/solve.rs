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
use faer::sparse::{SparseColMat, Triplet};
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

/// The normal equations: the lower triangle of `K` (local vertex 0 pinned, unknown
/// `v - 1` for local vertex `v`) and the two right-hand sides as columns.
pub(crate) fn assemble(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
) -> Result<(SparseColMat<usize, f64>, Mat<f64>), ParamError> {
    let vertex_count = patch.local_to_mesh.len();
    // Unknown of local vertex v is v - 1; vertex 0 is pinned at (0, 0).
    let unknowns = vertex_count - 1;
    let mut triplets = Vec::with_capacity(6 * patch.faces.len() + unknowns);
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
                    triplets.push(Triplet::new(ra, rb, area * grads[a].dot(grads[b])));
                }
            }
        }
    }
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(unknowns, unknowns, &triplets)
        .map_err(|_| ParamError::Solver { stage: "assembly" })?;
    Ok((matrix, rhs))
}

/// Solves for `(u, v)` per local vertex.
pub(crate) fn solve(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
) -> Result<Vec<DVec2>, ParamError> {
    let (matrix, rhs) = assemble(mesh, patch, frames)?;
    let unknowns = rhs.nrows();
    let rhs = solve_spd(&matrix, rhs)?;
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
