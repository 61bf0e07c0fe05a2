//! The `Sampler` and `Samples` classes: a preprocessed surface that draws any number
//! of samples, and the drawn samples as numpy arrays handed over without a copy.
//!
//! Input: a preprocessed [`Built`] surface, a count, a seed and an order. Output:
//! [`Samples`], one numpy array per attribute, each made from a Rust `Vec` by
//! `into_pyarray` (numpy takes the buffer; nothing is copied at the boundary).
//! Cost: the engine's sampling (parallel) plus one pass splitting the records into
//! the arrays, with the GIL released.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use strata_engine::sample::Sample;

use crate::args::{field_arg, options_arg, stderr_is_terminal};
use crate::arrays;
use crate::preprocess::{Built, Failure, preprocess};

/// A preprocessed mesh and field, ready to draw samples.
#[pyclass(module = "strata_sampling._strata", frozen)]
pub struct Sampler {
    built: Built,
}

/// How samples are drawn.
#[derive(Clone, Copy)]
enum Order {
    /// Exactly stratified for the count asked.
    Stratified,
    /// The first `n` of one sequence per surface and seed: fewer are a prefix of more.
    Progressive,
}

impl Order {
    fn parse(order: &str) -> PyResult<Self> {
        match order {
            "stratified" => Ok(Self::Stratified),
            "progressive" => Ok(Self::Progressive),
            other => Err(PyValueError::new_err(format!(
                "order must be \"stratified\" or \"progressive\", got {other:?}"
            ))),
        }
    }
}

#[pymethods]
impl Sampler {
    /// Preprocesses a mesh and field for sampling (the expensive part), with the GIL
    /// released; Ctrl-C cancels it with `KeyboardInterrupt`.
    #[new]
    #[pyo3(signature = (vertices, faces, field = None, *, options = None, progress = None))]
    fn py_new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        field: Option<&Bound<'_, PyAny>>,
        options: Option<&Bound<'_, PyAny>>,
        progress: Option<bool>,
    ) -> PyResult<Self> {
        let positions = arrays::vertices(vertices)?;
        let triangles = arrays::faces("faces", faces)?;
        let field = field_arg(field)?;
        let options = options_arg(options)?;
        let progress = progress.unwrap_or_else(|| stderr_is_terminal(py));
        match preprocess(py, positions, triangles, field, options, progress) {
            Ok(built) => Ok(Sampler { built }),
            Err(Failure::Interrupted(e)) => Err(e),
            Err(Failure::Input(message)) => Err(PyValueError::new_err(message)),
        }
    }

    /// Draws `n` samples with `seed`, in `order` (`"stratified"` or `"progressive"`).
    #[pyo3(signature = (n, seed = 0, order = "stratified"))]
    fn sample(&self, py: Python<'_>, n: i64, seed: u64, order: &str) -> PyResult<Samples> {
        let order = Order::parse(order)?;
        let n = usize::try_from(n)
            .map_err(|_| PyValueError::new_err(format!("n must be >= 0, got {n}")))?;
        if matches!(order, Order::Progressive) && u32::try_from(n).is_err() {
            return Err(PyValueError::new_err(format!(
                "progressive order draws at most {} samples, got {n}",
                u32::MAX
            )));
        }
        let columns = py.detach(|| draw(&self.built, n, seed, order))?;
        columns.into_samples(py)
    }

    /// Final segments of the preprocessing.
    #[getter]
    fn segments(&self) -> usize {
        self.built.segments
    }

    /// Singular faces of the field the segmentation worked with.
    #[getter]
    fn singularities(&self) -> usize {
        self.built.singularities
    }

    /// `"planar"` (a flat mesh: one linear map) or `"surface"`.
    #[getter]
    fn path(&self) -> &'static str {
        self.built.path
    }

    /// Invalid segments split during parameterization.
    #[getter]
    fn splits(&self) -> usize {
        self.built.splits
    }

    /// Valid neighbouring pieces merged back.
    #[getter]
    fn merges(&self) -> usize {
        self.built.merges
    }

    /// Adaptive Hilbert cells over all segments.
    #[getter]
    fn cells(&self) -> usize {
        self.built.cells
    }

    /// Seconds per preprocessing stage, in order (`mesh`, `field`, then the engine's).
    #[getter]
    fn stage_times<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, took) in &self.built.stages {
            d.set_item(name, took.as_secs_f64())?;
        }
        Ok(d)
    }

    /// Vertex count of the preprocessed mesh.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.built.sampler.mesh().vertex_count()
    }

    /// Face count of the preprocessed mesh.
    #[getter]
    fn face_count(&self) -> usize {
        self.built.sampler.mesh().face_count()
    }

    fn __repr__(&self) -> String {
        format!(
            "Sampler({} faces, {} path, {} segments, {} singularities, {} cells)",
            self.built.sampler.mesh().face_count(),
            self.built.path,
            self.built.segments,
            self.built.singularities,
            self.built.cells
        )
    }
}

/// Drawn samples, one numpy array per attribute (see the package docs for dtypes).
#[pyclass(module = "strata_sampling._strata", frozen)]
pub struct Samples {
    /// Positions, `(n, 3)` float32.
    #[pyo3(get)]
    positions: Py<PyArray2<f32>>,
    /// Unit normals, `(n, 3)` float32.
    #[pyo3(get)]
    normals: Py<PyArray2<f32>>,
    /// Face of each sample, `(n,)` uint32.
    #[pyo3(get)]
    face_ids: Py<PyArray1<u32>>,
    /// Barycentric coordinates on the face's three corners, `(n, 3)` float32.
    #[pyo3(get)]
    barycentrics: Py<PyArray2<f32>>,
    /// Unit major axis of the field, `(n, 3)` float32.
    #[pyo3(get)]
    major_axes: Py<PyArray2<f32>>,
    /// Expected spacing along the major and minor axis, `(n, 2)` float32.
    #[pyo3(get)]
    spacings: Py<PyArray2<f32>>,
    /// Segment of each sample, `(n,)` uint32.
    #[pyo3(get)]
    segments: Py<PyArray1<u32>>,
    /// Rank of each sample in its sequence, `(n,)` uint32.
    #[pyo3(get)]
    ranks: Py<PyArray1<u32>>,
    len: usize,
}

#[pymethods]
impl Samples {
    fn __len__(&self) -> usize {
        self.len
    }

    fn __repr__(&self) -> String {
        format!("Samples({} points)", self.len)
    }
}

/// The samples split into columns, before they become numpy arrays.
struct Columns {
    n: usize,
    positions: Vec<f32>,
    normals: Vec<f32>,
    face_ids: Vec<u32>,
    barycentrics: Vec<f32>,
    major_axes: Vec<f32>,
    spacings: Vec<f32>,
    segments: Vec<u32>,
    ranks: Vec<u32>,
}

/// A `Vec` of `len` default values, or `MemoryError` when it cannot be allocated.
fn alloc<T: Default + Clone>(len: usize) -> PyResult<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| {
        PyMemoryError::new_err(format!("cannot allocate {len} values for the samples"))
    })?;
    v.resize(len, T::default());
    Ok(v)
}

/// Samples drawn by the engine in one call and split into columns.
fn draw(built: &Built, n: usize, seed: u64, order: Order) -> PyResult<Columns> {
    let mut samples: Vec<Sample> = alloc(n)?;
    match order {
        Order::Stratified => built.sampler.sample_into(seed, &mut samples),
        // n fits in u32 (checked by the caller).
        Order::Progressive => built.sampler.progressive_into(seed, 0, &mut samples),
    }
    let mut c = Columns {
        n,
        positions: alloc(3 * n)?,
        normals: alloc(3 * n)?,
        face_ids: alloc(n)?,
        barycentrics: alloc(3 * n)?,
        major_axes: alloc(3 * n)?,
        spacings: alloc(2 * n)?,
        segments: alloc(n)?,
        ranks: alloc(n)?,
    };
    const CHUNK: usize = 1 << 14;
    samples
        .par_chunks(CHUNK)
        .zip(c.positions.par_chunks_mut(3 * CHUNK))
        .zip(c.normals.par_chunks_mut(3 * CHUNK))
        .zip(c.barycentrics.par_chunks_mut(3 * CHUNK))
        .zip(c.major_axes.par_chunks_mut(3 * CHUNK))
        .zip(c.spacings.par_chunks_mut(2 * CHUNK))
        .zip(c.face_ids.par_chunks_mut(CHUNK))
        .zip(c.segments.par_chunks_mut(CHUNK))
        .zip(c.ranks.par_chunks_mut(CHUNK))
        .for_each(|((((((((s, p), nr), b), m), sp), f), seg), r)| {
            for (i, x) in s.iter().enumerate() {
                p[3 * i..3 * i + 3].copy_from_slice(&x.position);
                nr[3 * i..3 * i + 3].copy_from_slice(&x.normal);
                m[3 * i..3 * i + 3].copy_from_slice(&x.major_axis);
                b[3 * i..3 * i + 3].copy_from_slice(&barycentric(x.bary));
                sp[2 * i..2 * i + 2].copy_from_slice(&x.spacing);
                f[i] = x.face;
                seg[i] = x.segment;
                r[i] = x.index;
            }
        });
    Ok(c)
}

/// The three barycentric coordinates from the engine's two (corners 1 and 2).
fn barycentric(b: [f32; 2]) -> [f32; 3] {
    [1.0 - b[0] - b[1], b[0], b[1]]
}

impl Columns {
    fn into_samples(self, py: Python<'_>) -> PyResult<Samples> {
        let n = self.n;
        let mat = |v: Vec<f32>, cols: usize| -> PyResult<Py<PyArray2<f32>>> {
            // The length is n * cols by construction.
            Array2::from_shape_vec((n, cols), v)
                .map(|a| a.into_pyarray(py).unbind())
                .map_err(|e| PyRuntimeError::new_err(format!("sample columns: {e}")))
        };
        Ok(Samples {
            positions: mat(self.positions, 3)?,
            normals: mat(self.normals, 3)?,
            barycentrics: mat(self.barycentrics, 3)?,
            major_axes: mat(self.major_axes, 3)?,
            spacings: mat(self.spacings, 2)?,
            face_ids: self.face_ids.into_pyarray(py).unbind(),
            segments: self.segments.into_pyarray(py).unbind(),
            ranks: self.ranks.into_pyarray(py).unbind(),
            len: n,
        })
    }
}
