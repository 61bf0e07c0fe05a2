//! Preprocessing: a blocking build, and a background build the host polls from its
//! frame (start, poll its stage and progress, cancel, take the sampler).
//!
//! Both run the streaming engine's build, `surface::incremental::rebuild` (a first
//! build of it is bit for bit the surface pipeline), with its `BuildControl` for
//! progress and cancellation; the background one runs on the streaming engine's own
//! low-priority build pool (`strata_systems::ecs::preprocess_pool`), so the host's
//! frame never waits for it. So the same inputs give the same sampler, bit for bit,
//! from either call and from the ECS engine.
//!
//! Cost: that of the build; a poll reads four atomics.

#![allow(unsafe_code)] // `#[unsafe(no_mangle)]` exports only; see `handle.rs` for the rest.

use std::ffi::c_char;
use std::sync::{Arc, Mutex};

use strata_engine::sample::Sampler;
use strata_engine::surface::SurfaceOptions;
use strata_engine::surface::incremental::{BuildControl, BuildInputs, BuildStage, rebuild};
use strata_engine::surface::{SurfaceError, incremental::BuildOutcome};
use strata_systems::ecs::preprocess_pool;

use crate::handle::{
    Failure, Handle, Kind, Outcome, StrataStatus, borrow, check_struct_size, engine_error, guard,
    register, release, require_out, slice, text, write_out,
};
use crate::mesh::StrataField;
use crate::sample::StrataSampler;

/// Build settings, for `strata_build` and `strata_build_start`. A null pointer means
/// the field's settings.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct StrataBuildOptions {
    /// `sizeof(StrataBuildOptions)`.
    pub struct_size: u32,
    /// The engine's `SurfaceOptions` in RON (for example
    /// `"(curve: (max_cells: 4096))"`; omitted settings keep their defaults), or null
    /// for the field's settings (a scene's, or the defaults).
    pub surface_ron: *const c_char,
}

/// A background build (opaque). Any thread may poll, cancel or take it; `take`
/// succeeds once. Freeing a running build cancels it (the build thread stops at its
/// next check and drops its result).
pub struct StrataBuild {
    control: Arc<BuildControl>,
    slot: Arc<Mutex<Slot>>,
}

impl Handle for StrataBuild {
    const KIND: Kind = Kind::Build;
}

/// Where a background build's result is.
enum Slot {
    Running,
    Done(Box<Result<Sampler, SurfaceError>>),
    Taken,
}

/// `StrataBuildProgress::stage`: waiting for a build thread.
pub const STRATA_STAGE_QUEUED: u32 = 0;
/// Preparing the field and segmenting.
pub const STRATA_STAGE_SEGMENTATION: u32 = 1;
/// Parameterizing segments, splitting invalid ones.
pub const STRATA_STAGE_PARAMETERIZATION: u32 = 2;
/// Building adaptive Hilbert cells.
pub const STRATA_STAGE_CELLS: u32 = 3;
/// Linking segments into chains.
pub const STRATA_STAGE_CHAINS: u32 = 4;
/// Done: successfully, with an error, or cancelled (`strata_build_take` says which).
pub const STRATA_STAGE_FINISHED: u32 = 5;

/// A background build's state, as `strata_build_poll` writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataBuildProgress {
    /// One of the `STRATA_STAGE_` values.
    pub stage: u32,
    /// 1 when the result can be taken (`stage` is `STRATA_STAGE_FINISHED`), else 0.
    pub finished: u32,
    /// Items of the stage done (segments).
    pub done: u64,
    /// Items of the stage in all (0 when the stage does not count items).
    pub total: u64,
    /// `done / total` in [0, 1] (0 for a stage of no items).
    pub fraction: f64,
}

fn stage_code(stage: BuildStage) -> u32 {
    match stage {
        BuildStage::Queued => STRATA_STAGE_QUEUED,
        BuildStage::Segmentation => STRATA_STAGE_SEGMENTATION,
        BuildStage::Parameterization => STRATA_STAGE_PARAMETERIZATION,
        BuildStage::Cells => STRATA_STAGE_CELLS,
        BuildStage::Chains => STRATA_STAGE_CHAINS,
        BuildStage::Finished => STRATA_STAGE_FINISHED,
    }
}

/// The build's inputs from the field handle and the caller's options.
fn inputs(field: *const StrataField, options: *const StrataBuildOptions) -> Outcome<BuildInputs> {
    let field = borrow(field, "field")?;
    let mut surface = field.options;
    if !options.is_null() {
        let options = &slice(options, 1, "options")?[0];
        check_struct_size(
            options.struct_size,
            size_of::<StrataBuildOptions>(),
            "StrataBuildOptions",
        )?;
        if !options.surface_ron.is_null() {
            surface = ron::from_str::<SurfaceOptions>(text(options.surface_ron, "surface_ron")?)
                .map_err(|e| engine_error(StrataStatus::Config, "surface_ron", e))?;
        }
    }
    surface
        .validate()
        .map_err(|e| engine_error(StrataStatus::InvalidArgument, "surface options", e))?;
    Ok(BuildInputs {
        mesh: field.mesh.clone(),
        field: field.field.clone(),
        options: surface,
    })
}

/// The sampler of a finished build, or its error as a failure.
fn sampler_of(result: Result<BuildOutcome, SurfaceError>) -> Result<Sampler, SurfaceError> {
    result?.sampler.ok_or(SurfaceError::Cancelled)
}

fn failure_of(error: SurfaceError) -> Failure {
    match error {
        SurfaceError::Cancelled => Failure::new(StrataStatus::Cancelled, "build: cancelled"),
        other => engine_error(StrataStatus::Build, "build", other),
    }
}

/// Preprocesses `field`'s mesh on the calling thread and returns its sampler.
///
/// # Safety
/// `field` is a handle from this library; `options` is null or a valid
/// `StrataBuildOptions`; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build(
    field: *const StrataField,
    options: *const StrataBuildOptions,
    out: *mut *mut StrataSampler,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let inputs = inputs(field, options)?;
        let sampler =
            sampler_of(rebuild(inputs, None, &BuildControl::new())).map_err(failure_of)?;
        write_out(out, register(StrataSampler::new(sampler)), "out")
    })
}

/// Starts preprocessing `field`'s mesh on the build pool and returns at once; poll it
/// with `strata_build_poll`, take the sampler with `strata_build_take`.
///
/// # Safety
/// As `strata_build`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build_start(
    field: *const StrataField,
    options: *const StrataBuildOptions,
    out: *mut *mut StrataBuild,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let inputs = inputs(field, options)?;
        let control = Arc::new(BuildControl::new());
        let slot = Arc::new(Mutex::new(Slot::Running));
        let (job_control, job_slot) = (control.clone(), slot.clone());
        let job = move || {
            let result = sampler_of(rebuild(inputs, None, &job_control));
            *job_slot.lock().unwrap_or_else(|e| e.into_inner()) = Slot::Done(Box::new(result));
        };
        match preprocess_pool() {
            Some(pool) => pool.spawn(job),
            None => rayon::spawn(job),
        }
        write_out(out, register(StrataBuild { control, slot }), "out")
    })
}

/// Writes the build's stage and progress into `progress`. Never blocks.
///
/// # Safety
/// `build` is a handle from this library; `progress` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build_poll(
    build: *const StrataBuild,
    progress: *mut StrataBuildProgress,
) -> StrataStatus {
    guard(|| {
        require_out(progress, "progress")?;
        let build = borrow(build, "build")?;
        let now = build.control.progress();
        let finished = !matches!(
            *build.slot.lock().unwrap_or_else(|e| e.into_inner()),
            Slot::Running
        );
        let value = StrataBuildProgress {
            stage: if finished {
                STRATA_STAGE_FINISHED
            } else {
                stage_code(now.stage).min(STRATA_STAGE_CHAINS)
            },
            finished: u32::from(finished),
            done: now.done as u64,
            total: now.total as u64,
            fraction: now.fraction(),
        };
        write_out(progress, value, "progress")
    })
}

/// Asks the build to stop (at its next check, between stages or segments); its
/// `strata_build_take` then fails with `STRATA_STATUS_CANCELLED`. Never blocks.
///
/// # Safety
/// `build` is a handle from this library.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build_cancel(build: *const StrataBuild) -> StrataStatus {
    guard(|| {
        borrow(build, "build")?.control.cancel();
        Ok(())
    })
}

/// Takes a finished build's sampler. `STRATA_STATUS_NOT_READY` while it runs (nothing
/// changes; poll again), `STRATA_STATUS_CANCELLED` or `STRATA_STATUS_BUILD` when it ended without
/// one, `STRATA_STATUS_INVALID_ARGUMENT` when its sampler was taken already. Never blocks.
///
/// # Safety
/// `build` is a handle from this library; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build_take(
    build: *const StrataBuild,
    out: *mut *mut StrataSampler,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let build = borrow(build, "build")?;
        let mut slot = build.slot.lock().unwrap_or_else(|e| e.into_inner());
        match std::mem::replace(&mut *slot, Slot::Taken) {
            Slot::Running => {
                *slot = Slot::Running;
                Err(Failure::new(
                    StrataStatus::NotReady,
                    "build: not finished yet (poll until finished)",
                ))
            }
            Slot::Taken => Err(Failure::new(
                StrataStatus::InvalidArgument,
                "build: its result was taken already",
            )),
            Slot::Done(result) => {
                let sampler = (*result).map_err(failure_of)?;
                write_out(out, register(StrataSampler::new(sampler)), "out")
            }
        }
    })
}

/// Frees a build (null: nothing), cancelling it if it runs.
///
/// # Safety
/// `build` is null or a handle from this library, used by no other call now.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_build_free(build: *mut StrataBuild) -> StrataStatus {
    guard(|| {
        if !build.is_null() {
            borrow(build.cast_const(), "build")?.control.cancel();
        }
        release(build, "build")
    })
}
