//! Hot reload of scene files: a watcher thread turns file changes into parsed scenes,
//! and a system applies them to the world at the start of the next update.
//!
//! The thread (notify) watches the folder of the scene file and the folders of the
//! files it names (mesh, field file), non-recursively, and matches file names, so that
//! editors that save by writing a temporary file and renaming it, and files deleted and
//! re-created, are seen. It reacts to `Access(Close(Write))`, `Modify(Name(_))` and
//! `Create(_)` only (plain `Modify` events arrive while a file is half written), waits
//! until no relevant event came for [`DEBOUNCE`], then parses the scene and sends the
//! result over a crossbeam channel: bursts of saves give one parse of the final file.
//!
//! [`apply_scene_updates`] drains the channel: a scene that failed to read, parse or
//! validate is reported (file, line, column, message) in [`EngineErrors`] and changes
//! nothing; of the good ones the newest is applied: the mesh is reloaded when its
//! source changed or its file changed on disk, the field rebuilt when its spec, the
//! mesh or its file changed, and the other settings set only when they differ, so
//! change detection sees only what changed. A scene that was bad at start-up is
//! picked up as soon as a good version is saved.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, select};
use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind};
use notify::{RecursiveMode, Watcher};

use crate::config::{ConfigError, MeshSource, SceneConfig};
use crate::ecs::components::*;
use crate::ecs::{EngineError, EngineErrors, EngineSystems, Stage, StageStats};

/// Quiet time after the last relevant file event before the scene is parsed.
pub const DEBOUNCE: Duration = Duration::from_millis(100);

/// A scene file read by the watcher.
#[derive(Debug)]
pub struct SceneUpdate {
    /// The scene, or why it could not be used.
    pub scene: Result<SceneConfig, ConfigError>,
    /// Files that changed on disk since the previous update (the scene file and the
    /// files it names), absolute.
    pub changed: Vec<PathBuf>,
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
/// in the channel when this returns; later ones follow each (debounced) change.
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
    let mut deps = dependencies(&first);
    for d in &deps {
        if let Some(dir) = d.parent() {
            // A missing folder is not fatal: the file may appear later in a new scene.
            let _ = watch_dir(&mut watcher, &mut watched, dir);
        }
    }
    let _ = out_tx.send(SceneUpdate {
        scene: first,
        changed: Vec::new(),
    });
    let thread = std::thread::Builder::new()
        .name("strata-scene-watcher".to_owned())
        .spawn(move || {
            let relevant = |event: &notify::Event, deps: &[PathBuf]| -> Vec<PathBuf> {
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
                    .filter(|p| **p == scene || deps.contains(p))
                    .cloned()
                    .collect()
            };
            loop {
                let mut changed: Vec<PathBuf> = Vec::new();
                // Wait for the first relevant event.
                select! {
                    recv(stop_rx) -> _ => return,
                    recv(raw_rx) -> event => match event {
                        Ok(Ok(e)) => changed.extend(relevant(&e, &deps)),
                        Ok(Err(_)) => {}
                        Err(_) => return,
                    },
                }
                if changed.is_empty() {
                    continue;
                }
                // Debounce: until DEBOUNCE passes without a relevant event.
                let mut deadline = Instant::now() + DEBOUNCE;
                loop {
                    let left = deadline.saturating_duration_since(Instant::now());
                    match raw_rx.recv_timeout(left) {
                        Ok(Ok(e)) => {
                            let more = relevant(&e, &deps);
                            if !more.is_empty() {
                                changed.extend(more);
                                deadline = Instant::now() + DEBOUNCE;
                            }
                        }
                        Ok(Err(_)) => {}
                        Err(RecvTimeoutError::Timeout) => break,
                        Err(RecvTimeoutError::Disconnected) => return,
                    }
                    if stop_rx.try_recv() != Err(crossbeam_channel::TryRecvError::Empty) {
                        return;
                    }
                }
                changed.sort();
                changed.dedup();
                let parsed = SceneConfig::load(&scene);
                let new_deps = dependencies(&parsed);
                if !new_deps.is_empty() {
                    for d in &new_deps {
                        if let Some(dir) = d.parent() {
                            let _ = watch_dir(&mut watcher, &mut watched, dir);
                        }
                    }
                    deps = new_deps;
                }
                if out_tx
                    .send(SceneUpdate {
                        scene: parsed,
                        changed,
                    })
                    .is_err()
                {
                    return; // the engine is gone
                }
            }
        })
        .map_err(|e| WatchError::Path(scene_dir, e))?;
    Ok((
        SceneWatcher {
            stop: Some(stop_tx),
            thread: Some(thread),
        },
        out_rx,
    ))
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
    if updates.is_empty() {
        return;
    }
    let mut changed: HashSet<PathBuf> = HashSet::new();
    let mut newest = None;
    for u in updates {
        changed.extend(u.changed);
        match u.scene {
            Ok(scene) => newest = Some(scene),
            Err(e) => world.resource_mut::<EngineErrors>().0.push(e.into()),
        }
    }
    let Some(config) = newest else {
        return;
    };
    let t = Instant::now();
    match apply_scene(world, config, &changed) {
        Ok((entity, note)) => {
            world
                .resource_mut::<StageStats>()
                .record(Stage::Scene, entity, 1, t.elapsed(), note);
        }
        Err(e) => world.resource_mut::<EngineErrors>().0.push(e),
    }
}

/// Applies one scene: loads what changed, sets components only where they differ.
fn apply_scene(
    world: &mut World,
    config: SceneConfig,
    changed: &HashSet<PathBuf>,
) -> Result<(Entity, String), EngineError> {
    let on_disk = |p: &Path| std::path::absolute(p).is_ok_and(|a| changed.contains(&a));
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
    let mesh_file_changed = matches!(&config.mesh, MeshSource::File(p) if on_disk(p));
    let field_file_changed = config.field.files().into_iter().any(on_disk);
    let reload_mesh =
        entity.is_none() || old.as_ref().is_none_or(|o| o.mesh != config.mesh) || mesh_file_changed;
    let mesh = match (reload_mesh, entity.and_then(|e| world.get::<MeshData>(e))) {
        (false, Some(m)) => m.0.clone(),
        _ => Arc::new(crate::scene::load_mesh(&config)?),
    };
    let rebuild_field =
        reload_mesh || old.as_ref().is_none_or(|o| o.field != config.field) || field_file_changed;
    let field = match (
        rebuild_field,
        entity.and_then(|e| world.get::<FieldData>(e)),
    ) {
        (false, Some(f)) => f.0.clone(),
        _ => Arc::new(config.field.build(&mesh)?),
    };
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
            if reload_mesh {
                entity.insert(MeshData(mesh));
                what.push("mesh");
            }
            if rebuild_field {
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
