//! `strata analyze`: read a sample file or sample a scene, then measure the samples
//! and write JSON numbers and PNG plots ([`crate::report::analysis`]).

use std::path::PathBuf;

use anyhow::{Context, bail};

use crate::report::analysis::{AnalysisInput, AnalysisOptions, write_analysis};
use crate::scene::Scene;

/// Arguments of `strata analyze`.
#[derive(Debug, clap::Args)]
pub struct AnalyzeArgs {
    /// Scene file (`.ron`) or mesh (`.obj`, a `.ply` mesh) to sample, or a sample file
    /// (`.ply`, as `strata sample` writes) to analyse as it is.
    pub input: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub mesh: super::MeshFieldArgs,
    /// Output folder for the JSON and PNG files (created if missing).
    #[arg(long, short = 'o', default_value = "analysis")]
    pub out: PathBuf,
    /// Samples per realization (scene only; overrides `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Realizations to average (scene only): seeds `seed, seed + 1, ...`.
    #[arg(long, default_value_t = 4)]
    pub runs: u64,
    /// First seed (scene only; overrides `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// DDA kernel support in expected spacings (the paper's epsilon).
    #[arg(long, default_value_t = 10.0)]
    pub epsilon: f64,
    /// Write only the JSON numbers, no PNG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Also map the angle between the field and the parameter axes (flat scenes).
    #[arg(long)]
    pub alignment: bool,
    /// Run even when the realizations (held in memory together, 64 bytes a sample)
    /// need more memory than is available (by default refused before preprocessing).
    #[arg(long)]
    pub ignore_memory_check: bool,
}

/// Runs `strata analyze`.
pub(super) fn run(args: &AnalyzeArgs) -> anyhow::Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    // The output folder first: a mistake there must not cost the sampling.
    if args.out.exists() && !args.out.is_dir() {
        bail!("{}: --out names a file; give a folder", args.out.display());
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out: creating the folder {}", args.out.display()))?;
    super::check_folder(&args.out.join("x"), "--out")?;
    let input = load(args)?;
    let options = AnalysisOptions {
        epsilon: args.epsilon,
        plots: !args.no_plots,
        alignment: args.alignment,
    };
    let summary = write_analysis(&input, &args.input, &args.out, &options)?;
    say!(
        "analysed {} x {} samples: wrote JSON{} to {}",
        summary.realizations,
        summary.samples,
        if args.no_plots { "" } else { " and PNG" },
        args.out.display()
    );
    for e in summary.plot_errors.iter().take(1) {
        eprintln!("warning: plots skipped: {e}");
    }
    Ok(())
}

/// The input named by the arguments: a sample file (`.ply`) as it is, or a scene
/// (`.ron`) sampled `--runs` times.
fn load(args: &AnalyzeArgs) -> anyhow::Result<AnalysisInput> {
    let ext = args
        .input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // A mesh PLY reads as points without spacings: it is sampled as a mesh.
    let samples = match ext.as_deref() {
        Some("ply") => Some(strata_engine::io::read_samples_ply(&args.input).ok())
            .flatten()
            .filter(|s| s.iter().any(|s| s.spacing != [0.0, 0.0])),
        _ => None,
    };
    match ext.as_deref() {
        Some("ply") if samples.is_some() => {
            let samples = samples.unwrap_or_default();
            Ok(AnalysisInput::from_samples(samples))
        }
        Some("ron" | "obj" | "ply") => {
            let config = args.mesh.load(&args.input)?;
            let count = args.count.unwrap_or(config.sampling.count);
            if count == 0 {
                bail!("sample count must be at least 1");
            }
            let name = args.input.display().to_string();
            super::check_budget(&name, crate::budget::check_count(count), None)?;
            if !args.ignore_memory_check {
                let total = crate::budget::check_memory_total(count.saturating_mul(args.runs));
                super::check_budget(&name, total, Some("--ignore-memory-check"))?;
            }
            let count = usize::try_from(count).context("sample count does not fit in memory")?;
            let scene = Scene::build(&config).with_context(|| name.clone())?;
            let seed = args.seed.unwrap_or(config.sampling.seed);
            Ok(AnalysisInput::from_scene(
                scene, config, count, seed, args.runs,
            ))
        }
        _ => bail!(
            "{}: expected a scene (.ron), a mesh (.obj, .ply) or a sample file (.ply)",
            args.input.display()
        ),
    }
}
