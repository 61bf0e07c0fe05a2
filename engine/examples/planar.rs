//! Samples a planar domain with a 4:1 anisotropic field and prints statistics:
//! `cargo run --release -p strata-engine --example planar -- [count] [repeats]`.

use std::sync::Arc;
use std::time::Instant;

use strata_engine::curve::CurveOptions;
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::planar;
use strata_engine::sample::Sample;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let count: usize = args
        .next()
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(100_000);
    let repeats: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(5);
    let mesh = Arc::new(shapes::plane(1.0, 64)?);
    let spec = FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 4.0,
        density: 1.0,
    };
    let field = Arc::new(spec.build(&mesh)?);
    let t = Instant::now();
    let (sampler, map) = planar::sampler(mesh.clone(), field, &CurveOptions::default())?;
    let cells: usize = sampler
        .segments()
        .iter()
        .map(|s| s.curve.cell_count())
        .sum();
    println!(
        "{} faces, {cells} cells, {} KiB, built in {:.1} ms; anisotropy {:.3}",
        mesh.face_count(),
        sampler.heap_bytes() / 1024,
        t.elapsed().as_secs_f64() * 1e3,
        map.reference.anisotropy()
    );
    let mut buf = vec![Sample::default(); count];
    let mut times = Vec::new();
    for seed in 0..repeats as u64 {
        let t = Instant::now();
        sampler.sample_into(seed, &mut buf);
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    println!(
        "{count} samples: median {:.3} ms over {repeats} runs ({:.1} M samples/s)",
        median * 1e3,
        count as f64 / median / 1e6
    );
    Ok(())
}
