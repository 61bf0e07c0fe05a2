//! The designed field source ([`FieldSpec::Designed`](crate::field::FieldSpec::Designed)): a
//! smooth line field with few singularities ([`constrained_line_field`](super::solve::constrained_line_field)) for the
//! direction, and per-vertex anisotropy and density from their own sources.
//!
//! Input: a mesh and a [`Design`]. Output: a [`TensorField`] and the [`LineField`]
//! behind it. Cost: one complex sparse Cholesky of a `V x V` system (plus a real one
//! for the smoothed normals, and inverse power iterations for the smoothest field), and
//! O(V) per curvature estimate.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::line_field::{LineField, LinearSolver};
use super::pieces::constrained_line_field_with;
use super::solve::{LineConstraint, LineFieldOptions};
use crate::field::curvature::{self, CurvatureMeasure, CurvatureNormalization};
use crate::field::guidance::{curvature_guidance, direction_guidance};
use crate::field::params::{
    direction, eigenvalues, invalid, non_negative, positive,
    smoothing_iterations as smoothing_iterations_ok, spacing_ratio,
};
use crate::field::{FieldError, PrincipalCurvatures, TensorField, principal_curvatures};
use crate::mesh::TriMesh;

/// What a designed line field aligns to.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Guidance {
    /// Nothing: the smoothest line field of the surface (Knöppel et al. 2013), or, with
    /// constraints, the smoothest one through them.
    Smoothest,
    /// The direction of largest signed principal curvature, trusted in proportion to
    /// `|k1 - k2|` (see [`curvature_guidance`]): umbilic regions follow their
    /// neighbours instead of noise.
    Curvature {
        /// Rounds of one-ring smoothing of the curvature tensors before use; at most
        /// 1000. Default 2.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_smoothing_iterations")
        )]
        smoothing_iterations: u32,
    },
    /// A world direction projected into each tangent plane, trusted where it lies in
    /// the surface (see [`direction_guidance`]); unlike
    /// [`FieldSpec::Constant`](crate::field::FieldSpec::Constant) the field turns smoothly
    /// where the surface faces the direction instead of flipping.
    Direction(
        /// World direction, finite and non-zero; `Direction(x, y, z)` or
        /// `Direction((x, y, z))` in RON.
        #[cfg_attr(
            feature = "serde",
            serde(deserialize_with = "crate::field::vec3_serde::deserialize")
        )]
        [f64; 3],
    ),
}

impl Default for Guidance {
    fn default() -> Self {
        Self::Curvature {
            smoothing_iterations: curvature::DEFAULT_SMOOTHING_ITERATIONS,
        }
    }
}

/// Where a [`Constraint`] applies.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Site {
    /// A mesh vertex, by index (after the loader's repairs).
    Vertex(u32),
    /// The mesh vertex nearest to a world point: `Point(x, y, z)` or
    /// `Point((x, y, z))` in RON.
    Point(
        #[cfg_attr(
            feature = "serde",
            serde(deserialize_with = "crate::field::vec3_serde::deserialize")
        )]
        [f64; 3],
    ),
}

/// A hard constraint of a designed field: its line at `at` is exactly `direction`'s.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Constraint {
    /// The vertex.
    pub at: Site,
    /// The world direction (projected into the vertex's tangent plane; sign ignored).
    pub direction: [f64; 3],
}

/// The spacing ratio `sqrt(l1 / l2)` of a designed field.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Anisotropy {
    /// The same ratio everywhere, finite and >= 1.
    Constant(f64),
    /// `clamp((R |k1| + eps) / (R |k2| + eps), min, max)` from principal curvatures
    /// smoothed `smoothing_iterations` times (`R` the area radius, `eps` =
    /// `isotropy_curvature`): high where the surface bends one way only, 1 where it
    /// is flat or umbilic (as [`FieldSpec::Curvature`](crate::field::FieldSpec::Curvature)).
    Curvature {
        /// Smallest ratio, >= 1. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        min: f64,
        /// Largest ratio, >= `min`. Default 3.
        #[cfg_attr(feature = "serde", serde(default = "three"))]
        max: f64,
        /// `eps`, > 0. Default 0.05.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_isotropy_curvature")
        )]
        isotropy_curvature: f64,
        /// Rounds of one-ring smoothing; at most 1000. Default 2.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_smoothing_iterations")
        )]
        smoothing_iterations: u32,
    },
}

impl Default for Anisotropy {
    fn default() -> Self {
        Self::Constant(3.0)
    }
}

/// The density `sqrt(l1 l2)` of a designed field.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Density {
    /// The same density everywhere, finite and > 0.
    Constant(f64),
    /// `floor + scale * c * measure(k1, k2)`, as
    /// [`FieldSpec::Curvature`](crate::field::FieldSpec::Curvature).
    Curvature {
        /// Which curvature measure. Default RMS.
        #[cfg_attr(feature = "serde", serde(default))]
        measure: CurvatureMeasure,
        /// The factor `c`. Default the area radius.
        #[cfg_attr(feature = "serde", serde(default))]
        normalization: CurvatureNormalization,
        /// Density where flat, > 0. Default 0.2.
        #[cfg_attr(feature = "serde", serde(default = "curvature::default_floor"))]
        floor: f64,
        /// Density per unit of normalized curvature, >= 0. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        scale: f64,
        /// Rounds of one-ring smoothing; at most 1000. Default 2.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_smoothing_iterations")
        )]
        smoothing_iterations: u32,
    },
    /// The densities `sqrt(l1 l2)` of the tensors in a field file (see
    /// [`read_field_file`](crate::field::read_field_file)); its directions are not used.
    File(
        /// The field file (relative paths as for `FieldSpec::File`).
        PathBuf,
    ),
    /// Density that follows tone, for stippling: `lit` where the surface faces the
    /// light, growing to `shadow` where it turns away
    /// ([`shading_densities`](crate::field::shading_densities)).
    Shading {
        /// Direction toward the light in the mesh's coordinates, finite and non-zero.
        /// Default `(0.4, 0.8, 0.45)`, the renderer's light.
        #[cfg_attr(feature = "serde", serde(default = "default_light"))]
        light: [f64; 3],
        /// Density where the surface faces the light, > 0. Default 0.25.
        #[cfg_attr(feature = "serde", serde(default = "quarter"))]
        lit: f64,
        /// Density where it faces away, > 0. Default 4.
        #[cfg_attr(feature = "serde", serde(default = "four"))]
        shadow: f64,
        /// Exponent of the darkness `1 - max(n . l, 0)` in the blend, > 0; larger keeps
        /// the half-lit band lighter. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        exponent: f64,
    },
}

impl Default for Density {
    fn default() -> Self {
        Self::Constant(1.0)
    }
}

/// The settings of a designed field ([`FieldSpec::Designed`](crate::field::FieldSpec::Designed)).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Design {
    /// What the direction aligns to. Default curvature.
    pub guidance: Guidance,
    /// Weight of the guidance against smoothness, >= 0 (0: the smoothest field, larger:
    /// closer to the guidance; see [`LineFieldOptions::weight`]). Default 1.
    pub weight: f64,
    /// Shift toward the smoothest field, in `[0, 0.95]` (see
    /// [`LineFieldOptions::smoothness`]). Default 0.5.
    pub smoothness: f64,
    /// Length over which the surface is smoothed for the field's connection, as a
    /// fraction of the area radius (of each connected piece, solved on its own), >= 0 (see [`LineFieldOptions::smoothing`]).
    /// Default 0.3.
    pub smoothing: f64,
    /// Hard constraints (for example strokes along feature lines). Default none.
    pub constraints: Vec<Constraint>,
    /// Spacing ratio. Default `Constant(3.0)`.
    pub anisotropy: Anisotropy,
    /// Density. Default `Constant(1.0)`.
    pub density: Density,
    /// How the sparse systems are solved (see [`LinearSolver`]): `Auto` (default),
    /// `Direct` or `Multigrid`. Results agree to the solver tolerance.
    pub solver: LinearSolver,
    /// Opposite singularity pairs (`+1/2` beside `-1/2`) closer than this fraction of
    /// the area radius (of each connected piece) are cancelled (see [`LineFieldOptions::cancel_distance`]); at
    /// least 0, and 0 cancels none. Default 0.5: on the bunny the curvature-aligned
    /// field's 10 singularities become 6 (the pairs 0.35 and 0.46 area radii apart,
    /// between the eyes and the nose), on the bunny Loop-subdivided once too.
    pub cancel_distance: f64,
}

impl Default for Design {
    fn default() -> Self {
        Self {
            guidance: Guidance::default(),
            weight: 1.0,
            smoothness: 0.5,
            smoothing: 0.3,
            constraints: Vec::new(),
            anisotropy: Anisotropy::default(),
            density: Density::default(),
            solver: LinearSolver::Auto,
            cancel_distance: 0.5,
        }
    }
}

#[cfg(feature = "serde")]
fn one() -> f64 {
    1.0
}

#[cfg(feature = "serde")]
fn three() -> f64 {
    3.0
}

#[cfg(feature = "serde")]
fn quarter() -> f64 {
    0.25
}

#[cfg(feature = "serde")]
fn four() -> f64 {
    4.0
}

/// Refuses a constraint whose direction lies within 1 degree of its vertex's normal:
/// its projection into the tangent plane, the constrained line, would be noise.
/// Vertices out of range are left to the solver, which names them.
fn check_constraints_leave_the_normal(
    mesh: &TriMesh,
    constraints: &[LineConstraint],
) -> Result<(), FieldError> {
    let normals = mesh.vertex_normals();
    for (index, c) in constraints.iter().enumerate() {
        let Some(n) = normals.get(c.vertex as usize) else {
            continue;
        };
        let along = c.direction.normalize_or_zero().dot(*n).abs();
        if along > 1f64.to_radians().cos() {
            return Err(super::LineFieldError::ConstraintDirection {
                index,
                vertex: c.vertex,
            }
            .into());
        }
    }
    Ok(())
}

#[cfg(feature = "serde")]
fn default_light() -> [f64; 3] {
    crate::field::DEFAULT_LIGHT
}

impl Design {
    /// Checks every setting (not the constraints' vertices, which need the mesh).
    pub fn validate(&self) -> Result<(), FieldError> {
        match &self.guidance {
            Guidance::Smoothest => {}
            Guidance::Curvature {
                smoothing_iterations,
            } => smoothing_iterations_ok(*smoothing_iterations)?,
            Guidance::Direction(d) => direction("guidance direction", *d)?,
        }
        non_negative("weight", self.weight)?;
        if !(self.smoothness >= 0.0 && self.smoothness <= 0.95) {
            return Err(invalid("smoothness", self.smoothness, "in [0, 0.95]"));
        }
        non_negative("smoothing", self.smoothing)?;
        non_negative("cancel_distance", self.cancel_distance)?;
        for c in &self.constraints {
            direction("constraint direction", c.direction)?;
            if let Site::Point(p) = c.at
                && !DVec3::from(p).is_finite()
            {
                return Err(invalid(
                    "constraint point",
                    DVec3::from(p).length(),
                    "finite coordinates",
                ));
            }
        }
        match &self.anisotropy {
            Anisotropy::Constant(a) => {
                spacing_ratio("anisotropy", *a)?;
            }
            Anisotropy::Curvature {
                min,
                max,
                isotropy_curvature,
                smoothing_iterations,
            } => {
                spacing_ratio("min", *min)?;
                if !(*max >= *min && max.is_finite()) {
                    return Err(invalid("max", *max, "a finite spacing ratio >= min"));
                }
                positive("isotropy_curvature", *isotropy_curvature)?;
                smoothing_iterations_ok(*smoothing_iterations)?;
            }
        }
        match &self.density {
            Density::Constant(d) => positive("density", *d)?,
            Density::Curvature {
                floor,
                scale,
                smoothing_iterations,
                ..
            } => curvature::check_density(*floor, *scale, *smoothing_iterations)?,
            Density::File(_) => {}
            Density::Shading {
                light,
                lit,
                shadow,
                exponent,
            } => {
                direction("light", *light)?;
                positive("lit", *lit)?;
                positive("shadow", *shadow)?;
                positive("exponent", *exponent)?;
            }
        }
        Ok(())
    }

    /// The files this design reads (the density file, if any).
    pub fn files(&self) -> Vec<&Path> {
        match &self.density {
            Density::File(path) => vec![path.as_path()],
            _ => Vec::new(),
        }
    }

    /// Makes a relative density file path relative to `base_dir`.
    pub fn resolve_paths(&mut self, base_dir: &Path) {
        if let Density::File(path) = &mut self.density
            && path.is_relative()
        {
            *path = base_dir.join(&*path);
        }
    }

    /// The line field of this design on `mesh`.
    pub fn line_field(&self, mesh: &TriMesh) -> Result<LineField, FieldError> {
        self.validate()?;
        let guidance = || {
            Cow::Owned(match &self.guidance {
                Guidance::Smoothest => Vec::new(),
                Guidance::Curvature {
                    smoothing_iterations,
                } => curvature_guidance(mesh, &principal_curvatures(mesh, *smoothing_iterations)),
                Guidance::Direction(d) => direction_guidance(mesh, DVec3::from(*d)),
            })
        };
        let constraints: Vec<LineConstraint> = self
            .constraints
            .iter()
            .map(|c| LineConstraint {
                vertex: match c.at {
                    Site::Vertex(v) => v,
                    Site::Point(p) => nearest_vertex(mesh, DVec3::from(p)),
                },
                direction: DVec3::from(c.direction),
            })
            .collect();
        check_constraints_leave_the_normal(mesh, &constraints)?;
        let options = LineFieldOptions {
            weight: self.weight,
            smoothness: self.smoothness,
            smoothing: self.smoothing,
            solver: self.solver,
            cancel_distance: self.cancel_distance,
            ..LineFieldOptions::default()
        };
        Ok(constrained_line_field_with(
            mesh,
            (!matches!(self.guidance, Guidance::Smoothest), guidance),
            &constraints,
            &options,
        )?)
    }

    /// The tensor field of this design on `mesh`: direction from
    /// [`line_field`](Self::line_field), spacing ratio and density from their sources.
    pub fn build(&self, mesh: &TriMesh) -> Result<TensorField, FieldError> {
        let lines = self.line_field(mesh)?;
        let mut curvatures = CurvatureCache::default();
        let ratios: Vec<f64> = match &self.anisotropy {
            Anisotropy::Constant(a) => vec![*a; mesh.vertex_count()],
            Anisotropy::Curvature {
                min,
                max,
                isotropy_curvature,
                smoothing_iterations,
            } => {
                let k = curvatures.get(mesh, *smoothing_iterations);
                let c = curvature::area_radius(mesh);
                curvature::ratios(k, c, *isotropy_curvature, [*min, *max])
            }
        };
        let densities: Vec<f64> = match &self.density {
            Density::Constant(d) => vec![*d; mesh.vertex_count()],
            Density::Curvature {
                measure,
                normalization,
                floor,
                scale,
                smoothing_iterations,
            } => {
                let k = curvatures.get(mesh, *smoothing_iterations);
                curvature::densities(mesh, k, *measure, *normalization, *floor, *scale).1
            }
            Density::File(path) => {
                crate::field::read_field_file(path, mesh)?.vertex_densities(mesh)
            }
            Density::Shading {
                light,
                lit,
                shadow,
                exponent,
            } => crate::field::shading_densities(mesh, *light, *lit, *shadow, *exponent),
        };
        let eigen: Vec<[f64; 2]> = densities
            .iter()
            .zip(&ratios)
            .map(|(&d, &a)| eigenvalues(d, a))
            .collect();
        lines.to_tensor_field(mesh, &eigen)
    }
}

/// Principal curvatures computed once per smoothing count.
#[derive(Default)]
struct CurvatureCache {
    computed: Vec<(u32, PrincipalCurvatures)>,
}

impl CurvatureCache {
    fn get(&mut self, mesh: &TriMesh, iterations: u32) -> &PrincipalCurvatures {
        let index = match self.computed.iter().position(|(i, _)| *i == iterations) {
            Some(i) => i,
            None => {
                self.computed
                    .push((iterations, principal_curvatures(mesh, iterations)));
                self.computed.len() - 1
            }
        };
        &self.computed[index].1
    }
}

/// The vertex nearest to `p` (the lowest index among ties). O(V).
fn nearest_vertex(mesh: &TriMesh, p: DVec3) -> u32 {
    let mut best = (f64::INFINITY, 0);
    for (v, q) in mesh.positions().iter().enumerate() {
        let d = q.distance_squared(p);
        if d < best.0 {
            best = (d, v as u32);
        }
    }
    best.1
}

#[cfg(test)]
#[path = "designed_tests.rs"]
mod tests;
