//! An interactive window (winit) with an orbit camera over the streaming engine
//! ([`crate::hot_reload::StreamingEngine`]), behind `strata view`: the scene file (and
//! the mesh and field files it names) is watched and hot-reloaded, the engine resamples
//! every frame, and the GPU upload system ([`crate::gpu::upload`]) streams the samples
//! into the renderer's buffer; the title shows the frame time, the sample count and
//! the progress of a build running off the frame (the last samples keep drawing).
//!
//! Input: [`ViewerOptions`]. Output: the window until it closes, then a
//! [`ViewerOutcome`]. Cost per frame: one sampling of the scene, one upload, one draw;
//! when the sampler is the GPU's ([`ViewerOptions::sampler`], resolved by
//! [`crate::gpu::backend`]), the sampling is compute passes into the renderer's buffer
//! and there is no upload. The sampler used is printed with the adapter and shown in
//! the title.
//!
//! Mouse: drag to orbit, wheel to zoom. Keys: `Up`/`Down` double or halve the count,
//! `S` a new seed (both until the scene file sets them again), `C` the next colour
//! mode, `M` the next mesh mode, `F` disc or Gaussian splats, `P` the next style
//! (splats, stipple, strokes), `B` strokes with the next brush, `Escape` quits. A scene
//! saved with an error keeps the last good state and prints the error (file, line,
//! column); the window shows it in its title until a good save.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

use strata_engine::mesh::TriMesh;

use crate::ecs::{
    EngineSettings, MeshData, MeshSampler, MeshTransform, SamplerBackend, SamplingSettings, Stage,
    StageStats,
};
use crate::gpu::backend::{GpuSampling, SamplerUse};
use crate::gpu::headless::DEPTH_FORMAT;
use crate::gpu::splat::{FrameTarget, TargetFormat};
use crate::gpu::{
    GpuContext, GpuOptions, GpuSplats, OrbitCamera, SplatLod, SplatRenderer, SplatStyle,
    StyleChoice, StyledFrame,
};
use crate::hot_reload::StreamingEngine;

mod keys;
mod lod;

/// What the viewer shows and how it starts.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// The scene file (RON) to watch.
    pub scene: PathBuf,
    /// Initial window size, logical pixels (at least 1 each).
    pub size: (u32, u32),
    /// Close after this many frames (scripted runs); `None`: run until the window
    /// closes.
    pub max_frames: Option<u64>,
    /// Sample count to start with instead of the scene's (until the scene sets it again).
    pub count: Option<usize>,
    /// Seed to start with instead of the scene's (until the scene sets it again).
    pub seed: Option<u64>,
    /// Which GPU adapter to use.
    pub gpu: GpuOptions,
    /// The camera's yaw, pitch and field of view; its target and distance are fitted
    /// to the mesh ([`OrbitCamera::fitted_to_mesh`]).
    pub camera: OrbitCamera,
    /// The fitted distance is multiplied by this (> 0; < 1 is closer).
    pub zoom: f32,
    /// The splat style to start with (the keys change it; the density colour map is
    /// refitted to the samples).
    pub style: SplatStyle,
    /// Splats, stipple or strokes to start with (`P` and `B` change it).
    pub paint: StyleChoice,
    /// Level of detail up to this multiplier: the count is the base count of a
    /// progressive pool ([`crate::ecs::Lod`]) that follows the camera, so zooming in
    /// adds samples near the camera and moves none. `None`: every sample drawn.
    pub lod_max: Option<f32>,
    /// With `lod_max`: a point budget ([`crate::ecs::Lod::shown`]): about this many
    /// samples are shown at any distance, and the count is the pool's prefix.
    pub lod_shown: Option<u32>,
    /// Who draws the samples once the window's GPU is open ([`EngineSettings::sampler`];
    /// before, the CPU). With level of detail the pool is drawn on the CPU.
    pub sampler: SamplerBackend,
}

/// How a viewer run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ViewerOutcome {
    /// Frames drawn.
    pub frames: u64,
    /// The last frame's status line (count, frame, sampling and upload times, modes).
    pub status: String,
}

/// Opens the window and runs it until it closes (or `options.max_frames` were drawn).
/// Fails in one line without a display or a GPU; a scene that is bad at start-up is
/// waited for (printing its errors), so the window opens on the first good save.
pub fn run(options: &ViewerOptions) -> anyhow::Result<ViewerOutcome> {
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
    let mut engine = StreamingEngine::watch(&options.scene)
        .with_context(|| format!("watching {}", options.scene.display()))?;
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = true;
    crate::gpu::upload::register(&mut engine.schedule);
    crate::gpu::backend::register(&mut engine.world, &mut engine.schedule);
    // A scene that is bad at start-up is waited for: the first good save opens it.
    // The watcher loads the scene off this thread; a scene that is bad at start-up
    // is waited for: the first good save opens it.
    let mesh_entity = loop {
        engine.update();
        let errors = engine.take_errors();
        for e in &errors {
            eprintln!("error: {e}");
        }
        if let Some(e) = engine.mesh_entity() {
            break e;
        }
        if !errors.is_empty() {
            eprintln!(
                "waiting for a good save of {} (Ctrl-C quits)",
                options.scene.display()
            );
        }
        engine.wait_for_change(Duration::from_secs(3600));
    };
    if let Some(count) = options.count {
        set_sampling(&mut engine, mesh_entity, |s| s.count = count);
    }
    if let Some(seed) = options.seed {
        set_sampling(&mut engine, mesh_entity, |s| s.seed = seed);
    }
    let mut app = Viewer {
        title: options.scene.display().to_string(),
        size: (options.size.0.max(1), options.size.1.max(1)),
        gpu_options: options.gpu.clone(),
        camera_look: options.camera,
        zoom: options.zoom,
        engine,
        mesh_entity,
        shown_mesh: None,
        style: options.style,
        paint: options.paint,
        camera: None,
        gpu: None,
        drag: None,
        dragging: false,
        error: None,
        scene_error: None,
        last_frame: None,
        frame_ms: 0.0,
        frames: 0,
        max_frames: options.max_frames,
        status: String::new(),
        refit_colors: true,
        lod_max: options.lod_max,
        lod_shown: options.lod_shown,
        lod: None,
        sampler: options.sampler,
    };
    if options.lod_max.is_some() {
        // The pool follows the camera; the sample buffer is not redrawn every frame.
        app.engine
            .world
            .resource_mut::<EngineSettings>()
            .sample_every_update = false;
    }
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window event loop: {e}"))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(ViewerOutcome {
            frames: app.frames,
            status: app.status,
        }),
    }
}

/// Changes the sampling settings of the engine's mesh entity.
fn set_sampling(
    engine: &mut StreamingEngine,
    e: bevy_ecs::entity::Entity,
    f: impl FnOnce(&mut SamplingSettings),
) {
    if let Some(mut s) = engine.world.get_mut::<SamplingSettings>(e) {
        f(&mut s);
    }
}

/// The mesh as placed by the entity's transform (what the samples lie on).
fn placed_mesh(mesh: &Arc<TriMesh>, transform: Option<&MeshTransform>) -> Arc<TriMesh> {
    match transform {
        Some(t) if t.0 != glam::DAffine3::IDENTITY => {
            let positions = mesh
                .positions()
                .iter()
                .map(|p| t.0.transform_point3(*p))
                .collect();
            TriMesh::new(positions, mesh.triangles().to_vec())
                .map(Arc::new)
                .unwrap_or_else(|_| mesh.clone())
        }
        _ => mesh.clone(),
    }
}

/// The window side of the GPU; the device and the renderer live in the engine's
/// [`GpuSplats`] resource, where the upload system streams the samples.
struct WindowGpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    depth: wgpu::TextureView,
    /// Splats or strokes into the surface's format.
    frame: StyledFrame,
}

struct Viewer {
    title: String,
    size: (u32, u32),
    gpu_options: GpuOptions,
    /// Yaw, pitch and field of view of the camera fitted to each new mesh.
    camera_look: OrbitCamera,
    zoom: f32,
    engine: StreamingEngine,
    mesh_entity: bevy_ecs::entity::Entity,
    /// The source mesh and transform drawn under the splats (to notice a reloaded
    /// mesh or a new transform).
    shown_mesh: Option<(Arc<TriMesh>, glam::DAffine3)>,
    style: SplatStyle,
    paint: StyleChoice,
    camera: Option<OrbitCamera>,
    gpu: Option<WindowGpu>,
    drag: Option<(f64, f64)>,
    dragging: bool,
    error: Option<anyhow::Error>,
    /// The last scene error, shown until a good save.
    scene_error: Option<String>,
    last_frame: Option<Instant>,
    frame_ms: f64,
    frames: u64,
    max_frames: Option<u64>,
    status: String,
    /// Refit the density colour map to the next frame's samples (after a count change).
    refit_colors: bool,
    /// `--lod`: the clamp of the multiplier; the reference is fixed at the first frame.
    lod_max: Option<f32>,
    /// `--lod-shown`: the point budget.
    lod_shown: Option<u32>,
    lod: Option<SplatLod>,
    /// `--sampler`: set in the engine when the window's GPU opens.
    sampler: SamplerBackend,
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
        if let Some(b) = self.gpu_options.backends {
            desc.backends = b;
        }
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .context("creating the window surface")?;
        let ctx = GpuContext::with_instance(instance, &self.gpu_options, Some(&surface))
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
        let target = TargetFormat {
            color: format,
            depth: DEPTH_FORMAT,
            samples: 1,
        };
        let renderer = SplatRenderer::new(&ctx.device, target)?;
        let frame = StyledFrame::new(&ctx.device, target, self.paint)?;
        let max = crate::gpu::buffers::max_samples(&ctx.device);
        let count = self.sampling().count;
        if count > max {
            anyhow::bail!(
                "{count} samples do not fit in one GPU buffer on this adapter (at most {max})"
            );
        }
        let depth = depth_view(&ctx.device, config.width, config.height);
        println!("strata view: {}", ctx.adapter_summary());
        let used = crate::gpu::backend::resolve(self.sampler, Some(&ctx.adapter.get_info()))?;
        match self.lod_max {
            Some(_) => println!("strata view: sampler cpu (level of detail)"),
            None => println!("strata view: {used}"),
        }
        let mut splats = GpuSplats::new(ctx, renderer);
        splats.mesh = Some(self.mesh_entity);
        self.engine.world.insert_resource(splats);
        self.engine.world.resource_mut::<EngineSettings>().sampler = self.sampler;
        self.gpu = Some(WindowGpu {
            window,
            surface,
            config,
            depth,
            frame,
        });
        let aspect = self.aspect();
        self.camera = self
            .current_mesh()
            .map(|mesh| self.camera_look.fitted_to_mesh(&mesh, aspect, self.zoom));
        Ok(())
    }

    fn aspect(&self) -> f32 {
        self.gpu.as_ref().map_or(1.0, |g| {
            g.config.width as f32 / g.config.height.max(1) as f32
        })
    }

    /// The sampling settings of the mesh entity.
    fn sampling(&self) -> SamplingSettings {
        self.engine
            .world
            .get::<SamplingSettings>(self.mesh_entity)
            .copied()
            .unwrap_or(SamplingSettings { count: 0, seed: 0 })
    }

    /// The mesh entity's mesh, placed by its transform.
    fn current_mesh(&self) -> Option<Arc<TriMesh>> {
        let (mesh, transform) = self.current_source()?;
        Some(placed_mesh(&mesh, Some(&MeshTransform(transform))))
    }

    /// The mesh entity's mesh and transform.
    fn current_source(&self) -> Option<(Arc<TriMesh>, glam::DAffine3)> {
        let world = &self.engine.world;
        let mesh = world.get::<MeshData>(self.mesh_entity)?.0.clone();
        let transform = world
            .get::<MeshTransform>(self.mesh_entity)
            .map_or(glam::DAffine3::IDENTITY, |t| t.0);
        Some((mesh, transform))
    }

    /// Runs the engine once (hot reload, recomputation, sampling, upload) and keeps
    /// the mesh under the splats current; scene errors go to stderr and the title.
    fn update_engine(&mut self) -> anyhow::Result<Duration> {
        self.engine.clear_stats();
        self.engine.update();
        for e in self.engine.take_errors() {
            eprintln!("error: {e}");
            self.scene_error = Some(e.to_string());
        }
        let stats = self.engine.world.resource::<StageStats>();
        if stats.runs_of(Stage::Scene) > 0 && self.scene_error.is_some() {
            // A good scene was applied after the error.
            self.scene_error = None;
        }
        let sampling: Duration = stats
            .runs
            .iter()
            .filter(|r| r.stage == Stage::Sampling)
            .map(|r| r.took)
            .sum();
        let chains_ran = stats.runs_of(Stage::Chains) > 0;
        let source = self.current_source();
        let mesh_changed = match (&source, &self.shown_mesh) {
            (Some((m, t)), Some((shown, shown_t))) => !Arc::ptr_eq(m, shown) || t != shown_t,
            (Some(_), None) => true,
            _ => false,
        };
        if let Some((mesh, transform)) = source
            && (mesh_changed || chains_ran)
        {
            let placed = placed_mesh(&mesh, Some(&MeshTransform(transform)));
            let segments = self
                .engine
                .world
                .get::<MeshSampler>(self.mesh_entity)
                .and_then(|s| s.0.as_ref())
                .map(crate::gpu::splat::face_segments);
            let mut gpu = self.engine.world.resource_mut::<GpuSplats>();
            let gpu = &mut *gpu;
            gpu.renderer.set_mesh(
                &gpu.ctx.device,
                &gpu.ctx.queue,
                &placed,
                segments.as_deref(),
            )?;
            if mesh_changed && self.shown_mesh.is_some() {
                let aspect = self.aspect();
                self.camera = Some(self.camera_look.fitted_to_mesh(&placed, aspect, self.zoom));
            }
            self.shown_mesh = Some((mesh, transform));
            self.refit_colors = true;
        }
        if let Some(e) = self.engine.world.resource_mut::<GpuSplats>().error.take() {
            return Err(e.into());
        }
        Ok(sampling)
    }

    fn frame(&mut self) -> anyhow::Result<()> {
        if self.gpu.is_none() || self.camera.is_none() {
            return Ok(());
        }
        self.follow_camera();
        let sampling = self.update_engine()?;
        self.draw_with_budget();
        let (count, upload) = {
            let splats = self.engine.world.resource::<GpuSplats>();
            (splats.renderer.samples().len(), splats.last.time)
        };
        let used = self.sampler_used();
        if self.refit_colors {
            self.style.log_density_range = self.density_range(used);
            self.refit_colors = false;
        }
        let seed = self.sampling().seed;
        let (Some(gpu), Some(camera)) = (&mut self.gpu, &self.camera) else {
            return Ok(());
        };
        let mut splats = self.engine.world.resource_mut::<GpuSplats>();
        let splats = &mut *splats;
        let texture = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gpu.surface.configure(&splats.ctx.device, &gpu.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        let view = texture.texture.create_view(&Default::default());
        let mut encoder = splats
            .ctx
            .device
            .create_command_encoder(&Default::default());
        gpu.frame.choice = self.paint;
        gpu.frame.encode(
            &splats.ctx.device,
            &splats.ctx.queue,
            &mut encoder,
            FrameTarget {
                color: &view,
                resolve: None,
                depth: &gpu.depth,
                size: (gpu.config.width, gpu.config.height),
            },
            camera,
            &splats.renderer,
            &self.style,
            seed,
        )?;
        splats.ctx.queue.submit([encoder.finish()]);
        splats.ctx.queue.present(texture);
        splats.ctx.take_uncaptured("drawing a frame")?;
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
        let what = if self.lod.is_some() {
            "pool samples (level of detail)"
        } else {
            "samples"
        };
        let sampler = used.map_or(String::new(), |u| format!("{u} | "));
        self.status = format!(
            "{count} {what} | frame {:.1} ms (sampling {:.1} ms, upload {:.1} ms) | {sampler}{}, {:?}, {:?}",
            self.frame_ms,
            sampling.as_secs_f64() * 1e3,
            upload.as_secs_f64() * 1e3,
            self.paint,
            self.style.color_mode,
            self.style.mesh_mode,
        );
        // A build off the frame shows its stage and progress; the last samples draw.
        if let Some(progress) = self.engine.progress() {
            self.status = format!("{} | {progress}", self.status);
        }
        let title = match &self.scene_error {
            Some(e) => format!("strata view: {} | {} | {e}", self.title, self.status),
            None => format!("strata view: {} | {}", self.title, self.status),
        };
        gpu.window.set_title(&title);
        self.frames += 1;
        if self.max_frames.is_some_and(|m| self.frames >= m) {
            return Ok(());
        }
        gpu.window.request_redraw();
        Ok(())
    }

    /// The sampler that drew this frame's samples, when the GPU one did.
    fn sampler_used(&self) -> Option<SamplerUse> {
        let on_gpu = self.engine.world.resource::<crate::ecs::GpuSampled>().0;
        let state = self.engine.world.get_resource::<GpuSampling>()?;
        state.used.filter(|u| !u.is_gpu() || on_gpu.is_some())
    }

    /// The density colour map's range: fitted to the samples, or with the GPU's
    /// sampler (whose samples stay on the GPU) to a CPU draw of at most 4096 of them.
    fn density_range(&self, used: Option<SamplerUse>) -> [f32; 2] {
        if !used.is_some_and(SamplerUse::is_gpu) {
            return crate::gpu::layout::log_density_range(self.engine.samples());
        }
        let sampling = self.sampling();
        let world = &self.engine.world;
        let sampler = world.get::<MeshSampler>(self.mesh_entity);
        let few = sampler.and_then(|s| s.0.as_ref()).map_or(Vec::new(), |s| {
            s.sample(sampling.count.min(4096), sampling.seed)
        });
        crate::gpu::layout::log_density_range(&few)
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
                    if let Some(splats) = self.engine.world.get_resource::<GpuSplats>() {
                        gpu.surface.configure(&splats.ctx.device, &gpu.config);
                        gpu.depth = depth_view(&splats.ctx.device, size.width, size.height);
                    }
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
