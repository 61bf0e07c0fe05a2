//! Non-photorealistic rendering (issue 21; the paper's Figs. 1, 3, 13 and 14): the
//! samples drawn as painted strokes with a procedural brush, or as stipple dots, on a
//! procedural paper (`shaders/npr.wgsl`).
//!
//! Input: the [`SplatRenderer`]'s sample buffer (the same instance records the splats
//! read, no second data path) and its mesh; output: one render pass. Each sample is one
//! instanced quad; a stroke lies in the sample's tangent plane along the axis of larger
//! spacing, sized by the spacings, with size, angle and hue varied by a hash of the
//! sample's rank and the seed, and coloured from a palette by Lambert tone. Colour
//! writes use min ("darken") blending, so the picture is the same, bit for bit,
//! whatever order the strokes are drawn in (the shader's header says why).
//!
//! Cost: one instanced quad per sample plus a full-screen paper triangle and the mesh
//! in depth only; the brushes are a few value-noise lookups per fragment.

use super::camera::OrbitCamera;
use super::context::{GpuError, scoped};
use super::layout::{FrameUniforms, NprUniforms};
use super::pipeline::{
    MESH_DEPTH_BIAS, RenderPipelineDesc, TargetFormat, VertexBuffer, buffer_entry, pipeline_layout,
    primitive, shader_module, uniform_buffer,
};
use super::shaders;
use super::splat::{FrameTarget, SplatRenderer, SplatStyle, frame_uniforms};

/// How `strata render` draws the samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RenderStyle {
    /// Field-aligned ellipses or glyphs ([`SplatRenderer`]).
    #[default]
    Splats,
    /// Round ink dots whose size follows the tone.
    Stipple,
    /// Painted strokes with a [`Brush`].
    Strokes,
}

impl RenderStyle {
    /// Every style, in the order of [`RenderStyle::NAMES`].
    pub const ALL: [Self; 3] = [Self::Splats, Self::Stipple, Self::Strokes];
    /// The styles' command-line names.
    pub const NAMES: [&'static str; 3] = ["splats", "stipple", "strokes"];

    /// The style named `name` (one of [`NAMES`](Self::NAMES)), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }

    /// The style's command-line name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The next style in [`ALL`](Self::ALL), after the last the first.
    pub fn next(self) -> Self {
        Self::ALL[(self as usize + 1) % Self::ALL.len()]
    }
}

/// The brush of [`RenderStyle::Strokes`]: a procedural texture in `fs_stroke`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Brush {
    /// Opaque paint with bristle streaks along the stroke, drier at its tail.
    #[default]
    Acrylic,
    /// Wax that only catches the paper's tooth: grainy, fuller in dark tones.
    Crayon,
    /// A light, blotchy wash with an irregular rim and wet darkened edges.
    Watercolor,
    /// Thin graphite lines with paper grain, lighter at both ends.
    Pencil,
    /// Thin solid ink lines tapered to points.
    Ink,
}

impl Brush {
    /// Every brush, in the order of [`Brush::NAMES`].
    pub const ALL: [Self; 5] = [
        Self::Acrylic,
        Self::Crayon,
        Self::Watercolor,
        Self::Pencil,
        Self::Ink,
    ];
    /// The brushes' command-line names.
    pub const NAMES: [&'static str; 5] = ["acrylic", "crayon", "watercolor", "pencil", "ink"];

    /// The brush named `name` (one of [`NAMES`](Self::NAMES)), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }

    /// The brush's command-line name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The value `fs_stroke` switches on ([`NprUniforms::brush`]).
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The next brush in [`ALL`](Self::ALL), after the last the first.
    pub fn next(self) -> Self {
        Self::ALL[(self as usize + 1) % Self::ALL.len()]
    }
}

/// What an [`NprRenderer`] draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NprKind {
    /// Stipple dots.
    Stipple,
    /// Strokes with a brush.
    Strokes(Brush),
}

impl NprKind {
    /// The value of [`NprUniforms::style`]: 0 stipple, 1 strokes.
    pub fn code(self) -> u32 {
        match self {
            Self::Stipple => 0,
            Self::Strokes(_) => 1,
        }
    }
}

/// The look of a stroke or stipple picture. Colours are sRGB in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NprStyle {
    /// Stipple or strokes with a brush.
    pub kind: NprKind,
    /// Seed of the per-stroke variation and of the paper and brush textures.
    pub seed: u32,
    /// Palette by tone: shadow, mid-tone, light (the paints; pencil, ink and stipple use
    /// [`ink`](Self::ink)). Default ultramarine, burnt sienna, Naples yellow.
    pub palette: [[f32; 3]; 3],
    /// Ink of stipple dots, pencil and ink strokes. Default near black.
    pub ink: [f32; 3],
    /// Paper colour. Default a warm off-white.
    pub paper: [f32; 3],
    /// Relative spread of stroke and dot size, `[0, 1)`: a stroke's size is scaled by
    /// a factor in `1 +- size_jitter`. Default 0.25 (0.15 for stipple).
    pub size_jitter: f32,
    /// Relative spread of each colour channel of a stroke, `[0, 1)`. Default 0.12 for
    /// the paints, 0.05 for pencil, 0 for ink.
    pub hue_jitter: f32,
    /// Stroke length as a multiple of the larger spacing (times the splat scale);
    /// above 1 neighbours overlap. Default 2 (watercolour and ink 1.8).
    pub stroke_length: f32,
    /// Stroke width as a multiple of the smaller spacing (times the splat scale),
    /// capped at 0.45 of the length. Default 1.6 for acrylic, 1.5 crayon, 1.8
    /// watercolour, 1 for pencil and 0.6 for ink (their lines thin in light tones).
    pub stroke_width: f32,
}

impl NprStyle {
    /// The default look of `kind` with `seed`.
    pub fn new(kind: NprKind, seed: u32) -> Self {
        let (size_jitter, hue_jitter, stroke_length, stroke_width) = match kind {
            NprKind::Stipple => (0.15, 0.0, 1.0, 1.0),
            NprKind::Strokes(Brush::Acrylic) => (0.25, 0.12, 2.0, 1.6),
            NprKind::Strokes(Brush::Crayon) => (0.25, 0.1, 2.0, 1.5),
            NprKind::Strokes(Brush::Watercolor) => (0.3, 0.15, 1.8, 1.8),
            NprKind::Strokes(Brush::Pencil) => (0.2, 0.05, 2.0, 1.0),
            NprKind::Strokes(Brush::Ink) => (0.2, 0.0, 1.8, 0.6),
        };
        Self {
            kind,
            seed,
            palette: [[0.1, 0.14, 0.4], [0.78, 0.32, 0.12], [0.96, 0.74, 0.3]],
            ink: [0.07, 0.06, 0.08],
            paper: [0.97, 0.95, 0.9],
            size_jitter,
            hue_jitter,
            stroke_length,
            stroke_width,
        }
    }

    /// The default look of `kind` for samples drawn with the 64-bit sample `seed`
    /// (folded to 32 bits): the same samples give the same picture.
    pub fn for_samples(kind: NprKind, seed: u64) -> Self {
        Self::new(kind, (seed ^ (seed >> 32)) as u32)
    }

    /// The uniforms of this style for `camera` on a target `height` pixels high.
    pub fn uniforms(&self, camera: &OrbitCamera, height: u32) -> NprUniforms {
        let c = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
        NprUniforms {
            shadow: c(self.palette[0]),
            mid: c(self.palette[1]),
            light: c(self.palette[2]),
            ink: c(self.ink),
            paper: c(self.paper),
            style: self.kind.code(),
            brush: match self.kind {
                NprKind::Strokes(b) => b.code(),
                NprKind::Stipple => 0,
            },
            seed: self.seed,
            focal_px: super::splat::focal_pixels(camera, height) as f32,
            size_jitter: self.size_jitter,
            hue_jitter: self.hue_jitter,
            stroke_length: self.stroke_length,
            stroke_width: self.stroke_width,
        }
    }
}

/// A style and a brush as `strata view`'s keys change them: the brush is kept while
/// the style is not strokes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StyleChoice {
    /// How the samples are drawn.
    pub style: RenderStyle,
    /// The brush of [`RenderStyle::Strokes`].
    pub brush: Brush,
}

impl StyleChoice {
    /// The choice that draws `kind` (`None`: splats).
    pub fn new(kind: Option<NprKind>) -> Self {
        match kind {
            None => Self::default(),
            Some(NprKind::Stipple) => Self {
                style: RenderStyle::Stipple,
                brush: Brush::default(),
            },
            Some(NprKind::Strokes(brush)) => Self {
                style: RenderStyle::Strokes,
                brush,
            },
        }
    }

    /// What an [`NprRenderer`] draws for this choice; `None` for splats.
    pub fn kind(self) -> Option<NprKind> {
        match self.style {
            RenderStyle::Splats => None,
            RenderStyle::Stipple => Some(NprKind::Stipple),
            RenderStyle::Strokes => Some(NprKind::Strokes(self.brush)),
        }
    }

    /// The next style (splats, stipple, strokes, splats, ...), the same brush.
    pub fn next_style(self) -> Self {
        Self {
            style: self.style.next(),
            ..self
        }
    }

    /// Strokes with the next brush; from another style, strokes with the same brush.
    pub fn next_brush(self) -> Self {
        Self {
            style: RenderStyle::Strokes,
            brush: if self.style == RenderStyle::Strokes {
                self.brush.next()
            } else {
                self.brush
            },
        }
    }
}

impl std::fmt::Display for StyleChoice {
    /// `splats`, `stipple` or `strokes (acrylic)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.style {
            RenderStyle::Strokes => write!(f, "strokes ({})", self.brush.name()),
            style => f.write_str(style.name()),
        }
    }
}

/// One frame of a sample buffer in the chosen style, as a window draws it: splats
/// through the [`SplatRenderer`], stipple and strokes through an [`NprRenderer`] built
/// for the target's format on first use and kept (a frame allocates no buffer).
#[derive(Debug)]
pub struct StyledFrame {
    /// What the next frames draw.
    pub choice: StyleChoice,
    format: TargetFormat,
    npr: Option<NprRenderer>,
}

impl StyledFrame {
    /// Frames in `choice` into targets of `format`; builds the stroke pipelines now
    /// when `choice` needs them, so that a format they cannot draw into fails here.
    pub fn new(
        device: &wgpu::Device,
        format: TargetFormat,
        choice: StyleChoice,
    ) -> Result<Self, GpuError> {
        let mut frame = Self {
            choice,
            format,
            npr: None,
        };
        if choice.kind().is_some() {
            frame.npr = Some(NprRenderer::new(device, format)?);
        }
        Ok(frame)
    }

    /// Records one render pass of `splats`' samples (and mesh) into `target`: splats
    /// with `look`, or stipple or strokes ([`NprRenderer::encode`]) with the default
    /// [`NprStyle`] for the sample `seed`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: FrameTarget<'_>,
        camera: &OrbitCamera,
        splats: &SplatRenderer,
        look: &SplatStyle,
        seed: u64,
    ) -> Result<(), GpuError> {
        let Some(kind) = self.choice.kind() else {
            return splats.encode(device, queue, encoder, target, camera, look);
        };
        // Built on the first frame that needs it (a key switched away from splats).
        let npr = match &mut self.npr {
            Some(npr) => npr,
            slot @ None => slot.insert(NprRenderer::new(device, self.format)?),
        };
        let style = NprStyle::for_samples(kind, seed);
        npr.encode(device, queue, encoder, target, camera, splats, look, &style)
    }
}

/// Min ("darken") blending: the result is the per-channel minimum of what is there and
/// what is drawn, whatever the order (see the module docs).
const DARKEN: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Min,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Min,
    },
};

/// Strokes lie this fraction of their smaller spacing above the surface, and the mesh's
/// depth is pushed back (its depth bias), so that strokes on the surface pass the
/// depth test and those behind it fail.
const STROKE_LIFT: f32 = 0.1;

/// The paper, depth-only mesh, stroke and stipple pipelines with their uniforms.
#[derive(Debug)]
pub struct NprRenderer {
    format: TargetFormat,
    frame: wgpu::Buffer,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    paper: wgpu::RenderPipeline,
    depth: wgpu::RenderPipeline,
    strokes: wgpu::RenderPipeline,
    stipple: wgpu::RenderPipeline,
}

impl NprRenderer {
    /// Builds the pipelines for targets of `format`.
    pub fn new(device: &wgpu::Device, format: TargetFormat) -> Result<Self, GpuError> {
        scoped(device, "building the stroke pipelines", || {
            build(device, format)
        })
    }

    /// The target format the pipelines were built for.
    pub fn format(&self) -> TargetFormat {
        self.format
    }

    /// Records one render pass: paper, `splats`' mesh into depth (when set), then one
    /// stroke or dot per sample of `splats`' buffer. `look` gives the light direction
    /// and the size scale ([`SplatStyle::splat_scale`]); its colours and footprint are
    /// not used.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: FrameTarget<'_>,
        camera: &OrbitCamera,
        splats: &SplatRenderer,
        look: &SplatStyle,
        style: &NprStyle,
    ) -> Result<(), GpuError> {
        let frame = frame_uniforms(camera, look, target.size, STROKE_LIFT);
        let params = style.uniforms(camera, target.size.1);
        scoped(device, "drawing strokes", || {
            queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            // White: the identity of min blending.
            let mut pass = target.begin_pass(encoder, "strata strokes", wgpu::Color::WHITE);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_pipeline(&self.paper);
            pass.draw(0..3, 0..1);
            if let Some((mesh, count)) = splats.mesh_buffer() {
                pass.set_pipeline(&self.depth);
                pass.set_vertex_buffer(0, mesh.slice(..));
                pass.draw(0..count, 0..1);
            }
            let n = splats.samples().len() as u32;
            if n > 0 {
                pass.set_pipeline(match style.kind {
                    NprKind::Stipple => &self.stipple,
                    NprKind::Strokes(_) => &self.strokes,
                });
                pass.set_vertex_buffer(0, splats.samples().buffer().slice(..));
                pass.draw(0..4, 0..n);
            }
        })
    }
}

fn build(device: &wgpu::Device, format: TargetFormat) -> NprRenderer {
    let frame_size = size_of::<FrameUniforms>();
    let params_size = size_of::<NprUniforms>();
    let frame = uniform_buffer(device, "strata stroke frame uniforms", frame_size);
    let params = uniform_buffer(device, "strata stroke uniforms", params_size);
    let entry = |binding, size| {
        buffer_entry(
            binding,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            wgpu::BufferBindingType::Uniform,
            Some(size),
        )
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("strata strokes"),
        entries: &[entry(0, frame_size), entry(1, params_size)],
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("strata strokes"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: frame.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: params.as_entire_binding(),
            },
        ],
    });
    let pipeline_layout = pipeline_layout(device, "strata strokes", &[Some(&layout)]);
    let module = shader_module(device, "npr.wgsl", shaders::NPR);
    let [paper, depth, strokes, stipple] =
        pipelines(format).map(|d| d.create(device, &pipeline_layout, &module));
    NprRenderer {
        format,
        frame,
        params,
        bind_group,
        paper,
        depth,
        strokes,
        stipple,
    }
}

/// The paper, depth-only mesh, stroke and stipple pipelines (`npr.wgsl`): all blend
/// with [`DARKEN`]; they differ in entry points, vertex buffer, topology, depth test
/// and whether colour is written.
fn pipelines(format: TargetFormat) -> [RenderPipelineDesc; 4] {
    let desc = |vs, fs, buffer: Option<VertexBuffer>, topology, depth_stencil, writes| {
        RenderPipelineDesc {
            label: fs,
            vertex_entry: vs,
            fragment_entry: fs,
            vertex_buffers: buffer.into_iter().collect(),
            targets: vec![format.color_target(Some(DARKEN), writes)],
            primitive: primitive(topology),
            depth_stencil,
            multisample: format.multisample(),
        }
    };
    let instanced = |vs, fs| {
        desc(
            vs,
            fs,
            Some(VertexBuffer::SAMPLES),
            wgpu::PrimitiveTopology::TriangleStrip,
            // Tested against the mesh, never written: no stroke hides another.
            format.depth_test(false, wgpu::CompareFunction::Less, Default::default()),
            wgpu::ColorWrites::ALL,
        )
    };
    let list = wgpu::PrimitiveTopology::TriangleList;
    [
        desc(
            "vs_paper",
            "fs_paper",
            None,
            list,
            format.depth_test(false, wgpu::CompareFunction::Always, Default::default()),
            wgpu::ColorWrites::ALL,
        ),
        // As the splat renderer's mesh: pushed back so that strokes on a face win.
        desc(
            "vs_depth",
            "fs_depth",
            Some(VertexBuffer::MESH),
            list,
            format.depth_test(true, wgpu::CompareFunction::Less, MESH_DEPTH_BIAS),
            wgpu::ColorWrites::empty(),
        ),
        instanced("vs_stroke", "fs_stroke"),
        instanced("vs_stipple", "fs_stipple"),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_none() {
        for s in RenderStyle::ALL {
            assert_eq!(RenderStyle::from_name(s.name()), Some(s));
        }
        for b in Brush::ALL {
            assert_eq!(Brush::from_name(b.name()), Some(b));
            assert_eq!(Brush::ALL[b.code() as usize], b);
        }
        assert_eq!(RenderStyle::from_name("Strokes"), None);
        assert_eq!(Brush::from_name("oil"), None);
    }

    #[test]
    fn keys_cycle_styles_and_brushes() {
        let mut choice = StyleChoice::new(None);
        let mut seen = Vec::new();
        for _ in 0..3 {
            seen.push(choice.to_string());
            choice = choice.next_style();
        }
        assert_eq!(seen, ["splats", "stipple", "strokes (acrylic)"]);
        assert_eq!(choice, StyleChoice::default());
        // From splats, the brush key shows strokes with the current brush first.
        let strokes = choice.next_brush();
        assert_eq!(strokes.kind(), Some(NprKind::Strokes(Brush::Acrylic)));
        let mut brushes = vec![strokes.brush];
        let mut c = strokes;
        for _ in 1..Brush::ALL.len() {
            c = c.next_brush();
            brushes.push(c.brush);
        }
        assert_eq!(brushes, Brush::ALL);
        assert_eq!(c.next_brush().brush, Brush::Acrylic);
        for kind in [
            None,
            Some(NprKind::Stipple),
            Some(NprKind::Strokes(Brush::Ink)),
        ] {
            assert_eq!(StyleChoice::new(kind).kind(), kind);
        }
    }

    #[test]
    fn line_brushes_are_thinner_than_paints() {
        let width = |b| NprStyle::new(NprKind::Strokes(b), 0).stroke_width;
        for line in [Brush::Pencil, Brush::Ink] {
            for paint in [Brush::Acrylic, Brush::Crayon, Brush::Watercolor] {
                assert!(width(line) < width(paint));
            }
        }
    }
}
