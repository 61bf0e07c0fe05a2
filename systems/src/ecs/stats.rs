//! Per-stage statistics: which stage ran, for which entity, on how many items, and
//! how long it took. Tests assert on them; `strata watch` prints them.

use std::fmt;
use std::time::Duration;

use bevy_ecs::prelude::*;

/// A stage of the streaming engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// Applying a changed scene (loading a mesh, building a field).
    Scene,
    /// Segmentation (whole mesh, or the region a field change touched).
    Segmentation,
    /// Parameterization with splitting, per new or changed segment.
    Parameterization,
    /// Adaptive Hilbert cells, per segment whose parameterization or omega changed.
    Curves,
    /// Assembling the sampler: the segments' cells in order, linked into chains.
    Chains,
    /// Drawing the samples into the mesh's sample buffer.
    Sampling,
}

impl Stage {
    /// Every stage, in pipeline order.
    pub const ALL: [Stage; 6] = [
        Stage::Scene,
        Stage::Segmentation,
        Stage::Parameterization,
        Stage::Curves,
        Stage::Chains,
        Stage::Sampling,
    ];

    /// The stage's name as printed.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Scene => "scene",
            Stage::Segmentation => "segmentation",
            Stage::Parameterization => "parameterization",
            Stage::Curves => "curves",
            Stage::Chains => "chains",
            Stage::Sampling => "sampling",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One run of a stage.
#[derive(Clone, Debug, PartialEq)]
pub struct StageRun {
    /// The stage.
    pub stage: Stage,
    /// The mesh entity it ran for.
    pub entity: Entity,
    /// How many items it processed: segments for segmentation (segments produced),
    /// parameterization and curves; segments assembled for chains; samples for
    /// sampling; 1 for the scene.
    pub items: usize,
    /// Wall time.
    pub took: Duration,
    /// The update (schedule run) it happened in.
    pub update: u64,
    /// A short note (for example "region of 812 faces").
    pub note: String,
}

/// Runs kept at most; older ones are dropped first (an application that never clears
/// the statistics does not grow without bound).
pub const MAX_RUNS: usize = 4096;

/// Every stage run since the last [`clear`](Self::clear) (at most [`MAX_RUNS`], the
/// newest), and the update counter.
#[derive(Resource, Clone, Debug, Default)]
pub struct StageStats {
    /// The current update (incremented at the start of every schedule run).
    pub update: u64,
    /// The runs, oldest first.
    pub runs: Vec<StageRun>,
}

impl StageStats {
    /// Records a run in the current update.
    pub fn record(
        &mut self,
        stage: Stage,
        entity: Entity,
        items: usize,
        took: Duration,
        note: String,
    ) {
        if self.runs.len() >= MAX_RUNS {
            self.runs.drain(..MAX_RUNS / 2);
        }
        self.runs.push(StageRun {
            stage,
            entity,
            items,
            took,
            update: self.update,
            note,
        });
    }

    /// Forgets all runs.
    pub fn clear(&mut self) {
        self.runs.clear();
    }

    /// How many times `stage` ran since the last clear.
    pub fn runs_of(&self, stage: Stage) -> usize {
        self.runs.iter().filter(|r| r.stage == stage).count()
    }

    /// Items `stage` processed since the last clear.
    pub fn items_of(&self, stage: Stage) -> usize {
        self.runs
            .iter()
            .filter(|r| r.stage == stage)
            .map(|r| r.items)
            .sum()
    }

    /// Total wall time of `stage` since the last clear.
    pub fn time_of(&self, stage: Stage) -> Duration {
        self.runs
            .iter()
            .filter(|r| r.stage == stage)
            .map(|r| r.took)
            .sum()
    }

    /// The stages that ran since the last clear, in pipeline order.
    pub fn stages_run(&self) -> Vec<Stage> {
        Stage::ALL
            .into_iter()
            .filter(|&s| self.runs_of(s) > 0)
            .collect()
    }
}

/// Errors met by the engine's systems since they were last taken; the state they
/// would have changed is left as it was.
#[derive(Resource, Debug, Default)]
pub struct EngineErrors(pub Vec<crate::ecs::EngineError>);

/// Advances the update counter; runs first in every update.
pub fn begin_update(mut stats: ResMut<StageStats>) {
    stats.update += 1;
}
