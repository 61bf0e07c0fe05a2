//! The progressive order on the GPU ([`GpuSampler::sample_progressive_sites`]): the
//! pass that places ranks of the progressive sequence, and the check, made when the
//! tables are uploaded, that it can place every boundary leaf as the CPU does.
//!
//! Input: the sampler's uploaded tables and a `(ranks, seed)` request. Output: sites in
//! the sampler's sites buffer (or one the caller names). Cost: the scramble's six words
//! per request on the CPU; O(boundary pieces) once for the check.

use strata_engine::sample::flat::{FlatError, FlatSampler, progressive_scramble};

use super::{GpuSampler, SITE_BYTES, SampleParams, WORKGROUP};
use crate::gpu::context::{GpuError, scoped};

/// Pieces of a boundary leaf that the progressive pass keeps per node
/// (`MAX_PIECES` in progressive.wgsl).
const PROGRESSIVE_PIECES: usize = 12;

/// The boundary leaves of `flat` whose clipped pieces (those with corners enough for
/// area) exceed what the progressive pass keeps per node: how many, and the most pieces
/// in one. The pass cannot place their samples as the CPU does (measured on a coarse
/// scene: samples a tenth of the bounding-box diagonal from the CPU's), so a sampler
/// with any refuses the progressive order. O(boundary pieces).
pub(super) fn progressive_overflow(flat: &FlatSampler) -> (u32, u32) {
    let (mut leaves, mut most) = (0u32, 0u32);
    for leaf in flat.leaves.iter().filter(|l| l[2] & 128 == 0) {
        let root = flat.nodes[leaf[3] as usize];
        let pieces = flat.pieces[root[3] as usize..(root[3] + root[4]) as usize]
            .iter()
            .filter(|p| p[1] >= 3)
            .count() as u32;
        if pieces as usize > PROGRESSIVE_PIECES {
            leaves += 1;
            most = most.max(pieces);
        }
    }
    (leaves, most)
}

/// Where a progressive pass takes its ranks ([`GpuSampler::encode_progressive`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Ranks<'a> {
    /// Ranks `first..first + count`.
    From(u32),
    /// The ranks in a buffer of `u32`, from entry `first` on.
    Listed(&'a wgpu::Buffer, u32),
}

impl GpuSampler {
    /// Whether the progressive pass places this sampler's samples as the CPU does: an
    /// error naming the boundary leaves it cannot place (leaves cut by more triangles
    /// than the pass keeps per node, as on scenes with very coarse cells), where
    /// [`sample_progressive_sites`](Self::sample_progressive_sites) refuses to draw
    /// rather than return wrong samples. Checked once, when the tables are uploaded.
    pub fn progressive_exact(&self) -> Result<(), GpuError> {
        let (leaves, most) = self.overflow;
        if leaves == 0 {
            return Ok(());
        }
        Err(GpuError::Mismatch {
            what: "the progressive order on the GPU",
            detail: format!(
                "{leaves} boundary leaves are cut by more than {PROGRESSIVE_PIECES} triangles (up to {most}), which the progressive pass cannot place as the CPU does; draw the progressive order on the CPU (finer cells, a smaller max_cell_share or a higher boundary_level, avoid such leaves)"
            ),
        })
    }

    /// Draws the sites of progressive ranks `first_rank..first_rank + n` for `seed` on
    /// the GPU (kept in the sampler's sites buffer, [`read_sites`](Self::read_sites)):
    /// the sites of [`Sampler::progressive_sites_into`](strata_engine::sample::Sampler::progressive_sites_into), so every prefix of a request
    /// is the request of that count. The CPU computes the scramble's six words; the
    /// pass places every rank. Records and submits; never waits. An error, before
    /// anything is drawn, where [`progressive_exact`](Self::progressive_exact) is one.
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
        self.progressive_exact()?;
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
            stamps,
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
    /// uniforms are written with `queue`: submit before the next progressive pass.
    /// The error of [`progressive_exact`](Self::progressive_exact) where it has one.
    pub(crate) fn encode_progressive(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (ranks, count, seed): (Ranks<'_>, u32, u64),
        (sites, out_at): (&wgpu::Buffer, u32),
        stamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<(), GpuError> {
        self.progressive_exact()?;
        if count == 0 {
            return Ok(());
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
        let bind_group = scoped(device, "binding the progressive pass", || {
            let entries = [&self.prog_params, &self.table, list, sites];
            let entries: Vec<wgpu::BindGroupEntry<'_>> = entries
                .iter()
                .enumerate()
                .map(|(binding, buffer)| wgpu::BindGroupEntry {
                    binding: binding as u32,
                    resource: buffer.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("strata progressive sample"),
                layout: &self.layout,
                entries: &entries,
            })
        })?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("strata progressive sample"),
            timestamp_writes: stamps,
        });
        pass.set_pipeline(&self.progressive);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders;

    /// The progressive pass refuses exactly the samplers with boundary leaves cut by
    /// more triangles than it keeps per node: none on the default scene (finest
    /// boundary leaves at level 4), most boundary leaves of the same shape with coarse
    /// cells; the Rust limit is the shader's.
    #[test]
    fn progressive_overflow_flags_coarse_cells_only() {
        assert!(
            shaders::SAMPLE.contains(&format!("const MAX_PIECES: u32 = {PROGRESSIVE_PIECES}u;")),
            "PROGRESSIVE_PIECES is progressive.wgsl's MAX_PIECES"
        );
        let build = |ron: &str| {
            let config = crate::config::SceneConfig::from_ron(ron, std::path::Path::new("t.ron"))
                .expect("scene parses");
            let scene = crate::scene::Scene::build(&config).expect("scene builds");
            progressive_overflow(&FlatSampler::new(&scene.sampler).expect("flat tables"))
        };
        let shape = "mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
             field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0)";
        assert_eq!(build(&format!("({shape})")), (0, 0));
        let (leaves, most) = build(&format!(
            "({shape}, curve: (max_cell_share: 0.02, boundary_level: 3))"
        ));
        assert!(
            leaves > 100 && most > 100,
            "{leaves} leaves, up to {most} pieces"
        );
    }
}
