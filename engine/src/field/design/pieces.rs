//! One solve per connected piece: the public line-field solvers
//! ([`smoothest_line_field`], [`guided_line_field`], [`constrained_line_field`]) split
//! a mesh of several components ([`TriMesh::face_components`]: faces joined through
//! manifold edges) into one mesh per piece, solve each on its own with the solvers of
//! `solve.rs`, and put the results back together.
//!
//! Knöppel et al.'s smoothest field is the eigenvector of the smallest eigenvalue of
//! one piece's connection Laplacian. Over several pieces one eigenproblem is
//! degenerate or nearly so (every piece has its own smallest eigenvalue, and a flat
//! or developable piece's is zero), so its eigenvector is some mixture: it gathered
//! on the piece of smallest eigenvalue and left the others almost zero, their
//! directions decided by round-off. Solved per piece, each piece gets its own
//! smoothest (or guided) field, the same as if it were the whole mesh: options
//! measured on the mesh (the guidance weight per area, the smoothing length, the
//! cancellation distance, the smoothness shift's `lambda_1`) are measured on the
//! piece. A vertex that several pieces share (on a non-manifold edge or a pinched
//! vertex) is solved in each and takes the value of the piece with the most faces
//! around it (the lowest-numbered piece among ties).
//!
//! Input: a mesh, options, guidance and constraints. Output: a [`LineField`]. Cost:
//! one sub-mesh build per piece (O(F log F) in all) and the solves, over the pieces on
//! every thread (each piece's solve is deterministic, and the results are gathered in
//! piece order, so the thread count changes nothing). A mesh of one piece is solved
//! directly.

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use super::line_field::LineField;
use super::solve::{
    LineConstraint, LineFieldOptions, check_constraint_vertices, check_guidance, constrained_piece,
    smoothest_piece,
};
use crate::field::LineFieldError;
use crate::mesh::{NONE, TriMesh};

/// The smoothest line field of each connected piece of `mesh`: per piece the
/// eigenvector of the smallest eigenvalue of `A z = lambda M z` (see the
/// [module docs](crate::field::design)), normalised on the piece
/// (`sum_v m_v |z_v|^2 = 1` over its vertices): Rayleigh-Ritz on a Krylov space with
/// a direct solver, Rayleigh-Ritz on multigrid-preconditioned residuals (the Davidson
/// method) with multigrid. `options.weight` is not used.
///
/// Errors: invalid options, an empty mesh, a failed factorization.
pub fn smoothest_line_field(
    mesh: &TriMesh,
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    if mesh.component_count() <= 1 {
        return smoothest_piece(mesh, options);
    }
    per_piece(mesh, |piece| smoothest_piece(&piece.mesh, options))
}

/// The line field that balances smoothness against `guidance`: the minimiser of
/// `E(z) + w sum_v m_v c_v |z_v - u_v|^2`, `w = options.weight / area`, on each
/// connected piece (`area` the piece's; see the [module docs](crate::field::design)).
/// Each guidance vector is projected into its vertex's tangent plane; its direction
/// gives the line `u_v` (its sign does not matter) and its length the confidence `c_v`
/// (a zero vector: no guidance there, the field follows its neighbours). A weight of
/// 0, or no guidance anywhere, gives [`smoothest_line_field`].
///
/// Errors: invalid options, an empty mesh, a guidance of the wrong length or with a
/// non-finite vector, a failed factorization.
pub fn guided_line_field(
    mesh: &TriMesh,
    guidance: &[DVec3],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    constrained_line_field(mesh, guidance, &[], options)
}

/// [`guided_line_field`] with hard constraints: the field's line at each constrained
/// vertex is exactly the constraint's, and the rest minimises the same energy. With
/// constraints and weight 0 (or no guidance) the field is the smoothest one through
/// the constraints. `guidance` may be empty, meaning no soft guidance at all.
///
/// ```
/// use glam::DVec3;
/// use strata_engine::field::{LineConstraint, LineFieldOptions, constrained_line_field};
/// use strata_engine::mesh::shapes;
/// let mesh = shapes::plane(1.0, 8)?;
/// let pin = LineConstraint { vertex: 0, direction: DVec3::new(1.0, 1.0, 0.0) };
/// let field = constrained_line_field(&mesh, &[], &[pin], &LineFieldOptions::default())?;
/// // One constraint on a flat square: the smoothest field through it is constant.
/// let diagonal = DVec3::new(1.0, 1.0, 0.0).normalize();
/// assert!(field.directions.iter().all(|d| d.dot(diagonal).abs() > 1.0 - 1e-9));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// Errors: those of [`guided_line_field`], and a constraint naming a missing vertex,
/// with a direction normal to the surface (or not finite), or fixing a vertex that
/// another constraint fixes.
pub fn constrained_line_field(
    mesh: &TriMesh,
    guidance: &[DVec3],
    constraints: &[LineConstraint],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    let guided = !guidance.is_empty();
    constrained_line_field_with(
        mesh,
        (guided, || Cow::Borrowed(guidance)),
        constraints,
        options,
    )
}

/// [`constrained_line_field`] with the guidance made by `guidance.1` (on the whole
/// mesh); `guidance.0` says whether it may be non-empty. On a mesh of one piece the
/// guidance is made beside the connection's build (`solve.rs`); on several it is made
/// first and each piece is solved with its share. The result does not depend on the
/// thread count.
pub(crate) fn constrained_line_field_with<'g>(
    mesh: &TriMesh,
    (guided, guidance): (bool, impl FnOnce() -> Cow<'g, [DVec3]> + Send),
    constraints: &[LineConstraint],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    if mesh.component_count() <= 1 {
        return constrained_piece(mesh, (guided, guidance), constraints, options);
    }
    let guidance = guidance();
    check_whole(mesh, &guidance, constraints)?;
    per_piece(mesh, |piece| {
        let local: Vec<DVec3> = if guidance.is_empty() {
            Vec::new()
        } else {
            piece
                .vertices
                .iter()
                .map(|&v| guidance[v as usize])
                .collect()
        };
        // Each constraint in every piece that holds its vertex, with its index in the
        // caller's list, to name it in an error.
        let mut indices = Vec::new();
        let mut pinned = Vec::new();
        for (index, c) in constraints.iter().enumerate() {
            if let Ok(local_vertex) = piece.vertices.binary_search(&c.vertex) {
                let vertex = piece.mesh.input_vertex_map()[local_vertex];
                if vertex != NONE {
                    indices.push(index);
                    pinned.push(LineConstraint {
                        vertex,
                        direction: c.direction,
                    });
                }
            }
        }
        let local_guided = guided && !local.is_empty();
        constrained_piece(
            &piece.mesh,
            (local_guided, || Cow::Owned(local)),
            &pinned,
            options,
        )
        .map_err(|e| match e {
            LineFieldError::ConstraintDirection { index, .. } => {
                LineFieldError::ConstraintDirection {
                    index: indices[index],
                    vertex: constraints[indices[index]].vertex,
                }
            }
            e => e,
        })
    })
}

/// The checks on the whole mesh's input that a piece could only report in its own
/// numbering: the guidance's length and values, the constraints' vertices and
/// duplicates.
fn check_whole(
    mesh: &TriMesh,
    guidance: &[DVec3],
    constraints: &[LineConstraint],
) -> Result<(), LineFieldError> {
    let n = mesh.vertex_count();
    check_guidance(guidance, n)?;
    check_constraint_vertices(n, constraints)
}

/// A connected piece of a mesh as a mesh of its own.
struct Piece {
    mesh: TriMesh,
    /// Per vertex given to the piece's mesh (ascending), its vertex in the whole mesh;
    /// [`TriMesh::input_vertex_map`] of the piece's mesh takes it to the piece's own.
    vertices: Vec<u32>,
}

/// The connected pieces of `mesh` in the order of their lowest face, each with its
/// faces in the mesh's order and its vertices in the mesh's relative order (so a
/// piece's solve starts from the same pseudo-random vector as the piece alone).
fn split(mesh: &TriMesh) -> Result<Vec<Piece>, LineFieldError> {
    let mut faces: Vec<Vec<u32>> = vec![Vec::new(); mesh.component_count()];
    for (f, &c) in mesh.face_components().iter().enumerate() {
        faces[c as usize].push(f as u32);
    }
    faces
        .into_par_iter()
        .map(|faces| {
            let triangles = mesh.triangles();
            let mut vertices: Vec<u32> =
                faces.iter().flat_map(|&f| triangles[f as usize]).collect();
            vertices.sort_unstable();
            vertices.dedup();
            let local = |v: u32| vertices.binary_search(&v).unwrap_or(0) as u32;
            let corners: Vec<[u32; 3]> = faces
                .iter()
                .map(|&f| triangles[f as usize].map(local))
                .collect();
            let positions = vertices
                .iter()
                .map(|&v| mesh.positions()[v as usize])
                .collect();
            let piece =
                TriMesh::new(positions, corners).map_err(|_| LineFieldError::Factorization {
                    stage: "split into connected pieces",
                })?;
            Ok(Piece {
                mesh: piece,
                vertices,
            })
        })
        .collect()
}

/// `solve` on each connected piece of `mesh` (on every thread), its results put back
/// together: each vertex from the piece with the most faces around it (the lowest
/// piece among ties). The energy is the sum of the pieces', the Rayleigh quotient
/// that of the whole field, the iterations the sum. The first piece's error (in piece
/// order), if any, is returned.
fn per_piece(
    mesh: &TriMesh,
    solve: impl Fn(&Piece) -> Result<LineField, LineFieldError> + Sync,
) -> Result<LineField, LineFieldError> {
    let pieces = split(mesh)?;
    let solved: Vec<Result<LineField, LineFieldError>> = pieces.par_iter().map(&solve).collect();
    let n = mesh.vertex_count();
    let mut out = LineField {
        directions: vec![DVec3::ZERO; n],
        magnitudes: vec![0.0; n],
        energy: 0.0,
        rayleigh: 0.0,
        iterations: 0,
    };
    let mut faces_at = vec![0usize; n];
    let mut mass_norm = 0.0;
    for (piece, field) in pieces.iter().zip(solved) {
        let field = field?;
        out.energy += field.energy;
        out.iterations += field.iterations;
        mass_norm += lumped_norm(&piece.mesh, &field.magnitudes);
        for (&global, &own) in piece.vertices.iter().zip(piece.mesh.input_vertex_map()) {
            if own == NONE {
                continue;
            }
            let faces = piece.mesh.vertex_faces(own).len();
            let g = global as usize;
            if faces > faces_at[g] {
                faces_at[g] = faces;
                out.directions[g] = field.directions[own as usize];
                out.magnitudes[g] = field.magnitudes[own as usize];
            }
        }
    }
    out.rayleigh = if mass_norm > 0.0 {
        out.energy / mass_norm
    } else {
        0.0
    };
    Ok(out)
}

/// `sum_v m_v |z_v|^2` with the lumped mass (a third of the adjacent face areas per
/// vertex) of `mesh`, as the solvers measure it.
fn lumped_norm(mesh: &TriMesh, magnitudes: &[f64]) -> f64 {
    mesh.triangles()
        .iter()
        .zip(mesh.face_areas())
        .map(|(t, area)| {
            area / 3.0
                * t.iter()
                    .map(|&v| magnitudes[v as usize].powi(2))
                    .sum::<f64>()
        })
        .sum()
}

#[cfg(test)]
#[path = "pieces_tests.rs"]
mod tests;
