//! Per-face target frames: the field's major direction combed to a consistent sign, or
//! the isotropic fallback frame. Cost O(F); the fallback adds one sparse Cholesky
//! solve on the face graph.

use std::collections::VecDeque;

use faer::Mat;
use faer::sparse::{SparseColMat, Triplet};
use glam::DVec3;

use crate::field::{Eigen2, TensorField, eigen_in_plane, tangent_frame};
use crate::mesh::{NONE, TriMesh};

use super::patch::Patch;
use super::spd::solve_spd;
use super::{ParamError, ParamOptions};

/// Spacing ratios are capped here when averaging (a degenerate face tensor would
/// otherwise make the mean infinite).
const MAX_ANISOTROPY: f64 = 1e6;

/// Target frames of a segment's faces.
#[derive(Clone, Debug)]
pub(crate) struct Frames {
    /// Combed unit major direction per local face, in the face's plane.
    pub m1: Vec<DVec3>,
    /// `(sqrt(l1), sqrt(l2))` per local face.
    pub sqrt_l: Vec<[f64; 2]>,
    /// Whether the isotropic fallback frame was used.
    pub isotropic_fallback: bool,
    /// Glued sides across which the combed direction turns by more than 90 degrees.
    pub inconsistent: usize,
    /// Area-weighted mean of `sqrt(l1 / l2)`.
    pub mean_anisotropy: f64,
}

/// Rotates tangent vector `m` of the plane with normal `nf` about the unit edge
/// direction `e` into the plane with normal `ng` (the hinge map of the shared edge).
fn transport(m: DVec3, nf: DVec3, ng: DVec3, e: DVec3) -> DVec3 {
    e * m.dot(e) + ng.cross(e) * m.dot(nf.cross(e))
}

/// The unit direction of side `k` of local face `f`.
fn side_direction(mesh: &TriMesh, patch: &Patch, f: usize, k: usize) -> DVec3 {
    let t = mesh.triangles()[patch.faces[f] as usize];
    let p = mesh.positions();
    (p[t[(k + 1) % 3] as usize] - p[t[k] as usize]).normalize()
}

/// The field's decomposition on mesh face `f` as the frames use it: the mean of its
/// corners' tensors, in the face's plane.
pub(crate) fn face_eigen(mesh: &TriMesh, field: &TensorField, f: u32) -> Eigen2 {
    let tensors = field.tensors();
    let t = mesh.triangles()[f as usize];
    let mean =
        (tensors[t[0] as usize] + tensors[t[1] as usize] + tensors[t[2] as usize]) * (1.0 / 3.0);
    eigen_in_plane(&mean, mesh.face_normals()[f as usize])
}

/// Computes the per-face frames of the segment from the field's decomposition on each
/// patch face (`eigen`, in the patch's face order; see [`face_eigen`]).
pub(crate) fn frames(
    mesh: &TriMesh,
    eigen: Vec<Eigen2>,
    patch: &Patch,
    options: &ParamOptions,
) -> Result<Frames, ParamError> {
    let areas = mesh.face_areas();
    let total_area: f64 = patch.faces.iter().map(|&f| areas[f as usize]).sum();
    let mean_anisotropy = patch
        .faces
        .iter()
        .zip(&eigen)
        .map(|(&f, e)| areas[f as usize] * e.anisotropy().min(MAX_ANISOTROPY))
        .sum::<f64>()
        / total_area;
    let isotropic_fallback = mean_anisotropy < options.isotropy_threshold;

    let (m1, sqrt_l) = if isotropic_fallback {
        // Parallel transport of face 0's tangent axis over a breadth-first tree, then
        // the holonomy of the non-tree edges spread smoothly over all faces.
        let transported = comb(mesh, patch, &vec![None; patch.faces.len()]);
        let m1 = spread_holonomy(mesh, patch, &transported)?;
        // Keep the local density: l1 = l2 = sqrt(l1 l2).
        let sqrt_l = eigen.iter().map(|e| [e.density().sqrt(); 2]).collect();
        (m1, sqrt_l)
    } else {
        let raw: Vec<Option<DVec3>> = eigen.iter().map(|e| Some(e.major)).collect();
        let sqrt_l = eigen
            .iter()
            .map(|e| [e.l1.max(0.0).sqrt(), e.l2.max(0.0).sqrt()])
            .collect();
        (comb(mesh, patch, &raw), sqrt_l)
    };
    let inconsistent = count_inconsistent(mesh, patch, &m1);
    Ok(Frames {
        m1,
        sqrt_l,
        isotropic_fallback,
        inconsistent,
        mean_anisotropy,
    })
}

/// Gives the line field `raw` (`None`: no direction of its own, take the parent's) a
/// consistent sign by breadth-first propagation from face 0 across glued sides.
fn comb(mesh: &TriMesh, patch: &Patch, raw: &[Option<DVec3>]) -> Vec<DVec3> {
    let normals = mesh.face_normals();
    let normal = |f: usize| normals[patch.faces[f] as usize];
    let n = patch.faces.len();
    let mut m1 = vec![DVec3::ZERO; n];
    let mut seen = vec![false; n];
    let mut queue = VecDeque::with_capacity(n);
    m1[0] = raw[0].unwrap_or_else(|| tangent_frame(normal(0)).0);
    seen[0] = true;
    queue.push_back(0usize);
    while let Some(f) = queue.pop_front() {
        for k in 0..3 {
            let (g, _) = patch.neighbors[f][k];
            if g == NONE || seen[g as usize] {
                continue;
            }
            let g = g as usize;
            let e = side_direction(mesh, patch, f, k);
            let carried = transport(m1[f], normal(f), normal(g), e);
            m1[g] = match raw[g] {
                Some(d) if d.dot(carried) < 0.0 => -d,
                Some(d) => d,
                None => carried.normalize(),
            };
            seen[g] = true;
            queue.push_back(g);
        }
    }
    // The patch is connected (checked when it was built), so every face was reached.
    m1
}

/// Glued sides across which the direction field `m1` turns by more than 90 degrees.
fn count_inconsistent(mesh: &TriMesh, patch: &Patch, m1: &[DVec3]) -> usize {
    let normals = mesh.face_normals();
    let normal = |f: usize| normals[patch.faces[f] as usize];
    let mut inconsistent = 0;
    for f in 0..m1.len() {
        for k in 0..3 {
            let (g, _) = patch.neighbors[f][k];
            if g == NONE || (g as usize) < f {
                continue;
            }
            let g = g as usize;
            let e = side_direction(mesh, patch, f, k);
            if transport(m1[f], normal(f), normal(g), e).dot(m1[g]) < 0.0 {
                inconsistent += 1;
            }
        }
    }
    inconsistent
}

/// Rotates each face's direction of `base` (a direction field that is parallel across
/// the edges of a spanning tree) by the angle `phi_f` minimising
/// `sum over glued sides (phi_g - phi_f - rho_fg)^2` with `phi_0 = 0`, where `rho_fg` is
/// the angle from the transported `base_f` to `base_g` (zero on tree edges, the
/// holonomy of a loop through the tree elsewhere). This spreads the turning that
/// curvature forces on any tangent frame evenly over the segment (a Poisson problem on
/// the face graph, in the spirit of Crane et al. 2010's trivial connections) instead of
/// leaving it as jumps across the tree's non-tree edges. On a flat segment all
/// `rho` vanish and `base` is returned rotated by zero.
fn spread_holonomy(
    mesh: &TriMesh,
    patch: &Patch,
    base: &[DVec3],
) -> Result<Vec<DVec3>, ParamError> {
    let normals = mesh.face_normals();
    let normal = |f: usize| normals[patch.faces[f] as usize];
    let n = patch.faces.len();
    if n == 1 {
        return Ok(base.to_vec());
    }
    // Unknown of face f is f - 1: face 0 is pinned at phi = 0.
    let mut triplets = Vec::with_capacity(4 * n);
    let mut rhs = Mat::<f64>::zeros(n - 1, 1);
    for f in 0..n {
        for k in 0..3 {
            let (g, _) = patch.neighbors[f][k];
            if g == NONE || (g as usize) < f {
                continue;
            }
            let g = g as usize;
            let e = side_direction(mesh, patch, f, k);
            let carried = transport(base[f], normal(f), normal(g), e);
            let rho = carried
                .dot(normal(g).cross(base[g]))
                .atan2(carried.dot(base[g]));
            for (v, sign) in [(f, -1.0), (g, 1.0)] {
                if let Some(r) = v.checked_sub(1) {
                    triplets.push(Triplet::new(r, r, 1.0));
                    rhs[(r, 0)] += sign * rho;
                }
            }
            // f < g, so (g - 1, f - 1) is in the lower triangle.
            if f > 0 {
                triplets.push(Triplet::new(g - 1, f - 1, -1.0));
            }
        }
    }
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n - 1, n - 1, &triplets)
        .map_err(|_| ParamError::Solver {
            stage: "assembly of the fallback frame",
        })?;
    // Unknown r is face r + 1, at its centroid.
    let points: Vec<DVec3> = patch.faces[1..]
        .iter()
        .map(|&f| mesh.face_positions(f).iter().sum::<DVec3>() / 3.0)
        .collect();
    let phi = solve_spd(&matrix, rhs, Some(&points))?;
    Ok((0..n)
        .map(|f| {
            let angle = if f == 0 { 0.0 } else { phi[(f - 1, 0)] };
            let (s, c) = angle.sin_cos();
            base[f] * c + normal(f).cross(base[f]) * s
        })
        .collect())
}
