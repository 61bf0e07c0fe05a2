//! Field design: smooth line fields (2-direction fields) on vertex tangent planes with
//! few singularities, after Knöppel, Crane, Pinkall and Schröder, "Globally optimal
//! direction fields" (SIGGRAPH 2013).
//!
//! # Representation
//! Each vertex `v` has the tangent frame `(e1, e2)` of [`tangent_frame`](super::tangent_frame) of its vertex
//! normal. A line field is a complex number per vertex, `z_v = r_v e^(2 i theta_v)`, in
//! that frame: the doubled angle makes `theta` and `theta + pi` the same line, so no sign
//! has to be chosen anywhere.
//!
//! # Connection and energy
//! Along edge `a -> b` with direction `d`, let `psi_v` be the angle of `d` projected into
//! the tangent plane of `v`, in `v`'s frame (the discrete Levi-Civita connection of the
//! paper: transport keeps the angle to the edge). A line at doubled angle `alpha` at `a`
//! arrives at `b` as `alpha + 2 (psi_b - psi_a)`, i.e. multiplied by
//! `r_ab = e^(2 i (psi_b - psi_a))`. This is the same connection as the singularity
//! detector's ([`line_field_transport`](crate::segment::line_field_transport)), so a
//! field that is smooth here turns little there. The energy is
//!
//! `E(z) = sum_edges w_ab |z_b - r_ab z_a|^2 = z^H A z`,
//!
//! with `A` Hermitian positive semi-definite. The weights are the cotangent weights
//! `w_ab = (cot alpha + cot beta) / 2` of the two opposite corners, clamped from below at
//! [`MIN_EDGE_WEIGHT`] (cotangents are negative at obtuse corners, and a negative weight
//! would break positivity; the floor also keeps every edge coupled). The mass `M` is
//! lumped: a third of the adjacent face areas per vertex.
//!
//! # Solves
//! The complex Hermitian `n x n` system is written as a real symmetric `2n x 2n` one
//! (`x + i y` becomes `(x, y)`, the entry `p + i q` the block `[[p, -q], [q, p]]`) and
//! factored by a sparse Cholesky (faer, sequential).
//! - Smoothest field ([`smoothest_line_field`]): the eigenvector of the smallest
//!   eigenvalue of `A z = lambda M z`, by inverse power iteration with one factorization
//!   of `A + sigma M` (`sigma` = [`SHIFT`] times the ratio of the traces of `A` and `M`),
//!   from a fixed pseudo-random start, `M`-normalised each step, until the Rayleigh
//!   quotient settles or the iteration budget is spent.
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
//!
//! Input: a [`TriMesh`] (and a guidance per vertex). Output: a [`LineField`], a unit
//! world-space direction and a magnitude per vertex, which [`LineField::to_tensor_field`]
//! turns into a [`TensorField`]. Cost: O(V + E) assembly, one sparse Cholesky of a
//! `2V x 2V` matrix, and one solve with that factor per iteration (not yet timed on
//! large meshes).
//! Deterministic: fixed iteration order, sequential solves, fixed start vector.

use faer::Mat;
use faer::Side;
use faer::prelude::*;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use glam::DVec3;

use super::{FieldError, TensorField, frame_angle, tangent_frame, vertex_frames};
use crate::mesh::TriMesh;

/// Floor of the cotangent edge weights (dimensionless).
pub const MIN_EDGE_WEIGHT: f64 = 1e-3;

/// Relative shift of the inverse power iteration: `sigma = SHIFT * tr(A) / tr(M)`.
pub const SHIFT: f64 = 1e-8;

/// Settings of the line-field solvers.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct LineFieldOptions {
    /// Weight of the guidance against smoothness ([`guided_line_field`] only). It is
    /// divided by the mesh area, `w = weight / area`, so that it is dimensionless (the
    /// Dirichlet energy of a field is scale-invariant on a surface, the guidance term
    /// `w |z - q|_M^2` scales with area). Range `[0, inf)`, 0 meaning the smoothest field;
    /// default 10.
    pub weight: f64,
    /// Length over which the surface's normals are smoothed before they define the
    /// connection, as a fraction of the mesh's area radius `R = sqrt(area / 4 pi)`:
    /// bumps smaller than about `smoothing R` then create no singularities (see
    /// [`smoothed_normals`]). Range `[0, inf)`, 0 using the mesh's own normals;
    /// default 0.
    pub smoothing: f64,
    /// Most inverse power iterations of the smoothest field. Range `[1, inf)`; default 200.
    pub iterations: usize,
    /// The iteration stops when the Rayleigh quotient changes by at most `tolerance`
    /// times its value (or the shift, whichever is larger). Range `(0, inf)`; default 1e-12.
    pub tolerance: f64,
}

impl Default for LineFieldOptions {
    fn default() -> Self {
        Self {
            weight: 10.0,
            smoothing: 0.0,
            iterations: 200,
            tolerance: 1e-12,
        }
    }
}

impl LineFieldOptions {
    /// Checks every setting against its documented range.
    pub fn validate(&self) -> Result<(), LineFieldError> {
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "weight",
                value: self.weight,
                expected: "finite and >= 0",
            });
        }
        if !(self.smoothing.is_finite() && self.smoothing >= 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "smoothing",
                value: self.smoothing,
                expected: "finite and >= 0",
            });
        }
        if self.iterations == 0 {
            return Err(LineFieldError::InvalidOption {
                option: "iterations",
                value: 0.0,
                expected: ">= 1",
            });
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "tolerance",
                value: self.tolerance,
                expected: "finite and > 0",
            });
        }
        Ok(())
    }
}

/// Everything that can go wrong designing a line field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LineFieldError {
    /// The mesh has no vertices or no area.
    #[error("the mesh has no vertices or zero area")]
    EmptyMesh,
    /// The guidance has a different length from the mesh's vertex count.
    #[error("guidance has {found} values but the mesh has {expected} vertices")]
    GuidanceLength {
        /// Mesh vertex count.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A guidance vector has a NaN or infinite coordinate.
    #[error("guidance at vertex {vertex} is not finite")]
    NonFiniteGuidance {
        /// Vertex index.
        vertex: usize,
    },
    /// A constraint names a vertex the mesh does not have.
    #[error("constraint {index} names vertex {vertex}, but the mesh has {vertices} vertices")]
    ConstraintVertex {
        /// Position of the constraint in the list.
        index: usize,
        /// The vertex it names.
        vertex: u32,
        /// Mesh vertex count.
        vertices: usize,
    },
    /// A constraint's direction is not finite or has no part in the tangent plane.
    #[error(
        "constraint {index} at vertex {vertex}: the direction is not finite or is normal to the surface"
    )]
    ConstraintDirection {
        /// Position of the constraint in the list.
        index: usize,
        /// Its vertex.
        vertex: u32,
    },
    /// Two constraints fix the same vertex.
    #[error("constraints {first} and {second} both fix vertex {vertex}")]
    DuplicateConstraint {
        /// The earlier constraint.
        first: usize,
        /// The later one.
        second: usize,
        /// The vertex both fix.
        vertex: u32,
    },
    /// A setting is out of its range.
    #[error("line-field option `{option}` = {value} is invalid: {expected}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// The sparse solve failed.
    #[error("line-field solve failed in the {stage}")]
    Factorization {
        /// The step that failed.
        stage: &'static str,
    },
}

/// A hard constraint of [`constrained_line_field`]: the field's line at `vertex` is
/// exactly `direction`'s (projected into the vertex's tangent plane; its sign does not
/// matter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineConstraint {
    /// Mesh vertex index.
    pub vertex: u32,
    /// World-space direction, not parallel to the vertex normal.
    pub direction: DVec3,
}

/// A line field: per vertex, a unit tangent direction (world space; its negation is the
/// same line) and the magnitude `|z_v|` of the solution.
#[derive(Clone, Debug, PartialEq)]
pub struct LineField {
    /// Unit direction per vertex, in the vertex's tangent plane (the first axis of the
    /// tangent frame where the magnitude is 0).
    pub directions: Vec<DVec3>,
    /// `|z_v|` per vertex: for the smoothest field with `sum_v m_v |z_v|^2 = 1`; for a
    /// guided field about 1 where it follows confident guidance or a constraint, smaller
    /// where guidance is contradictory (near singularities).
    pub magnitudes: Vec<f64>,
    /// The smoothness energy `E(z) = z^H A z` of the solution.
    pub energy: f64,
    /// The Rayleigh quotient `E(z) / (z^H M z)` (0 for a zero field); for the smoothest
    /// field, the estimate of the smallest eigenvalue.
    pub rayleigh: f64,
    /// Inverse power iterations done (0 for a guided field).
    pub iterations: usize,
}

impl LineField {
    /// A tensor field whose major direction is this field's, with the per-vertex
    /// eigenvalues `[l1, l2]` (`l1 >= l2 > 0`; see [`TensorField::from_frames`]).
    pub fn to_tensor_field(
        &self,
        mesh: &TriMesh,
        eigenvalues: &[[f64; 2]],
    ) -> Result<TensorField, FieldError> {
        TensorField::from_frames(mesh, &self.directions, eigenvalues)
    }
}

/// One edge of the energy: `w |z_b - r z_a|^2`.
#[derive(Clone, Copy, Debug)]
struct EdgeTerm {
    a: usize,
    b: usize,
    weight: f64,
    /// `r_ab` as `(re, im)`.
    rotation: [f64; 2],
}

/// The discretised energy and mass of a mesh.
struct System {
    frames: Vec<(DVec3, DVec3)>,
    edges: Vec<EdgeTerm>,
    /// Per vertex, the diagonal `sum w` of `A`.
    diagonal: Vec<f64>,
    /// Per vertex, the lumped mass.
    mass: Vec<f64>,
}

impl System {
    /// The system of `mesh`, with its connection measured in the tangent planes of the
    /// normals smoothed over `smoothing` (a length; 0 keeps the mesh's own normals).
    fn build(mesh: &TriMesh, smoothing: f64) -> Result<Self, LineFieldError> {
        let n = mesh.vertex_count();
        if n == 0 {
            return Err(LineFieldError::EmptyMesh);
        }
        let pos = mesh.positions();
        let mut mass = vec![0.0; n];
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
        if !(mass.iter().sum::<f64>() > 0.0) {
            return Err(LineFieldError::EmptyMesh);
        }
        let weights: Vec<f64> = cotan
            .iter()
            .map(|&c| {
                if c.is_finite() {
                    c.max(MIN_EDGE_WEIGHT)
                } else {
                    MIN_EDGE_WEIGHT
                }
            })
            .collect();
        let frames: Vec<(DVec3, DVec3)> = if smoothing > 0.0 {
            smoothed_normals(mesh, &weights, &mass, smoothing)?
                .into_iter()
                .map(tangent_frame)
                .collect()
        } else {
            vertex_frames(mesh)
        };
        let mut diagonal = vec![0.0; n];
        let edges: Vec<EdgeTerm> = mesh
            .edges()
            .iter()
            .zip(&weights)
            .map(|(&[a, b], &weight)| {
                let (a, b) = (a as usize, b as usize);
                let d = pos[b] - pos[a];
                let psi = |v: usize| frame_angle(d, frames[v]);
                let (s, c2) = (2.0 * (psi(b) - psi(a))).sin_cos();
                diagonal[a] += weight;
                diagonal[b] += weight;
                EdgeTerm {
                    a,
                    b,
                    weight,
                    rotation: [c2, s],
                }
            })
            .collect();
        Ok(Self {
            frames,
            edges,
            diagonal,
            mass,
        })
    }

    fn len(&self) -> usize {
        self.mass.len()
    }

    /// The lower triangle of the real form of `A + shift M`.
    fn matrix(&self, shift: f64) -> Result<SparseColMat<usize, f64>, LineFieldError> {
        let extra: Vec<f64> = self.mass.iter().map(|m| shift * m).collect();
        let slots: Vec<usize> = (0..self.len()).collect();
        self.reduced_matrix(&extra, &slots, self.len())
    }

    /// The lower triangle of the real form of `A + diag(extra)` restricted to the
    /// vertices with `slots[v] < free` (vertex `v` becomes unknown `slots[v]`).
    fn reduced_matrix(
        &self,
        extra: &[f64],
        slots: &[usize],
        free: usize,
    ) -> Result<SparseColMat<usize, f64>, LineFieldError> {
        let mut triplets = Vec::with_capacity(2 * free + 4 * self.edges.len());
        for (v, &i) in slots.iter().enumerate() {
            if i < free {
                let d = self.diagonal[v] + extra[v];
                triplets.push(Triplet::new(2 * i, 2 * i, d));
                triplets.push(Triplet::new(2 * i + 1, 2 * i + 1, d));
            }
        }
        for e in &self.edges {
            let (sa, sb) = (slots[e.a], slots[e.b]);
            if sa >= free || sb >= free {
                continue;
            }
            // Entry (b, a) of A is c = -w r_ab = p + i q; entry (a, b) is its conjugate.
            let (p, q) = (-e.weight * e.rotation[0], -e.weight * e.rotation[1]);
            let (row, col, q) = if sb > sa { (sb, sa, q) } else { (sa, sb, -q) };
            triplets.push(Triplet::new(2 * row, 2 * col, p));
            triplets.push(Triplet::new(2 * row, 2 * col + 1, -q));
            triplets.push(Triplet::new(2 * row + 1, 2 * col, q));
            triplets.push(Triplet::new(2 * row + 1, 2 * col + 1, p));
        }
        SparseColMat::try_new_from_triplets(2 * free, 2 * free, &triplets)
            .map_err(|_| LineFieldError::Factorization { stage: "assembly" })
    }

    /// `E(z)` for `z` in real form (`z_v = x[2v] + i x[2v + 1]`).
    fn energy(&self, x: &Mat<f64>) -> f64 {
        self.edges
            .iter()
            .map(|e| {
                let (za, zb) = (
                    [x[(2 * e.a, 0)], x[(2 * e.a + 1, 0)]],
                    [x[(2 * e.b, 0)], x[(2 * e.b + 1, 0)]],
                );
                let [c, s] = e.rotation;
                let re = zb[0] - (c * za[0] - s * za[1]);
                let im = zb[1] - (s * za[0] + c * za[1]);
                e.weight * (re * re + im * im)
            })
            .sum()
    }

    /// `z^H M z`.
    fn mass_norm2(&self, x: &Mat<f64>) -> f64 {
        self.mass
            .iter()
            .enumerate()
            .map(|(v, m)| m * (x[(2 * v, 0)].powi(2) + x[(2 * v + 1, 0)].powi(2)))
            .sum()
    }

    /// `M x`.
    fn apply_mass(&self, x: &Mat<f64>) -> Mat<f64> {
        Mat::from_fn(2 * self.len(), 1, |r, _| self.mass[r / 2] * x[(r, 0)])
    }

    fn output(&self, x: &Mat<f64>, iterations: usize) -> LineField {
        let (directions, magnitudes) = (0..self.len())
            .map(|v| {
                let (re, im) = (x[(2 * v, 0)], x[(2 * v + 1, 0)]);
                let (s, c) = (0.5 * im.atan2(re)).sin_cos();
                let (e1, e2) = self.frames[v];
                (e1 * c + e2 * s, re.hypot(im))
            })
            .unzip();
        let energy = self.energy(x);
        let norm2 = self.mass_norm2(x);
        LineField {
            directions,
            magnitudes,
            energy,
            rayleigh: if norm2 > 0.0 { energy / norm2 } else { 0.0 },
            iterations,
        }
    }
}

/// The vertex normals after one implicit heat step of time `length^2`,
/// `(M + length^2 L) N = M N0` with the (clamped) cotangent Laplacian `L`, normalised:
/// details of the surface smaller than about `length` no longer turn the normals, and
/// so no longer turn the connection (Ray, Vallet, Alonso and Lévy 2009 make fields
/// ignore small geometric details the same way). One sparse Cholesky, three columns.
fn smoothed_normals(
    mesh: &TriMesh,
    weights: &[f64],
    mass: &[f64],
    length: f64,
) -> Result<Vec<DVec3>, LineFieldError> {
    let t = length * length;
    let n = mesh.vertex_count();
    let mut triplets = Vec::with_capacity(n + mesh.edge_count());
    let mut diagonal: Vec<f64> = mass.to_vec();
    for (&[a, b], &w) in mesh.edges().iter().zip(weights) {
        let (a, b) = (a as usize, b as usize);
        diagonal[a] += t * w;
        diagonal[b] += t * w;
        triplets.push(Triplet::new(a.max(b), a.min(b), -t * w));
    }
    triplets.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(v, &d)| Triplet::new(v, v, d)),
    );
    let matrix = SparseColMat::try_new_from_triplets(n, n, &triplets)
        .map_err(|_| LineFieldError::Factorization { stage: "assembly" })?;
    let normals = mesh.vertex_normals();
    let mut rhs = Mat::from_fn(n, 3, |v, k| mass[v] * normals[v][k]);
    factor(&matrix)?.solve_in_place(rhs.as_mut());
    check_finite(&rhs)?;
    Ok((0..n)
        .map(|v| {
            let smooth = DVec3::new(rhs[(v, 0)], rhs[(v, 1)], rhs[(v, 2)]);
            // Where opposite normals cancel (a thin sheet) keep the mesh's own.
            smooth.try_normalize().unwrap_or(normals[v])
        })
        .collect())
}

/// Sparse Cholesky of `matrix` (lower triangle), sequential.
fn factor(matrix: &SparseColMat<usize, f64>) -> Result<Llt<usize, f64>, LineFieldError> {
    let symbolic = SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).map_err(|_| {
        LineFieldError::Factorization {
            stage: "symbolic factorization",
        }
    })?;
    Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower).map_err(|_| {
        LineFieldError::Factorization {
            stage: "numeric factorization (matrix not positive definite)",
        }
    })
}

fn check_finite(x: &Mat<f64>) -> Result<(), LineFieldError> {
    if (0..x.ncols()).all(|c| (0..x.nrows()).all(|r| x[(r, c)].is_finite())) {
        Ok(())
    } else {
        Err(LineFieldError::Factorization {
            stage: "solve (non-finite solution)",
        })
    }
}

/// `sqrt(area / 4 pi)`: the radius of the sphere with the mesh's area.
fn area_radius(mesh: &TriMesh) -> f64 {
    (mesh.area() / (4.0 * std::f64::consts::PI)).sqrt()
}

/// A fixed pseudo-random value in `[-1, 1)` for index `i` (SplitMix64 finaliser).
fn start_value(i: u64) -> f64 {
    let mut z = i.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// The smoothest line field of `mesh`: the eigenvector of the smallest eigenvalue of
/// `A z = lambda M z` (see the [module docs](self)), by inverse power iteration.
/// `options.weight` is not used.
///
/// Errors: invalid options, an empty mesh, a failed factorization.
pub fn smoothest_line_field(
    mesh: &TriMesh,
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    let system = System::build(mesh, options.smoothing * area_radius(mesh))?;
    let n = system.len();
    let trace_a: f64 = system.diagonal.iter().sum();
    let trace_m: f64 = system.mass.iter().sum();
    let shift = SHIFT * trace_a / trace_m;
    let llt = factor(&system.matrix(shift)?)?;

    let mut x = Mat::from_fn(2 * n, 1, |r, _| start_value(r as u64));
    x *= Scale(1.0 / system.mass_norm2(&x).sqrt());
    let mut previous = f64::INFINITY;
    let mut iterations = 0;
    for _ in 0..options.iterations {
        let mut y = system.apply_mass(&x);
        llt.solve_in_place(y.as_mut());
        check_finite(&y)?;
        let norm2 = system.mass_norm2(&y);
        if !(norm2 > 0.0 && norm2.is_finite()) {
            return Err(LineFieldError::Factorization {
                stage: "solve (zero iterate)",
            });
        }
        y *= Scale(1.0 / norm2.sqrt());
        x = y;
        iterations += 1;
        let rayleigh = system.energy(&x);
        let settled = (rayleigh - previous).abs() <= options.tolerance * rayleigh.abs().max(shift);
        previous = rayleigh;
        if settled {
            break;
        }
    }
    Ok(system.output(&x, iterations))
}

/// The line field that balances smoothness against `guidance`: the minimiser of
/// `E(z) + w sum_v m_v c_v |z_v - u_v|^2`, `w = options.weight / area` (see the
/// [module docs](self)). Each guidance vector is projected into its vertex's tangent
/// plane; its direction gives the line `u_v` (its sign does not matter) and its length
/// the confidence `c_v` (a zero vector: no guidance there, the field follows its
/// neighbours). A weight of 0, or no guidance anywhere, gives
/// [`smoothest_line_field`].
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
    options.validate()?;
    let n = mesh.vertex_count();
    if !guidance.is_empty() && guidance.len() != n {
        return Err(LineFieldError::GuidanceLength {
            expected: n,
            found: guidance.len(),
        });
    }
    if let Some(vertex) = guidance.iter().position(|d| !d.is_finite()) {
        return Err(LineFieldError::NonFiniteGuidance { vertex });
    }
    let system = System::build(mesh, options.smoothing * area_radius(mesh))?;
    let fixed = fixed_values(mesh, &system, constraints)?;
    let q = if options.weight > 0.0 && !guidance.is_empty() {
        guidance_lines(mesh, &system, guidance)
    } else {
        vec![None; n]
    };
    if constraints.is_empty() && q.iter().all(Option::is_none) {
        return smoothest_line_field(mesh, options);
    }

    // Unknowns: the free vertices in index order, then the fixed ones (slots >= free).
    let mut slots = vec![0; n];
    let mut free = 0;
    for v in 0..n {
        if fixed[v].is_none() {
            slots[v] = free;
            free += 1;
        }
    }
    let mut next = free;
    for v in 0..n {
        if fixed[v].is_some() {
            slots[v] = next;
            next += 1;
        }
    }
    let area: f64 = system.mass.iter().sum();
    let w = options.weight / area;
    // Only a connected component with no guidance and no constraint leaves the system
    // singular (its field is free up to a rotation); the shift pins it to zero there and
    // leaves every other component exact.
    let shift = SHIFT * system.diagonal.iter().sum::<f64>() / area;
    let component = |v: usize| mesh.face_components()[mesh.vertex_faces(v as u32)[0] as usize];
    let mut pinned = vec![false; mesh.component_count()];
    for v in 0..n {
        if fixed[v].is_some() || q[v].is_some() {
            pinned[component(v) as usize] = true;
        }
    }
    let mut extra = vec![0.0; n];
    let mut rhs = Mat::zeros(2 * free, 1);
    for v in 0..n {
        let mut d = if pinned[component(v) as usize] {
            0.0
        } else {
            shift * system.mass[v]
        };
        if let Some((c, [ur, ui])) = q[v] {
            let k = w * system.mass[v] * c;
            d += k;
            if fixed[v].is_none() {
                rhs[(2 * slots[v], 0)] += k * ur;
                rhs[(2 * slots[v] + 1, 0)] += k * ui;
            }
        }
        extra[v] = d;
    }
    // Edges with one fixed end: their coupling moves to the right-hand side.
    for e in &system.edges {
        let [c, s] = e.rotation;
        match (fixed[e.a], fixed[e.b]) {
            (Some([xr, xi]), None) => {
                // rhs_b += w r z_a
                let i = slots[e.b];
                rhs[(2 * i, 0)] += e.weight * (c * xr - s * xi);
                rhs[(2 * i + 1, 0)] += e.weight * (s * xr + c * xi);
            }
            (None, Some([xr, xi])) => {
                // rhs_a += w conj(r) z_b
                let i = slots[e.a];
                rhs[(2 * i, 0)] += e.weight * (c * xr + s * xi);
                rhs[(2 * i + 1, 0)] += e.weight * (c * xi - s * xr);
            }
            _ => {}
        }
    }
    let mut x = Mat::zeros(2 * n, 1);
    if free > 0 {
        let llt = factor(&system.reduced_matrix(&extra, &slots, free)?)?;
        llt.solve_in_place(rhs.as_mut());
        check_finite(&rhs)?;
    }
    for v in 0..n {
        let [re, im] = match fixed[v] {
            Some(z) => z,
            None => [rhs[(2 * slots[v], 0)], rhs[(2 * slots[v] + 1, 0)]],
        };
        x[(2 * v, 0)] = re;
        x[(2 * v + 1, 0)] = im;
    }
    Ok(system.output(&x, 0))
}

/// `t` in the frame `(e1, e2)` as a unit doubled-angle complex number, with its
/// tangent length; `None` where `t` has no tangent part.
fn doubled_unit(t: DVec3, (e1, e2): (DVec3, DVec3)) -> Option<(f64, [f64; 2])> {
    let (c, s) = (t.dot(e1), t.dot(e2));
    let len2 = c * c + s * s;
    (len2 > 0.0).then(|| (len2.sqrt(), [(c * c - s * s) / len2, 2.0 * c * s / len2]))
}

/// Per vertex, the guidance's confidence and unit doubled-angle line in the vertex
/// frame; `None` where there is no guidance.
fn guidance_lines(
    mesh: &TriMesh,
    system: &System,
    guidance: &[DVec3],
) -> Vec<Option<(f64, [f64; 2])>> {
    guidance
        .iter()
        .zip(mesh.vertex_normals())
        .zip(&system.frames)
        .map(|((d, nv), frame)| doubled_unit(*d - *nv * d.dot(*nv), *frame))
        .collect()
}

/// Per vertex, the fixed unit doubled-angle value of its constraint, if any.
fn fixed_values(
    mesh: &TriMesh,
    system: &System,
    constraints: &[LineConstraint],
) -> Result<Vec<Option<[f64; 2]>>, LineFieldError> {
    let n = mesh.vertex_count();
    let mut fixed = vec![None; n];
    let mut owner = vec![usize::MAX; n];
    for (index, c) in constraints.iter().enumerate() {
        let v = c.vertex as usize;
        if v >= n {
            return Err(LineFieldError::ConstraintVertex {
                index,
                vertex: c.vertex,
                vertices: n,
            });
        }
        if owner[v] != usize::MAX {
            return Err(LineFieldError::DuplicateConstraint {
                first: owner[v],
                second: index,
                vertex: c.vertex,
            });
        }
        let nv = mesh.vertex_normals()[v];
        let d = c.direction;
        let tangent = d - nv * d.dot(nv);
        let usable = d.is_finite() && tangent.length_squared() > 1e-12 * d.length_squared();
        let Some((_, z)) = doubled_unit(tangent, system.frames[v]).filter(|_| usable) else {
            return Err(LineFieldError::ConstraintDirection {
                index,
                vertex: c.vertex,
            });
        };
        owner[v] = index;
        fixed[v] = Some(z);
    }
    Ok(fixed)
}

#[cfg(test)]
#[path = "design_tests.rs"]
mod tests;
