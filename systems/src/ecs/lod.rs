//! View-dependent level of detail in the ECS engine: a mesh entity with a
//! [`Lod`] component keeps a progressive pool ([`LodPool`]) of its sampler's sequence
//! in [`LodState`], and [`update_lod_pools`] brings it up to the `Lod`'s camera every
//! update: only the ranks the view adds are drawn. The visible set (ranks under the
//! camera's threshold) is then picked per sample on the GPU
//! ([`SplatLod`](crate::gpu::SplatLod)); [`crate::gpu::upload`] streams the new entries.
//!
//! The camera is in world space; a mesh placed by a [`MeshTransform`] (a similarity) is
//! sampled in its own frame, so the pool is updated with the camera taken into that frame
//! ([`ViewLod::in_local_frame`]): the ranks it holds are those a renderer of the placed
//! mesh shows. Another transform is an [`EngineError::Lod`] and leaves the pool as it was.
//!
//! The pool is rebuilt (ranks `0..base` drawn again) when the sampler, the seed, the
//! base count or the budget changes. That is preprocessing-sized work (about a second
//! for 3 x 10^6 ranks), so it runs on the build pool ([`super::jobs`]), like a build:
//! meanwhile the old pool keeps following the camera with the sampler it was drawn
//! from, and the new pool replaces both in one update when it is ready
//! ([`PreprocessMode::Blocking`] builds it inside
//! the update instead).
//!
//! [`update_lod_pools`] runs on the thread that runs the schedule (it takes a
//! [`NonSendMarker`](bevy_ecs::system::NonSendMarker)). The update's parallel work then
//! starts at once when that thread is a rayon worker
//! ([`join_rayon_pool`](crate::frame_thread::join_rayon_pool), which the `strata`
//! binary calls at start-up). From a thread outside rayon's pool (a bevy thread, or a schedule
//! thread not in the pool), the update waits for a sleeping rayon worker to wake: on the
//! bunny's 1% dolly in (2-core virtual machine) it takes 3.5-4.0 ms that way against
//! 2.7-2.9 ms (the `lod_ecs` bench; bench/README.md).

use std::time::Instant;

use bevy_ecs::prelude::*;
use crossbeam_channel::Receiver;
use strata_engine::sample::lod::{Budget, FrameUpdate, ViewLod};
use strata_engine::sample::{LodPool, PoolChange, Sampler};

use super::components::{MeshSampler, MeshTransform, SamplingSettings};
use super::jobs::{PreprocessJobs, PreprocessMode, TaskToken, preprocess_pool};
use super::stats::{EngineErrors, Stage, StageStats};
use super::{EngineError, EngineSettings};

/// Level of detail of a mesh entity: the camera (plain data, updated by the
/// application every frame), the base count and the pool's budget.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Lod {
    /// The camera's multiplier settings ([`ViewLod`]).
    pub view: ViewLod,
    /// Samples over the whole surface at multiplier 1; the pool holds ranks `0..base`.
    pub base: u32,
    /// Entries the pool may add beyond `base` where views ask for them
    /// ([`LodPool::room_for`] gives room for close views).
    pub budget: usize,
    /// A point budget: when set, every update thresholds with the base count under
    /// which the camera shows about this many samples
    /// ([`Budget::Shown`]; within 3% on the bunny, near or far), instead of `base`
    /// (which stays the pool's prefix, and the base count of a view of nothing). The
    /// base count used is [`LodState::base`]: a renderer draws with it.
    pub shown: Option<u32>,
}

/// The pool of a [`Lod`] entity and what its last update did.
#[derive(Component, Debug, Default)]
pub struct LodState {
    /// The pool; `None` until the entity has a sampler.
    pub pool: Option<LodPool>,
    /// The last update's change.
    pub last: Option<PoolChange>,
    /// CPU time of the last update (the point budget's base count, new ranks and their
    /// sites), whether or not it drew anything.
    pub update: std::time::Duration,
    /// The base count the last update thresholded with: [`Lod::base`], or the point
    /// budget's ([`Lod::shown`], rounded to `f32` as a renderer's uniform holds it).
    pub base: f64,
    /// Times the pool was built or rebuilt (a GPU copy resends everything when it
    /// moves).
    pub builds: u64,
    /// `(base, budget, seed)` the pool was built with.
    built_for: Option<(u32, usize, u64)>,
    /// The sampler the pool was drawn from: the pool's ranks are its sequence's, so the
    /// pool is extended with it (the pool checks it: [`LodPool::drawn_from`]) until a
    /// pool of a newer sampler replaces both.
    drawn_from: Option<Sampler>,
    /// A pool building off the frame, and what it is built for.
    building: Option<PendingPool>,
}

/// A pool being built on the build pool.
#[derive(Debug)]
struct PendingPool {
    key: (u32, usize, u64),
    receiver: Receiver<(LodPool, Sampler)>,
    /// Keeps the engine from counting as idle until the pool is taken.
    _task: TaskToken,
}

/// Brings every [`Lod`] entity's pool up to its camera (see the module docs).
#[allow(clippy::type_complexity)]
pub fn update_lod_pools(
    // On the schedule's own thread (see the module docs).
    _schedule_thread: bevy_ecs::system::NonSendMarker,
    settings: Res<EngineSettings>,
    jobs: Res<PreprocessJobs>,
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    mut meshes: Query<(
        Entity,
        Ref<MeshSampler>,
        &SamplingSettings,
        &Lod,
        Option<&MeshTransform>,
        &mut LodState,
    )>,
) {
    for (entity, sampler, sampling, lod, transform, mut state) in &mut meshes {
        let Some(s) = sampler.0.as_ref() else {
            continue;
        };
        let view = match transform.map(|t| lod.view.in_local_frame(&t.0)) {
            None => lod.view,
            Some(Ok(view)) => view,
            Some(Err(e)) => {
                errors.0.push(EngineError::Lod(e));
                continue;
            }
        };
        let key = (lod.base, lod.budget, sampling.seed);
        let state = &mut *state;
        let t = Instant::now();
        // The key of the pool in use or being built.
        let target = state.building.as_ref().map(|b| b.key).or(state.built_for);
        if sampler.is_changed() || target != Some(key) {
            rebuild_pool(state, s, key, settings.preprocess, &jobs);
        }
        state.take_built();
        let (Some(pool), Some(s)) = (state.pool.as_mut(), state.drawn_from.as_ref()) else {
            continue; // the first pool is still building
        };
        let budget = Budget::new(f64::from(lod.base), lod.shown);
        // The pool refuses any sampler but its own: a mismatch is reported, never drawn.
        let FrameUpdate { change, base } = match pool.update(s, &view, budget) {
            Ok(frame) => frame,
            Err(e) => {
                errors.0.push(EngineError::Lod(e));
                continue;
            }
        };
        state.base = base;
        state.update = t.elapsed();
        if change != PoolChange::Unchanged {
            stats.record(
                Stage::Sampling,
                entity,
                pool.len(),
                t.elapsed(),
                "lod pool".into(),
            );
        }
        state.last = Some(change);
    }
}

impl LodState {
    /// The sampler the pool was drawn from (its sites index that sampler's segments).
    pub fn drawn_from(&self) -> Option<&Sampler> {
        self.drawn_from.as_ref()
    }

    /// Puts a pool built off the frame in use, with the sampler it was drawn from; the
    /// ones it replaces are dropped on the build pool (a large pool takes milliseconds
    /// to free).
    fn take_built(&mut self) {
        let Some(b) = &self.building else {
            return;
        };
        if let Ok((pool, drawn_from)) = b.receiver.try_recv() {
            self.built_for = Some(b.key);
            let old = (self.pool.replace(pool), self.drawn_from.replace(drawn_from));
            if let Some(threads) = preprocess_pool() {
                threads.spawn(move || drop(old));
            }
            self.builds += 1;
            self.building = None;
        }
    }
}

/// Starts building the pool of `sampler` for `key` (replacing a build in flight, whose
/// result is then dropped), on the build pool or, blocking, right here.
fn rebuild_pool(
    state: &mut LodState,
    sampler: &Sampler,
    key: (u32, usize, u64),
    mode: PreprocessMode,
    jobs: &PreprocessJobs,
) {
    let (sender, receiver) = crossbeam_channel::bounded(1);
    let sampler = sampler.clone();
    let (base, budget, seed) = key;
    let work = move || {
        let pool = LodPool::new(&sampler, seed, base, budget);
        let _ = sender.send((pool, sampler));
    };
    state.building = Some(PendingPool {
        key,
        receiver,
        _task: jobs.task_token(),
    });
    match (mode, preprocess_pool()) {
        (PreprocessMode::Background, Some(pool)) => pool.spawn(work),
        _ => work(),
    }
}

#[cfg(test)]
mod tests {
    use bevy_ecs::system::{IntoSystem, System};
    use bevy_ecs::world::World;

    use super::update_lod_pools;

    /// The update runs on the schedule's thread, which the binary makes a rayon worker
    /// (`frame_thread`): removing the marker lets the executor move it to bevy's
    /// threads, where its parallel work waits for a worker to wake.
    #[test]
    fn the_update_runs_on_the_schedules_thread() {
        let mut system = IntoSystem::into_system(update_lod_pools);
        system.initialize(&mut World::new());
        assert!(!system.is_send());
    }
}
