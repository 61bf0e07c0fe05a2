//! Issue 17's table: designed fields on the bundled `configs/<mesh>-smooth.ron` scenes
//! (and on the shared bunny Loop-subdivided once, made in code; for the bunny also the
//! smoothest field, without guidance), with the field's build
//! time, its singularities (singular faces, and clusters of touching faces with a
//! non-zero index) and the segments the surface pipeline makes of it, as a Markdown
//! table: `cargo run --release -p strata-bench --bin field_design [-- repeats]`.
//!
//! Each time is the median of `repeats` builds (default 5) of the scene's field alone
//! (`FieldSpec::build`: curvature, normal smoothing, the sparse solves); segments are
//! those of `Preprocessed::build` with the scene's settings (after splitting invalid
//! segments, as `strata sample` reports them). Needs the shared meshes
//! (`STRATA_MESH_DIR` or `../shared/meshes`).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use strata_engine::field::{Design, FieldSpec, Guidance};
use strata_engine::mesh::{TriMesh, loop_subdivide};
use strata_engine::segment::{detect_singularities, singularity_clusters};
use strata_engine::surface::{Preprocessed, SurfaceOptions};
use strata_systems::config::SceneConfig;

fn row(
    name: &str,
    mesh: TriMesh,
    spec: &FieldSpec,
    options: &SurfaceOptions,
    repeats: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut times = Vec::new();
    let mut field = None;
    for _ in 0..repeats {
        let t = Instant::now();
        field = Some(spec.build(&mesh)?);
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let field = field.ok_or("no run")?;
    let found = detect_singularities(&mesh, &field);
    let clusters = singularity_clusters(&mesh, &found);
    let net = clusters.iter().filter(|c| c.is_singular()).count();
    let faces = mesh.face_count();
    let pre = Preprocessed::build(Arc::new(mesh), Arc::new(field), options)?;
    println!(
        "| {name} | {faces} | {:.3} | {} | {net} | {} | {} |",
        times[times.len() / 2],
        found.len(),
        pre.report.segments_before_split,
        pre.report.segments,
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?;
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    println!(
        "| scene | faces | field build median (s) | singular faces | singularities (net clusters) | segments before split | segments |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for name in strata_bench::SHARED_MESHES {
        let config = SceneConfig::load(&configs.join(format!("{name}-smooth.ron")))?;
        let mesh = strata_systems::scene::load_mesh(&config)?;
        let options = config.surface_options();
        if name == "stanford-bunny" {
            // Also the smoothest field (no guidance), the "smooth field".
            let smoothest = FieldSpec::Designed(Design {
                guidance: Guidance::Smoothest,
                ..Design::default()
            });
            let fine = loop_subdivide(&mesh)?;
            row(name, mesh.clone(), &config.field, &options, repeats)?;
            row(
                "stanford-bunny, Loop-subdivided once",
                fine.clone(),
                &config.field,
                &options,
                repeats.min(3),
            )?;
            row(
                "stanford-bunny, smoothest",
                mesh,
                &smoothest,
                &options,
                repeats.min(3),
            )?;
            row(
                "stanford-bunny, Loop-subdivided once, smoothest",
                fine,
                &smoothest,
                &options,
                repeats.min(3),
            )?;
        } else {
            row(name, mesh, &config.field, &options, repeats)?;
        }
    }
    Ok(())
}
