//! The `strata` command-line tool.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Parser, Subcommand};
use strata_engine::sample::Sample;

use crate::config::SceneConfig;
use crate::scene::Scene;

/// strata: anisotropic, density-controlled stratified sampling of surfaces.
#[derive(Debug, Parser)]
#[command(name = "strata", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Sample a scene and optionally write the samples (PLY or CSV).
    Sample(SampleArgs),
}

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
}

/// An error and its causes in one line, joined by `": "`, leaving out causes whose
/// text the line already holds (our error messages often quote their source).
pub fn one_line(error: &anyhow::Error) -> String {
    let mut line = error.to_string();
    for cause in error.chain().skip(1) {
        let text = cause.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
    }
    line
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Sample(args) => sample(&args),
    }
}

fn sample(args: &SampleArgs) -> anyhow::Result<()> {
    if let Some(threads) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("could not start the thread pool")?;
    }
    let config = SceneConfig::load(&args.config)?;
    let out_kind = match &args.out {
        Some(path) => Some(output_kind(path)?),
        None => None,
    };
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    for w in scene.mesh.warnings() {
        eprintln!("warning: {}: mesh: {w}", args.config.display());
    }
    let count = args.count.unwrap_or(config.sampling.count);
    let count = usize::try_from(count).context("sample count does not fit in memory")?;
    let seed = args.seed.unwrap_or(config.sampling.seed);
    let mut samples = vec![Sample::default(); count];
    let t = Instant::now();
    scene.sampler.sample_into(seed, &mut samples);
    let sample_time = t.elapsed();
    let preprocess: f64 = scene.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
    let cells: usize = scene
        .sampler
        .segments()
        .iter()
        .map(|s| s.curve.cell_count())
        .sum();
    println!(
        "sampled {count} points (seed {seed}) on {} faces, {cells} cells: sampling {:.3} ms, preprocessing {:.3} ms ({})",
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

#[derive(Clone, Copy, Debug)]
enum OutputKind {
    Ply,
    Csv,
}

fn output_kind(path: &Path) -> anyhow::Result<OutputKind> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("ply") => Ok(OutputKind::Ply),
        Some("csv") => Ok(OutputKind::Csv),
        _ => bail!("{}: output must end in .ply or .csv", path.display()),
    }
}
