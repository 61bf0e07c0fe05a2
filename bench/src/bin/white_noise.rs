//! Per core against a white-noise sampler: 10^6 samples on the Stanford bunny by Bevy's
//! `UniformMeshSampler` (bevy_math 0.16, the last release that has it: area-weighted
//! alias table over the faces, then a uniform point in the face, positions only,
//! `StdRng` as in Bevy's own example) and by strata's preprocessed sampler on the same
//! mesh with a uniform field (`configs/stanford-bunny-isotropic.ron`), as sites
//! (`Sampler::sample_sites_into`, 16 bytes each) and as full records
//! (`Sampler::sample_into`, 64 bytes each). Everything runs in one process on a
//! one-thread rayon pool, the three paths taking turns in every round (the first path
//! of a round rotates), so that each ratio is measured on the same machine state. Run
//! it pinned to one core:
//!
//! ```text
//! cargo build --release -p strata-bench --bin white_noise
//! taskset -c 0 ./target/release/white_noise [repeats] [bevy|sites|records]
//! ```
//!
//! A path named after the repeats runs that path alone (to profile it, say under
//! `valgrind --tool=callgrind`); the ratios then compare against nothing and read 0.
//!
//! Prints a Markdown table of medians and, per strata path, the median over rounds of
//! its time over Bevy's in the same round; then an FNV-1a hash of strata's records and
//! sites (the same for the same code and seed, so two builds can be checked to draw the
//! same samples). Each path writes into a buffer allocated once.

use std::hint::black_box;
use std::time::Instant;

use bevy_math_016::Vec3;
use bevy_math_016::primitives::Triangle3d;
use bevy_math_016::sampling::UniformMeshSampler;
use rand_08::SeedableRng;
use rand_08::distributions::Distribution;
use rand_08::rngs::StdRng;
use strata_engine::sample::{Sample, SampleSite};
use strata_systems::config::SceneConfig;
use strata_systems::scene::Scene;

const N: usize = 1_000_000;
const SEED: u64 = 1;
const PATHS: [&str; 3] = [
    "Bevy UniformMeshSampler, positions",
    "strata sites",
    "strata records",
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// 64-bit FNV-1a over bytes.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The buffers the three paths write.
struct Outputs {
    points: Vec<Vec3>,
    sites: Vec<SampleSite>,
    records: Vec<Sample>,
}

/// Runs path `path` once and returns its time in milliseconds.
fn run(path: usize, bevy: &UniformMeshSampler, scene: &Scene, out: &mut Outputs) -> f64 {
    let t = Instant::now();
    match path {
        0 => {
            let rng = StdRng::seed_from_u64(SEED);
            for (o, p) in out.points.iter_mut().zip(bevy.sample_iter(rng)) {
                *o = p;
            }
            black_box(&out.points);
        }
        1 => {
            scene.sampler.sample_sites_into(SEED, &mut out.sites);
            black_box(&out.sites);
        }
        _ => {
            scene.sampler.sample_into(SEED, &mut out.records);
            black_box(&out.records);
        }
    }
    t.elapsed().as_secs_f64() * 1e3
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(11)?.max(1);
    let only = match std::env::args().nth(2).as_deref() {
        None => None,
        Some("bevy") => Some(0),
        Some("sites") => Some(1),
        Some("records") => Some(2),
        Some(other) => return Err(format!("{other}: expected bevy, sites or records").into()),
    };
    let chosen = |path: usize| only.is_none_or(|o| o == path);
    let mesh_file = strata_bench::shared_mesh_dir()?.join("stanford-bunny.obj");
    if !mesh_file.is_file() {
        return Err(format!("{}: the bunny mesh is missing", mesh_file.display()).into());
    }
    let config = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/stanford-bunny-isotropic.ron");
    let scene = Scene::build(&SceneConfig::load(&config)?)?;
    let mesh = &scene.mesh;
    let v = |p: glam::DVec3| Vec3::new(p.x as f32, p.y as f32, p.z as f32);
    let triangles = (0..mesh.face_count() as u32).map(|f| {
        let [a, b, c] = mesh.face_positions(f);
        Triangle3d::new(v(a), v(b), v(c))
    });
    let bevy = UniformMeshSampler::try_new(triangles)?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    if cores != 1 {
        eprintln!("this process may run on {cores} cores: pin it with `taskset -c 0`");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut out = Outputs {
        points: vec![Vec3::ZERO; N],
        sites: vec![SampleSite::default(); N],
        records: vec![Sample::default(); N],
    };
    let mut times = [vec![], vec![], vec![]];
    pool.install(|| {
        for path in (0..3).filter(|&p| chosen(p)) {
            run(path, &bevy, &scene, &mut out); // warm-up: pages touched
        }
        for round in 0..repeats {
            for path in (0..3).map(|k| (round + k) % 3).filter(|&p| chosen(p)) {
                times[path].push(run(path, &bevy, &scene, &mut out));
            }
        }
    });
    println!(
        "Stanford bunny ({} faces, {} segments), 10^6 samples, one rayon thread on {cores} \
         core(s), medians of {repeats} alternating rounds\n",
        mesh.face_count(),
        scene.sampler.segments().len()
    );
    println!("| path | ms | M samples/s | time / Bevy's |");
    println!("| --- | --- | --- | --- |");
    for (path, name) in PATHS.iter().enumerate().filter(|&(p, _)| chosen(p)) {
        let ms = median(times[path].clone());
        let ratio = median(
            times[path]
                .iter()
                .zip(&times[0])
                .map(|(t, b)| t / b)
                .collect(),
        );
        println!(
            "| {name} | {ms:.1} | {:.1} | {ratio:.2} |",
            N as f64 / ms / 1e3
        );
    }
    println!(
        "\nstrata's preprocessed data: {:.1} MB (`Sampler::heap_bytes`)",
        scene.sampler.heap_bytes() as f64 / 1e6
    );
    println!(
        "records {:016x}, sites {:016x} (FNV-1a, seed {SEED})",
        fnv(bytemuck::cast_slice(&out.records)),
        fnv(bytemuck::cast_slice(&out.sites))
    );
    Ok(())
}
