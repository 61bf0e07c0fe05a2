//! # strata-python
//!
//! The extension module `strata_sampling._strata`: strata's sampling for Python, with
//! numpy arrays in and out. A thin layer over `strata-engine`: arrays are checked and
//! converted (`arrays`), fields are the engine's sources (`field`), preprocessing is
//! the engine's front door run off the GIL and cancellable by Ctrl-C (`preprocess`),
//! and samples come back as numpy arrays that own the engine's buffers (`sampler`);
//! `analysis` exposes the quality measures. The Python package around it
//! (`strata_sampling/`) adds the one-call `sample`, field helpers, `interpolate` and
//! the type stubs.
//!
//! Errors: the engine's message as `ValueError` (bad shapes, non-finite or
//! out-of-range values, degenerate meshes, bad field values), `OSError` for files,
//! `KeyboardInterrupt` when Ctrl-C cancels a build.

mod analysis;
mod args;
mod arrays;
mod field;
mod pool;
mod preprocess;
mod sampler;
mod scene_ron;

use glam::DVec3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::prelude::*;
use strata_engine::mesh::MeshError;

use field::Field;
use sampler::{Sampler, Samples};

/// A mesh as numpy arrays: vertices `(V, 3)` float64, faces `(F, 3)` uint32.
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<u32>>);

/// Reads an OBJ or PLY mesh with strata's loaders: `(vertices, faces)` as float64
/// `(V, 3)` and uint32 `(F, 3)` arrays (polygons triangulated, as the engine loads
/// them).
#[pyfunction]
fn load_mesh<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<MeshArrays<'py>> {
    let mesh = py
        .detach(|| strata_engine::io::load(&path))
        .map_err(|e| match &e {
            MeshError::Io { source, .. } => match source.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(e.to_string()),
                std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(e.to_string()),
                _ => PyOSError::new_err(e.to_string()),
            },
            _ => PyValueError::new_err(e.to_string()),
        })?;
    let v: Vec<f64> = mesh.positions().iter().flat_map(DVec3::to_array).collect();
    let f: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
    let shape_err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    Ok((
        Array2::from_shape_vec((mesh.vertex_count(), 3), v)
            .map_err(shape_err)?
            .into_pyarray(py),
        Array2::from_shape_vec((mesh.face_count(), 3), f)
            .map_err(shape_err)?
            .into_pyarray(py),
    ))
}

/// The extension module.
#[pymodule]
fn _strata(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Sampler>()?;
    m.add_class::<Samples>()?;
    m.add_class::<Field>()?;
    m.add_function(wrap_pyfunction!(load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::star_discrepancy, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::radial_spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::surface_spectrum, m)?)?;
    Ok(())
}
