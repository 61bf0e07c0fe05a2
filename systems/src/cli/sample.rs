//! `strata sample`: preprocess a scene, draw its samples once, print the timings and
//! optionally write the samples (PLY or CSV).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use strata_engine::sample::Sample;

use super::{OutputKind, output_kind};
use crate::config::SceneConfig;
use crate::scene::Scene;

/// Arguments of `strata sample`.
#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Scene file (RON); see configs/ and the README.
    pub config: PathBuf,
    /// Number of samples (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Random seed (overrides the scene's `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output file: `.ply` (binary) or `.csv`, chosen by extension.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// Worker threads (default: one per core). The samples do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Sample order: `stratified` (exactly stratified for this count) or
    /// `progressive` (the first N of one sequence per scene and seed, so the samples of
    /// a count are among those of any larger count).
    #[arg(long, value_enum, default_value_t = Order::Stratified)]
    pub order: Order,
    /// Draw even when the samples (64 bytes each) need more memory than the machine
    /// has available (by default such a request is refused before preprocessing).
    #[arg(long)]
    pub ignore_memory_check: bool,
}

/// How samples are drawn (`--order`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    /// `Sampler::sample_into`: exactly stratified for the count asked.
    Stratified,
    /// `Sampler::progressive_into`: nested prefixes of one stratified sequence.
    Progressive,
}

/// Runs `strata sample`.
pub(super) fn run(args: &SampleArgs) -> anyhow::Result<()> {
    if let Some(threads) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("could not start the thread pool")?;
    }
    let config = SceneConfig::load(&args.config)?;
    super::refuse_inputs_as_outputs(&args.config, &config, &[args.out.as_deref()])?;
    let out_kind = match &args.out {
        Some(path) => Some(output_kind(path)?),
        None => None,
    };
    // Every check of the request before the preprocessing.
    let count = args.count.unwrap_or(config.sampling.count);
    if args.order == Order::Progressive && count > 1 << 32 {
        anyhow::bail!(
            "{}: --order progressive draws at most 2^32 = 4294967296 samples, asked for {count}",
            args.config.display()
        );
    }
    let bytes = count.checked_mul(std::mem::size_of::<Sample>() as u64);
    let available = if args.ignore_memory_check && bytes.is_some() {
        None
    } else {
        super::available_memory()
    };
    super::check_memory(&format!("{count} samples"), bytes, available)
        .with_context(|| args.config.display().to_string())?;
    let count = usize::try_from(count).context("sample count does not fit in memory")?;
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    for w in scene.mesh.warnings() {
        eprintln!("warning: {}: mesh: {w}", args.config.display());
    }
    let seed = args.seed.unwrap_or(config.sampling.seed);
    let mut samples = Vec::new();
    samples
        .try_reserve_exact(count)
        .with_context(|| format!("{}: allocating {count} samples", args.config.display()))?;
    samples.resize(count, Sample::default());
    let t = Instant::now();
    match args.order {
        Order::Stratified => scene.sampler.sample_into(seed, &mut samples),
        Order::Progressive => scene.sampler.progressive_into(seed, 0, &mut samples),
    }
    let sample_time = t.elapsed();
    let preprocess: f64 = scene.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
    let cells: usize = scene
        .sampler
        .segments()
        .iter()
        .map(|s| s.curve.cell_count())
        .sum();
    println!(
        "sampled {count} points (seed {seed}, {} order) on {} faces, {cells} cells: sampling {:.3} ms, preprocessing {:.3} ms ({})",
        match args.order {
            Order::Stratified => "stratified",
            Order::Progressive => "progressive",
        },
        scene.mesh.face_count(),
        sample_time.as_secs_f64() * 1e3,
        preprocess * 1e3,
        scene
            .stages
            .iter()
            .map(|(n, d)| format!("{n} {:.3} ms", d.as_secs_f64() * 1e3))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(s) = &scene.surface {
        println!(
            "surface: {} singularities; {} segments after segmentation, {} after {} splits of invalid ones ({} with the isotropic fallback)",
            s.singularities, s.segments_before_split, s.segments, s.splits, s.isotropic_segments
        );
    }
    if let (Some(path), Some(kind)) = (&args.out, out_kind) {
        match kind {
            OutputKind::Ply => strata_engine::io::write_samples_ply(path, &samples),
            OutputKind::Csv => strata_engine::io::write_samples_csv(path, &samples),
        }
        .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
