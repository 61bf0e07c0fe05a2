//! `strata view`: a window (winit) with an orbit camera that resamples the scene every
//! frame and draws the splats; the title shows the frame time and the sample count.
//!
//! Mouse: drag to orbit, wheel to zoom. Keys: `Up`/`Down` double or halve the count,
//! `S` a new seed, `C` the next colour mode, `M` the next mesh mode, `F` disc or
//! Gaussian splats, `Escape` quits. (Live config reload arrives with the ECS engine.)

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, anyhow};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::config::SceneConfig;
use crate::gpu::headless::DEPTH_FORMAT;
use crate::gpu::splat::{FrameTarget, TargetFormat};
use crate::gpu::stream::StreamTimings;
use crate::gpu::{
    ColorMode, Footprint, GpuContext, MeshMode, OrbitCamera, SampleStream, SplatRenderer,
    SplatStyle,
};
use crate::render::LookArgs;
use crate::scene::Scene;

/// Arguments of `strata view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// Scene file (RON).
    pub config: PathBuf,
    /// Initial window width (logical pixels).
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Initial window height (logical pixels).
    #[arg(long, default_value_t = 960)]
    pub height: u32,
    /// Close after this many frames and print the last frame's timings (for scripted
    /// runs); default: run until the window closes.
    #[arg(long)]
    pub frames: Option<u64>,
    /// Camera, colours and sample count.
    #[command(flatten)]
    pub look: LookArgs,
}

/// Runs `strata view` until the window closes.
pub fn run(args: &ViewArgs) -> anyhow::Result<()> {
    args.look.validate()?;
    let config = SceneConfig::load(&args.config)?;
    // The display first: without one, fail in one line before the preprocessing.
    let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if cfg!(target_os = "linux")
        && !["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
            .map(set)
            .contains(&true)
    {
        anyhow::bail!(
            "cannot open a window: no display (neither DISPLAY nor WAYLAND_DISPLAY is set); `strata render` draws without one"
        );
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("cannot open a window: {e} (no display; `strata render` draws without one)")
    })?;
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    let count = usize::try_from(args.look.count.unwrap_or(config.sampling.count))
        .context("sample count does not fit in memory")?;
    let mut app = Viewer {
        title: args.config.display().to_string(),
        size: (args.width.max(1), args.height.max(1)),
        look: args.look.clone(),
        scene,
        count,
        seed: args.look.seed.unwrap_or(config.sampling.seed),
        stream: SampleStream::new(),
        style: SplatStyle::default(),
        camera: None,
        gpu: None,
        drag: None,
        dragging: false,
        error: None,
        last_frame: None,
        frame_ms: 0.0,
        frames: 0,
        max_frames: args.frames,
        status: String::new(),
        refit_colors: true,
    };
    app.style = args.look.style(&[]);
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window event loop: {e}"))?;
    match app.error {
        Some(e) => Err(e),
        None => {
            if args.frames.is_some() {
                println!("{} frames; last: {}", app.frames, app.status);
            }
            Ok(())
        }
    }
}

struct WindowGpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: SplatRenderer,
    depth: wgpu::TextureView,
}

struct Viewer {
    title: String,
    size: (u32, u32),
    look: LookArgs,
    scene: Scene,
    count: usize,
    seed: u64,
    stream: SampleStream,
    style: SplatStyle,
    camera: Option<OrbitCamera>,
    gpu: Option<WindowGpu>,
    drag: Option<(f64, f64)>,
    dragging: bool,
    error: Option<anyhow::Error>,
    last_frame: Option<Instant>,
    frame_ms: f64,
    frames: u64,
    max_frames: Option<u64>,
    status: String,
    /// Refit the density colour map to the next frame's samples (after a count change).
    refit_colors: bool,
}

fn depth_view(device: &wgpu::Device, width: u32, height: u32) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("strata window depth"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

impl Viewer {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let attributes = Window::default_attributes()
            .with_title(format!("strata view: {}", self.title))
            .with_inner_size(winit::dpi::LogicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| anyhow!("cannot open a window: {e}"))?,
        );
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
            event_loop.owned_display_handle(),
        ));
        if let Some(b) = self.look.gpu_options().backends {
            desc.backends = b;
        }
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .context("creating the window surface")?;
        let ctx = GpuContext::with_instance(instance, &self.look.gpu_options(), Some(&surface))
            .context("opening a GPU")?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| anyhow!("the window surface offers no format on this adapter"))?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        crate::gpu::context::scoped(&ctx.device, "configuring the window surface", || {
            surface.configure(&ctx.device, &config)
        })?;
        let mut renderer = SplatRenderer::new(
            &ctx.device,
            TargetFormat {
                color: format,
                depth: DEPTH_FORMAT,
                samples: 1,
            },
        )?;
        let max = crate::gpu::buffers::max_samples(&ctx.device);
        if self.count > max {
            anyhow::bail!(
                "{} samples do not fit in one GPU buffer on this adapter (at most {max})",
                self.count
            );
        }
        let segments = crate::gpu::splat::face_segments(&self.scene.sampler);
        renderer.set_mesh(&ctx.device, &ctx.queue, &self.scene.mesh, Some(&segments))?;
        self.camera = Some(
            self.look
                .camera(&self.scene, config.width as f32 / config.height as f32),
        );
        let depth = depth_view(&ctx.device, config.width, config.height);
        println!("strata view: {}", ctx.adapter_summary());
        self.gpu = Some(WindowGpu {
            window,
            surface,
            config,
            ctx,
            renderer,
            depth,
        });
        Ok(())
    }

    fn frame(&mut self) -> anyhow::Result<()> {
        let (Some(gpu), Some(camera)) = (&mut self.gpu, &self.camera) else {
            return Ok(());
        };
        let timings: StreamTimings = self.stream.frame(
            &self.scene.sampler,
            self.count,
            self.seed,
            &mut gpu.renderer,
            &gpu.ctx.device,
            &gpu.ctx.queue,
        )?;
        if self.refit_colors {
            self.style.log_density_range =
                crate::gpu::layout::log_density_range(self.stream.samples());
            self.refit_colors = false;
        }
        let texture = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gpu.surface.configure(&gpu.ctx.device, &gpu.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        let view = texture.texture.create_view(&Default::default());
        let mut encoder = gpu.ctx.device.create_command_encoder(&Default::default());
        gpu.renderer.encode(
            &gpu.ctx.device,
            &gpu.ctx.queue,
            &mut encoder,
            FrameTarget {
                color: &view,
                resolve: None,
                depth: &gpu.depth,
                size: (gpu.config.width, gpu.config.height),
            },
            camera,
            &self.style,
        )?;
        gpu.ctx.queue.submit([encoder.finish()]);
        gpu.ctx.queue.present(texture);
        gpu.ctx.take_uncaptured("drawing a frame")?;
        let now = Instant::now();
        if let Some(last) = self.last_frame {
            // Smoothed, so that the title is readable.
            let ms = (now - last).as_secs_f64() * 1e3;
            self.frame_ms = if self.frame_ms == 0.0 {
                ms
            } else {
                0.9 * self.frame_ms + 0.1 * ms
            };
        }
        self.last_frame = Some(now);
        self.status = format!(
            "{} samples | frame {:.1} ms (sampling {:.1} ms, upload {:.1} ms) | {:?}, {:?}",
            timings.count,
            self.frame_ms,
            timings.sample.as_secs_f64() * 1e3,
            timings.upload.as_secs_f64() * 1e3,
            self.style.color_mode,
            self.style.mesh_mode,
        );
        gpu.window
            .set_title(&format!("strata view: {} | {}", self.title, self.status));
        self.frames += 1;
        if self.max_frames.is_some_and(|m| self.frames >= m) {
            return Ok(());
        }
        gpu.window.request_redraw();
        Ok(())
    }

    fn key(&mut self, key: &Key, event_loop: &ActiveEventLoop) {
        match key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::ArrowUp) => {
                let max = self.gpu.as_ref().map_or(usize::MAX, |g| {
                    crate::gpu::buffers::max_samples(&g.ctx.device)
                });
                self.count = self.count.saturating_mul(2).clamp(1, max);
                self.refit_colors = true;
            }
            Key::Named(NamedKey::ArrowDown) => {
                self.count /= 2;
                self.refit_colors = true;
            }
            Key::Character(c) => match c.as_str() {
                "s" | "S" => self.seed = self.seed.wrapping_add(1),
                "c" | "C" => {
                    self.style.color_mode = match self.style.color_mode {
                        ColorMode::Density => ColorMode::Segment,
                        ColorMode::Segment => ColorMode::Constant,
                        ColorMode::Constant => ColorMode::Density,
                    }
                }
                "m" | "M" => {
                    self.style.mesh_mode = match self.style.mesh_mode {
                        MeshMode::Plain => MeshMode::Segments,
                        MeshMode::Segments => MeshMode::None,
                        MeshMode::None => MeshMode::Plain,
                    }
                }
                "f" | "F" => {
                    self.style.footprint = match self.style.footprint {
                        Footprint::Disc => Footprint::Gaussian,
                        Footprint::Gaussian => Footprint::Disc,
                    }
                }
                _ => {}
            },
            _ => {}
        }
    }

    fn fail(&mut self, e: anyhow::Error, event_loop: &ActiveEventLoop) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(e, event_loop);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = &mut self.gpu
                    && size.width > 0
                    && size.height > 0
                {
                    gpu.config.width = size.width;
                    gpu.config.height = size.height;
                    gpu.surface.configure(&gpu.ctx.device, &gpu.config);
                    gpu.depth = depth_view(&gpu.ctx.device, size.width, size.height);
                    gpu.window.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame() {
                    self.fail(e, event_loop);
                } else if self.max_frames.is_some_and(|m| self.frames >= m) {
                    event_loop.exit();
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                self.dragging = state == ElementState::Pressed;
                self.drag = None;
            }
            WindowEvent::CursorMoved { position, .. } if self.dragging => {
                if let (Some((x, y)), Some(camera)) = (self.drag, &mut self.camera) {
                    let dx = (position.x - x) as f32;
                    let dy = (position.y - y) as f32;
                    camera.orbit(-dx * 0.008, dy * 0.008);
                }
                self.drag = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(camera) = &mut self.camera {
                    camera.zoom(0.9f32.powf(lines));
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(&event.logical_key, event_loop);
            }
            _ => {}
        }
    }
}
