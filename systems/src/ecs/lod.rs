//! View-dependent level of detail in the ECS engine (issue 19): a mesh entity with a
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
//! base count or the budget changes: that is preprocessing-sized work and, like the
//! other preprocessing systems, still runs inside the update (issue 20).

use std::time::Instant;

use bevy_ecs::prelude::*;
use strata_engine::sample::lod::ViewLod;
use strata_engine::sample::{LodPool, PoolChange};

use super::EngineError;
use super::components::{MeshSampler, MeshTransform, SamplingSettings};
use super::stats::{EngineErrors, Stage, StageStats};

/// Level of detail of a mesh entity: the camera (plain data, updated by the
/// application every frame), the base count and the pool's budget.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Lod {
    /// The camera's multiplier settings ([`ViewLod`]).
    pub view: ViewLod,
    /// Samples over the whole surface at multiplier 1; the pool holds ranks `0..base`.
    pub base: u32,
    /// Entries the pool may add beyond `base` where views ask for them.
    pub budget: usize,
}

/// The pool of a [`Lod`] entity and what its last update did.
#[derive(Component, Debug, Default)]
pub struct LodState {
    /// The pool; `None` until the entity has a sampler.
    pub pool: Option<LodPool>,
    /// The last update's change.
    pub last: Option<PoolChange>,
    /// Times the pool was built or rebuilt (a GPU copy resends everything when it
    /// moves).
    pub builds: u64,
    /// `(base, budget, seed)` the pool was built with.
    built_for: Option<(u32, usize, u64)>,
}

/// Brings every [`Lod`] entity's pool up to its camera (see the module docs).
#[allow(clippy::type_complexity)]
pub fn update_lod_pools(
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
        if sampler.is_changed() || state.built_for != Some(key) || state.pool.is_none() {
            state.pool = Some(LodPool::new(s, sampling.seed, lod.base, lod.budget));
            state.built_for = Some(key);
            state.builds += 1;
        }
        let Some(pool) = state.pool.as_mut() else {
            continue;
        };
        let change = pool.update(s, &view, f64::from(lod.base));
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
