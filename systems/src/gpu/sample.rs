//! Stratified sampling on the GPU: a compute pass (`shaders/sample.wgsl`) draws the
//! sites of an `(n, seed)` request from the sampler's cells, flattened once by the
//! engine ([`FlatSampler`]), and [`SiteExpander`]'s pass turns them into the records of
//! the [`GpuSampleBuffer`] the renderers draw.
//!
//! Per request the CPU computes the allocation over segments or chains and the levels
//! of the continuous map per segment (O(segments), [`FlatSampler::request`]) and
//! uploads them with a 48-byte uniform; every per-sample step (the counter-based
//! random value, the leaf search over the cumulative measures, the point in the leaf
//! and its triangle) runs on the GPU, in 32-bit integers (64-bit values as word pairs)
//! and `f32`. The sites are those of [`Sampler::sample_sites_into`]: the same leaf for
//! every sample (the stratified value and the cumulative measures are compared in
//! 64-bit fixed point), the point in it up to `f32` round-off, so a face or segment
//! can differ only for a point within round-off of a triangle edge. A boundary leaf
//! that expects several samples is descended as the sequential sampler descends it,
//! over a tree of its sub-cells' exact measures that the engine unrolls from that
//! descent ([`FlatSampler::deepen`]) the first time a count needs it; the table is
//! then uploaded again (larger counts need deeper trees, about `2^depth` nodes per
//! boundary leaf).
//!
//! The progressive order (`shaders/progressive.wgsl`,
//! [`GpuSampler::sample_progressive_sites`]) needs no per-request table: the CPU
//! computes the scramble's six words ([`progressive_scramble`](strata_engine::sample::flat::progressive_scramble)) and the pass maps each
//! rank's value through the cumulative measures of all leaves to a leaf, as
//! [`Sampler::progressive_sites_into`] does. Its boundary leaves descend twelve levels
//! whatever the count, too deep to unroll into trees, so the pass runs the descent
//! itself in `f32` from the leaf's clipped pieces and the triangles' density planes
//! ([`FlatProgressive`], 12 bytes per domain triangle, uploaded with the table),
//! carrying the target as a 64-bit fraction: the same sub-cells as the CPU but where
//! the target lies within `f32` round-off of a cut. Boundary leaves too coarse for
//! that (or cut by more triangles than the pass keeps) start over the top of their
//! descent unrolled in `f64` ([`FlatProgressive::nodes`]), to level 9. Ranks come either as a range or
//! as a list in a buffer, which is how a level-of-detail pool's new entries are placed
//! ([`GpuLodPool::sync_placed`](super::lod::GpuLodPool::sync_placed)).

use strata_engine::sample::flat::{FlatError, FlatProgressive, FlatRequest, FlatSampler};
use strata_engine::sample::{SampleSite, Sampler};
use wgpu::util::DeviceExt;

use super::buffers::{GpuSampleBuffer, read_buffer};
use super::context::{GpuError, scoped};
use super::expand::{Bound, SiteExpander, bind_cached};
use super::pipeline::{
    ComputePipelineDesc, compute_storage, compute_uniform, pipeline_layout, shader_module,
    uniform_buffer,
};
use super::shaders;

mod progressive;
mod timing;

pub(crate) use progressive::Ranks;

/// Samples per workgroup of the sampling pass (the shader's `@workgroup_size`).
const WORKGROUP: u32 = 64;

const SITE_BYTES: u64 = std::mem::size_of::<SampleSite>() as u64;

/// The sampling pass's uniforms; twin of `SampleParams` in `shaders/sample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleParams {
    /// Samples requested.
    pub count: u32,
    /// Groups in the request table.
    pub groups: u32,
    /// Invocations per row of the 2-D dispatch.
    pub row: u32,
    /// First word of the per-slot levels in the request table.
    pub levels_at: u32,
    /// First word of the cumulative measures in the table.
    pub cum_at: u32,
    /// First word of the leaves.
    pub leaves_at: u32,
    /// First word of the full leaves' candidates.
    pub cands_at: u32,
    /// First word of the boundary leaves' pieces.
    pub pieces_at: u32,
    /// First word of the domain triangles.
    pub tris_at: u32,
    /// First word of the segment ids per slot.
    pub slots_at: u32,
    /// First word of the descent-tree nodes.
    pub nodes_at: u32,
    /// First word of the descent thresholds in the request table.
    pub thresholds_at: u32,
    /// Descent thresholds per group.
    pub depth: u32,
    /// Progressive: the first rank drawn, or the first word of the rank list.
    pub first: u32,
    /// Progressive: 1 when the ranks are listed in the request binding.
    pub listed: u32,
    /// Progressive: the first site written.
    pub out_at: u32,
    /// Leaves in the table.
    pub leaves: u32,
    /// Progressive: the scramble's words ([`progressive_scramble`](strata_engine::sample::flat::progressive_scramble)).
    pub scramble: [u32; 6],
    /// First word of the density planes in the table.
    pub planes_at: u32,
    /// First word of the progressive levels per slot in the table.
    pub prog_levels_at: u32,
    /// First word of the progressive order's descent-tree nodes in the table.
    pub prog_nodes_at: u32,
    /// First word of those nodes' pieces.
    pub prog_pieces_at: u32,
    /// First word of the list of leaves with a progressive tree (a count, then
    /// `[leaf, root]` pairs).
    pub trees_at: u32,
}

/// The flat tables of `flat` and `prog` as one array of 32-bit words, and where each
/// part starts.
fn table_words(flat: &FlatSampler, prog: &FlatProgressive) -> (Vec<u32>, SampleParams) {
    let mut words = Vec::with_capacity((flat.bytes() + prog.bytes()) / 4);
    let at = |w: &Vec<u32>| w.len() as u32;
    let cum_at = at(&words);
    words.extend(
        flat.cumulative
            .iter()
            .flat_map(|&c| [c as u32, (c >> 32) as u32]),
    );
    let leaves_at = at(&words);
    words.extend(flat.leaves.iter().flatten());
    let cands_at = at(&words);
    words.extend(&flat.candidates);
    let pieces_at = at(&words);
    words.extend(flat.pieces.iter().flatten());
    let tris_at = at(&words);
    words.extend(flat.triangles.iter().flatten());
    let slots_at = at(&words);
    words.extend(&flat.slot_segments);
    let nodes_at = at(&words);
    words.extend(flat.nodes.iter().flatten());
    let planes_at = at(&words);
    words.extend(prog.planes.iter().flatten());
    let prog_levels_at = at(&words);
    words.extend(&prog.levels);
    let prog_nodes_at = at(&words);
    words.extend(prog.nodes.iter().flatten());
    let prog_pieces_at = at(&words);
    words.extend(prog.pieces.iter().flatten());
    let trees_at = at(&words);
    words.push(prog.trees.len() as u32);
    words.extend(prog.trees.iter().flatten());
    let offsets = SampleParams {
        nodes_at,
        planes_at,
        prog_levels_at,
        prog_nodes_at,
        prog_pieces_at,
        trees_at,
        leaves: flat.leaves.len() as u32,
        cum_at,
        leaves_at,
        cands_at,
        pieces_at,
        tris_at,
        slots_at,
        ..Default::default()
    };
    (words, offsets)
}

/// The tables of `flat` uploaded: the buffer, its bytes and where each part starts.
fn upload_table(
    device: &wgpu::Device,
    flat: &FlatSampler,
    prog: &FlatProgressive,
) -> Result<(wgpu::Buffer, u64, SampleParams), GpuError> {
    let (words, offsets) = table_words(flat, prog);
    let table_bytes = std::mem::size_of_val(words.as_slice()) as u64;
    let limit = device.limits().max_storage_buffer_binding_size;
    if table_bytes > limit {
        return Err(GpuError::Limit {
            what: "cell table for GPU sampling (bytes)",
            requested: table_bytes,
            limit,
        });
    }
    let table = scoped(device, "uploading the sampling tables", || {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("strata sample table"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::STORAGE,
        })
    })?;
    Ok((table, table_bytes, offsets))
}

/// A storage buffer that grows (by doubling) to hold what it is asked to.
#[derive(Debug)]
struct Growable {
    label: &'static str,
    usage: wgpu::BufferUsages,
    buffer: Option<wgpu::Buffer>,
    /// Counts the buffers made: a submission checked with generation `g` bound the
    /// current buffer while this is `g`.
    generation: u64,
}

impl Growable {
    fn new(label: &'static str, usage: wgpu::BufferUsages) -> Self {
        Self {
            label,
            usage,
            buffer: None,
            generation: 0,
        }
    }

    /// The buffer, at least `bytes` long (a new one, its contents lost, when it was
    /// shorter).
    fn at_least(&mut self, device: &wgpu::Device, bytes: u64) -> Result<&wgpu::Buffer, GpuError> {
        let limit = device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(GpuError::Limit {
                what: self.label,
                requested: bytes,
                limit,
            });
        }
        let size = self.buffer.as_ref().map_or(0, wgpu::Buffer::size);
        if size < bytes {
            let size = bytes.max(2 * size).min(limit).max(256);
            self.buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: self.usage,
                mapped_at_creation: false,
            }));
            self.generation += 1;
        }
        // Set just above when it was missing or short.
        self.buffer.as_ref().ok_or(GpuError::Limit {
            what: self.label,
            requested: bytes,
            limit,
        })
    }
}

/// Draws stratified samples of one sampler on the GPU ([module docs](self)).
///
/// Bound to the sampler it was built from: for a new sampler (another mesh, field or
/// preprocessing) build a new one. Any count and seed reuse it.
#[derive(Debug)]
pub struct GpuSampler {
    sampler: Sampler,
    flat: FlatSampler,
    prog: FlatProgressive,
    pipeline: wgpu::ComputePipeline,
    progressive: wgpu::ComputePipeline,
    /// The progressive pass's uniforms (apart from the stratified pass's, so both
    /// can be recorded before one submission).
    prog_params: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    table: wgpu::Buffer,
    table_bytes: u64,
    /// Counts the cell tables uploaded (a deeper request uploads them again).
    table_generation: u64,
    offsets: SampleParams,
    request: Growable,
    sites: Growable,
    /// The request table and its words, kept so that a request allocates nothing
    /// once they have grown to the largest.
    groups: FlatRequest,
    words: Vec<u32>,
    /// The sites pass's uniforms as last written (a request that leaves them as they
    /// are does not write them again).
    written: Option<SampleParams>,
    /// The `(count, seed)` whose request table and uniforms the GPU holds, with the
    /// table generation they were computed for: a repeated request uploads nothing.
    uploaded: Option<(u32, u64, u64)>,
    /// The sites pass's bind group and the buffers it binds: made again only when one
    /// of them was reallocated.
    bind_group: Bound<4>,
    /// What the last submission checked in error scopes bound: the sites pass's
    /// buffer generations, the count and the records buffer. A resample binding the
    /// same is submitted without scopes ([`sample`](Self::sample)).
    checked: Option<([u64; 3], u32, wgpu::Buffer)>,
    /// Sites written by the last request.
    count: u32,
    expander: SiteExpander,
    /// Where the device has timestamp queries: the begin and end of the sites pass and
    /// of the expansion, and the buffer they resolve into.
    timer: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// Whether the passes write their timestamps ([`set_timing`](Self::set_timing)).
    timing: bool,
}

/// Timestamps per request: the sites pass's begin and end, the expansion's.
const STAMPS: u32 = 4;

impl GpuSampler {
    /// Flattens `sampler`'s cells, uploads them and builds the sampling and expansion
    /// passes (the expander uploads the mesh table).
    pub fn new(device: &wgpu::Device, sampler: &Sampler) -> Result<Self, GpuError> {
        let flat = FlatSampler::new(sampler)?;
        let prog = FlatProgressive::new(sampler);
        let (table, table_bytes, offsets) = upload_table(device, &flat, &prog)?;
        let expander = SiteExpander::new(device, sampler)?;
        scoped(device, "building the sampling pass", || {
            let module = shader_module(device, "strata sample", shaders::SAMPLE);
            let (storage, uniform) = (compute_storage, compute_uniform(0));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("strata sample"),
                entries: &[
                    uniform,
                    storage(1, true),
                    storage(2, true),
                    storage(3, false),
                ],
            });
            let pipeline_layout = pipeline_layout(device, "strata sample", &[Some(&layout)]);
            let pipeline = ComputePipelineDesc {
                label: "strata sample",
                entry: "cs_sample",
            }
            .create(device, &pipeline_layout, &module);
            let progressive = ComputePipelineDesc {
                label: "strata progressive sample",
                entry: "cs_progressive",
            }
            .create(device, &pipeline_layout, &module);
            let params_bytes = std::mem::size_of::<SampleParams>();
            Self {
                sampler: sampler.clone(),
                flat,
                prog,
                pipeline,
                progressive,
                prog_params: uniform_buffer(device, "strata progressive params", params_bytes),
                layout,
                params: uniform_buffer(
                    device,
                    "strata sample params",
                    std::mem::size_of::<SampleParams>(),
                ),
                table,
                table_bytes,
                table_generation: 0,
                offsets,
                groups: FlatRequest::default(),
                words: Vec::new(),
                written: None,
                uploaded: None,
                bind_group: None,
                checked: None,
                request: Growable::new(
                    "strata sample request",
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                ),
                sites: Growable::new(
                    "strata GPU sites",
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                ),
                count: 0,
                expander,
                timing: false,
                timer: device
                    .features()
                    .contains(wgpu::Features::TIMESTAMP_QUERY)
                    .then(|| {
                        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                            label: Some("strata sample timestamps"),
                            ty: wgpu::QueryType::Timestamp,
                            count: STAMPS,
                        });
                        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("strata sample timestamps"),
                            size: u64::from(STAMPS) * 8,
                            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                            mapped_at_creation: false,
                        });
                        (set, resolve)
                    }),
            }
        })
    }

    /// The flat tables this sampler draws from (as deep as the largest request so far
    /// needed).
    pub fn flat(&self) -> &FlatSampler {
        &self.flat
    }

    /// Bytes of the cell table on the GPU (the expander's mesh table not counted).
    pub fn table_bytes(&self) -> u64 {
        self.table_bytes
    }

    /// The expander whose mesh table the records are made with.
    pub fn expander(&self) -> &SiteExpander {
        &self.expander
    }

    /// Draws the sites of an `n`-sample stratified request for `seed` on the GPU (kept
    /// in the sampler's sites buffer): records the pass and submits it; never waits.
    pub fn sample_sites(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        n: usize,
        seed: u64,
    ) -> Result<(), GpuError> {
        // Unlabelled: wgpu copies a per-frame object's label into a new string.
        let mut encoder = device.create_command_encoder(&Default::default());
        self.encode_sites(device, queue, &mut encoder, n, seed)?;
        queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Draws an `n`-sample stratified request for `seed` on the GPU into `samples`
    /// (resized to `n`): the sites, then their expansion into records, as two
    /// dispatches of one compute pass (two passes with their timestamps while the
    /// passes are timed), one submission; never waits.
    pub fn sample(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        n: usize,
        seed: u64,
        samples: &mut GpuSampleBuffer,
    ) -> Result<(), GpuError> {
        samples.resize(device, n)?;
        let mut encoder = device.create_command_encoder(&Default::default());
        if self.timer().is_some() {
            self.encode_timed(device, queue, &mut encoder, (n, seed), samples.buffer())?;
        } else if let Some((gx, gy)) = self.prepare_sites(device, queue, n, seed)?
            && let Some(sites) = &self.sites.buffer
        {
            // One pass: wgpu puts a barrier between the two dispatches (the sites are
            // written by the first and read by the second).
            let expand =
                self.expander
                    .prepare_resident(device, queue, sites, samples.buffer(), self.count);
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_sites(&mut pass, gx, gy);
            if let Some(groups) = expand {
                self.expander.record_resident(&mut pass, groups);
            }
        }
        // The same bindings and count as a submission already checked: wgpu validates
        // these commands as it did then, so no error scopes (popping them allocates);
        // an error (out of memory) reaches the device's uncaptured-error handler.
        let checked = (
            [
                self.table_generation,
                self.request.generation,
                self.sites.generation,
            ],
            self.count,
            samples.buffer().clone(),
        );
        if self.checked.as_ref() == Some(&checked) {
            queue.submit([encoder.finish()]);
            return Ok(());
        }
        self.checked = None;
        scoped(device, "sampling on the GPU", || {
            queue.submit([encoder.finish()]);
        })?;
        self.checked = Some(checked);
        Ok(())
    }

    /// Records the sites pass of an `(n, seed)` request into `encoder` in a pass of
    /// its own (timed where the passes are); its uniforms and request table are
    /// written with `queue` (submit before the next request).
    fn encode_sites(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        n: usize,
        seed: u64,
    ) -> Result<(), GpuError> {
        let Some((gx, gy)) = self.prepare_sites(device, queue, n, seed)? else {
            return Ok(());
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: self
                .timer()
                .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
        });
        self.record_sites(&mut pass, gx, gy);
        Ok(())
    }

    /// Records the sites pass's dispatch (`gx` by `gy` workgroups) into `pass`.
    fn record_sites(&self, pass: &mut wgpu::ComputePass<'_>, gx: u32, gy: u32) {
        if let Some((_, bind_group)) = &self.bind_group {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
    }

    /// Prepares the sites pass of an `(n, seed)` request: writes its uniforms and
    /// request table with `queue` where they changed and makes its bind group where a
    /// buffer it binds was reallocated. The workgroups to dispatch, `None` for no
    /// samples.
    fn prepare_sites(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        n: usize,
        seed: u64,
    ) -> Result<Option<(u32, u32)>, GpuError> {
        let count = u32::try_from(n).map_err(|_| FlatError::TooLarge {
            what: "samples per request",
            value: n as u64,
        })?;
        self.count = count;
        if count == 0 {
            return Ok(None);
        }
        let groups = count.div_ceil(WORKGROUP);
        let max = device.limits().max_compute_workgroups_per_dimension.max(1);
        let (gx, gy) = (groups.min(max), groups.div_ceil(max));
        if self.uploaded != Some((count, seed, self.table_generation)) {
            self.upload_request(device, queue, (count, seed), gx)?;
        }
        // A handle (no copy of the buffer).
        let sites = self
            .sites
            .at_least(device, u64::from(count) * SITE_BYTES)?
            .clone();
        // The whole sites buffer is bound: the pass writes the first `count` entries
        // (its uniform), so one bind group serves every count the buffer holds.
        let request = self.request.buffer.as_ref().unwrap_or(&self.table);
        bind_cached(
            device,
            (&self.layout, "strata sample"),
            &mut self.bind_group,
            [&self.params, &self.table, request, &sites],
        )?;
        Ok(Some((gx, gy)))
    }

    /// Computes the `(count, seed)` request (deepening and uploading the tables again
    /// when it needs deeper descent trees) and writes its table and the pass's
    /// uniforms (`gx` workgroups per row) with `queue`. Allocates only while the
    /// request table grows past its largest so far (and in the engine's request).
    fn upload_request(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (count, seed): (u32, u64),
        gx: u32,
    ) -> Result<(), GpuError> {
        let n = u64::from(count);
        let request = &mut self.groups;
        match self.flat.request_into(&self.sampler, n, seed, request) {
            Err(FlatError::Shallow { .. }) => {
                // Deeper descent trees for this count: built once, uploaded again.
                self.flat.deepen(&self.sampler, n)?;
                (self.table, self.table_bytes, self.offsets) =
                    upload_table(device, &self.flat, &self.prog)?;
                self.table_generation += 1;
                self.flat.request_into(&self.sampler, n, seed, request)?;
            }
            other => other?,
        }
        let words = &mut self.words;
        words.clear();
        words.extend(request.groups.iter().flatten());
        let levels_at = words.len() as u32;
        words.extend(&request.levels);
        let thresholds_at = words.len() as u32;
        words.extend(
            request
                .thresholds
                .iter()
                .flat_map(|&t| [t as u32, (t >> 32) as u32]),
        );
        let params = SampleParams {
            count,
            groups: request.groups.len() as u32,
            row: gx * WORKGROUP,
            levels_at,
            thresholds_at,
            depth: request.depth,
            ..self.offsets
        };
        let request_buffer = self
            .request
            .at_least(device, std::mem::size_of_val(words.as_slice()) as u64)?;
        queue.write_buffer(request_buffer, 0, bytemuck::cast_slice(words));
        // The uniforms depend on the count, not the seed: a new seed leaves them.
        if self.written != Some(params) {
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            self.written = Some(params);
        }
        self.uploaded = Some((count, seed, self.table_generation));
        Ok(())
    }

    /// Copies the sites of the last request back (waits for the device; for tests,
    /// checks and benchmarks, not for the frame loop).
    pub fn read_sites(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<SampleSite>, GpuError> {
        let Some(sites) = &self.sites.buffer else {
            return Ok(Vec::new());
        };
        let bytes = read_buffer(device, queue, sites, u64::from(self.count) * SITE_BYTES)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::super::wgsl_layout::wgsl_layout;
    use super::*;

    /// `SampleParams` and `Site` in sample.wgsl have the layouts of their Rust twins.
    #[test]
    fn wgsl_twins_match_rust_layouts() {
        let (params, span) = wgsl_layout(shaders::SAMPLE, "SampleParams");
        assert_eq!(span, size_of::<SampleParams>());
        let want = [
            ("count", offset_of!(SampleParams, count)),
            ("groups", offset_of!(SampleParams, groups)),
            ("row", offset_of!(SampleParams, row)),
            ("levels_at", offset_of!(SampleParams, levels_at)),
            ("cum_at", offset_of!(SampleParams, cum_at)),
            ("leaves_at", offset_of!(SampleParams, leaves_at)),
            ("cands_at", offset_of!(SampleParams, cands_at)),
            ("pieces_at", offset_of!(SampleParams, pieces_at)),
            ("tris_at", offset_of!(SampleParams, tris_at)),
            ("slots_at", offset_of!(SampleParams, slots_at)),
            ("nodes_at", offset_of!(SampleParams, nodes_at)),
            ("thresholds_at", offset_of!(SampleParams, thresholds_at)),
            ("depth", offset_of!(SampleParams, depth)),
            ("first", offset_of!(SampleParams, first)),
            ("listed", offset_of!(SampleParams, listed)),
            ("out_at", offset_of!(SampleParams, out_at)),
            ("leaves", offset_of!(SampleParams, leaves)),
            ("add", offset_of!(SampleParams, scramble)),
            ("even0", offset_of!(SampleParams, scramble) + 4),
            ("even1", offset_of!(SampleParams, scramble) + 8),
            ("odd", offset_of!(SampleParams, scramble) + 12),
            ("jitter_lo", offset_of!(SampleParams, scramble) + 16),
            ("jitter_hi", offset_of!(SampleParams, scramble) + 20),
            ("planes_at", offset_of!(SampleParams, planes_at)),
            ("prog_levels_at", offset_of!(SampleParams, prog_levels_at)),
            ("prog_nodes_at", offset_of!(SampleParams, prog_nodes_at)),
            ("prog_pieces_at", offset_of!(SampleParams, prog_pieces_at)),
            ("trees_at", offset_of!(SampleParams, trees_at)),
        ];
        let want: Vec<(String, usize)> = want.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(params, want);
        let (site, span) = wgsl_layout(shaders::SAMPLE, "Site");
        assert_eq!(span, size_of::<SampleSite>());
        assert_eq!(
            site.iter().map(|(_, o)| *o).collect::<Vec<_>>(),
            [
                offset_of!(SampleSite, face),
                offset_of!(SampleSite, segment),
                offset_of!(SampleSite, bary)
            ]
        );
    }
}

/// GPU against CPU sampling on whatever adapter wgpu opens (the software adapter in
/// CI); skipped without one unless `STRATA_REQUIRE_GPU=1`.
#[cfg(test)]
mod gpu_tests {
    use std::io::Write;
    use std::path::Path;

    use strata_engine::sample::{SampleSite, Sampler};

    use super::GpuSampler;
    use crate::config::SceneConfig;
    use crate::gpu::sample_check::{PROGRESSIVE_POSITION_TOLERANCE, SLIVER_TOLERANCE};
    use crate::gpu::{GpuContext, GpuSampleBuffer};
    use crate::scene::Scene;

    fn gpu(test: &str) -> Option<GpuContext> {
        GpuContext::headless_or_skip(test)
    }

    /// The bunny (shared mesh) under a constant anisotropic field; `None`, with a
    /// line on stderr, without the shared meshes.
    fn bunny() -> Option<Scene> {
        let Some(dir) = strata_engine::io::shared_mesh_dir() else {
            let _ = writeln!(std::io::stderr(), "bunny skipped: no shared meshes");
            return None;
        };
        let ron = format!(
            "(mesh: File({:?}), field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0))",
            dir.join("stanford-bunny.obj").display().to_string()
        );
        Some(scene(&ron))
    }

    fn scene(ron: &str) -> Scene {
        let config = SceneConfig::from_ron(ron, Path::new("test.ron")).expect("scene parses");
        Scene::build(&config).expect("scene builds")
    }

    /// The default scene (`configs/default.ron`): a genus-2 surface, singularities,
    /// many segments.
    const DEFAULT: &str = "(mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
         field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0))";

    /// A unit square with a 2:1 field along x (planar path).
    const PLANE: &str = "(mesh: Shape(Plane(size: 1.0, resolution: 8)), \
         field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0))";

    /// A plane whose density varies eightfold (`configs/plane-gaussian.ron`, coarser).
    const GAUSSIAN: &str = "(mesh: Shape(Plane(size: 1.0, resolution: 16)), \
         field: Planar(density: Gaussian(center: (0.5, 0.5), sigma: 0.15, peak: 8.0, base: 0.5)))";

    /// How the GPU's sites differ from the CPU's for one request.
    #[derive(Debug, Default)]
    struct Difference {
        /// Samples whose face differs.
        faces: usize,
        /// Samples whose segment differs.
        segments: usize,
        /// The largest distance between the two sites' points over the bounding-box
        /// diagonal.
        position: f64,
        /// Samples farther apart than 1e-5 of the diagonal.
        beyond: usize,
    }

    fn compare(sampler: &Sampler, gpu: &[SampleSite], cpu: &[SampleSite]) -> Difference {
        let (lo, hi) = sampler.mesh().bounds();
        let diagonal = (hi - lo).length();
        let mut d = Difference::default();
        assert_eq!(gpu.len(), cpu.len());
        for (g, c) in gpu.iter().zip(cpu) {
            d.faces += usize::from(g.face != c.face);
            d.segments += usize::from(g.segment != c.segment);
            let at = |x: &SampleSite| x.position_on(sampler.mesh()).expect("a face of the mesh");
            let dist = at(g).distance(at(c)) / diagonal;
            d.position = d.position.max(dist);
            d.beyond += usize::from(dist > 1e-5);
        }
        d
    }

    /// Sites and records drawn on the GPU are the CPU's: the same face and segment for
    /// every sample (up to a few points within round-off of an edge, counted and
    /// printed), positions within 1e-5 of the bounding-box diagonal; on a planar scene
    /// and the default scene (chains at 1 and 7 samples), at counts that are and are
    /// not powers of two; the same bits in two runs.
    #[test]
    fn gpu_sites_are_the_cpu_sites() {
        let Some(ctx) = gpu("gpu_sites_are_the_cpu_sites") else {
            return;
        };
        let (device, queue) = (&ctx.device, &ctx.queue);
        for (name, ron) in [
            ("plane", PLANE),
            ("gaussian", GAUSSIAN),
            ("default", DEFAULT),
        ] {
            let scene = scene(ron);
            let sampler = &scene.sampler;
            let mut gpu = GpuSampler::new(device, sampler).expect("GPU sampler");
            let mut buffer = GpuSampleBuffer::new(device).expect("buffer");
            for (n, seed) in [(1usize, 3u64), (7, 3), (4096, 5), (10_007, 9)] {
                let at = format!("{name}, n {n}");
                let d = check(&ctx, &mut gpu, sampler, n, seed, &at);
                // No sliver allowance on these scenes: every sample within 1e-5.
                assert!(d.position <= 1e-5, "{at}: {d:?}");
                let sites = gpu.read_sites(device, queue).expect("read back");
                // Records: the sites expanded into the renderer's buffer.
                gpu.sample(device, queue, n, seed, &mut buffer)
                    .expect("samples");
                let records = buffer.read_back(device, queue).expect("read back");
                // Timed, the two dispatches run as two passes: the same records.
                gpu.set_timing(true);
                gpu.sample(device, queue, n, seed, &mut buffer)
                    .expect("samples");
                let timed = buffer.read_back(device, queue).expect("read back");
                gpu.set_timing(false);
                assert!(
                    bytemuck::cast_slice::<_, u8>(&timed)
                        == bytemuck::cast_slice::<_, u8>(&records),
                    "{at}: the timed passes wrote other records"
                );
                let want = sampler.sample(n, seed);
                let (lo, hi) = sampler.mesh().bounds();
                let diagonal = (hi - lo).length() as f32;
                for (k, (r, s)) in records.iter().zip(&want).enumerate() {
                    assert_eq!(r.index, k as u32, "{at}");
                    assert_eq!((r.face, r.segment), (sites[k].face, sites[k].segment));
                    let dist = glam::Vec3::from(r.position).distance(s.position.into());
                    assert!(dist <= 1e-5 * diagonal, "{at}, sample {k}: {dist}");
                }
            }
        }
    }

    /// The default scene with coarse cells: boundary leaves receive many samples even
    /// at counts where segments are linked into chains.
    const COARSE: &str = "(mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
         field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0), \
         curve: (max_cell_share: 0.02, boundary_level: 3))";

    /// Draws `n` samples for `seed` on both sides and checks them as
    /// `gpu_sites_are_the_cpu_sites` does; returns the difference.
    fn check(
        ctx: &GpuContext,
        gpu: &mut GpuSampler,
        sampler: &Sampler,
        n: usize,
        seed: u64,
        at: &str,
    ) -> Difference {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut cpu = vec![SampleSite::default(); n];
        sampler.sample_sites_into(seed, &mut cpu);
        gpu.sample_sites(device, queue, n, seed).expect("sites");
        let sites = gpu.read_sites(device, queue).expect("read back");
        let d = compare(sampler, &sites, &cpu);
        let _ = writeln!(
            std::io::stderr(),
            "{at}: chains {}, descent depth {}, {} faces and {} segments differ, largest deviation {:.2e} of the diagonal ({} beyond 1e-5)",
            sampler.uses_chains(n),
            gpu.flat()
                .request(sampler, n as u64, seed)
                .map_or(0, |r| r.depth),
            d.faces,
            d.segments,
            d.position,
            d.beyond
        );
        // Within 1e-5 of the diagonal but for points in triangles that are slivers in
        // the parameterization, where f32 coordinates of the point resolve the
        // triangle's width only to a few percent (on the bunny at 10^5: one sample, in
        // a uv triangle 5e-7 wide, at 2.1e-5).
        assert!(d.beyond * 10_000 <= n && d.position <= 1e-4, "{at}: {d:?}");
        assert!(d.faces * 1000 <= n && d.segments * 1000 <= n, "{at}: {d:?}");
        gpu.sample_sites(device, queue, n, seed).expect("sites");
        assert!(
            gpu.read_sites(device, queue).expect("read back") == sites,
            "{at}: two runs differ"
        );
        d
    }

    /// Counts that put several samples in boundary leaves descend through them as the
    /// CPU does (the trees deepened on the way): the same faces and segments, positions
    /// within 1e-5 of the diagonal, with chains on a many-segment scene, at 10^5 on the
    /// default scene and on the bunny (shared mesh, skipped without it).
    #[test]
    fn boundary_descent_matches_the_cpu() {
        let Some(ctx) = gpu("boundary_descent_matches_the_cpu") else {
            return;
        };
        let device = &ctx.device;
        let coarse = scene(COARSE);
        let sampler = &coarse.sampler;
        let mut gpu = GpuSampler::new(device, sampler).expect("GPU sampler");
        let chained = 3 * sampler.segments().len();
        assert!(
            sampler.uses_chains(chained),
            "the coarse scene links segments"
        );
        for (n, seed) in [(chained, 2u64), (chained / 2 + 1, 4), (50_000, 6)] {
            check(&ctx, &mut gpu, sampler, n, seed, &format!("coarse, n {n}"));
            let depth = gpu
                .flat()
                .request(sampler, n as u64, seed)
                .expect("request")
                .depth;
            assert!(depth >= 1, "coarse, n {n}: no descent exercised");
        }
        let default = scene(DEFAULT);
        let mut gpu = GpuSampler::new(device, &default.sampler).expect("GPU sampler");
        check(
            &ctx,
            &mut gpu,
            &default.sampler,
            100_000,
            1,
            "default, n 100000",
        );
        gpu.sample_sites(device, &ctx.queue, 0, 1).expect("nothing");
        assert!(gpu.read_sites(device, &ctx.queue).expect("read").is_empty());
        let Some(bunny) = bunny() else {
            return;
        };
        let mut gpu = GpuSampler::new(device, &bunny.sampler).expect("GPU sampler");
        check(
            &ctx,
            &mut gpu,
            &bunny.sampler,
            100_000,
            1,
            "bunny, n 100000",
        );
    }

    /// Draws progressive ranks `first..first + n` for `seed` on both sides and checks
    /// them with the tolerances of `check`; returns the GPU's sites.
    fn check_progressive(
        ctx: &GpuContext,
        gpu: &mut GpuSampler,
        sampler: &Sampler,
        (first, n, seed): (u32, usize, u64),
        at: &str,
    ) -> Vec<SampleSite> {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut cpu = vec![SampleSite::default(); n];
        sampler.progressive_sites_into(seed, first, &mut cpu);
        gpu.sample_progressive_sites(device, queue, first, n, seed)
            .expect("progressive sites");
        let sites = gpu.read_sites(device, queue).expect("read back");
        let d = compare(sampler, &sites, &cpu);
        let _ = writeln!(
            std::io::stderr(),
            "{at} (progressive from {first}): {} faces and {} segments differ, largest deviation {:.2e} of the diagonal ({} beyond 1e-5)",
            d.faces,
            d.segments,
            d.position,
            d.beyond
        );
        // The sampler check's tolerances for the progressive order (sliver leaves,
        // `PROGRESSIVE_POSITION_TOLERANCE`).
        let slivers = (SLIVER_TOLERANCE * n as f64).floor() as usize;
        assert!(
            d.beyond <= slivers && d.position <= PROGRESSIVE_POSITION_TOLERANCE,
            "{at}: {d:?}"
        );
        assert!(d.faces * 1000 <= n && d.segments * 1000 <= n, "{at}: {d:?}");
        gpu.sample_progressive_sites(device, queue, first, n, seed)
            .expect("progressive sites");
        assert!(
            gpu.read_sites(device, queue).expect("read back") == sites,
            "{at}: two runs differ"
        );
        sites
    }

    /// Progressive sites drawn on the GPU are the CPU's on a planar scene, a varying
    /// density and the default scene (many segments; boundary leaves descended twelve
    /// levels), at counts 1, 7, 4096 and 10^5; the same bits in two runs; prefixes
    /// nested: the first `n` sites of a larger request, and a request from a later
    /// first rank, are the same bits as the matching entries of the larger one.
    #[test]
    fn gpu_progressive_sites_are_the_cpu_sites() {
        let Some(ctx) = gpu("gpu_progressive_sites_are_the_cpu_sites") else {
            return;
        };
        let device = &ctx.device;
        for (name, ron) in [
            ("plane", PLANE),
            ("gaussian", GAUSSIAN),
            ("default", DEFAULT),
        ] {
            let scene = scene(ron);
            let sampler = &scene.sampler;
            let mut gpu = GpuSampler::new(device, sampler).expect("GPU sampler");
            let seed = 7;
            let mut runs = Vec::new();
            for n in [1usize, 7, 4096, 100_000] {
                let at = format!("{name}, n {n}");
                runs.push(check_progressive(
                    &ctx,
                    &mut gpu,
                    sampler,
                    (0, n, seed),
                    &at,
                ));
            }
            for pair in runs.windows(2) {
                assert!(
                    pair[1][..pair[0].len()] == pair[0][..],
                    "{name}: prefixes not nested"
                );
            }
            let later = check_progressive(
                &ctx,
                &mut gpu,
                sampler,
                (1000, 3000, seed),
                &format!("{name}, ranks 1000..4000"),
            );
            assert!(
                later[..] == runs[2][1000..4000],
                "{name}: later ranks differ"
            );
        }
    }

    /// Prints the bytes of the progressive trees on the GPU, per mesh face.
    fn trees_line(gpu: &GpuSampler, at: &str) {
        let prog = &gpu.prog;
        let bytes = prog.nodes.len() * 52 + prog.pieces.len() * 80 + prog.trees.len() * 8 + 4;
        let faces = gpu.sampler.mesh().face_count();
        let _ = writeln!(
            std::io::stderr(),
            "{at}: progressive trees for {} leaves, {} nodes, {} pieces: {bytes} bytes, {:.1} per face ({faces} faces; the whole table {} bytes, {:.1} per face)",
            prog.trees.len(),
            prog.nodes.len(),
            prog.pieces.len(),
            bytes as f64 / faces as f64,
            gpu.table_bytes(),
            gpu.table_bytes() as f64 / faces as f64,
        );
    }

    /// The bunny (shared mesh, skipped without it) in progressive order at 10^5.
    #[test]
    fn gpu_progressive_bunny_matches_the_cpu() {
        let Some(ctx) = gpu("gpu_progressive_bunny_matches_the_cpu") else {
            return;
        };
        let Some(bunny) = bunny() else {
            return;
        };
        let mut gpu = GpuSampler::new(&ctx.device, &bunny.sampler).expect("GPU sampler");
        trees_line(&gpu, "bunny");
        for n in [1usize, 7, 4096, 100_000] {
            let at = format!("bunny, n {n}");
            check_progressive(&ctx, &mut gpu, &bunny.sampler, (0, n, 1), &at);
        }
    }

    /// On a scene whose boundary leaves are coarse and cut by many triangles (coarse
    /// cells), the progressive order descends the top of those leaves over the trees
    /// the engine unrolls in `f64` and matches the CPU at counts 1, 7, 4096 and 10^5:
    /// the same faces and segments, every position within 1e-5 of the diagonal; the
    /// stratified order still matches there.
    #[test]
    fn gpu_progressive_coarse_cells_match_the_cpu() {
        let Some(ctx) = gpu("gpu_progressive_coarse_cells_match_the_cpu") else {
            return;
        };
        let coarse = scene(COARSE);
        let sampler = &coarse.sampler;
        let mut gpu = GpuSampler::new(&ctx.device, sampler).expect("GPU sampler");
        assert!(!gpu.prog.trees.is_empty(), "coarse leaves with trees");
        trees_line(&gpu, "coarse");
        for n in [1usize, 7, 4096, 100_000] {
            let at = format!("coarse, n {n}");
            let sites = check_progressive(&ctx, &mut gpu, sampler, (0, n, 7), &at);
            let mut cpu = vec![SampleSite::default(); n];
            sampler.progressive_sites_into(7, 0, &mut cpu);
            let d = compare(sampler, &sites, &cpu);
            assert!(
                d.faces == 0 && d.segments == 0 && d.position <= 1e-5,
                "{at}: {d:?}"
            );
        }
        check(
            &ctx,
            &mut gpu,
            sampler,
            4096,
            5,
            "coarse, stratified, n 4096",
        );
    }

    /// `strata bench --gpu` prints the check and succeeds on a scene within tolerance.
    #[test]
    fn bench_gpu_checks_against_the_cpu() {
        use clap::Parser;
        if gpu("bench_gpu_checks_against_the_cpu").is_none() {
            return;
        }
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("plane.ron");
        std::fs::write(&path, GAUSSIAN).expect("scene written");
        let path = path.to_str().expect("utf-8");
        let args = [
            "strata", "bench", path, "-n", "3000", "--repeat", "2", "--gpu",
        ];
        let cli = crate::cli::Cli::try_parse_from(args).expect("arguments parse");
        crate::cli::run(cli).expect("bench --gpu succeeds");
    }
}
