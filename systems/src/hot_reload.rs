//! Hot reload of scene files: a watcher thread turns file changes into loaded scenes
//! (parsed, their mesh loaded and their field built, off the frame), and a system
//! applies them to the world at the start of the next update.
//!
//! The thread (notify) watches the folder of the scene file and the folders of the
//! files it names (mesh, field file), non-recursively, and matches file names, so that
//! editors that save by writing a temporary file and renaming it, and files deleted and
//! re-created, are seen. It reacts to `Access(Close(Write))`, `Modify(Name(_))` and
//! `Create(_)` only (plain `Modify` events arrive while a file is half written), waits
//! until no relevant event came for [`DEBOUNCE`], then parses the scene, loads what
//! changed (the mesh when its source changed or its file changed on disk, the field
//! when its spec, the mesh or its file changed; the rest is reused from the last good
//! scene) and sends the result over a crossbeam channel: bursts of saves give one load
//! of the final file.
//!
//! [`apply_scene_updates`] drains the channel: a scene that failed to read, parse,
//! validate or load is reported (file, line, column, message) in [`EngineErrors`] and
//! changes nothing; of the good ones the newest is applied, setting only the
//! components that differ, so change detection sees only what changed (and the
//! builds of [`crate::ecs::jobs`] redo only that). Nothing heavy runs in the update. A
//! scene that was bad at start-up is picked up as soon as a good version is saved.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, select};
use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind};
use notify::{RecursiveMode, Watcher};

use strata_engine::field::TensorField;
use strata_engine::mesh::TriMesh;

use crate::config::{ConfigError, MeshSource, SceneConfig};
use crate::ecs::components::*;
use crate::ecs::{
    EngineError, EngineErrors, EngineSystems, JobCounts, PreprocessJobs, PreprocessProgress, Stage,
    StageStats,
};

/// Quiet time after the last relevant file event before the scene is parsed.
pub const DEBOUNCE: Duration = Duration::from_millis(100);

/// A scene file read and loaded by the watcher.
#[derive(Debug)]
pub struct SceneUpdate {
    /// The scene, or why it could not be used.
    pub scene: Result<LoadedScene, EngineError>,
}

/// A good scene with its mesh and field, as the watcher loaded them.
#[derive(Debug)]
pub struct LoadedScene {
    /// The scene.
    pub config: SceneConfig,
    /// Its mesh (the last good scene's when neither its source nor its file changed).
    pub mesh: Arc<TriMesh>,
    /// Its field (the last good scene's when neither its spec, the mesh nor its files
    /// changed).
    pub field: Arc<TensorField>,
    /// Whether the mesh was loaded anew.
    pub reloaded_mesh: bool,
    /// Whether the field was built anew.
    pub rebuilt_field: bool,
    /// Time the watcher spent loading.
    pub took: Duration,
}

/// The watcher thread's memory of the last good scene, so that a change loads only
/// what it touched.
#[derive(Default)]
struct Loader {
    last: Option<(SceneConfig, Arc<TriMesh>, Arc<TensorField>)>,
    /// Files changed on disk that no good scene has loaded since.
    unapplied: Vec<PathBuf>,
}

impl Loader {
    fn load(
        &mut self,
        parsed: Result<SceneConfig, ConfigError>,
        changed: Vec<PathBuf>,
    ) -> Result<LoadedScene, EngineError> {
        let t = Instant::now();
        self.unapplied.extend(changed);
        self.unapplied.sort();
        self.unapplied.dedup();
        let config = parsed?;
        let changed = &self.unapplied;
        let on_disk = |p: &Path| std::path::absolute(p).is_ok_and(|a| changed.contains(&a));
        let last = self.last.as_ref();
        let mesh_file_changed = matches!(&config.mesh, MeshSource::File(p) if on_disk(p));
        let reloaded_mesh = last.is_none_or(|(c, ..)| c.mesh != config.mesh) || mesh_file_changed;
        let mesh = match last.filter(|_| !reloaded_mesh) {
            Some((_, m, _)) => m.clone(),
            None => Arc::new(crate::scene::load_mesh(&config)?),
        };
        let rebuilt_field = reloaded_mesh
            || last.is_none_or(|(c, ..)| c.field != config.field)
            || config.field.files().into_iter().any(on_disk);
        let field = match last.filter(|_| !rebuilt_field) {
            Some((_, _, f)) => f.clone(),
            None => Arc::new(config.field.build(&mesh)?),
        };
        self.unapplied.clear();
        self.last = Some((config.clone(), mesh.clone(), field.clone()));
        Ok(LoadedScene {
            config,
            mesh,
            field,
            reloaded_mesh,
            rebuilt_field,
            took: t.elapsed(),
        })
    }
}

/// The receiving end of the watcher's channel, as a resource.
#[derive(Resource, Debug)]
pub struct SceneInbox {
    receiver: Receiver<SceneUpdate>,
    /// Updates already taken off the channel (by [`SceneInbox::wait`]) but not applied.
    pending: Vec<SceneUpdate>,
}

impl SceneInbox {
    /// An inbox reading `receiver`.
    pub fn new(receiver: Receiver<SceneUpdate>) -> Self {
        Self {
            receiver,
            pending: Vec::new(),
        }
    }

    /// Blocks until an update is waiting or `timeout` passed; true if one is waiting.
    pub fn wait(&mut self, timeout: Duration) -> bool {
        if !self.pending.is_empty() || !self.receiver.is_empty() {
            return true;
        }
        match self.receiver.recv_timeout(timeout) {
            Ok(u) => {
                self.pending.push(u);
                true
            }
            Err(_) => false,
        }
    }

    fn drain(&mut self) -> Vec<SceneUpdate> {
        let mut out = std::mem::take(&mut self.pending);
        out.extend(self.receiver.try_iter());
        out
    }
}

/// The scene currently applied, and the mesh entity it drives.
#[derive(Resource, Debug, Default)]
pub struct SceneState {
    /// The last good scene applied.
    pub config: Option<SceneConfig>,
    /// The mesh entity it drives (spawned by the first good scene).
    pub entity: Option<Entity>,
}

/// The watcher thread; dropping it stops the thread.
#[derive(Debug)]
pub struct SceneWatcher {
    stop: Option<Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for SceneWatcher {
    fn drop(&mut self) {
        self.stop.take(); // disconnects the stop channel: the thread ends
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Errors starting the watcher.
#[derive(Debug, thiserror::Error)]
pub enum WatchError {
    /// notify could not watch a folder.
    #[error("watching {path}: {source}")]
    Notify {
        /// The folder.
        path: PathBuf,
        /// The cause.
        #[source]
        source: notify::Error,
    },
    /// The scene path has no usable form (for example an empty path).
    #[error("scene path {0}: {1}")]
    Path(PathBuf, std::io::Error),
}

/// Starts watching `scene`: the first update (the file as it is now, good or bad) is
/// sent as soon as the thread has loaded it; later ones follow each (debounced) change.
pub fn watch_scene(scene: &Path) -> Result<(SceneWatcher, Receiver<SceneUpdate>), WatchError> {
    let scene = std::path::absolute(scene).map_err(|e| WatchError::Path(scene.to_path_buf(), e))?;
    let (out_tx, out_rx) = crossbeam_channel::unbounded();
    let (raw_tx, raw_rx) = crossbeam_channel::unbounded();
    let (stop_tx, stop_rx) = crossbeam_channel::bounded::<()>(0);
    let mut watcher = notify::recommended_watcher(move |event| {
        let _ = raw_tx.send(event);
    })
    .map_err(|source| WatchError::Notify {
        path: scene.clone(),
        source,
    })?;
    let mut watched: HashSet<PathBuf> = HashSet::new();
    let scene_dir = scene.parent().unwrap_or(Path::new("/")).to_path_buf();
    watch_dir(&mut watcher, &mut watched, &scene_dir)?;
    let first = SceneConfig::load(&scene);
    let deps = dependencies(&first);
    for d in &deps {
        if let Some(dir) = d.parent() {
            // A missing folder is not fatal: the file may appear later in a new scene.
            let _ = watch_dir(&mut watcher, &mut watched, dir);
        }
    }
    let watch = WatchLoop {
        scene,
        deps,
        watcher,
        watched,
        raw: raw_rx,
        stop: stop_rx,
        out: out_tx,
        loader: Loader::default(),
    };
    let thread = std::thread::Builder::new()
        .name("strata-scene-watcher".to_owned())
        .spawn(move || watch.run(first))
        .map_err(|e| WatchError::Path(scene_dir, e))?;
    Ok((
        SceneWatcher {
            stop: Some(stop_tx),
            thread: Some(thread),
        },
        out_rx,
    ))
}

/// The watcher thread: what it watches, the raw events and the stop signal it
/// listens to, and where it sends the scenes it loads.
struct WatchLoop {
    /// The scene file (absolute).
    scene: PathBuf,
    /// The files the last parsed scene names.
    deps: Vec<PathBuf>,
    watcher: notify::RecommendedWatcher,
    /// The folders watched.
    watched: HashSet<PathBuf>,
    raw: Receiver<notify::Result<notify::Event>>,
    stop: Receiver<()>,
    out: Sender<SceneUpdate>,
    loader: Loader,
}

impl WatchLoop {
    /// Sends the `first` scene, then one loaded scene per burst of relevant changes,
    /// until stopped or the receiver is gone.
    fn run(mut self, first: Result<SceneConfig, ConfigError>) {
        if !self.send(first, Vec::new()) {
            return;
        }
        while let Some(changed) = self.next_changes() {
            let parsed = SceneConfig::load(&self.scene);
            self.follow(dependencies(&parsed));
            if !self.send(parsed, changed) {
                return; // the engine is gone
            }
        }
    }

    /// Loads `parsed` (on this thread, not on the build pool: a load waiting behind a
    /// long build would hold back the change that cancels that build) and sends it;
    /// false when the receiver is gone.
    fn send(&mut self, parsed: Result<SceneConfig, ConfigError>, changed: Vec<PathBuf>) -> bool {
        let update = SceneUpdate {
            scene: self.loader.load(parsed, changed),
        };
        self.out.send(update).is_ok()
    }

    /// Waits for a relevant event, then until [`DEBOUNCE`] passes without one: the
    /// files changed, sorted and without repeats. `None` when stopped or when the
    /// events' sender is gone.
    fn next_changes(&self) -> Option<Vec<PathBuf>> {
        loop {
            let mut changed: Vec<PathBuf> = Vec::new();
            select! {
                recv(self.stop) -> _ => return None,
                recv(self.raw) -> event => match event {
                    Ok(Ok(e)) => changed.extend(self.relevant(&e)),
                    Ok(Err(_)) => {}
                    Err(_) => return None,
                },
            }
            if changed.is_empty() {
                continue;
            }
            self.debounce(&mut changed)?;
            changed.sort();
            changed.dedup();
            return Some(changed);
        }
    }

    /// Adds the relevant changes to `changed` until [`DEBOUNCE`] passes without one;
    /// `None` when stopped or when the events' sender is gone.
    fn debounce(&self, changed: &mut Vec<PathBuf>) -> Option<()> {
        let mut deadline = Instant::now() + DEBOUNCE;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.raw.recv_timeout(left) {
                Ok(Ok(e)) => {
                    let more = self.relevant(&e);
                    if !more.is_empty() {
                        changed.extend(more);
                        deadline = Instant::now() + DEBOUNCE;
                    }
                }
                Ok(Err(_)) => {}
                Err(RecvTimeoutError::Timeout) => return Some(()),
                Err(RecvTimeoutError::Disconnected) => return None,
            }
            if self.stop.try_recv() != Err(crossbeam_channel::TryRecvError::Empty) {
                return None;
            }
        }
    }

    /// The scene file and its dependencies that `event` wrote, renamed or created.
    fn relevant(&self, event: &notify::Event) -> Vec<PathBuf> {
        let kind_ok = matches!(
            event.kind,
            EventKind::Access(AccessKind::Close(AccessMode::Write))
                | EventKind::Modify(ModifyKind::Name(_))
                | EventKind::Create(_)
        );
        if !kind_ok {
            return Vec::new();
        }
        event
            .paths
            .iter()
            .filter(|p| **p == self.scene || self.deps.contains(p))
            .cloned()
            .collect()
    }

    /// Watches the folders of a newly parsed scene's files and follows them from now
    /// on; a scene that named none (or failed to parse) keeps the last dependencies.
    fn follow(&mut self, new_deps: Vec<PathBuf>) {
        if new_deps.is_empty() {
            return;
        }
        for d in &new_deps {
            if let Some(dir) = d.parent() {
                let _ = watch_dir(&mut self.watcher, &mut self.watched, dir);
            }
        }
        self.deps = new_deps;
    }
}

/// Watches `dir` (non-recursively) unless it is watched already.
fn watch_dir(
    watcher: &mut notify::RecommendedWatcher,
    watched: &mut HashSet<PathBuf>,
    dir: &Path,
) -> Result<(), WatchError> {
    if watched.contains(dir) {
        return Ok(());
    }
    watcher
        .watch(dir, RecursiveMode::NonRecursive)
        .map_err(|source| WatchError::Notify {
            path: dir.to_path_buf(),
            source,
        })?;
    watched.insert(dir.to_path_buf());
    Ok(())
}

/// The files a scene names (mesh file, field files), absolute.
fn dependencies(scene: &Result<SceneConfig, ConfigError>) -> Vec<PathBuf> {
    scene
        .as_ref()
        .map_or_else(|_| Vec::new(), SceneConfig::input_files)
}

/// Applies the newest good scene from the inbox (see the module docs).
pub fn apply_scene_updates(world: &mut World) {
    let updates = match world.get_resource_mut::<SceneInbox>() {
        Some(mut inbox) => inbox.drain(),
        None => return,
    };
    let mut newest = None;
    for u in updates {
        match u.scene {
            Ok(scene) => newest = Some(scene),
            Err(e) => world.resource_mut::<EngineErrors>().0.push(e),
        }
    }
    let Some(loaded) = newest else {
        return;
    };
    let t = Instant::now();
    let took = loaded.took;
    match apply_scene(world, loaded) {
        Ok((entity, note)) => {
            world.resource_mut::<StageStats>().record(
                Stage::Scene,
                entity,
                1,
                took + t.elapsed(),
                note,
            );
        }
        Err(e) => world.resource_mut::<EngineErrors>().0.push(e),
    }
}

/// Applies one loaded scene: sets components only where they differ.
fn apply_scene(world: &mut World, loaded: LoadedScene) -> Result<(Entity, String), EngineError> {
    let LoadedScene {
        config,
        mesh,
        field,
        reloaded_mesh,
        rebuilt_field,
        ..
    } = loaded;
    let state = world.get_resource_or_init::<SceneState>();
    let old = state.config.clone();
    let entity = state.entity.filter(|e| world.get_entity(*e).is_ok());
    // The engine holds every sample: a count memory cannot hold is refused before
    // anything changes (an unchanged count already has its buffer).
    if old
        .as_ref()
        .is_none_or(|o| o.sampling.count != config.sampling.count)
    {
        crate::budget::check_memory(config.sampling.count)?;
    }
    let options = config.surface_options();
    let count = usize::try_from(config.sampling.count).unwrap_or(usize::MAX);
    let mut what = Vec::new();
    let entity = match entity {
        None => {
            let mut bundle = MeshBundle::new(mesh, field, options, count, config.sampling.seed);
            bundle.transform = MeshTransform(config.transform.to_affine());
            what.push("new mesh entity");
            world.spawn(bundle).id()
        }
        Some(e) => {
            let mut entity = world.entity_mut(e);
            // Host code may have set other data meanwhile: the scene's wins.
            let differs = |a: Option<&Arc<TriMesh>>| a.is_none_or(|a| !Arc::ptr_eq(a, &mesh));
            if reloaded_mesh || differs(entity.get::<MeshData>().map(|m| &m.0)) {
                entity.insert(MeshData(mesh));
                what.push("mesh");
            }
            let differs = |a: Option<&Arc<TensorField>>| a.is_none_or(|a| !Arc::ptr_eq(a, &field));
            if rebuilt_field || differs(entity.get::<FieldData>().map(|f| &f.0)) {
                entity.insert(FieldData(field));
                what.push("field");
            }
            let mut set = |changed: bool, name: &'static str| {
                if changed {
                    what.push(name);
                }
            };
            if let Some(mut c) = entity.get_mut::<PreprocessSettings>() {
                set(
                    c.set_if_neq(PreprocessSettings::new(options)),
                    "segmentation settings",
                );
            }
            if let Some(mut c) = entity.get_mut::<CurveSettings>() {
                set(c.set_if_neq(CurveSettings(options.curve)), "curve settings");
            }
            if let Some(mut c) = entity.get_mut::<SamplingSettings>() {
                let s = SamplingSettings {
                    count,
                    seed: config.sampling.seed,
                };
                set(c.set_if_neq(s), "sampling");
            }
            if let Some(mut c) = entity.get_mut::<MeshTransform>() {
                set(
                    c.set_if_neq(MeshTransform(config.transform.to_affine())),
                    "transform",
                );
            }
            e
        }
    };
    let mut state = world.resource_mut::<SceneState>();
    state.config = Some(config);
    state.entity = Some(entity);
    let note = if what.is_empty() {
        "no change".to_owned()
    } else {
        what.join(", ")
    };
    Ok((entity, note))
}

/// Adds the engine ([`crate::ecs::register`]) and scene application to `world` and
/// `schedule`, reading scenes from `inbox` (see [`watch_scene`]).
pub fn register(world: &mut World, schedule: &mut Schedule, inbox: Receiver<SceneUpdate>) {
    crate::ecs::register(world, schedule);
    world.insert_resource(SceneInbox::new(inbox));
    world.init_resource::<SceneState>();
    schedule.add_systems(apply_scene_updates.in_set(EngineSystems::ApplyScene));
}

/// A world, a schedule and a scene watcher: the engine loop of `strata watch`, the
/// tests and the benchmarks, in one value.
pub struct StreamingEngine {
    /// The world (mesh and segment entities, the engine's resources).
    pub world: World,
    /// The schedule with the engine's systems.
    pub schedule: Schedule,
    _watcher: SceneWatcher,
}

impl StreamingEngine {
    /// Watches `scene` and prepares the engine; the scene is applied by the first
    /// [`update`](Self::update).
    pub fn watch(scene: &Path) -> Result<Self, WatchError> {
        let (watcher, inbox) = watch_scene(scene)?;
        let mut world = World::new();
        let mut schedule = Schedule::default();
        register(&mut world, &mut schedule, inbox);
        Ok(Self {
            world,
            schedule,
            _watcher: watcher,
        })
    }

    /// Runs the schedule once (applies waiting scene changes, recomputes what they
    /// invalidated, samples).
    pub fn update(&mut self) {
        self.schedule.run(&mut self.world);
        self.world.clear_trackers();
    }

    /// Blocks until a scene change is waiting or `timeout` passed; true if one is.
    pub fn wait_for_change(&mut self, timeout: Duration) -> bool {
        self.world.resource_mut::<SceneInbox>().wait(timeout)
    }

    /// Blocks until a scene change or a finished build waits to be applied, or
    /// `timeout` passed; true if something waits. The loop of `strata watch`: wait,
    /// then [`update`](Self::update).
    pub fn wait(&mut self, timeout: Duration) -> bool {
        self.world
            .resource_scope(|world, mut inbox: Mut<SceneInbox>| {
                let mut jobs = world.resource_mut::<PreprocessJobs>();
                if !inbox.pending.is_empty() || !inbox.receiver.is_empty() {
                    return true;
                }
                let (builds, stash) = jobs.finished_channel();
                if !stash.is_empty() || !builds.is_empty() {
                    return true;
                }
                select! {
                    recv(inbox.receiver) -> u => {
                        if let Ok(u) = u {
                            inbox.pending.push(u);
                        }
                        true
                    }
                    recv(builds) -> done => {
                        if let Ok(done) = done {
                            stash.push(done);
                        }
                        true
                    }
                    default(timeout) => false,
                }
            })
    }

    /// True when no build runs or waits to start and no finished one waits to be
    /// applied (scene changes not yet seen by the watcher do not count).
    pub fn is_idle(&self) -> bool {
        self.world.resource::<PreprocessJobs>().is_idle()
    }

    /// Runs updates until every build has been applied (or `timeout` passed); true if
    /// the engine is idle. A scene change that arrives meanwhile is applied too.
    pub fn settle(&mut self, timeout: Duration) -> bool {
        let idle = crate::ecs::settle(&mut self.world, &mut self.schedule, timeout);
        self.world.clear_trackers();
        idle
    }

    /// The running builds' progress (`None` when none runs): what `strata watch`
    /// prints and `strata view` shows in its title.
    pub fn progress(&self) -> Option<String> {
        self.world.resource::<PreprocessProgress>().summary()
    }

    /// How many builds started, completed, were cancelled or failed.
    pub fn builds(&self) -> JobCounts {
        self.world.resource::<PreprocessJobs>().counts()
    }

    /// The mesh entity driven by the scene, once a good scene was applied.
    pub fn mesh_entity(&self) -> Option<Entity> {
        self.world
            .get_resource::<SceneState>()
            .and_then(|s| s.entity)
    }

    /// The current samples (empty before the first good scene).
    pub fn samples(&self) -> &[strata_engine::sample::Sample] {
        self.mesh_entity()
            .and_then(|e| self.world.get::<SampleBuffer>(e))
            .map_or(&[], |b| b.samples.as_slice())
    }

    /// How many times the samples were rewritten.
    pub fn sample_generation(&self) -> u64 {
        self.mesh_entity()
            .and_then(|e| self.world.get::<SampleBuffer>(e))
            .map_or(0, |b| b.generation)
    }

    /// The per-stage statistics.
    pub fn stats(&self) -> &StageStats {
        self.world.resource::<StageStats>()
    }

    /// Clears the per-stage statistics.
    pub fn clear_stats(&mut self) {
        self.world.resource_mut::<StageStats>().clear();
    }

    /// Takes the errors reported since the last call.
    pub fn take_errors(&mut self) -> Vec<EngineError> {
        std::mem::take(&mut self.world.resource_mut::<EngineErrors>().0)
    }
}
