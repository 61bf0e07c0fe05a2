//! Field design: smooth line fields (2-direction fields) on vertex tangent planes with
//! few singularities, after Knöppel, Crane, Pinkall and Schröder, "Globally optimal
//! direction fields" (SIGGRAPH 2013).
//!
//! # Representation
//! Each vertex `v` has the intrinsic, angle-rescaled tangent space of
//! [`TangentSpaces`](crate::field::tangent_space::TangentSpaces) (Knöppel, Crane,
//! Pinkall and Schröder 2013, section 6.1; the conventions of geometry-central's
//! `IntrinsicGeometryInterface`, except at boundary vertices, see there). A line field
//! is a complex number per vertex, `z_v = r_v e^(2 i theta_v)`, with `theta_v` the
//! intrinsic angle: the doubled angle makes `theta` and `theta + pi` the same line, so
//! no sign has to be chosen anywhere. World directions come in and go out through each
//! vertex's exact line map (`design/frames.rs`).
//!
//! # Connection and energy
//! The discrete Levi-Civita connection of the paper: along edge `a -> b`, with
//! `phi_v` the intrinsic angle of the direction `a -> b` at `v`, a line at doubled
//! angle `alpha` at `a` arrives at `b` as `alpha + 2 (phi_b - phi_a)`, i.e. multiplied
//! by `r_ab = e^(2 i (phi_b - phi_a))`. Its holonomy around a face is the vertices'
//! intrinsic angle defect spread over their corners, so creases and the resolution of
//! flat regions do not turn it. This is the same connection as the singularity
//! detector's ([`line_field_transport`](crate::segment::line_field_transport)), so a
//! field that is smooth here turns little there. The energy is
//!
//! `E(z) = sum_edges w_ab |z_b - r_ab z_a|^2 = z^H A z`,
//!
//! with `A` Hermitian. The weights are the paper's cotangent weights
//! `w_ab = (cot alpha + cot beta) / 2` of the corners opposite the edge (one corner on a
//! boundary edge), as they are: negative across obtuse corners, which midpoint
//! subdivision of the same flat faces needs to leave the field unchanged (0 where a
//! sliver's cotangent overflows). The mass `M` is lumped: a third of the adjacent face
//! areas per vertex. Boundary vertices keep their real angle sums
//! ([`TangentSpaces`](crate::field::tangent_space::TangentSpaces)).
//!
//! **Where the energy is not positive definite.** With every weight positive `A` is
//! positive semi-definite under any connection; with negative weights it need not be:
//! an obtuse triangle across which the connection turns has an indefinite term of its
//! own, which its neighbours outweigh on a well-shaped surface but not at a scan's
//! slivers, and not under the smoothed connection below (its holonomy is not the
//! surface's). Two rules keep every solve definite:
//! - With [`LineFieldOptions::smoothing`] `> 0` the weights are floored at
//!   [`MIN_EDGE_WEIGHT`].
//! - Without smoothing, a piece whose system turns out not positive definite (a
//!   failed numeric Cholesky factorization, conjugate gradients meeting negative
//!   curvature or not converging, a multigrid hierarchy's coarse factor failing, or a
//!   smoothest field's eigenvalue below `-sigma`) is solved once more from the start
//!   with the floored weights. The other pieces keep the paper's weights.
//! - [`LineFieldOptions::weights`] asks for the floored weights on every piece.
//!
//! With multigrid, the smoothest field's eigen-iteration under the paper's weights is
//! preconditioned by the hierarchy of the floored weights' system: the negative
//! couplings turn the phase the aggregation transports and weaken the Gauss-Seidel
//! smoother (the bunny took 35 V-cycles with the system's own hierarchy, 21 with the
//! floored one's, 18 with the floored weights throughout), while Rayleigh-Ritz
//! applies the paper's `A`, so the field is theirs to the solver's tolerance
//! (`design/connection.rs`, `Connection::preconditioner`).
//!
//! # One solve per connected piece
//! Each connected piece of the mesh ([`TriMesh::face_components`](crate::mesh::TriMesh::face_components):
//! faces joined through manifold edges) is solved on its own, as a mesh of its own
//! (`design/pieces.rs`): its own smoothest, guided or constrained field, its own
//! `lambda_1`, and the options measured on the mesh (the weight per area, the
//! smoothing length, the cancellation distance) measured on the piece. The field on
//! a piece does not depend on the other pieces. One eigenproblem over several pieces
//! would not give each its smoothest field: its smallest eigenvalue is nearly
//! repeated (exactly zero on every flat or developable piece), so the eigenvector
//! gathers on the piece of smallest eigenvalue and leaves the others near zero, their
//! directions decided by round-off. A vertex that several pieces share (on a
//! non-manifold edge or a pinched vertex) takes the value of the piece with the most
//! faces around it. The pieces are solved on every thread; each solve is
//! deterministic and the results are gathered in piece order.
//!
//! # Solves
//! The complex Hermitian `n x n` systems are factored by faer's sparse Cholesky over
//! `c64` (sequential), with one symbolic factorization (AMD ordering) of the mesh's
//! pattern shared by every solve on the piece (see `design/connection.rs`). From
//! [`MULTIGRID_VERTICES`] vertices ([`LinearSolver::Auto`]) they are solved instead by
//! conjugate gradients preconditioned with algebraic multigrid ([`crate::linalg`]) to
//! [`SOLVE_TOLERANCE`], since a factor's fill grows faster than the mesh; the
//! eigen-solves then take one V-cycle on the eigen-residual per step instead of a
//! solve (the Davidson method, Rayleigh-Ritz on the space of those corrections).
//!
//! **Smoothed connection.** With [`LineFieldOptions::smoothing`] `> 0` the rotations
//! `r_ab` are those of the intrinsic connection times the change that smoothing the
//! vertex normals makes to the projected connection: `r_ab = r_intrinsic
//! r_smoothed conj(r_projected)`, where `r_projected` rotates by the difference of the
//! edge's angles projected into the two vertices' normal planes and `r_smoothed` the
//! same in the planes of the normals after one implicit heat step
//! `(M + l^2 L) N = M N0` (`l` the smoothing length, `L` the cotangent Laplacian
//! with the floored weights; each smoothed frame is the mesh's turned by the least
//! rotation between the two normals, so the factor carries no gauge). Bumps smaller than about `l` no
//! longer turn the connection, so they no longer attract singularities (Ray, Vallet,
//! Alonso and Lévy 2009 make fields ignore small details in the same spirit), and the
//! field stays in the intrinsic frames where the segmentation measures it.
//! - Smoothest field ([`smoothest_line_field`]): the eigenvector of the smallest
//!   eigenvalue of `A z = lambda M z`, with one factorization of `A + sigma M`
//!   (`sigma` = [`SHIFT`] times the ratio of the traces of `A` and `M`), from a fixed
//!   pseudo-random start: Rayleigh-Ritz on the Krylov space of `(A + sigma M)^-1 M`
//!   (`linalg/lanczos.rs`), until the Ritz value settles and the Ritz vector's residual is
//!   small, or the solve budget is spent. Its global phase (a rotation of every line)
//!   is free; the one returned is the limit of inverse iteration from the same start.
//!   On the bunny 12 solves give what inverse iteration gave in 64. With multigrid:
//!   30 V-cycles on the bunny Loop-subdivided once (`design/eigenpair.rs`).
//! - Guided field ([`guided_line_field`], [`constrained_line_field`]): given a guidance
//!   per vertex (a unit line `u_v` and a confidence `c_v >= 0`), a weight and optional
//!   hard constraints, one solve for the minimiser of
//!   `E(z) + w sum_v m_v c_v |z_v - u_v|^2` with `z_k = u_k` fixed at constrained
//!   vertices (they are eliminated: their terms move to the right-hand side). Where the
//!   confidence is 0 the field is free and interpolates its surroundings harmonically,
//!   so regions without guidance follow their neighbours instead of shrinking to zero
//!   (a plain `w |z - q|^2` pull toward `q = 0` would). A tiny shift `sigma M` (as for
//!   the smoothest field) keeps the system definite in a connected component that
//!   nothing pins (its field is then zero, and its directions are the frames' first
//!   axes). Weight 0 and no constraints give the smoothest field.
//! - Pair cancellation ([`LineFieldOptions::cancel_distance`], `design/cancel.rs`): after
//!   either solve, opposite singularities closer than a distance are removed together
//!   by re-solving the field's angle on a disc around both (Zhang, Hays and Turk 2007).
//!   It measures indices under the unsmoothed intrinsic connection, where the
//!   segmentation measures singularities.
//!
//! Input: a [`TriMesh`](crate::mesh::TriMesh) (and a guidance per vertex). Output: a [`LineField`], a unit
//! world-space direction and a magnitude per vertex, which [`LineField::to_tensor_field`]
//! turns into a [`TensorField`](crate::field::TensorField). Cost: O(V + E) assembly, one AMD ordering, one
//! complex `V x V` sparse Cholesky (plus a real one for the smoothed normals), and one
//! solve with that factor per Krylov step. With a smoothness shift the estimate of
//! `lambda_1` adds one factorization and a few solves (Rayleigh-Ritz on a Krylov space,
//! `linalg/lanczos.rs`; [`LAMBDA_TOLERANCE`]), or from [`MULTIGRID_VERTICES`] a
//! multigrid hierarchy and a few V-cycles. Measured (2 cores, release, `field_design`):
//! the rocker arm (10k vertices, factored) 0.04 s; the Stanford bunny (35k vertices,
//! multigrid) 0.16-0.17 s for the designed (curvature-aligned, shifted) field and
//! 0.17-0.18 s for the smoothest field. Two threads:
//! the AMD ordering beside the weights, the factor buffers' allocation beside the
//! normals' smoothing, the guidance (the designed field's curvature) beside the
//! estimate of `lambda_1`; the factors reuse one set of buffers (`linalg/cholesky.rs`).
//! Deterministic: fixed iteration order, sequential solves, fixed start vector, the
//! eigen-solvers' vector sums over fixed blocks of rows; the second thread computes an
//! independent input, so the thread count changes nothing.

//!
//! # Parts
//! - `pieces.rs`: the solvers' entry points ([`smoothest_line_field`],
//!   [`guided_line_field`], [`constrained_line_field`]): one solve per connected piece.
//! - `solve.rs`: the solvers on one piece and their options ([`LineFieldOptions`]).
//! - `line_field.rs`: the result [`LineField`], [`LinearSolver`] and the solver
//!   constants, below the solver and its system.
//! - `connection.rs`: the connection Laplacian, its factors and multigrid solves, on
//!   the vertex pattern (`pattern.rs`) or the vertex graph (`vertex_graph.rs`);
//!   `normals.rs`: the smoothed normals behind the smoothed connection.
//! - `frames.rs`: doubled angles to world directions and back, in the intrinsic
//!   tangent spaces (or, for the smoothing's factor, in vertex-normal planes).
//! - `eigenpair.rs`: the smallest eigenpair of the connection Laplacian (the
//!   eigensolver itself is `linalg::lanczos`).
//! - `index.rs`, `disc_angles.rs`, `cancel.rs`: face indices of a field, the angle
//!   re-solve on a disc, and pair cancellation built on both.
//! - `designed.rs`: the designed field source ([`Design`]), a line field with
//!   anisotropy and density from their own sources.

mod cancel;
mod connection;
mod designed;
mod disc_angles;
mod eigenpair;
mod frames;
mod index;
mod line_field;
mod normals;
mod pattern;
mod pieces;
mod solve;
mod vertex_graph;

pub use designed::{Anisotropy, Constraint, Density, Design, Guidance, Site};
pub use eigenpair::{LAMBDA_ITERATIONS, LAMBDA_TOLERANCE};
pub use line_field::{
    EdgeWeights, LineField, LinearSolver, MIN_EDGE_WEIGHT, MULTIGRID_VERTICES, SHIFT,
    SOLVE_TOLERANCE,
};
pub use pieces::{constrained_line_field, guided_line_field, smoothest_line_field};
pub use solve::{LineConstraint, LineFieldOptions, line_field_energy};

pub use crate::field::error::LineFieldError;
