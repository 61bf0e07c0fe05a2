//! `strata bench`: preprocess a scene once, resample it several times, print the
//! stage times, the median sampling time and the memory, optionally as JSON.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use strata_engine::sample::{Sample, SampleSite};

use super::write_file;
use crate::config::SceneConfig;
use crate::scene::Scene;

/// Arguments of `strata bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Scene file (RON).
    pub config: PathBuf,
    /// Samples per run (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Number of sampling runs (their median is reported).
    #[arg(long, default_value_t = 10)]
    pub repeat: usize,
    /// Also write the numbers as JSON (keys in the README).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Time `Sampler::sample_sites_into` (16-byte sites: face, segment, barycentric
    /// coordinates; no record) instead of full samples.
    #[arg(long)]
    pub sites: bool,
}

/// The JSON written by `strata bench --json`.
#[derive(Debug, serde::Serialize)]
pub struct BenchReport {
    /// Faces of the mesh.
    pub faces: usize,
    /// Segments sampled (1 for flat meshes).
    pub segments: usize,
    /// Total preprocessing wall time, seconds (mesh loading included).
    pub preprocess_s: f64,
    /// Wall time of each preprocessing stage, seconds, in order.
    pub stages: Vec<(String, f64)>,
    /// Samples per run.
    pub count: usize,
    /// What was timed: `"samples"` (full records) or `"sites"` (`--sites`).
    pub mode: &'static str,
    /// Sampling runs.
    pub repeat: usize,
    /// Median sampling time, seconds.
    pub sample_median_s: f64,
    /// Fastest sampling run, seconds.
    pub sample_min_s: f64,
    /// Memory held by the preprocessed data (cells and per-face records), bytes.
    pub bytes: usize,
    /// `bytes` per face.
    pub bytes_per_face: f64,
}

/// Runs `strata bench`.
pub(super) fn run(args: &BenchArgs) -> anyhow::Result<()> {
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    let config = SceneConfig::load(&args.config)?;
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    let count = usize::try_from(args.count.unwrap_or(config.sampling.count))
        .context("sample count does not fit in memory")?;
    let (mut samples, mut sites) = if args.sites {
        (Vec::new(), vec![SampleSite::default(); count])
    } else {
        (vec![Sample::default(); count], Vec::new())
    };
    let mut times = Vec::with_capacity(args.repeat);
    for run in 0..args.repeat {
        let seed = config.sampling.seed.wrapping_add(run as u64);
        let t = Instant::now();
        if args.sites {
            scene.sampler.sample_sites_into(seed, &mut sites);
        } else {
            scene.sampler.sample_into(seed, &mut samples);
        }
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let stages: Vec<(String, f64)> = scene
        .stages
        .iter()
        .map(|(n, d)| (n.to_string(), d.as_secs_f64()))
        .collect();
    let bytes = scene.sampler.heap_bytes();
    let report = BenchReport {
        faces: scene.mesh.face_count(),
        segments: scene.sampler.segments().len(),
        preprocess_s: stages.iter().map(|(_, s)| s).sum(),
        stages,
        count,
        mode: if args.sites { "sites" } else { "samples" },
        repeat: args.repeat,
        sample_median_s: times[times.len() / 2],
        sample_min_s: times[0],
        bytes,
        bytes_per_face: bytes as f64 / scene.mesh.face_count().max(1) as f64,
    };
    println!("| stage | time (ms) |");
    println!("| --- | --- |");
    for (name, s) in &report.stages {
        println!("| {name} | {:.1} |", s * 1e3);
    }
    println!("| preprocessing total | {:.1} |", report.preprocess_s * 1e3);
    println!(
        "{} faces, {} segments; {count} {}: median {:.3} ms over {} runs ({:.1} M samples/s); preprocessed data {:.1} MiB ({:.0} bytes per face)",
        report.faces,
        report.segments,
        report.mode,
        report.sample_median_s * 1e3,
        report.repeat,
        count as f64 / report.sample_median_s / 1e6,
        bytes as f64 / (1024.0 * 1024.0),
        report.bytes_per_face,
    );
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report)?;
        write_file(path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
