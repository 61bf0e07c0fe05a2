//! `strata bench`: preprocess a scene once, resample it several times, print the
//! stage times, the median sampling time and the memory, optionally as JSON.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use strata_engine::sample::{Sample, SampleSite};

use super::write_file;
use crate::gpu::sample_check::{GpuOrder, GpuSampleCheck};
use crate::scene::Scene;

/// Arguments of `strata bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) sampled with the field of `--field`
    /// (uniform density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Samples per run (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Number of sampling runs (their median is reported).
    #[arg(long, default_value_t = 10)]
    pub repeat: usize,
    /// Also write the numbers as JSON (keys in docs/cli.md).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Time `Sampler::sample_sites_into` (16-byte sites: face, segment, barycentric
    /// coordinates; no record) instead of full samples.
    #[arg(long)]
    pub sites: bool,
    /// Run even when the samples (held in memory at once, to time one call) need more
    /// memory than is available (by default refused before preprocessing).
    #[arg(long)]
    pub ignore_memory_check: bool,
    /// Also sample on the GPU (the adapter wgpu opens), in the stratified and the
    /// progressive order: time it per stage and check its samples against the CPU's;
    /// fails past the tolerances.
    #[arg(long)]
    pub gpu: bool,
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
    if let Some(path) = &args.json {
        super::check_output(path, "--json", &["json"])?;
    }
    let config = args.input.load(&args.config)?;
    let count = args.count.unwrap_or(config.sampling.count);
    let fits = if args.ignore_memory_check {
        crate::budget::check_count(count)
    } else {
        crate::budget::check_memory(count)
    };
    let name = args.config.display().to_string();
    super::check_budget(&name, fits, Some("--ignore-memory-check"))?;
    let count = usize::try_from(count).context("sample count does not fit in memory")?;
    let scene = Scene::build(&config).with_context(|| name.clone())?;
    // Reserved fallibly: past --ignore-memory-check an impossible size is an error,
    // not an abort.
    let (mut samples, mut sites) = if args.sites {
        (Vec::new(), filled(count, SampleSite::default(), &name)?)
    } else {
        (filled(count, Sample::default(), &name)?, Vec::new())
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
    say!("| stage | time (ms) |");
    say!("| --- | --- |");
    for (name, s) in &report.stages {
        say!("| {name} | {:.1} |", s * 1e3);
    }
    say!("| preprocessing total | {:.1} |", report.preprocess_s * 1e3);
    say!(
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
    let mut gpu = None;
    if args.gpu {
        let ctx = crate::gpu::GpuContext::headless(&Default::default())?;
        let seed = config.sampling.seed;
        let mut checks = Vec::new();
        for order in [GpuOrder::Stratified, GpuOrder::Progressive] {
            let request = (count, seed, order);
            let check = GpuSampleCheck::run_order(&ctx, &scene.sampler, request, args.repeat)?;
            say!("{check}");
            if !check.passes() {
                bail!(
                    "{name}: the GPU's {order} samples differ from the CPU's past the tolerances"
                );
            }
            checks.push(check);
        }
        gpu = Some(checks);
    }
    if let Some(path) = &args.json {
        // With `--gpu`, the checks' numbers under `gpu` (stratified) and
        // `gpu_progressive`.
        let mut value = serde_json::to_value(&report)?;
        if let (Some(checks), Some(object)) = (&gpu, value.as_object_mut()) {
            for (key, check) in ["gpu", "gpu_progressive"].into_iter().zip(checks) {
                object.insert(key.to_owned(), serde_json::to_value(check)?);
            }
        }
        let text = serde_json::to_string_pretty(&value)?;
        write_file(path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// `count` copies of `value`, or an error naming the scene where they cannot be
/// allocated.
fn filled<T: Clone>(count: usize, value: T, name: &str) -> anyhow::Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|_| {
        anyhow::anyhow!(
            "{name}: {count} samples: could not allocate {:.1} GB",
            (count as f64) * size_of::<T>() as f64 / 1e9
        )
    })?;
    v.resize(count, value);
    Ok(v)
}
