//! Offscreen rendering: a colour and depth target without a window, read back into an
//! RGBA image and written as PNG; [`HeadlessTarget::render_samples`] draws a set of
//! samples (and their mesh) in one call (`strata render`).

use std::path::Path;

use strata_engine::mesh::TriMesh;
use strata_engine::sample::Sample;

use super::buffers::map_read;
use super::camera::OrbitCamera;
use super::context::{GpuContext, GpuError, scoped};
use super::npr::{NprRenderer, NprStyle};
use super::splat::{FrameTarget, SplatRenderer, SplatStyle, TargetFormat};

/// An 8-bit sRGB RGBA image, rows top to bottom, no padding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `4 * width * height` bytes.
    pub pixels: Vec<u8>,
}

impl RgbaImage {
    /// The pixel at column `x`, row `y` (0 at the top).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [
            self.pixels[i],
            self.pixels[i + 1],
            self.pixels[i + 2],
            self.pixels[i + 3],
        ]
    }

    /// Writes the image as an 8-bit RGBA PNG, atomically
    /// ([`strata_engine::io::write_atomically`]).
    pub fn write_png(&self, path: &Path) -> Result<(), png::EncodingError> {
        strata_engine::io::write_atomically(path, |file| {
            let mut encoder = png::Encoder::new(file, self.width, self.height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let mut writer = encoder.write_header()?;
            writer.write_image_data(&self.pixels)?;
            writer.finish()
        })
    }
}

/// The colour format of offscreen targets.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The depth format of every target.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// An offscreen colour (optionally multisampled) and depth target with a readback
/// buffer whose rows are padded to 256 bytes.
#[derive(Debug)]
pub struct HeadlessTarget {
    size: (u32, u32),
    samples: u32,
    color_format: wgpu::TextureFormat,
    multisampled: Option<wgpu::TextureView>,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
}

impl HeadlessTarget {
    /// A `width` x `height` target with `samples` samples per pixel (1 or 4).
    pub fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        samples: u32,
    ) -> Result<Self, GpuError> {
        Self::with_format(device, width, height, samples, COLOR_FORMAT)
    }

    /// [`new`](Self::new) with the colour format `color` instead of [`COLOR_FORMAT`]:
    /// a 4-byte `Rgba8*` or `Bgra8*` format (the one a window's surface often has, to
    /// draw offscreen what a window shows); pictures are read back as RGBA either way.
    pub fn with_format(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        samples: u32,
        color: wgpu::TextureFormat,
    ) -> Result<Self, GpuError> {
        use wgpu::TextureFormat as F;
        if !matches!(
            color,
            F::Rgba8Unorm | F::Rgba8UnormSrgb | F::Bgra8Unorm | F::Bgra8UnormSrgb
        ) {
            return Err(GpuError::Device {
                operation: "creating the offscreen target",
                message: format!("colour format {color:?} is not an 8-bit RGBA or BGRA format"),
            });
        }
        let limit = device.limits().max_texture_dimension_2d;
        for v in [width, height] {
            if v == 0 || v > limit {
                return Err(GpuError::Limit {
                    what: "image side (pixels, at least 1)",
                    requested: u64::from(v),
                    limit: u64::from(limit),
                });
            }
        }
        let padded_row = (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        scoped(device, "creating the offscreen target", || {
            let extent = wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            };
            let texture = |label, format, usage, count| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: extent,
                    mip_level_count: 1,
                    sample_count: count,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
            };
            let color_texture = texture(
                "strata colour",
                color,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                1,
            );
            let multisampled = (samples > 1).then(|| {
                texture(
                    "strata colour (multisampled)",
                    color,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                    samples,
                )
                .create_view(&Default::default())
            });
            let depth = texture(
                "strata depth",
                DEPTH_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
                samples,
            );
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("strata image readback"),
                size: u64::from(padded_row) * u64::from(height),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            Self {
                size: (width, height),
                samples,
                color_format: color,
                multisampled,
                color_view: color_texture.create_view(&Default::default()),
                color: color_texture,
                depth_view: depth.create_view(&Default::default()),
                readback,
                padded_row,
            }
        })
    }

    /// The format a [`SplatRenderer`] must be built with to draw here.
    pub fn format(&self) -> TargetFormat {
        TargetFormat {
            color: self.color_format,
            depth: DEPTH_FORMAT,
            samples: self.samples,
        }
    }

    /// Draws `samples` as splats, over `mesh` when given (with each face's segment id,
    /// for [`MeshMode::Segments`](super::MeshMode::Segments)), with a new
    /// [`SplatRenderer`] for this target, and reads the picture back (waits for the
    /// device). For one picture; to draw many, keep a renderer and call
    /// [`render`](Self::render).
    pub fn render_samples(
        &self,
        ctx: &GpuContext,
        samples: &[Sample],
        mesh: Option<(&TriMesh, &[u32])>,
        camera: &OrbitCamera,
        style: &SplatStyle,
    ) -> Result<RgbaImage, GpuError> {
        let mut renderer = SplatRenderer::new(&ctx.device, self.format())?;
        renderer.upload(&ctx.device, &ctx.queue, samples)?;
        if let Some((mesh, face_segments)) = mesh {
            renderer.set_mesh(&ctx.device, &ctx.queue, mesh, Some(face_segments))?;
        }
        self.render(ctx, &renderer, camera, style)
    }

    /// Draws `renderer`'s samples (and mesh) and reads the picture back (waits for
    /// the device).
    pub fn render(
        &self,
        ctx: &GpuContext,
        renderer: &SplatRenderer,
        camera: &OrbitCamera,
        style: &SplatStyle,
    ) -> Result<RgbaImage, GpuError> {
        self.draw_and_read(ctx, |encoder, target| {
            renderer.encode(&ctx.device, &ctx.queue, encoder, target, camera, style)
        })
    }

    /// Draws `splats`' samples as strokes or stipple ([`NprRenderer::encode`]) and reads
    /// the picture back (waits for the device). `npr` must be built for
    /// [`format`](Self::format).
    pub fn render_npr(
        &self,
        ctx: &GpuContext,
        splats: &SplatRenderer,
        npr: &NprRenderer,
        camera: &OrbitCamera,
        look: &SplatStyle,
        style: &NprStyle,
    ) -> Result<RgbaImage, GpuError> {
        self.draw_and_read(ctx, |encoder, target| {
            npr.encode(
                &ctx.device,
                &ctx.queue,
                encoder,
                target,
                camera,
                splats,
                look,
                style,
            )
        })
    }

    /// Records `draw` into this target (what a window's frame records into its
    /// surface texture), copies the picture out and reads it back as RGBA (waits for
    /// the device).
    pub fn draw_and_read(
        &self,
        ctx: &GpuContext,
        draw: impl FnOnce(&mut wgpu::CommandEncoder, FrameTarget<'_>) -> Result<(), GpuError>,
    ) -> Result<RgbaImage, GpuError> {
        const OP: &str = "rendering offscreen";
        let (device, queue) = (&ctx.device, &ctx.queue);
        let (width, height) = self.size;
        let mut encoder = device.create_command_encoder(&Default::default());
        let target = match &self.multisampled {
            Some(ms) => FrameTarget {
                color: ms,
                resolve: Some(&self.color_view),
                depth: &self.depth_view,
                size: self.size,
            },
            None => FrameTarget {
                color: &self.color_view,
                resolve: None,
                depth: &self.depth_view,
                size: self.size,
            },
        };
        draw(&mut encoder, target)?;
        scoped(device, OP, || {
            encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.color,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.readback,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(self.padded_row),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
            queue.submit([encoder.finish()]);
        })?;
        let padded = map_read(device, &self.readback, OP)?;
        ctx.take_uncaptured(OP)?;
        let row = 4 * width as usize;
        let mut pixels = Vec::with_capacity(row * height as usize);
        for r in padded.chunks_exact(self.padded_row as usize) {
            pixels.extend_from_slice(&r[..row]);
        }
        if matches!(
            self.color_format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        ) {
            for p in pixels.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        Ok(RgbaImage {
            width,
            height,
            pixels,
        })
    }
}
