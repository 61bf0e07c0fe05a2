//! The `strata` command-line tool.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Parser, Subcommand};
use strata_engine::sample::{Sample, SampleSite};

use strata_engine::surface::{SurfaceOptions, parameterize_with_splitting};

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
    /// Segment a scene's mesh along its field; write the mesh coloured by segment.
    Segment(SegmentArgs),
    /// Preprocess a scene once, resample it several times, and report timings and memory.
    Bench(BenchArgs),
    /// Sample a scene and draw it as field-aligned splats into a PNG, without a window.
    Render(crate::render::RenderArgs),
    /// Open a window that resamples and draws the scene every frame (orbit camera).
    View(crate::view::ViewArgs),
    /// Watch a scene file: recompute what each change invalidates, print per stage what
    /// reran, rewrite the samples file atomically after each change.
    Watch(crate::watch::WatchArgs),
    /// Measure samples: discrepancy, spectra, differential domain analysis (JSON + PNG).
    Analyze(crate::analyze::AnalyzeArgs),
}

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

/// Arguments of `strata segment`.
#[derive(Debug, clap::Args)]
pub struct SegmentArgs {
    /// Scene file (RON); its `mesh`, `field` and `segment` sections are used.
    pub config: PathBuf,
    /// Output mesh (binary PLY) with one colour per segment; singular faces are black.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// JSON report (schema in the README).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Segmentation seed (overrides the scene's `segment.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// SVG drawing of every final segment's parameter layout with the mapped field.
    #[arg(long)]
    pub atlas: Option<PathBuf>,
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
        Command::Segment(args) => segment(&args),
        Command::Bench(args) => bench(&args),
        Command::Render(args) => crate::render::run(&args),
        Command::View(args) => crate::view::run(&args),
        Command::Watch(args) => crate::watch::run(&args),
        Command::Analyze(args) => crate::analyze::analyze(&args),
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

fn bench(args: &BenchArgs) -> anyhow::Result<()> {
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
        write_atomically(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn segment(args: &SegmentArgs) -> anyhow::Result<()> {
    let config = SceneConfig::load(&args.config)?;
    let name = args.config.display().to_string();
    let t = Instant::now();
    let mesh = crate::scene::load_mesh(&config).with_context(|| name.clone())?;
    let field = config
        .field
        .build(&mesh)
        .with_context(|| format!("{name}: field"))?;
    let load_time = t.elapsed();
    for w in mesh.warnings() {
        eprintln!("warning: {name}: mesh: {w}");
    }
    let mut options = config.segment;
    if let Some(seed) = args.seed {
        options.seed = seed;
    }
    let t = Instant::now();
    let seg = strata_engine::segment::segment(&mesh, &field, &options)
        .with_context(|| format!("{name}: segmentation"))?;
    let seg_time = t.elapsed();
    let surface_options = SurfaceOptions {
        segment: options,
        param: config.param,
        curve: config.curve,
        ..Default::default()
    };
    let t = Instant::now();
    let (params, split) = parameterize_with_splitting(&mesh, &field, &seg, &surface_options)
        .with_context(|| format!("{name}: parameterization"))?;
    let param_time = t.elapsed();
    let report = SegmentReport::new(
        &mesh,
        &seg,
        &params,
        split.splits,
        seg_time.as_secs_f64(),
        param_time.as_secs_f64(),
    );
    let plus = report
        .singularities
        .iter()
        .filter(|s| s.index > 0.0)
        .count();
    let minus = report.singularities.len() - plus;
    let index_sum: f64 = report.singularities.iter().map(|s| s.index).sum();
    println!(
        "{} faces (Euler characteristic {}): {} segments, {} singularities ({plus} of +1/2, {minus} of -1/2, index sum {index_sum}), {} cut edges; segmentation {:.3} s (loading {:.3} s)",
        report.faces,
        report.euler_characteristic,
        report.segments_before_split,
        report.singularities.len(),
        report.cut_edges,
        seg_time.as_secs_f64(),
        load_time.as_secs_f64(),
    );
    let valid = report.segments.iter().filter(|s| s.valid).count();
    let fallback = report
        .segments
        .iter()
        .filter(|s| s.isotropic_fallback)
        .count();
    println!(
        "parameterization: {} segments after {} splits, {valid} valid, {fallback} with the isotropic fallback; {:.3} s",
        report.segment_count,
        report.splits,
        param_time.as_secs_f64()
    );
    let not_discs = report
        .segments
        .iter()
        .filter(|s| s.euler_characteristic != 1 || s.boundary_loops != 1)
        .count();
    if not_discs > 0 {
        eprintln!("warning: {name}: {not_discs} segments are not topological discs");
    }
    if let Some(path) = &args.atlas {
        crate::atlas::write_atlas_svg(path, &mesh, &field, &params)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    let mut singular = vec![false; mesh.face_count()];
    for s in &seg.singularities {
        singular[s.face as usize] = true;
    }
    let mut final_segment = vec![0u32; mesh.face_count()];
    for (id, p) in params.iter().enumerate() {
        for &f in &p.faces {
            final_segment[f as usize] = id as u32;
        }
    }
    if let Some(path) = &args.out {
        let colors: Vec<[u8; 3]> = (0..mesh.face_count())
            .map(|f| {
                if singular[f] {
                    [16, 16, 16]
                } else {
                    segment_color(final_segment[f])
                }
            })
            .collect();
        strata_engine::io::write_mesh_ply(path, &mesh, Some(&colors))
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.report {
        let text = serde_json::to_string_pretty(&report)?;
        write_atomically(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The JSON report of `strata segment` (schema in the README).
#[derive(Debug, serde::Serialize)]
pub struct SegmentReport {
    /// Faces of the mesh.
    pub faces: usize,
    /// Euler characteristic of the whole mesh.
    pub euler_characteristic: i64,
    /// Segments made by the segmentation (section 4), before splitting.
    pub segments_before_split: usize,
    /// Final segments, after splitting invalid ones (section 5.2).
    pub segment_count: usize,
    /// Splits of invalid segments.
    pub splits: usize,
    /// Singular faces with their index (+0.5 or -0.5).
    pub singularities: Vec<SingularityReport>,
    /// Edges cut inside segments (singularity trees and disc cuts).
    pub cut_edges: usize,
    /// Wall time of the segmentation, seconds.
    pub segmentation_s: f64,
    /// Wall time of parameterization with splitting, seconds.
    pub parameterization_s: f64,
    /// Per final segment.
    pub segments: Vec<SegmentEntry>,
}

/// One singularity in the report.
#[derive(Debug, serde::Serialize)]
pub struct SingularityReport {
    /// Face index.
    pub face: u32,
    /// Index of the line-field singularity.
    pub index: f64,
}

/// One final segment in the report.
#[derive(Debug, serde::Serialize)]
pub struct SegmentEntry {
    /// Segment id (as in the coloured mesh, the atlas and the samples).
    pub id: usize,
    /// Number of faces.
    pub faces: usize,
    /// Euler characteristic after cutting (1 for a disc).
    pub euler_characteristic: i64,
    /// Number of boundary loops after cutting (1 for a disc).
    pub boundary_loops: usize,
    /// Whether the segment holds a singular face.
    pub has_singular_face: bool,
    /// Valid parameterization: no flip, no overlap, mean angle under gamma.
    pub valid: bool,
    /// Faces flipped in the parameter plane.
    pub flipped: usize,
    /// Whether the parameter mesh overlaps itself.
    pub overlaps: bool,
    /// Area-weighted mean angle between the mapped major direction and the u axis.
    pub mean_angle_deg: f64,
    /// Largest per-face angle.
    pub max_angle_deg: f64,
    /// Parameterized with the isotropic fallback frame.
    pub isotropic_fallback: bool,
}

impl SegmentReport {
    /// Builds the report of a segmentation and its final parameterizations.
    pub fn new(
        mesh: &strata_engine::mesh::TriMesh,
        seg: &strata_engine::segment::Segmentation,
        params: &[strata_engine::param::SegmentParam],
        splits: usize,
        segmentation_s: f64,
        parameterization_s: f64,
    ) -> Self {
        let mut cut = vec![false; mesh.edge_count()];
        for &e in &seg.cut_edges {
            cut[e as usize] = true;
        }
        let mut singular = vec![false; mesh.face_count()];
        for s in &seg.singularities {
            singular[s.face as usize] = true;
        }
        Self {
            faces: mesh.face_count(),
            euler_characteristic: mesh.euler_characteristic(),
            segments_before_split: seg.segments.len(),
            segment_count: params.len(),
            splits,
            singularities: seg
                .singularities
                .iter()
                .map(|s| SingularityReport {
                    face: s.face,
                    index: s.index,
                })
                .collect(),
            cut_edges: seg.cut_edges.len(),
            segmentation_s,
            parameterization_s,
            segments: params
                .iter()
                .enumerate()
                .map(|(id, p)| {
                    let topo = strata_engine::segment::patch_topology(mesh, &p.faces, &cut);
                    let r = &p.report;
                    SegmentEntry {
                        id,
                        faces: p.faces.len(),
                        euler_characteristic: topo.euler_characteristic,
                        boundary_loops: topo.boundary_loops.len(),
                        has_singular_face: p.faces.iter().any(|&f| singular[f as usize]),
                        valid: r.valid,
                        flipped: r.flipped,
                        overlaps: r.overlaps,
                        mean_angle_deg: r.mean_angle_deg,
                        max_angle_deg: r.max_angle_deg,
                        isotropic_fallback: r.isotropic_fallback,
                    }
                })
                .collect(),
        }
    }
}

/// A bright, deterministic colour per segment id (the atlas's hues).
fn segment_color(id: u32) -> [u8; 3] {
    crate::atlas::segment_hue(id as usize).map(|c| (60.0 + 195.0 * c) as u8)
}

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`.
fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
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
