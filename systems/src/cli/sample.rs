//! `strata sample`: preprocess a scene, draw its samples once, print the timings and
//! optionally write the samples (PLY or CSV).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use strata_engine::io::SampleFormat;
use strata_engine::sample::{Sample, Sampler};

use super::output_kind;
use crate::config::SceneConfig;
use crate::scene::Scene;

/// Samples drawn and written at a time (4 MiB): any count runs in this much memory
/// beyond the preprocessed scene.
const BLOCK: usize = 1 << 16;

/// Arguments of `strata sample`.
#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) sampled with the field of `--field`
    /// (uniform density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Number of samples (overrides the scene's `sampling.count`).
    #[arg(long, short = 'n')]
    pub count: Option<u64>,
    /// Random seed (overrides the scene's `sampling.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output file: `.ply` (binary) or `.csv`, chosen by extension (default:
    /// `<input name>.samples.ply` beside the input).
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// Write no file: print the timings only.
    #[arg(long, conflicts_with = "out")]
    pub no_out: bool,
    /// Worker threads, 1 to 1024 (default: one per core). The samples do not depend on
    /// it.
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Sample order: `stratified` (exactly stratified for this count) or
    /// `progressive` (the first N of one sequence per scene and seed, so the samples of
    /// a count are among those of any larger count).
    #[arg(long, value_enum, default_value_t = Order::Stratified)]
    pub order: Order,
    /// Write even when the output (64 bytes per sample in PLY, at least 32 in CSV)
    /// needs more space than its file system has free (by default such a request is
    /// refused before preprocessing). Samples are drawn and written a block of 65,536
    /// at a time, so memory never limits the count.
    #[arg(long)]
    pub ignore_space_check: bool,
}

/// How samples are drawn (`--order`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    /// `Sampler::sample_into`: exactly stratified for the count asked.
    Stratified,
    /// `Sampler::progressive_into`: nested prefixes of one stratified sequence.
    Progressive,
}

/// Most worker threads `--threads` takes: far beyond any core count, and few enough
/// that starting them cannot exhaust a process's threads.
pub const MAX_THREADS: usize = 1024;

/// Parses `--threads`: a count from 1 to [`MAX_THREADS`].
fn parse_threads(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!("give a count from 1 to {MAX_THREADS}")),
    }
}

/// Runs `strata sample`: on a pool of `--threads` workers when given (the samples are
/// the same for any count), else on the process's pool.
pub(super) fn run(args: &SampleArgs) -> anyhow::Result<()> {
    let Some(threads) = args.threads else {
        return run_here(args);
    };
    if !(1..=MAX_THREADS).contains(&threads) {
        anyhow::bail!("--threads {threads}: give a count from 1 to {MAX_THREADS}");
    }
    // A pool of its own: the process's global pool is built at start-up (the binary
    // makes its main thread a worker), and rayon's global pool cannot be rebuilt.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .with_context(|| format!("could not start {threads} worker threads"))?;
    pool.install(|| run_here(args))
}

/// [`run`]'s work, on the pool it is called from.
fn run_here(args: &SampleArgs) -> anyhow::Result<()> {
    let config = args.input.load(&args.config)?;
    super::refuse_inputs_as_outputs(&args.config, &config, &[output_path(args).as_deref()])?;
    let out_path = output_path(args);
    let out = match &out_path {
        Some(path) => {
            let kind = output_kind(path)?;
            super::check_output(path, "--out", &[])?;
            Some((path.as_path(), kind))
        }
        None => None,
    };
    let count = check_request(args, &config, out)?;
    let scene = Scene::build(&config).with_context(|| args.config.display().to_string())?;
    for w in scene.mesh.warnings() {
        eprintln!("warning: {}: mesh: {w}", args.config.display());
    }
    let seed = args.seed.unwrap_or(config.sampling.seed);
    let mut draw = Draw::new(&scene.sampler, args.order, seed, count);
    draw.all(out)?;
    draw.bar.finish_and_clear();
    print_timings(&scene, args.order, count, seed, draw.took);
    if let Some(path) = &out_path {
        say!("wrote {}", path.display());
        if args.out.is_none() {
            let image = path.with_extension("").with_extension("png");
            say!(
                "see them: strata render {} -o {}",
                args.config.display(),
                image.display()
            );
        }
    }
    Ok(())
}

/// Where the samples go: `--out`, else `<input stem>.samples.ply` beside the input,
/// or nowhere with `--no-out`.
fn output_path(args: &SampleArgs) -> Option<PathBuf> {
    if args.no_out {
        return None;
    }
    args.out.clone().or_else(|| {
        let stem = args.config.file_stem()?.to_string_lossy().into_owned();
        Some(args.config.with_file_name(format!("{stem}.samples.ply")))
    })
}

/// Every check of the request before the preprocessing: the sample count, and the
/// space the output file needs (unless `--ignore-space-check`). Returns the count.
fn check_request(
    args: &SampleArgs,
    config: &SceneConfig,
    out: Option<(&Path, SampleFormat)>,
) -> anyhow::Result<u64> {
    let count = args.count.unwrap_or(config.sampling.count);
    let config_name = args.config.display().to_string();
    super::check_budget(&config_name, crate::budget::check_count(count), None)?;
    // Drawn a block at a time, so memory does not limit the count; a file's size does
    // (a device, pipe or standard output takes what its reader does).
    if let Some((path, format)) = out
        && !args.ignore_space_check
        && !super::is_stream(path)
    {
        let per_sample = match format {
            SampleFormat::Ply => crate::budget::SAMPLE_BYTES,
            SampleFormat::Csv => 32,
        };
        let free = crate::budget::available_space(path);
        super::check_budget(
            &path.display().to_string(),
            crate::budget::check_fits(count, per_sample, free, crate::budget::Resource::Space),
            Some("--ignore-space-check"),
        )?;
    }
    Ok(count)
}

/// Prints the count, order, cells and the sampling and preprocessing times (and the
/// surface pipeline's counts, when the scene went through it).
fn print_timings(scene: &Scene, order: Order, count: u64, seed: u64, sample_time: Duration) {
    let preprocess: f64 = scene.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
    let cells: usize = scene
        .sampler
        .segments()
        .iter()
        .map(|s| s.curve.cell_count())
        .sum();
    say!(
        "sampled {count} points (seed {seed}, {} order) on {} faces, {cells} cells: sampling {:.3} ms, preprocessing {:.3} ms ({})",
        match order {
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
        say!(
            "surface: {} singularities; {} segments after segmentation, {} after {} splits of invalid ones and {} merges of valid neighbours ({} with the isotropic fallback)",
            s.singularities,
            s.segments_before_split,
            s.segments,
            s.splits,
            s.merges,
            s.isotropic_segments
        );
    }
}

/// Draws one request a block at a time, timing the drawing alone and showing progress
/// on a terminal for large counts.
struct Draw<'a> {
    sampler: &'a Sampler,
    order: Order,
    seed: u64,
    count: u64,
    /// Time spent drawing (not writing).
    took: Duration,
    /// Progress over the samples (hidden for small counts and off a terminal).
    bar: indicatif::ProgressBar,
}

impl<'a> Draw<'a> {
    fn new(sampler: &'a Sampler, order: Order, seed: u64, count: u64) -> Self {
        let bar = if count >= 10 * BLOCK as u64 {
            indicatif::ProgressBar::new(count).with_message("sampling")
        } else {
            indicatif::ProgressBar::hidden()
        };
        Self {
            sampler,
            order,
            seed,
            count,
            took: Duration::ZERO,
            bar,
        }
    }

    /// Draws the whole request, a block at a time, into `out` (a file and its format)
    /// or, without one, into a reused block only (for the timings).
    fn all(&mut self, out: Option<(&Path, SampleFormat)>) -> anyhow::Result<()> {
        let count = self.count;
        match out {
            Some((path, format)) => {
                // Ctrl-C stops the write at the next block; the temporary file goes.
                let _writing = super::interrupt::writing();
                strata_engine::io::write_samples_in_blocks(
                    path,
                    format,
                    count,
                    BLOCK,
                    |start, block| {
                        super::interrupt::check()?;
                        self.fill(start, block);
                        Ok(())
                    },
                )
                .with_context(|| format!("writing {}", path.display()))?;
            }
            None => {
                let mut block = vec![Sample::default(); BLOCK.min(count as usize)];
                let mut start = 0;
                while start < count {
                    let len = block.len().min((count - start) as usize);
                    self.fill(start, &mut block[..len]);
                    start += len as u64;
                }
            }
        }
        Ok(())
    }

    /// Fills `block` with the samples `start..start + block.len()` of the request.
    fn fill(&mut self, start: u64, block: &mut [Sample]) {
        let t = Instant::now();
        match self.order {
            Order::Stratified => self
                .sampler
                .sample_range_into(self.seed, self.count, start, block),
            // Ranks fit in u32: the count is at most 2^32 (checked before).
            Order::Progressive => self
                .sampler
                .progressive_into(self.seed, start as u32, block),
        }
        self.took += t.elapsed();
        self.bar.inc(block.len() as u64);
    }
}
