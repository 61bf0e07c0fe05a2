//! Turning a [`SceneConfig`] into engine data: mesh, field and sampler.

use std::sync::Arc;
use std::time::{Duration, Instant};

use strata_engine::field::{FieldError, TensorField};
use strata_engine::mesh::{MeshError, TriMesh};
use strata_engine::planar::{self, PlanarError};
use strata_engine::sample::Sampler;

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
    /// Preprocessing for sampling failed.
    #[error("sampling: {0}")]
    Planar(#[from] PlanarError),
}

impl Scene {
    /// Loads the mesh, builds the field and preprocesses for sampling.
    pub fn build(config: &SceneConfig) -> Result<Self, SceneError> {
        let mut stages = Vec::new();
        let t = Instant::now();
        let mesh = Arc::new(load_mesh(config)?);
        stages.push(("mesh", t.elapsed()));
        let t = Instant::now();
        let field = Arc::new(config.field.build(&mesh)?);
        stages.push(("field", t.elapsed()));
        let t = Instant::now();
        let (sampler, _) = planar::sampler(mesh.clone(), field.clone(), &config.curve)?;
        stages.push(("cells", t.elapsed()));
        Ok(Self {
            mesh,
            field,
            sampler,
            stages,
        })
    }
}

/// Loads or builds the scene's mesh.
pub fn load_mesh(config: &SceneConfig) -> Result<TriMesh, MeshError> {
    match &config.mesh {
        MeshSource::File(path) => strata_engine::io::load(path),
        MeshSource::Shape(shape) => shape.build(),
    }
}
