//! The per-frame ECS system that streams the engine's samples into the GPU.
//!
//! The engine's `sample_meshes` system ([`crate::ecs::sampling`]) fills each mesh
//! entity's CPU-side [`SampleBuffer`]; [`upload_samples`],
//! running after it, copies the buffer of one mesh entity into the [`SplatRenderer`]'s
//! [`GpuSampleBuffer`](super::GpuSampleBuffer) whenever it was rewritten (its `generation` moved). The upload goes
//! through the renderer's staging ring and never waits on the GPU, so the CPU does not
//! stall on the previous frame. Drawing stays with the caller (a window or a headless
//! target), which reads the renderer from the [`GpuSplats`] resource.

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;

use super::context::{GpuContext, GpuError};
use super::splat::SplatRenderer;
use crate::ecs::{EngineSystems, MeshData, SampleBuffer};

/// The GPU side of the engine: the device and the renderer whose sample buffer
/// [`upload_samples`] keeps current.
#[derive(Resource)]
pub struct GpuSplats {
    /// The device and queue.
    pub ctx: GpuContext,
    /// The pipelines and the sample buffer.
    pub renderer: SplatRenderer,
    /// The mesh entity whose samples are streamed; `None`: the lowest mesh entity.
    pub mesh: Option<Entity>,
    /// What the last upload did.
    pub last: UploadStats,
    /// The error of the last failed upload (the previous samples stay on the GPU).
    pub error: Option<GpuError>,
    /// `(entity, generation)` of the samples on the GPU.
    uploaded: Option<(Entity, u64)>,
}

/// What [`upload_samples`] did in its last upload.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UploadStats {
    /// Samples uploaded.
    pub count: usize,
    /// Wall time of the copy into staging memory and the recorded buffer copy.
    pub time: Duration,
    /// Uploads so far.
    pub uploads: u64,
}

impl GpuSplats {
    /// Streams into `renderer` on `ctx`.
    pub fn new(ctx: GpuContext, renderer: SplatRenderer) -> Self {
        Self {
            ctx,
            renderer,
            mesh: None,
            last: UploadStats::default(),
            error: None,
            uploaded: None,
        }
    }

    /// The entity and sample-buffer generation now on the GPU.
    pub fn uploaded(&self) -> Option<(Entity, u64)> {
        self.uploaded
    }
}

/// Uploads the streamed mesh entity's samples when they changed since the last upload.
pub fn upload_samples(
    gpu: Option<ResMut<GpuSplats>>,
    meshes: Query<(Entity, &SampleBuffer), With<MeshData>>,
) {
    let Some(mut gpu) = gpu else {
        return;
    };
    let target = match gpu.mesh {
        Some(e) => meshes.get(e).ok(),
        None => meshes.iter().min_by_key(|(e, _)| *e),
    };
    let Some((entity, buffer)) = target else {
        return;
    };
    if gpu.uploaded == Some((entity, buffer.generation)) {
        return;
    }
    let t = Instant::now();
    let gpu = &mut *gpu;
    match gpu
        .renderer
        .upload(&gpu.ctx.device, &gpu.ctx.queue, &buffer.samples)
    {
        Ok(()) => {
            gpu.uploaded = Some((entity, buffer.generation));
            gpu.last = UploadStats {
                count: buffer.samples.len(),
                time: t.elapsed(),
                uploads: gpu.last.uploads + 1,
            };
            gpu.error = None;
        }
        Err(e) => gpu.error = Some(e),
    }
}

/// Adds [`upload_samples`] to `schedule`, after the engine's sampling. The engine must
/// be registered ([`crate::ecs::register`]); insert a [`GpuSplats`] resource to start
/// streaming (without one the system does nothing).
pub fn register(schedule: &mut Schedule) {
    schedule.add_systems(upload_samples.after(EngineSystems::Sample));
}
