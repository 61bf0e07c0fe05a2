//! The segmentation step of the surface path: isotropic charts for an isotropic field,
//! the field-aligned segmentation otherwise.
//!
//! - Every vertex isotropic (anisotropy `sqrt(l1 / l2)` under
//!   [`SurfaceOptions::isotropy_threshold`]): the field has no direction to align to,
//!   so the mesh is covered with [`isotropic_charts`] (normal-cone discs, O(F))
//!   and parameterized with the field's [`isotropic_copy`] (the same densities, the
//!   isotropic fallback frame). No line field is solved and no random walk runs.
//! - Otherwise isotropic vertices take a smooth direction
//!   ([`smooth_isotropic_directions`]) and the random walk segments along the field
//!   (paper section 4).

use std::sync::Arc;
use std::time::Instant;

use super::{Progress, SurfaceError, SurfaceOptions, record_stage};
use crate::field::{TensorField, all_isotropic, isotropic_copy, smooth_isotropic_directions};
use crate::mesh::TriMesh;
use crate::segment::{Segmentation, isotropic_charts, segment};

/// How the surface was segmented.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentationKind {
    /// The field is isotropic everywhere: normal-cone charts, no field alignment.
    IsotropicCharts,
    /// Field-aligned segments (section 4); this many isotropic vertices took a smooth
    /// direction first.
    FieldAligned {
        /// Vertices whose direction was replaced by the smooth line field.
        smoothed_vertices: usize,
    },
}

/// The output of [`segment_surface`].
#[derive(Debug)]
pub struct SurfaceSegmentation {
    /// The field to parameterize and sample with: the input's isotropic copy for
    /// charts, the input with smooth directions in its isotropic regions otherwise.
    pub field: Arc<TensorField>,
    /// The segments.
    pub segmentation: Segmentation,
    /// Which way it went.
    pub kind: SegmentationKind,
}

/// Segments `mesh` for the surface path (see the module docs), reporting the stages
/// `"isotropic directions"` and `"segmentation"` to `progress` and appending their
/// times to `stages`. `options` must be validated.
///
/// Errors: a failed line-field solve or segmentation.
///
/// ```
/// use std::sync::Arc;
/// use strata_engine::{field::FieldSpec, mesh::shapes};
/// use strata_engine::surface::{SegmentationKind, SurfaceOptions, segment_surface};
/// let mesh = shapes::sphere(1.0, 4)?;
/// let iso = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 };
/// let out = segment_surface(&mesh, Arc::new(iso.build(&mesh)?), &SurfaceOptions::default(),
///     &|_| {}, &mut Vec::new())?;
/// assert_eq!(out.kind, SegmentationKind::IsotropicCharts);
/// assert!(out.segmentation.singularities.is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn segment_surface(
    mesh: &TriMesh,
    field: Arc<TensorField>,
    options: &SurfaceOptions,
    progress: &dyn Fn(Progress),
    stages: &mut Vec<(&'static str, std::time::Duration)>,
) -> Result<SurfaceSegmentation, SurfaceError> {
    progress(Progress::Start("isotropic directions"));
    let t = Instant::now();
    let (field, kind) = prepare_field(mesh, field, options)?;
    record_stage(stages, progress, "isotropic directions", t);
    progress(Progress::Start("segmentation"));
    let t = Instant::now();
    let segmentation = segment_prepared(mesh, &field, kind, options)?;
    record_stage(stages, progress, "segmentation", t);
    Ok(SurfaceSegmentation {
        field,
        segmentation,
        kind,
    })
}

/// The first half of [`segment_surface`]: the field the surface path works with (the
/// input's isotropic copy when every vertex is isotropic, the input with smooth
/// directions at its isotropic vertices otherwise) and which segmentation it takes.
/// `options` must be validated. Cost: O(V) when no vertex is isotropic, one sparse
/// line-field solve otherwise.
pub fn prepare_field(
    mesh: &TriMesh,
    field: Arc<TensorField>,
    options: &SurfaceOptions,
) -> Result<(Arc<TensorField>, SegmentationKind), SurfaceError> {
    if options.isotropy_threshold > 1.0 && all_isotropic(mesh, &field, options.isotropy_threshold) {
        let field = Arc::new(isotropic_copy(mesh, &field)?);
        return Ok((field, SegmentationKind::IsotropicCharts));
    }
    Ok(
        match smooth_isotropic_directions(mesh, &field, options.isotropy_threshold)? {
            Some((smoothed, changed)) => (
                Arc::new(smoothed),
                SegmentationKind::FieldAligned {
                    smoothed_vertices: changed,
                },
            ),
            None => (
                field,
                SegmentationKind::FieldAligned {
                    smoothed_vertices: 0,
                },
            ),
        },
    )
}

/// The second half of [`segment_surface`]: normal-cone charts or the field-aligned
/// segmentation of `field` (from [`prepare_field`], with its `kind`).
pub fn segment_prepared(
    mesh: &TriMesh,
    field: &TensorField,
    kind: SegmentationKind,
    options: &SurfaceOptions,
) -> Result<Segmentation, SurfaceError> {
    Ok(match kind {
        SegmentationKind::IsotropicCharts => isotropic_charts(mesh, options.chart_angle),
        SegmentationKind::FieldAligned { .. } => segment(mesh, field, &options.segment)?,
    })
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::shapes;

    fn run(mesh: &TriMesh, field: TensorField, options: &SurfaceOptions) -> SurfaceSegmentation {
        let mut stages = Vec::new();
        let out =
            segment_surface(mesh, Arc::new(field), options, &|_| {}, &mut stages).expect("segment");
        let names: Vec<&str> = stages.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, ["isotropic directions", "segmentation"]);
        out
    }

    fn constant(mesh: &TriMesh, anisotropy: f64) -> TensorField {
        FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy,
            density: 2.0,
        }
        .build(mesh)
        .expect("field")
    }

    #[test]
    fn the_field_decides_charts_or_field_aligned_segments() {
        let mesh = shapes::torus(1.0, 0.4, 24).expect("torus");
        let options = SurfaceOptions::default();
        // Isotropic everywhere, and nearly so (under the threshold): charts, on the
        // field's isotropic copy (densities kept).
        for anisotropy in [1.0, 1.05] {
            let input = constant(&mesh, anisotropy);
            let out = run(&mesh, input.clone(), &options);
            assert_eq!(out.kind, SegmentationKind::IsotropicCharts);
            assert!(out.segmentation.singularities.is_empty());
            for v in 0..mesh.vertex_count() as u32 {
                let (a, b) = (
                    out.field.vertex_density(&mesh, v),
                    input.vertex_density(&mesh, v),
                );
                assert!((a - b).abs() < 1e-9 * b, "vertex {v}: {a} vs {b}");
            }
        }
        // Anisotropic everywhere: the field-aligned path, nothing smoothed.
        let out = run(&mesh, constant(&mesh, 3.0), &options);
        assert_eq!(
            out.kind,
            SegmentationKind::FieldAligned {
                smoothed_vertices: 0
            }
        );
        // A threshold of 1 turns isotropic handling off: even an isotropic field is
        // segmented along its (arbitrary) eigenvectors.
        let off = SurfaceOptions {
            isotropy_threshold: 1.0,
            ..options
        };
        let out = run(&mesh, constant(&mesh, 1.0), &off);
        assert!(matches!(out.kind, SegmentationKind::FieldAligned { .. }));
    }

    #[test]
    fn a_mixed_field_smooths_its_isotropic_vertices_and_stays_field_aligned() {
        // Isotropic on the torus's upper half, 3:1 along x on the lower half.
        let mesh = shapes::torus(1.0, 0.4, 24).expect("torus");
        let upper: Vec<bool> = mesh.positions().iter().map(|p| p.z > 0.0).collect();
        let directions = vec![DVec3::X; mesh.vertex_count()];
        let eigenvalues: Vec<[f64; 2]> = upper
            .iter()
            .map(|&u| if u { [1.0, 1.0] } else { [9.0, 1.0] })
            .collect();
        let field = TensorField::from_frames(&mesh, &directions, &eigenvalues).expect("field");
        let isotropic = upper.iter().filter(|&&u| u).count();
        assert!(isotropic > 0 && isotropic < mesh.vertex_count());
        let out = run(&mesh, field, &SurfaceOptions::default());
        assert_eq!(
            out.kind,
            SegmentationKind::FieldAligned {
                smoothed_vertices: isotropic
            }
        );
    }
}
