//! Surface preprocessing per shared mesh: segmentation, parameterization with
//! splitting, cells, and the time to draw 10^5 samples, as a Markdown table:
//! `cargo run --release -p strata-bench --bin surface_meshes [-- repeats]`.
//!
//! Each time is the median of `repeats` full preprocessings (default 3). Reads the
//! meshes from `STRATA_MESH_DIR` or `../shared/meshes`.

use std::sync::Arc;
use std::time::Instant;

use strata_bench::median;
use strata_engine::field::FieldSpec;
use strata_engine::sample::Sample;
use strata_engine::surface::{Preprocessed, SurfaceOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(3)?;
    let dir = strata_bench::shared_mesh_dir()?;
    let spec = FieldSpec::Constant {
        direction: [1.0, 0.3, 0.2],
        anisotropy: 3.0,
        density: 1.0,
    };
    println!(
        "Field: constant direction (1, 0.3, 0.2) projected, 3:1. Medians of {repeats} runs, ms.\n"
    );
    println!(
        "| mesh | faces | segmentation | parameterization + splitting | cells | total | segments before / after split | splits | isotropic fallback | single-face | cells | 10^5 samples |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for name in strata_bench::SHARED_MESHES {
        let mesh = Arc::new(strata_engine::io::load(&dir.join(format!("{name}.obj")))?);
        let field = Arc::new(spec.build(&mesh)?);
        let mut stage_times: Vec<Vec<f64>> = vec![Vec::new(); 3];
        let mut sample_times = Vec::new();
        let mut last = None;
        for _ in 0..repeats {
            let pre = Preprocessed::build(mesh.clone(), field.clone(), &SurfaceOptions::default())?;
            for (k, (_, d)) in pre.stages.iter().enumerate().take(3) {
                stage_times[k].push(d.as_secs_f64() * 1e3);
            }
            let mut buf = vec![Sample::default(); 100_000];
            let t = Instant::now();
            pre.sampler.sample_into(1, &mut buf);
            sample_times.push(t.elapsed().as_secs_f64() * 1e3);
            last = Some(pre);
        }
        let pre = last.ok_or("no run")?;
        let [s, p, c] = [0, 1, 2].map(|k| median(stage_times[k].clone()));
        let r = &pre.report;
        println!(
            "| {name} | {} | {s:.0} | {p:.0} | {c:.0} | {:.0} | {} / {} | {} | {} | {} | {} | {:.1} |",
            mesh.face_count(),
            s + p + c,
            r.segments_before_split,
            r.segments,
            r.splits,
            r.isotropic_segments,
            r.single_face_segments,
            r.cells,
            median(sample_times),
        );
    }
    Ok(())
}
