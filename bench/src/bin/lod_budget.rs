//! The point budget on close views: a camera moves from 2 bounding radii
//! above the bunny's surface down to 0.01, 3% nearer per frame, looking at the surface
//! point it approaches, with a budget of `S` samples shown (default 10^5):
//! `cargo run --release -p strata-bench --bin lod_budget [-- S]`.
//!
//! The camera is the `lod` bench's (1280 x 720, 45 degrees, back faces culled,
//! multiplier clamped at 4) on the bunny (3:1 field, seed 3). Per frame, two base
//! counts: the probes' alone (`ShownEstimate::mean_multiplier`, the first 4096 ranks)
//! and the engine's (`LodPool::base_for_shown`, refined in view); for each, the samples
//! a pool then shows (`LodPool::fades_into`, exact) over the budget, and the ratio of
//! the base count to the previous frame's (a jump pops samples everywhere in view).
//! The engine's estimate is timed on each new view (its bounds included, which the
//! frame's update reuses; the sites the last view's refinement evaluated are kept, as a
//! renderer's estimator keeps them), the frame thread in rayon's pool as in the `lod`
//! bench. `LOD_BUDGET_COLD=1` times every view's estimate on a copy of an estimator
//! that has seen no view (each placing every site it evaluates). For the frames closer
//! than 0.1 radius the summary also gives the entries the pool drew per frame and the
//! update's time per entry drawn.

use std::time::Instant;

use glam::DVec3;
use strata_bench::lod_camera::{LodCamera, lod_scene};
use strata_engine::mesh::TriMesh;
use strata_engine::sample::lod::{Budget, LodError, MeanMultiplier, ViewLod};
use strata_engine::sample::{LodPool, Sampler};

const SEED: u64 = 3;

/// The samples the pool shows under `v` with base `base` (after drawing them), and the
/// time of the update that drew them, in ms.
fn shown(
    pool: &mut LodPool,
    s: &Sampler,
    v: &ViewLod,
    base: f64,
    fades: &mut Vec<f32>,
) -> Result<(f64, f64), LodError> {
    let t = Instant::now();
    pool.update(s, v, Budget::Base(base))?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    fades.resize(pool.len(), 0.0);
    pool.fades_into(s, v, base, fades);
    Ok((fades.iter().filter(|&&f| f > 0.0).count() as f64, ms))
}

/// The view from `distance` along `normal` above `target`, looking at it, with the
/// `lod` bench's camera and near and far planes scaled to the mesh's `radius`.
fn close_view(
    camera: &LodCamera,
    (target, normal): (DVec3, DVec3),
    distance: f64,
    radius: f64,
) -> ViewLod {
    let eye = target + normal * distance;
    let proj = glam::dcamera::rh::proj::directx::perspective(
        std::f64::consts::FRAC_PI_4,
        1280.0 / 720.0,
        1e-4 * radius,
        100.0 * radius,
    );
    let look = glam::dcamera::rh::view::look_at_mat4(eye, target, DVec3::Y);
    ViewLod {
        clip_from_world: proj * look,
        ..camera.view(eye)
    }
}

/// The engine's estimate of `v` and its time in ms: on `pool`, or with `cold` on a
/// copy of `empty` (an estimator that has seen no view), checked against `pool`'s.
fn timed_estimate(
    pool: &mut LodPool,
    empty: &LodPool,
    s: &Sampler,
    v: &ViewLod,
    cold: bool,
) -> Result<(MeanMultiplier, f64), LodError> {
    if cold {
        let mut fresh = empty.clone();
        let t = Instant::now();
        let estimate = fresh.mean_multiplier(s, v)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        // The pool's own estimate, untimed: the same numbers.
        assert_eq!(pool.mean_multiplier(s, v)?.mean, estimate.mean);
        Ok((estimate, ms))
    } else {
        let t = Instant::now();
        let estimate = pool.mean_multiplier(s, v)?;
        Ok((estimate, t.elapsed().as_secs_f64() * 1e3))
    }
}

/// The run's summary: the worst errors and base steps, and the times.
#[derive(Default)]
struct Summary {
    /// Frames run.
    frames: usize,
    /// Shown / budget, largest error: the engine's, the probes' alone.
    worst: f64,
    worst_alone: f64,
    /// Largest base step between frames: the engine's, the probes' alone.
    step: f64,
    step_alone: f64,
    /// Estimate and update times, ms; update times closer than 0.1 radius.
    times: Vec<f64>,
    updates: Vec<f64>,
    close: Vec<f64>,
    /// Entries the pool drew in the frames closer than 0.1 radius.
    close_drawn: usize,
}

impl Summary {
    /// Prints the summary line; `entries`: the pool's at the end.
    fn print(mut self, entries: usize) {
        let (step, step_alone, frame) = (self.step, self.step_alone, self.frames);
        let (times, updates, close) = (&mut self.times, &mut self.updates, &mut self.close);
        times.sort_by(f64::total_cmp);
        updates.sort_by(f64::total_cmp);
        close.sort_by(f64::total_cmp);
        println!(
            "\n{frame} frames. Shown / budget, worst: probes alone {:.1}% off, refined {:.1}% off. Largest base step between frames (a camera 3% nearer moves it by about 1.06): probes alone {step_alone:.3}, refined {step:.3}. Estimate ms: median {:.2}, 90th percentile {:.2}, largest {:.2}; the frame's update after it: median {:.2}, 90th percentile {:.2}; closer than 0.1 radius ({} frames, the pool growing most): median {:.2}, 90th percentile {:.2}, {:.0} entries drawn per frame, {:.0} ns of update per entry drawn. Entries held at the end: {}.",
            100.0 * self.worst_alone,
            100.0 * self.worst,
            times[times.len() / 2],
            times[times.len() * 9 / 10],
            times[times.len() - 1],
            updates[updates.len() / 2],
            updates[updates.len() * 9 / 10],
            close.len(),
            close[close.len() / 2],
            close[close.len() * 9 / 10],
            self.close_drawn as f64 / close.len() as f64,
            close.iter().sum::<f64>() * 1e6 / self.close_drawn as f64,
            entries,
        );
    }
}

/// The vertex nearest the `lod` bench's first eye, and its normal: the surface point
/// the camera approaches.
fn approached(mesh: &TriMesh, camera: &LodCamera) -> Option<(DVec3, DVec3)> {
    let (vertex, &target) = mesh.positions().iter().enumerate().min_by(|a, b| {
        a.1.distance(camera.start)
            .total_cmp(&b.1.distance(camera.start))
    })?;
    Some((target, mesh.vertex_normals()[vertex]))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let budget = strata_bench::repeats_arg(100_000)? as f64;
    let cold = std::env::var_os("LOD_BUDGET_COLD").is_some();
    rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global()?;
    let (file, scene) = lod_scene(SEED)?;
    let s = &scene.sampler;
    let mesh = &scene.mesh;
    let camera = LodCamera::around(mesh.positions());
    let radius = (camera.start - camera.centre).length() / 2.5;
    let (target, normal) = approached(mesh, &camera).ok_or("an empty mesh")?;
    println!(
        "scene `{file}`: {} faces, budget {budget} samples shown, the camera 3% nearer per frame.\n",
        mesh.face_count()
    );
    println!(
        "| distance / radius | probes in view | probes alone: shown / budget | ranks averaged | of them in view | ranks evaluated | of them placed | estimate ms | update ms | entries the view needs | pool entries | bins | shown / budget | base step, probes alone | base step |"
    );
    println!(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    let mut pool = LodPool::new(s, SEED, 0, usize::MAX / 4);
    let mut alone = pool.clone();
    // An empty pool drawing no more than each view needs.
    let empty = pool.clone().with_draw_ahead(0.0);
    let mut fades = Vec::new();
    let (mut last, mut last_alone) = (None::<f64>, None::<f64>);
    let mut sum = Summary {
        step: 1.0,
        step_alone: 1.0,
        ..Summary::default()
    };
    let mut distance = 2.0 * radius;
    while distance > 0.01 * radius {
        let v = close_view(&camera, (target, normal), distance, radius);
        let probed = pool.shown_estimate().probe(&v);
        let base_alone = (probed.mean > 0.0).then(|| (budget / probed.mean).min(4_294_967_296.0));
        let (estimate, ms) = timed_estimate(&mut pool, &empty, s, &v, cold)?;
        sum.times.push(ms);
        let base = pool
            .base_for_shown(s, &v, budget)?
            .ok_or("nothing in view")?;
        let held = pool.len();
        let (count, update) = shown(&mut pool, s, &v, base, &mut fades)?;
        let ratio = count / budget;
        sum.updates.push(update);
        if distance < 0.1 * radius {
            sum.close.push(update);
            sum.close_drawn += pool.len() - held;
        }
        let ratio_alone = match base_alone {
            Some(b) => shown(&mut alone, s, &v, b, &mut fades)?.0 / budget,
            None => f64::INFINITY,
        };
        let jump = |b: f64, l: Option<f64>| l.map_or(1.0, |l| (b / l).max(l / b));
        let (j, j_alone) = (
            jump(base, last),
            base_alone.map_or(f64::INFINITY, |b| jump(b, last_alone)),
        );
        // Ignore the steps of the first frames: the camera starts there.
        if sum.frames > 0 {
            sum.step = sum.step.max(j);
            sum.step_alone = sum.step_alone.max(j_alone);
        }
        sum.worst = sum.worst.max((ratio - 1.0).abs());
        sum.worst_alone = sum.worst_alone.max((ratio_alone - 1.0).abs());
        if sum.frames.is_multiple_of(8) {
            let mut fresh = empty.clone();
            fresh.update(s, &v, Budget::Base(base))?;
            println!(
                "| {:.3} | {} | {ratio_alone:.3} | {} | {} | {} | {} | {ms:.2} | {update:.2} | {} | {} | {} | {ratio:.3} | {j_alone:.3} | {j:.3} |",
                distance / radius,
                probed.in_view,
                estimate.ranks,
                estimate.in_view,
                estimate.evaluated,
                estimate.placed,
                fresh.len(),
                pool.len(),
                pool.bins(),
            );
        }
        last = Some(base);
        last_alone = base_alone;
        sum.frames += 1;
        distance *= 0.97;
    }
    sum.print(pool.len());
    Ok(())
}
