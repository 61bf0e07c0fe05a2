//! `strata render`: sample a scene and draw it headlessly to a PNG.

use std::path::PathBuf;

use anyhow::Context;

use crate::config::SceneConfig;
use crate::gpu::layout::log_density_range;
use crate::gpu::{
    ColorMode, Footprint, GpuContext, GpuOptions, HeadlessTarget, MeshMode, OrbitCamera,
    SplatRenderer, SplatStyle,
};
use crate::scene::Scene;

/// Camera and look options shared by `strata render` and `strata view`.
#[derive(Debug, Clone, clap::Args)]
pub struct LookArgs {
    /// Number of samples (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Random seed (overrides the scene's `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Camera rotation about the vertical (Y) axis, degrees; 0 looks from +Z.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub yaw: f32,
    /// Camera elevation, degrees (-89 to 89).
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    pub pitch: f32,
    /// Distance as a multiple of the one that frames the mesh's bounding box (< 1 is closer).
    #[arg(long, default_value_t = 1.0)]
    pub zoom: f32,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 35.0)]
    pub fov: f32,
    /// Splat colours.
    #[arg(long, value_enum, default_value_t = ColorMode::Density)]
    pub color: ColorMode,
    /// Splat shape.
    #[arg(long, value_enum, default_value_t = Footprint::Disc)]
    pub footprint: Footprint,
    /// The mesh under the splats.
    #[arg(long, value_enum, default_value_t = MeshMode::Plain)]
    pub mesh: MeshMode,
    /// Splat size as a fraction of the sample spacing (1: neighbours touch on average).
    #[arg(long, default_value_t = 0.8)]
    pub scale: f32,
    /// Use the GPU adapter whose name contains this (case-insensitive); default:
    /// `WGPU_ADAPTER_NAME`, else wgpu's choice. `WGPU_BACKEND=vulkan|gl` picks backends.
    #[arg(long)]
    pub adapter: Option<String>,
}

impl LookArgs {
    /// Checks the numeric options.
    pub fn validate(&self) -> anyhow::Result<()> {
        if !(self.zoom > 0.0 && self.zoom.is_finite()) {
            anyhow::bail!("--zoom must be a positive number, not {}", self.zoom);
        }
        if !(self.fov > 1.0 && self.fov < 170.0) {
            anyhow::bail!("--fov must be between 1 and 170 degrees, not {}", self.fov);
        }
        if !(self.scale > 0.0 && self.scale.is_finite()) {
            anyhow::bail!("--scale must be a positive number, not {}", self.scale);
        }
        if !(self.pitch.abs() <= 89.0) {
            anyhow::bail!(
                "--pitch must be between -89 and 89 degrees, not {}",
                self.pitch
            );
        }
        if !self.yaw.is_finite() {
            anyhow::bail!("--yaw must be a number");
        }
        Ok(())
    }

    /// The GPU options these arguments ask for.
    pub fn gpu_options(&self) -> GpuOptions {
        GpuOptions {
            backends: None,
            adapter_name: self.adapter.clone(),
        }
    }

    /// The camera framing `scene`'s mesh for a target of `aspect` (width / height).
    pub fn camera(&self, scene: &Scene, aspect: f32) -> OrbitCamera {
        self.camera_for_mesh(&scene.mesh, aspect)
    }

    /// The camera framing `mesh` for a target of `aspect` (width / height).
    pub fn camera_for_mesh(&self, mesh: &strata_engine::mesh::TriMesh, aspect: f32) -> OrbitCamera {
        let (min, max) = mesh.bounds();
        let mut camera = OrbitCamera {
            yaw: self.yaw.to_radians(),
            pitch: self.pitch.to_radians(),
            fov_y: self.fov.to_radians(),
            ..OrbitCamera::default()
        };
        camera.fit_box(min.as_vec3(), max.as_vec3(), aspect);
        camera.distance *= self.zoom;
        camera
    }

    /// The style these arguments ask for, with the colour map fitted to `samples`.
    pub fn style(&self, samples: &[strata_engine::sample::Sample]) -> SplatStyle {
        SplatStyle {
            color_mode: self.color,
            footprint: self.footprint,
            mesh_mode: self.mesh,
            splat_scale: self.scale,
            log_density_range: log_density_range(samples),
            ..SplatStyle::default()
        }
    }
}

/// Arguments of `strata render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file (RON).
    pub config: PathBuf,
    /// Output image (PNG).
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 960)]
    pub height: u32,
    /// Samples per pixel (1 or 4).
    #[arg(long, default_value_t = 4)]
    pub msaa: u32,
    /// Camera, colours and sample count.
    #[command(flatten)]
    pub look: LookArgs,
}

/// Runs `strata render`.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    args.look.validate()?;
    if !matches!(args.msaa, 1 | 4) {
        anyhow::bail!("--msaa must be 1 or 4, not {}", args.msaa);
    }
    let config = SceneConfig::load(&args.config)?;
    // The GPU first: without one, fail before the preprocessing.
    let ctx = GpuContext::headless(&args.look.gpu_options()).context("opening a GPU")?;
    let target = HeadlessTarget::new(&ctx.device, args.width, args.height, args.msaa)?;
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    let count = usize::try_from(args.look.count.unwrap_or(config.sampling.count))
        .context("sample count does not fit in memory")?;
    let seed = args.look.seed.unwrap_or(config.sampling.seed);
    let max = crate::gpu::buffers::max_samples(&ctx.device);
    if count > max {
        anyhow::bail!(
            "{count} samples do not fit in one GPU buffer on this adapter (at most {max})"
        );
    }
    let samples = scene.sampler.sample(count, seed);
    let mut renderer = SplatRenderer::new(&ctx.device, target.format())?;
    renderer.upload(&ctx.device, &ctx.queue, &samples)?;
    if args.look.mesh != MeshMode::None {
        let segments = crate::gpu::splat::face_segments(&scene.sampler);
        renderer.set_mesh(&ctx.device, &ctx.queue, &scene.mesh, Some(&segments))?;
    }
    let camera = args
        .look
        .camera(&scene, args.width as f32 / args.height as f32);
    let image = target.render(&ctx, &renderer, &camera, &args.look.style(&samples))?;
    image
        .write_png(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "rendered {count} samples (seed {seed}) at {}x{} on {}; wrote {}",
        args.width,
        args.height,
        ctx.adapter_summary(),
        args.out.display()
    );
    Ok(())
}
