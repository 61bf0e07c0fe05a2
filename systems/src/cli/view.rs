//! `strata view`: the arguments of the interactive window; the window itself is
//! [`crate::viewer`].

use std::path::PathBuf;

use super::{LookArgs, StyleArgs};
use crate::gpu::StyleChoice;
use crate::viewer::{self, ViewerOptions};

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
    /// Level of detail: the count is the base count of progressive samples that follow
    /// the camera (as `strata render --lod`); zooming in adds samples near the camera
    /// and moves none.
    #[arg(long)]
    pub lod: bool,
    /// With `--lod`: the largest multiplier of the count's density.
    #[arg(long, default_value_t = 4.0, requires = "lod")]
    pub lod_max: f32,
    /// With `--lod`: a point budget: about this many samples are shown at any camera
    /// distance (the base count of each frame is chosen for it); the count is then the
    /// pool's prefix, drawn up front.
    #[arg(long, requires = "lod")]
    pub lod_shown: Option<u32>,
    /// `--style` and `--brush`, as `strata render`'s (the keys `P` and `B` change them).
    #[command(flatten)]
    pub paint: StyleArgs,
}

/// Runs `strata view` until the window closes.
pub(super) fn run(args: &ViewArgs) -> anyhow::Result<()> {
    args.look.validate()?;
    let paint = StyleChoice::new(args.paint.npr_kind_for(args.lod)?);
    if !(args.lod_max > 0.0 && args.lod_max.is_finite()) {
        anyhow::bail!("--lod-max must be a positive number, not {}", args.lod_max);
    }
    if args.lod_shown == Some(0) {
        anyhow::bail!("--lod-shown must be at least 1");
    }
    let options = ViewerOptions {
        scene: args.config.clone(),
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
        lod_max: args.lod.then_some(args.lod_max),
        lod_shown: args.lod_shown.filter(|_| args.lod),
    };
    let outcome = viewer::run(&options)?;
    if args.frames.is_some() {
        println!("{} frames; last: {}", outcome.frames, outcome.status);
    }
    Ok(())
}
