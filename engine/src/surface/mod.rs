//! The front door of preprocessing: a mesh and a field in, a [`Preprocessed`] surface
//! ready to sample out.
//!
//! [`Preprocessed::build`] picks the path itself. A flat mesh takes the planar fast
//! path ([`planar::sampler`]: one segment under one linear map, exact for fields of
//! constant direction and anisotropy). Any other mesh takes the surface pipeline:
//! segmentation ([`segment_surface`]: normal-cone charts for a fully isotropic field,
//! the field-aligned segmentation of paper section 4 otherwise), parameterization with splitting of invalid segments
//! ([`refine`], section 5.2), and adaptive Hilbert cells per segment under one shared
//! cell budget ([`budget_cells`](crate::curve::budget_cells), section 6.1).
//! [`SurfaceReport::path`] says which path ran.
//!
//! Input: a mesh, a field and [`SurfaceOptions`]. Output: [`Preprocessed`], holding the
//! final segments, their parameterizations and a [`Sampler`] that draws any count.
//!
//! Cost: planar, O(F) plus the cells; surface, the segmentation, then one sparse
//! factorization per parameterized segment (segments in parallel with rayon), then the
//! cells.

mod assemble;
mod build_control;
mod cells;
pub mod incremental;
mod key;
pub mod merge;
mod piece;
pub mod refine;
mod segmentation;

use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::curve::{CurveError, CurveOptions};
use crate::field::{FieldError, TensorField};
use crate::mesh::TriMesh;
use crate::param::{ParamError, ParamOptions, SegmentParam};
use crate::planar::{self, PlanarError, PlanarMap};
use crate::sample::{SampleError, Sampler};
use crate::segment::{SegmentError, SegmentOptions, Segmentation};

pub use assemble::{order_segments, total_measure};
pub use cells::segment_cells;
use cells::{build_cells, cell_inputs};
pub use key::KeyBuilder;
pub use piece::lowest_face;
pub use refine::{SplitContext, parameterize_segment_with_splitting, parameterize_with_splitting};
pub use segmentation::{
    SegmentationKind, SurfaceSegmentation, prepare_field, segment_prepared, segment_surface,
};
// Old paths of items that moved to their stage (new code should use the new homes:
// `curve::CellInput`, `segment::segmentation_from_labels`).
pub use crate::curve::CellInput;
pub use crate::segment::segmentation_from_labels;

/// Settings of the whole preprocessing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SurfaceOptions {
    /// Segmentation settings.
    pub segment: SegmentOptions,
    /// Parameterization settings (gamma, isotropy threshold).
    pub param: ParamOptions,
    /// Cell settings. `max_cell_share` is a share of the whole surface's measure here,
    /// so the number of cells does not grow with the number of segments.
    pub curve: CurveOptions,
    /// Segments with fewer faces are not split further (isotropic fallback instead).
    /// Range >= 1; default 16.
    pub min_segment_faces: usize,
    /// Which angle between the mapped field and the u axis must stay below `gamma`:
    /// the area-weighted mean over the segment's faces (section 5.2, the default) or
    /// the largest per-face angle (section 7.3.1's "no angle greater than gamma"),
    /// which splits more.
    pub angle_criterion: AngleCriterion,
    /// Vertices whose anisotropy `sqrt(l1 / l2)` is below this count as isotropic. A
    /// field isotropic everywhere is covered by normal-cone charts
    /// ([`segment_surface`]); otherwise isotropic vertices take their direction from a
    /// smooth line field before segmentation
    /// ([`smooth_isotropic_directions`](crate::field::smooth_isotropic_directions)):
    /// isotropic regions then make no singularities and no over-segmentation. Densities do not change; an exactly isotropic tensor
    /// becomes [`ISOTROPIC_DIRECTION_RATIO`](crate::field::ISOTROPIC_DIRECTION_RATIO)
    /// (1.02) anisotropic along that direction so
    /// that it holds it, and a nearly isotropic one turns by at most its small
    /// anisotropy. Range >= 1, 1 turning it off; default 1.1 (the segmentation's own
    /// isotropy threshold).
    pub isotropy_threshold: f64,
    /// Half-angle (radians) of the normal cones that cover a fully isotropic field's
    /// surface with charts ([`isotropic_charts`](crate::segment::isotropic_charts));
    /// larger makes fewer, more distorted charts. Range (0, pi]; default
    /// [`CHART_NORMAL_ANGLE`](crate::segment::CHART_NORMAL_ANGLE) (60 degrees).
    pub chart_angle: f64,
    /// Whether neighbouring pieces of a split segment are merged back where their union
    /// parameterizes validly ([`merge`]): fewer, larger segments for a few small extra
    /// factorizations. Default true.
    pub merge_pieces: bool,
}

/// The angle that the validity test compares with `gamma`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AngleCriterion {
    /// Area-weighted mean angle over the segment (section 5.2).
    #[default]
    Mean,
    /// Largest per-face angle (section 7.3.1).
    Max,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        Self {
            segment: SegmentOptions::default(),
            param: ParamOptions::default(),
            curve: CurveOptions::default(),
            min_segment_faces: 16,
            angle_criterion: AngleCriterion::Mean,
            isotropy_threshold: crate::segment::seeds::ISOTROPY_THRESHOLD,
            chart_angle: crate::segment::CHART_NORMAL_ANGLE,
            merge_pieces: true,
        }
    }
}

impl SurfaceOptions {
    /// Checks the options that preprocessing reads before any work starts: the
    /// minimum segment size, the cell settings and the parameterization settings.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        if self.min_segment_faces == 0 {
            return Err(SurfaceError::InvalidMinSegmentFaces);
        }
        if !(self.isotropy_threshold >= 1.0 && self.isotropy_threshold.is_finite()) {
            return Err(SurfaceError::InvalidIsotropyThreshold(
                self.isotropy_threshold,
            ));
        }
        if !(self.chart_angle > 0.0 && self.chart_angle <= std::f64::consts::PI) {
            return Err(SurfaceError::InvalidChartAngle(self.chart_angle));
        }
        self.curve
            .validate()
            .map_err(|source| SurfaceError::Curve { segment: 0, source })?;
        self.param.validate()?;
        Ok(())
    }
}

/// Errors of the surface preprocessing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// Segmentation failed.
    #[error("segmentation: {0}")]
    Segment(#[from] SegmentError),
    /// A parameterization failed in a way splitting cannot fix.
    #[error("parameterization: {0}")]
    Param(#[from] ParamError),
    /// The isotropic fallback field could not be built.
    #[error("isotropic fallback field: {0}")]
    Field(#[from] FieldError),
    /// Cells could not be built for a segment.
    #[error("cells of segment {segment}: {source}")]
    Curve {
        /// Segment id.
        segment: usize,
        /// The cause.
        #[source]
        source: CurveError,
    },
    /// The sampler could not be built.
    #[error("sampler: {0}")]
    Sample(#[from] SampleError),
    /// The planar fast path (a flat mesh) could not build its cells or sampler.
    #[error("planar domain: {0}")]
    Planar(#[from] PlanarError),
    /// `min_segment_faces` is 0.
    #[error("min_segment_faces must be at least 1")]
    InvalidMinSegmentFaces,
    /// `isotropy_threshold` is below 1 or not finite.
    #[error("isotropy_threshold must be a finite number >= 1 (1 turns it off), got {0}")]
    InvalidIsotropyThreshold(f64),
    /// `chart_angle` is not in (0, pi].
    #[error("chart_angle must be in (0, pi] radians, got {0}")]
    InvalidChartAngle(f64),
    /// An incremental build was cancelled through its
    /// [`BuildControl`](incremental::BuildControl) (a newer change superseded it).
    #[error("cancelled: a newer change superseded this build")]
    Cancelled,
}

/// Which path of the preprocessing ran.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum PreprocessPath {
    /// Segmentation, parameterization with splitting, cells per segment.
    #[default]
    Surface,
    /// The flat-mesh fast path: one segment under this linear map
    /// ([`planar::sampler`]).
    Planar(PlanarMap),
}

/// Counts describing what the preprocessing did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceReport {
    /// Which path ran (the planar one has one segment, no splits).
    pub path: PreprocessPath,
    /// Segments after segmentation, before splitting.
    pub segments_before_split: usize,
    /// Final segments.
    pub segments: usize,
    /// Segments split because their parameterization was invalid.
    pub splits: usize,
    /// Pairs of neighbouring pieces of a split segment merged back because their union
    /// is valid ([`merge`]).
    pub merges: usize,
    /// Final segments parameterized with the isotropic fallback frame: those whose
    /// field is isotropic (mean spacing ratio under `isotropy_threshold`), those no
    /// split made valid with the field's frame, and single faces (also counted in
    /// `single_face_segments`). Equals the segments whose parameterization report has
    /// `isotropic_fallback` set.
    pub isotropic_segments: usize,
    /// Faces that ended as single-triangle segments (last resort).
    pub single_face_segments: usize,
    /// Total cells over all segments.
    pub cells: usize,
}

/// A surface ready to sample.
#[derive(Debug)]
pub struct Preprocessed {
    /// The segmentation (before splitting). Surface path only: empty (no segments, no
    /// faces) when the planar path ran.
    pub segmentation: Segmentation,
    /// The final segments' parameterizations; segment `i` of the samples is `params[i]`.
    /// Surface path only: empty when the planar path ran (its one linear map is in
    /// [`SurfaceReport::path`]).
    pub params: Vec<SegmentParam>,
    /// The per-frame sampler.
    pub sampler: Sampler,
    /// What happened, and which path ran.
    pub report: SurfaceReport,
    /// Wall time per stage, in order.
    pub stages: Vec<(&'static str, Duration)>,
}

/// A preprocessing stage starting or finishing, reported to a caller's callback (the
/// engine does not log; an application shows progress from these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// A stage starts.
    Start(&'static str),
    /// A stage finished after this long.
    Done(&'static str, Duration),
}

impl Preprocessed {
    /// Preprocesses `mesh` for sampling: the planar fast path for a flat mesh, the
    /// surface pipeline otherwise (see the [module docs](self)).
    ///
    /// ```
    /// use std::sync::Arc;
    /// use strata_engine::{field::FieldSpec, mesh::shapes, surface};
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 };
    /// let plane = Arc::new(shapes::plane(1.0, 8)?);
    /// let field = Arc::new(spec.build(&plane)?);
    /// let pre = surface::Preprocessed::build(plane, field, &Default::default())?;
    /// assert!(pre.planar_map().is_some());
    /// let torus = Arc::new(shapes::torus(1.0, 0.4, 12)?);
    /// let field = Arc::new(spec.build(&torus)?);
    /// let pre = surface::Preprocessed::build(torus, field, &Default::default())?;
    /// assert!(pre.planar_map().is_none() && !pre.params.is_empty());
    /// assert_eq!(pre.sampler.sample(100, 1).len(), 100);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
    ) -> Result<Self, SurfaceError> {
        Self::build_with_progress(mesh, field, options, &|_| {})
    }

    /// As [`build`](Self::build), calling `progress` when each stage starts and ends
    /// (`"cells"` on the planar path; `"segmentation"`, `"parameterization"`,
    /// `"cells"` on the surface path).
    pub fn build_with_progress(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
        progress: &dyn Fn(Progress),
    ) -> Result<Self, SurfaceError> {
        options.validate()?;
        let t = Instant::now();
        let map = match planar::planar_map(&mesh, &field) {
            Ok(map) => map,
            Err(PlanarError::NotPlanar { .. }) => {
                return Self::surface(mesh, field, options, progress);
            }
            Err(e) => return Err(e.into()),
        };
        progress(Progress::Start("cells"));
        let sampler = planar::sampler_with_map(mesh, field, &map, &options.curve)?;
        let took = t.elapsed();
        progress(Progress::Done("cells", took));
        let report = SurfaceReport {
            path: PreprocessPath::Planar(map),
            segments_before_split: 1,
            segments: 1,
            cells: sampler
                .segments()
                .iter()
                .map(|s| s.curve.cell_count())
                .sum(),
            ..Default::default()
        };
        Ok(Self {
            segmentation: Segmentation {
                face_segment: Vec::new(),
                segments: Vec::new(),
                singularities: Vec::new(),
                cut_edges: Vec::new(),
            },
            params: Vec::new(),
            sampler,
            report,
            stages: vec![("cells", took)],
        })
    }

    /// The surface pipeline whatever the mesh, also on a flat one (to study the
    /// segmentation and splitting there, or a field that turns, for which the planar
    /// path's one linear map is not exact).
    pub fn build_surface(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
    ) -> Result<Self, SurfaceError> {
        options.validate()?;
        Self::surface(mesh, field, options, &|_| {})
    }

    /// The linear map of the planar path, `None` if the surface path ran.
    pub fn planar_map(&self) -> Option<&PlanarMap> {
        match &self.report.path {
            PreprocessPath::Planar(map) => Some(map),
            PreprocessPath::Surface => None,
        }
    }

    /// Segmentation, parameterization with splitting and cells (options validated).
    fn surface(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
        progress: &dyn Fn(Progress),
    ) -> Result<Self, SurfaceError> {
        let mut stages = Vec::new();
        let out = segment_surface(&mesh, field, options, progress, &mut stages)?;
        Self::after_segmentation(mesh, out.field, out.segmentation, options, progress, stages)
    }

    /// Parameterization with splitting and cells of a given segmentation (options
    /// validated), after the stages already timed in `stages`.
    fn after_segmentation(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segmentation: Segmentation,
        options: &SurfaceOptions,
        progress: &dyn Fn(Progress),
        mut stages: Vec<(&'static str, Duration)>,
    ) -> Result<Self, SurfaceError> {
        progress(Progress::Start("parameterization"));
        let t = Instant::now();
        let (params, mut report) =
            parameterize_with_splitting(&mesh, &field, &segmentation, options)?;
        report.segments_before_split = segmentation.segments.len();
        report.segments = params.len();
        record_stage(&mut stages, progress, "parameterization", t);

        progress(Progress::Start("cells"));
        let t = Instant::now();
        let inputs = cell_inputs(&mesh, &field, &params);
        let lowest: Vec<u32> = params.iter().map(lowest_face).collect();
        let total = total_measure(lowest.iter().copied().zip(inputs.iter().map(|c| c.measure)));
        let curves = build_cells(&params, &inputs, total, &options.curve)?;
        let segments = order_segments(
            lowest
                .iter()
                .zip(&params)
                .zip(curves)
                .map(|((&low, p), c)| (low, p.faces.clone(), Arc::new(c))),
        );
        report.cells = segments.iter().map(|s| s.curve.cell_count()).sum();
        record_stage(&mut stages, progress, "cells", t);
        let sampler = Sampler::new(mesh, field, segments)?;
        Ok(Self {
            segmentation,
            params,
            sampler,
            report,
            stages,
        })
    }

    /// As [`build_surface`](Self::build_surface), but with a given segmentation
    /// instead of the random walk's (for controlled experiments: a fixed number of
    /// segments, a boundary of a chosen shape). Invalid segments are still split, so
    /// the final segments may be more than given. Build `segmentation` with
    /// [`segmentation_from_labels`].
    ///
    /// ```
    /// use std::sync::Arc;
    /// use strata_engine::{field::FieldSpec, mesh::shapes, surface};
    /// let mesh = Arc::new(shapes::plane(1.0, 8)?);
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 };
    /// let field = Arc::new(spec.build(&mesh)?);
    /// // Left and right halves.
    /// let labels: Vec<u32> = (0..mesh.face_count() as u32)
    ///     .map(|f| (mesh.face_positions(f)[0].x + mesh.face_positions(f)[1].x
    ///         + mesh.face_positions(f)[2].x > 1.5) as u32)
    ///     .collect();
    /// let seg = surface::segmentation_from_labels(&mesh, &labels);
    /// let pre = surface::Preprocessed::from_segmentation(mesh, field, seg, &Default::default())?;
    /// assert_eq!(pre.params.len(), 2);
    /// assert_eq!(pre.sampler.sample(100, 1).len(), 100);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_segmentation(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segmentation: Segmentation,
        options: &SurfaceOptions,
    ) -> Result<Self, SurfaceError> {
        options.validate()?;
        Self::after_segmentation(mesh, field, segmentation, options, &|_| {}, Vec::new())
    }
}

/// Records the time since `start` of stage `name`, and reports it to `progress`.
fn record_stage(
    stages: &mut Vec<(&'static str, Duration)>,
    progress: &dyn Fn(Progress),
    name: &'static str,
    start: Instant,
) {
    let took = start.elapsed();
    progress(Progress::Done(name, took));
    stages.push((name, took));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::fixtures::torus_case;
    use crate::mesh::shapes;
    use crate::segment::segment;

    #[test]
    fn per_segment_parameterization_and_cells_equal_the_whole_build() {
        let (mesh, field) = torus_case();
        let options = SurfaceOptions::default();
        let pre = Preprocessed::build(mesh.clone(), field.clone(), &options).expect("build");
        let seg = &pre.segmentation;
        let context = SplitContext::new(&mesh, &field, &seg.cut_edges, &options);
        let mut pieces = Vec::new();
        for s in &seg.segments {
            let (p, _) =
                parameterize_segment_with_splitting(&mesh, &field, &context, &s.faces, &options)
                    .expect("segment");
            assert!(
                p.windows(2)
                    .all(|w| lowest_face(&w[0]) < lowest_face(&w[1]))
            );
            pieces.extend(p);
        }
        pieces.sort_by_key(lowest_face);
        assert_eq!(pieces.len(), pre.params.len());
        for (a, b) in pieces.iter().zip(&pre.params) {
            assert_eq!(a.faces, b.faces);
            assert_eq!(a.uv, b.uv);
        }
        let inputs: Vec<CellInput> = pieces
            .iter()
            .map(|p| CellInput::new(&mesh, &field, p))
            .collect();
        let total: f64 = inputs.iter().map(|c| c.measure).sum();
        // The cells' exact measures sum to the same total up to rounding.
        assert!((total / pre.sampler.total_measure() - 1.0).abs() < 1e-9);
        for ((p, c), s) in pieces.iter().zip(&inputs).zip(pre.sampler.segments()) {
            let curve = segment_cells(p, c, total, &options.curve).expect("cells");
            assert_eq!(curve.cell_count(), s.curve.cell_count());
            assert_eq!(curve.measure(), s.curve.measure());
        }
    }

    #[test]
    fn bad_options_are_errors_before_any_work() {
        let (mesh, field) = torus_case();
        let good = SurfaceOptions::default();
        let seg = segment(&mesh, &field, &good.segment).expect("segmentation");
        let zero = SurfaceOptions {
            min_segment_faces: 0,
            ..good
        };
        let mut bad_gamma = good;
        bad_gamma.param.gamma = -1.0;
        let bad_chart_angle = SurfaceOptions {
            chart_angle: 0.0,
            ..good
        };
        assert!(matches!(
            bad_chart_angle.validate(),
            Err(SurfaceError::InvalidChartAngle(_))
        ));
        for options in [zero, bad_gamma, bad_chart_angle] {
            assert!(Preprocessed::build(mesh.clone(), field.clone(), &options).is_err());
            assert!(
                Preprocessed::from_segmentation(mesh.clone(), field.clone(), seg.clone(), &options)
                    .is_err()
            );
        }
        assert!(matches!(
            zero.validate(),
            Err(SurfaceError::InvalidMinSegmentFaces)
        ));
    }

    #[test]
    fn a_flat_mesh_takes_the_planar_path_bit_for_bit() {
        let mesh = Arc::new(shapes::plane(1.0, 12).expect("plane"));
        let field = Arc::new(
            FieldSpec::Constant {
                direction: [1.0, 1.0, 0.0],
                anisotropy: 3.0,
                density: 2.0,
            }
            .build(&mesh)
            .expect("field"),
        );
        let options = SurfaceOptions::default();
        let seen = std::sync::Mutex::new(Vec::new());
        let record = |p: Progress| {
            if let Ok(mut seen) = seen.lock() {
                seen.push(p);
            }
        };
        let pre = Preprocessed::build_with_progress(mesh.clone(), field.clone(), &options, &record)
            .expect("build");
        let (sampler, map) =
            crate::planar::sampler(mesh.clone(), field.clone(), &options.curve).expect("planar");
        assert_eq!(pre.planar_map(), Some(&map));
        assert_eq!(pre.report.path, PreprocessPath::Planar(map));
        assert!(pre.params.is_empty() && pre.segmentation.segments.is_empty());
        assert_eq!(pre.report.segments, 1);
        assert_eq!(pre.report.cells, sampler.segments()[0].curve.cell_count());
        assert_eq!(pre.stages.len(), 1);
        assert_eq!(pre.stages[0].0, "cells");
        let seen = seen.into_inner().expect("progress");
        assert_eq!(seen.len(), 2);
        assert_eq!(seen[0], Progress::Start("cells"));
        for (n, seed) in [(1, 3), (777, 5), (20_000, 9)] {
            assert!(
                pre.sampler.sample(n, seed) == sampler.sample(n, seed),
                "{n} samples, seed {seed}"
            );
        }
        // The surface pipeline on the same plane is another result.
        let surface = Preprocessed::build_surface(mesh, field, &options).expect("surface");
        assert_eq!(surface.report.path, PreprocessPath::Surface);
        assert!(!surface.params.is_empty());
    }

    #[test]
    fn a_curved_mesh_takes_the_surface_path() {
        let (mesh, field) = torus_case();
        let options = SurfaceOptions::default();
        let pre = Preprocessed::build(mesh.clone(), field.clone(), &options).expect("build");
        assert_eq!(pre.report.path, PreprocessPath::Surface);
        assert!(pre.planar_map().is_none());
        assert!(pre.segmentation.segments.len() > 1);
        assert_eq!(pre.params.len(), pre.report.segments);
        let names: Vec<&str> = pre.stages.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names,
            [
                "isotropic directions",
                "segmentation",
                "parameterization",
                "cells"
            ]
        );
        let surface = Preprocessed::build_surface(mesh, field, &options).expect("surface");
        for (a, b) in surface.params.iter().zip(&pre.params) {
            assert_eq!(a.faces, b.faces);
        }
        assert!(surface.sampler.sample(5000, 2) == pre.sampler.sample(5000, 2));
    }
}
