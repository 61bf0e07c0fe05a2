//! Expanding sample sites into full samples on the GPU: the CPU writes 16 bytes per
//! sample ([`Sampler::sample_sites_into`]) instead of 64 and skips the record
//! (interpolated position, normal and field, the field's eigen-decomposition), which a
//! compute pass (`shaders/expand.wgsl`) then computes per sample in `f32`, straight
//! into the renderer's [`GpuSampleBuffer`].
//!
//! On the bunny at 10^6 samples this takes the CPU side of a frame from the full
//! sampler's time to the sites' time (`sample_floor` in `bench/`) and the upload from
//! 64 MB to 16 MB. The records agree with the CPU's to `f32` round-off (tested against
//! [`Sampler::sample_into`] on whatever adapter wgpu finds).

use strata_engine::mesh::TriMesh;
use strata_engine::sample::{SampleSite, Sampler};
use wgpu::util::DeviceExt;

use super::buffers::{GpuSampleBuffer, Streamed, StreamedBuffer};
use super::context::{GpuError, scoped};
use super::pipeline::{
    ComputePipelineDesc, compute_storage, compute_uniform, pipeline_layout, shader_module,
    uniform_buffer,
};
use super::shaders;

/// Sites per workgroup of the expansion pass (the shader's `@workgroup_size`).
const WORKGROUP: u32 = 64;

const SITE_BYTES: u64 = std::mem::size_of::<SampleSite>() as u64;

/// The expansion pass's uniforms; twin of `ExpandParams` in `shaders/expand.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ExpandParams {
    /// Sites to expand.
    pub count: u32,
    /// `sqrt(M / N)`, the spacing scale of an `N`-sample request.
    pub scale: f32,
    /// First word of the vertex normals in the mesh table (positions start at 0).
    pub normals_at: u32,
    /// First word of the face normals.
    pub face_normals_at: u32,
    /// First word of the triangles.
    pub triangles_at: u32,
    /// First word of the face-frame corner tensors.
    pub tensors_at: u32,
    /// Invocations per row of the 2-D dispatch.
    pub row: u32,
    /// The first entry of a ranked expansion (`cs_expand_ranked`); 0 otherwise.
    pub first: u32,
}

/// The expansion pipeline, the mesh table of one sampler and a growable sites buffer.
///
/// Bound to the sampler it was built from (its mesh, field and total measure): for a
/// new sampler (another mesh or field, or one reassembled by the engine after a
/// reload) build a new expander. Any count and seed of the same sampler reuse it.
#[derive(Debug)]
pub struct SiteExpander {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    ranked_pipeline: wgpu::ComputePipeline,
    ranked_layout: wgpu::BindGroupLayout,
    /// The ranked pass's parameters, rewritten per pass.
    ranked_params: wgpu::Buffer,
    params: wgpu::Buffer,
    mesh: wgpu::Buffer,
    offsets: ExpandParams,
    total_measure: f64,
    sites: StreamedBuffer,
    /// The resident pass's bind group and what it binds (sites, samples, count), kept
    /// while a caller expands the same buffers at the same count frame after frame.
    resident: Option<(wgpu::BindGroup, [wgpu::Buffer; 2], u32)>,
    /// The uniforms as last written to `params` (an expansion of the same count does
    /// not write them again).
    written: Option<ExpandParams>,
}

/// The mesh table of `sampler` as 32-bit words (layout: `ExpandParams`), and the
/// offsets of its parts.
fn mesh_words(sampler: &Sampler) -> (Vec<u32>, ExpandParams) {
    let mesh = sampler.mesh();
    let f32s = |v: &glam::DVec3| v.as_vec3().to_array().map(f32::to_bits);
    let mut words = Vec::with_capacity(6 * mesh.vertex_count() + 15 * mesh.face_count());
    words.extend(mesh.positions().iter().flat_map(f32s));
    let normals_at = words.len() as u32;
    words.extend(mesh.vertex_normals().iter().flat_map(f32s));
    let face_normals_at = words.len() as u32;
    words.extend(mesh.face_normals().iter().flat_map(f32s));
    let triangles_at = words.len() as u32;
    words.extend(mesh.triangles().iter().flatten());
    let tensors_at = words.len() as u32;
    words.extend(
        sampler
            .face_tensor_corners()
            .iter()
            .flat_map(|t| t.map(f32::to_bits)),
    );
    let offsets = ExpandParams {
        normals_at,
        face_normals_at,
        triangles_at,
        tensors_at,
        ..Default::default()
    };
    (words, offsets)
}

const PARAMS_BYTES: usize = std::mem::size_of::<ExpandParams>();

/// The plain (`cs_expand`) and ranked (`cs_expand_ranked`) expansion pipelines with
/// their bind group layouts (group 1: parameters, sites, mesh table, samples; the
/// ranked pass adds the ranks).
struct ExpandPasses {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    ranked_pipeline: wgpu::ComputePipeline,
    ranked_layout: wgpu::BindGroupLayout,
}

impl ExpandPasses {
    fn new(device: &wgpu::Device) -> Self {
        let module = shader_module(device, "strata expand", shaders::EXPAND);
        let (storage, uniform) = (compute_storage, compute_uniform(0));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("strata expand"),
            entries: &[
                uniform,
                storage(1, true),
                storage(2, true),
                storage(3, false),
            ],
        });
        let ranked_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("strata expand ranked"),
            entries: &[
                uniform,
                storage(1, true),
                storage(2, true),
                storage(3, false),
                storage(4, true),
            ],
        });
        // Group 0 is the render pipelines' frame uniforms, which this pass does not use.
        let compute = |layout: &wgpu::BindGroupLayout, entry| {
            let pipeline_layout = pipeline_layout(device, "strata expand", &[None, Some(layout)]);
            ComputePipelineDesc {
                label: "strata expand",
                entry,
            }
            .create(device, &pipeline_layout, &module)
        };
        Self {
            pipeline: compute(&layout, "cs_expand"),
            ranked_pipeline: compute(&ranked_layout, "cs_expand_ranked"),
            layout,
            ranked_layout,
        }
    }
}

impl SiteExpander {
    /// Builds the pipeline and uploads `sampler`'s mesh, normals, triangles and
    /// face-frame tensors (24 bytes per vertex and 60 per face).
    pub fn new(device: &wgpu::Device, sampler: &Sampler) -> Result<Self, GpuError> {
        let (words, offsets) = mesh_words(sampler);
        let bytes = std::mem::size_of_val(words.as_slice()) as u64;
        let limit = device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(GpuError::Limit {
                what: "mesh table for sample expansion (bytes)",
                requested: bytes,
                limit,
            });
        }
        let limits = device.limits();
        let sites = StreamedBuffer::new(
            device,
            Streamed {
                label: "strata sites",
                what: "sites buffer size (bytes)",
                operation: "allocating the sites buffer",
                item_bytes: SITE_BYTES,
                limit: limits
                    .max_buffer_size
                    .min(limits.max_storage_buffer_binding_size),
                usage: wgpu::BufferUsages::STORAGE,
            },
        )?;
        scoped(device, "building the sample expansion pass", || {
            let passes = ExpandPasses::new(device);
            let params = uniform_buffer(device, "strata expand params", PARAMS_BYTES);
            let ranked_params = uniform_buffer(device, "strata expand ranked params", PARAMS_BYTES);
            let mesh = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("strata expand mesh"),
                contents: bytemuck::cast_slice(&words),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            });
            Self {
                pipeline: passes.pipeline,
                layout: passes.layout,
                ranked_pipeline: passes.ranked_pipeline,
                ranked_layout: passes.ranked_layout,
                ranked_params,
                params,
                mesh,
                offsets,
                total_measure: sampler.total_measure(),
                sites,
                resident: None,
                written: None,
            }
        })
    }

    /// Uploads `sites` (an `n`-sample request of the sampler this expander was built
    /// for, `n = sites.len()`) and expands them into `samples`, which then holds the
    /// records [`Sampler::sample_into`] would have written, up to `f32` round-off.
    /// Records only commands and submits them; never waits on the GPU. Sites of
    /// another mesh give records that are wrong but memory-safe (wgpu bounds every
    /// storage access).
    pub fn expand(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        sites: &[SampleSite],
        samples: &mut GpuSampleBuffer,
    ) -> Result<(), GpuError> {
        let n = sites.len();
        samples.resize(device, n)?;
        if n == 0 {
            return Ok(());
        }
        let count = u32::try_from(n).map_err(|_| GpuError::Limit {
            what: "sites per expansion",
            requested: n as u64,
            limit: u64::from(u32::MAX),
        })?;
        let out_bytes = n as u64 * std::mem::size_of::<strata_engine::sample::Sample>() as u64;
        let binding_limit = device.limits().max_storage_buffer_binding_size;
        if out_bytes > binding_limit {
            return Err(GpuError::Limit {
                what: "expanded samples per pass (bytes)",
                requested: out_bytes,
                limit: binding_limit,
            });
        }
        let groups = count.div_ceil(WORKGROUP);
        let max = device.limits().max_compute_workgroups_per_dimension.max(1);
        let (gx, gy) = (groups.min(max), groups.div_ceil(max));
        let params = ExpandParams {
            count,
            scale: (self.total_measure / n as f64).sqrt() as f32,
            row: gx * WORKGROUP,
            ..self.offsets
        };
        scoped(device, "expanding sample sites", || {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("strata expand"),
            });
            self.sites.write(device, &mut encoder, sites)?;
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            self.written = Some(params);
            let bind_group = self.bind_group(
                device,
                "strata expand",
                (self.sites.buffer(), self.sites.bytes()),
                (samples.buffer(), out_bytes),
            );
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("strata expand"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(1, &bind_group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            self.sites.submit(queue, encoder);
            Ok(())
        })?
    }
}

impl SiteExpander {
    /// Records the expansion of the first `n` sites of `sites` (a GPU buffer of
    /// [`SampleSite`]s of an `n`-sample request, as the GPU sampler writes them) into
    /// `samples` (at least
    /// `n` records), each sample's index its place. The parameters go through the
    /// expander's uniform buffer written with `queue`: submit `encoder` before the next
    /// expansion. `timestamps`, where the device has timestamp queries, times the
    /// pass. The pass's bind group is kept for the next call with the same buffers and
    /// count.
    #[allow(clippy::too_many_arguments)]
    pub fn expand_resident(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        sites: &wgpu::Buffer,
        samples: &wgpu::Buffer,
        n: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let Some(groups) = self.prepare_resident(device, queue, sites, samples, n) else {
            return;
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            // Unlabelled: wgpu copies a per-frame pass's label into a new string.
            label: None,
            timestamp_writes: timestamps,
        });
        self.record_resident(&mut pass, groups);
    }

    /// Prepares [`expand_resident`](Self::expand_resident)'s dispatch without recording
    /// it: writes the uniforms with `queue` where they changed and makes the bind group
    /// where the buffers or the count changed. The workgroups for
    /// [`record_resident`](Self::record_resident), `None` for no sites.
    pub fn prepare_resident(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        sites: &wgpu::Buffer,
        samples: &wgpu::Buffer,
        n: u32,
    ) -> Option<(u32, u32)> {
        if n == 0 {
            return None;
        }
        let groups = n.div_ceil(WORKGROUP);
        let max = device.limits().max_compute_workgroups_per_dimension.max(1);
        let (gx, gy) = (groups.min(max), groups.div_ceil(max));
        let params = ExpandParams {
            count: n,
            scale: (self.total_measure / f64::from(n)).sqrt() as f32,
            row: gx * WORKGROUP,
            ..self.offsets
        };
        if self.written != Some(params) {
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            self.written = Some(params);
        }
        let bound = self.resident.as_ref().is_some_and(|(_, buffers, count)| {
            *count == n && buffers[0] == *sites && buffers[1] == *samples
        });
        if !bound {
            let record_bytes = std::mem::size_of::<strata_engine::sample::Sample>() as u64;
            let bind_group = self.bind_group(
                device,
                "strata expand resident",
                (sites, u64::from(n) * SITE_BYTES),
                (samples, u64::from(n) * record_bytes),
            );
            self.resident = Some((bind_group, [sites.clone(), samples.clone()], n));
        }
        Some((gx, gy))
    }

    /// Records the dispatch that [`prepare_resident`](Self::prepare_resident) prepared
    /// (`groups` workgroups) into `pass`, which may hold other dispatches before it
    /// (wgpu orders a dispatch's reads after an earlier one's writes).
    pub fn record_resident(&self, pass: &mut wgpu::ComputePass<'_>, (gx, gy): (u32, u32)) {
        if let Some((bind_group, _, _)) = &self.resident {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(1, bind_group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
    }

    /// The expansion pass's bind group: its uniforms and mesh table, the first
    /// `site_bytes` of `sites` and the first `sample_bytes` of `samples`.
    fn bind_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        (sites, site_bytes): (&wgpu::Buffer, u64),
        (samples, sample_bytes): (&wgpu::Buffer, u64),
    ) -> wgpu::BindGroup {
        let part = |buffer, bytes| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                size: wgpu::BufferSize::new(bytes),
            })
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: part(sites, site_bytes),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.mesh.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: part(samples, sample_bytes),
                },
            ],
        })
    }

    /// Replaces the positions and normals of the mesh table with those of `mesh`, a
    /// deformation of the sampler's mesh (same vertices and triangles; the field's
    /// face-frame tensors move with the faces): expansions from now on place the sites
    /// on the deformed surface. 36 bytes per vertex and 12 per face, no resampling.
    pub fn set_geometry(&self, queue: &wgpu::Queue, mesh: &TriMesh) -> Result<(), GpuError> {
        let o = &self.offsets;
        let vertices = (o.face_normals_at - o.normals_at) / 3;
        let faces = (o.triangles_at - o.face_normals_at) / 3;
        if mesh.vertex_count() != vertices as usize || mesh.face_count() != faces as usize {
            return Err(GpuError::Mismatch {
                what: "deformed mesh",
                detail: format!(
                    "{} vertices and {} faces, the sampler's mesh has {vertices} and {faces}",
                    mesh.vertex_count(),
                    mesh.face_count()
                ),
            });
        }
        let f32s = |v: &glam::DVec3| v.as_vec3().to_array().map(f32::to_bits);
        let words = |v: &[glam::DVec3]| v.iter().flat_map(f32s).collect::<Vec<u32>>();
        queue.write_buffer(
            &self.mesh,
            0,
            bytemuck::cast_slice(&words(mesh.positions())),
        );
        let at = |w: u32| u64::from(w) * 4;
        queue.write_buffer(
            &self.mesh,
            at(o.normals_at),
            bytemuck::cast_slice(&words(mesh.vertex_normals())),
        );
        queue.write_buffer(
            &self.mesh,
            at(o.face_normals_at),
            bytemuck::cast_slice(&words(mesh.face_normals())),
        );
        Ok(())
    }

    /// Records the expansion of entries `range` of a resident pool (`sites` and
    /// `ranks`, one per entry, as [`LodPool`](strata_engine::sample::LodPool) holds
    /// them) into the same entries of `samples`, with the spacings of `base` samples
    /// over the surface and each sample's index its rank. Every buffer must hold at
    /// least `range.end` entries. The parameters go through one uniform buffer written
    /// with `queue`: submit `encoder` before the next call. The pass's bind group is
    /// taken from `group` where it binds the same buffers, else made (in error scopes)
    /// and kept there. Whether it was made.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn expand_ranked(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (sites, ranks, samples): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        range: std::ops::Range<u32>,
        base: f64,
        group: &mut Bound<5>,
    ) -> Result<bool, GpuError> {
        if range.is_empty() {
            return Ok(false);
        }
        let groups = (range.end - range.start).div_ceil(WORKGROUP);
        let max = device.limits().max_compute_workgroups_per_dimension.max(1);
        let (gx, gy) = (groups.min(max), groups.div_ceil(max));
        let params = ExpandParams {
            count: range.end,
            scale: (self.total_measure / base.max(1.0)).sqrt() as f32,
            row: gx * WORKGROUP,
            first: range.start,
            ..self.offsets
        };
        queue.write_buffer(&self.ranked_params, 0, bytemuck::bytes_of(&params));
        let (bind_group, made) = bind_cached(
            device,
            (&self.ranked_layout, "strata expand ranked"),
            group,
            [&self.ranked_params, sites, &self.mesh, samples, ranks],
        )?;
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.ranked_pipeline);
        pass.set_bind_group(1, bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        Ok(made)
    }
}

/// A bind group with the buffers it binds (binding `i` the whole of buffer `i`):
/// [`bind_cached`] makes it again only when one of them is another buffer.
pub(crate) type Bound<const N: usize> = Option<([wgpu::Buffer; N], wgpu::BindGroup)>;

/// The bind group in `layout` of `buffers` (binding `i` the whole of buffer `i`): the
/// one `cache` holds where it binds the same buffers (no allocation), else one made in
/// error scopes and kept in `cache`. Whether it was made.
pub(crate) fn bind_cached<'a, const N: usize>(
    device: &wgpu::Device,
    (layout, label): (&wgpu::BindGroupLayout, &'static str),
    cache: &'a mut Bound<N>,
    buffers: [&wgpu::Buffer; N],
) -> Result<(&'a wgpu::BindGroup, bool), GpuError> {
    let same = cache
        .as_ref()
        .is_some_and(|(bound, _)| bound.iter().zip(buffers).all(|(a, b)| a == b));
    let kept = match cache.take() {
        Some(kept) if same => kept,
        _ => {
            let group = scoped(device, "binding a pass", || {
                let entries = std::array::from_fn::<_, N, _>(|i| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: buffers[i].as_entire_binding(),
                });
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(label),
                    layout,
                    entries: &entries,
                })
            })?;
            (buffers.map(Clone::clone), group)
        }
    };
    Ok((&cache.insert(kept).1, !same))
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::super::wgsl_layout::wgsl_layout;
    use super::*;

    /// `Site` and `ExpandParams` in expand.wgsl have the layouts of `SampleSite` and
    /// [`ExpandParams`] (a reordered or resized member fails this).
    #[test]
    fn wgsl_twins_match_rust_layouts() {
        let named = |v: &[(&str, usize)]| {
            v.iter()
                .map(|(n, o)| (n.to_string(), *o))
                .collect::<Vec<_>>()
        };
        let (site, span) = wgsl_layout(shaders::EXPAND, "Site");
        assert_eq!(span, size_of::<SampleSite>());
        assert_eq!(
            site,
            named(&[
                ("face", offset_of!(SampleSite, face)),
                ("segment", offset_of!(SampleSite, segment)),
                ("bary", offset_of!(SampleSite, bary)),
            ])
        );
        let (params, span) = wgsl_layout(shaders::EXPAND, "ExpandParams");
        assert_eq!(span, size_of::<ExpandParams>());
        assert_eq!(
            params,
            named(&[
                ("count", offset_of!(ExpandParams, count)),
                ("scale", offset_of!(ExpandParams, scale)),
                ("normals_at", offset_of!(ExpandParams, normals_at)),
                ("face_normals_at", offset_of!(ExpandParams, face_normals_at)),
                ("triangles_at", offset_of!(ExpandParams, triangles_at)),
                ("tensors_at", offset_of!(ExpandParams, tensors_at)),
                ("row", offset_of!(ExpandParams, row)),
                ("first", offset_of!(ExpandParams, first)),
            ])
        );
    }
}
