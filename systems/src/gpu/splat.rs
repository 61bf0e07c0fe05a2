//! The splat renderer: field-aligned elliptical splats (paper Figs. 4f and 12) or line
//! glyphs along the field, one instanced quad per sample, optionally over the mesh.
//!
//! Plain data in, draw commands out: [`SplatRenderer::upload`] takes `&[Sample]` (from
//! any sampler, an ECS resource or a file) and [`SplatRenderer::encode`] records one
//! render pass into caller-owned views, so the same renderer serves the headless
//! target, a window and, later, an ECS render system.
//!
//! Each quad spans the ellipse with semi-axes `splat_scale * spacing / 2` along the
//! sample's major axis (projected into its tangent plane) and `normal x major`; the
//! fragment stage cuts the ellipse (disc) or weighs it (Gaussian). A glyph
//! ([`Footprint::Glyph`]) is instead a thin quad along the major axis, `splat_scale`
//! times the larger spacing long and a fixed number of pixels wide (its ends are
//! projected and the quad widened across them on screen), in the splat colour darkened:
//! hatching that shows the field's direction. Depth-tested; samples facing away from the camera
//! are dropped in the vertex stage.

use glam::Vec3;
use strata_engine::mesh::TriMesh;
use strata_engine::sample::lod::ViewLod;
use strata_engine::sample::{Sample, Sampler};

use super::buffers::GpuSampleBuffer;
use super::camera::OrbitCamera;
use super::context::{GpuError, scoped};
use super::layout::{ColorMode, Footprint, FrameUniforms, MeshMode, MeshVertex};
pub use super::pipeline::TargetFormat;
use super::pipeline::{
    MESH_DEPTH_BIAS, RenderPipelineDesc, VertexBuffer, buffer_entry, pipeline_layout, primitive,
    shader_module, uniform_buffer,
};
use super::shaders;

/// How a frame looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatStyle {
    /// Splat colours.
    pub color_mode: ColorMode,
    /// Splat shape.
    pub footprint: Footprint,
    /// The mesh under the splats.
    pub mesh_mode: MeshMode,
    /// Semi-axes as a fraction of half the spacings (1: neighbours touch on average);
    /// a glyph's length as a fraction of the larger spacing. Default 0.8.
    pub splat_scale: f32,
    /// Colour of [`ColorMode::Constant`], sRGB. Default a warm orange.
    pub base_color: [f32; 3],
    /// Log-density range of the colour map (see
    /// [`log_density_range`](super::layout::log_density_range)).
    pub log_density_range: [f32; 2],
    /// Direction towards the key light, world space (normalized when used).
    pub light_dir: Vec3,
    /// Clear colour, sRGB.
    pub background: [f32; 3],
    /// Level of detail over progressive samples; `None` draws every sample.
    pub lod: Option<SplatLod>,
}

/// Level of detail in the splat pipelines: the samples' `index` is their progressive
/// rank, and a sample of rank `k` is drawn when `k < base x lod(p_k)`, its splat scaled
/// by its fade weight `clamp(base x lod(p_k) - k, 0, 1)` and its spacings by
/// `sqrt(expanded / (base lod(p_k)))` (the density there is `lod` times the base
/// density; the samples' spacings were expanded for `expanded`), with the
/// multiplier `lod` of [`ViewLod`] for the frame's
/// camera, evaluated in `f32` per sample in the vertex shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatLod {
    /// Samples over the whole surface at multiplier 1.
    pub base: f32,
    /// The base count the samples' spacings were expanded with (a pool's prefix,
    /// [`GpuLodPool`](super::lod::GpuLodPool)): a frame whose base count differs (a
    /// point budget's, [`LodPool::base_for_shown`](strata_engine::sample::LodPool::base_for_shown))
    /// still sizes splats to its density.
    pub expanded: f32,
    /// Projected area (pixels^2) of a unit of surface at multiplier 1.
    pub reference: f32,
    /// Clamp of the multiplier.
    pub max: f32,
    /// Back faces get multiplier 0.
    pub cull_back_faces: bool,
}

impl SplatLod {
    /// `base` samples over the surface at multiplier 1, where 1 is the projected area
    /// per unit area of a surface facing `camera` at its target's distance (so the
    /// first frame shows about `base` samples per visible area), clamped at `max`.
    pub fn for_camera(camera: &OrbitCamera, height: u32, base: f32, max: f32) -> Self {
        let f = focal_pixels(camera, height) as f32;
        Self {
            base,
            expanded: base,
            reference: f * f / (camera.distance * camera.distance),
            max,
            cull_back_faces: true,
        }
    }

    /// The CPU twin of this level of detail for `camera` and a target of `size`
    /// pixels: what [`LodPool`](strata_engine::sample::LodPool) and the reference
    /// visible sets are computed with.
    pub fn view(&self, camera: &OrbitCamera, size: (u32, u32)) -> ViewLod {
        let (w, h) = size;
        let aspect = w.max(1) as f32 / h.max(1) as f32;
        ViewLod {
            clip_from_world: camera.view_proj(aspect).as_dmat4(),
            eye: camera.eye().as_dvec3(),
            focal_pixels: focal_pixels(camera, h),
            reference: f64::from(self.reference),
            max: f64::from(self.max),
            cull_back_faces: self.cull_back_faces,
        }
    }
}

/// The focal length in pixels of `camera` on a target `height` pixels high.
pub(crate) fn focal_pixels(camera: &OrbitCamera, height: u32) -> f64 {
    f64::from(height.max(1)) / (2.0 * (f64::from(camera.fov_y) / 2.0).tan())
}

/// The frame uniforms of `camera` and `style` on a target of `size` pixels, with
/// splats lifted by `normal_offset` of their smaller spacing.
pub(crate) fn frame_uniforms(
    camera: &OrbitCamera,
    style: &SplatStyle,
    size: (u32, u32),
    normal_offset: f32,
) -> FrameUniforms {
    let (w, h) = size;
    let aspect = w.max(1) as f32 / h.max(1) as f32;
    let light = style.light_dir.normalize_or(Vec3::Y);
    let (lod_flags, lod, lod_spacing) = match style.lod {
        Some(l) => (
            1 | (u32::from(l.cull_back_faces) << 1),
            [l.base, l.reference, l.max, focal_pixels(camera, h) as f32],
            lod_spacing(&l),
        ),
        None => (0, [0.0; 4], 1.0),
    };
    FrameUniforms {
        view_proj: camera.view_proj(aspect).to_cols_array_2d(),
        eye: camera.eye().extend(1.0).to_array(),
        light_dir: light.extend(0.0).to_array(),
        base_color: [
            style.base_color[0],
            style.base_color[1],
            style.base_color[2],
            1.0,
        ],
        log_density_range: style.log_density_range,
        viewport: [w as f32, h as f32],
        splat_scale: style.splat_scale,
        color_mode: style.color_mode.code(),
        footprint: style.footprint.code(),
        mesh_mode: style.mesh_mode.code(),
        normal_offset,
        lod_flags,
        lod_spacing,
        _pad: 0,
        lod,
    }
}

/// The factor `sqrt(expanded / base)` of a level of detail's spacings (1 where either
/// count is not positive).
fn lod_spacing(l: &SplatLod) -> f32 {
    if l.base > 0.0 && l.expanded > 0.0 {
        (l.expanded / l.base).sqrt()
    } else {
        1.0
    }
}

impl Default for SplatStyle {
    fn default() -> Self {
        Self {
            color_mode: ColorMode::Density,
            footprint: Footprint::Disc,
            mesh_mode: MeshMode::Plain,
            splat_scale: 0.8,
            base_color: [0.95, 0.55, 0.2],
            log_density_range: [0.0, 1.0],
            light_dir: Vec3::new(0.4, 0.8, 0.45),
            background: [0.07, 0.075, 0.09],
            lod: None,
        }
    }
}

impl SplatStyle {
    /// The clear colour as a linear wgpu colour.
    pub fn clear_color(&self) -> wgpu::Color {
        let lin = |c: f32| f64::from(c.max(0.0)).powf(2.2);
        wgpu::Color {
            r: lin(self.background[0]),
            g: lin(self.background[1]),
            b: lin(self.background[2]),
            a: 1.0,
        }
    }
}

/// Where one frame is drawn.
#[derive(Clone, Copy, Debug)]
pub struct FrameTarget<'a> {
    /// Colour attachment (multisampled when the format has samples > 1).
    pub color: &'a wgpu::TextureView,
    /// Single-sample resolve target when `color` is multisampled.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// Depth attachment.
    pub depth: &'a wgpu::TextureView,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl<'a> FrameTarget<'a> {
    /// Begins a pass that clears colour to `clear` and depth to 1, resolves a
    /// multisampled colour, stores colour and discards depth (what every style's frame
    /// does).
    pub fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: self.color,
                depth_slice: None,
                resolve_target: self.resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: self.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// Pipelines, uniforms, the sample buffer and the optional mesh.
#[derive(Debug)]
pub struct SplatRenderer {
    format: TargetFormat,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    disc: wgpu::RenderPipeline,
    gaussian: wgpu::RenderPipeline,
    glyph: wgpu::RenderPipeline,
    mesh_pipeline: wgpu::RenderPipeline,
    samples: GpuSampleBuffer,
    mesh: Option<(wgpu::Buffer, u32)>,
}

impl SplatRenderer {
    /// Builds the pipelines for targets of `format`.
    pub fn new(device: &wgpu::Device, format: TargetFormat) -> Result<Self, GpuError> {
        let samples = GpuSampleBuffer::new(device)?;
        let Pipelines {
            uniforms,
            bind_group,
            disc,
            gaussian,
            glyph,
            mesh_pipeline,
        } = scoped(device, "building the splat pipelines", || {
            build_pipelines(device, format)
        })?;
        Ok(Self {
            format,
            uniforms,
            bind_group,
            disc,
            gaussian,
            glyph,
            mesh_pipeline,
            samples,
            mesh: None,
        })
    }

    /// The target format the pipelines were built for.
    pub fn format(&self) -> TargetFormat {
        self.format
    }

    /// Replaces the samples drawn (see [`GpuSampleBuffer::upload`]).
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        samples: &[Sample],
    ) -> Result<(), GpuError> {
        self.samples.upload(device, queue, samples)
    }

    /// The sample buffer.
    pub fn samples(&self) -> &GpuSampleBuffer {
        &self.samples
    }

    /// The sample buffer, for a GPU pass that writes the samples itself
    /// ([`SiteExpander`](super::expand::SiteExpander)).
    pub fn samples_mut(&mut self) -> &mut GpuSampleBuffer {
        &mut self.samples
    }

    /// The mesh vertex buffer and its vertex count, when a mesh is set (the stroke
    /// renderer draws it into depth).
    pub(crate) fn mesh_buffer(&self) -> Option<(&wgpu::Buffer, u32)> {
        self.mesh.as_ref().map(|(b, n)| (b, *n))
    }

    /// Uploads `mesh` (flat-shaded, one vertex per face corner) to draw under the
    /// splats; `face_segments[f]` colours face `f` in [`MeshMode::Segments`].
    pub fn set_mesh(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &TriMesh,
        face_segments: Option<&[u32]>,
    ) -> Result<(), GpuError> {
        let vertices = mesh_vertices(mesh, face_segments);
        let count = u32::try_from(vertices.len()).map_err(|_| GpuError::Limit {
            what: "mesh vertices",
            requested: vertices.len() as u64,
            limit: u64::from(u32::MAX),
        })?;
        let buffer = scoped(device, "uploading the mesh", || {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("strata mesh"),
                size: (std::mem::size_of_val(vertices.as_slice()) as u64).max(32),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&vertices));
            buffer
        })?;
        self.mesh = Some((buffer, count));
        Ok(())
    }

    /// Records one render pass: clear, the mesh (if set and wanted), the splats.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: FrameTarget<'_>,
        camera: &OrbitCamera,
        style: &SplatStyle,
    ) -> Result<(), GpuError> {
        // Lifted only over a mesh, where flat splats would otherwise cut into it.
        let lift = if style.mesh_mode == MeshMode::None || self.mesh.is_none() {
            0.0
        } else {
            0.05
        };
        let uniforms = frame_uniforms(camera, style, target.size, lift);
        scoped(device, "drawing splats", || {
            queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
            let mut pass = target.begin_pass(encoder, "strata splats", style.clear_color());
            pass.set_bind_group(0, &self.bind_group, &[]);
            if let (Some((mesh, count)), false) = (&self.mesh, style.mesh_mode == MeshMode::None) {
                pass.set_pipeline(&self.mesh_pipeline);
                pass.set_vertex_buffer(0, mesh.slice(..));
                pass.draw(0..*count, 0..1);
            }
            let n = self.samples.len() as u32;
            if n > 0 {
                pass.set_pipeline(match style.footprint {
                    Footprint::Disc => &self.disc,
                    Footprint::Gaussian => &self.gaussian,
                    Footprint::Glyph => &self.glyph,
                });
                pass.set_vertex_buffer(0, self.samples.buffer().slice(..));
                pass.draw(0..4, 0..n);
            }
        })
    }
}

/// The segment of every face of `sampler`'s mesh (`u32::MAX` for faces no segment
/// samples), for [`MeshMode::Segments`].
pub fn face_segments(sampler: &Sampler) -> Vec<u32> {
    let mut out = vec![u32::MAX; sampler.mesh().face_count()];
    for s in sampler.segments() {
        for &f in &s.faces {
            if let Some(slot) = out.get_mut(f as usize) {
                *slot = s.segment;
            }
        }
    }
    out
}

fn mesh_vertices(mesh: &TriMesh, face_segments: Option<&[u32]>) -> Vec<MeshVertex> {
    let positions = mesh.positions();
    let normals = mesh.face_normals();
    let mut out = Vec::with_capacity(mesh.face_count() * 3);
    for (f, tri) in mesh.triangles().iter().enumerate() {
        let n = normals[f].as_vec3();
        let segment = face_segments
            .and_then(|s| s.get(f).copied())
            .unwrap_or(u32::MAX);
        for &v in tri {
            out.push(MeshVertex {
                position: positions[v as usize].as_vec3().to_array(),
                segment,
                normal: n.to_array(),
                _pad: 0,
            });
        }
    }
    out
}

/// What [`build_pipelines`] makes.
struct Pipelines {
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    disc: wgpu::RenderPipeline,
    gaussian: wgpu::RenderPipeline,
    glyph: wgpu::RenderPipeline,
    mesh_pipeline: wgpu::RenderPipeline,
}

fn build_pipelines(device: &wgpu::Device, format: TargetFormat) -> Pipelines {
    let size = size_of::<FrameUniforms>();
    let uniforms = uniform_buffer(device, "strata frame uniforms", size);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("strata frame"),
        entries: &[buffer_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            wgpu::BufferBindingType::Uniform,
            Some(size),
        )],
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("strata frame"),
        layout: &layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniforms.as_entire_binding(),
        }],
    });
    let pipeline_layout = pipeline_layout(device, "strata", &[Some(&layout)]);
    let splat_module = shader_module(device, "splat.wgsl", shaders::SPLAT);
    let mesh_module = shader_module(device, "mesh.wgsl", shaders::MESH);
    let [disc, glyph, gaussian] =
        splat_pipelines(format).map(|d| d.create(device, &pipeline_layout, &splat_module));
    let mesh_pipeline = mesh_pipeline(format).create(device, &pipeline_layout, &mesh_module);
    Pipelines {
        uniforms,
        bind_group,
        disc,
        gaussian,
        glyph,
        mesh_pipeline,
    }
}

/// The disc, glyph and Gaussian pipelines (`splat.wgsl`): instanced quads, the
/// Gaussian blended and not writing depth.
fn splat_pipelines(format: TargetFormat) -> [RenderPipelineDesc; 3] {
    let splat = |vs, fs, blend, depth_write| RenderPipelineDesc {
        label: fs,
        vertex_entry: vs,
        fragment_entry: fs,
        vertex_buffers: vec![VertexBuffer::SAMPLES],
        targets: vec![format.color_target(blend, wgpu::ColorWrites::ALL)],
        primitive: primitive(wgpu::PrimitiveTopology::TriangleStrip),
        depth_stencil: format.depth_test(
            depth_write,
            wgpu::CompareFunction::Less,
            Default::default(),
        ),
        multisample: format.multisample(),
    };
    [
        splat("vs_splat", "fs_disc", None, true),
        splat("vs_glyph", "fs_glyph", None, true),
        splat(
            "vs_splat",
            "fs_gaussian",
            Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            false,
        ),
    ]
}

/// The mesh under the splats (`mesh.wgsl`), its depth pushed back.
fn mesh_pipeline(format: TargetFormat) -> RenderPipelineDesc {
    RenderPipelineDesc {
        label: "strata mesh",
        vertex_entry: "vs_mesh",
        fragment_entry: "fs_mesh",
        vertex_buffers: vec![VertexBuffer::MESH],
        targets: vec![format.color_target(None, wgpu::ColorWrites::ALL)],
        primitive: primitive(wgpu::PrimitiveTopology::TriangleList),
        depth_stencil: format.depth_test(true, wgpu::CompareFunction::Less, MESH_DEPTH_BIAS),
        multisample: format.multisample(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame whose base count differs from the one the samples were expanded with
    /// (a point budget's) scales their spacings by `sqrt(expanded / base)`: a quarter
    /// of the base count, twice the spacing; without level of detail, 1.
    #[test]
    fn spacings_follow_the_frames_base_count() {
        let camera = OrbitCamera {
            target: Vec3::ZERO,
            distance: 3.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 0.8,
            radius: 1.0,
        };
        let lod = SplatLod::for_camera(&camera, 240, 40_000.0, 4.0);
        assert_eq!(lod.expanded, 40_000.0);
        let at = |lod: Option<SplatLod>| {
            let style = SplatStyle {
                lod,
                ..SplatStyle::default()
            };
            frame_uniforms(&camera, &style, (320, 240), 0.0).lod_spacing
        };
        assert_eq!(at(Some(lod)), 1.0);
        let quarter = SplatLod {
            base: 10_000.0,
            ..lod
        };
        assert!((at(Some(quarter)) - 2.0).abs() < 1e-6);
        assert_eq!(at(None), 1.0);
        let (layout, uniforms) = (
            std::mem::size_of::<FrameUniforms>(),
            frame_uniforms(&camera, &SplatStyle::default(), (1, 1), 0.0),
        );
        assert_eq!(layout, 176, "the WGSL twin's size");
        assert_eq!(uniforms._pad, 0);
    }
}
