//! Field sources: how a user describes a tensor field (in a config file or in code).
//!
//! Analytic planar test fields (paper section 7.5, after Wei and Wang 2011), per-vertex
//! tensors from a file ([`super::read_field_file`]) and principal curvatures
//! ([`super::principal_curvatures`]) all end up as a validated [`TensorField`].

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};

use super::curvature::{self, CurvatureMeasure, CurvatureNormalization};
use super::design::Design;
use super::params::{self, eigenvalues, finite_point, invalid, positive, spacing_ratio};
use super::warp::PlanarWarp;
use super::{FieldError, TensorField};
use crate::mesh::TriMesh;

/// A tensor field description, turned into per-vertex tensors by [`FieldSpec::build`].
///
/// `anisotropy` is always the spacing ratio `sqrt(l1 / l2) >= 1`: samples are
/// `anisotropy` times closer along the major direction than along the minor one.
/// `density` is `delta = sqrt(l1 l2)` (samples per unit area, up to the global count).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub enum FieldSpec {
    /// A constant direction projected into each tangent plane, with constant
    /// anisotropy and density. Where the direction is parallel to the normal a
    /// deterministic tangent is used instead.
    Constant {
        /// World-space major direction (need not be unit length).
        direction: [f64; 3],
        /// Spacing ratio `sqrt(l1 / l2)`, at least 1. Default 1 (isotropic).
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        anisotropy: f64,
        /// Density `sqrt(l1 l2)`, positive. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        density: f64,
    },
    /// A planar isotropic density function of the vertices' (x, y) coordinates, with a
    /// constant direction and anisotropy on top (paper section 7.5's test fields).
    Planar {
        /// The density function.
        density: PlanarDensity,
        /// World-space major direction. Default +x.
        #[cfg_attr(feature = "serde", serde(default = "x_axis"))]
        direction: [f64; 3],
        /// Spacing ratio `sqrt(l1 / l2)`, at least 1. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        anisotropy: f64,
    },
    /// The metric of a planar map `f: (x, y) -> R^2` (paper section 7.5's anisotropic
    /// test fields "shear" and "perspective", after Wei and Wang 2011 and Li et al.
    /// 2010; the closed forms are ours, see [`PlanarWarp`], as the paper does not give
    /// theirs): with `J` the Jacobian of `f` at a vertex's `(x, y)`,
    /// `T = density * J^T J`, embedded in the xy plane and projected into the vertex's
    /// tangent plane. Samples that would be uniform and isotropic in the image of `f`
    /// have spacing proportional to `1 / |J d|` along a unit direction `d`; the density
    /// is `density * |det J|`. Meant for meshes in a `z = const` plane; on other
    /// surfaces the xy metric is projected (and fails with `NotPositiveDefinite` where a
    /// tangent plane is vertical). Errors with [`FieldError::OutsideDomain`] where the
    /// map is undefined at a vertex.
    Warp {
        /// The map.
        warp: PlanarWarp,
        /// Density scale, positive: the density where `J` is a rotation. Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        density: f64,
    },
    /// Per-vertex tensors read from a text file; see [`read_field_file`](super::read_field_file)
    /// for the format. [`build`](FieldSpec::build) opens `path` as given (relative to
    /// the working directory); call [`resolve_paths`](FieldSpec::resolve_paths) first to
    /// make it relative to a config file's folder.
    File {
        /// The field file.
        path: PathBuf,
    },
    /// A sampling tensor from the surface's principal curvatures (Rusinkiewicz 2004,
    /// see [`principal_curvatures`](super::principal_curvatures)), smoothed over the
    /// mesh. Per vertex, with `k1` the principal curvature of largest magnitude (along
    /// `d1`) and `k2` the other one, and `c` the normalization factor:
    ///
    /// - major direction `m1 = d1`, the direction of strongest bending: samples are
    ///   closest along it (spacing along `m1` is `1 / anisotropy` times that along `m2`);
    /// - `density = floor + scale * c * measure(k1, k2)`;
    /// - `anisotropy = clamp((c |k1| + eps) / (c |k2| + eps), 1, max_anisotropy)`
    ///   with `eps = isotropy_curvature`, so that spacing is inversely proportional to
    ///   curvature in each principal direction, saturating on developable parts
    ///   (`k2 = 0`) and fading to isotropic where both curvatures are small against
    ///   `eps` (flat or nearly flat parts, whose directions are noise).
    ///
    /// A flat mesh gets `density = floor`, isotropic; a sphere gets a constant
    /// isotropic tensor; a cylinder gets `max_anisotropy` with `m1` around it.
    ///
    /// ```
    /// use glam::DVec3;
    /// use strata_engine::{field::FieldSpec, mesh::{TriMesh, shapes}};
    /// // A parabolic trough z = (x - 1)^2 / 2: bent along x, straight along y.
    /// let flat = shapes::plane(2.0, 16)?;
    /// let bent: Vec<DVec3> = flat.positions().iter()
    ///     .map(|p| DVec3::new(p.x, p.y, 0.5 * (p.x - 1.0).powi(2)))
    ///     .collect();
    /// let mesh = TriMesh::new(bent, flat.triangles().to_vec())?;
    /// let field = FieldSpec::default_curvature().build(&mesh)?;
    /// let centre = 8 * 17 + 8; // the vertex at (1, 1)
    /// let e = strata_engine::field::eigen_in_plane(
    ///     &field.tensors()[centre], mesh.vertex_normals()[centre]);
    /// assert!(e.major.x.abs() > 0.99); // densest across the bend
    /// assert!((e.anisotropy() - 4.0).abs() < 1e-9); // max_anisotropy: k2 = 0
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    Curvature {
        /// Which curvature measure drives the density. Default
        /// [`CurvatureMeasure::Rms`].
        #[cfg_attr(feature = "serde", serde(default))]
        measure: CurvatureMeasure,
        /// How curvatures are made comparable across meshes (the factor `c`). Default
        /// [`CurvatureNormalization::AreaRadius`] (dimensionless, 1 on any sphere).
        #[cfg_attr(feature = "serde", serde(default))]
        normalization: CurvatureNormalization,
        /// Density where the surface is flat; finite, > 0 (keeps every tensor
        /// positive definite). Default 0.2.
        #[cfg_attr(feature = "serde", serde(default = "curvature::default_floor"))]
        floor: f64,
        /// Density added per unit of normalized curvature measure; finite, >= 0.
        /// Default 1.
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        scale: f64,
        /// Largest spacing ratio `sqrt(l1 / l2)`; finite, >= 1 (1 gives an isotropic
        /// field). Default 4.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_max_anisotropy")
        )]
        max_anisotropy: f64,
        /// `eps` in the anisotropy ratio, in normalized curvature units (the units of
        /// `c * k`); finite, > 0. Curvatures well below it count as flat. Default 0.05.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_isotropy_curvature")
        )]
        isotropy_curvature: f64,
        /// Iterations of neighbour averaging of the curvature tensors (each transported
        /// into the vertex's tangent plane, weighted by Voronoi area); 0 to 1000.
        /// Default 2.
        #[cfg_attr(
            feature = "serde",
            serde(default = "curvature::default_smoothing_iterations")
        )]
        smoothing_iterations: u32,
    },
    /// A designed field ([`Design`]): the direction is a smooth line field with few
    /// singularities (Knöppel et al. 2013) aligned to a guidance (curvature, a world
    /// direction, or none) and to hard constraints; spacing ratio and density come from
    /// their own sources (constant, curvature, or a field file's densities). In a scene
    /// file: `Designed(guidance: Curvature(), weight: 1.0, anisotropy: Constant(3.0))`.
    Designed(Design),
}

#[cfg(feature = "serde")]
fn one() -> f64 {
    1.0
}

#[cfg(feature = "serde")]
fn x_axis() -> [f64; 3] {
    [1.0, 0.0, 0.0]
}

/// Density functions of planar position `p = (x, y)`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub enum PlanarDensity {
    /// `delta(p) = base + peak * exp(-|p - center|^2 / (2 sigma^2))`.
    Gaussian {
        /// Centre of the blob.
        center: [f64; 2],
        /// Standard deviation (world units), positive.
        sigma: f64,
        /// Added density at the centre, non-negative.
        peak: f64,
        /// Density far from the centre, positive.
        base: f64,
    },
    /// A linear ramp between two points, constant beyond them:
    /// `delta(p) = d0 + t (d1 - d0)` with
    /// `t = clamp((p - start) . (end - start) / |end - start|^2, 0, 1)`,
    /// `d0 = start_density`, `d1 = end_density`. Positive everywhere.
    Ramp {
        /// Where the density is `start_density`.
        start: [f64; 2],
        /// Where the density is `end_density`; differs from `start`.
        end: [f64; 2],
        /// Density at and before `start`, positive.
        start_density: f64,
        /// Density at and beyond `end`, positive.
        end_density: f64,
    },
    /// The test density of Balzer, Schlömer and Deussen 2009 ("Capacity-constrained
    /// point distributions", also used by Wei and Wang 2011 and paper section 7.5),
    /// on the square `[origin, origin + size]^2` mapped to `u in [-1, 1]^2`:
    /// `delta = floor + exp(-20 |u|^2) + 0.2 sin^2(pi u_x) sin^2(pi u_y)`.
    /// A sharp peak of 1 at the centre over a weak periodic pattern; Balzer's original
    /// has `floor = 0` and falls to about 1e-9 at the square's edges.
    Balzer {
        /// Lower-left corner of the square. Default `[0, 0]`.
        #[cfg_attr(feature = "serde", serde(default))]
        origin: [f64; 2],
        /// Side of the square (world units), positive. Default 1 (the paper uses
        /// `[0, 4]^2`: `size = 4`).
        #[cfg_attr(feature = "serde", serde(default = "one"))]
        size: f64,
        /// Added density, finite and > 0 so that the density stays positive where the
        /// exponential underflows. Default 0.001.
        #[cfg_attr(feature = "serde", serde(default = "default_balzer_floor"))]
        floor: f64,
    },
}

#[cfg(feature = "serde")]
fn default_balzer_floor() -> f64 {
    0.001
}

impl PlanarDensity {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), FieldError> {
        match *self {
            Self::Gaussian {
                center,
                sigma,
                peak,
                base,
            } => {
                positive("sigma", sigma)?;
                positive("base", base)?;
                if !(peak >= 0.0) || !peak.is_finite() {
                    return Err(invalid("peak", peak, "a finite value >= 0"));
                }
                finite_point("center", center)
            }
            Self::Ramp {
                start,
                end,
                start_density,
                end_density,
            } => {
                finite_point("start", start)?;
                finite_point("end", end)?;
                let length = (DVec2::from(end) - DVec2::from(start)).length();
                if !(length > 0.0) || !length.is_finite() {
                    return Err(invalid(
                        "end",
                        length,
                        "a point at a finite non-zero distance from `start`",
                    ));
                }
                positive("start_density", start_density)?;
                positive("end_density", end_density)
            }
            Self::Balzer {
                origin,
                size,
                floor,
            } => {
                finite_point("origin", origin)?;
                positive("size", size)?;
                positive("floor", floor)
            }
        }
    }

    /// The density at `p`.
    pub fn eval(&self, p: DVec2) -> f64 {
        match *self {
            Self::Gaussian {
                center,
                sigma,
                peak,
                base,
            } => {
                let d2 = (p - DVec2::from(center)).length_squared();
                base + peak * (-d2 / (2.0 * sigma * sigma)).exp()
            }
            Self::Ramp {
                start,
                end,
                start_density,
                end_density,
            } => {
                let (a, b) = (DVec2::from(start), DVec2::from(end));
                let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                start_density + t * (end_density - start_density)
            }
            Self::Balzer {
                origin,
                size,
                floor,
            } => {
                let u = (p - DVec2::from(origin)) * (2.0 / size) - DVec2::ONE;
                let s = (std::f64::consts::PI * u).to_array().map(f64::sin);
                floor + (-20.0 * u.length_squared()).exp() + 0.2 * s[0] * s[0] * s[1] * s[1]
            }
        }
    }
}

impl FieldSpec {
    /// Checks the parameters without building anything.
    pub fn validate(&self) -> Result<(), FieldError> {
        match self {
            Self::Constant {
                direction,
                anisotropy,
                density,
            } => {
                params::direction("direction", *direction)?;
                spacing_ratio("anisotropy", *anisotropy)?;
                positive("density", *density)
            }
            Self::Planar {
                density,
                direction,
                anisotropy,
            } => {
                params::direction("direction", *direction)?;
                spacing_ratio("anisotropy", *anisotropy)?;
                density.validate()
            }
            Self::Warp { warp, density } => {
                warp.validate()?;
                positive("density", *density)
            }
            Self::File { .. } => Ok(()),
            Self::Designed(design) => design.validate(),
            Self::Curvature {
                floor,
                scale,
                max_anisotropy,
                isotropy_curvature,
                smoothing_iterations,
                ..
            } => {
                curvature::check_density(*floor, *scale, *smoothing_iterations)?;
                spacing_ratio("max_anisotropy", *max_anisotropy)?;
                positive("isotropy_curvature", *isotropy_curvature)
            }
        }
    }

    /// The curvature source with every setting at its default: RMS curvature,
    /// area-radius normalization, `floor` 0.2, `scale` 1, `max_anisotropy` 4,
    /// `isotropy_curvature` 0.05, `smoothing_iterations` 2.
    pub fn default_curvature() -> Self {
        Self::Curvature {
            measure: CurvatureMeasure::default(),
            normalization: CurvatureNormalization::default(),
            floor: curvature::DEFAULT_FLOOR,
            scale: 1.0,
            max_anisotropy: curvature::DEFAULT_MAX_ANISOTROPY,
            isotropy_curvature: curvature::DEFAULT_ISOTROPY_CURVATURE,
            smoothing_iterations: curvature::DEFAULT_SMOOTHING_ITERATIONS,
        }
    }

    /// Makes relative file paths in this spec relative to `base_dir` (typically the
    /// folder of the config file that holds the spec); absolute paths and sources
    /// without files are left alone.
    ///
    /// ```
    /// use std::path::{Path, PathBuf};
    /// use strata_engine::field::FieldSpec;
    /// let mut spec = FieldSpec::File { path: PathBuf::from("wing.field") };
    /// spec.resolve_paths(Path::new("configs"));
    /// assert_eq!(spec, FieldSpec::File { path: Path::new("configs").join("wing.field") });
    /// ```
    pub fn resolve_paths(&mut self, base_dir: &Path) {
        match self {
            Self::File { path } if path.is_relative() => *path = base_dir.join(&*path),
            Self::Designed(design) => design.resolve_paths(base_dir),
            _ => {}
        }
    }

    /// The files this spec reads when it is built (a field file, a designed field's
    /// density file), for hot reload to watch.
    pub fn files(&self) -> Vec<&Path> {
        match self {
            Self::File { path } => vec![path.as_path()],
            Self::Designed(design) => design.files(),
            _ => Vec::new(),
        }
    }

    /// Builds the per-vertex tensors on `mesh`.
    ///
    /// ```
    /// use strata_engine::{field::FieldSpec, mesh::shapes};
    /// let mesh = shapes::plane(1.0, 4)?;
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 4.0, density: 2.0 };
    /// let field = spec.build(&mesh)?;
    /// let e = field.face_eigen(&mesh, 0, [1.0 / 3.0; 3]);
    /// assert!((e.anisotropy() - 4.0).abs() < 1e-12 && (e.density() - 2.0).abs() < 1e-12);
    /// assert!(e.major.x.abs() > 0.999_999);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(&self, mesh: &TriMesh) -> Result<TensorField, FieldError> {
        self.validate()?;
        match self {
            Self::Constant {
                direction,
                anisotropy,
                density,
            } => {
                let n = mesh.vertex_count();
                let ev = eigenvalues(*density, *anisotropy);
                TensorField::from_frames(mesh, &vec![DVec3::from(*direction); n], &vec![ev; n])
            }
            Self::Planar {
                density,
                direction,
                anisotropy,
            } => {
                let n = mesh.vertex_count();
                let ev: Vec<[f64; 2]> = mesh
                    .positions()
                    .iter()
                    .map(|p| eigenvalues(density.eval(p.truncate()), *anisotropy))
                    .collect();
                TensorField::from_frames(mesh, &vec![DVec3::from(*direction); n], &ev)
            }
            Self::Warp { warp, density } => warp.build(mesh, *density),
            Self::File { path } => super::read_field_file(path, mesh),
            Self::Designed(design) => design.build(mesh),
            Self::Curvature {
                measure,
                normalization,
                floor,
                scale,
                max_anisotropy,
                isotropy_curvature,
                smoothing_iterations,
            } => {
                let settings = curvature::Settings {
                    measure: *measure,
                    normalization: *normalization,
                    floor: *floor,
                    scale: *scale,
                    max_anisotropy: *max_anisotropy,
                    isotropy_curvature: *isotropy_curvature,
                };
                let k = super::principal_curvatures(mesh, *smoothing_iterations);
                curvature::sampling_field(mesh, &k, &settings)
            }
        }
    }
}
