//! The floor under per-frame sampling on this machine: how long it takes only to
//! write 10^6 64-byte `Sample` records into a reused buffer, with the same rayon
//! chunking as `Sampler::sample_into` and almost no work per record, beside the real
//! sampler on the bunny. As a Markdown table:
//! `cargo run --release -p strata-bench --bin sample_floor [-- repeats]`.
//!
//! `write only`: each record gets values derived from its index with a handful of
//! integer and float operations (so the stores cannot be turned into a memset).
//! `rng + write`: the same plus the counter-based random value and the stratified
//! value that the sampler draws per record. `record + write`: the sampler's own record
//! (position, normal, major axis, spacings interpolated on the face) rebuilt with
//! `Sampler::record` from the face and barycentric coordinates of a previous sampler
//! output, in that output's order: the cost of the record without the curve, as an
//! upper bound (each call also reads its 24-byte input back from memory, checks it and
//! recomputes the spacing scale, which the sampler does once per request). The
//! difference between that row and the sampler is, at least, the cost of the
//! stratified values, the curve and point location. `sites only`: the sampler writing
//! only where each sample lies (`Sampler::sample_sites_into`, 16-byte `SampleSite`s:
//! face, segment, barycentric coordinates), which times the stratified values, the
//! curve and point location without the record.

use std::time::Instant;

use rayon::prelude::*;
use strata_bench::median;
use strata_engine::sample::{Sample, SampleSite, stratified_value};
use strata_systems::config::SceneConfig;
use strata_systems::scene::Scene;

const N: usize = 1_000_000;
const CHUNK: usize = 4096;

fn time(repeats: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm-up: pages touched, pool started
    median(
        (0..repeats)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    )
}

fn trivial(i: usize, v: f64) -> Sample {
    let x = i as f32;
    Sample {
        position: [x, v as f32, -x],
        face: i as u32,
        normal: [0.0, 0.0, 1.0],
        segment: (i >> 12) as u32,
        major_axis: [1.0, 0.0, 0.0],
        index: i as u32,
        bary: [0.25, 0.5],
        spacing: [x * 1e-6, x * 2e-6],
    }
}

fn sites_size() -> usize {
    std::mem::size_of::<SampleSite>()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(21)?.max(1);
    let mut out = vec![Sample::default(); N];
    let write = time(repeats, || {
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, dst)| {
            for (j, s) in dst.iter_mut().enumerate() {
                *s = trivial(c * CHUNK + j, 0.5);
            }
        });
    });
    let rng = time(repeats, || {
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, dst)| {
            for (j, s) in dst.iter_mut().enumerate() {
                let k = (c * CHUNK + j) as u64;
                *s = trivial(k as usize, stratified_value(1, 0, k, N as u64));
            }
        });
    });
    let config = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/stanford-bunny-anisotropic.ron");
    let full = std::mem::size_of::<Sample>();
    let mut rows = vec![("write only", write, full), ("rng + write", rng, full)];
    match strata_bench::shared_mesh_dir() {
        Ok(_) => {
            let scene = Scene::build(&SceneConfig::load(&config)?)?;
            let real = time(repeats, || scene.sampler.sample_into(1, &mut out));
            let points: Vec<(u32, [f64; 3], u32)> = out
                .iter()
                .map(|s| (s.face, s.barycentric().map(f64::from), s.segment))
                .collect();
            let sampler = &scene.sampler;
            let record = time(repeats, || {
                out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, dst)| {
                    for (j, s) in dst.iter_mut().enumerate() {
                        let k = c * CHUNK + j;
                        let (face, bary, segment) = points[k];
                        *s = sampler
                            .record(face, bary, segment, k as u32, N)
                            .expect("a face of the mesh");
                    }
                });
            });
            let mut sites = vec![SampleSite::default(); N];
            let located = time(repeats, || scene.sampler.sample_sites_into(1, &mut sites));
            rows.push(("record + write, bunny 3:1", record, full));
            rows.push(("sites only, bunny 3:1", located, sites_size()));
            rows.push(("sampler, bunny 3:1", real, full));
        }
        Err(e) => eprintln!("skipping the bunny: {e}"),
    }
    println!(
        "{} threads, 10^6 records of {full} bytes ({} for sites), medians of {repeats}\n",
        rayon::current_num_threads(),
        sites_size()
    );
    println!("| path | ms | GB/s written | M records/s |");
    println!("| --- | --- | --- | --- |");
    for (name, ms, size) in rows {
        let bytes = (N * size) as f64;
        println!(
            "| {name} | {ms:.2} | {:.1} | {:.0} |",
            bytes / ms / 1e6,
            N as f64 / ms / 1e3
        );
    }
    Ok(())
}
