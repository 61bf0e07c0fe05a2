//! Fingerprints of everything strata draws, for checking that a change which should not
//! move the samples does not: one 64-bit FNV-1a hash per bundled scene, count and order,
//! and one per level-of-detail camera path of the pool's entries.
//!
//! ```text
//! cargo run --release -p strata-bench --bin fingerprint > before.txt
//! (change the code)
//! cargo run --release -p strata-bench --bin fingerprint > after.txt
//! diff before.txt after.txt
//! ```
//!
//! Scenes: every `configs/*.ron` (those on the shared meshes are skipped when the meshes
//! are absent), sampled at 1,000, 20,011 and 100,003 samples, stratified
//! (`Sampler::sample_into`) and progressive (`Sampler::progressive_into`), each with
//! the scene's seed. Level of detail: the `lod` bench's scene and camera paths (a 1%
//! count step, dolly in and out, a 1-degree orbit, each also with a point budget of
//! 10^6 shown), 30 frames each from a pool of the first 200,000 ranks; the hash covers
//! the pool's ranks and sites and the last frame's fades.
//!
//! `FINGERPRINT_SKIP_LOD=1` skips the level-of-detail part; `FINGERPRINT_ONLY=name`
//! fingerprints only the scenes whose file name contains `name`.

use std::path::Path;

use glam::{DQuat, DVec3};
use strata_bench::lod_camera::{LodCamera, lod_scene};
use strata_engine::sample::{Budget, LodPool, Sample, SampleSite, Sampler};
use strata_systems::config::SceneConfig;
use strata_systems::scene::Scene;

/// Sample counts fingerprinted per scene: small, the default scene's, and one that is
/// not a round number.
const COUNTS: [usize; 3] = [1_000, 20_011, 100_003];

/// 64-bit FNV-1a over bytes: stable across toolchains and platforms, unlike std's
/// `DefaultHasher`.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

fn scene_fingerprints(only: Option<&str>) -> Result<(), Box<dyn std::error::Error>> {
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let mut files: Vec<_> = std::fs::read_dir(&configs)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    files.retain(|p| p.extension().is_some_and(|x| x == "ron"));
    files.sort();
    for file in files {
        let name = file
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_owned();
        if only.is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let config = SceneConfig::load(&file)?;
        let scene = match Scene::build(&config) {
            Ok(scene) => scene,
            Err(e) if strata_bench::shared_mesh_dir().is_err() => {
                println!("{name}: skipped ({e})");
                continue;
            }
            Err(e) => return Err(format!("{name}: {e}").into()),
        };
        let seed = config.sampling.seed;
        for n in COUNTS {
            let mut out = vec![Sample::default(); n];
            scene.sampler.sample_into(seed, &mut out);
            let stratified = hash_samples(&out);
            scene.sampler.progressive_into(seed, 0, &mut out);
            let progressive = hash_samples(&out);
            println!("{name} n={n}: stratified {stratified:016x} progressive {progressive:016x}");
        }
    }
    Ok(())
}

fn hash_samples(samples: &[Sample]) -> u64 {
    let mut h = Fnv::new();
    h.bytes(bytemuck::cast_slice(samples));
    h.0
}

/// The pool's ranks and sites, and the fades of `view` at `base`.
fn hash_pool(
    pool: &LodPool,
    s: &Sampler,
    view: &strata_engine::sample::lod::ViewLod,
    base: f64,
) -> u64 {
    let mut h = Fnv::new();
    for r in pool.ranks() {
        h.bytes(&r.to_le_bytes());
    }
    h.bytes(bytemuck::cast_slice::<SampleSite, u8>(pool.sites()));
    let mut fades = vec![0.0f32; pool.len()];
    pool.fades_into(s, view, base, &mut fades);
    for f in fades {
        h.bytes(&f.to_bits().to_le_bytes());
    }
    h.0
}

fn lod_fingerprints() -> Result<(), Box<dyn std::error::Error>> {
    const SEED: u64 = 7;
    const FRAMES: i32 = 30;
    const BASE: f64 = 200_000.0;
    const SHOWN: u32 = 1_000_000;
    let (file, scene) = lod_scene(SEED)?;
    let s = &scene.sampler;
    let camera = LodCamera::around(scene.mesh.positions());
    let prefix = LodPool::new(s, SEED, BASE as u32, 8_000_000);
    type PathFn<'a> = Box<dyn Fn(i32) -> (strata_engine::sample::lod::ViewLod, f64) + 'a>;
    let dolly = |factor: f64| -> PathFn { Box::new(move |t| (camera.dolly(factor, t), BASE)) };
    let orbit = || -> PathFn {
        Box::new(move |t| {
            let turn = DQuat::from_rotation_y(f64::from(t).to_radians());
            let eye: DVec3 = camera.centre + turn * (camera.start - camera.centre);
            (camera.view(eye), BASE)
        })
    };
    let paths: [(&str, PathFn, bool); 7] = [
        (
            "count +1%",
            Box::new(|t| (camera.view(camera.start), BASE * 1.01f64.powi(t))),
            false,
        ),
        ("dolly in 1%", dolly(0.99), false),
        ("dolly out 1%", dolly(1.01), false),
        ("orbit 1 degree", orbit(), false),
        ("dolly in 1%, shown held", dolly(0.99), true),
        ("dolly out 1%, shown held", dolly(1.01), true),
        ("orbit 1 degree, shown held", orbit(), true),
    ];
    for (path, frame, held) in paths {
        let mut pool = prefix.clone();
        let budget = held.then_some(SHOWN);
        let mut last = None;
        for t in 0..FRAMES {
            let (v, b) = frame(t);
            let b = pool.update(s, &v, Budget::new(b, budget))?.base;
            last = Some((v, b));
        }
        let (v, b) = last.ok_or("no frames")?;
        println!(
            "lod `{file}` {path}: {} entries, base {b:.6}, {:016x}",
            pool.len(),
            hash_pool(&pool, s, &v, b)
        );
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let only = std::env::var("FINGERPRINT_ONLY").ok();
    scene_fingerprints(only.as_deref())?;
    if std::env::var_os("FINGERPRINT_SKIP_LOD").is_none() && only.is_none() {
        lod_fingerprints()?;
    }
    Ok(())
}
