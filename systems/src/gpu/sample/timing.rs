//! Timing the GPU sampler's passes with timestamp queries, on request
//! ([`GpuSampler::set_timing`]): a timed [`GpuSampler::sample`] records the sites pass
//! and the expansion as two passes, each with its timestamps resolved into the
//! sampler's buffer, and [`GpuSampler::pass_times`] reads them back. Input: the device's
//! timestamp queries (where it has them); output: seconds of GPU time per pass. Cost:
//! one extra pass and its timestamps per timed frame (wgpu allocations on the CPU),
//! and a read-back (a wait) per reading.

use super::{GpuError, GpuSampler, STAMPS, read_buffer};

impl GpuSampler {
    /// Whether the passes write timestamps ([`set_timing`](Self::set_timing) on a device
    /// with timestamp queries; [`pass_times`](Self::pass_times) reads them).
    pub fn times_passes(&self) -> bool {
        self.timer().is_some()
    }

    /// Times the passes from now on (`on`, where the device has timestamp queries:
    /// [`pass_times`](Self::pass_times), [`sites_pass_time`](Self::sites_pass_time)) or
    /// not (the default). Untimed, [`sample`](Self::sample) records the sites and their
    /// expansion as two dispatches of one compute pass; timed, as two passes, each
    /// with its timestamps (each pass and its timestamps cost wgpu allocations on the
    /// CPU every frame).
    pub fn set_timing(&mut self, on: bool) {
        self.timing = on;
    }

    /// The timestamp queries and their resolve buffer while the passes are timed.
    pub(super) fn timer(&self) -> Option<&(wgpu::QuerySet, wgpu::Buffer)> {
        self.timer.as_ref().filter(|_| self.timing)
    }

    /// [`sample`](Self::sample)'s passes, timed: the sites pass and the expansion each
    /// in its own pass with its timestamps, resolved into the timer's buffer.
    pub(super) fn encode_timed(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (n, seed): (usize, u64),
        samples: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        self.encode_sites(device, queue, encoder, n, seed)?;
        let Some(sites) = &self.sites.buffer else {
            return Ok(());
        };
        // The fields, not `timer()`: the expander is borrowed mutably beside them.
        let timer = self.timer.as_ref().filter(|_| self.timing);
        let stamps = timer.map(|(set, _)| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(2),
            end_of_pass_write_index: Some(3),
        });
        self.expander
            .expand_resident(device, queue, encoder, sites, samples, self.count, stamps);
        if let Some((set, resolve)) = timer
            && self.count > 0
        {
            encoder.resolve_query_set(set, 0..STAMPS, resolve, 0);
        }
        Ok(())
    }

    /// The GPU time in seconds of the last sites pass alone (stratified or
    /// progressive), from timestamp queries (waits for the device); `None` while the
    /// passes are not timed ([`set_timing`](Self::set_timing)) or where the device has
    /// no timestamp queries.
    pub fn sites_pass_time(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<f64>, GpuError> {
        let Some((set, resolve)) = self.timer() else {
            return Ok(None);
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(set, 0..2, resolve, 0);
        queue.submit([encoder.finish()]);
        let bytes = read_buffer(device, queue, resolve, 16)?;
        let t: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
        let period = f64::from(queue.get_timestamp_period()) * 1e-9;
        Ok(Some(t[1].saturating_sub(t[0]) as f64 * period))
    }

    /// The GPU times in seconds of the last [`sample`](Self::sample)'s sites pass (the
    /// stratified values, the leaf search and the points, one pass) and its expansion
    /// into records, from timestamp queries (waits for the device); `None` while the
    /// passes are not timed ([`set_timing`](Self::set_timing)) or where the device has
    /// no timestamp queries.
    pub fn pass_times(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<[f64; 2]>, GpuError> {
        let Some((_, resolve)) = self.timer() else {
            return Ok(None);
        };
        let bytes = read_buffer(device, queue, resolve, u64::from(STAMPS) * 8)?;
        let t: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
        let period = f64::from(queue.get_timestamp_period()) * 1e-9;
        let span = |a: usize| t[a + 1].saturating_sub(t[a]) as f64 * period;
        Ok(Some([span(0), span(2)]))
    }
}
