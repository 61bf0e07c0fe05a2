//! Times the first segmentation step (seeds and random walk, paper section 4) on the
//! Stanford bunny with a constant direction projected into the tangent planes:
//! `cargo run --release -p strata-engine --example segment_walk -- [mesh] [beta] [repeats]`.
//!
//! Loads `../shared/meshes/stanford-bunny.obj` (relative to the working directory) if no
//! mesh is given and it exists, else a geodesic sphere of similar size. Prints the face
//! and seed counts and the time of each stage: face frames, weights, seeds, and the
//! walk split into assembly + factorization and the solves (best of `repeats`).

use std::path::Path;
use std::time::Instant;

use strata_engine::field::FieldSpec;
use strata_engine::io;
use strata_engine::mesh::shapes;
use strata_engine::segment::{WalkSystem, connected_parts, face_frames, place_seeds, walk_weights};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "../shared/meshes/stanford-bunny.obj".to_string());
    let beta: f64 = args
        .next()
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(std::f64::consts::FRAC_PI_4);
    let repeats: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(3);
    let mesh = if Path::new(&path).exists() {
        println!("mesh {path}");
        io::load(Path::new(&path))?
    } else {
        println!("{path} not found: geodesic sphere instead");
        shapes::sphere(1.0, 59)?
    };
    let field = FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 2.0,
        density: 1.0,
    }
    .build(&mesh)?;
    let blocked = vec![false; mesh.edge_count()];
    let mask = vec![true; mesh.face_count()];
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;

    let mut best = [f64::INFINITY; 5];
    let mut summary = String::new();
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let faces = face_frames(&mesh, &field);
        let t_frames = ms(t);
        let t = Instant::now();
        let weights = walk_weights(&mesh, &faces, 1.0, &blocked);
        let t_weights = ms(t);
        let t = Instant::now();
        let seeds = place_seeds(&mesh, &faces, &weights, &mask, beta, 0);
        let t_seeds = ms(t);
        let t = Instant::now();
        let system = WalkSystem::build(&mesh, &weights, &mask, &seeds)?;
        let t_factor = ms(t);
        let t = Instant::now();
        let labels = system.labels();
        let t_solve = ms(t);
        for (b, v) in best
            .iter_mut()
            .zip([t_frames, t_weights, t_seeds, t_factor, t_solve])
        {
            *b = b.min(v);
        }
        let parts = connected_parts(&mesh, &labels, &blocked);
        let part_count = parts.iter().max().map_or(0, |&p| p + 1);
        summary = format!(
            "{} faces, {} seeds, {} unknowns, {part_count} connected parts",
            mesh.face_count(),
            seeds.len(),
            system.unknown_count()
        );
    }
    println!("{summary}");
    println!(
        "best of {repeats} (ms): frames {:.1}, weights {:.1}, seeds {:.1}, \
         walk factorization {:.1}, walk solves {:.1} (total {:.1})",
        best[0],
        best[1],
        best[2],
        best[3],
        best[4],
        best.iter().sum::<f64>()
    );
    Ok(())
}
