//! The `lod` bench: a camera moves along fixed paths around the bunny (3:1
//! field, seed 3; the default scene when the shared meshes are absent) and a
//! progressive pool ([`LodPool`]) serves the visible set of every frame:
//! `cargo run --release -p strata-bench --bin lod [-- frames]`.
//!
//! The camera starts 2.5 bounding radii from the mesh's centre (45-degree vertical
//! field of view, 1280 x 720, back faces culled, multiplier clamped at 4). The
//! reference area is the projected area per unit area of a surface facing the camera
//! at the centre, and the base count is set once so that the first frame shows about
//! 10^6 samples. The pool holds the ranks `0..base` and grows by rank enumeration per
//! segment. Paths, `frames` timed steps each (default 20), after 30 untimed steps along
//! the same path that end at that first frame (the camera was already moving):
//!
//! - `count`: base count times 1.01 per frame, camera still;
//! - `dolly in` / `dolly out`: the distance to the centre times 0.99 / 1.01 per frame;
//! - `orbit`: 1 degree per frame about the vertical axis through the centre;
//! - `dolly in` / `dolly out` / `orbit`, `shown held`: the same paths with the samples shown
//!   held at 10^6, as a renderer with a point budget holds them: every frame's base
//!   count is the engine's estimate of the one that shows 10^6 samples under the
//!   frame's view ([`Budget::Shown`] in [`LodPool::update`]), computed within the timed
//!   update.
//!
//! Per path: the visible samples of the first frame and their range over the timed
//! frames, in millions; the kept share (the samples of
//! frame t visible in frame t+1 with the same rank and site, over those of frame t,
//! worst and mean over the steps); the same share among the samples that stay in view
//! (multiplier above 0 in frame t+1), worst and mean, and the mean share of them that
//! the change of the multipliers and base count alone lets stay (expected if the ranks
//! below a site's threshold were spread evenly: what any visible set following the
//! issue's definition keeps, the pool aside); whether a kept sample ever moved; the CPU time
//! of `LodPool::update` per frame (median and mean: the whole per-frame CPU work of a
//! renderer that culls on the GPU, besides a uniform write); the samples newly visible
//! per frame (visible in frame t+1 and not kept from frame t), those of them beyond
//! the prefix (ranks from `base` on shown for the first time: what any update must
//! place, unless it placed them ahead), the pool's new entries per frame, and the
//! bytes a GPU copy of the pool receives per frame (20 per new entry: site and rank).
//! The visible sets are computed on the CPU (`LodPool::fades_into`), outside the
//! timing.
//!
//! `LOD_DRAW_AHEAD=a` sets the pool's draw-ahead fraction (default [`DRAW_AHEAD`]),
//! to compare with and without it on one binary. The frame loop runs on a worker of
//! rayon's global pool (`use_current_thread`), as in a renderer that drives rayon
//! from its frame thread; `LOD_OUTSIDE_POOL=1` calls the update from outside the pool
//! (bench/README.md: on a 2-core machine it then often waits for a worker to wake).
//!
//! The point budget's estimate is timed alone (`ShownEstimate::mean_multiplier`, per
//! view of the dolly in, between full passes over the pool that leave caches cold).
//!
//! For comparison, `stratified` redraws `N` and `1.01 N` samples in today's stratified
//! order and counts the samples that kept their place, and times the sampler's
//! cheapest placement (the stratified order's `N = 10^6` sites, consecutive values
//! along the curves) per site: newly visible samples times that is the floor of an
//! update.

use std::time::Instant;

use glam::DVec3;
use strata_bench::lod_camera::{LodCamera, lod_scene};
use strata_bench::median;
use strata_engine::sample::lod::{Budget, FrameUpdate, LodError, ViewLod};
use strata_engine::sample::{DRAW_AHEAD, LodPool, PoolChange, SampleSite, Sampler};

const SEED: u64 = 3;
/// The samples the first frame shows, and the budget the `shown held` paths keep.
const SHOWN: f64 = 1e6;
/// Untimed frames along each path before the timed ones: the camera was already
/// moving, so the pool's draw-ahead is in its steady state (bins refilled at spread
/// phases) rather than all filled together for a still first frame.
const WARM_UP: i32 = 30;

/// The visible samples of the pool, as (rank, site) sorted by rank.
fn visible(
    pool: &LodPool,
    s: &Sampler,
    v: &ViewLod,
    base: f64,
    fades: &mut Vec<f32>,
) -> Vec<(u32, SampleSite)> {
    fades.resize(pool.len(), 0.0);
    pool.fades_into(s, v, base, fades);
    let mut shown: Vec<(u32, SampleSite)> = (0..pool.len())
        .filter(|&i| fades[i] > 0.0)
        .map(|i| (pool.ranks()[i], pool.sites()[i]))
        .collect();
    shown.sort_unstable_by_key(|e| e.0);
    shown
}

/// Samples of `a` also in `b` with the same site, and whether any rank of both moved.
fn kept(a: &[(u32, SampleSite)], b: &[(u32, SampleSite)]) -> (usize, bool) {
    let (mut i, mut j, mut same, mut moved) = (0, 0, 0, false);
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                if a[i].1 == b[j].1 {
                    same += 1;
                } else {
                    moved = true;
                }
                i += 1;
                j += 1;
            }
        }
    }
    (same, moved)
}

/// Ranks of `b` at or above `from` that `a` lacks: samples newly shown that no pool
/// holding ranks `0..from` had placed before they were first asked for.
fn new_from(a: &[(u32, SampleSite)], b: &[(u32, SampleSite)], from: u32) -> usize {
    let mut i = a.partition_point(|e| e.0 < from);
    let mut count = 0;
    for e in &b[b.partition_point(|e| e.0 < from)..] {
        while i < a.len() && a[i].0 < e.0 {
            i += 1;
        }
        if i == a.len() || a[i].0 != e.0 {
            count += 1;
        }
    }
    count
}

/// What the view's change does to the samples `a` visible in frame t (view `v0`, base
/// `b0`) by frame t+1 (`v1`, `b1`): how many leave the view (multiplier 0 under `v1`),
/// and how many of the others are expected to leave the visible set through their
/// threshold alone. A sample of rank `k` is visible while `k < b x multiplier`; if
/// the ranks below a site's threshold were spread evenly, the share of them past the
/// new threshold would be `1 - (b1 m1) / (b0 m0)` where the threshold falls. That sum
/// depends on the multipliers and base counts only, not on the pool, and is what any
/// visible set following the definition must lose besides the samples leaving
/// the view.
fn leaving(
    a: &[(u32, SampleSite)],
    s: &Sampler,
    (v0, b0): (&ViewLod, f64),
    (v1, b1): (&ViewLod, f64),
) -> (usize, f64) {
    let (mut gone, mut forced) = (0, 0.0);
    for (k, site) in a {
        let r = s
            .record(site.face, site.barycentric().map(f64::from), 0, *k, 1)
            .expect("a pool site is on the mesh");
        let p = DVec3::from(r.position.map(f64::from));
        let n = DVec3::from(r.normal.map(f64::from));
        let m1 = v1.multiplier(p, n);
        if m1 == 0.0 {
            gone += 1;
        } else {
            let before = b0 * v0.multiplier(p, n);
            forced += (1.0 - b1 * m1 / before).clamp(0.0, 1.0);
        }
    }
    (gone, forced)
}

/// A camera path: frame `t`'s view and base count.
type Path<'a> = Box<dyn Fn(i32) -> (ViewLod, f64) + 'a>;

/// The base count under which `first` shows about [`SHOWN`] samples, from a small
/// pool's: visible samples grow linearly with the base count.
fn calibrate_base(s: &Sampler, first: &ViewLod, fades: &mut Vec<f32>) -> Result<f64, LodError> {
    let probe_base = 100_000.0;
    let mut probe = LodPool::new(s, SEED, probe_base as u32, usize::MAX / 4);
    probe.update(s, first, Budget::Base(probe_base))?;
    let shown = visible(&probe, s, first, probe_base, fades).len() as f64;
    Ok((probe_base * SHOWN / shown).round())
}

/// Runs `frame` along a path on `pool`: [`WARM_UP`] untimed frames, then `frames`
/// timed ones, under a point budget of `budget` samples or the path's base counts;
/// prints the path's row of the table.
fn run_path(
    (path, frame, budget): (&str, &Path, Option<u32>),
    mut pool: LodPool,
    s: &Sampler,
    frames: usize,
    fades: &mut Vec<f32>,
) -> Result<(), LodError> {
    // A held path's base count: the engine's point budget for the frame's view.
    let update =
        |pool: &mut LodPool, v: &ViewLod, b: f64| pool.update(s, v, Budget::new(b, budget));
    // The camera was already moving: untimed frames -WARM_UP..=0 along the path.
    let (mut before, mut last) = (vec![], frame(0));
    for t in -WARM_UP..=0 {
        let (v, b) = frame(t);
        let b = update(&mut pool, &v, b)?.base;
        if t == 0 {
            before = visible(&pool, s, &v, b, fades);
            last = (v, b);
        }
    }
    let shown = before.len();
    let (mut shares, mut in_view, mut times, mut bytes) = (vec![], vec![], vec![], vec![]);
    let (mut fresh, mut beyond, mut counts) = (vec![], vec![], vec![]);
    // Per step, the expected share kept among the samples staying in view, from
    // the multipliers' change alone (`leaving`).
    let mut allowed = vec![];
    let mut moved = false;
    for t in 1..=frames as i32 {
        let (v, b) = frame(t);
        let clock = Instant::now();
        let FrameUpdate { change, base: b } = update(&mut pool, &v, b)?;
        times.push(clock.elapsed().as_secs_f64() * 1e3);
        bytes.push(match change {
            PoolChange::Unchanged => 0.0,
            PoolChange::Appended(r) => r.len() as f64 * 20.0,
            PoolChange::Rebuilt => (pool.len() - pool.prefix() as usize) as f64 * 20.0,
        });
        let after = visible(&pool, s, &v, b, fades);
        let (same, m) = kept(&before, &after);
        moved |= m;
        fresh.push((after.len() - same) as f64);
        beyond.push(new_from(&before, &after, pool.prefix()) as f64);
        counts.push(after.len() as f64);
        let (gone, forced) = leaving(&before, s, (&last.0, last.1), (&v, b));
        let staying = (before.len() - gone).max(1) as f64;
        shares.push(same as f64 / before.len() as f64);
        in_view.push(same as f64 / staying);
        allowed.push(1.0 - forced / staying);
        (before, last) = (after, (v, b));
    }
    let worst = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let range = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        format!("{:.3}-{:.3}", lo / 1e6, hi / 1e6)
    };
    println!(
        "| {path} | {shown} | {} | {:.2}% | {:.2}% | {:.2}% | {:.2}% | {:.2}% | {} | {:.3} | {:.3} | {:.1}k | {:.1}k | {:.1}k | {:.1} | {} |",
        range(&counts),
        100.0 * worst(&shares),
        100.0 * mean(&shares),
        100.0 * worst(&in_view),
        100.0 * mean(&in_view),
        100.0 * mean(&allowed),
        if moved { "yes" } else { "no" },
        median(times.clone()),
        mean(&times),
        mean(&fresh) / 1e3,
        mean(&beyond) / 1e3,
        mean(&bytes) / 20e3,
        mean(&bytes) / 1e3,
        pool.len(),
    );
    Ok(())
}

/// Today's stratified order, `N` to `N + 1%`: the samples that kept their place, and
/// the sampler's cheapest placement per site, for the floor of an update.
fn stratified_comparison(s: &Sampler) {
    let n = 1_000_000usize;
    let (mut a, mut b) = (
        vec![SampleSite::default(); n],
        vec![SampleSite::default(); n + n / 100],
    );
    // The stratified order places consecutive values along the curves (warm cells).
    let mut placing = vec![];
    for _ in 0..5 {
        let clock = Instant::now();
        s.sample_sites_into(SEED, &mut a);
        placing.push(clock.elapsed().as_secs_f64() * 1e9 / n as f64);
    }
    s.sample_sites_into(SEED, &mut b);
    let key = |x: &SampleSite| (x.face, x.segment, x.bary[0].to_bits(), x.bary[1].to_bits());
    let mut set: Vec<_> = b.iter().map(key).collect();
    set.sort_unstable();
    let same = a
        .iter()
        .filter(|x| set.binary_search(&key(x)).is_ok())
        .count();
    println!(
        "\nStratified order, {n} to {} samples: {:.1}% kept their place. Placing its {n} sites takes {:.1} ns of wall time per site (median of 5, {} threads).",
        n + n / 100,
        100.0 * same as f64 / n as f64,
        median(placing),
        rayon::current_num_threads(),
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames = strata_bench::repeats_arg(20)?.max(1);
    // The frame loop runs on a worker of rayon's pool, as a renderer driving rayon
    // from its frame thread would: an update's parallel work then starts on the
    // calling thread, and the other worker joins when it wakes. `LOD_OUTSIDE_POOL=1`
    // calls from outside the pool instead (see bench/README.md for what that costs).
    let inside = std::env::var_os("LOD_OUTSIDE_POOL").is_none();
    if inside {
        rayon::ThreadPoolBuilder::new()
            .use_current_thread()
            .build_global()?;
    }
    let (file, scene) = lod_scene(SEED)?;
    let s = &scene.sampler;
    let camera = LodCamera::around(scene.mesh.positions());
    let LodCamera {
        centre,
        start,
        reference,
    } = camera;
    let view = |eye: DVec3| camera.view(eye);
    let first = view(start);
    let mut fades = Vec::new();
    let base = calibrate_base(s, &first, &mut fades)?;
    println!(
        "scene `{file}`: {} faces, {} segments; base count {base:.0}, reference {reference:.1} px^2 per unit area, {frames} frames per path.\n",
        scene.mesh.face_count(),
        s.segments().len(),
    );

    let ahead = match std::env::var("LOD_DRAW_AHEAD") {
        Ok(a) => a.parse()?,
        Err(_) => DRAW_AHEAD,
    };
    let t = Instant::now();
    let budget = 8_000_000;
    let prefix = LodPool::new(s, SEED, base as u32, budget).with_draw_ahead(ahead);
    println!(
        "Pool of ranks 0..{base:.0}: built in {:.0} ms ({:.1} MB of sites and ranks); draw-ahead {ahead}.\n",
        t.elapsed().as_secs_f64() * 1e3,
        prefix.len() as f64 * 20.0 / 1e6
    );
    println!(
        "| path | visible (first frame) | visible 10^6, range | kept, worst | kept, mean | kept among those in view, worst | the same, mean | expected from the multipliers alone, mean | kept moved | update ms, median | update ms, mean | newly visible per frame, mean | of them beyond the prefix | entries per frame, mean | upload KB per frame, mean | pool entries at end |"
    );
    println!(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    let dolly = |factor: f64| -> Path { Box::new(move |t| (camera.dolly(factor, t), base)) };
    let orbit = || -> Path {
        Box::new(move |t| {
            let turn = glam::DQuat::from_rotation_y(f64::from(t).to_radians());
            (view(centre + turn * (start - centre)), base)
        })
    };
    // The `shown held` paths hold the samples shown at the budget, as a renderer with
    // a point budget does: each frame's base count is the engine's estimate of the one
    // that shows `SHOWN` samples under its view (`Budget::Shown`), timed with the
    // update.
    let paths: [(&str, Path, bool); 7] = [
        (
            "count +1%",
            Box::new(|t| (first, base * 1.01f64.powi(t))),
            false,
        ),
        ("dolly in 1%", dolly(0.99), false),
        ("dolly out 1%", dolly(1.01), false),
        ("orbit 1 degree", orbit(), false),
        ("dolly in 1%, shown held", dolly(0.99), true),
        ("dolly out 1%, shown held", dolly(1.01), true),
        ("orbit 1 degree, shown held", orbit(), true),
    ];
    for (path, frame, held) in &paths {
        let budget = held.then_some(SHOWN as u32);
        run_path((path, frame, budget), prefix.clone(), s, frames, &mut fades)?;
    }

    // The point budget's estimate alone, along the dolly in (cold caches between
    // calls, as between frames: the visible sets of a path are computed in between).
    let mut estimates = vec![];
    for t in 1..=frames as i32 {
        let v = camera.dolly(0.99, t);
        std::hint::black_box(visible(&prefix, s, &first, base, &mut fades).len());
        let clock = Instant::now();
        std::hint::black_box(prefix.shown_estimate().mean_multiplier(&v));
        estimates.push(clock.elapsed().as_secs_f64() * 1e6);
    }
    println!(
        "\nPoint budget: the mean multiplier of a new view (`ShownEstimate::mean_multiplier`, {} probes) takes {:.0} us, median of {frames}.",
        strata_engine::sample::lod::PROBES,
        median(estimates),
    );
    stratified_comparison(s);
    Ok(())
}
