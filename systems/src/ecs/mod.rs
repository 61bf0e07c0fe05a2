//! The streaming engine as a bevy_ecs world: meshes, segments, parameterizations and
//! cells are components; systems with change detection redo only what a change of the
//! mesh, the field or the settings invalidated (DESIGN.md, "Architecture"), as builds
//! off the frame ([`jobs`]) while the last good sampler keeps drawing.
//!
//! Embedding: call [`register`] on a caller's `World` and `Schedule` (or add
//! [`StrataPlugin`](crate::StrataPlugin) to a Bevy app), spawn a mesh entity with
//! [`MeshBundle`], run the schedule every frame; the samples appear in the entity's
//! [`SampleBuffer`] once its first build finished ([`settle`] runs updates until then).
//! Per-stage runs are recorded in [`StageStats`], errors in [`EngineErrors`], running
//! builds in [`PreprocessProgress`]. Scene files and hot reload: [`crate::hot_reload`].
//!
//! ```
//! use std::sync::Arc;
//! use bevy_ecs::prelude::*;
//! use strata_engine::{field::FieldSpec, mesh::shapes, surface::SurfaceOptions};
//! use strata_systems::ecs::{self, MeshBundle, SampleBuffer, Stage, StageStats};
//! let mesh = Arc::new(shapes::sphere(1.0, 4)?);
//! let field = Arc::new(FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
//!     .build(&mesh)?);
//! let mut world = World::new();
//! let mut schedule = Schedule::default();
//! ecs::register(&mut world, &mut schedule);
//! let e = world.spawn(MeshBundle::new(mesh, field, SurfaceOptions::default(), 500, 7)).id();
//! schedule.run(&mut world); // starts the build; the buffer is empty until it is done
//! assert!(ecs::settle(&mut world, &mut schedule, std::time::Duration::from_secs(60)));
//! assert_eq!(world.get::<SampleBuffer>(e).map(|b| b.samples.len()), Some(500));
//! assert_eq!(world.resource::<StageStats>().runs_of(Stage::Segmentation), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod components;
pub mod jobs;
pub mod lod;
pub mod sampling;
pub mod stats;

use bevy_ecs::prelude::*;

pub use components::*;
pub use jobs::{
    JobCounts, JobStatus, PreprocessJobs, PreprocessMode, PreprocessProgress, apply_builds,
    launch_builds, preprocess_pool, report_progress, settle,
};
pub use lod::{Lod, LodState, update_lod_pools};
pub use sampling::{GpuSampled, SampleRequest, sample_meshes};
pub use stats::{EngineErrors, Stage, StageRun, StageStats};

/// The engine's systems, in the order they run in an update.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EngineSystems {
    /// Bookkeeping at the start of an update.
    Begin,
    /// Applying changed scene files ([`crate::hot_reload`]).
    ApplyScene,
    /// Starting builds for changed meshes ([`launch_builds`]).
    Launch,
    /// Applying finished builds: segment entities and samplers ([`apply_builds`]).
    Apply,
    /// Sampling into the sample buffers.
    Sample,
}

/// Global settings of the engine.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct EngineSettings {
    /// Where builds run: off the frame (the default) or inside the update.
    pub preprocess: PreprocessMode,
    /// Resample every update even when nothing changed (per-frame LOD, renderers that
    /// consume the buffer); default false: sample when something changed or on
    /// [`SampleRequest`].
    pub sample_every_update: bool,
    /// Which sampler draws the samples: the CPU's (`Sampler::sample_into` into the
    /// [`SampleBuffer`]) or the GPU's compute passes, straight into the renderer's
    /// buffer ([`crate::gpu::backend`]). Default [`SamplerBackend::Auto`].
    pub sampler: SamplerBackend,
}

/// Which sampler draws a frame's samples ([`EngineSettings::sampler`], the `--sampler`
/// flag of `strata view` and `strata render`). The CPU sampler is the reference and the
/// fallback; the GPU draws the same samples (the same face and segment, positions
/// within `f32` round-off) with no per-sample work or upload on the CPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum SamplerBackend {
    /// The GPU when the adapter is a real GPU (discrete, integrated or virtual), the
    /// CPU on a software adapter (llvmpipe, lavapipe, WARP) and without a GPU.
    #[default]
    Auto,
    /// Always the CPU.
    Cpu,
    /// Always the GPU, the software adapter included; an error without any adapter.
    Gpu,
}

/// An error of one of the engine's stages; the state it would have changed is kept.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EngineError {
    /// A scene file could not be read, parsed or validated.
    #[error("{0}")]
    Config(#[from] crate::config::ConfigError),
    /// The scene's mesh could not be loaded or built.
    #[error("mesh: {0}")]
    Mesh(#[from] strata_engine::mesh::MeshError),
    /// The scene's field could not be built.
    #[error("field: {0}")]
    Field(#[from] strata_engine::field::FieldError),
    /// Segmentation failed.
    #[error("segmentation: {0}")]
    Segment(#[from] strata_engine::segment::SegmentError),
    /// Parameterization or its splitting failed.
    #[error("{0}")]
    Surface(#[from] strata_engine::surface::SurfaceError),
    /// Cells could not be built.
    #[error("cells: {0}")]
    Curve(#[from] strata_engine::curve::CurveError),
    /// The sampler could not be assembled.
    #[error("sampler: {0}")]
    Sample(#[from] strata_engine::sample::SampleError),
    /// The scene asks for more samples than memory holds.
    #[error("sampling: {0}")]
    Budget(#[from] crate::budget::BudgetError),
    /// A level of detail that cannot apply (a mesh placed by a transform that is not a
    /// similarity).
    #[error("{0}")]
    Lod(#[from] strata_engine::sample::lod::LodError),
    /// GPU sampling was asked for and cannot run (no device, or the device refused);
    /// the CPU sampler keeps drawing.
    #[error("GPU sampling: {0}")]
    GpuSampling(String),
}

/// Adds the engine's resources to `world` and its systems to `schedule`, ordered by
/// [`EngineSystems`]. Call once; works with any `Schedule`. A Bevy app (same bevy_ecs
/// version) keeps its schedules in the world: register with
/// `world.schedule_scope(Update, |world, schedule| register(world, schedule))`.
pub fn register(world: &mut World, schedule: &mut Schedule) {
    world.init_resource::<StageStats>();
    world.init_resource::<EngineErrors>();
    world.init_resource::<EngineSettings>();
    world.init_resource::<SampleRequest>();
    world.init_resource::<GpuSampled>();
    world.init_resource::<PreprocessJobs>();
    world.init_resource::<PreprocessProgress>();
    schedule.configure_sets(
        (
            EngineSystems::Begin,
            EngineSystems::ApplyScene,
            EngineSystems::Launch,
            EngineSystems::Apply,
            EngineSystems::Sample,
        )
            .chain(),
    );
    schedule.add_systems((
        stats::begin_update.in_set(EngineSystems::Begin),
        launch_builds.in_set(EngineSystems::Launch),
        (apply_builds, report_progress)
            .chain()
            .in_set(EngineSystems::Apply),
        (sample_meshes, update_lod_pools).in_set(EngineSystems::Sample),
    ));
}
