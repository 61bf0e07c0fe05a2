//! `strata render`: sample a scene and draw it headlessly to a PNG
//! ([`HeadlessTarget::render_samples`](crate::gpu::HeadlessTarget::render_samples));
//! with `--lod`, draw progressive samples with view-dependent level of detail
//! ([`LodScene`](crate::gpu::LodScene)), for one still or, with `--frames`, a PNG
//! sequence of a moving camera; with `--style stipple|strokes`, draw the samples as
//! stipple dots or brush strokes on paper ([`NprRenderer`](crate::gpu::NprRenderer)).
//! `--sampler` picks who draws the samples ([`crate::gpu::backend`]): the CPU, or the
//! GPU's compute passes straight into the renderer's buffer; the status line names it.

use std::path::{Path, PathBuf};

use anyhow::Context;

use super::{LodArgs, LookArgs, StyleArgs};
use strata_engine::mesh::TriMesh;
use strata_engine::sample::{LodPool, PoolChange, Sample};

use crate::ecs::SamplerBackend;
use crate::gpu::backend::{self, SamplerUse, UsedSampler};
use crate::gpu::{
    GpuContext, GpuSampler, HeadlessTarget, LodFades, LodScene, MeshMode, NprKind, NprRenderer,
    NprStyle, OrbitCamera, SplatLod, SplatRenderer,
};
use crate::scene::Scene;

/// Arguments of `strata render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) sampled with the field of `--field`
    /// (uniform density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Output image (PNG).
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Image width in pixels (at least 1).
    #[arg(long, default_value_t = 1280, value_parser = super::pixels)]
    pub width: u32,
    /// Image height in pixels (at least 1).
    #[arg(long, default_value_t = 960, value_parser = super::pixels)]
    pub height: u32,
    /// Samples per pixel (1 or 4).
    #[arg(long, default_value_t = 4)]
    pub msaa: u32,
    /// Camera, colours and sample count.
    #[command(flatten)]
    pub look: LookArgs,
    /// `--lod`, `--lod-max` and `--lod-shown`.
    #[command(flatten)]
    pub lod: LodArgs,
    /// With `--lod`: frames to draw; with more than one, `--out` gets a frame number
    /// (`out.png` becomes `out_0000.png`, `out_0001.png`, ...).
    #[arg(long, default_value_t = 1, requires = "lod")]
    pub frames: u32,
    /// With `--frames`: camera turn about the vertical axis per frame, degrees.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        requires = "lod"
    )]
    pub orbit: f32,
    /// With `--frames`: camera distance factor per frame (0.99 moves 1% closer).
    #[arg(long, default_value_t = 1.0, requires = "lod")]
    pub dolly: f32,
    /// With `--lod`: twist the mesh about the vertical axis through its centre, up to
    /// this many degrees between its bottom and top, swinging once over the frames:
    /// the samples ride the deforming surface without being drawn again.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        requires = "lod"
    )]
    pub twist: f32,
    /// `--style` and `--brush`.
    #[command(flatten)]
    pub paint: StyleArgs,
    /// Who draws the samples: `auto` (the GPU on a hardware adapter, the CPU on a
    /// software one), `cpu` (the reference) or `gpu` (compute passes on any adapter;
    /// the same samples to `f32` round-off). With `--lod` the pool is drawn on the CPU.
    #[arg(long, value_enum, default_value_t = SamplerBackend::Auto)]
    pub sampler: SamplerBackend,
}

/// Runs `strata render`.
pub(super) fn run(args: &RenderArgs) -> anyhow::Result<()> {
    args.look.validate()?;
    if !matches!(args.msaa, 1 | 4) {
        anyhow::bail!("--msaa must be 1 or 4, not {}", args.msaa);
    }
    let npr = args.paint.npr_kind_for(args.lod.lod)?;
    super::check_output(&args.out, "--out (PNG)", &["png"])?;
    if args.lod.lod {
        check_lod_args(args)?;
    }
    let config = args.input.load(&args.config)?;
    super::refuse_inputs_as_outputs(&args.config, &config, &[Some(&args.out)])?;
    // The GPU first: without one, fail before the preprocessing.
    let ctx = GpuContext::headless(&args.look.gpu_options()).context(match args.sampler {
        SamplerBackend::Gpu => "--sampler gpu needs a GPU adapter; opening one",
        _ => "opening a GPU",
    })?;
    let used = backend::resolve(args.sampler, Some(&ctx.adapter.get_info()))?;
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
    if args.lod.lod {
        return run_lod(args, &ctx, &target, &scene, count, seed);
    }
    let mut splats = SplatRenderer::new(&ctx.device, target.format())?;
    let samples = draw(&ctx, &scene, used, count, seed, &mut splats)?;
    if let Some(kind) = npr {
        let drawn = Drawn {
            samples: &samples,
            used,
            seed,
        };
        return run_npr(args, &ctx, &target, &scene, &mut splats, kind, &drawn);
    }
    if args.look.mesh != MeshMode::None {
        let segments = crate::gpu::splat::face_segments(&scene.sampler);
        splats.set_mesh(&ctx.device, &ctx.queue, &scene.mesh, Some(&segments))?;
    }
    let camera = args
        .look
        .camera(&scene, args.width as f32 / args.height as f32);
    let image = target.render(&ctx, &splats, &camera, &args.look.style(&samples))?;
    image
        .write_png(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    say!(
        "rendered {count} samples (seed {seed}, {used}) at {}x{} on {}; wrote {}",
        args.width,
        args.height,
        ctx.adapter_summary(),
        args.out.display()
    );
    Ok(())
}

/// Draws `count` samples for `seed` into `splats`' buffer with the sampler `used`: on
/// the CPU and uploaded, or on the GPU in place. Returns them on the CPU (the GPU's
/// read back once), for the colour map's range.
fn draw(
    ctx: &GpuContext,
    scene: &Scene,
    used: SamplerUse,
    count: usize,
    seed: u64,
    splats: &mut SplatRenderer,
) -> anyhow::Result<Vec<Sample>> {
    let (device, queue) = (&ctx.device, &ctx.queue);
    Ok(match used.used {
        UsedSampler::Cpu => {
            let samples = scene.sampler.sample(count, seed);
            splats.upload(device, queue, &samples)?;
            samples
        }
        UsedSampler::Gpu => {
            let mut gpu = GpuSampler::new(device, &scene.sampler)?;
            gpu.sample(device, queue, count, seed, splats.samples_mut())?;
            splats.samples().read_back(device, queue)?
        }
    })
}

/// The samples drawn for a picture: on the CPU (the GPU's read back), the sampler that
/// drew them and their seed.
#[derive(Clone, Copy)]
struct Drawn<'a> {
    samples: &'a [Sample],
    used: SamplerUse,
    seed: u64,
}

/// `strata render --style stipple|strokes`: the samples in `splats` as dots or strokes
/// on paper, the mesh drawn into depth only (it hides what lies behind it).
fn run_npr(
    args: &RenderArgs,
    ctx: &GpuContext,
    target: &HeadlessTarget,
    scene: &Scene,
    splats: &mut SplatRenderer,
    kind: NprKind,
    drawn: &Drawn<'_>,
) -> anyhow::Result<()> {
    let Drawn {
        samples,
        used,
        seed,
    } = *drawn;
    splats.set_mesh(&ctx.device, &ctx.queue, &scene.mesh, None)?;
    let npr = NprRenderer::new(&ctx.device, target.format())?;
    let camera = args
        .look
        .camera(scene, args.width as f32 / args.height as f32);
    let style = NprStyle::for_samples(kind, seed);
    let image = target.render_npr(
        ctx,
        splats,
        &npr,
        &camera,
        &args.look.style(samples),
        &style,
    )?;
    image
        .write_png(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let what = match kind {
        NprKind::Stipple => "stipple".to_string(),
        NprKind::Strokes(b) => format!("{} strokes", b.name()),
    };
    say!(
        "rendered {} samples as {what} (seed {seed}, {used}) at {}x{} on {}; wrote {}",
        samples.len(),
        args.width,
        args.height,
        ctx.adapter_summary(),
        args.out.display()
    );
    Ok(())
}

/// `strata render --lod`: a still or a sequence of a moving camera.
fn run_lod(
    args: &RenderArgs,
    ctx: &GpuContext,
    target: &HeadlessTarget,
    scene: &Scene,
    count: usize,
    seed: u64,
) -> anyhow::Result<()> {
    check_lod_args(args)?;
    let size = (args.width, args.height);
    let base = u32::try_from(count).context("--count: at most 2^32 - 1 with --lod")?;
    let mut camera = args
        .look
        .camera(scene, args.width as f32 / args.height as f32);
    let mut lod_scene = lod_scene(args, ctx, scene, &camera, base, seed)?;
    let mut renderer = SplatRenderer::new(&ctx.device, target.format())?;
    let segments = (args.look.mesh != MeshMode::None)
        .then(|| crate::gpu::splat::face_segments(&scene.sampler));
    if let Some(segments) = &segments {
        renderer.set_mesh(&ctx.device, &ctx.queue, &scene.mesh, Some(segments))?;
    }
    let fades = LodFades::new(&ctx.device)?;
    let look = args
        .look
        .style(&first_records(lod_scene.pool(), scene, count));
    let mut shown_before: Option<Vec<bool>> = None;
    for frame in 0..args.frames {
        if args.twist != 0.0 {
            let phase =
                std::f64::consts::TAU * f64::from(frame) / f64::from(args.frames.max(2) - 1);
            let twisted = twist(
                &scene.mesh,
                f64::from(args.twist).to_radians() * phase.sin(),
            )?;
            lod_scene.deform(
                &ctx.device,
                &ctx.queue,
                &scene.sampler,
                &twisted,
                renderer.samples(),
            )?;
            if let Some(segments) = &segments {
                renderer.set_mesh(&ctx.device, &ctx.queue, &twisted, Some(segments))?;
            }
        }
        let step = lod_scene.frame(
            &ctx.device,
            &ctx.queue,
            &scene.sampler,
            renderer.samples_mut(),
            &camera,
            size,
        )?;
        let style = lod_scene.style(&look);
        let weights = fades.fades(
            &ctx.device,
            &ctx.queue,
            renderer.samples(),
            &camera,
            &style,
            size,
        )?;
        let shown: Vec<bool> = weights.iter().map(|&w| w > 0.0).collect();
        let visible = shown.iter().filter(|&&v| v).count();
        let image = target.render(ctx, &renderer, &camera, &style)?;
        let path = frame_path(&args.out, frame, args.frames);
        image
            .write_png(&path)
            .with_context(|| format!("writing {}", path.display()))?;
        let kept = kept_note(shown_before.as_deref(), &shown, &step.change);
        say!(
            "frame {frame}: {visible} of {} pool samples shown (base count {:.0}), {:.1} KB sent, pool update {:.2} ms{kept}; wrote {}",
            step.entries,
            style.lod.map_or(0.0, |l| l.base),
            step.uploaded as f64 / 1e3,
            step.update.as_secs_f64() * 1e3,
            path.display()
        );
        shown_before = Some(shown);
        camera.orbit(args.orbit.to_radians(), 0.0);
        camera.distance *= args.dolly;
    }
    say!(
        "level of detail: base {base} samples (seed {seed}, sampler cpu (level of detail)), multiplier up to {} at {}x{} on {}",
        args.lod.lod_max,
        args.width,
        args.height,
        ctx.adapter_summary()
    );
    Ok(())
}

/// Checks the options of `strata render --lod`.
fn check_lod_args(args: &RenderArgs) -> anyhow::Result<()> {
    args.lod.validate()?;
    if args.sampler == SamplerBackend::Gpu {
        anyhow::bail!(
            "--sampler gpu does not apply with --lod: the level-of-detail pool is drawn on the CPU (use --sampler auto or cpu)"
        );
    }
    if !(args.dolly > 0.0 && args.dolly.is_finite() && args.orbit.is_finite()) {
        anyhow::bail!("--dolly must be a positive number and --orbit a number");
    }
    if args.frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    if !args.twist.is_finite() {
        anyhow::bail!("--twist must be a number of degrees");
    }
    Ok(())
}

/// The level-of-detail scene of `scene`'s sampler for `seed` with base count `base`,
/// its multiplier set for `camera`, and room for the ranks beyond the count that near
/// surface asks for, or a point budget.
fn lod_scene(
    args: &RenderArgs,
    ctx: &GpuContext,
    scene: &Scene,
    camera: &OrbitCamera,
    base: u32,
    seed: u64,
) -> anyhow::Result<LodScene> {
    let (max, shown) = (args.lod.lod_max, args.lod.lod_shown);
    let lod = SplatLod::for_camera(camera, args.height, base as f32, max);
    let budget = LodPool::room_for(base, shown, f64::from(max));
    let lod_scene = LodScene::new(&ctx.device, &scene.sampler, seed, lod, budget)?;
    Ok(match shown {
        Some(shown) => lod_scene.with_shown(shown),
        None => lod_scene,
    })
}

/// The records of `pool`'s first entries (4096 at most), with the spacings of `count`
/// samples: what the colour map's range is taken from.
fn first_records(pool: &LodPool, scene: &Scene, count: usize) -> Vec<Sample> {
    (pool.sites().iter().zip(pool.ranks()))
        .take(4096)
        .filter_map(|(s, &k)| {
            let b = s.barycentric().map(f64::from);
            scene.sampler.record(s.face, b, s.segment, k, count)
        })
        .collect()
}

/// How many of the last frame's shown samples (`before`) a frame that made `change`
/// still shows (`shown`), as a note for its line; nothing for the first frame or a
/// rebuilt pool (entries keep their rank and site unless the pool was rebuilt).
fn kept_note(before: Option<&[bool]>, shown: &[bool], change: &PoolChange) -> String {
    match (before, change) {
        (Some(before), PoolChange::Appended(_) | PoolChange::Unchanged) => {
            let was = before.iter().filter(|&&v| v).count();
            let still = before.iter().zip(shown).filter(|&(&a, &b)| a && b).count();
            format!(
                ", {:.2}% of the last frame's kept",
                100.0 * still as f64 / was.max(1) as f64
            )
        }
        _ => String::new(),
    }
}

/// `mesh` twisted about the vertical axis through its bounding box's centre by
/// `angle` radians between its bottom and top (linearly in height).
fn twist(mesh: &TriMesh, angle: f64) -> anyhow::Result<TriMesh> {
    let (lo, hi) = mesh.bounds();
    let centre = 0.5 * (lo + hi);
    let height = (hi.y - lo.y).max(f64::MIN_POSITIVE);
    let moved = mesh
        .positions()
        .iter()
        .map(|p| {
            let q = *p - centre;
            let (sin, cos) = (angle * q.y / height).sin_cos();
            centre + glam::DVec3::new(cos * q.x + sin * q.z, q.y, -sin * q.x + cos * q.z)
        })
        .collect();
    Ok(TriMesh::new(moved, mesh.triangles().to_vec())?)
}

/// `out` for a single frame; `out` with `_NNNN` before its extension in a sequence.
fn frame_path(out: &Path, frame: u32, frames: u32) -> PathBuf {
    if frames == 1 {
        return out.to_path_buf();
    }
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}_{frame:04}{ext}"))
}
