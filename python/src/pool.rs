//! Sample columns whose memory is reused: when numpy frees the arrays of a `Samples`
//! (and every view of them), their buffers go back to the pool of the `Sampler` that
//! drew them, and its next draw writes into that memory instead of fresh pages. Fresh
//! pages cost the kernel a fault and a zeroing per 4 KiB at first touch (48 MB for
//! 10^6 samples), about half as much again as the sampling itself; reused pages cost
//! nothing, so `sample(n)` in a loop runs as fast as `sample_into`.
//!
//! Input: column lengths. Output: `Vec`s (a pooled one of fitting capacity, or a new
//! zeroed one) and numpy arrays over them whose base object hands the `Vec` back when
//! numpy drops the array. Cost: O(1) per column; the pool keeps at most one set of
//! columns (the memory of the last `Samples` freed), and is freed with its `Sampler`.

// One `unsafe` block: numpy's foreign interface takes a raw buffer and a base object
// that keeps it alive (`PyArray::borrow_from_array`).
#![allow(unsafe_code)]

use std::sync::{Arc, Mutex, PoisonError};

use numpy::PyArray;
use numpy::ndarray::{ArrayView, Dimension};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError};
use pyo3::prelude::*;

/// Buffers of one element type kept for reuse: at most one `Samples`' worth.
type Shelf<T> = Mutex<Vec<Vec<T>>>;

/// Float columns of one `Samples` (positions, normals, barycentrics, major axes,
/// spacings).
const KEEP_F32: usize = 5;
/// Integer columns of one `Samples` (faces, segments, ranks).
const KEEP_U32: usize = 3;

/// Freed sample buffers of one sampler, by element type.
#[derive(Default)]
pub struct Pool {
    floats: Shelf<f32>,
    ints: Shelf<u32>,
}

/// An element type the pool keeps, with its shelf.
pub trait Pooled: numpy::Element + Copy + Default + Send + Sync + 'static {
    /// The shelf of this type in `pool`.
    fn shelf(pool: &Pool) -> &Shelf<Self>;
    /// How many buffers of this type the shelf keeps.
    const KEEP: usize;
    /// The buffer as the column kind the base object holds.
    fn column(v: Vec<Self>) -> Column;
}

impl Pooled for f32 {
    fn shelf(pool: &Pool) -> &Shelf<Self> {
        &pool.floats
    }
    const KEEP: usize = KEEP_F32;
    fn column(v: Vec<Self>) -> Column {
        Column::F32(v)
    }
}

impl Pooled for u32 {
    fn shelf(pool: &Pool) -> &Shelf<Self> {
        &pool.ints
    }
    const KEEP: usize = KEEP_U32;
    fn column(v: Vec<Self>) -> Column {
        Column::U32(v)
    }
}

impl Pool {
    /// A buffer of `len` values to be overwritten: the smallest pooled buffer whose
    /// capacity holds `len` without being over twice it (its old values, or zeros
    /// past them), else a new zeroed one (`calloc`: untouched pages, first written by
    /// the parallel fill). `MemoryError` when `len` values cannot be allocated.
    pub fn take<T: Pooled>(&self, len: usize) -> PyResult<Vec<T>> {
        let reused = {
            let mut shelf = T::shelf(self)
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            let fits = |v: &Vec<T>| v.capacity() >= len && v.capacity() / 2 <= len;
            let best = (0..shelf.len())
                .filter(|&i| fits(&shelf[i]))
                .min_by_key(|&i| shelf[i].capacity());
            best.map(|i| shelf.swap_remove(i))
        };
        if let Some(mut v) = reused {
            v.truncate(len);
            v.resize(len, T::default());
            return Ok(v);
        }
        let mut probe: Vec<T> = Vec::new();
        probe.try_reserve_exact(len).map_err(|_| {
            PyMemoryError::new_err(format!("cannot allocate {len} values for the samples"))
        })?;
        drop(probe);
        Ok(vec![T::default(); len])
    }

    /// Keeps `v` for a later draw if the shelf has room; frees it otherwise.
    fn give<T: Pooled>(&self, v: Vec<T>) {
        if v.capacity() == 0 {
            return;
        }
        let mut shelf = T::shelf(self)
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if shelf.len() < T::KEEP {
            shelf.push(v);
        }
    }
}

/// A column's buffer, of either element type.
pub enum Column {
    /// Float values.
    F32(Vec<f32>),
    /// Integer values.
    U32(Vec<u32>),
}

/// The base object of a sample array: owns the buffer the array shows and hands it
/// back to its pool when numpy drops the array (and every view of it).
#[pyclass(module = "strata_sampling._strata", frozen)]
pub struct SampleBuffer {
    column: Column,
    pool: Arc<Pool>,
}

impl Drop for SampleBuffer {
    fn drop(&mut self) {
        match std::mem::replace(&mut self.column, Column::U32(Vec::new())) {
            Column::F32(v) => self.pool.give(v),
            Column::U32(v) => self.pool.give(v),
        }
    }
}

impl SampleBuffer {
    /// The buffer's values, of the element type it was made with.
    fn values<T: Pooled>(&self) -> PyResult<&[T]> {
        let any: &dyn std::any::Any = match &self.column {
            Column::F32(v) => v,
            Column::U32(v) => v,
        };
        any.downcast_ref::<Vec<T>>()
            .map(Vec::as_slice)
            .ok_or_else(|| PyRuntimeError::new_err("sample buffer of another element type"))
    }
}

/// `v` as a numpy array of shape `shape` (holding `v.len()` values) that returns `v`
/// to `pool` when it is freed (no copy).
pub fn array<'py, T: Pooled, D: Dimension>(
    py: Python<'py>,
    v: Vec<T>,
    shape: D,
    pool: &Arc<Pool>,
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    let owner = Bound::new(
        py,
        SampleBuffer {
            column: T::column(v),
            pool: Arc::clone(pool),
        },
    )?;
    let values = owner.get().values::<T>()?;
    let view = ArrayView::from_shape(shape, values)
        .map_err(|e| PyRuntimeError::new_err(format!("sample columns: {e}")))?;
    // SAFETY: the array's data is the buffer `owner` holds, and `owner` becomes the
    // array's base object, so it lives as long as the array (and its views). The
    // buffer is never reallocated or touched by Rust while `owner` lives: `owner` is
    // frozen and hands the buffer back only when it is dropped.
    Ok(unsafe { PyArray::borrow_from_array(&view, owner.clone().into_any()) })
}
