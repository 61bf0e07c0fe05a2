//! The per-frame streaming step without any ECS: resample into a reused CPU staging
//! vector, then upload it into the renderer's sample buffer.
//!
//! This is the body of the future `sample_splats` + `upload_splats` systems: an ECS
//! resource holds a [`SampleStream`], and the systems call [`SampleStream::sample`] and
//! [`SampleStream::upload`] (or [`SampleStream::frame`] for both).

use std::time::{Duration, Instant};

use strata_engine::sample::{Sample, Sampler};

use super::context::GpuError;
use super::splat::SplatRenderer;

/// Wall time of one frame's streaming.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamTimings {
    /// Samples drawn.
    pub count: usize,
    /// `Sampler::sample_into` into the staging vector.
    pub sample: Duration,
    /// Copy into mapped staging memory, recording and submitting the buffer copy.
    pub upload: Duration,
}

/// A reused CPU-side staging vector of samples.
#[derive(Debug, Default)]
pub struct SampleStream {
    staging: Vec<Sample>,
}

impl SampleStream {
    /// An empty stream.
    pub fn new() -> Self {
        Self::default()
    }

    /// Resamples `count` samples with `seed` into the staging vector (allocates only
    /// when `count` exceeds every earlier count).
    pub fn sample(&mut self, sampler: &Sampler, count: usize, seed: u64) -> Duration {
        let t = Instant::now();
        self.staging.resize(count, Sample::default());
        sampler.sample_into(seed, &mut self.staging);
        t.elapsed()
    }

    /// Uploads the staging vector into `renderer`.
    pub fn upload(
        &self,
        renderer: &mut SplatRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Duration, GpuError> {
        let t = Instant::now();
        renderer.upload(device, queue, &self.staging)?;
        Ok(t.elapsed())
    }

    /// [`sample`](Self::sample) then [`upload`](Self::upload).
    pub fn frame(
        &mut self,
        sampler: &Sampler,
        count: usize,
        seed: u64,
        renderer: &mut SplatRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<StreamTimings, GpuError> {
        let sample = self.sample(sampler, count, seed);
        let upload = self.upload(renderer, device, queue)?;
        Ok(StreamTimings {
            count,
            sample,
            upload,
        })
    }

    /// The samples of the last frame.
    pub fn samples(&self) -> &[Sample] {
        &self.staging
    }
}
