//! `strata segment`: segment a scene's mesh along its field, parameterize the segments
//! (splitting invalid ones), print the counts, and write the mesh coloured by segment,
//! the JSON report ([`SegmentReport`]) and the SVG atlas on request.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use strata_engine::surface::{
    SegmentationKind, SurfaceOptions, parameterize_with_splitting, segment_surface,
};

use super::write_file;
use crate::report::segment::{SegmentReport, segment_colors};

/// Arguments of `strata segment`.
#[derive(Debug, clap::Args)]
pub struct SegmentArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) sampled with the field of `--field`
    /// (uniform density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Output mesh (binary PLY) with one colour per segment; singular faces are black.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// JSON report (schema in docs/cli.md).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Segmentation seed (overrides the scene's `segment.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// SVG drawing of every final segment's parameter layout with the mapped field.
    #[arg(long)]
    pub atlas: Option<PathBuf>,
}

/// Runs `strata segment`.
pub(super) fn run(args: &SegmentArgs) -> anyhow::Result<()> {
    check_out_is_ply(args)?;
    let config = args.input.load(&args.config)?;
    super::refuse_inputs_as_outputs(
        &args.config,
        &config,
        &[
            args.out.as_deref(),
            args.report.as_deref(),
            args.atlas.as_deref(),
        ],
    )?;
    for (path, flag, ext) in [
        (&args.out, "--out (a PLY mesh)", "ply"),
        (&args.report, "--report (JSON)", "json"),
        (&args.atlas, "--atlas (SVG)", "svg"),
    ] {
        if let Some(path) = path {
            super::check_output(path, flag, &[ext])?;
        }
    }
    let name = args.config.display().to_string();
    let progress = crate::scene::progress_spinners();
    let (mesh, mesh_time) =
        crate::scene::stage(&progress, "mesh", || crate::scene::load_mesh(&config));
    let mesh = mesh.with_context(|| name.clone())?;
    let (field, field_time) = crate::scene::stage(&progress, "field", || config.field.build(&mesh));
    let field = field.with_context(|| format!("{name}: field"))?;
    let load_time = mesh_time + field_time;
    for w in mesh.warnings() {
        eprintln!("warning: {name}: mesh: {w}");
    }
    let mut options = config.surface_options();
    if let Some(seed) = args.seed {
        options.segment.seed = seed;
    }
    // Which vertices are isotropic in the scene's own field (charts in the report).
    let isotropic =
        strata_engine::field::isotropic_vertices(&mesh, &field, options.isotropy_threshold);
    // As preprocessing does: charts for a fully isotropic field, otherwise isotropic
    // regions take a smooth direction before the field-aligned segmentation.
    options
        .validate()
        .with_context(|| format!("{name}: surface settings"))?;
    let mut stages = Vec::new();
    let surface = segment_surface(&mesh, Arc::new(field), &options, &progress, &mut stages)
        .with_context(|| format!("{name}: segmentation"))?;
    print_segmentation_kind(surface.kind, &options, mesh.vertex_count());
    let (field, seg) = (surface.field, surface.segmentation);
    let seg_time: Duration = stages.iter().map(|(_, d)| *d).sum();
    let (split, param_time) = crate::scene::stage(&progress, "parameterization", || {
        parameterize_with_splitting(&mesh, &field, &seg, &options)
    });
    let (params, split) = split.with_context(|| format!("{name}: parameterization"))?;
    let report = SegmentReport::new(
        &mesh,
        &seg,
        &params,
        split.splits,
        seg_time.as_secs_f64(),
        param_time.as_secs_f64(),
        &isotropic,
    );
    let times = Times {
        load: load_time,
        segmentation: seg_time,
        parameterization: param_time,
    };
    print_summary(&name, &report, split.merges, times);
    if let Some(path) = &args.atlas {
        crate::report::atlas::write_atlas_svg(path, &mesh, &field, &params)
            .with_context(|| format!("writing {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &args.out {
        let colors = segment_colors(&mesh, &seg, &params);
        strata_engine::io::write_mesh_ply(path, &mesh, Some(&colors))
            .with_context(|| format!("writing {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &args.report {
        let text = serde_json::to_string_pretty(&report)?;
        write_file(path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// `--out` writes a binary PLY: refuses another extension before any work.
fn check_out_is_ply(args: &SegmentArgs) -> anyhow::Result<()> {
    if let Some(out) = &args.out {
        let ply = out
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
        if !ply {
            anyhow::bail!(
                "{}: --out writes a binary PLY mesh; name it .ply",
                out.display()
            );
        }
    }
    Ok(())
}

/// Says how isotropy shaped the segmentation (charts everywhere, or how many
/// vertices took a smooth direction); nothing for a fully anisotropic field.
fn print_segmentation_kind(kind: SegmentationKind, options: &SurfaceOptions, vertices: usize) {
    match kind {
        SegmentationKind::IsotropicCharts => say!(
            "the field is isotropic everywhere (anisotropy under {}): normal-cone charts of half-angle {:.1} degrees",
            options.isotropy_threshold,
            options.chart_angle.to_degrees()
        ),
        SegmentationKind::FieldAligned { smoothed_vertices } if smoothed_vertices > 0 => say!(
            "{smoothed_vertices} of {vertices} vertices are isotropic (anisotropy under {}): they take a smooth direction",
            options.isotropy_threshold
        ),
        SegmentationKind::FieldAligned { .. } => {}
    }
}

/// The stages' wall times.
#[derive(Clone, Copy)]
struct Times {
    load: Duration,
    segmentation: Duration,
    parameterization: Duration,
}

/// Prints the segmentation's and the parameterization's counts and times, and warns
/// about segments that are not topological discs.
fn print_summary(name: &str, report: &SegmentReport, merges: usize, times: Times) {
    let plus = report
        .singularities
        .iter()
        .filter(|s| s.index > 0.0)
        .count();
    let minus = report.singularities.len() - plus;
    let index_sum: f64 = report.singularities.iter().map(|s| s.index).sum();
    say!(
        "{} faces (Euler characteristic {}): {} segments, {} singularities ({plus} of +1/2, {minus} of -1/2, index sum {}), {} cut edges; segmentation {:.3} s (loading {:.3} s)",
        report.faces,
        report.euler_characteristic,
        report.segments_before_split,
        report.singularities.len(),
        index_sum + 0.0, // an empty sum is -0
        report.cut_edges,
        times.segmentation.as_secs_f64(),
        times.load.as_secs_f64(),
    );
    let valid = report.segments.iter().filter(|s| s.valid).count();
    let fallback = report
        .segments
        .iter()
        .filter(|s| s.isotropic_fallback)
        .count();
    say!(
        "parameterization: {} segments after {} splits and {} merges ({} isotropic charts, {} field-aligned), {valid} valid, {fallback} with the isotropic fallback; {:.3} s",
        report.segment_count,
        report.splits,
        merges,
        report.charts,
        report.segment_count - report.charts,
        times.parameterization.as_secs_f64()
    );
    let not_discs = report
        .segments
        .iter()
        .filter(|s| s.euler_characteristic != 1 || s.boundary_loops != 1)
        .count();
    if not_discs > 0 {
        eprintln!("warning: {name}: {not_discs} segments are not topological discs");
    }
}
