//! The multilevel random walk against the exact one (`segment::multilevel`):
//! `cargo run --release -p strata-bench --bin walk_levels [-- repeats [levels]]`.
//!
//! On the shared bunny and the bunny Loop-subdivided, `levels` meshes in all (default
//! 3: 69k, 278k and 1.1M faces, the larger two made in code), for the fields of
//! `stanford-bunny-anisotropic.ron` (a constant direction projected, 3:1) and
//! `stanford-bunny-smooth.ron` (designed, curvature-aligned): the first random walk of
//! the segmentation (seeds of `beta = pi/4` over the whole mesh),
//! solved by [`random_walk`] (multilevel from `MULTILEVEL_FACES` faces) and by
//! [`WalkSystem`] (always exact). Per walk: seconds (median of `repeats`, default 1),
//! the mean turn between a face's major direction and its seed's (radians; lower
//! follows the field better), the total weight of the edges between labels (lower:
//! boundaries on field turns), the labels' connected parts, and the share of faces
//! with the same label in both.

use std::sync::Arc;
use std::time::Instant;

use strata_bench::median;
use strata_engine::mesh::{NONE, TriMesh, loop_subdivide};
use strata_engine::segment::{
    FaceField, WalkSystem, connected_parts, face_frames, place_seeds, random_walk, walk_weights,
};

const SCENES: [(&str, &str); 2] = [
    ("constant 3:1", "stanford-bunny-anisotropic.ron"),
    ("smooth curvature-aligned 3:1", "stanford-bunny-smooth.ron"),
];

/// Mean line angle between each face's major direction and its label's seed's.
fn mean_turn(frames: &FaceField, labels: &[u32], seeds: &[u32]) -> f64 {
    let total: f64 = labels
        .iter()
        .enumerate()
        .map(|(f, &k)| {
            let seed = seeds[k as usize] as usize;
            frames.major[f]
                .dot(frames.major[seed])
                .abs()
                .min(1.0)
                .acos()
        })
        .sum();
    total / labels.len() as f64
}

/// Total weight of the edges whose two faces have different labels.
fn boundary_weight(mesh: &TriMesh, weights: &[f64], labels: &[u32]) -> f64 {
    mesh.edge_faces()
        .iter()
        .zip(weights)
        .filter(|([a, b], _)| {
            *a != NONE && *b != NONE && labels[*a as usize] != labels[*b as usize]
        })
        .map(|(_, w)| w)
        .sum()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(1)?;
    let levels = strata_bench::levels_arg(3)?;
    let scenes = strata_bench::bundled_scenes(&SCENES)?;
    let mut mesh = Arc::new(strata_systems::scene::load_mesh(&scenes[0].1)?);
    println!(
        "| field | faces | seeds | walk | time (s) | mean turn to seed (rad) | boundary weight | connected parts | same label |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for level in 0..levels {
        if level > 0 {
            mesh = Arc::new(loop_subdivide(&mesh)?);
        }
        for (name, config) in &scenes {
            let options = config.surface_options().segment;
            let field = config.field.build(&mesh)?;
            let frames = face_frames(&mesh, &field);
            let open = vec![false; mesh.edge_count()];
            let weights = walk_weights(&mesh, &frames, options.sigma, &open);
            let mask = vec![true; mesh.face_count()];
            let seeds = place_seeds(&mesh, &frames, &weights, &mask, options.beta, options.seed);
            let mut results = Vec::new();
            for exact in [false, true] {
                let mut times = Vec::new();
                let mut labels = Vec::new();
                for _ in 0..repeats {
                    let t = Instant::now();
                    labels = if exact {
                        WalkSystem::build(&mesh, &weights, &mask, &seeds)?.labels()
                    } else {
                        random_walk(&mesh, &weights, &mask, &seeds)?
                    };
                    times.push(t.elapsed().as_secs_f64());
                }
                results.push((exact, median(times), labels));
            }
            let same = results[0]
                .2
                .iter()
                .zip(&results[1].2)
                .filter(|(a, b)| a == b)
                .count() as f64
                / mesh.face_count() as f64;
            for (exact, time, labels) in &results {
                let parts = connected_parts(&mesh, labels, &open);
                println!(
                    "| {name} | {} | {} | {} | {time:.2} | {:.4} | {:.2} | {} | {:.1}% |",
                    mesh.face_count(),
                    seeds.len(),
                    if *exact { "exact" } else { "multilevel" },
                    mean_turn(&frames, labels, &seeds),
                    boundary_weight(&mesh, &weights, labels),
                    parts.iter().max().map_or(0, |&p| p + 1),
                    100.0 * same,
                );
            }
        }
    }
    Ok(())
}
