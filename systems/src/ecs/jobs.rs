//! Preprocessing off the frame: a change to a mesh entity's mesh, field or settings
//! starts a build ([`rebuild`]) on the preprocessing thread pool; the last good sampler
//! keeps drawing until the build's result replaces it, in one update.
//!
//! - [`launch_builds`] sees the changes (change detection on [`MeshData`],
//!   [`FieldData`], [`PreprocessSettings`], [`CurveSettings`]), snapshots the mesh's
//!   last build (its [`SurfaceBase`], its segment entities, its sampler's chains: `Arc`s,
//!   O(segments)) and starts the build. At most one build runs per mesh: a change while
//!   one runs cancels it ([`BuildControl::cancel`], seen between stages and between
//!   segments) and the mesh is built again, from the newest state, when the cancelled
//!   build has stopped. So edits never queue up.
//! - [`apply_builds`] takes finished builds off the channel: it spawns the new segment
//!   entities, despawns the replaced ones, updates rebuilt cells, swaps the sampler and
//!   records the stages in [`StageStats`]. A failed build reports its error in
//!   [`EngineErrors`] and changes nothing; a cancelled one is counted.
//! - [`report_progress`] copies each running build's stage and fraction into
//!   [`PreprocessProgress`] (shown by `strata view` in its title and printed by
//!   `strata watch`).
//!
//! Builds run on one pool of their own ([`preprocess_pool`]), one thread per core,
//! started in the order their changes were seen, so the meshes of a world share it
//! first come, first served, and the frame's own work (sampling, on rayon's global
//! pool) never waits behind a build's tasks. [`PreprocessMode::Blocking`] runs each
//! build inside the update instead (tools and tests that want one update to do
//! everything); the result is the same bit for bit.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use crossbeam_channel::{Receiver, Sender};
use strata_engine::surface::SurfaceError;
use strata_engine::surface::incremental::{
    BuildControl, BuildInputs, BuildOutcome, BuildStage, BuiltSegment, SegmentCurves, SegmentCut,
    SegmentPieces, SurfaceState, rebuild,
};

use super::components::*;
use super::stats::{EngineErrors, Stage, StageStats};
use super::{EngineError, EngineSettings};

/// Where preprocessing runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PreprocessMode {
    /// On the preprocessing pool, off the frame (the default).
    #[default]
    Background,
    /// Inside the update that saw the change (the update takes as long as the build).
    Blocking,
}

/// The threads builds run on: one per core, named `strata-build-N`, made on first use,
/// at a lower scheduling priority than the frame (nice 10 on Linux), so that on a
/// machine whose cores the builds fill the frame's thread still runs when it is ready.
/// `None` if the system refused to start threads (builds then run on rayon's global
/// pool).
pub fn preprocess_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(std::thread::available_parallelism().map_or(2, |n| n.get()))
            .thread_name(|i| format!("strata-build-{i}"))
            .start_handler(|_| lower_priority())
            .build()
            .ok()
    })
    .as_ref()
}

/// Lowers the calling thread's scheduling priority (Linux: `setpriority` on its thread
/// id; raising nice needs no privilege). Best effort: a refusal leaves it as it was.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    {
        let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), BUILD_NICE);
    }
}

/// The nice value of build threads.
#[cfg(target_os = "linux")]
const BUILD_NICE: i32 = 10;

/// A build that ended, on its way back to the world.
pub(crate) struct Finished {
    entity: Entity,
    job: u64,
    /// The segment entities the build's previous state was taken from, in its order.
    snapshot: Vec<Entity>,
    result: Result<BuildOutcome, SurfaceError>,
}

/// A build in flight.
#[derive(Debug)]
struct Running {
    entity: Entity,
    job: u64,
    control: Arc<BuildControl>,
    started: Instant,
    /// When a newer change cancelled it.
    cancelled_at: Option<Instant>,
}

/// How many builds started and how they ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JobCounts {
    /// The longest time from a cancel to the cancelled build's end being applied (the
    /// build stops at its next check, between stages or segments; the apply waits for
    /// the next update).
    pub max_cancel_wait: Duration,
    /// Builds started.
    pub launched: u64,
    /// Builds whose result was applied.
    pub completed: u64,
    /// Builds cancelled by a newer change (or by their mesh's despawn).
    pub cancelled: u64,
    /// Builds that failed (their error is in [`EngineErrors`]).
    pub failed: u64,
}

/// The builds in flight and the channel they report on.
#[derive(Resource)]
pub struct PreprocessJobs {
    sender: Sender<Finished>,
    receiver: Receiver<Finished>,
    running: Vec<Running>,
    /// Builds taken off the channel by [`wait`](Self::wait), not applied yet.
    stash: Vec<Finished>,
    /// Meshes changed while their build ran: built again when it stops.
    pending: Vec<Entity>,
    next_job: u64,
    counts: JobCounts,
    /// Other work off the frame not yet taken by the world (level-of-detail pools).
    tasks: Arc<AtomicUsize>,
}

/// Counts one piece of work off the frame as pending until dropped (when its result is
/// taken, or its owner is gone).
#[derive(Debug)]
pub struct TaskToken(Arc<AtomicUsize>);

impl Drop for TaskToken {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::Relaxed);
    }
}

impl Default for PreprocessJobs {
    fn default() -> Self {
        let (sender, receiver) = crossbeam_channel::unbounded();
        Self {
            sender,
            receiver,
            running: Vec::new(),
            stash: Vec::new(),
            pending: Vec::new(),
            next_job: 0,
            counts: JobCounts::default(),
            tasks: Arc::new(AtomicUsize::new(0)),
        }
    }
}

impl PreprocessJobs {
    /// Builds started, completed, cancelled and failed so far.
    pub fn counts(&self) -> JobCounts {
        self.counts
    }

    /// Builds running now.
    pub fn in_flight(&self) -> usize {
        self.running.len()
    }

    /// True when no build runs, none waits to start and no result waits to be applied.
    pub fn is_idle(&self) -> bool {
        self.tasks.load(Ordering::Relaxed) == 0
            && self.running.is_empty()
            && self.pending.is_empty()
            && self.stash.is_empty()
            && self.receiver.is_empty()
    }

    /// Blocks until a finished build waits to be applied, or `timeout` passed; true if
    /// one waits.
    pub fn wait(&mut self, timeout: Duration) -> bool {
        if !self.stash.is_empty() || !self.receiver.is_empty() {
            return true;
        }
        match self.receiver.recv_timeout(timeout) {
            Ok(done) => {
                self.stash.push(done);
                true
            }
            Err(_) => false,
        }
    }

    /// A token that keeps the engine from counting as idle (see [`is_idle`](Self::is_idle))
    /// until dropped: for other work off the frame whose result an update takes.
    pub fn task_token(&self) -> TaskToken {
        self.tasks.fetch_add(1, Ordering::Relaxed);
        TaskToken(self.tasks.clone())
    }

    /// The channel finished builds arrive on, and where a waiter that took one off it
    /// puts it (for waits that select over several channels).
    pub(crate) fn finished_channel(&mut self) -> (&Receiver<Finished>, &mut Vec<Finished>) {
        (&self.receiver, &mut self.stash)
    }

    /// The next finished build, if any.
    fn next_finished(&mut self) -> Option<Finished> {
        self.stash.pop().or_else(|| self.receiver.try_recv().ok())
    }

    /// Marks `entity` changed: cancels its running build, and queues it.
    fn mark(&mut self, entity: Entity) {
        if let Some(r) = self.running.iter_mut().find(|r| r.entity == entity) {
            r.control.cancel();
            r.cancelled_at.get_or_insert_with(Instant::now);
        }
        if !self.pending.contains(&entity) {
            self.pending.push(entity);
        }
    }

    /// The changed meshes whose build may start now (none of theirs is running; a
    /// cancelled one must stop first), taken off the pending list.
    fn take_startable(&mut self) -> Vec<Entity> {
        let running = &self.running;
        let (wait, start): (Vec<Entity>, Vec<Entity>) = self
            .pending
            .iter()
            .partition(|&&e| running.iter().any(|r| r.entity == e));
        self.pending = wait;
        start
    }

    /// Starts a build of `entity` from `previous` (its segments are `snapshot`).
    fn launch(
        &mut self,
        entity: Entity,
        inputs: BuildInputs,
        previous: Option<SurfaceState>,
        snapshot: Vec<Entity>,
        mode: PreprocessMode,
    ) {
        let job = self.next_job;
        self.next_job += 1;
        self.counts.launched += 1;
        let control = Arc::new(BuildControl::new());
        self.running.push(Running {
            entity,
            job,
            control: control.clone(),
            started: Instant::now(),
            cancelled_at: None,
        });
        let sender = self.sender.clone();
        let work = move || {
            let result = rebuild(inputs, previous.as_ref(), &control);
            // The world may be gone (the application quit): nothing to report to.
            let _ = sender.send(Finished {
                entity,
                job,
                snapshot,
                result,
            });
        };
        match (mode, preprocess_pool()) {
            (PreprocessMode::Blocking, _) => work(),
            (PreprocessMode::Background, Some(pool)) => pool.spawn(work),
            (PreprocessMode::Background, None) => rayon::spawn(work),
        }
    }
}

/// Running builds: mesh entity, stage, share of the stage done, time since it started.
#[derive(Resource, Clone, Debug, Default)]
pub struct PreprocessProgress {
    /// One entry per running build.
    pub jobs: Vec<JobStatus>,
}

/// One running build, as [`PreprocessProgress`] shows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JobStatus {
    /// The mesh entity being built.
    pub entity: Entity,
    /// Its stage.
    pub stage: BuildStage,
    /// Share of the stage done, in [0, 1].
    pub fraction: f64,
    /// Time since the build started.
    pub elapsed: Duration,
}

impl PreprocessProgress {
    /// One line for a title bar or a log, e.g. `"building: parameterization 40% (2.1 s)"`
    /// (the first build, and how many others run); `None` when nothing runs.
    pub fn summary(&self) -> Option<String> {
        let first = self.jobs.first()?;
        let others = match self.jobs.len() - 1 {
            0 => String::new(),
            n => format!(", {n} more"),
        };
        Some(format!(
            "building: {} {:.0}% ({:.1} s{others})",
            first.stage.name(),
            first.fraction * 100.0,
            first.elapsed.as_secs_f64()
        ))
    }
}

/// What a build of a mesh entity reads: its inputs, its last build and segments.
type MeshInputs<'a> = (
    &'a MeshData,
    &'a FieldData,
    &'a PreprocessSettings,
    &'a CurveSettings,
    &'a SurfaceBase,
    &'a MeshSampler,
    Option<&'a Segments>,
);

/// A segment entity's shared build state.
type SegmentParts<'a> = (&'a SegmentFaces, &'a SegmentParams, &'a SegmentCells);

/// Starts builds for changed meshes (see the module docs).
#[allow(clippy::type_complexity)]
pub fn launch_builds(
    settings: Res<EngineSettings>,
    mut jobs: ResMut<PreprocessJobs>,
    changed: Query<
        Entity,
        Or<(
            Changed<MeshData>,
            Changed<FieldData>,
            Changed<PreprocessSettings>,
            Changed<CurveSettings>,
        )>,
    >,
    meshes: Query<MeshInputs>,
    segments: Query<SegmentParts>,
) {
    for entity in &changed {
        jobs.mark(entity);
    }
    for r in &mut jobs.running {
        if !meshes.contains(r.entity) {
            r.control.cancel(); // its mesh is gone
            r.cancelled_at.get_or_insert_with(Instant::now);
        }
    }
    for entity in jobs.take_startable() {
        if let Ok(mesh) = meshes.get(entity) {
            let (inputs, previous, snapshot) = snapshot(mesh, &segments);
            jobs.launch(entity, inputs, previous, snapshot, settings.preprocess);
        }
    }
}

/// A mesh entity's build inputs, its last build (`None` before the first) and the
/// segment entities that build's segments come from, in the same order.
fn snapshot(
    (mesh, field, pre, curve, base, sampler, children): MeshInputs,
    segments: &Query<SegmentParts>,
) -> (BuildInputs, Option<SurfaceState>, Vec<Entity>) {
    let inputs = BuildInputs {
        mesh: mesh.0.clone(),
        field: field.0.clone(),
        options: strata_engine::surface::SurfaceOptions {
            curve: curve.0,
            ..pre.0
        },
    };
    let (entities, built): (Vec<Entity>, Vec<BuiltSegment>) = children
        .into_iter()
        .flat_map(|c| c.iter())
        .filter_map(|e| {
            let (f, p, c) = segments.get(e).ok()?;
            Some((e, SegmentBundle::built(f, p, c)))
        })
        .unzip();
    let previous = base.0.as_ref().map(|b| SurfaceState {
        inputs: b.inputs.clone(),
        working_field: b.working_field.clone(),
        kind: b.kind,
        segments: built,
        chains: sampler.0.as_ref().map_or_else(Vec::new, |s| {
            s.chains().iter().map(|c| c.to_vec()).collect()
        }),
    });
    (inputs, previous, entities)
}

/// Applies finished builds (see the module docs). What they replace (the old sampler,
/// the despawned segments' data) is dropped on the build pool, not in the frame.
pub fn apply_builds(
    mut commands: Commands,
    mut jobs: ResMut<PreprocessJobs>,
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    mut meshes: Query<(&mut MeshSampler, &mut SurfaceBase)>,
    mut segments: Query<(&mut SegmentFaces, &mut SegmentParams, &mut SegmentCells)>,
) {
    let mut garbage = Garbage::default();
    while let Some(done) = jobs.next_finished() {
        if !jobs.end(&done) {
            continue; // cancelled
        }
        let outcome = match done.result {
            Ok(outcome) => outcome,
            Err(e) => {
                errors.0.push(EngineError::Surface(e));
                continue;
            }
        };
        let Ok((mut sampler, mut base)) = meshes.get_mut(done.entity) else {
            continue; // the mesh entity is gone
        };
        jobs.counts.completed += 1;
        for run in &outcome.runs {
            let note = run.note.clone();
            stats.record(stage_of(run.stage), done.entity, run.items, run.took, note);
        }
        let (entity, snapshot) = (done.entity, &done.snapshot);
        write_segments(
            &mut commands,
            entity,
            snapshot,
            &outcome,
            &mut segments,
            &mut garbage,
        );
        if let Some(s) = outcome.sampler {
            garbage.0.push(Box::new(sampler.0.replace(s)));
        }
        garbage
            .0
            .push(Box::new(base.0.replace(LastBuild::from(outcome.state))));
    }
    garbage.drop_off_frame();
}

impl From<SurfaceState> for LastBuild {
    /// The inputs and prepared field of a build's state (its segments go to entities).
    fn from(state: SurfaceState) -> Self {
        Self {
            inputs: state.inputs,
            working_field: state.working_field,
            kind: state.kind,
        }
    }
}

/// Values to drop on the build pool (freeing a large sampler takes milliseconds).
#[derive(Default)]
struct Garbage(Vec<Box<dyn Send>>);

impl Garbage {
    fn drop_off_frame(self) {
        if self.0.is_empty() {
            return;
        }
        match preprocess_pool() {
            Some(pool) => pool.spawn(move || drop(self)),
            None => drop(self),
        }
    }
}

impl PreprocessJobs {
    /// Takes a finished build off the running list and counts a cancelled or failed
    /// one; false when there is nothing to apply (cancelled).
    fn end(&mut self, done: &Finished) -> bool {
        let cancelled_at = self
            .running
            .iter()
            .find(|r| r.job == done.job)
            .and_then(|r| r.cancelled_at);
        self.running.retain(|r| r.job != done.job);
        match &done.result {
            Err(SurfaceError::Cancelled) => {
                self.counts.cancelled += 1;
                let wait = cancelled_at.map_or(Duration::ZERO, |t| t.elapsed());
                self.counts.max_cancel_wait = self.counts.max_cancel_wait.max(wait);
                false
            }
            Err(_) => {
                self.counts.failed += 1;
                true
            }
            Ok(_) => true,
        }
    }
}

/// Spawns a build's new segments, despawns those it replaced (their data moved to
/// `garbage` first) and updates the cells of those it kept with new cells.
fn write_segments(
    commands: &mut Commands,
    mesh: Entity,
    snapshot: &[Entity],
    outcome: &BuildOutcome,
    segments: &mut Query<(&mut SegmentFaces, &mut SegmentParams, &mut SegmentCells)>,
    garbage: &mut Garbage,
) {
    let mut kept = vec![false; snapshot.len()];
    for (s, origin) in outcome.state.segments.iter().zip(&outcome.origins) {
        match origin.and_then(|i| Some((i, *snapshot.get(i)?))) {
            Some((i, e)) => {
                kept[i] = true;
                if let Ok((_, _, mut c)) = segments.get_mut(e)
                    && !Arc::ptr_eq(&c.0, &s.curves)
                {
                    garbage
                        .0
                        .push(Box::new(std::mem::replace(&mut c.0, s.curves.clone())));
                }
            }
            None => {
                commands.spawn(SegmentBundle::new(mesh, s));
            }
        }
    }
    let empty = empty_segment();
    for (&e, _) in snapshot.iter().zip(kept).filter(|(_, k)| !k) {
        if let Ok((mut f, mut p, mut c)) = segments.get_mut(e) {
            let old = (
                std::mem::replace(&mut f.0, empty.cut.clone()),
                std::mem::replace(&mut p.0, empty.pieces.clone()),
                std::mem::replace(&mut c.0, empty.curves.clone()),
            );
            garbage.0.push(Box::new(old));
        }
        commands.entity(e).try_despawn();
    }
}

/// An empty segment, put into the components of a segment about to be despawned.
fn empty_segment() -> &'static BuiltSegment {
    static EMPTY: OnceLock<BuiltSegment> = OnceLock::new();
    EMPTY.get_or_init(|| BuiltSegment {
        cut: Arc::new(SegmentCut {
            faces: Vec::new(),
            cut_edges: Vec::new(),
            key: 0,
        }),
        pieces: Arc::new(SegmentPieces {
            pieces: Vec::new(),
            inputs: Vec::new(),
            report: Default::default(),
        }),
        curves: Arc::new(SegmentCurves { curves: Vec::new() }),
    })
}

/// The ECS stage that records an engine build stage.
fn stage_of(stage: BuildStage) -> Stage {
    match stage {
        BuildStage::Parameterization => Stage::Parameterization,
        BuildStage::Cells => Stage::Curves,
        BuildStage::Chains => Stage::Chains,
        _ => Stage::Segmentation,
    }
}

/// Copies the running builds' progress into [`PreprocessProgress`] (no allocation once
/// its list has grown to the number of concurrent builds).
pub fn report_progress(jobs: Res<PreprocessJobs>, mut progress: ResMut<PreprocessProgress>) {
    if jobs.running.is_empty() && progress.jobs.is_empty() {
        return;
    }
    let progress = &mut progress.jobs;
    progress.clear();
    progress.extend(jobs.running.iter().map(|r| {
        let p = r.control.progress();
        JobStatus {
            entity: r.entity,
            stage: p.stage,
            fraction: p.fraction(),
            elapsed: r.started.elapsed(),
        }
    }));
}

/// Runs `schedule` until every build has finished and been applied (or `timeout`
/// passed): for tools, tests and hosts that want the result of a change before they go
/// on. Returns whether the engine is idle. Waits on the builds between updates instead
/// of spinning the schedule.
pub fn settle(world: &mut World, schedule: &mut Schedule, timeout: Duration) -> bool {
    let deadline = Instant::now() + timeout;
    loop {
        schedule.run(world);
        let mut jobs = world.resource_mut::<PreprocessJobs>();
        if jobs.is_idle() {
            return true;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return false;
        }
        // Builds report on the channel; other tasks are polled.
        let others = jobs.tasks.load(Ordering::Relaxed) > 0;
        if jobs.pending.is_empty() {
            jobs.wait(if others {
                left.min(Duration::from_millis(2))
            } else {
                left
            });
        }
    }
}
