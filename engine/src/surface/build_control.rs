//! Cancellation and progress of an incremental build
//! ([`rebuild`](super::incremental::rebuild)): a [`BuildControl`] shared between the
//! build and its owner, read and cancelled from any thread.

use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};

use super::SurfaceError;

/// A stage of an incremental build, as [`BuildControl::progress`] reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BuildStage {
    /// Not started yet.
    Queued,
    /// Preparing the field and segmenting (the whole mesh or a region).
    Segmentation,
    /// Parameterizing new segments, splitting invalid ones.
    Parameterization,
    /// Building adaptive Hilbert cells.
    Cells,
    /// Ordering the segments and linking them into chains.
    Chains,
    /// Done (successfully or not).
    Finished,
}

impl BuildStage {
    const ALL: [BuildStage; 6] = [
        BuildStage::Queued,
        BuildStage::Segmentation,
        BuildStage::Parameterization,
        BuildStage::Cells,
        BuildStage::Chains,
        BuildStage::Finished,
    ];

    /// The stage's name as printed.
    pub fn name(self) -> &'static str {
        match self {
            BuildStage::Queued => "queued",
            BuildStage::Segmentation => "segmentation",
            BuildStage::Parameterization => "parameterization",
            BuildStage::Cells => "cells",
            BuildStage::Chains => "chains",
            BuildStage::Finished => "finished",
        }
    }
}

/// Where a build is: its stage and how many of the stage's items are done.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildProgress {
    /// The current stage.
    pub stage: BuildStage,
    /// Items of the stage done (segments; 0 or 1 for segmentation).
    pub done: usize,
    /// Items of the stage in all.
    pub total: usize,
}

impl BuildProgress {
    /// The share of the stage done, in [0, 1] (0 for a stage of no items).
    pub fn fraction(&self) -> f64 {
        if self.total == 0 {
            0.0
        } else {
            (self.done as f64 / self.total as f64).min(1.0)
        }
    }
}

/// Called when a build enters a stage (with the control, so it may cancel).
type Observer = Box<dyn Fn(&BuildControl, BuildStage) + Send + Sync>;

/// Shared between a running [`rebuild`](super::incremental::rebuild) and its owner:
/// the owner cancels it and reads
/// its progress from any thread; the build checks for cancellation between stages and
/// between segments.
#[derive(Default)]
pub struct BuildControl {
    cancelled: AtomicBool,
    stage: AtomicU8,
    done: AtomicUsize,
    total: AtomicUsize,
    observer: Option<Observer>,
}

impl std::fmt::Debug for BuildControl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BuildControl")
            .field("cancelled", &self.is_cancelled())
            .field("progress", &self.progress())
            .finish()
    }
}

impl BuildControl {
    /// A control for a build not started yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A control that calls `observer` whenever the build enters a stage (logging, or
    /// cancelling at a chosen point).
    pub fn with_observer(
        observer: impl Fn(&BuildControl, BuildStage) + Send + Sync + 'static,
    ) -> Self {
        Self {
            observer: Some(Box::new(observer)),
            ..Self::default()
        }
    }

    /// Asks the build to stop: it returns [`SurfaceError::Cancelled`] at its next
    /// check (between stages, or before its next segment).
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    /// Whether [`cancel`](Self::cancel) was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }

    /// The build's stage and its items done.
    pub fn progress(&self) -> BuildProgress {
        let stage = BuildStage::ALL
            .get(usize::from(self.stage.load(Ordering::Relaxed)))
            .copied()
            .unwrap_or(BuildStage::Finished);
        BuildProgress {
            stage,
            done: self.done.load(Ordering::Relaxed),
            total: self.total.load(Ordering::Relaxed),
        }
    }

    /// Enters `stage` with `total` items, after checking for cancellation.
    pub(super) fn enter(&self, stage: BuildStage, total: usize) -> Result<(), SurfaceError> {
        self.check()?;
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.stage.store(stage as u8, Ordering::Relaxed);
        if let Some(observer) = &self.observer {
            observer(self, stage);
        }
        Ok(())
    }

    /// One item of the current stage done.
    pub(super) fn advance(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    /// `Err(Cancelled)` once cancelled.
    pub(super) fn check(&self) -> Result<(), SurfaceError> {
        if self.is_cancelled() {
            Err(SurfaceError::Cancelled)
        } else {
            Ok(())
        }
    }

    pub(super) fn finish(&self) {
        self.stage
            .store(BuildStage::Finished as u8, Ordering::Relaxed);
    }
}
