//! Components of the streaming engine: a mesh entity holds the mesh, its field, its
//! settings, the assembled sampler (segments linked into chains) and the current
//! samples; one entity per segment holds the segment's faces, parameterizations and
//! cells (shared with the engine's build state), related to its mesh by [`SegmentOf`].

use std::sync::Arc;

use bevy_ecs::prelude::*;
use strata_engine::curve::CurveOptions;
use strata_engine::field::TensorField;
use strata_engine::mesh::TriMesh;
use strata_engine::sample::{Sample, Sampler};
use strata_engine::surface::SegmentationKind;
use strata_engine::surface::SurfaceOptions;
use strata_engine::surface::incremental::{
    BuildInputs, BuiltSegment, SegmentCurves, SegmentCut, SegmentPieces,
};

/// The mesh of a mesh entity. Replacing it reruns everything downstream (segments
/// whose content hash is unchanged keep their parameterizations and cells).
#[derive(Component, Clone, Debug)]
pub struct MeshData(pub Arc<TriMesh>);

/// The tensor field on the mesh. Replacing it re-segments only the segments that hold
/// a vertex whose tensor changed ([`strata_engine::surface::incremental`]).
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

/// What the last completed build of a mesh entity was computed from: the base that the
/// next build compares a change with. `None` until a build completed.
#[derive(Component, Clone, Debug, Default)]
pub struct SurfaceBase(pub Option<LastBuild>);

/// The inputs and prepared field of a completed build (the segments are the mesh's
/// segment entities, the chains its sampler's).
#[derive(Clone, Debug)]
pub struct LastBuild {
    /// Mesh, field and settings built.
    pub inputs: BuildInputs,
    /// The field the surface path worked with.
    pub working_field: Arc<TensorField>,
    /// Charts or field-aligned segments.
    pub kind: SegmentationKind,
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
    /// What the last build was computed from.
    pub base: SurfaceBase,
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
            base: SurfaceBase::default(),
            sampler: MeshSampler::default(),
            samples: SampleBuffer::default(),
        }
    }
}

/// Links a segment entity to its mesh entity (a bevy_ecs relationship: the mesh holds
/// the reverse list in [`Segments`], and despawning the mesh despawns its segments).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = Segments)]
pub struct SegmentOf(pub Entity);

/// The segment entities of a mesh entity, kept by bevy_ecs from their [`SegmentOf`].
#[derive(Component, Debug, Default)]
#[relationship_target(relationship = SegmentOf, linked_spawn)]
pub struct Segments(Vec<Entity>);

/// One segment of a mesh: a connected set of faces that the segmentation made a disc,
/// with the cut edges that touch it and its content key
/// ([`segment_key`](strata_engine::surface::incremental::segment_key): a later
/// build that produces a segment with the same key keeps this entity and its results).
#[derive(Component, Clone, Debug)]
pub struct SegmentFaces(pub Arc<SegmentCut>);

/// The parameterizations of a segment: one per piece it was split into while invalid
/// (usually one), with its cells' inputs.
#[derive(Component, Clone, Debug)]
pub struct SegmentParams(pub Arc<SegmentPieces>);

/// The cells of a segment's pieces (one
/// [`SegmentCurve`](strata_engine::curve::SegmentCurve) per piece, shared with the
/// mesh's sampler).
#[derive(Component, Clone, Debug)]
pub struct SegmentCells(pub Arc<SegmentCurves>);

macro_rules! deref_to {
    ($component:ty, $target:ty) => {
        impl std::ops::Deref for $component {
            type Target = $target;
            fn deref(&self) -> &$target {
                &self.0
            }
        }
    };
}
deref_to!(SegmentFaces, SegmentCut);
deref_to!(SegmentParams, SegmentPieces);
deref_to!(SegmentCells, SegmentCurves);

/// The components a segment entity is spawned with.
#[derive(Bundle)]
pub struct SegmentBundle {
    /// Its mesh.
    pub of: SegmentOf,
    /// Faces, cut edges, key.
    pub faces: SegmentFaces,
    /// Parameterized pieces.
    pub params: SegmentParams,
    /// Cells.
    pub cells: SegmentCells,
}

impl SegmentBundle {
    /// The entity of segment `s` of mesh entity `mesh`.
    pub fn new(mesh: Entity, s: &BuiltSegment) -> Self {
        Self {
            of: SegmentOf(mesh),
            faces: SegmentFaces(s.cut.clone()),
            params: SegmentParams(s.pieces.clone()),
            cells: SegmentCells(s.curves.clone()),
        }
    }

    /// The engine's view of a segment entity's components.
    pub fn built(
        faces: &SegmentFaces,
        params: &SegmentParams,
        cells: &SegmentCells,
    ) -> BuiltSegment {
        BuiltSegment {
            cut: faces.0.clone(),
            pieces: params.0.clone(),
            curves: cells.0.clone(),
        }
    }
}
