//! The vertex normals after one implicit heat step, which the smoothed connection of
//! [`design`](super) is measured in (see its module docs, "Smoothed connection").
//!
//! Input: a mesh, its cotangent weights and lumped masses, a smoothing length, and the
//! solver's pattern (direct) or vertex graph (multigrid). Output: a unit normal per
//! vertex. Cost: one real numeric Cholesky on the shared symbolic factorization with
//! three columns, or one multigrid hierarchy and conjugate gradients on the three
//! columns side by side.

use faer::Mat;
use glam::DVec3;

use super::line_field::MAX_CG_ITERATIONS;
use super::pattern::VertexPattern;
use super::vertex_graph::VertexGraph;
use crate::field::LineFieldError;
use crate::linalg::cholesky::{Cholesky, Symbolic};
use crate::linalg::pcg;
use crate::mesh::TriMesh;

/// Relative residual of the multigrid solves of the normal smoothing: the smoothed
/// normals only steer the connection, so 1e-4 (about 1e-4 rad) is ample. Against
/// 1e-5 the designed bunny field Loop-subdivided once and twice moves by at most 0.009
/// and 0.029 degrees (mean 2e-5 degrees), with the same singularities, for 2 fewer
/// iterations of 11 and 13 (bench/README.md, "Solver tolerances").
const NORMALS_TOLERANCE: f64 = 1e-4;

/// How the normals' heat step is solved: on the direct solver's pattern and symbolic
/// factorization, or by multigrid on the vertex graph.
pub(super) enum Normals<'a> {
    Direct((&'a VertexPattern, &'a Symbolic)),
    Multigrid(&'a VertexGraph),
}

/// The vertex normals after one implicit heat step of time `length^2`,
/// `(M + length^2 L) N = M N0` with the (clamped) cotangent Laplacian `L`, normalised:
/// details of the surface smaller than about `length` no longer turn the normals, and
/// so no longer turn the connection (Ray, Vallet, Alonso and Lévy 2009 make fields
/// ignore small geometric details the same way). One numeric Cholesky on the shared
/// symbolic factorization, three columns.
pub(super) fn smoothed_normals(
    mesh: &TriMesh,
    weights: &[f64],
    mass: &[f64],
    length: f64,
    solver: Normals<'_>,
) -> Result<Vec<DVec3>, LineFieldError> {
    let t = length * length;
    let n = mesh.vertex_count();
    let mut diagonal: Vec<f64> = mass.to_vec();
    for (&[a, b], &w) in mesh.edges().iter().zip(weights) {
        diagonal[a as usize] += t * w;
        diagonal[b as usize] += t * w;
    }
    let normals = mesh.vertex_normals();
    let mut rhs = Mat::from_fn(n, 3, |v, k| mass[v] * normals[v][k]);
    let amg = match solver {
        Normals::Direct((pattern, symbolic)) => {
            let values = pattern.values(|v| diagonal[v], |e| -t * weights[e]);
            let mut llt = Cholesky::new(symbolic.clone(), pattern.matrix(&values), None)?;
            llt.solve(rhs.as_mut())?;
            None
        }
        Normals::Multigrid(graph) => {
            Some(graph.hierarchy(|v| diagonal[v], |e, _| -t * weights[e], mesh)?)
        }
    };
    if let Some(amg) = amg {
        // The three coordinates side by side: one pass over the hierarchy for all
        // three, each column solved as it would be alone.
        let b: Vec<DVec3> = (0..n).map(|v| normals[v] * mass[v]).collect();
        let mut x = vec![DVec3::ZERO; n];
        pcg::solve_three(&amg, &b, &mut x, NORMALS_TOLERANCE, MAX_CG_ITERATIONS)?;
        for (v, x) in x.into_iter().enumerate() {
            for k in 0..3 {
                rhs[(v, k)] = x[k];
            }
        }
    }
    Ok((0..n)
        .map(|v| {
            let smooth = DVec3::new(rhs[(v, 0)], rhs[(v, 1)], rhs[(v, 2)]);
            // Where opposite normals cancel (a thin sheet), or on round-off trouble,
            // keep the mesh's own normal.
            smooth
                .try_normalize()
                .filter(|s| s.is_finite())
                .unwrap_or(normals[v])
        })
        .collect())
}
