//! Which sampler draws the samples, the CPU's or the GPU's ([`SamplerBackend`], one
//! switch in [`EngineSettings`]), and the ECS systems that draw a mesh's samples on the
//! GPU when it says so.
//!
//! [`resolve`] turns the choice into the sampler used on an adapter:
//! [`SamplerBackend::Auto`] is the GPU on a real GPU (discrete, integrated or virtual)
//! and the CPU on a software adapter (`DeviceType::Cpu`: llvmpipe, lavapipe, WARP) or
//! without an adapter; [`SamplerBackend::Gpu`] is the GPU on any adapter (the software
//! adapter included, which is how the tests run it) and an error without one.
//!
//! In the engine ([`register`]): [`choose_sampler`] runs before the CPU sampling and
//! names the streamed mesh entity in [`GpuSampled`] when the GPU draws it (the CPU's
//! `sample_meshes` then leaves its [`SampleBuffer`](crate::ecs::SampleBuffer) alone);
//! [`sample_on_gpu`] runs after the upload system and records the frame's resample as
//! compute passes ([`GpuSampler::sample`]: the stratified sites, then their records)
//! straight into the [`GpuSplats`] renderer's sample buffer. The CPU's frame cost is
//! then O(segments), whatever the count: the per-segment counts and the request's
//! uniforms, no per-sample work and no per-sample upload. Level of detail
//! ([`Lod`]) and a mesh placed by a transform other than the identity
//! keep the CPU sampler (the progressive pool is drawn on the CPU; the GPU's records
//! have the untransformed spacings).

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;

use super::sample::GpuSampler;
use super::upload::{GpuSplats, upload_samples};
use crate::ecs::{
    EngineError, EngineErrors, EngineSettings, EngineSystems, GpuSampled, Lod, MeshData,
    MeshSampler, MeshTransform, SampleRequest, SamplerBackend, SamplingSettings, Stage, StageStats,
    sample_meshes,
};

/// Whether `info` names a real GPU (discrete, integrated or virtual), not a software
/// rasterizer on the CPU or an adapter of unknown kind.
pub fn is_hardware(info: &wgpu::AdapterInfo) -> bool {
    matches!(
        info.device_type,
        wgpu::DeviceType::DiscreteGpu
            | wgpu::DeviceType::IntegratedGpu
            | wgpu::DeviceType::VirtualGpu
    )
}

/// The sampler that draws the samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UsedSampler {
    /// `Sampler::sample_into` on the CPU, the reference.
    Cpu,
    /// The compute passes of [`GpuSampler`].
    Gpu,
}

/// The sampler a [`SamplerBackend`] resolved to, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerUse {
    /// The sampler used.
    pub used: UsedSampler,
    /// Why: `"forced"`, or the adapter kind that decided `auto`.
    pub why: &'static str,
}

impl SamplerUse {
    /// Whether the GPU draws the samples.
    pub fn is_gpu(self) -> bool {
        self.used == UsedSampler::Gpu
    }
}

impl std::fmt::Display for SamplerUse {
    /// `sampler gpu (forced)`, `sampler cpu (auto: software adapter)`, ...
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self.used {
            UsedSampler::Cpu => "cpu",
            UsedSampler::Gpu => "gpu",
        };
        write!(f, "sampler {name} ({})", self.why)
    }
}

/// GPU sampling asked for where it cannot run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BackendError {
    /// `gpu` was forced and no GPU adapter is open.
    #[error(
        "sampler gpu needs a GPU adapter and none is open (use sampler auto or cpu to sample on the CPU)"
    )]
    NoAdapter,
}

/// The sampler `choice` uses on `adapter` (`None`: no adapter could be opened); see the
/// [module docs](self).
pub fn resolve(
    choice: SamplerBackend,
    adapter: Option<&wgpu::AdapterInfo>,
) -> Result<SamplerUse, BackendError> {
    let (used, why) = match (choice, adapter) {
        (SamplerBackend::Cpu, _) => (UsedSampler::Cpu, "forced"),
        (SamplerBackend::Gpu, Some(_)) => (UsedSampler::Gpu, "forced"),
        (SamplerBackend::Gpu, None) => return Err(BackendError::NoAdapter),
        (SamplerBackend::Auto, None) => (UsedSampler::Cpu, "auto: no GPU adapter"),
        (SamplerBackend::Auto, Some(info)) if is_hardware(info) => {
            (UsedSampler::Gpu, "auto: hardware adapter")
        }
        (SamplerBackend::Auto, Some(_)) => (UsedSampler::Cpu, "auto: software adapter"),
    };
    Ok(SamplerUse { used, why })
}

/// What one GPU resample cost the CPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuFrame {
    /// Samples drawn.
    pub count: usize,
    /// CPU time to record and submit the passes (the GPU runs them afterwards).
    pub record: Duration,
    /// GPU resamples so far.
    pub frames: u64,
}

/// The engine's GPU sampling state: the resolved choice and the GPU sampler of the
/// streamed mesh entity. [`register`] adds it.
#[derive(Resource, Debug, Default)]
pub struct GpuSampling {
    /// What [`EngineSettings::sampler`] resolved to on the open device (`None` before
    /// the first update).
    pub used: Option<SamplerUse>,
    /// The last GPU resample.
    pub last: GpuFrame,
    /// The choice and whether a device was open when `used` was resolved.
    resolved_for: Option<(SamplerBackend, bool)>,
    /// The GPU sampler of the entity the GPU draws.
    sampler: Option<(Entity, GpuSampler)>,
    /// `(entity, count, seed)` of the samples in the renderer's buffer.
    drawn: Option<(Entity, usize, u64)>,
}

impl GpuSampling {
    /// The GPU sampler of the mesh entity the GPU draws, once it drew.
    pub fn sampler(&self) -> Option<&GpuSampler> {
        self.sampler.as_ref().map(|(_, s)| s)
    }
}

/// The mesh entity [`GpuSplats`] streams (its `mesh`, else the lowest mesh entity),
/// with what decides whether the GPU may draw it.
type Target<'a> = (
    Entity,
    Ref<'a, MeshSampler>,
    Ref<'a, SamplingSettings>,
    &'a MeshTransform,
    Has<Lod>,
);

/// Resolves [`EngineSettings::sampler`] on the open device (when the setting or the
/// device's presence changed; a forced `gpu` without a device is reported in
/// [`EngineErrors`] once, and the CPU keeps drawing) and names in [`GpuSampled`] the
/// mesh entity the GPU draws.
pub fn choose_sampler(
    settings: Res<EngineSettings>,
    gpu: Option<Res<GpuSplats>>,
    mut state: ResMut<GpuSampling>,
    mut on_gpu: ResMut<GpuSampled>,
    mut errors: ResMut<EngineErrors>,
    meshes: Query<Target<'_>, With<MeshData>>,
) {
    let key = (settings.sampler, gpu.is_some());
    if state.resolved_for != Some(key) {
        let info = gpu.as_ref().map(|g| g.ctx.adapter.get_info());
        state.used = Some(
            resolve(settings.sampler, info.as_ref()).unwrap_or_else(|e| {
                errors.0.push(EngineError::GpuSampling(e.to_string()));
                SamplerUse {
                    used: UsedSampler::Cpu,
                    why: "gpu forced without an adapter",
                }
            }),
        );
        state.resolved_for = Some(key);
    }
    let target = gpu
        .filter(|_| state.used.is_some_and(SamplerUse::is_gpu))
        .and_then(|gpu| match gpu.mesh {
            Some(e) => meshes.get(e).ok(),
            None => meshes.iter().min_by_key(|t| t.0),
        });
    let drawn_here = target.filter(|(_, sampler, _, transform, lod)| {
        sampler.0.is_some() && !lod && transform.0 == glam::DAffine3::IDENTITY
    });
    let entity = drawn_here.map(|t| t.0);
    on_gpu.set_if_neq(GpuSampled(entity));
    if entity.is_none() {
        // Frees the GPU tables; a later switch back builds them again.
        state.sampler = None;
        state.drawn = None;
    }
}

/// Draws the [`GpuSampled`] entity's samples on the GPU into the [`GpuSplats`]
/// renderer's buffer when its sampler, count or seed changed, on [`SampleRequest`], or
/// every update with [`EngineSettings::sample_every_update`]. A failure is reported
/// in [`EngineErrors`] and the last samples stay on the GPU.
#[allow(clippy::too_many_arguments)]
pub fn sample_on_gpu(
    settings: Res<EngineSettings>,
    request: Res<SampleRequest>,
    on_gpu: Res<GpuSampled>,
    gpu: Option<ResMut<GpuSplats>>,
    mut state: ResMut<GpuSampling>,
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    meshes: Query<(Ref<MeshSampler>, Ref<SamplingSettings>)>,
) {
    let (Some(entity), Some(mut gpu)) = (on_gpu.0, gpu) else {
        return;
    };
    let Ok((sampler, sampling)) = meshes.get(entity) else {
        return;
    };
    let Some(cpu_sampler) = sampler.0.as_ref() else {
        return;
    };
    let state = &mut *state;
    let gpu = &mut *gpu;
    let (device, queue) = (&gpu.ctx.device, &gpu.ctx.queue);
    let stale = state.sampler.as_ref().is_none_or(|(e, _)| *e != entity) || sampler.is_changed();
    if stale {
        state.drawn = None;
        match GpuSampler::new(device, cpu_sampler) {
            Ok(s) => state.sampler = Some((entity, s)),
            Err(e) => {
                state.sampler = None;
                errors.0.push(EngineError::GpuSampling(e.to_string()));
                return;
            }
        }
    }
    let Some((_, gpu_sampler)) = state.sampler.as_mut() else {
        return;
    };
    let (count, seed) = (sampling.count, sampling.seed);
    let forced = settings.sample_every_update || request.0;
    if !forced && state.drawn == Some((entity, count, seed)) {
        return;
    }
    let max = super::buffers::max_samples(device);
    if count > max {
        let e = format!("{count} samples do not fit in one GPU buffer (at most {max})");
        errors.0.push(EngineError::GpuSampling(e));
        return;
    }
    let t = Instant::now();
    // A resample the GPU sampler submits without error scopes (its bindings were
    // checked before) reports an error through the device's uncaptured-error sink.
    let drawn = gpu_sampler
        .sample(device, queue, count, seed, gpu.renderer.samples_mut())
        .and_then(|()| gpu.ctx.take_uncaptured("sampling on the GPU"));
    let record = t.elapsed();
    match drawn {
        Ok(()) => {
            state.drawn = Some((entity, count, seed));
            state.last = GpuFrame {
                count,
                record,
                frames: state.last.frames + 1,
            };
            stats.record(Stage::Sampling, entity, count, record, String::new());
        }
        Err(e) => {
            state.drawn = None;
            errors.0.push(EngineError::GpuSampling(e.to_string()));
        }
    }
}

/// Adds [`choose_sampler`] (before the CPU's `sample_meshes`) and [`sample_on_gpu`]
/// (after [`upload_samples`], so that a CPU upload of the same entity never lands over
/// the GPU's samples) to `schedule`, with the [`GpuSampling`] resource. The engine
/// ([`crate::ecs::register`]) and the upload ([`super::upload::register`]) must be
/// registered; the GPU draws once a [`GpuSplats`] resource is inserted and
/// [`EngineSettings::sampler`] resolves to it.
pub fn register(world: &mut World, schedule: &mut Schedule) {
    world.init_resource::<GpuSampling>();
    schedule.add_systems((
        choose_sampler
            .in_set(EngineSystems::Sample)
            .before(sample_meshes),
        sample_on_gpu
            .after(EngineSystems::Sample)
            .after(upload_samples),
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(device_type: wgpu::DeviceType) -> wgpu::AdapterInfo {
        wgpu::AdapterInfo::new(device_type, wgpu::Backend::Vulkan)
    }

    /// Auto picks the GPU on real GPUs only; forced choices hold on any adapter; a
    /// forced GPU without an adapter is an error.
    #[test]
    fn choices_resolve_by_adapter_kind() {
        use wgpu::DeviceType as D;
        let used = |c, a: Option<&wgpu::AdapterInfo>| resolve(c, a).map(|u| u.used).ok();
        for (kind, auto) in [
            (D::DiscreteGpu, UsedSampler::Gpu),
            (D::IntegratedGpu, UsedSampler::Gpu),
            (D::VirtualGpu, UsedSampler::Gpu),
            (D::Cpu, UsedSampler::Cpu),
            (D::Other, UsedSampler::Cpu),
        ] {
            let info = adapter(kind);
            assert_eq!(
                used(SamplerBackend::Auto, Some(&info)),
                Some(auto),
                "{kind:?}"
            );
            assert_eq!(
                used(SamplerBackend::Cpu, Some(&info)),
                Some(UsedSampler::Cpu)
            );
            assert_eq!(
                used(SamplerBackend::Gpu, Some(&info)),
                Some(UsedSampler::Gpu)
            );
        }
        assert_eq!(used(SamplerBackend::Auto, None), Some(UsedSampler::Cpu));
        assert_eq!(used(SamplerBackend::Cpu, None), Some(UsedSampler::Cpu));
        let e = resolve(SamplerBackend::Gpu, None).expect_err("no adapter");
        assert!(e.to_string().contains("needs a GPU adapter"), "{e}");
        let line = resolve(SamplerBackend::Auto, Some(&adapter(D::Cpu)))
            .expect("resolves")
            .to_string();
        assert_eq!(line, "sampler cpu (auto: software adapter)");
    }
}
