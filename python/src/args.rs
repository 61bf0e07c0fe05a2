//! Arguments that take several forms: a field (`None`, a `Field`, a RON text or a
//! dictionary), the preprocessing options (`None`, a dictionary or a RON text), and
//! the progress default (on only when standard error is a terminal).
//!
//! Input: Python objects. Output: engine values, or a `ValueError` with the parser's
//! or the engine's message. Cost: linear in the text.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use strata_engine::surface::SurfaceOptions;

use crate::field::Field;
use crate::scene_ron;

/// A field argument: `None` (uniform), a [`Field`], a RON description (a scene
/// file's `field:` entry) or a dictionary of the same structure.
pub fn field_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Field> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Field::uniform());
    };
    if let Ok(f) = obj.extract::<Field>() {
        return Ok(f);
    }
    if let Ok(text) = obj.cast::<PyString>() {
        return Field::from_ron_text(&text.to_cow()?);
    }
    if obj.cast::<PyDict>().is_ok() {
        return Field::from_json_text(&to_json(obj)?);
    }
    Err(PyValueError::new_err(
        "field must be None, a Field, a RON description or a dict",
    ))
}

/// `json.dumps(obj)`.
fn to_json(obj: &Bound<'_, PyAny>) -> PyResult<String> {
    obj.py()
        .import("json")?
        .call_method1("dumps", (obj,))?
        .extract()
}

/// The preprocessing options: `None` (the engine's defaults), a dictionary or a RON
/// text of [`SurfaceOptions`] (`segment`, `param`, `curve`, `min_segment_faces`,
/// `angle_criterion`, `isotropy_threshold`, `chart_angle`, `merge_pieces`).
pub fn options_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<SurfaceOptions> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(SurfaceOptions::default());
    };
    let parsed = if let Ok(text) = obj.cast::<PyString>() {
        scene_ron::parse::<SurfaceOptions>(&text.to_cow()?)
    } else if obj.cast::<PyDict>().is_ok() {
        serde_json::from_str::<SurfaceOptions>(&to_json(obj)?).map_err(|e| e.to_string())
    } else {
        return Err(PyValueError::new_err(
            "options must be None, a dict or a RON text",
        ));
    };
    let options = parsed.map_err(|e| PyValueError::new_err(format!("options: {e}")))?;
    options
        .validate()
        .map_err(|e| PyValueError::new_err(format!("options: {e}")))?;
    Ok(options)
}

/// Whether standard error is a terminal (`sys.stderr.isatty()`).
pub fn stderr_is_terminal(py: Python<'_>) -> bool {
    py.import("sys")
        .and_then(|sys| sys.getattr("stderr"))
        .and_then(|e| e.call_method0("isatty"))
        .and_then(|t| t.extract::<bool>())
        .unwrap_or(false)
}
