//! The per-frame streaming step without any ECS: resample into a reused CPU staging
//! vector, then upload it into the renderer's sample buffer; or, with a
//! [`SiteExpander`], resample only the sites (16 bytes per sample) and let a compute
//! pass expand them into the renderer's sample buffer.
//!
//! For callers without the ECS engine (`strata render`, the frame benchmark); the
//! engine streams through its own sample buffer and [`super::upload::upload_samples`].

use std::time::{Duration, Instant};

use strata_engine::sample::{Sample, SampleSite, Sampler};

use super::context::GpuError;
use super::expand::SiteExpander;
use super::splat::SplatRenderer;

/// Wall time of one frame's streaming.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamTimings {
    /// Samples drawn.
    pub count: usize,
    /// `Sampler::sample_into` (or `sample_sites_into`) into the staging vector.
    pub sample: Duration,
    /// Copy into mapped staging memory, recording and submitting the buffer copy (and
    /// the expansion pass, for sites).
    pub upload: Duration,
}

/// A reused CPU-side staging vector of samples (or of sites).
#[derive(Debug, Default)]
pub struct SampleStream {
    staging: Vec<Sample>,
    sites: Vec<SampleSite>,
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

    /// Resamples `count` sites with `seed` into the sites vector, uploads them and
    /// expands them into `renderer`'s sample buffer with `expander` (built for the same
    /// sampler): the frame of [`frame`](Self::frame) with a quarter of the bytes and
    /// without the record on the CPU. The expansion runs on the GPU after the submit;
    /// neither step waits for it.
    #[allow(clippy::too_many_arguments)]
    pub fn frame_sites(
        &mut self,
        sampler: &Sampler,
        count: usize,
        seed: u64,
        expander: &mut SiteExpander,
        renderer: &mut SplatRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<StreamTimings, GpuError> {
        let t = Instant::now();
        self.sites.resize(count, SampleSite::default());
        sampler.sample_sites_into(seed, &mut self.sites);
        let sample = t.elapsed();
        let t = Instant::now();
        expander.expand(device, queue, &self.sites, renderer.samples_mut())?;
        Ok(StreamTimings {
            count,
            sample,
            upload: t.elapsed(),
        })
    }

    /// The sites of the last [`frame_sites`](Self::frame_sites).
    pub fn sites(&self) -> &[SampleSite] {
        &self.sites
    }

    /// The samples of the last frame.
    pub fn samples(&self) -> &[Sample] {
        &self.staging
    }
}
