//! Preprocessing from Python: the mesh, the field and the engine's front door run on a
//! worker thread while the calling thread, without the GIL, waits for it, polls
//! Python's signal handlers (Ctrl-C cancels the build through the engine's
//! [`BuildControl`] and raises `KeyboardInterrupt`) and draws an optional progress
//! line on standard error.
//!
//! Input: vertices, triangles, a [`Field`] and [`SurfaceOptions`]. Output: a
//! [`Built`] sampler with its report. A flat mesh takes the planar path of
//! [`Preprocessed::build`]; any other mesh the surface path of
//! [`incremental::rebuild`] from nothing, which is bit for bit
//! [`Preprocessed::build_surface`], the path `Preprocessed::build` takes for it, and
//! can be cancelled. Cost: that of the engine's preprocessing, plus a wake-up of the
//! waiting thread every 50 ms (it wakes at once when the build ends).

use std::io::Write;
use std::sync::Arc;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

use glam::DVec3;
use pyo3::prelude::*;
use strata_engine::field::TensorField;
use strata_engine::mesh::TriMesh;
use strata_engine::planar::{self, PlanarError};
use strata_engine::sample::Sampler;
use strata_engine::segment::detect_singularities;
use strata_engine::surface::incremental::{self, BuildControl, BuildInputs};
use strata_engine::surface::{Preprocessed, SegmentationKind, SurfaceError, SurfaceOptions};

use crate::field::Field;

/// How often the waiting thread checks for signals and redraws the progress line.
const POLL: Duration = Duration::from_millis(50);
/// Builds shorter than this show no progress line, unless the environment variable
/// `STRATA_PROGRESS_AFTER` gives another delay in seconds (0: from the start).
const QUIET: Duration = Duration::from_secs(1);

/// The delay before the progress line: [`QUIET`], or `STRATA_PROGRESS_AFTER` seconds
/// where that is a finite number of at least 0.
fn quiet() -> Duration {
    std::env::var("STRATA_PROGRESS_AFTER")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map_or(QUIET, Duration::from_secs_f64)
}

/// A preprocessed surface and what the preprocessing did.
pub struct Built {
    /// The engine's sampler.
    pub sampler: Sampler,
    /// `"planar"` (one linear map) or `"surface"` (segmentation and parameterization).
    pub path: &'static str,
    /// Final segments.
    pub segments: usize,
    /// Singular faces of the field the segmentation worked with (0 on the planar path
    /// and for an isotropic field's charts).
    pub singularities: usize,
    /// Splits of invalid segments.
    pub splits: usize,
    /// Merges of valid neighbouring pieces.
    pub merges: usize,
    /// Adaptive Hilbert cells over all segments.
    pub cells: usize,
    /// Wall time of each stage, in order (`mesh` and `field` first).
    pub stages: Vec<(&'static str, Duration)>,
}

/// Why preprocessing failed.
pub enum Failure {
    /// The input (mesh, field or options) was refused: the engine's message.
    Input(String),
    /// Python raised while the build was waited for (`KeyboardInterrupt`).
    Interrupted(PyErr),
}

/// Builds mesh, field and sampler on a worker thread, with the GIL released; Ctrl-C
/// cancels. `progress` draws a line on standard error for builds over a second.
pub fn preprocess(
    py: Python<'_>,
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    field: Field,
    options: SurfaceOptions,
    progress: bool,
) -> Result<Built, Failure> {
    let control = BuildControl::new();
    let (result, interrupt) = py.detach(|| {
        std::thread::scope(|s| {
            // The worker says when it is done, so the build's result is taken at once,
            // not at the next poll.
            let (done, finished) = mpsc::channel::<()>();
            let (field, options, building) = (&field, &options, &control);
            let worker = s.spawn(move || {
                let result = build(positions, triangles, field, options, building);
                let _ = done.send(());
                result
            });
            let started = Instant::now();
            let quiet = quiet();
            let mut interrupt = None;
            let mut drawn = false;
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(POLL) {
                if interrupt.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    control.cancel();
                    interrupt = Some(e);
                }
                if progress && started.elapsed() >= quiet {
                    draw(&control, started.elapsed());
                    drawn = true;
                }
            }
            if drawn {
                eprint!("\r\x1b[2K");
                let _ = std::io::stderr().flush();
            }
            let result = worker
                .join()
                .unwrap_or_else(|_| Err("preprocessing panicked".to_string()));
            (result, interrupt)
        })
    });
    if let Some(e) = interrupt {
        return Err(Failure::Interrupted(e));
    }
    result.map_err(Failure::Input)
}

/// The progress line: stage, items done and time.
fn draw(control: &BuildControl, elapsed: Duration) {
    let p = control.progress();
    let items = if p.total > 0 {
        format!(" {}/{}", p.done, p.total)
    } else {
        String::new()
    };
    eprint!(
        "\r\x1b[2Kstrata: preprocessing: {}{items} ({:.1} s)",
        p.stage.name(),
        elapsed.as_secs_f64()
    );
    let _ = std::io::stderr().flush();
}

/// Mesh, field, then the planar or the surface path (see the module docs).
fn build(
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    field: &Field,
    options: &SurfaceOptions,
    control: &BuildControl,
) -> Result<Built, String> {
    let t = Instant::now();
    let mesh = Arc::new(TriMesh::new(positions, triangles).map_err(|e| format!("mesh: {e}"))?);
    let mut stages = vec![("mesh", t.elapsed())];
    let t = Instant::now();
    let field = Arc::new(field.build(&mesh)?);
    stages.push(("field", t.elapsed()));
    options.validate().map_err(|e| e.to_string())?;
    match planar::planar_map(&mesh, &field) {
        Err(PlanarError::NotPlanar { .. }) => surface(mesh, field, options, control, stages),
        _ => planar(mesh, field, options, stages),
    }
}

/// The engine's front door on a flat mesh (its planar path).
fn planar(
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    options: &SurfaceOptions,
    mut stages: Vec<(&'static str, Duration)>,
) -> Result<Built, String> {
    let pre = Preprocessed::build(mesh, field, options).map_err(|e| e.to_string())?;
    stages.extend(pre.stages.iter().copied());
    Ok(Built {
        path: if pre.planar_map().is_some() {
            "planar"
        } else {
            "surface"
        },
        segments: pre.report.segments,
        singularities: pre.segmentation.singularities.len(),
        splits: pre.report.splits,
        merges: pre.report.merges,
        cells: pre.report.cells,
        sampler: pre.sampler,
        stages,
    })
}

/// The surface path, cancellable through `control`.
fn surface(
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    options: &SurfaceOptions,
    control: &BuildControl,
    mut stages: Vec<(&'static str, Duration)>,
) -> Result<Built, String> {
    let inputs = BuildInputs {
        mesh: mesh.clone(),
        field,
        options: *options,
    };
    let outcome = incremental::rebuild(inputs, None, control).map_err(|e| match e {
        SurfaceError::Cancelled => "preprocessing cancelled".to_string(),
        e => e.to_string(),
    })?;
    stages.extend(outcome.runs.iter().map(|r| (r.stage.name(), r.took)));
    let state = &outcome.state;
    let singularities = match state.kind {
        SegmentationKind::IsotropicCharts => 0,
        SegmentationKind::FieldAligned { .. } => {
            detect_singularities(&mesh, &state.working_field).len()
        }
    };
    let pieces = state.segments.iter().map(|s| &s.pieces);
    let sampler = outcome
        .sampler
        .ok_or_else(|| "the build made no sampler".to_string())?;
    Ok(Built {
        path: "surface",
        segments: sampler.segments().len(),
        singularities,
        splits: pieces.clone().map(|p| p.report.splits).sum(),
        merges: pieces.map(|p| p.report.merges).sum(),
        cells: sampler
            .segments()
            .iter()
            .map(|s| s.curve.cell_count())
            .sum(),
        sampler,
        stages,
    })
}
