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
//! - Guided field ([`guided_line_field`]): given a guidance `q` (direction and
//!   confidence per vertex) and a weight, one solve of `(A + w M) z = w M q`, the
//!   minimiser of `E(z) + w |z - q|_M^2`. Weight 0 gives the smoothest field.
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

use super::{FieldError, TensorField, frame_angle, vertex_frames};
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

/// A line field: per vertex, a unit tangent direction (world space; its negation is the
/// same line) and the magnitude `|z_v|` of the solution.
#[derive(Clone, Debug, PartialEq)]
pub struct LineField {
    /// Unit direction per vertex, in the vertex's tangent plane (the first axis of the
    /// tangent frame where the magnitude is 0).
    pub directions: Vec<DVec3>,
    /// `|z_v|` per vertex: for the smoothest field with `sum_v m_v |z_v|^2 = 1`; for a
    /// guided field in the guidance's units (small where guidance is weak or
    /// contradictory).
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
    fn build(mesh: &TriMesh) -> Result<Self, LineFieldError> {
        let n = mesh.vertex_count();
        if n == 0 {
            return Err(LineFieldError::EmptyMesh);
        }
        let pos = mesh.positions();
        let frames = vertex_frames(mesh);
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
        let mut diagonal = vec![0.0; n];
        let edges: Vec<EdgeTerm> = mesh
            .edges()
            .iter()
            .zip(&cotan)
            .map(|(&[a, b], &c)| {
                let (a, b) = (a as usize, b as usize);
                let d = pos[b] - pos[a];
                let psi = |v: usize| frame_angle(d, frames[v]);
                let (s, c2) = (2.0 * (psi(b) - psi(a))).sin_cos();
                let weight = if c.is_finite() {
                    c.max(MIN_EDGE_WEIGHT)
                } else {
                    MIN_EDGE_WEIGHT
                };
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
        let n = self.len();
        let mut triplets = Vec::with_capacity(2 * n + 4 * self.edges.len());
        for v in 0..n {
            let d = self.diagonal[v] + shift * self.mass[v];
            triplets.push(Triplet::new(2 * v, 2 * v, d));
            triplets.push(Triplet::new(2 * v + 1, 2 * v + 1, d));
        }
        for e in &self.edges {
            // Entry (b, a) of A is c = -w r_ab = p + i q; entry (a, b) is its conjugate.
            let (p, q) = (-e.weight * e.rotation[0], -e.weight * e.rotation[1]);
            let (row, col, q) = if e.b > e.a {
                (e.b, e.a, q)
            } else {
                (e.a, e.b, -q)
            };
            triplets.push(Triplet::new(2 * row, 2 * col, p));
            triplets.push(Triplet::new(2 * row, 2 * col + 1, -q));
            triplets.push(Triplet::new(2 * row + 1, 2 * col, q));
            triplets.push(Triplet::new(2 * row + 1, 2 * col + 1, p));
        }
        SparseColMat::try_new_from_triplets(2 * n, 2 * n, &triplets)
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
    fn apply_mass(&self, x: &Mat<f64>, scale: f64) -> Mat<f64> {
        Mat::from_fn(2 * self.len(), 1, |r, _| {
            scale * self.mass[r / 2] * x[(r, 0)]
        })
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
    let n = x.nrows();
    if (0..n).all(|r| x[(r, 0)].is_finite()) {
        Ok(())
    } else {
        Err(LineFieldError::Factorization {
            stage: "solve (non-finite solution)",
        })
    }
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
    let system = System::build(mesh)?;
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
        let mut y = system.apply_mass(&x, 1.0);
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
/// `E(z) + w |z - q|_M^2`, `w = options.weight / area`, one solve of
/// `(A + w M) z = w M q`. Each guidance vector is projected into its vertex's tangent
/// plane; its direction gives the line (its sign does not matter) and its length the
/// confidence `|q_v|` (a zero vector: no guidance there). A weight of 0 gives
/// [`smoothest_line_field`].
///
/// Errors: invalid options, an empty mesh, a guidance of the wrong length or with a
/// non-finite vector, a failed factorization.
pub fn guided_line_field(
    mesh: &TriMesh,
    guidance: &[DVec3],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    if guidance.len() != mesh.vertex_count() {
        return Err(LineFieldError::GuidanceLength {
            expected: mesh.vertex_count(),
            found: guidance.len(),
        });
    }
    if let Some(vertex) = guidance.iter().position(|d| !d.is_finite()) {
        return Err(LineFieldError::NonFiniteGuidance { vertex });
    }
    if options.weight == 0.0 {
        return smoothest_line_field(mesh, options);
    }
    let system = System::build(mesh)?;
    let w = options.weight / system.mass.iter().sum::<f64>();
    let llt = factor(&system.matrix(w)?)?;
    let q = guidance_values(mesh, &system, guidance);
    let mut x = system.apply_mass(&q, w);
    llt.solve_in_place(x.as_mut());
    check_finite(&x)?;
    Ok(system.output(&x, 0))
}

/// The guidance as doubled-angle complex numbers in the vertex frames, real form:
/// `t = |t| (cos phi e1 + sin phi e2)` becomes `|t| e^(2 i phi)`.
fn guidance_values(mesh: &TriMesh, system: &System, guidance: &[DVec3]) -> Mat<f64> {
    let mut q = Mat::zeros(2 * system.len(), 1);
    for (v, (d, nv)) in guidance.iter().zip(mesh.vertex_normals()).enumerate() {
        let t = *d - *nv * d.dot(*nv);
        let (e1, e2) = system.frames[v];
        let (c, s) = (t.dot(e1), t.dot(e2));
        let len = c.hypot(s);
        if len > 0.0 {
            q[(2 * v, 0)] = (c * c - s * s) / len;
            q[(2 * v + 1, 0)] = 2.0 * c * s / len;
        }
    }
    q
}

#[cfg(test)]
#[path = "design_tests.rs"]
mod tests;
