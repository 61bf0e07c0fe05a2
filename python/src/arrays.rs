//! numpy arrays in: vertices, faces, points, per-vertex values and tensors from
//! whatever array-like a caller passes (any float or integer dtype, C or Fortran
//! order, lists), checked for shape and converted to the engine's types.
//!
//! Input: Python objects. Output: `Vec`s of engine types, or a `ValueError` that says
//! which argument is wrong and how. Cost: one pass (and one copy) over each array.

use glam::{DMat3, DVec2, DVec3};
use numpy::ndarray::{ArrayView2, ArrayView3};
use numpy::{
    AllowTypeChange, PyArrayDescrMethods, PyArrayLike2, PyArrayLike3, PyReadonlyArray2,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `numpy.asarray(obj)` as an untyped array: lists and other array-likes become arrays.
fn as_array<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    let np = obj.py().import("numpy")?;
    let arr = np.call_method1("asarray", (obj,))?;
    Ok(arr.cast_into::<PyUntypedArray>()?)
}

/// Checks that `arr` has the shape `(*, cols)` (`cols` `None`: any column count, 1-D
/// allowed) and returns its numpy dtype kind (`'f'`, `'i'`, `'u'`, ...).
fn check_shape(name: &str, arr: &Bound<'_, PyUntypedArray>, cols: &[usize]) -> PyResult<char> {
    let shape = arr.shape();
    let ok = shape.len() == cols.len() + 1 && shape[1..] == *cols;
    if !ok {
        let want: Vec<String> = cols.iter().map(usize::to_string).collect();
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (N, {}), got {shape:?}",
            want.join(", ")
        )));
    }
    Ok(char::from(arr.dtype().kind()))
}

/// Requires a float or integer dtype (numpy kinds `f`, `i`, `u`).
fn check_numeric(name: &str, kind: char, arr: &Bound<'_, PyUntypedArray>) -> PyResult<()> {
    if matches!(kind, 'f' | 'i' | 'u') {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name} must hold numbers, got dtype {}",
            arr.dtype()
        )))
    }
}

/// Rows of an `(N, C)` array of any numeric dtype as `f64` (float32 and integers
/// converted; Fortran order read as is).
fn float_rows<'py, const C: usize>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Vec<[f64; C]>> {
    let arr = as_array(obj)?;
    let kind = check_shape(name, &arr, &[C])?;
    check_numeric(name, kind, &arr)?;
    let typed: PyArrayLike2<'py, f64, AllowTypeChange> = arr.into_any().extract()?;
    Ok(rows(typed.as_array()))
}

fn rows<T: Copy, const C: usize>(view: ArrayView2<'_, T>) -> Vec<[T; C]> {
    view.rows()
        .into_iter()
        .map(|r| std::array::from_fn(|j| r[j]))
        .collect()
}

/// Mesh vertices, shape `(V, 3)`, any float or integer dtype.
pub fn vertices(obj: &Bound<'_, PyAny>) -> PyResult<Vec<DVec3>> {
    Ok(float_rows::<3>("vertices", obj)?
        .into_iter()
        .map(DVec3::from_array)
        .collect())
}

/// Points in the plane, shape `(N, 2)`.
pub fn points2(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<DVec2>> {
    Ok(float_rows::<2>(name, obj)?
        .into_iter()
        .map(DVec2::from_array)
        .collect())
}

/// Vectors, shape `(N, 3)`, as `f64` rows.
pub fn rows3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<DVec3>> {
    Ok(float_rows::<3>(name, obj)?
        .into_iter()
        .map(DVec3::from_array)
        .collect())
}

/// Pairs, shape `(N, 2)`, as `f64` rows.
pub fn rows2(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 2]>> {
    float_rows::<2>(name, obj)
}

/// A 1-D array of numbers as `f64`.
pub fn values(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let arr = as_array(obj)?;
    let kind = check_shape(name, &arr, &[])?;
    check_numeric(name, kind, &arr)?;
    let typed: numpy::PyArrayLike1<'_, f64, AllowTypeChange> = arr.into_any().extract()?;
    Ok(typed.as_array().iter().copied().collect())
}

/// Symmetric tensors, shape `(V, 3, 3)`.
pub fn tensors(obj: &Bound<'_, PyAny>) -> PyResult<Vec<DMat3>> {
    let arr = as_array(obj)?;
    let kind = check_shape("tensors", &arr, &[3, 3])?;
    check_numeric("tensors", kind, &arr)?;
    let typed: PyArrayLike3<'_, f64, AllowTypeChange> = arr.into_any().extract()?;
    Ok(mats(typed.as_array()))
}

fn mats(view: ArrayView3<'_, f64>) -> Vec<DMat3> {
    view.outer_iter()
        .map(|m| {
            DMat3::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| m[[r, c]])))
        })
        .collect()
}

/// Integer rows of width 3 of any integer dtype, each entry checked to fit in `u32`.
fn int_rows<'py, T>(name: &str, arr: &Bound<'py, PyUntypedArray>) -> PyResult<Option<Vec<[u32; 3]>>>
where
    T: numpy::Element + Copy + Into<i128>,
{
    let Ok(typed) = arr.extract::<PyReadonlyArray2<'py, T>>() else {
        return Ok(None);
    };
    let view = typed.as_array();
    let mut out = Vec::with_capacity(view.nrows());
    for (row, r) in view.rows().into_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (j, slot) in tri.iter_mut().enumerate() {
            let v: i128 = r[j].into();
            *slot = u32::try_from(v).map_err(|_| {
                PyValueError::new_err(format!(
                    "{name}: row {row} has index {v}; indices must be in 0..{}",
                    u64::from(u32::MAX) + 1
                ))
            })?;
        }
        out.push(tri);
    }
    Ok(Some(out))
}

/// Triangles, shape `(F, 3)`, of any integer dtype (signed or unsigned, 8 to 64
/// bits); negative or too large indices are a `ValueError` (the engine checks the
/// indices against the vertex count).
pub fn faces(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[u32; 3]>> {
    let arr = as_array(obj)?;
    let kind = check_shape(name, &arr, &[3])?;
    if !matches!(kind, 'i' | 'u') {
        return Err(PyValueError::new_err(format!(
            "{name} must hold integers, got dtype {}",
            arr.dtype()
        )));
    }
    macro_rules! try_types {
        ($($t:ty),*) => {
            $(if let Some(v) = int_rows::<$t>(name, &arr)? { return Ok(v); })*
        };
    }
    try_types!(i64, i32, u32, u64, i16, u16, i8, u8);
    Err(PyValueError::new_err(format!(
        "{name}: unsupported integer dtype {}",
        arr.dtype()
    )))
}
