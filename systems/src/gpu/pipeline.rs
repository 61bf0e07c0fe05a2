//! Pipelines as plain data: a [`RenderPipelineDesc`] or [`ComputePipelineDesc`] says
//! everything that differs between the renderers' pipelines (label, entry points,
//! vertex buffers, colour targets and blending, depth, primitive, multisampling), is
//! hashable and comparable, and is turned into a wgpu pipeline in one place
//! ([`RenderPipelineDesc::create`], [`ComputePipelineDesc::create`]).
//!
//! Input: a description, the shader module and the pipeline layout (wgpu handles,
//! which are neither hashable nor comparable, so they are given at creation). Output:
//! the wgpu pipeline. Cost: wgpu's pipeline creation; the description itself is a few
//! words. The small builders beside it ([`shader_module`], [`uniform_buffer`],
//! [`buffer_entry`], [`pipeline_layout`]) are the set-up every renderer repeats.

use strata_engine::sample::Sample;

use super::layout::{MESH_ATTRIBUTES, MeshVertex, SAMPLE_ATTRIBUTES};

/// The formats of the targets a renderer draws into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TargetFormat {
    /// Colour format (an `*Srgb` format: shaders output linear colour).
    pub color: wgpu::TextureFormat,
    /// Depth format.
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel (1 or 4).
    pub samples: u32,
}

impl TargetFormat {
    /// One colour target of this format with `blend`, writing the channels `writes`.
    pub fn color_target(
        &self,
        blend: Option<wgpu::BlendState>,
        writes: wgpu::ColorWrites,
    ) -> Option<wgpu::ColorTargetState> {
        Some(wgpu::ColorTargetState {
            format: self.color,
            blend,
            write_mask: writes,
        })
    }

    /// A depth test against this format's depth with `compare`, writing depth when
    /// `write`, the depth pushed back by `bias`; no stencil.
    pub fn depth_test(
        &self,
        write: bool,
        compare: wgpu::CompareFunction,
        bias: wgpu::DepthBiasState,
    ) -> Option<wgpu::DepthStencilState> {
        Some(wgpu::DepthStencilState {
            format: self.depth,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias,
        })
    }

    /// This format's samples per pixel, every sample written, no alpha to coverage.
    pub fn multisample(&self) -> wgpu::MultisampleState {
        wgpu::MultisampleState {
            count: self.samples,
            mask: !0,
            alpha_to_coverage_enabled: false,
        }
    }
}

/// The depth bias of a mesh drawn under samples: pushed back a little so that samples
/// lying on a face win the depth test.
pub const MESH_DEPTH_BIAS: wgpu::DepthBiasState = wgpu::DepthBiasState {
    constant: 4,
    slope_scale: 2.0,
    clamp: 0.0,
};

/// A vertex buffer's layout as plain data (wgpu's borrows its attributes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VertexBuffer {
    /// Bytes from one element to the next.
    pub stride: u64,
    /// Per vertex or per instance.
    pub step_mode: wgpu::VertexStepMode,
    /// The attributes of one element.
    pub attributes: &'static [wgpu::VertexAttribute],
}

impl VertexBuffer {
    /// The sample buffer, one [`Sample`] per instance ([`SAMPLE_ATTRIBUTES`]).
    pub const SAMPLES: Self = Self {
        stride: size_of::<Sample>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &SAMPLE_ATTRIBUTES,
    };

    /// The flat-shaded mesh, one [`MeshVertex`] per vertex ([`MESH_ATTRIBUTES`]).
    pub const MESH: Self = Self {
        stride: size_of::<MeshVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &MESH_ATTRIBUTES,
    };

    fn to_wgpu(self) -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: self.stride,
            step_mode: self.step_mode,
            attributes: self.attributes,
        }
    }
}

/// A render pipeline as plain, hashable data; [`create`](Self::create) makes it.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct RenderPipelineDesc {
    /// Debug label (shown by graphics debuggers and in validation errors).
    pub label: &'static str,
    /// Vertex entry point in the shader module.
    pub vertex_entry: &'static str,
    /// Fragment entry point in the shader module.
    pub fragment_entry: &'static str,
    /// The vertex buffers, in slot order.
    pub vertex_buffers: Vec<VertexBuffer>,
    /// The colour targets, with their blending and write masks.
    pub targets: Vec<Option<wgpu::ColorTargetState>>,
    /// Topology and rasterization.
    pub primitive: wgpu::PrimitiveState,
    /// The depth test, if any.
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// Multisampling.
    pub multisample: wgpu::MultisampleState,
}

impl RenderPipelineDesc {
    /// The pipeline with both stages in `module` and the bind groups of `layout`.
    pub fn create(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
    ) -> wgpu::RenderPipeline {
        let buffers: Vec<Option<wgpu::VertexBufferLayout<'static>>> = self
            .vertex_buffers
            .iter()
            .map(|b| Some(b.to_wgpu()))
            .collect();
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(self.vertex_entry),
                compilation_options: Default::default(),
                buffers: &buffers,
            },
            primitive: self.primitive,
            depth_stencil: self.depth_stencil.clone(),
            multisample: self.multisample,
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(self.fragment_entry),
                compilation_options: Default::default(),
                targets: &self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// Primitives of `topology`, both faces drawn.
pub fn primitive(topology: wgpu::PrimitiveTopology) -> wgpu::PrimitiveState {
    wgpu::PrimitiveState {
        topology,
        cull_mode: None,
        ..Default::default()
    }
}

/// A compute pipeline as plain, hashable data; [`create`](Self::create) makes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ComputePipelineDesc {
    /// Debug label.
    pub label: &'static str,
    /// Compute entry point in the shader module.
    pub entry: &'static str,
}

impl ComputePipelineDesc {
    /// The pipeline with its entry point in `module` and the bind groups of `layout`.
    pub fn create(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
    ) -> wgpu::ComputePipeline {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(self.label),
            layout: Some(layout),
            module,
            entry_point: Some(self.entry),
            compilation_options: Default::default(),
            cache: None,
        })
    }
}

/// The WGSL module `source`, labelled `label`.
pub fn shader_module(
    device: &wgpu::Device,
    label: &'static str,
    source: &'static str,
) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// A uniform buffer of `size` bytes that the queue writes.
pub fn uniform_buffer(device: &wgpu::Device, label: &'static str, size: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A bind group layout entry for a buffer of type `ty` at `binding`, seen by
/// `visibility`, at least `min_size` bytes when given.
pub fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
    min_size: Option<usize>,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: min_size.and_then(|s| wgpu::BufferSize::new(s as u64)),
        },
        count: None,
    }
}

/// A compute shader's storage buffer at `binding` (any size).
pub fn compute_storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        wgpu::ShaderStages::COMPUTE,
        wgpu::BufferBindingType::Storage { read_only },
        None,
    )
}

/// A compute shader's uniform buffer at `binding` (any size).
pub fn compute_uniform(binding: u32) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(
        binding,
        wgpu::ShaderStages::COMPUTE,
        wgpu::BufferBindingType::Uniform,
        None,
    )
}

/// A pipeline layout of the bind `groups` (`None`: a group the pipeline does not use).
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &'static str,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: groups,
        immediate_size: 0,
    })
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;

    /// The vertex layouts' attributes sit at distinct shader locations within one
    /// element's bytes.
    #[test]
    fn vertex_buffers_are_consistent() {
        for buffer in [VertexBuffer::SAMPLES, VertexBuffer::MESH] {
            let locations: HashSet<u32> = buffer
                .attributes
                .iter()
                .map(|a| a.shader_location)
                .collect();
            assert_eq!(locations.len(), buffer.attributes.len());
            for a in buffer.attributes {
                assert!(a.offset + a.format.size() <= buffer.stride, "{a:?}");
            }
        }
    }

    /// Equal descriptions hash alike and a changed field tells them apart (what a
    /// cache of pipelines keyed by description needs).
    #[test]
    fn descriptions_are_hashable_keys() {
        let format = TargetFormat {
            color: wgpu::TextureFormat::Rgba8UnormSrgb,
            depth: wgpu::TextureFormat::Depth32Float,
            samples: 4,
        };
        let desc = RenderPipelineDesc {
            label: "test",
            vertex_entry: "vs",
            fragment_entry: "fs",
            vertex_buffers: vec![VertexBuffer::SAMPLES],
            targets: vec![format.color_target(None, wgpu::ColorWrites::ALL)],
            primitive: primitive(wgpu::PrimitiveTopology::TriangleStrip),
            depth_stencil: format.depth_test(true, wgpu::CompareFunction::Less, MESH_DEPTH_BIAS),
            multisample: format.multisample(),
        };
        let blended = RenderPipelineDesc {
            targets: vec![format.color_target(
                Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                wgpu::ColorWrites::ALL,
            )],
            ..desc.clone()
        };
        let set: HashSet<RenderPipelineDesc> = [desc.clone(), desc.clone(), blended].into();
        assert_eq!(set.len(), 2);
        let compute = ComputePipelineDesc {
            label: "c",
            entry: "cs",
        };
        assert_eq!(
            HashSet::from([
                compute,
                compute,
                ComputePipelineDesc {
                    entry: "cs2",
                    ..compute
                }
            ])
            .len(),
            2
        );
    }
}
