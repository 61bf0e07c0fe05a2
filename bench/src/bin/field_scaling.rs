//! The designed field's build time against mesh size, with each linear solver: the
//! bundled `configs/stanford-bunny-smooth.ron` field on the shared bunny and on the
//! bunny Loop-subdivided once and twice (made in code), as a Markdown table:
//! `cargo run --release -p strata-bench --bin field_scaling [-- repeats]`.
//!
//! Per mesh, the two solvers run alternately (`repeats` times each, default 3; once
//! each on the largest mesh) and the table shows their medians, the growth of each per
//! 4x faces, and the net singularities of both fields (they should agree). Needs the
//! shared meshes (`STRATA_MESH_DIR` or `../shared/meshes`).

use std::path::Path;
use std::time::Instant;

use strata_bench::median;
use strata_engine::field::{FieldSpec, LinearSolver, TensorField};
use strata_engine::mesh::{TriMesh, loop_subdivide};
use strata_engine::segment::{detect_singularities, singularity_clusters};
use strata_systems::config::SceneConfig;

fn with_solver(spec: &FieldSpec, solver: LinearSolver) -> Result<FieldSpec, String> {
    match spec {
        FieldSpec::Designed(design) => {
            let mut design = design.clone();
            design.solver = solver;
            Ok(FieldSpec::Designed(design))
        }
        _ => Err("the bunny scene's field is not a designed field".into()),
    }
}

fn net_singularities(mesh: &TriMesh, field: &TensorField) -> usize {
    let found = detect_singularities(mesh, field);
    singularity_clusters(mesh, &found)
        .iter()
        .filter(|c| c.is_singular())
        .count()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(3)?;
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let config = SceneConfig::load(&configs.join("stanford-bunny-smooth.ron"))?;
    let bunny = strata_systems::scene::load_mesh(&config)?;
    let direct = with_solver(&config.field, LinearSolver::Direct)?;
    let multigrid = with_solver(&config.field, LinearSolver::Multigrid)?;
    println!(
        "| mesh | faces | vertices | sparse Cholesky (s) | growth | multigrid (s) | growth | net singularities (Cholesky / multigrid) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut mesh = bunny;
    let mut previous: Option<(f64, f64)> = None;
    for level in 0..3 {
        let runs = if level == 2 { 1 } else { repeats };
        let (mut td, mut tm) = (Vec::new(), Vec::new());
        let (mut fd, mut fm) = (None, None);
        for _ in 0..runs {
            let t = Instant::now();
            fd = Some(direct.build(&mesh)?);
            td.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            fm = Some(multigrid.build(&mesh)?);
            tm.push(t.elapsed().as_secs_f64());
        }
        let (td, tm) = (median(td), median(tm));
        let growth = |now: f64, before: Option<f64>| {
            before.map_or_else(|| "-".to_string(), |b| format!("{:.1}x", now / b))
        };
        let name = match level {
            0 => "stanford-bunny",
            1 => "Loop-subdivided once",
            _ => "Loop-subdivided twice",
        };
        println!(
            "| {name} | {} | {} | {td:.2} | {} | {tm:.2} | {} | {} / {} |",
            mesh.face_count(),
            mesh.vertex_count(),
            growth(td, previous.map(|p| p.0)),
            growth(tm, previous.map(|p| p.1)),
            net_singularities(&mesh, &fd.ok_or("no run")?),
            net_singularities(&mesh, &fm.ok_or("no run")?),
        );
        previous = Some((td, tm));
        if level < 2 {
            mesh = loop_subdivide(&mesh)?;
        }
    }
    Ok(())
}
