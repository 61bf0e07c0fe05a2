//! Tensor fields from Python: a scene file's field description (RON, as in a scene's
//! `field:` entry, or the same structure as JSON from Python dictionaries), or
//! per-vertex arrays (isotropic densities, frames, tensors).
//!
//! Input: a [`Field`] object (or `None` for the scene default). Output: the engine's
//! [`TensorField`] for a mesh, built by the engine's own sources
//! ([`FieldSpec::build`], [`TensorField::from_frames`], [`TensorField::new`]).
//! Cost: that of the source; parsing is linear in the text.

use glam::{DMat3, DVec3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use strata_engine::field::{FieldSpec, TensorField};
use strata_engine::mesh::TriMesh;

use crate::{arrays, scene_ron};

/// What a [`Field`] is made from.
#[derive(Clone, Debug)]
enum Source {
    /// A description, as in a scene file.
    Spec(FieldSpec),
    /// Per-vertex major directions and eigenvalues `(l1, l2)`.
    Frames(Vec<DVec3>, Vec<[f64; 2]>),
    /// Per-vertex isotropic densities.
    Densities(Vec<f64>),
    /// Per-vertex tensors.
    Tensors(Vec<DMat3>),
}

/// A tensor field, built for a mesh when a `Sampler` preprocesses it.
#[pyclass(module = "strata_sampling._strata", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Field {
    source: Source,
}

#[pymethods]
impl Field {
    /// A field from its scene-file description in RON, e.g. `"Curvature(floor: 0.1)"`.
    #[staticmethod]
    fn from_ron(text: &str) -> PyResult<Self> {
        Self::from_ron_text(text)
    }

    /// A field from its scene-file description as JSON (what the Python helpers
    /// write): `{"Constant": {"direction": [1, 0, 0], "anisotropy": 2}}`.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Self::from_json_text(text)
    }

    /// Isotropic, with a density per vertex (shape `(V,)`, each finite and > 0).
    #[staticmethod]
    fn from_densities(densities: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(Self {
            source: Source::Densities(arrays::values("densities", densities)?),
        })
    }

    /// Per vertex a major direction (shape `(V, 3)`, projected into the tangent plane)
    /// and eigenvalues `(l1, l2)` (shape `(V, 2)`, both > 0).
    #[staticmethod]
    fn from_frames(
        directions: &Bound<'_, PyAny>,
        eigenvalues: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        Ok(Self {
            source: Source::Frames(
                arrays::rows3("directions", directions)?,
                arrays::rows2("eigenvalues", eigenvalues)?,
            ),
        })
    }

    /// Symmetric tensors per vertex (shape `(V, 3, 3)`, positive definite in the
    /// vertex's tangent plane).
    #[staticmethod]
    fn from_tensors(tensors: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(Self {
            source: Source::Tensors(arrays::tensors(tensors)?),
        })
    }

    fn __repr__(&self) -> String {
        match &self.source {
            Source::Spec(spec) => format!("Field({spec:?})"),
            Source::Frames(d, _) => format!("Field(frames of {} vertices)", d.len()),
            Source::Densities(d) => format!("Field(densities of {} vertices)", d.len()),
            Source::Tensors(t) => format!("Field(tensors of {} vertices)", t.len()),
        }
    }
}

impl Field {
    /// The scene default: isotropic, density 1.
    pub fn uniform() -> Self {
        Self {
            source: Source::Spec(FieldSpec::Constant {
                direction: [1.0, 0.0, 0.0],
                anisotropy: 1.0,
                density: 1.0,
            }),
        }
    }

    /// A field from RON (see `from_ron`).
    pub fn from_ron_text(text: &str) -> PyResult<Self> {
        let spec: FieldSpec = scene_ron::parse(text)
            .map_err(|e| PyValueError::new_err(format!("field description: {e}")))?;
        Self::checked(spec)
    }

    /// A field from JSON (see `from_json`).
    pub fn from_json_text(text: &str) -> PyResult<Self> {
        let spec: FieldSpec = serde_json::from_str(text)
            .map_err(|e| PyValueError::new_err(format!("field description: {e}")))?;
        Self::checked(spec)
    }

    fn checked(spec: FieldSpec) -> PyResult<Self> {
        spec.validate()
            .map_err(|e| PyValueError::new_err(format!("field: {e}")))?;
        Ok(Self {
            source: Source::Spec(spec),
        })
    }

    /// The field on `mesh`, built by the engine (errors as the engine's message).
    pub fn build(&self, mesh: &TriMesh) -> Result<TensorField, String> {
        let field = match &self.source {
            Source::Spec(spec) => spec.build(mesh),
            Source::Frames(d, l) => TensorField::from_frames(mesh, d, l),
            Source::Densities(densities) => {
                // Isotropic: the direction is not used (any tangent will do).
                let directions = vec![DVec3::X; densities.len()];
                let eigen: Vec<[f64; 2]> = densities.iter().map(|&d| [d, d]).collect();
                TensorField::from_frames(mesh, &directions, &eigen)
            }
            Source::Tensors(t) => TensorField::new(mesh, t.clone()),
        };
        field.map_err(|e| format!("field: {e}"))
    }
}
