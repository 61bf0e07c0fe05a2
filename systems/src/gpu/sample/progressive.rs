//! The progressive order on the GPU ([`GpuSampler::sample_progressive_sites`]): the
//! pass that places ranks of the progressive sequence.
//!
//! Input: the sampler's uploaded tables (with the progressive order's density planes
//! and, for boundary leaves the pass cannot descend in `f32` alone, the top of their
//! descent unrolled in `f64`: [`FlatProgressive`](strata_engine::sample::flat::FlatProgressive)) and a `(ranks, seed)`
//! request. Output: sites in the sampler's sites buffer (or one the caller names).
//! Cost: the scramble's six words per request on the CPU.

use strata_engine::sample::flat::{FlatError, progressive_scramble};

use super::{GpuSampler, SITE_BYTES, SampleParams, WORKGROUP};
use crate::gpu::context::{GpuError, scoped};
use crate::gpu::expand::{Bound, bind_cached};

/// Where a progressive pass takes its ranks ([`GpuSampler::encode_progressive`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Ranks<'a> {
    /// Ranks `first..first + count`.
    From(u32),
    /// The ranks in a buffer of `u32`, from entry `first` on.
    Listed(&'a wgpu::Buffer, u32),
}

impl GpuSampler {
    /// Draws the sites of progressive ranks `first_rank..first_rank + n` for `seed` on
    /// the GPU (kept in the sampler's sites buffer, [`read_sites`](Self::read_sites)):
    /// the sites of [`Sampler::progressive_sites_into`](strata_engine::sample::Sampler::progressive_sites_into), so every prefix of a request
    /// is the request of that count. The CPU computes the scramble's six words; the
    /// pass places every rank. Records and submits; never waits. An error for ranks
    /// past 2^32.
    pub fn sample_progressive_sites(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        first_rank: u32,
        n: usize,
        seed: u64,
    ) -> Result<(), GpuError> {
        let count = u32::try_from(n)
            .ok()
            .filter(|&c| u64::from(first_rank) + u64::from(c) <= 1 << 32)
            .ok_or(FlatError::TooLarge {
                what: "progressive ranks (past 2^32)",
                value: u64::from(first_rank) + n as u64,
            })?;
        self.count = count;
        if count == 0 {
            return Ok(());
        }
        let sites = self
            .sites
            .at_least(device, u64::from(count) * SITE_BYTES)?
            .clone();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("strata progressive sample"),
        });
        let stamps = self.stamps(0);
        self.encode_progressive(
            device,
            queue,
            &mut encoder,
            (Ranks::From(first_rank), count, seed),
            (&sites, 0),
            (stamps, &mut None),
        )?;
        scoped(device, "sampling progressively on the GPU", || {
            queue.submit([encoder.finish()]);
        })
    }

    /// Timestamp writes at `first` and `first + 1`, where the device has them.
    fn stamps(&self, first: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.timer()
            .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(first),
                end_of_pass_write_index: Some(first + 1),
            })
    }

    /// Records the progressive pass: the sites of `count` ranks (`ranks`) for `seed`,
    /// written into `sites` from entry `out_at` on (the buffer must hold them). Its
    /// uniforms are written with `queue`: submit before the next progressive pass. Its
    /// bind group is taken from `group` where it binds the same buffers, else made (in
    /// error scopes) and kept there. Whether it was made.
    pub(crate) fn encode_progressive(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (ranks, count, seed): (Ranks<'_>, u32, u64),
        (sites, out_at): (&wgpu::Buffer, u32),
        (stamps, group): (Option<wgpu::ComputePassTimestampWrites<'_>>, &mut Bound<4>),
    ) -> Result<bool, GpuError> {
        if count == 0 {
            return Ok(false);
        }
        let groups = count.div_ceil(WORKGROUP);
        let max = device.limits().max_compute_workgroups_per_dimension.max(1);
        let (gx, gy) = (groups.min(max), groups.div_ceil(max));
        let (list, first, listed) = match ranks {
            Ranks::From(first) => (&self.table, first, 0),
            Ranks::Listed(buffer, first) => (buffer, first, 1),
        };
        let params = SampleParams {
            count,
            row: gx * WORKGROUP,
            first,
            listed,
            out_at,
            scramble: progressive_scramble(seed),
            ..self.offsets
        };
        queue.write_buffer(&self.prog_params, 0, bytemuck::bytes_of(&params));
        let (bind_group, made) = bind_cached(
            device,
            (&self.layout, "strata progressive sample"),
            group,
            [&self.prog_params, &self.table, list, sites],
        )?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: stamps,
        });
        pass.set_pipeline(&self.progressive);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        Ok(made)
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use strata_engine::sample::flat::{FlatProgressive, PROGRESSIVE_PIECES};

    use crate::gpu::shaders;

    /// The pieces the engine leaves to the pass per node are what the pass keeps; the
    /// default scene (boundary leaves at level 4) needs no progressive tree, the same
    /// shape with coarse cells has trees for most boundary leaves, each a run of nodes
    /// listed once, in leaf order.
    #[test]
    fn progressive_trees_cover_coarse_cells_only() {
        assert!(
            shaders::SAMPLE.contains(&format!("const MAX_PIECES: u32 = {PROGRESSIVE_PIECES}u;")),
            "PROGRESSIVE_PIECES is progressive.wgsl's MAX_PIECES"
        );
        let build = |ron: &str| {
            let config = crate::config::SceneConfig::from_ron(ron, std::path::Path::new("t.ron"))
                .expect("scene parses");
            let scene = crate::scene::Scene::build(&config).expect("scene builds");
            FlatProgressive::new(&scene.sampler)
        };
        let shape = "mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
             field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0)";
        let fine = build(&format!("({shape})"));
        assert!(fine.trees.is_empty() && fine.nodes.is_empty());
        let config = crate::config::SceneConfig::from_ron(
            &format!("({shape}, curve: (max_cell_share: 0.02, boundary_level: 3))"),
            std::path::Path::new("t.ron"),
        )
        .expect("scene parses");
        let scene = crate::scene::Scene::build(&config).expect("scene builds");
        let start = std::time::Instant::now();
        let coarse = FlatProgressive::new(&scene.sampler);
        let _ = writeln!(
            std::io::stderr(),
            "coarse cells: progressive tables built in {:.1} ms, {} bytes",
            start.elapsed().as_secs_f64() * 1e3,
            coarse.bytes()
        );
        assert!(coarse.trees.len() > 100, "{} trees", coarse.trees.len());
        assert!(coarse.trees.windows(2).all(|w| w[0][0] < w[1][0]));
        assert!(
            coarse
                .trees
                .iter()
                .all(|t| (t[1] as usize) < coarse.nodes.len())
        );
    }
}
