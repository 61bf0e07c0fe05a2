//! Soak drivers (issue 22): long runs of the streaming engine that should leave resident
//! memory flat once warmed up, shared by `bin/soak.rs` and the test suite's bounded copy.
//!
//! - [`watch_soak`]: the loop of `strata watch` ([`StreamingEngine::watch`] with the real
//!   watcher) on a torus scene in a temporary folder, through `edits` saves that cycle
//!   through a bounded set of scenes ([`EDIT_CYCLE`]: seed, count, field, cell settings,
//!   an invalid save that must be reported and change nothing, its fix). Every save is
//!   checked (the applied scene, the stages rerun, the samples), and the samples file is
//!   rewritten atomically after each change, as `strata watch --out` does.
//! - [`ecs_soak`]: the ECS engine ([`strata_systems::ecs::register`], one mesh entity)
//!   for `frames` updates with a sample request and a new count (in a bounded range)
//!   every frame, and a field edit (undone shortly after) once per period.
//!
//! Both read the resident set (`VmRSS` in `/proc/self/status`; Linux only) after
//! `warm_up` iterations, after every later one (its maximum), and at the end, plus the
//! world's entity count, open file descriptors and threads, so that a leak shows as a
//! trend with a count to blame. Cost: a save costs the watcher's debounce
//! ([`strata_systems::hot_reload::DEBOUNCE`], 100 ms) plus an update of 1-50 ms; a frame
//! about 0.1-1 ms.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use strata_engine::curve::CurveOptions;
use strata_engine::field::{FieldSpec, TensorField};
use strata_engine::mesh::shapes::Shape;
use strata_engine::surface::SurfaceOptions;
use strata_systems::config::SceneConfig;
use strata_systems::ecs::{
    EngineErrors, FieldData, MeshBundle, SampleBuffer, SampleRequest, SamplingSettings, Stage,
    StageStats,
};
use strata_systems::hot_reload::{SceneState, StreamingEngine};

/// The error type of the drivers: a failed invariant or an I/O error, as text.
pub type SoakError = Box<dyn std::error::Error>;

/// Longest wait for one save to be applied or reported (a busy shared machine included).
const EDIT_LIMIT: Duration = Duration::from_secs(30);

/// The kinds of save [`watch_soak`] cycles through, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edit {
    /// The sampling seed: reruns sampling only.
    Seed,
    /// The sample count: reruns sampling only.
    Count,
    /// The constant field's direction and anisotropy: re-segments.
    Field,
    /// The cell refinement (`curve.max_cell_share`): rebuilds cells, resamples.
    Curve,
    /// A save that does not load (a parse error, an invalid option, an unknown field, in
    /// turn): reported, and the last good state kept.
    Invalid,
    /// The last good scene saved again: applied, and nothing reruns.
    Fix,
}

/// One round of saves, each changing one thing (the values of each kind cycle through
/// short lists).
pub const EDIT_CYCLE: [Edit; 6] = [
    Edit::Seed,
    Edit::Count,
    Edit::Field,
    Edit::Curve,
    Edit::Invalid,
    Edit::Fix,
];

/// Saves after which the scene file is the same again: 6 rounds of [`EDIT_CYCLE`], 6
/// being the least common multiple of the value lists' lengths (3 and 2) and of the 3
/// invalid variants.
pub const EDIT_PERIOD: usize = 36;

const SEEDS: [u64; 3] = [1, 2, 3];
const COUNTS: [u64; 3] = [3000, 4000, 5000];
/// Constant fields: direction (projected into the tangent planes) and anisotropy.
const FIELDS: [([f64; 3], f64); 3] = [
    ([1.0, 0.3, 0.2], 3.0),
    ([0.2, 1.0, 0.3], 2.0),
    ([1.0, 0.3, 0.2], 2.0),
];
const SHARES: [f64; 2] = [1.0 / 8192.0, 1.0 / 16384.0];
/// Segments around the torus's tube (5 888 faces at 32 with radii 1 and 0.4).
const TORUS_RESOLUTION: u32 = 32;

/// Indices into the value lists: one good scene.
#[derive(Clone, Copy, Debug, Default)]
struct SceneValues {
    seed: usize,
    count: usize,
    field: usize,
    share: usize,
}

impl SceneValues {
    fn text(&self) -> String {
        let ([x, y, z], anisotropy) = FIELDS[self.field];
        format!(
            "(\n    mesh: Shape(Torus(major_radius: 1.0, minor_radius: 0.4, resolution: {TORUS_RESOLUTION})),\n    field: Constant(direction: ({x:?}, {y:?}, {z:?}), anisotropy: {anisotropy:?}, density: 1.0),\n    sampling: (count: {}, seed: {}),\n    curve: (max_cell_share: {:?}),\n)\n",
            COUNTS[self.count], SEEDS[self.seed], SHARES[self.share]
        )
    }

    /// The `k`-th invalid variant of this scene.
    fn invalid_text(&self, k: usize) -> String {
        let good = self.text();
        match k % 3 {
            0 => good.replace(
                &format!("count: {}", COUNTS[self.count]),
                "count: -3", // not a u64: a parse error
            ),
            1 => good.replace(
                &format!("max_cell_share: {:?}", SHARES[self.share]),
                "max_cell_share: 2.0", // parses, fails validation
            ),
            _ => good.replace("\n)\n", "\n    colour: 3,\n)\n"),
        }
    }
}

/// Resident memory and the counts that usually explain its growth, at one moment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Probe {
    /// Resident set size (KiB): `VmRSS`.
    pub rss_kib: u64,
    /// Its anonymous part (KiB; heaps, stacks): `RssAnon`. The rest is mostly pages of
    /// the binary, touched once.
    pub rss_anon_kib: u64,
    /// Open file descriptors.
    pub fds: usize,
    /// Threads of the process.
    pub threads: usize,
    /// Entities spawned in the world.
    pub entities: u32,
    /// Entity indices the world has allocated (spawned or free for reuse).
    pub entity_indices: u32,
}

/// `VmRSS` of this process in KiB (`None` off Linux).
pub fn resident_kib() -> Option<u64> {
    status_field("VmRSS:")
}

/// A `Name:  value [kB]` line of `/proc/self/status`, its number.
fn status_field(name: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix(name))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
}

/// When this variable is set, every reading first returns the allocator's free pages to
/// the system (glibc's `malloc_trim(0)`), so that the resident set counts what is live and
/// not which freed pages glibc happens to keep. The test suite's bounded soak sets it:
/// its two readings (one period apart) otherwise catch glibc holding a field rebuild's
/// freed pages or not, a step of 2-3 MiB either way with no trend.
pub const TRIM_ENV: &str = "STRATA_SOAK_TRIM";

/// glibc's `malloc_trim(0)`: releases the free memory at the top of the heap and the
/// free pages inside it. Nothing on other platforms.
fn trim_allocator() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        #[allow(unsafe_code)]
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> std::ffi::c_int;
        }
        // SAFETY: `malloc_trim` only hands free pages of the process's allocator (the
        // system allocator, which Rust's global allocator is here) back to the kernel;
        // live allocations are untouched.
        #[allow(unsafe_code)]
        unsafe {
            malloc_trim(0);
        }
    }
}

impl Probe {
    /// Reads the process's figures now; `entities` is a world's (spawned, allocated
    /// indices).
    fn now(entities: (u32, u32)) -> Result<Self, SoakError> {
        if std::env::var_os(TRIM_ENV).is_some() {
            trim_allocator();
        }
        Ok(Self {
            rss_kib: resident_kib().ok_or("no VmRSS in /proc/self/status (Linux only)")?,
            rss_anon_kib: status_field("RssAnon:").unwrap_or(0),
            fds: std::fs::read_dir("/proc/self/fd").map_or(0, Iterator::count),
            threads: status_field("Threads:").unwrap_or(0) as usize,
            entities: entities.0,
            entity_indices: entities.1,
        })
    }
}

/// A world's entity counts for [`Probe`]: spawned, and allocated indices. A macro, as
/// bevy_ecs is not a dependency of this crate (the world's type is only inferred).
macro_rules! entity_counts {
    ($world:expr) => {
        ($world.entity_count(), $world.entities().len())
    };
}

/// What a soak measured.
#[derive(Clone, Debug)]
pub struct SoakReport {
    /// Which soak ("watch" or "ecs").
    pub name: &'static str,
    /// Iterations run (saves or frames).
    pub iterations: usize,
    /// What an iteration is ("edits", "frames").
    pub unit: &'static str,
    /// Iterations before the baseline was read.
    pub warm_up: usize,
    /// After the warm-up.
    pub warm: Probe,
    /// At the end.
    pub end: Probe,
    /// Largest resident set after the warm-up (KiB).
    pub rss_max_kib: u64,
    /// Resident set (KiB) after every tenth of the run, `(iteration, KiB)`.
    pub trend: Vec<(usize, u64)>,
    /// Resident set (KiB) after every hundredth of the run from the warm-up on.
    pub readings: Vec<u64>,
    /// Wall time of the whole run.
    pub elapsed: Duration,
    /// Time spent in engine updates (schedule runs), all iterations together.
    pub update_time: Duration,
    /// Invalid saves reported (watch), or 0.
    pub errors_reported: usize,
    /// Errors that arrived for good saves (stale parses; expected 0).
    pub stray_errors: usize,
}

impl SoakReport {
    /// Resident set growth from the warm-up baseline to the end, in percent.
    pub fn growth_percent(&self) -> f64 {
        100.0 * (self.end.rss_kib as f64 - self.warm.rss_kib as f64) / self.warm.rss_kib as f64
    }

    /// Resident set growth from the warm-up baseline to the end, in KiB.
    pub fn growth_kib(&self) -> i64 {
        self.end.rss_kib as i64 - self.warm.rss_kib as i64
    }

    /// Growth of the largest resident set after the warm-up over the baseline, in
    /// percent.
    pub fn peak_growth_percent(&self) -> f64 {
        100.0 * (self.rss_max_kib as f64 - self.warm.rss_kib as f64) / self.warm.rss_kib as f64
    }

    /// The peaks of the first and the last quarter of the readings after the warm-up
    /// (KiB). Each quarter spans several of the run's cycles, so the allocator's
    /// states (glibc keeps or returns a few MiB depending on which blocks are free
    /// where) are in both, and only memory the run keeps raises the second.
    pub fn quarter_peaks_kib(&self) -> (u64, u64) {
        let q = (self.readings.len() / 4).max(1);
        let peak = |r: &[u64]| r.iter().copied().max().unwrap_or(0);
        let n = self.readings.len();
        (
            peak(&self.readings[..q.min(n)]),
            peak(&self.readings[n.saturating_sub(q)..]),
        )
    }

    /// The lower of [`growth_kib`](Self::growth_kib) and
    /// [`floor_growth_kib`](Self::floor_growth_kib): memory the run keeps raises both,
    /// a transient at the end point or a build in flight through the last quarter
    /// raises one.
    pub fn kept_growth_kib(&self) -> i64 {
        self.growth_kib().min(self.floor_growth_kib())
    }

    /// The lowest reading of the last quarter of the run over the warm-up baseline, in
    /// KiB. Memory kept by the run raises every reading after it, the lowest too; a
    /// transient (a build's buffers alive at the moment of one reading, an allocator
    /// step) raises single readings only, so it moves the end point but not this.
    pub fn floor_growth_kib(&self) -> i64 {
        let n = self.readings.len();
        let q = (n / 4).max(1);
        let floor = self.readings[n.saturating_sub(q)..]
            .iter()
            .copied()
            .min()
            .unwrap_or(self.end.rss_kib);
        floor as i64 - self.warm.rss_kib as i64
    }

    /// Growth of the last quarter's peak over the first quarter's, in percent (see
    /// [`quarter_peaks_kib`](Self::quarter_peaks_kib)): the trend a leak makes,
    /// without the allocator's steps of a point-to-point comparison.
    pub fn trend_growth_percent(&self) -> f64 {
        let (first, last) = self.quarter_peaks_kib();
        100.0 * (last as f64 - first as f64) / first.max(1) as f64
    }
}

/// Collects the probes of a run.
struct Recorder {
    iterations: usize,
    warm_up: usize,
    warm: Option<Probe>,
    rss_max_kib: u64,
    trend: Vec<(usize, u64)>,
    readings: Vec<u64>,
}

impl Recorder {
    fn new(iterations: usize, warm_up: usize) -> Self {
        Self {
            iterations,
            warm_up,
            warm: None,
            rss_max_kib: 0,
            trend: Vec::new(),
            readings: Vec::new(),
        }
    }

    /// After iteration `done` (1-based count of iterations finished).
    fn after(&mut self, done: usize, entities: (u32, u32)) -> Result<(), SoakError> {
        let step = (self.iterations / 10).max(1);
        let fine = (self.iterations / 100).max(1);
        let reading = done >= self.warm_up && (done - self.warm_up).is_multiple_of(fine);
        if !reading && !done.is_multiple_of(step) && done != self.warm_up {
            return Ok(());
        }
        let probe = Probe::now(entities)?;
        if done == self.warm_up {
            self.warm = Some(probe);
        }
        if done >= self.warm_up {
            self.rss_max_kib = self.rss_max_kib.max(probe.rss_kib);
        }
        if reading {
            self.readings.push(probe.rss_kib);
        }
        if done.is_multiple_of(step) || done == self.iterations {
            self.trend.push((done, probe.rss_kib));
        }
        Ok(())
    }

    fn finish(
        self,
        name: &'static str,
        unit: &'static str,
        entities: (u32, u32),
        elapsed: Duration,
    ) -> Result<SoakReport, SoakError> {
        let end = Probe::now(entities)?;
        Ok(SoakReport {
            name,
            iterations: self.iterations,
            unit,
            warm_up: self.warm_up,
            warm: self.warm.ok_or("the run ended before its warm-up")?,
            end,
            rss_max_kib: self.rss_max_kib.max(end.rss_kib),
            trend: self.trend,
            readings: self.readings,
            elapsed,
            update_time: Duration::ZERO,
            errors_reported: 0,
            stray_errors: 0,
        })
    }
}

/// Saves `text` to `path` as editors do: in place, or a temporary file renamed over it.
fn save(path: &Path, text: &str, in_place: bool) -> std::io::Result<()> {
    if in_place {
        return std::fs::write(path, text);
    }
    let tmp = path.with_extension("ron.tmp~");
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}

/// Runs engine updates as they arrive until `done` holds; errors taken on the way are
/// appended to `errors`, the updates' time added to `update_time`.
fn run_until(
    engine: &mut StreamingEngine,
    errors: &mut Vec<String>,
    update_time: &mut Duration,
    mut done: impl FnMut(&StreamingEngine, &[String]) -> bool,
) -> Result<(), SoakError> {
    let deadline = Instant::now() + EDIT_LIMIT;
    loop {
        if engine.wait(Duration::from_millis(250)) {
            let t = Instant::now();
            engine.update();
            *update_time += t.elapsed();
            errors.extend(engine.take_errors().iter().map(ToString::to_string));
            if done(engine, errors) {
                return Ok(());
            }
        } else if Instant::now() > deadline {
            return Err(format!(
                "no update within {EDIT_LIMIT:?} (stages {:?}, errors {errors:?})",
                engine.stats().stages_run()
            )
            .into());
        }
    }
}

fn applied(engine: &StreamingEngine) -> Option<&SceneConfig> {
    engine
        .world
        .get_resource::<SceneState>()
        .and_then(|s| s.config.as_ref())
}

/// `strata watch` through `edits` saves of a torus scene in a temporary folder (see the
/// module docs); the baseline is read after `warm_up` saves. Choose `edits - warm_up`
/// as a multiple of [`EDIT_PERIOD`], so that the baseline and the end are read with
/// the same scene applied. Errs on the first save that is not applied, reported or
/// rerun as expected.
pub fn watch_soak(edits: usize, warm_up: usize) -> Result<SoakReport, SoakError> {
    if warm_up == 0 || warm_up > edits {
        return Err(format!("warm-up {warm_up} must be in 1..={edits}").into());
    }
    let dir = tempfile::tempdir()?;
    let scene = dir.path().join("scene.ron");
    let out = dir.path().join("samples.ply");
    let mut values = SceneValues::default();
    let mut good = values.text();
    std::fs::write(&scene, &good)?;
    let mut engine = StreamingEngine::watch(&scene)?;
    let mut expected = SceneConfig::from_ron(&good, &scene)?;
    let mut errors = Vec::new();
    let mut update_time = Duration::ZERO;
    run_until(&mut engine, &mut errors, &mut update_time, |e, _| {
        applied(e) == Some(&expected) && e.is_idle()
    })?;
    if !errors.is_empty() {
        return Err(format!("the first scene failed: {errors:?}").into());
    }
    strata_engine::io::write_samples_ply(&out, engine.samples())?;

    let mut recorder = Recorder::new(edits, warm_up);
    update_time = Duration::ZERO;
    let (mut invalid, mut reported, mut stray) = (0usize, 0usize, 0usize);
    let start = Instant::now();
    for i in 0..edits {
        let edit = EDIT_CYCLE[i % EDIT_CYCLE.len()];
        let round = i / EDIT_CYCLE.len();
        match edit {
            Edit::Seed => values.seed = (round + 1) % SEEDS.len(),
            Edit::Count => values.count = (round + 1) % COUNTS.len(),
            Edit::Field => values.field = (round + 1) % FIELDS.len(),
            Edit::Curve => values.share = (round + 1) % SHARES.len(),
            Edit::Invalid | Edit::Fix => {}
        }
        let text = if edit == Edit::Invalid {
            invalid += 1;
            values.invalid_text(invalid - 1)
        } else {
            values.text()
        };
        let before = engine.sample_generation();
        let count_before = engine.samples().len();
        engine.clear_stats();
        errors.clear();
        save(&scene, &text, i % 2 == 1)?;
        let context = |what: &str| format!("edit {i} ({edit:?}): {what}");
        if edit == Edit::Invalid {
            run_until(&mut engine, &mut errors, &mut update_time, |_, errs| {
                !errs.is_empty()
            })?;
            reported += 1;
            if !errors.iter().all(|e| e.contains("scene.ron")) {
                return Err(context(&format!("error without the file: {errors:?}")).into());
            }
            if engine.sample_generation() != before
                || engine.samples().len() != count_before
                || applied(&engine) != Some(&expected)
            {
                return Err(context("an invalid save changed the state").into());
            }
        } else {
            good = text;
            expected = SceneConfig::from_ron(&good, &scene)?;
            run_until(&mut engine, &mut errors, &mut update_time, |e, _| {
                // The scene applied and its build (if any) applied too.
                e.stats().runs_of(Stage::Scene) > 0 && applied(e) == Some(&expected) && e.is_idle()
            })?;
            stray += errors.len();
            check_stages(&engine, edit, before).map_err(|m| context(&m))?;
        }
        if engine.sample_generation() != before {
            // As `strata watch --out`: the samples rewritten atomically after a change.
            strata_engine::io::write_samples_ply(&out, engine.samples())?;
        }
        recorder.after(i + 1, entity_counts!(engine.world))?;
    }
    let mut report = recorder.finish(
        "watch",
        "edits",
        entity_counts!(engine.world),
        start.elapsed(),
    )?;
    report.update_time = update_time;
    report.errors_reported = reported;
    report.stray_errors = stray;
    let written = strata_engine::io::read_samples_ply(&out)?;
    if written.len() != engine.samples().len() {
        return Err("the samples file is not the last samples".into());
    }
    Ok(report)
}

/// The stages a good save must have rerun, and the samples it must have left.
fn check_stages(engine: &StreamingEngine, edit: Edit, before: u64) -> Result<(), String> {
    let stages = engine.stats().stages_run();
    let resampled = engine.sample_generation() != before;
    let ok = match edit {
        Edit::Seed | Edit::Count => stages == [Stage::Scene, Stage::Sampling],
        Edit::Curve => {
            resampled && stages.contains(&Stage::Curves) && !stages.contains(&Stage::Segmentation)
        }
        Edit::Field => resampled && stages.contains(&Stage::Segmentation),
        Edit::Fix => stages == [Stage::Scene] && !resampled,
        Edit::Invalid => true,
    };
    let count = applied(engine).map_or(0, |c| c.sampling.count as usize);
    if !ok || engine.samples().len() != count {
        return Err(format!(
            "reran {stages:?} (resampled: {resampled}), {} samples for a count of {count}",
            engine.samples().len()
        ));
    }
    Ok(())
}

/// Sample counts of [`ecs_soak`]: in `ECS_COUNT_MIN..ECS_COUNT_MIN + ECS_COUNT_SPAN`.
const ECS_COUNT_MIN: usize = 4000;
const ECS_COUNT_SPAN: usize = 1000;

/// The ECS engine for `frames` updates of one torus entity (see the module docs); the
/// baseline is read after `warm_up` frames. Every `period` frames the field is edited
/// (a second field at frame `period / 2`) and the edit undone `period / 10` frames later,
/// and the counts repeat (each of the 1 000 once when `period` is 1 000), so the state
/// repeats every `period` frames: choose `warm_up` and `frames` as multiples of it, so that the baseline and
/// the end are read in the same state. Errs on an engine error or a frame without the
/// requested samples.
pub fn ecs_soak(frames: usize, warm_up: usize, period: usize) -> Result<SoakReport, SoakError> {
    if warm_up == 0 || warm_up > frames || period < 20 {
        return Err(format!("warm-up {warm_up} must be in 1..={frames}, period >= 20").into());
    }
    let mesh = Arc::new(
        Shape::Torus {
            major_radius: 1.0,
            minor_radius: 0.4,
            resolution: TORUS_RESOLUTION,
        }
        .build()?,
    );
    let fields: Vec<Arc<TensorField>> = FIELDS[..2]
        .iter()
        .map(|&(direction, anisotropy)| {
            FieldSpec::Constant {
                direction,
                anisotropy,
                density: 1.0,
            }
            .build(&mesh)
            .map(Arc::new)
        })
        .collect::<Result<_, _>>()?;
    let options = SurfaceOptions {
        curve: CurveOptions {
            max_cell_share: SHARES[0],
            ..CurveOptions::default()
        },
        ..SurfaceOptions::default()
    };
    // The world and schedule types are inferred from `register`'s signature.
    let mut world = Default::default();
    let mut schedule = Default::default();
    strata_systems::ecs::register(&mut world, &mut schedule);
    let bundle = MeshBundle::new(mesh, fields[0].clone(), options, ECS_COUNT_MIN, 9);
    let entity = world.spawn(bundle).id();
    // The first build runs off the frame: wait for it before the frames are timed.
    if !strata_systems::ecs::settle(&mut world, &mut schedule, Duration::from_secs(600)) {
        return Err("the first build did not finish in 10 minutes".into());
    }

    let mut recorder = Recorder::new(frames, warm_up);
    let mut update_time = Duration::ZERO;
    let start = Instant::now();
    for frame in 0..frames {
        let phase = frame % period;
        if phase == period / 2 || phase == period / 2 + period / 10 {
            let field = fields[usize::from(phase == period / 2)].clone();
            world.entity_mut(entity).insert(FieldData(field));
        }
        // Every count of the range once per `period` frames (7919 is prime).
        let count = ECS_COUNT_MIN + frame * 7919 % period % ECS_COUNT_SPAN;
        world
            .get_mut::<SamplingSettings>(entity)
            .ok_or("the mesh entity lost its settings")?
            .count = count;
        world.resource_mut::<SampleRequest>().0 = true;
        world.resource_mut::<StageStats>().clear();
        let before = world
            .get::<SampleBuffer>(entity)
            .map_or(0, |b| b.generation);
        let t = Instant::now();
        schedule.run(&mut world);
        world.clear_trackers();
        update_time += t.elapsed();
        let errors = &world.resource::<EngineErrors>().0;
        if !errors.is_empty() {
            return Err(format!("frame {frame}: {errors:?}").into());
        }
        let buffer = world
            .get::<SampleBuffer>(entity)
            .ok_or("the mesh entity lost its samples")?;
        if buffer.generation != before + 1 || buffer.samples.len() != count {
            return Err(format!(
                "frame {frame}: generation {} -> {}, {} samples for {count}",
                before,
                buffer.generation,
                buffer.samples.len()
            )
            .into());
        }
        // The baseline and the end are read with no build in flight: a build's
        // buffers alive at one reading and not at the other are not memory the run
        // keeps (the edits' rebuilds can outlast hundreds of sub-millisecond frames).
        if (frame + 1 == warm_up || frame + 1 == frames)
            && !strata_systems::ecs::settle(&mut world, &mut schedule, Duration::from_secs(600))
        {
            return Err(format!("frame {frame}: a build did not finish in 10 minutes").into());
        }
        recorder.after(frame + 1, entity_counts!(world))?;
    }
    let mut report = recorder.finish("ecs", "frames", entity_counts!(world), start.elapsed())?;
    report.update_time = update_time;
    Ok(report)
}

/// The reports as a Markdown table (one row per soak).
pub fn markdown_table(reports: &[SoakReport]) -> String {
    let mut t = String::from(
        "| soak | iterations (warm-up) | time | RSS after warm-up | RSS at end | growth | max after warm-up | peak, first -> last quarter | anonymous RSS | entities (indices) | fds | threads |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mib = |kib: u64| kib as f64 / 1024.0;
    for r in reports {
        t.push_str(&format!(
            "| {} | {} {} ({}) | {:.1} s | {:.1} MiB | {:.1} MiB | {:+.2}% ({:+} KiB) | {:.1} MiB ({:+.2}%) | {:.1} -> {:.1} MiB ({:+.2}%) | {:.1} -> {:.1} MiB | {} ({}) -> {} ({}) | {} -> {} | {} -> {} |\n",
            r.name,
            r.iterations,
            r.unit,
            r.warm_up,
            r.elapsed.as_secs_f64(),
            mib(r.warm.rss_kib),
            mib(r.end.rss_kib),
            r.growth_percent(),
            r.growth_kib(),
            mib(r.rss_max_kib),
            r.peak_growth_percent(),
            mib(r.quarter_peaks_kib().0),
            mib(r.quarter_peaks_kib().1),
            r.trend_growth_percent(),
            mib(r.warm.rss_anon_kib),
            mib(r.end.rss_anon_kib),
            r.warm.entities,
            r.warm.entity_indices,
            r.end.entities,
            r.end.entity_indices,
            r.warm.fds,
            r.end.fds,
            r.warm.threads,
            r.end.threads,
        ));
    }
    t
}
