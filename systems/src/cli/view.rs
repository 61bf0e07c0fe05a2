//! `strata view`: the arguments of the interactive window; the window itself is
//! [`crate::viewer`].

use std::path::PathBuf;

use anyhow::Context;

use super::{LodArgs, LookArgs, StyleArgs};
use crate::ecs::SamplerBackend;
use crate::gpu::StyleChoice;
use crate::viewer::{self, ViewerOptions};

/// Arguments of `strata view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) with the field of `--field` (uniform
    /// density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Initial window width (logical pixels, at least 1).
    #[arg(long, default_value_t = 1280, value_parser = super::pixels)]
    pub width: u32,
    /// Initial window height (logical pixels, at least 1).
    #[arg(long, default_value_t = 960, value_parser = super::pixels)]
    pub height: u32,
    /// Close after this many frames and print the last frame's timings (for scripted
    /// runs); default: run until the window closes.
    #[arg(long)]
    pub frames: Option<u64>,
    /// Camera, colours and sample count.
    #[command(flatten)]
    pub look: LookArgs,
    /// `--lod`, `--lod-max` and `--lod-shown`, as `strata render`'s.
    #[command(flatten)]
    pub lod: LodArgs,
    /// `--style` and `--brush`, as `strata render`'s (the keys `P` and `B` change them).
    #[command(flatten)]
    pub paint: StyleArgs,
    /// Who draws the samples each frame: `auto` (the GPU on a hardware adapter, the CPU
    /// on a software one), `cpu` (the reference) or `gpu` (compute passes straight into
    /// the renderer's buffer, on any adapter). With `--lod` the pool is drawn on the CPU.
    #[arg(long, value_enum, default_value_t = SamplerBackend::Auto)]
    pub sampler: SamplerBackend,
}

/// Runs `strata view` until the window closes.
pub(super) fn run(args: &ViewArgs) -> anyhow::Result<()> {
    let options = view_options(args)?;
    let outcome = viewer::run(&options)?;
    if args.frames.is_some() {
        println!("{} frames; last: {}", outcome.frames, outcome.status);
    }
    Ok(())
}

/// What `strata view` opens its window with: the arguments checked and the scene
/// loaded (a mesh input's scene written to a temporary scene file, which the viewer
/// watches). Needs no display or GPU: the flag table checks each flag here.
pub fn view_options(args: &ViewArgs) -> anyhow::Result<ViewerOptions> {
    args.look.validate()?;
    let lod = &args.lod;
    lod.validate()?;
    if lod.lod && args.sampler == SamplerBackend::Gpu {
        anyhow::bail!(
            "--sampler gpu does not apply with --lod: the level-of-detail pool is drawn on the CPU (use --sampler auto or cpu)"
        );
    }
    let paint = StyleChoice::new(args.paint.npr_kind_for(lod.lod)?);
    let scene = if super::input::is_mesh(&args.config) {
        // The viewer watches a scene file: the mesh's scene, written to a temporary one.
        let config = args.input.load(&args.config)?;
        let path = std::env::temp_dir().join(format!("strata-view-{}.ron", std::process::id()));
        super::write_file(&path, super::input::scene_ron(&config)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        path
    } else {
        args.input.load(&args.config)?;
        args.config.clone()
    };
    let options = ViewerOptions {
        scene,
        size: (args.width, args.height),
        max_frames: args.frames,
        count: args
            .look
            .count
            .map(|c| usize::try_from(c).unwrap_or(usize::MAX)),
        seed: args.look.seed,
        gpu: args.look.gpu_options(),
        camera: args.look.orientation(),
        zoom: args.look.zoom,
        style: args.look.style(&[]),
        paint,
        lod_max: lod.lod.then_some(lod.lod_max),
        lod_shown: lod.lod_shown.filter(|_| lod.lod),
        sampler: args.sampler,
    };
    Ok(options)
}
