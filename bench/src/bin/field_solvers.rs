//! Where the designed field's solver should switch from sparse Cholesky to multigrid
//! (`field::MULTIGRID_VERTICES`): `cargo run --release -p strata-bench --bin
//! field_solvers [-- repeats]`.
//!
//! For each bundled `configs/<mesh>-smooth.ron` scene, on the shared mesh and on the
//! mesh Loop-subdivided once (made in code), the scene's field built with
//! `LinearSolver::Direct` and with `LinearSolver::Multigrid`, alternated `repeats`
//! times (default 3): vertices, the median seconds of each, which is faster, and the
//! net singularities of each (they should agree). Meshes of 100,000 vertices or more
//! are skipped: there the factor's fill makes the direct solver slower by far.

use std::time::Instant;

use strata_bench::median;
use strata_engine::field::{FieldSpec, LinearSolver};
use strata_engine::mesh::{TriMesh, loop_subdivide};
use strata_engine::segment::{detect_singularities, singularity_clusters};

const SCENES: [(&str, &str); 8] = [
    ("stanford-bunny", "stanford-bunny-smooth.ron"),
    ("rocker-arm", "rocker-arm-smooth.ron"),
    ("fandisk", "fandisk-smooth.ron"),
    ("homer", "homer-smooth.ron"),
    ("spot", "spot-smooth.ron"),
    ("cow", "cow-smooth.ron"),
    ("two-torus", "two-torus-smooth.ron"),
    ("wing", "wing-smooth.ron"),
];

/// Skipped from this many vertices (see the module documentation).
const MAX_VERTICES: usize = 100_000;

/// Seconds of each build and the net singularities of the last one.
fn timed(
    spec: &FieldSpec,
    solver: LinearSolver,
    mesh: &TriMesh,
) -> Result<(f64, usize), Box<dyn std::error::Error>> {
    let FieldSpec::Designed(mut design) = spec.clone() else {
        return Err("the scene's field is not a designed field".into());
    };
    design.solver = solver;
    let spec = FieldSpec::Designed(design);
    let t = Instant::now();
    let field = spec.build(mesh)?;
    let seconds = t.elapsed().as_secs_f64();
    let found = detect_singularities(mesh, &field);
    let net = singularity_clusters(mesh, &found)
        .iter()
        .filter(|c| c.is_singular())
        .count();
    Ok((seconds, net))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(3)?;
    let scenes = strata_bench::bundled_scenes(&SCENES)?;
    println!(
        "| mesh | vertices | direct (s) | multigrid (s) | faster | singularities (direct, multigrid) |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (name, config) in &scenes {
        let mut mesh = strata_systems::scene::load_mesh(config)?;
        for level in 0..2 {
            if level > 0 {
                mesh = loop_subdivide(&mesh)?;
            }
            if mesh.vertex_count() >= MAX_VERTICES {
                continue;
            }
            let (mut direct, mut multigrid) = (Vec::new(), Vec::new());
            let mut singular = (0, 0);
            for _ in 0..repeats {
                let (d, sd) = timed(&config.field, LinearSolver::Direct, &mesh)?;
                let (m, sm) = timed(&config.field, LinearSolver::Multigrid, &mesh)?;
                direct.push(d);
                multigrid.push(m);
                singular = (sd, sm);
            }
            let (d, m) = (median(direct), median(multigrid));
            let label = if level > 0 {
                format!("{name}, subdivided once")
            } else {
                name.to_string()
            };
            println!(
                "| {label} | {} | {d:.3} | {m:.3} | {} | {}, {} |",
                mesh.vertex_count(),
                if d <= m { "direct" } else { "multigrid" },
                singular.0,
                singular.1,
            );
        }
    }
    Ok(())
}
