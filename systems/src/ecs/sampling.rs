//! Sampling: draws each mesh's samples into its [`SampleBuffer`] when its sampler,
//! count, seed or transform changed, on demand ([`SampleRequest`]), or every update
//! when [`EngineSettings::sample_every_update`] is set. A mesh entity that the GPU
//! layer samples ([`GpuSampled`], set by [`crate::gpu::backend`]) is left alone: its
//! samples are drawn on the GPU, straight into the renderer's buffer.

use std::time::Instant;

use bevy_ecs::prelude::*;
use strata_engine::sample::Sample;

use super::components::*;
use super::stats::{EngineErrors, Stage, StageStats};
use super::{EngineError, EngineSettings};
use crate::budget::{BudgetError, check_count};

/// Set `0` to true to resample every mesh in the next update (cleared by sampling).
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct SampleRequest(pub bool);

/// The mesh entity whose samples the GPU draws (`None`: every mesh is sampled on the
/// CPU). Written by the GPU layer's sampling system ([`crate::gpu::backend`]) before
/// [`sample_meshes`] runs; when it changes, the CPU redraws the meshes it samples.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuSampled(pub Option<Entity>);

/// Draws samples into the sample buffers (see the module docs).
#[allow(clippy::type_complexity)]
pub fn sample_meshes(
    settings: Res<EngineSettings>,
    on_gpu: Res<GpuSampled>,
    mut request: ResMut<SampleRequest>,
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    mut meshes: Query<(
        Entity,
        Ref<MeshSampler>,
        Ref<SamplingSettings>,
        Ref<MeshTransform>,
        &mut SampleBuffer,
    )>,
) {
    let forced = settings.sample_every_update || request.0;
    for (entity, sampler, sampling, transform, mut buffer) in &mut meshes {
        if on_gpu.0 == Some(entity) {
            continue;
        }
        let dirty = sampler.is_changed()
            || sampling.is_changed()
            || transform.is_changed()
            || on_gpu.is_changed();
        let Some(s) = sampler.0.as_ref() else {
            continue;
        };
        if !(forced || dirty) {
            continue;
        }
        let t = Instant::now();
        match draw(s, *sampling, &transform.0, &mut buffer) {
            Ok(()) => stats.record(
                Stage::Sampling,
                entity,
                sampling.count,
                t.elapsed(),
                String::new(),
            ),
            Err(e) => errors.0.push(EngineError::Budget(e)),
        }
    }
    if request.0 {
        request.0 = false;
    }
}

/// Draws `sampling`'s samples from `sampler` into `buffer`, placed by `transform`. A
/// count set by host code is checked here: too many, or more than memory gives, is an
/// error that keeps the last samples, never an abort.
fn draw(
    sampler: &strata_engine::sample::Sampler,
    sampling: SamplingSettings,
    transform: &glam::DAffine3,
    buffer: &mut SampleBuffer,
) -> Result<(), BudgetError> {
    reserve(&mut buffer.samples, sampling.count)?;
    buffer.samples.resize(sampling.count, Sample::default());
    sampler.sample_into(sampling.seed, &mut buffer.samples);
    if *transform != glam::DAffine3::IDENTITY {
        transform_samples(transform, &mut buffer.samples);
    }
    buffer.generation += 1;
    Ok(())
}

/// Makes room for `count` samples in `samples` without aborting: counts above the
/// index limit and allocations the system refuses are errors.
fn reserve(samples: &mut Vec<Sample>, count: usize) -> Result<(), BudgetError> {
    check_count(count as u64)?;
    samples
        .try_reserve_exact(count.saturating_sub(samples.len()))
        .map_err(|_| BudgetError::OutOfMemory {
            count: count as u64,
        })
}

/// Applies a similarity transform to samples: positions mapped, normals and major axes
/// rotated (and renormalised), spacings scaled.
pub fn transform_samples(transform: &glam::DAffine3, samples: &mut [Sample]) {
    let m = transform.matrix3;
    // The uniform scale of a similarity: the cube root of the determinant.
    let scale = m.determinant().abs().cbrt();
    let dir = |v: [f32; 3]| -> [f32; 3] {
        let d = m * glam::DVec3::from(v.map(f64::from));
        d.normalize_or_zero().as_vec3().to_array()
    };
    for s in samples {
        let p = transform.transform_point3(glam::DVec3::from(s.position.map(f64::from)));
        s.position = p.as_vec3().to_array();
        s.normal = dir(s.normal);
        s.major_axis = dir(s.major_axis);
        s.spacing = s.spacing.map(|x| (f64::from(x) * scale) as f32);
    }
}
