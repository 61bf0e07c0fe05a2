//! The discrete connection Laplacian of line fields on vertex tangent planes, the
//! system behind [`design`](super) (see its module docs for the energy).
//!
//! Input: a [`TriMesh`] and a smoothing length. Output: a [`Connection`]: per edge the
//! cotangent weight and the rotation `r_ab` of the intrinsic connection (with the
//! smoothing's factor), per vertex the intrinsic frame and lumped mass, and Cholesky
//! factors of `A + diag(extra)` restricted to any subset of vertices. Complex Hermitian `V x V` systems (faer's sparse
//! Cholesky over `c64`, sequential); the symbolic factorization of the whole mesh's
//! pattern is computed once and shared by the normal smoothing and the field solves,
//! and the buffers of a finished factor are kept for the next ([`Connection::recycle`]).
//! Cost: O(V + E) assembly, one AMD ordering, one numeric factorization per solve.

use std::cell::{OnceCell, RefCell};
use std::sync::Arc;

use faer::c64;
use faer::sparse::{SparseColMat, Triplet};
use faer::{MatMut, traits::ComplexField};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

use super::normals::{Normals, smoothed_normals};
use super::pattern::VertexPattern;
use super::vertex_graph::VertexGraph;

use super::frames::Frames;
use super::line_field::{
    EdgeWeights, LineField, LinearSolver, MAX_CG_ITERATIONS, MIN_EDGE_WEIGHT, MULTIGRID_VERTICES,
    SHIFT, SOLVE_TOLERANCE,
};
use crate::field::LineFieldError;
use crate::field::tangent_space::TangentSpaces;
use crate::field::{tangent_frame, vertex_frames};
use crate::linalg::cholesky::{self, Cholesky, Storage, Symbolic};
use crate::linalg::{Amg, AmgOptions, Csr, Scalar, pcg};
use crate::mesh::TriMesh;

/// One edge of the energy: `w |z_b - r z_a|^2`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeTerm {
    pub(crate) a: usize,
    pub(crate) b: usize,
    pub(crate) weight: f64,
    pub(crate) rotation: c64,
}

/// A factored (direct) or preconditioned (multigrid) system, ready to solve.
pub(crate) enum Factor {
    Direct(Cholesky<c64>),
    Multigrid(Amg<c64>),
}

impl Factor {
    /// Solves in place, checking the result is finite.
    pub(crate) fn solve(&mut self, z: &mut [c64]) -> Result<(), LineFieldError> {
        match self {
            Self::Direct(llt) => solve(llt, z),
            Self::Multigrid(amg) => {
                let rhs = z.to_vec();
                z.iter_mut().for_each(|v| *v = c64::new(0.0, 0.0));
                pcg::solve(amg, &rhs, z, SOLVE_TOLERANCE, MAX_CG_ITERATIONS)?;
                Ok(())
            }
        }
    }
}

/// The discretised energy and mass of a mesh (see the [module docs](self)).
pub(crate) struct Connection {
    pub(crate) frames: Frames,
    /// Per face, the doubled holonomy `2 Omega_f` as a real number (intrinsic
    /// frames only; see [`TangentSpaces::face_holonomy`]).
    pub(crate) holonomy: Option<Vec<f64>>,
    pub(crate) edges: Vec<EdgeTerm>,
    /// Per vertex, the diagonal `sum w` of `A`.
    pub(crate) diagonal: Vec<f64>,
    /// Per vertex, the lumped mass.
    pub(crate) mass: Vec<f64>,
    /// The lower-triangle pattern of the whole mesh (direct solves only).
    pattern: Option<VertexPattern>,
    /// The vertex graph in the hierarchies' order (multigrid solves only).
    graph: Option<VertexGraph>,
    /// The symbolic Cholesky of the whole mesh's pattern, made by `build` when asked to
    /// prepare, else on first use (an energy evaluation never needs it).
    symbolic: OnceCell<Symbolic>,
    /// The buffers of the last direct factor handed back, for the next.
    spare: RefCell<Option<Storage<c64>>>,
    /// Whether solves use multigrid (else sparse Cholesky).
    pub(crate) multigrid: bool,
}

/// Conjugate-gradient iterations a solve with a reused hierarchy
/// ([`Connection::solve_with_hierarchy`]) may take before the caller builds a fresh
/// one: three times the 15 to 21 a fresh hierarchy takes on the bunny at every size,
/// and more than a fresh hierarchy's setup costs (about 14 iterations at 1.1M faces).
const REUSE_MAX_ITERATIONS: usize = 60;

/// `e^(i psi)` for the angle `psi` of `d` in the frame `(e1, e2)`
/// ([`frame_angle`](crate::field::frame_angle) without trigonometry); 1 where `d` has no
/// tangent part, as `atan2(0, 0) = 0` gives.
fn unit_direction(d: DVec3, (e1, e2): (DVec3, DVec3)) -> c64 {
    let (c, s) = (d.dot(e1), d.dot(e2));
    let r2 = c * c + s * s;
    if r2 > 0.0 {
        let r = r2.sqrt();
        c64::new(c / r, s / r)
    } else {
        c64::new(1.0, 0.0)
    }
}

/// Assembles the full Hermitian matrix from lower-triangle triplets.
fn hermitian_csr<T: Scalar>(n: usize, lower: &[Triplet<usize, usize, T>]) -> Csr<T> {
    let mut full = Vec::with_capacity(2 * lower.len());
    for t in lower {
        full.push((t.row, t.col, t.val));
        if t.row != t.col {
            full.push((t.col, t.row, t.val.conj()));
        }
    }
    Csr::from_triplets(n, n, &full)
}

/// Cotangent weight per edge, `(cot alpha + cot beta) / 2`, as it is
/// ([`EdgeWeights::Cotan`]: negative across obtuse corners, 0 where it is not finite) or
/// floored at [`MIN_EDGE_WEIGHT`] ([`EdgeWeights::Floored`]: the floor where it is not
/// finite), and lumped mass per vertex.
fn weights_and_mass(mesh: &TriMesh, kind: EdgeWeights) -> (Vec<f64>, Vec<f64>) {
    let pos = mesh.positions();
    let mut mass = vec![0.0; mesh.vertex_count()];
    let mut cotan = vec![0.0; mesh.edge_count()];
    for ((t, fe), area) in mesh
        .triangles()
        .iter()
        .zip(mesh.face_edges())
        .zip(mesh.face_areas())
    {
        for k in 0..3 {
            mass[t[k] as usize] += area / 3.0;
            // Edge k joins corners k and k + 1; the opposite corner is k + 2.
            let o = pos[t[(k + 2) % 3] as usize];
            let u = pos[t[k] as usize] - o;
            let v = pos[t[(k + 1) % 3] as usize] - o;
            let cross = u.cross(v).length();
            if cross > 0.0 {
                cotan[fe[k] as usize] += 0.5 * u.dot(v) / cross;
            }
        }
    }
    let weights = cotan
        .into_iter()
        .map(|c| match (kind, c.is_finite()) {
            (EdgeWeights::Cotan, true) => c,
            (EdgeWeights::Cotan, false) => 0.0,
            (EdgeWeights::Floored, true) => c.max(MIN_EDGE_WEIGHT),
            (EdgeWeights::Floored, false) => MIN_EDGE_WEIGHT,
        })
        .collect();
    (weights, mass)
}

/// The lower-triangle triplets of the pattern of `mesh` restricted to `slots < free`,
/// with `diagonal(v)` and `off(edge index)` as values (each off-diagonal at
/// `(larger slot, smaller slot)`, given the orientation `slot_b > slot_a`).
fn triplets<T>(
    mesh: &TriMesh,
    slots: &[usize],
    free: usize,
    diagonal: impl Fn(usize) -> T,
    off: impl Fn(usize, bool) -> T,
) -> Vec<Triplet<usize, usize, T>> {
    let mut out = Vec::with_capacity(free + mesh.edge_count());
    for (v, &i) in slots.iter().enumerate() {
        if i < free {
            out.push(Triplet::new(i, i, diagonal(v)));
        }
    }
    for (e, &[a, b]) in mesh.edges().iter().enumerate() {
        let (sa, sb) = (slots[a as usize], slots[b as usize]);
        if sa < free && sb < free {
            out.push(Triplet::new(sa.max(sb), sa.min(sb), off(e, sb > sa)));
        }
    }
    out
}

/// The symbolic factorization in `cell`, made from the whole mesh's `pattern` on first
/// use.
fn shared_symbolic(
    cell: &OnceCell<Symbolic>,
    pattern: &VertexPattern,
) -> Result<Symbolic, LineFieldError> {
    if let Some(s) = cell.get() {
        return Ok(s.clone());
    }
    let s = cholesky::symbolic(pattern.symbolic())?;
    Ok(cell.get_or_init(|| s).clone())
}

fn assemble<T: ComplexField>(
    n: usize,
    triplets: &[Triplet<usize, usize, T>],
) -> Result<SparseColMat<usize, T>, LineFieldError> {
    SparseColMat::try_new_from_triplets(n, n, triplets)
        .map_err(|_| LineFieldError::Factorization { stage: "assembly" })
}

impl Connection {
    /// The system of `mesh`, with its connection measured in the tangent planes of the
    /// normals smoothed over `smoothing` (a length; 0 keeps the mesh's own normals).
    /// With `prepare` (the caller will factor the system) a direct solver's symbolic
    /// factorization is made on a second thread while the weights are summed, and the
    /// buffers of the complex factors are allocated there while the normals are
    /// smoothed; the results do not depend on it. The weights are [`EdgeWeights::first`]
    /// of `smoothing`.
    pub(crate) fn build(
        mesh: &TriMesh,
        smoothing: f64,
        solver: LinearSolver,
        prepare: bool,
    ) -> Result<Self, LineFieldError> {
        Self::build_with(
            mesh,
            smoothing,
            solver,
            prepare,
            EdgeWeights::Cotan.first(smoothing),
        )
    }

    /// [`build`](Self::build) with the edge weights `kind`.
    pub(crate) fn build_with(
        mesh: &TriMesh,
        smoothing: f64,
        solver: LinearSolver,
        prepare: bool,
        kind: EdgeWeights,
    ) -> Result<Self, LineFieldError> {
        let n = mesh.vertex_count();
        if n == 0 {
            return Err(LineFieldError::EmptyMesh);
        }
        let multigrid = match solver {
            LinearSolver::Auto => n >= MULTIGRID_VERTICES,
            LinearSolver::Direct => false,
            LinearSolver::Multigrid => true,
        };
        let pattern = if multigrid {
            None
        } else {
            Some(VertexPattern::new(mesh)?)
        };
        let eager = pattern.as_ref().filter(|_| prepare || smoothing > 0.0);
        let (symbolic, (weights, mass), graph) = match eager {
            Some(pattern) => {
                let (made, weights_and_mass) = rayon::join(
                    || cholesky::symbolic(pattern.symbolic()),
                    || weights_and_mass(mesh, kind),
                );
                (Some(made?), weights_and_mass, None)
            }
            None => {
                let (graph, weights_and_mass) = rayon::join(
                    || multigrid.then(|| VertexGraph::new(mesh)),
                    || weights_and_mass(mesh, kind),
                );
                (None, weights_and_mass, graph)
            }
        };
        if !(mass.iter().sum::<f64>() > 0.0) {
            return Err(LineFieldError::EmptyMesh);
        }
        let (smoothed, spare) = rayon::join(
            || -> Result<Option<Vec<(DVec3, DVec3)>>, LineFieldError> {
                if !(smoothing > 0.0) {
                    return Ok(None);
                }
                let solver = match (pattern.as_ref().zip(symbolic.as_ref()), &graph) {
                    (Some(direct), _) => Normals::Direct(direct),
                    (None, Some(graph)) => Normals::Multigrid(graph),
                    (None, None) => Normals::Multigrid(&VertexGraph::new(mesh)),
                };
                // Each vertex frame turned by the least rotation from the mesh's normal
                // to the smoothed one, so that the two sets of frames differ by no
                // gauge, only by the smoothing.
                Ok(Some(
                    smoothed_normals(mesh, &weights, &mass, smoothing, solver)?
                        .into_iter()
                        .zip(mesh.vertex_normals())
                        .map(|(smooth, n)| {
                            let (e1, _) = tangent_frame(*n);
                            let e1 = DQuat::from_rotation_arc(*n, smooth) * e1;
                            (e1, smooth.cross(e1))
                        })
                        .collect(),
                ))
            },
            || {
                symbolic
                    .as_ref()
                    .filter(|_| prepare)
                    .and_then(Storage::<c64>::allocate)
            },
        );
        let frames = Frames::Intrinsic(Arc::new(TangentSpaces::new(mesh)));
        let (mut edges, mut holonomy) = edge_terms(mesh, &frames, weights.iter().copied());
        if let Some(planes) = smoothed? {
            // The smoothing's change of the projected connection, carried over to the
            // intrinsic one: `r = r_intrinsic r_smoothed conj(r_projected)`.
            let (smooth, _) = edge_terms(mesh, &Frames::Planes(planes), weights.iter().copied());
            let (raw, _) = edge_terms(
                mesh,
                &Frames::Planes(vertex_frames(mesh)),
                weights.iter().copied(),
            );
            for ((e, s), r) in edges.iter_mut().zip(&smooth).zip(&raw) {
                e.rotation *= s.rotation * r.rotation.conj();
            }
            holonomy = None;
        }
        let mut diagonal = vec![0.0; n];
        for e in &edges {
            diagonal[e.a] += e.weight;
            diagonal[e.b] += e.weight;
        }
        Ok(Self {
            frames,
            holonomy,
            edges,
            diagonal,
            mass,
            pattern,
            graph,
            symbolic: symbolic.map_or_else(OnceCell::new, OnceCell::from),
            spare: RefCell::new(spare),
            multigrid,
        })
    }

    /// The same weights and masses with the connection measured in the mesh's own
    /// intrinsic tangent spaces (no smoothing), for evaluation only (no factorization
    /// is prepared): where a field is compared with the segmentation's view of it.
    pub(crate) fn unsmoothed(&self, mesh: &TriMesh) -> Self {
        let frames = Frames::Intrinsic(Arc::new(TangentSpaces::new(mesh)));
        let (edges, holonomy) = edge_terms(mesh, &frames, self.edges.iter().map(|e| e.weight));
        Self {
            frames,
            holonomy,
            edges,
            diagonal: self.diagonal.clone(),
            mass: self.mass.clone(),
            pattern: None,
            graph: None,
            symbolic: OnceCell::new(),
            spare: RefCell::new(None),
            multigrid: self.multigrid,
        }
    }

    /// The doubled-angle values `z` of this system's frames in `to`'s: each line
    /// taken to `to`'s frame through its world direction, with the same magnitude (0
    /// where the line is normal to `to`'s plane).
    pub(crate) fn transfer(&self, z: &[c64], to: &Connection) -> Vec<c64> {
        z.iter()
            .enumerate()
            .map(|(v, z)| {
                let d = self.frames.direction(v, *z);
                to.frames
                    .doubled(v, d)
                    .map_or(c64::new(0.0, 0.0), |(_, u)| u * z.norm())
            })
            .collect()
    }

    /// The tiny shift `sigma = SHIFT tr(A) / tr(M)` that keeps `A + sigma M` definite.
    pub(crate) fn shift(&self) -> f64 {
        SHIFT * self.diagonal.iter().sum::<f64>() / self.mass.iter().sum::<f64>()
    }

    pub(crate) fn len(&self) -> usize {
        self.mass.len()
    }

    /// The Cholesky factor of `A + diag(extra)` restricted to the vertices with
    /// `slots[v] < free` (vertex `v` becomes unknown `slots[v]`). The whole mesh
    /// (`free == len`, `slots` the identity) reuses the shared symbolic factorization.
    pub(crate) fn factor(
        &self,
        mesh: &TriMesh,
        extra: &[f64],
        slots: &[usize],
        free: usize,
    ) -> Result<Factor, LineFieldError> {
        // Entry (b, a) of A is -w r_ab; entry (a, b) is its conjugate.
        let diagonal = |v: usize| c64::new(self.diagonal[v] + extra[v], 0.0);
        if let Some(pattern) = self.pattern.as_ref().filter(|_| free == self.len()) {
            // The whole mesh: edges are sorted pairs, so `b > a` is the lower entry.
            let values = pattern.values(diagonal, |e| {
                let term = &self.edges[e];
                -term.rotation * term.weight
            });
            let symbolic = shared_symbolic(&self.symbolic, pattern)?;
            let spare = self.spare.borrow_mut().take();
            let llt = Cholesky::new(symbolic, pattern.matrix(&values), spare)?;
            return Ok(Factor::Direct(llt));
        }
        if self.multigrid {
            return Ok(Factor::Multigrid(self.hierarchy(mesh, extra, slots, free)?));
        }
        let matrix = assemble(free, &self.lower_triplets(mesh, extra, slots, free))?;
        let symbolic = cholesky::symbolic(matrix.symbolic())?;
        let spare = self.spare.borrow_mut().take();
        Ok(Factor::Direct(Cholesky::new(
            symbolic,
            matrix.as_ref(),
            spare,
        )?))
    }

    /// The multigrid hierarchy of `A + diag(extra)` restricted as in
    /// [`factor`](Self::factor), whichever solver the system uses.
    pub(crate) fn hierarchy(
        &self,
        mesh: &TriMesh,
        extra: &[f64],
        slots: &[usize],
        free: usize,
    ) -> Result<Amg<c64>, LineFieldError> {
        if let Some(graph) = self.graph.as_ref().filter(|_| free == self.len()) {
            // Every vertex free: the unknowns are the vertices (see `design`).
            debug_assert!(slots.iter().enumerate().all(|(v, &s)| v == s));
            let (diagonal, edges) = (&self.diagonal, &self.edges);
            return Ok(graph.hierarchy(
                |v| c64::new(diagonal[v] + extra[v], 0.0),
                |e, larger| {
                    let term = &edges[e];
                    let c = -term.rotation * term.weight;
                    if larger { c } else { c.conj() }
                },
                mesh,
            )?);
        }
        let lower = self.lower_triplets(mesh, extra, slots, free);
        Ok(Amg::new(
            hermitian_csr(free, &lower),
            None,
            &AmgOptions::default(),
        )?)
    }

    /// The multigrid hierarchy that preconditions the eigen-iteration of the whole
    /// mesh's `A + diag(extra)` (see `eigenpair.rs`), and whether it is that system's
    /// own (the one [`hierarchy`](Self::hierarchy) makes). Where every weight is at
    /// least [`MIN_EDGE_WEIGHT`] it is; where the paper's weights are negative across
    /// obtuse corners it is the hierarchy of the same system with the weights floored
    /// at [`MIN_EDGE_WEIGHT`]. A preconditioner need only be positive definite and
    /// close: the iteration applies the true `A`, so its result is the true system's,
    /// while the floored system's couplings all carry the connection's own phase,
    /// which the aggregation's near-null vector and the Gauss-Seidel smoother assume.
    pub(crate) fn preconditioner(
        &self,
        mesh: &TriMesh,
        extra: &[f64],
    ) -> Result<(Amg<c64>, bool), LineFieldError> {
        let n = self.len();
        let identity: Vec<usize> = (0..n).collect();
        let exact = self.edges.iter().all(|e| e.weight >= MIN_EDGE_WEIGHT);
        let Some(graph) = self.graph.as_ref().filter(|_| !exact) else {
            return Ok((self.hierarchy(mesh, extra, &identity, n)?, true));
        };
        let mut diagonal = extra.to_vec();
        for e in &self.edges {
            let w = e.weight.max(MIN_EDGE_WEIGHT);
            diagonal[e.a] += w;
            diagonal[e.b] += w;
        }
        let edges = &self.edges;
        let amg = graph.hierarchy(
            |v| c64::new(diagonal[v], 0.0),
            |e, larger| {
                let term = &edges[e];
                let c = -term.rotation * term.weight.max(MIN_EDGE_WEIGHT);
                if larger { c } else { c.conj() }
            },
            mesh,
        )?;
        Ok((amg, false))
    }

    /// The lower triangle of `A + diag(extra)` on the unknowns of `slots`.
    fn lower_triplets(
        &self,
        mesh: &TriMesh,
        extra: &[f64],
        slots: &[usize],
        free: usize,
    ) -> Vec<Triplet<usize, usize, c64>> {
        let diagonal = |v: usize| c64::new(self.diagonal[v] + extra[v], 0.0);
        triplets(mesh, slots, free, diagonal, |e, b_below| {
            let term = &self.edges[e];
            let c = -term.rotation * term.weight;
            if b_below { c } else { c.conj() }
        })
    }

    /// Solves `(A + diag(extra)) z = rhs` on the whole mesh by conjugate gradients
    /// preconditioned with `amg`, the hierarchy of `A + shift M` (see
    /// [`pcg::solve_with_diagonal`]); `None` where it fails or runs out of iterations
    /// (the caller then builds a hierarchy of its own).
    pub(crate) fn solve_with_hierarchy(
        &self,
        amg: &Amg<c64>,
        shift: f64,
        extra: &[f64],
        rhs: &[c64],
    ) -> Option<Vec<c64>> {
        let delta: Vec<f64> = extra
            .iter()
            .zip(&self.mass)
            .map(|(d, m)| d - shift * m)
            .collect();
        let mut z = vec![c64::new(0.0, 0.0); rhs.len()];
        let solved = pcg::solve_with_diagonal(
            amg,
            &delta,
            rhs,
            &mut z,
            SOLVE_TOLERANCE,
            REUSE_MAX_ITERATIONS,
        );
        (solved.is_ok() && z.iter().all(|v| v.is_finite())).then_some(z)
    }

    /// Keeps `factor`'s buffers for the next [`factor`](Self::factor).
    pub(crate) fn recycle(&self, factor: Factor) {
        if let Factor::Direct(llt) = factor {
            *self.spare.borrow_mut() = Some(llt.into_storage());
        }
    }

    /// `E(z) = sum_edges w |z_b - r z_a|^2`.
    pub(crate) fn energy(&self, z: &[c64]) -> f64 {
        self.edges
            .iter()
            .map(|e| e.weight * (z[e.b] - e.rotation * z[e.a]).norm_sqr())
            .sum()
    }

    /// `A z`.
    pub(crate) fn apply(&self, z: &[c64]) -> Vec<c64> {
        let mut out = vec![c64::new(0.0, 0.0); z.len()];
        for e in &self.edges {
            let d = z[e.b] - e.rotation * z[e.a];
            out[e.b] += d * e.weight;
            out[e.a] -= e.rotation.conj() * d * e.weight;
        }
        out
    }

    /// `z^H M z`.
    pub(crate) fn mass_norm2(&self, z: &[c64]) -> f64 {
        self.mass.iter().zip(z).map(|(m, z)| m * z.norm_sqr()).sum()
    }

    /// The line field of the doubled-angle values `z` in the vertex frames.
    pub(crate) fn output(&self, z: &[c64], iterations: usize) -> LineField {
        let (directions, magnitudes) = z
            .iter()
            .enumerate()
            .map(|(v, z)| (self.frames.direction(v, *z), z.norm()))
            .unzip();
        let energy = self.energy(z);
        let norm2 = self.mass_norm2(z);
        LineField {
            directions,
            magnitudes,
            energy,
            rayleigh: if norm2 > 0.0 { energy / norm2 } else { 0.0 },
            iterations,
        }
    }
}

/// Per edge the term `w |z_b - r z_a|^2` in `frames`, and per face the doubled
/// holonomy where the frames are intrinsic. Intrinsic: `r = e^(2 i rho)` with the
/// transport angle `rho` of [`TangentSpaces::transport`]. Planes: `e^(i psi)` at both
/// ends by arithmetic rather than angles, the rotation `(u_b conj(u_a))^2` (the doubled
/// angle difference of the edge projected into the two planes).
fn edge_terms(
    mesh: &TriMesh,
    frames: &Frames,
    weights: impl IntoIterator<Item = f64>,
) -> (Vec<EdgeTerm>, Option<Vec<f64>>) {
    let pos = mesh.positions();
    let weights: Vec<f64> = weights.into_iter().collect();
    let term = |e: usize, [a, b]: [u32; 2], weight: f64| {
        let (a, b) = (a as usize, b as usize);
        let rotation = match frames {
            Frames::Intrinsic(spaces) => {
                let (s, c) = (2.0 * spaces.transport(e)).sin_cos();
                c64::new(c, s)
            }
            Frames::Planes(planes) => {
                let d = pos[b] - pos[a];
                let r = unit_direction(d, planes[b]) * unit_direction(d, planes[a]).conj();
                r * r
            }
        };
        EdgeTerm {
            a,
            b,
            weight,
            rotation,
        }
    };
    let edges = mesh
        .edges()
        .par_iter()
        .zip(&weights)
        .enumerate()
        .map(|(e, (&ab, &weight))| term(e, ab, weight))
        .collect();
    let holonomy = match frames {
        Frames::Intrinsic(spaces) => Some(spaces.face_holonomy().iter().map(|h| 2.0 * h).collect()),
        Frames::Planes(_) => None,
    };
    (edges, holonomy)
}

/// Solves in place with `llt`, checking the result is finite.
fn solve(llt: &mut Cholesky<c64>, z: &mut [c64]) -> Result<(), LineFieldError> {
    let n = z.len();
    llt.solve(MatMut::from_column_major_slice_mut(z, n, 1))?;
    if z.iter().all(|v| v.re.is_finite() && v.im.is_finite()) {
        Ok(())
    } else {
        Err(LineFieldError::Factorization {
            stage: "solve (non-finite solution)",
        })
    }
}
