//! Quality measures of point sets, by the engine's analysis module: star discrepancy
//! and the radially averaged power spectrum in the unit square, and the
//! differential-domain spectrum of points on a surface.
//!
//! Input: `(N, 2)` arrays, or `(N, 3)` positions and normals. Output: numbers, or numpy arrays of the spectrum's
//! annuli. Cost: that of the engine's measures (the GIL is released while they run).

use glam::DVec3;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use strata_engine::analysis::dda::{DdaOptions, dda};
use strata_engine::analysis::discrepancy::{try_star_discrepancy_l2, try_star_discrepancy_sup};
use strata_engine::analysis::spectrum::periodogram;
use strata_engine::sample::Sample;

use crate::arrays;

/// Star discrepancy of points in the unit square: `kind` `"l2"` (the L2 star
/// discrepancy) or `"sup"` (the largest local discrepancy over anchored boxes).
#[pyfunction]
#[pyo3(signature = (points, kind = "l2"))]
pub fn star_discrepancy(py: Python<'_>, points: &Bound<'_, PyAny>, kind: &str) -> PyResult<f64> {
    let points = arrays::points2("points", points)?;
    let result = match kind {
        "l2" => py.detach(|| try_star_discrepancy_l2(&points)),
        "sup" => py.detach(|| try_star_discrepancy_sup(&points)),
        other => {
            return Err(PyValueError::new_err(format!(
                "kind must be \"l2\" or \"sup\", got {other:?}"
            )));
        }
    };
    result.map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A radial profile: frequency, power and anisotropy (dB) per annulus.
type Profile<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// The radially averaged power spectrum of one or more point sets in the unit square
/// (each `(N, 2)`, all of the same `N`), up to `max_frequency` (in units of
/// `sqrt(N)`): `(frequency, power, anisotropy_db)` per annulus of integer radius.
/// White noise gives power 1 at every frequency; blue noise little at low ones.
#[pyfunction]
#[pyo3(signature = (point_sets, max_frequency = 2.0))]
pub fn radial_spectrum<'py>(
    py: Python<'py>,
    point_sets: &Bound<'py, PyAny>,
    max_frequency: f64,
) -> PyResult<Profile<'py>> {
    let sets = if let Ok(list) = point_sets.cast::<pyo3::types::PyList>() {
        list.iter()
            .map(|s| arrays::points2("point_sets", &s))
            .collect::<PyResult<Vec<_>>>()?
    } else {
        vec![arrays::points2("point_sets", point_sets)?]
    };
    let profile = py
        .detach(|| periodogram(&sets, max_frequency).map(|s| s.radial()))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((
        profile.frequency.into_pyarray(py),
        profile.rapsd.into_pyarray(py),
        profile.anisotropy_db.into_pyarray(py),
    ))
}

/// The differential-domain spectrum (the engine's `dda`) of points on a surface of
/// uniform, isotropic density: each point's neighbours within `epsilon` expected
/// spacings, their differences unfolded into its tangent plane (given by `normals`)
/// and measured in units of `spacing` (the expected distance between neighbours,
/// `sqrt(area / N)`), then `(frequency, power, anisotropy_db)` per annulus up to
/// `max_frequency` (normalised: the nominal frequency is 1). White noise gives power
/// about 1 beyond the kernel's low-frequency bump; blue noise little below 1.
#[pyfunction]
#[pyo3(signature = (positions, normals, spacing, *, epsilon = 10.0, max_frequency = 2.5))]
pub fn surface_spectrum<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    normals: &Bound<'py, PyAny>,
    spacing: f64,
    epsilon: f64,
    max_frequency: f64,
) -> PyResult<Profile<'py>> {
    let p = arrays::rows3("positions", positions)?;
    let nr = arrays::rows3("normals", normals)?;
    if p.len() != nr.len() {
        return Err(PyValueError::new_err(format!(
            "positions and normals differ in length: {} and {}",
            p.len(),
            nr.len()
        )));
    }
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(PyValueError::new_err(format!(
            "spacing must be finite and > 0, got {spacing}"
        )));
    }
    let options = DdaOptions {
        epsilon,
        max_frequency,
        ..DdaOptions::default()
    };
    let samples: Vec<Sample> = p
        .iter()
        .zip(&nr)
        .map(|(&x, &n)| {
            let n = n.normalize_or(DVec3::Z);
            Sample {
                position: x.as_vec3().to_array(),
                normal: n.as_vec3().to_array(),
                major_axis: n.any_orthonormal_vector().as_vec3().to_array(),
                spacing: [spacing as f32; 2],
                ..Sample::default()
            }
        })
        .collect();
    let profile = py
        .detach(|| dda(&[samples], &options).map(|s| s.radial()))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((
        profile.frequency.into_pyarray(py),
        profile.rapsd.into_pyarray(py),
        profile.anisotropy_db.into_pyarray(py),
    ))
}
