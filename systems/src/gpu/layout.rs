//! GPU-visible structs: `#[repr(C)]`, `bytemuck::Pod`, a compile-time size check, and
//! the name of each one's WGSL twin in `shaders/common.wgsl`.
//!
//! The per-sample record is the engine's [`Sample`] itself (64 bytes, uploaded as is);
//! its WGSL twin is `Sample` in `shaders/common.wgsl`, read by the splat pipeline as an
//! instance-rate vertex buffer whose attributes are [`SAMPLE_ATTRIBUTES`]. A unit test
//! parses the WGSL with naga and checks every member offset against the Rust struct.

use std::mem::{offset_of, size_of};

use strata_engine::sample::Sample;

/// How the splats are coloured; the `color_mode` of [`FrameUniforms`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ColorMode {
    /// Sample density `1 / (spacing_major * spacing_minor)` on a log scale (viridis).
    #[default]
    Density,
    /// One hue per segment (the atlas's and `strata segment`'s hues).
    Segment,
    /// [`SplatStyle::base_color`](super::splat::SplatStyle::base_color) everywhere.
    Constant,
}

impl ColorMode {
    /// The value the shader switches on.
    pub fn code(self) -> u32 {
        match self {
            Self::Density => 0,
            Self::Segment => 1,
            Self::Constant => 2,
        }
    }
}

/// The shape of one splat in the fragment stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Footprint {
    /// An opaque ellipse with a darkened rim, depth-written.
    #[default]
    Disc,
    /// A Gaussian blob blended over what is behind it (depth-tested, not written).
    Gaussian,
    /// A thin line along the sample's major axis (the field's direction), `splat_scale`
    /// times the larger spacing long and a couple of pixels wide, in the splat colour
    /// darkened: hatching that shows the field. Depth-written.
    Glyph,
}

impl Footprint {
    /// The value of [`FrameUniforms::footprint`].
    pub fn code(self) -> u32 {
        match self {
            Self::Disc => 0,
            Self::Gaussian => 1,
            Self::Glyph => 2,
        }
    }
}

/// How the mesh under the splats is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum MeshMode {
    /// Not drawn.
    None,
    /// Plain grey, lit.
    #[default]
    Plain,
    /// Each face in its segment's hue, lit.
    Segments,
}

impl MeshMode {
    /// The value the mesh shader switches on.
    pub fn code(self) -> u32 {
        match self {
            Self::None | Self::Plain => 0,
            Self::Segments => 1,
        }
    }
}

/// Per-frame uniforms shared by the splat and the mesh pipelines. WGSL twin: `Frame` in
/// `shaders/common.wgsl` (bind group 0, binding 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// Clip-from-world matrix, column major.
    pub view_proj: [[f32; 4]; 4],
    /// Camera position in world space (w unused).
    pub eye: [f32; 4],
    /// Unit direction towards the light, world space (w unused).
    pub light_dir: [f32; 4],
    /// Colour of [`ColorMode::Constant`] splats, sRGB, alpha unused.
    pub base_color: [f32; 4],
    /// Natural log of the density that maps to the bottom and the top of the colour
    /// map in [`ColorMode::Density`].
    pub log_density_range: [f32; 2],
    /// Target size in pixels.
    pub viewport: [f32; 2],
    /// Splat semi-axes as a fraction of the sample spacings: semi-axis k is
    /// `splat_scale * spacing[k] / 2`, so 1 makes neighbours just touch on average.
    /// A glyph is `splat_scale * max(spacing[0], spacing[1])` long.
    pub splat_scale: f32,
    /// [`ColorMode::code`].
    pub color_mode: u32,
    /// [`Footprint::code`].
    pub footprint: u32,
    /// [`MeshMode::code`].
    pub mesh_mode: u32,
    /// Splats are lifted along their normal by this fraction of their smaller spacing,
    /// so that they do not fight with the mesh for depth.
    pub normal_offset: f32,
    /// Level of detail: bit 0 on (splats are culled and faded by rank, see
    /// [`SplatLod`](super::splat::SplatLod)), bit 1 back faces get multiplier 0.
    pub lod_flags: u32,
    /// Level of detail: the factor of the samples' spacings, `sqrt(expanded / base)`
    /// ([`SplatLod::expanded`](super::splat::SplatLod::expanded)).
    pub lod_spacing: f32,
    /// Padding to the next 16 bytes.
    pub _pad: u32,
    /// Level of detail: base count, reference area (pixels^2 per unit area), the
    /// multiplier's clamp and the focal length in pixels.
    pub lod: [f32; 4],
}

/// One mesh vertex of the (unindexed) mesh drawn under the splats. WGSL twin: the
/// `MeshVertex` input of `shaders/mesh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    /// Position, world space.
    pub position: [f32; 3],
    /// Segment of the face (for [`MeshMode::Segments`]); `u32::MAX` when unknown.
    pub segment: u32,
    /// Unit normal (the face normal: faces are drawn flat).
    pub normal: [f32; 3],
    /// Padding.
    pub _pad: u32,
}

/// Per-frame uniforms of the stroke and stipple pipelines (bind group 0, binding 1,
/// beside [`FrameUniforms`]). WGSL twin: `NprParams` in `shaders/npr.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct NprUniforms {
    /// Palette colour of the darkest tone, sRGB (alpha unused).
    pub shadow: [f32; 4],
    /// Palette colour of the middle tone, sRGB.
    pub mid: [f32; 4],
    /// Palette colour of the lightest tone, sRGB.
    pub light: [f32; 4],
    /// Ink of stipple dots and of pencil and ink strokes, sRGB.
    pub ink: [f32; 4],
    /// Paper colour, sRGB.
    pub paper: [f32; 4],
    /// [`NprKind::code`](super::npr::NprKind::code).
    pub style: u32,
    /// [`Brush::code`](super::npr::Brush::code).
    pub brush: u32,
    /// Seed of the per-stroke hash and of the paper and brush textures.
    pub seed: u32,
    /// Focal length of the camera in pixels.
    pub focal_px: f32,
    /// Relative spread of stroke and dot size.
    pub size_jitter: f32,
    /// Relative spread of stroke colour.
    pub hue_jitter: f32,
    /// Stroke length as a multiple of the larger spacing.
    pub stroke_length: f32,
    /// Stroke width as a multiple of the smaller spacing.
    pub stroke_width: f32,
}

const _: () = assert!(size_of::<Sample>() == 64);
const _: () = assert!(size_of::<NprUniforms>() == 112);
const _: () = assert!(size_of::<FrameUniforms>() == 176);
const _: () = assert!(size_of::<FrameUniforms>().is_multiple_of(16));
const _: () = assert!(size_of::<MeshVertex>() == 32);

/// The vertex attributes of one [`Sample`] read at instance rate: locations 0-7, one per
/// field, at the field's offset. Formats follow the WGSL `SampleInput` of
/// `shaders/splat.wgsl`.
pub const SAMPLE_ATTRIBUTES: [wgpu::VertexAttribute; 8] = [
    attribute(
        0,
        offset_of!(Sample, position),
        wgpu::VertexFormat::Float32x3,
    ),
    attribute(1, offset_of!(Sample, face), wgpu::VertexFormat::Uint32),
    attribute(2, offset_of!(Sample, normal), wgpu::VertexFormat::Float32x3),
    attribute(3, offset_of!(Sample, segment), wgpu::VertexFormat::Uint32),
    attribute(
        4,
        offset_of!(Sample, major_axis),
        wgpu::VertexFormat::Float32x3,
    ),
    attribute(5, offset_of!(Sample, index), wgpu::VertexFormat::Uint32),
    attribute(6, offset_of!(Sample, bary), wgpu::VertexFormat::Float32x2),
    attribute(
        7,
        offset_of!(Sample, spacing),
        wgpu::VertexFormat::Float32x2,
    ),
];

/// The vertex attributes of one [`MeshVertex`].
pub const MESH_ATTRIBUTES: [wgpu::VertexAttribute; 3] = [
    attribute(
        0,
        offset_of!(MeshVertex, position),
        wgpu::VertexFormat::Float32x3,
    ),
    attribute(
        1,
        offset_of!(MeshVertex, segment),
        wgpu::VertexFormat::Uint32,
    ),
    attribute(
        2,
        offset_of!(MeshVertex, normal),
        wgpu::VertexFormat::Float32x3,
    ),
];

const fn attribute(
    shader_location: u32,
    offset: usize,
    format: wgpu::VertexFormat,
) -> wgpu::VertexAttribute {
    wgpu::VertexAttribute {
        format,
        offset: offset as u64,
        shader_location,
    }
}

/// The natural log of the 1st and 99th percentile of the density
/// `1 / (spacing[0] spacing[1])` among `samples` (at most 4096 of them, evenly strided),
/// for [`FrameUniforms::log_density_range`]: percentiles, so that a few samples in the
/// isotropic fallback near singularities do not flatten the colour map. `[0, 1]` without
/// samples with positive spacings; a unit-wide range around a constant density.
pub fn log_density_range(samples: &[Sample]) -> [f32; 2] {
    let stride = samples.len().div_ceil(4096).max(1);
    let mut values: Vec<f32> = samples
        .iter()
        .step_by(stride)
        .map(|s| s.spacing[0] * s.spacing[1])
        .filter(|a| *a > 0.0 && a.is_finite())
        .map(|a| -a.ln())
        .collect();
    if values.is_empty() {
        return [0.0, 1.0];
    }
    values.sort_by(f32::total_cmp);
    let last = values.len() - 1;
    let lo = values[last / 100];
    let hi = values[last - last / 100];
    if hi - lo < 1e-3 {
        return [lo - 0.5, hi + 0.5];
    }
    [lo, hi]
}

#[cfg(test)]
mod tests {
    use super::super::wgsl_layout::wgsl_layout;
    use super::*;

    /// The WGSL `Sample` and `Frame` structs have the Rust structs' sizes and offsets.
    #[test]
    fn wgsl_twins_match_rust_layouts() {
        let layout = |name: &str| wgsl_layout(super::super::shaders::COMMON, name);
        let (members, span) = layout("Sample");
        assert_eq!(span, size_of::<Sample>());
        let expected = [
            ("position", offset_of!(Sample, position)),
            ("face", offset_of!(Sample, face)),
            ("normal", offset_of!(Sample, normal)),
            ("segment", offset_of!(Sample, segment)),
            ("major_axis", offset_of!(Sample, major_axis)),
            ("index", offset_of!(Sample, index)),
            ("bary", offset_of!(Sample, bary)),
            ("spacing", offset_of!(Sample, spacing)),
        ];
        let expected: Vec<(String, usize)> =
            expected.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(members, expected);
        // The vertex attributes name the same offsets.
        for (a, (_, o)) in SAMPLE_ATTRIBUTES.iter().zip(&expected) {
            assert_eq!(a.offset as usize, *o);
        }

        let (members, span) = layout("Frame");
        assert_eq!(span, size_of::<FrameUniforms>());
        let expected = [
            ("view_proj", offset_of!(FrameUniforms, view_proj)),
            ("eye", offset_of!(FrameUniforms, eye)),
            ("light_dir", offset_of!(FrameUniforms, light_dir)),
            ("base_color", offset_of!(FrameUniforms, base_color)),
            (
                "log_density_range",
                offset_of!(FrameUniforms, log_density_range),
            ),
            ("viewport", offset_of!(FrameUniforms, viewport)),
            ("splat_scale", offset_of!(FrameUniforms, splat_scale)),
            ("color_mode", offset_of!(FrameUniforms, color_mode)),
            ("footprint", offset_of!(FrameUniforms, footprint)),
            ("mesh_mode", offset_of!(FrameUniforms, mesh_mode)),
            ("normal_offset", offset_of!(FrameUniforms, normal_offset)),
            ("lod_flags", offset_of!(FrameUniforms, lod_flags)),
            ("lod", offset_of!(FrameUniforms, lod)),
        ];
        for (name, offset) in expected {
            let found = members.iter().find(|(n, _)| n == name);
            assert_eq!(found.map(|(_, o)| *o), Some(offset), "Frame.{name}");
        }
    }

    /// The WGSL `NprParams` has the size and offsets of [`NprUniforms`].
    #[test]
    fn npr_uniforms_match_their_wgsl_twin() {
        let (members, span) = wgsl_layout(super::super::shaders::NPR, "NprParams");
        assert_eq!(span, size_of::<NprUniforms>());
        let expected = [
            ("shadow", offset_of!(NprUniforms, shadow)),
            ("mid", offset_of!(NprUniforms, mid)),
            ("light", offset_of!(NprUniforms, light)),
            ("ink", offset_of!(NprUniforms, ink)),
            ("paper", offset_of!(NprUniforms, paper)),
            ("style", offset_of!(NprUniforms, style)),
            ("brush", offset_of!(NprUniforms, brush)),
            ("seed", offset_of!(NprUniforms, seed)),
            ("focal_px", offset_of!(NprUniforms, focal_px)),
            ("size_jitter", offset_of!(NprUniforms, size_jitter)),
            ("hue_jitter", offset_of!(NprUniforms, hue_jitter)),
            ("stroke_length", offset_of!(NprUniforms, stroke_length)),
            ("stroke_width", offset_of!(NprUniforms, stroke_width)),
        ];
        let expected: Vec<(String, usize)> =
            expected.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(members, expected);
    }

    #[test]
    fn density_range_is_ordered_and_widened_when_constant() {
        let a = Sample {
            spacing: [0.1, 0.2],
            ..Sample::default()
        };
        let b = Sample {
            spacing: [0.05, 0.1],
            ..Sample::default()
        };
        let [lo, hi] = log_density_range(&[a, b]);
        assert!((lo - (1.0f32 / 0.02).ln()).abs() < 1e-5);
        assert!((hi - (1.0f32 / 0.005).ln()).abs() < 1e-5);
        let [lo, hi] = log_density_range(&[a, a]);
        assert!((hi - lo - 1.0).abs() < 1e-5);
        assert_eq!(log_density_range(&[]), [0.0, 1.0]);
    }
}
