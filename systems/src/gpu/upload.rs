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

use strata_engine::sample::{PoolChange, Sampler};

use super::context::{GpuContext, GpuError};
use super::expand::SiteExpander;
use super::lod::GpuLodPool;
use super::splat::SplatRenderer;
use crate::ecs::{EngineSystems, LodState, MeshData, SampleBuffer};

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
    /// The GPU copy of the streamed entity's level-of-detail pool, when it has one.
    lod: Option<LodStream>,
}

/// The GPU copy of one entity's [`LodState`] pool.
struct LodStream {
    entity: Entity,
    builds: u64,
    pool: GpuLodPool,
    expander: SiteExpander,
}

impl std::fmt::Debug for LodStream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LodStream")
            .field("entity", &self.entity)
            .field("builds", &self.builds)
            .field("entries", &self.pool.len())
            .finish()
    }
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
            lod: None,
        }
    }

    /// Entries of the streamed entity's level-of-detail pool on the GPU (0 without one).
    pub fn lod_entries(&self) -> usize {
        self.lod.as_ref().map_or(0, |l| l.pool.len())
    }

    /// The entity and sample-buffer generation now on the GPU.
    pub fn uploaded(&self) -> Option<(Entity, u64)> {
        self.uploaded
    }
}

/// Uploads the streamed mesh entity's samples when they changed since the last upload;
/// for an entity with a level-of-detail pool ([`LodState`]), sends the pool's new
/// entries and expands them instead ([`GpuLodPool::sync`]).
pub fn upload_samples(
    gpu: Option<ResMut<GpuSplats>>,
    meshes: Query<(Entity, &SampleBuffer, Option<&LodState>), With<MeshData>>,
) {
    let Some(mut gpu) = gpu else {
        return;
    };
    let target = match gpu.mesh {
        Some(e) => meshes.get(e).ok(),
        None => meshes.iter().min_by_key(|(e, ..)| *e),
    };
    let Some((entity, buffer, lod)) = target else {
        return;
    };
    if let Some(state) = lod.filter(|l| l.pool.is_some()) {
        // The pool's own sampler: a newer one may be building its pool meanwhile.
        if let Some(sampler) = state.drawn_from() {
            let t = Instant::now();
            match stream_lod(&mut gpu, entity, state, sampler) {
                Ok(bytes) => {
                    gpu.last = UploadStats {
                        count: (bytes / 20) as usize,
                        time: t.elapsed(),
                        uploads: gpu.last.uploads + u64::from(bytes > 0),
                    };
                    gpu.error = None;
                }
                Err(e) => gpu.error = Some(e),
            }
        }
        return;
    }
    // Nothing new, or nothing sampled yet (the first build still runs).
    if gpu.uploaded == Some((entity, buffer.generation)) || buffer.generation == 0 {
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

/// Brings the GPU copy of `entity`'s pool up to `state`, starting a new copy when the
/// entity or its pool's build changed; returns the bytes sent.
fn stream_lod(
    gpu: &mut GpuSplats,
    entity: Entity,
    state: &LodState,
    sampler: &Sampler,
) -> Result<u64, GpuError> {
    let Some(pool) = state.pool.as_ref() else {
        return Ok(0);
    };
    let (device, queue) = (&gpu.ctx.device, &gpu.ctx.queue);
    let current = gpu
        .lod
        .as_ref()
        .is_some_and(|l| l.entity == entity && l.builds == state.builds);
    if !current {
        gpu.lod = Some(LodStream {
            entity,
            builds: state.builds,
            pool: GpuLodPool::new(device, f64::from(pool.prefix()))?,
            expander: SiteExpander::new(device, sampler)?,
        });
    }
    let Some(stream) = gpu.lod.as_mut() else {
        return Ok(0);
    };
    // Entries are appended between builds, or the extension is rebuilt in place.
    let change = match &state.last {
        Some(PoolChange::Rebuilt) => PoolChange::Rebuilt,
        _ => PoolChange::Appended(stream.pool.len().min(pool.len())..pool.len()),
    };
    if stream.pool.len() == pool.len() && change != PoolChange::Rebuilt {
        return Ok(0);
    }
    stream.pool.sync(
        device,
        queue,
        pool,
        &change,
        &stream.expander,
        gpu.renderer.samples_mut(),
    )
}

/// Adds [`upload_samples`] to `schedule`, after the engine's sampling. The engine must
/// be registered ([`crate::ecs::register`]); insert a [`GpuSplats`] resource to start
/// streaming (without one the system does nothing).
pub fn register(schedule: &mut Schedule) {
    schedule.add_systems(upload_samples.after(EngineSystems::Sample));
}
