//! Sampling of planar domains as one segment, parameterized by a single linear map.
//!
//! Input: a flat [`TriMesh`] (all faces in one plane, facing one way) and a
//! [`TensorField`]. The field's area-weighted mean tensor gives the map
//! `u = sqrt(l1) m1 . (x - o)`, `v = sqrt(l2) m2 . (x - o)`, which makes a constant
//! tensor the identity in `(u, v)` (paper section 3: the parameter domain is the domain
//! stretched by the square roots of the eigenvalues along the eigenvectors). The
//! parameter domain is scaled uniformly into the unit square and covered by adaptive
//! Hilbert cells whose measures carry the density, so density may vary freely.
//! Direction and anisotropy are those of the mean tensor: exact for fields with a
//! constant direction and anisotropy; fields that turn need the segmentation and
//! per-segment parameterization of the surface pipeline.
//!
//! Output: a [`Sampler`] with one segment and the [`PlanarMap`] used. Cost: O(F) plus
//! the cells' construction. [`Preprocessed::build`](crate::surface::Preprocessed::build)
//! takes this path by itself for a flat mesh.

use std::sync::Arc;

use glam::{DMat3, DVec2, DVec3};

use crate::curve::{CurveDomain, CurveError, CurveOptions, SegmentCurve, corner_densities};
use crate::field::{Eigen2, TensorField, eigen_in_plane};
use crate::mesh::TriMesh;
use crate::sample::{SampleError, Sampler, SegmentSampling};

/// Relative tolerance (to the bounding-box diagonal) for a vertex to count as in plane.
const PLANE_TOLERANCE: f64 = 1e-9;

/// Errors of the planar pipeline.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlanarError {
    /// The mesh is not flat, or folds over itself.
    #[error(
        "mesh is not planar: face {face} {why}; surfaces need segmentation and parameterization, \
         which the planar sampler does not do"
    )]
    NotPlanar {
        /// The first offending face.
        face: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// The adaptive cells could not be built.
    #[error(transparent)]
    Curve(#[from] CurveError),
    /// The sampler could not be built.
    #[error(transparent)]
    Sample(#[from] SampleError),
}

/// The linear parameterization of a planar domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarMap {
    /// World-space origin (maps to `uv = (0, 0)`).
    pub origin: DVec3,
    /// Unit plane normal.
    pub normal: DVec3,
    /// The mean tensor's eigen-decomposition (its major axis is the u direction).
    pub reference: Eigen2,
    /// World to unit square: `uv = scale * (sqrt(l1) m1 . (x - o), sqrt(l2) m2 . (x - o))`.
    pub scale: f64,
}

impl PlanarMap {
    /// Parameter coordinates (in the unit square for points of the domain).
    pub fn to_uv(&self, x: DVec3) -> DVec2 {
        let d = x - self.origin;
        let e = &self.reference;
        DVec2::new(e.l1.sqrt() * e.major.dot(d), e.l2.sqrt() * e.minor.dot(d)) * self.scale
    }

    /// World position of parameter coordinates.
    pub fn to_world(&self, uv: DVec2) -> DVec3 {
        let e = &self.reference;
        self.origin
            + e.major * (uv.x / (self.scale * e.l1.sqrt()))
            + e.minor * (uv.y / (self.scale * e.l2.sqrt()))
    }
}

/// Builds the one-segment sampler of a planar domain.
///
/// ```
/// use std::sync::Arc;
/// use strata_engine::{curve::CurveOptions, field::FieldSpec, mesh::shapes, planar};
/// let mesh = Arc::new(shapes::plane(1.0, 8)?);
/// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 };
/// let field = Arc::new(spec.build(&mesh)?);
/// let (sampler, _map) = planar::sampler(mesh, field, &CurveOptions::default())?;
/// let samples = sampler.sample(1000, 42);
/// assert_eq!(samples.len(), 1000);
/// assert!(samples.iter().all(|s| (0.0..=1.0).contains(&s.position[0])));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn sampler(
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    options: &CurveOptions,
) -> Result<(Sampler, PlanarMap), PlanarError> {
    let map = planar_map(&mesh, &field)?;
    Ok((sampler_with_map(mesh, field, &map, options)?, map))
}

/// The one-segment sampler of a planar domain whose map [`planar_map`] has already
/// derived (so a caller that tested planarity with it does not test twice).
pub fn sampler_with_map(
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    map: &PlanarMap,
    options: &CurveOptions,
) -> Result<Sampler, PlanarError> {
    let uv: Vec<DVec2> = mesh
        .positions()
        .iter()
        .map(|p| map.to_uv(*p).clamp(DVec2::ZERO, DVec2::ONE))
        .collect();
    let density = field.vertex_densities(&mesh);
    let corner_density = corner_densities(
        &uv,
        mesh.triangles(),
        |f| mesh.face_areas()[f],
        |v| density[v as usize],
    );
    let curve = SegmentCurve::build(
        &CurveDomain {
            uv: &uv,
            triangles: mesh.triangles(),
            corner_density: &corner_density,
        },
        options,
    )?;
    let faces = (0..mesh.face_count() as u32).collect();
    let sampler = Sampler::new(
        mesh,
        field,
        vec![SegmentSampling {
            segment: 0,
            faces,
            curve: std::sync::Arc::new(curve),
        }],
    )?;
    Ok(sampler)
}

/// Checks planarity and derives the linear map from the mean tensor.
pub fn planar_map(mesh: &TriMesh, field: &TensorField) -> Result<PlanarMap, PlanarError> {
    let normal = mesh
        .face_normals()
        .iter()
        .zip(mesh.face_areas())
        .fold(DVec3::ZERO, |acc, (n, a)| acc + *n * *a)
        .try_normalize()
        .ok_or(PlanarError::NotPlanar {
            face: 0,
            why: "has normals that cancel out",
        })?;
    let (lo, hi) = mesh.bounds();
    let tolerance = PLANE_TOLERANCE * (hi - lo).length().max(f64::MIN_POSITIVE);
    let origin = mesh.positions()[0];
    for (face, (t, n)) in mesh.triangles().iter().zip(mesh.face_normals()).enumerate() {
        if n.dot(normal) < 1.0 - 1e-9 {
            return Err(PlanarError::NotPlanar {
                face,
                why: "is tilted or flipped against the mean plane",
            });
        }
        if t.iter()
            .any(|&v| (mesh.positions()[v as usize] - origin).dot(normal).abs() > tolerance)
        {
            return Err(PlanarError::NotPlanar {
                face,
                why: "has a corner off the mean plane",
            });
        }
    }
    let mean = mesh
        .triangles()
        .iter()
        .zip(mesh.face_areas())
        .fold(DMat3::ZERO, |acc, (t, a)| {
            let m = t
                .iter()
                .fold(DMat3::ZERO, |s, &v| s + field.tensors()[v as usize]);
            acc + m * (*a / 3.0)
        });
    let reference = eigen_in_plane(&mean, normal);
    let mut map = PlanarMap {
        origin: DVec3::ZERO,
        normal,
        reference,
        scale: 1.0,
    };
    // Place the domain's lower-left corner at uv = 0 and scale its extent to 1.
    let (mut uv_lo, mut uv_hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in mesh.positions() {
        let q = map.to_uv(*p);
        uv_lo = uv_lo.min(q);
        uv_hi = uv_hi.max(q);
    }
    map.origin = map.to_world(uv_lo);
    map.scale = 1.0 / (uv_hi - uv_lo).max_element();
    Ok(map)
}

#[cfg(test)]
mod tests;
