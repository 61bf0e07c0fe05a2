//! `strata render`: sample a scene and draw it headlessly to a PNG
//! ([`HeadlessTarget::render_samples`](crate::gpu::HeadlessTarget::render_samples)).

use std::path::PathBuf;

use anyhow::Context;

use super::LookArgs;
use crate::config::SceneConfig;
use crate::gpu::{GpuContext, HeadlessTarget, MeshMode};
use crate::scene::Scene;

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
pub(super) fn run(args: &RenderArgs) -> anyhow::Result<()> {
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
    let segments = (args.look.mesh != MeshMode::None)
        .then(|| crate::gpu::splat::face_segments(&scene.sampler));
    let mesh = segments.as_deref().map(|s| (&*scene.mesh, s));
    let camera = args
        .look
        .camera(&scene, args.width as f32 / args.height as f32);
    let image = target.render_samples(&ctx, &samples, mesh, &camera, &args.look.style(&samples))?;
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
