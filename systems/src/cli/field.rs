//! `strata field`: build a scene's field, find the singularities of its major line
//! field, print one summary line ([`FieldReport::summary`]), and write the field as a
//! PLY mesh and the JSON report on request ([`crate::report::field`]).

use std::path::PathBuf;

use anyhow::Context;

use super::write_file;
use crate::report::field::{FieldReport, write_field_ply};

/// Arguments of `strata field`.
#[derive(Debug, clap::Args)]
pub struct FieldArgs {
    /// Scene file (RON), or a mesh (OBJ, PLY) sampled with the field of `--field`
    /// (uniform density by default).
    pub config: PathBuf,
    /// `--field`, `--anisotropy` and `--density-from`, for a mesh input.
    #[command(flatten)]
    pub input: super::MeshFieldArgs,
    /// Output mesh (binary PLY) with per-vertex normal, major direction, anisotropy and
    /// density, and per-face singularity index.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// JSON report (schema in docs/cli.md).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Runs `strata field`.
pub(super) fn run(args: &FieldArgs) -> anyhow::Result<()> {
    let config = args.input.load(&args.config)?;
    super::refuse_inputs_as_outputs(
        &args.config,
        &config,
        &[args.out.as_deref(), args.report.as_deref()],
    )?;
    if let Some(path) = &args.out {
        super::check_output(path, "--out (a PLY mesh)", &["ply"])?;
    }
    if let Some(path) = &args.report {
        super::check_output(path, "--report (JSON)", &["json"])?;
    }
    let name = args.config.display().to_string();
    let progress = crate::scene::progress_spinners();
    let (mesh, _) = crate::scene::stage(&progress, "mesh", || crate::scene::load_mesh(&config));
    let mesh = mesh.with_context(|| name.clone())?;
    for w in mesh.warnings() {
        eprintln!("warning: {name}: mesh: {w}");
    }
    let (field, took) = crate::scene::stage(&progress, "field", || config.field.build(&mesh));
    let field = field.with_context(|| format!("{name}: field"))?;
    let field_s = took.as_secs_f64();
    let singularities = strata_engine::segment::detect_singularities(&mesh, &field);
    let report = FieldReport::new(
        &mesh,
        &field,
        &singularities,
        config.param.isotropy_threshold,
        field_s,
    );
    say!("{}", report.summary());
    if let Some(path) = &args.out {
        write_field_ply(path, &mesh, &field, &singularities)
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
