//! Preprocesses a curved surface and samples it: segmentation, parameterization with
//! splitting, cells, then samples of any count. Prints what each stage did.
//! `cargo run --release -p strata-engine --example surface -- [count]`
//! (uses the built-in genus-2 surface; no external file).

use std::sync::Arc;

use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::surface::{Preprocessed, SurfaceOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let count: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(100_000);
    let mesh = Arc::new(shapes::genus2(2.0, 3)?);
    let spec = FieldSpec::Constant {
        direction: [1.0, 0.3, 0.2],
        anisotropy: 3.0,
        density: 1.0,
    };
    let field = Arc::new(spec.build(&mesh)?);
    let pre = Preprocessed::build(mesh.clone(), field, &SurfaceOptions::default())?;
    let index_sum: f64 = pre.segmentation.singularities.iter().map(|s| s.index).sum();
    println!(
        "{} faces (Euler characteristic {}): {} singularities, index sum {index_sum}",
        mesh.face_count(),
        mesh.euler_characteristic(),
        pre.segmentation.singularities.len()
    );
    println!("{:?}", pre.report);
    for (stage, took) in &pre.stages {
        println!("{stage}: {:.1} ms", took.as_secs_f64() * 1e3);
    }
    let samples = pre.sampler.sample(count, 1);
    let per_segment = samples.iter().filter(|s| s.segment == 0).count();
    println!(
        "{} samples; segment 0 holds {per_segment}; chains used: {}",
        samples.len(),
        pre.sampler.uses_chains(count)
    );
    Ok(())
}
