//! Turning a [`SceneConfig`] into engine data: mesh, field and sampler.

use std::sync::Arc;
use std::time::{Duration, Instant};

use strata_engine::field::{FieldError, TensorField};
use strata_engine::mesh::{MeshError, TriMesh};
use strata_engine::sample::Sampler;
use strata_engine::surface::{Preprocessed, SurfaceError};

use crate::config::{MeshSource, SceneConfig};

/// A scene ready to sample.
#[derive(Debug)]
pub struct Scene {
    /// The mesh.
    pub mesh: Arc<TriMesh>,
    /// The field on it.
    pub field: Arc<TensorField>,
    /// The preprocessed sampler.
    pub sampler: Sampler,
    /// Wall time of each preprocessing stage, in order.
    pub stages: Vec<(&'static str, Duration)>,
    /// The surface preprocessing (segments, parameterizations), for curved meshes;
    /// `None` for flat meshes, which use one linear map.
    pub surface: Option<SurfaceSummary>,
}

/// What the surface preprocessing produced.
#[derive(Debug, Clone)]
pub struct SurfaceSummary {
    /// Segments after segmentation.
    pub segments_before_split: usize,
    /// Final segments.
    pub segments: usize,
    /// Splits of invalid segments.
    pub splits: usize,
    /// Merges of neighbouring pieces back into one valid segment.
    pub merges: usize,
    /// Segments with the isotropic fallback.
    pub isotropic_segments: usize,
    /// Singularities found.
    pub singularities: usize,
}

/// Errors building a scene, by stage.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Loading or building the mesh failed.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// Building the field failed.
    #[error("field: {0}")]
    Field(#[from] FieldError),
    /// Preprocessing failed (a flat domain's fast path or a surface's pipeline; the
    /// engine's front door picks which).
    #[error("{0}")]
    Surface(#[from] SurfaceError),
}

impl Scene {
    /// Loads the mesh, builds the field and preprocesses for sampling.
    pub fn build(config: &SceneConfig) -> Result<Self, SceneError> {
        let mut stages = Vec::new();
        let progress = progress_spinners();
        let (mesh, took) = stage(&progress, "mesh", || load_mesh(config));
        let mesh = Arc::new(mesh?);
        stages.push(("mesh", took));
        let (field, took) = stage(&progress, "field", || config.field.build(&mesh));
        let field = Arc::new(field?);
        stages.push(("field", took));
        let options = config.surface_options();
        // The engine's front door: one linear map for flat meshes (exact for
        // constant-frame fields), the full surface pipeline otherwise.
        let pre =
            Preprocessed::build_with_progress(mesh.clone(), field.clone(), &options, &progress)?;
        stages.extend(pre.stages.iter().copied());
        let surface = pre.planar_map().is_none().then_some(SurfaceSummary {
            segments_before_split: pre.report.segments_before_split,
            segments: pre.report.segments,
            splits: pre.report.splits,
            merges: pre.report.merges,
            isotropic_segments: pre.report.isotropic_segments,
            singularities: pre.segmentation.singularities.len(),
        });
        Ok(Self {
            mesh,
            field,
            sampler: pre.sampler,
            stages,
            surface,
        })
    }
}

/// Runs `work` as the stage `name` of `progress` (start, then done with its time) and
/// returns its result and wall time: loading and field building report like the
/// engine's stages, since on large meshes they take seconds too.
pub(crate) fn stage<T>(
    progress: &dyn Fn(strata_engine::surface::Progress),
    name: &'static str,
    work: impl FnOnce() -> T,
) -> (T, std::time::Duration) {
    use strata_engine::surface::Progress;
    progress(Progress::Start(name));
    let t = Instant::now();
    let out = work();
    let took = t.elapsed();
    progress(Progress::Done(name, took));
    (out, took)
}

/// Progress of the stages as spinners on standard error (hidden when it is not a
/// terminal, so logs and CI output stay clean).
pub(crate) fn progress_spinners() -> impl Fn(strata_engine::surface::Progress) {
    use strata_engine::surface::Progress;
    let bar = std::sync::Mutex::new(None::<indicatif::ProgressBar>);
    move |p| {
        let Ok(mut slot) = bar.lock() else { return };
        match p {
            Progress::Start(stage) => {
                let b = indicatif::ProgressBar::new_spinner();
                b.set_message(stage);
                b.enable_steady_tick(std::time::Duration::from_millis(100));
                *slot = Some(b);
            }
            Progress::Done(stage, took) => {
                if let Some(b) = slot.take() {
                    b.finish_with_message(format!("{stage}: {:.1} ms", took.as_secs_f64() * 1e3));
                }
            }
        }
    }
}

/// Largest coordinate magnitude of a placed mesh: samples are 32-bit floats (at most
/// 3.4e38), and their spacings and the renderer's arithmetic need room above the
/// coordinates.
pub const MAX_SAMPLE_COORDINATE: f64 = 1e36;

/// Smallest bounding-box diagonal of a placed mesh: its sample spacings (down to a
/// millionth of it for the largest counts) must stay normal 32-bit floats (1.2e-38).
pub const MIN_SAMPLE_EXTENT: f64 = 1e-30;

/// Loads or builds the scene's mesh, refusing one whose samples, placed by the scene's
/// transform, would not be representable as 32-bit floats
/// ([`MAX_SAMPLE_COORDINATE`], [`MIN_SAMPLE_EXTENT`]).
pub fn load_mesh(config: &SceneConfig) -> Result<TriMesh, MeshError> {
    let mesh = match &config.mesh {
        MeshSource::File(path) => strata_engine::io::load(path)?,
        MeshSource::Shape(shape) => shape.build()?,
    };
    let name = match &config.mesh {
        MeshSource::File(path) => path.clone(),
        MeshSource::Shape(_) => "the built-in shape".into(),
    };
    match sample_range_problem(&mesh, config.transform.scale, config.transform.translation) {
        None => Ok(mesh),
        Some(what) => Err(MeshError::Io {
            path: name,
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, what),
        }),
    }
}

/// Why `mesh`, scaled by `scale` and moved by `translation`, makes samples that 32-bit
/// floats cannot hold, or `None`.
fn sample_range_problem(mesh: &TriMesh, scale: f64, translation: [f64; 3]) -> Option<String> {
    let (lo, hi) = mesh.bounds();
    let reach = lo.abs().max(hi.abs()).max_element() * scale
        + glam::DVec3::from(translation).abs().max_element();
    let extent = (hi - lo).length() * scale;
    if reach > MAX_SAMPLE_COORDINATE {
        return Some(format!(
            "placed coordinates reach {reach:.3e}, beyond the {MAX_SAMPLE_COORDINATE:.0e} that 32-bit samples hold with room for their spacings; scale the mesh down (for example `transform: (scale: {:.0e})`)",
            MAX_SAMPLE_COORDINATE / reach / 10.0
        ));
    }
    if extent < MIN_SAMPLE_EXTENT {
        return Some(format!(
            "the placed mesh spans only {extent:.3e} (its bounding-box diagonal), under the {MIN_SAMPLE_EXTENT:.0e} at which 32-bit samples still resolve their spacings; scale the mesh up (for example `transform: (scale: {:.0e})`)",
            MIN_SAMPLE_EXTENT / extent * 10.0
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use strata_engine::surface::Progress;

    use super::stage;

    #[test]
    fn a_stage_reports_its_start_and_its_time_and_returns_the_work() {
        let seen = Mutex::new(Vec::new());
        let record = |p: Progress| seen.lock().expect("lock").push(p);
        let (out, took) = stage(&record, "field", || {
            std::thread::sleep(std::time::Duration::from_millis(5));
            41 + 1
        });
        assert_eq!(out, 42);
        assert!(took >= std::time::Duration::from_millis(5));
        let seen = seen.into_inner().expect("lock");
        assert_eq!(
            seen,
            [Progress::Start("field"), Progress::Done("field", took)]
        );
    }
}
