//! Components of the streaming engine: a mesh entity holds the mesh, its field, its
//! settings, the assembled sampler (segments linked into chains) and the current
//! samples; one entity per segment holds the segment's faces, parameterizations and
//! cells, and a link to its mesh.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use strata_engine::curve::{CurveOptions, SegmentCurve};
use strata_engine::field::TensorField;
use strata_engine::mesh::TriMesh;
use strata_engine::param::SegmentParam;
use strata_engine::sample::{Sample, Sampler};
use strata_engine::surface::{CellInput, SurfaceOptions, SurfaceReport};

/// The mesh of a mesh entity. Replacing it reruns everything downstream (segments
/// whose content hash is unchanged keep their parameterizations and cells).
#[derive(Component, Clone, Debug)]
pub struct MeshData(pub Arc<TriMesh>);

/// The tensor field on the mesh. Replacing it re-segments only the segments that hold
/// a vertex whose tensor changed (see [`segment_meshes`](super::preprocess::segment_meshes)).
#[derive(Component, Clone, Debug)]
pub struct FieldData(pub Arc<TensorField>);

/// Sample count and seed of a mesh entity. Changing them reruns sampling only.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplingSettings {
    /// Samples drawn per update.
    pub count: usize,
    /// Random seed of the stratified sequence.
    pub seed: u64,
}

/// Segmentation and parameterization settings of a mesh entity (its `curve` part is
/// ignored: cells follow [`CurveSettings`]). Changing them re-segments the mesh.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct PreprocessSettings(pub SurfaceOptions);

impl PreprocessSettings {
    /// The settings of `options` with its `curve` part reset to the default, so that
    /// a change of the cell settings alone does not look like a change of these.
    pub fn new(options: SurfaceOptions) -> Self {
        Self(SurfaceOptions {
            curve: Default::default(),
            ..options
        })
    }
}

/// Cell settings (the curve refinement, omega). Changing them rebuilds every segment's
/// cells and resamples, nothing before.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct CurveSettings(pub CurveOptions);

/// Where the mesh lies in the world; applied to the samples (positions, normals and
/// axes; spacings scaled), so changing it reruns sampling only.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct MeshTransform(pub glam::DAffine3);

impl Default for MeshTransform {
    fn default() -> Self {
        Self(glam::DAffine3::IDENTITY)
    }
}

/// What the last segmentation of a mesh entity was computed from, so that the next
/// change can be compared with it.
#[derive(Component, Clone, Debug, Default)]
pub struct SegmentationState {
    /// The mesh segmented.
    pub mesh: Option<Arc<TriMesh>>,
    /// The field segmented.
    pub field: Option<Arc<TensorField>>,
    /// The settings used.
    pub settings: Option<PreprocessSettings>,
}

impl SegmentationState {
    /// Whether the segments were computed on `mesh` (false after a segmentation of a
    /// new mesh failed: the old segments then must not be used with it).
    pub fn segments_current(&self, mesh: &MeshData) -> bool {
        self.mesh.as_ref().is_some_and(|m| Arc::ptr_eq(m, &mesh.0))
    }
}

/// The sampler of a mesh entity: all its segments' cells, in the engine's segment
/// order, linked into chains. `None` until the first segments have cells.
#[derive(Component, Debug, Default)]
pub struct MeshSampler(pub Option<Sampler>);

/// The current samples of a mesh entity, rewritten by sampling.
#[derive(Component, Clone, Debug, Default)]
pub struct SampleBuffer {
    /// The samples (exactly the configured count once sampled).
    pub samples: Vec<Sample>,
    /// How many times the buffer has been rewritten.
    pub generation: u64,
}

/// The components a mesh entity needs; spawn it with [`MeshBundle::new`].
#[derive(Bundle)]
pub struct MeshBundle {
    /// The mesh.
    pub mesh: MeshData,
    /// The field.
    pub field: FieldData,
    /// Segmentation and parameterization settings.
    pub preprocess: PreprocessSettings,
    /// Cell settings.
    pub curve: CurveSettings,
    /// Sample count and seed.
    pub sampling: SamplingSettings,
    /// Placement.
    pub transform: MeshTransform,
    /// Bookkeeping of the last segmentation.
    pub state: SegmentationState,
    /// The assembled sampler.
    pub sampler: MeshSampler,
    /// The samples.
    pub samples: SampleBuffer,
}

impl MeshBundle {
    /// A mesh entity for `mesh` with `field`, preprocessed with `options` (cells with
    /// `options.curve`) and sampled `count` times with `seed`.
    pub fn new(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: SurfaceOptions,
        count: usize,
        seed: u64,
    ) -> Self {
        Self {
            mesh: MeshData(mesh),
            field: FieldData(field),
            preprocess: PreprocessSettings::new(options),
            curve: CurveSettings(options.curve),
            sampling: SamplingSettings { count, seed },
            transform: MeshTransform::default(),
            state: SegmentationState::default(),
            sampler: MeshSampler::default(),
            samples: SampleBuffer::default(),
        }
    }
}

/// One segment of a mesh: a connected set of faces that the segmentation made a disc.
/// Its `hash` covers everything its parameterization depends on (faces, their vertex
/// positions and tensors, cut edges, settings); a re-segmentation that produces a
/// segment with the same hash keeps the existing entity and its results.
#[derive(Component, Clone, Debug)]
pub struct SegmentFaces {
    /// The mesh entity it belongs to.
    pub mesh: Entity,
    /// Its faces (mesh face ids, ascending).
    pub faces: Vec<u32>,
    /// Cut edges of the segmentation that touch its faces (the walk and the
    /// parameterization treat them as boundary).
    pub cut_edges: Vec<u32>,
    /// Content hash (see the type docs).
    pub hash: u64,
}

/// The parameterizations of a segment: one per piece it was split into while invalid
/// (usually one).
#[derive(Component, Clone, Debug, Default)]
pub struct SegmentParams {
    /// The pieces, ordered by their lowest face.
    pub pieces: Vec<SegmentParam>,
    /// Splits and fallbacks that happened.
    pub report: SurfaceReport,
}

/// The cells of a segment's pieces (one [`SegmentCurve`] per piece).
#[derive(Component, Clone, Debug, Default)]
pub struct SegmentCells {
    /// Per piece: unit-square layout, corner densities and measure.
    pub inputs: Vec<CellInput>,
    /// Per piece: the adaptive Hilbert cells (shared with the mesh's sampler).
    pub curves: Vec<Arc<SegmentCurve>>,
}

/// The components a segment entity starts with.
#[derive(Bundle)]
pub struct SegmentBundle {
    /// Faces, link to the mesh, hash.
    pub faces: SegmentFaces,
    /// Filled by parameterization.
    pub params: SegmentParams,
    /// Filled by the curve stage.
    pub cells: SegmentCells,
}
