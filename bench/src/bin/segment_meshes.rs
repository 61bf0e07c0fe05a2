//! Segmentation time per shared mesh, for a projected constant-direction field and a
//! curvature field, with segment and singularity counts, as a Markdown table:
//! `cargo run --release -p strata-bench --bin segment_meshes [-- repeats]`.
//!
//! Reads the meshes from `STRATA_MESH_DIR` or `../shared/meshes`; each row is the
//! median of `repeats` runs (default 3) of `segment::segment` alone (loading the mesh
//! and building the field are excluded and shown apart).

use std::time::Instant;

use strata_engine::field::FieldSpec;
use strata_engine::segment::{SegmentOptions, segment};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(3)?;
    let dir = strata_bench::shared_mesh_dir()?;
    let fields = [
        (
            "constant 3:1",
            FieldSpec::Constant {
                direction: [1.0, 0.3, 0.2],
                anisotropy: 3.0,
                density: 1.0,
            },
        ),
        ("curvature", FieldSpec::default_curvature()),
    ];
    println!(
        "| mesh | faces | field | field build (ms) | segmentation median (ms) | segments | singularities | index sum | Euler char. | cut edges |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for name in strata_bench::SHARED_MESHES {
        let mesh = strata_engine::io::load(&dir.join(format!("{name}.obj")))?;
        for (label, spec) in &fields {
            let t = Instant::now();
            let field = spec.build(&mesh)?;
            let field_ms = t.elapsed().as_secs_f64() * 1e3;
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..repeats {
                let t = Instant::now();
                let seg = segment(&mesh, &field, &SegmentOptions::default())?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                last = Some(seg);
            }
            times.sort_by(f64::total_cmp);
            let seg = last.ok_or("no run")?;
            let index_sum: f64 = seg.singularities.iter().map(|s| s.index).sum();
            println!(
                "| {name} | {} | {label} | {field_ms:.1} | {:.1} | {} | {} | {index_sum} | {} | {} |",
                mesh.face_count(),
                times[times.len() / 2],
                seg.segments.len(),
                seg.singularities.len(),
                mesh.euler_characteristic(),
                seg.cut_edges.len(),
            );
        }
    }
    Ok(())
}
