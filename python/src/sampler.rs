//! The `Sampler` and `Samples` classes: a preprocessed surface that draws any number
//! of samples, and the drawn samples as numpy arrays handed over without a copy.
//!
//! Input: a preprocessed [`Built`] surface, a count, a seed and an order. Output:
//! [`Samples`], one numpy array per attribute over the Rust `Vec` the samples were
//! written into (nothing is copied at the boundary; the memory of freed `Samples` is
//! reused, see [`pool`](crate::pool)), or an earlier `Samples` refilled in place
//! (`sample_into`). Cost: the engine's sampling, a block of records per worker at a
//! time, each block written into the columns while it is in cache; all in parallel,
//! with the GIL released.

use std::sync::Arc;

use numpy::ndarray::{Ix1, Ix2};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use strata_engine::sample::Sample;

use crate::args::{field_arg, options_arg, stderr_is_terminal};
use crate::arrays;
use crate::pool::{self, Pool};
use crate::preprocess::{Built, Failure, preprocess};

/// A preprocessed mesh and field, ready to draw samples.
#[pyclass(module = "strata_sampling._strata", frozen)]
pub struct Sampler {
    built: Built,
    /// Buffers of freed `Samples`, reused by the next draw.
    pool: Arc<Pool>,
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
    /// The order named `order`, checked against the count `n` it is to draw.
    fn for_count(order: &str, n: usize) -> PyResult<Self> {
        let order = match order {
            "stratified" => Self::Stratified,
            "progressive" => Self::Progressive,
            other => {
                return Err(PyValueError::new_err(format!(
                    "order must be \"stratified\" or \"progressive\", got {other:?}"
                )));
            }
        };
        if matches!(order, Self::Progressive) && u32::try_from(n).is_err() {
            return Err(PyValueError::new_err(format!(
                "progressive order draws at most {} samples, got {n}",
                u32::MAX
            )));
        }
        Ok(order)
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
            Ok(built) => Ok(Sampler {
                built,
                pool: Arc::default(),
            }),
            Err(Failure::Interrupted(e)) => Err(e),
            Err(Failure::Input(message)) => Err(PyValueError::new_err(message)),
        }
    }

    /// Draws `n` samples with `seed`, in `order` (`"stratified"` or `"progressive"`).
    #[pyo3(signature = (n, seed = 0, order = "stratified"))]
    fn sample(&self, py: Python<'_>, n: i64, seed: u64, order: &str) -> PyResult<Samples> {
        let n = usize::try_from(n)
            .map_err(|_| PyValueError::new_err(format!("n must be >= 0, got {n}")))?;
        let order = Order::for_count(order, n)?;
        let columns = Columns::take(&self.pool, n)?;
        let columns = py.detach(|| columns.drawn(&self.built, seed, order));
        columns.into_samples(py, &self.pool)
    }

    /// Draws `len(out)` samples into the arrays of `out` (from an earlier `sample`
    /// call), in place: the same values as `sample(len(out), seed, order)`, without
    /// allocating (the per-frame path, as the engine's `sample_into`).
    #[pyo3(signature = (out, seed = 0, order = "stratified"))]
    fn sample_into(&self, py: Python<'_>, out: &Samples, seed: u64, order: &str) -> PyResult<()> {
        let order = Order::for_count(order, out.len)?;
        let mut positions = out.positions.bind(py).try_readwrite()?;
        let mut normals = out.normals.bind(py).try_readwrite()?;
        let mut face_ids = out.face_ids.bind(py).try_readwrite()?;
        let mut barycentrics = out.barycentrics.bind(py).try_readwrite()?;
        let mut major_axes = out.major_axes.bind(py).try_readwrite()?;
        let mut spacings = out.spacings.bind(py).try_readwrite()?;
        let mut segments = out.segments.bind(py).try_readwrite()?;
        let mut ranks = out.ranks.bind(py).try_readwrite()?;
        let columns = ColumnsMut {
            positions: positions.as_slice_mut()?,
            normals: normals.as_slice_mut()?,
            face_ids: face_ids.as_slice_mut()?,
            barycentrics: barycentrics.as_slice_mut()?,
            major_axes: major_axes.as_slice_mut()?,
            spacings: spacings.as_slice_mut()?,
            segments: segments.as_slice_mut()?,
            ranks: ranks.as_slice_mut()?,
        };
        py.detach(|| fill(&self.built, seed, order, columns));
        Ok(())
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

/// Samples per block of the parallel fill: a multiple of the engine's chunk (4096),
/// 1 MiB of records per worker.
const BLOCK: usize = 1 << 14;

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

impl Columns {
    /// Buffers for `n` samples, from `pool` where it has them.
    fn take(pool: &Pool, n: usize) -> PyResult<Self> {
        Ok(Columns {
            n,
            positions: pool.take(3 * n)?,
            normals: pool.take(3 * n)?,
            face_ids: pool.take(n)?,
            barycentrics: pool.take(3 * n)?,
            major_axes: pool.take(3 * n)?,
            spacings: pool.take(2 * n)?,
            segments: pool.take(n)?,
            ranks: pool.take(n)?,
        })
    }

    /// The columns with the samples drawn into them (see [`fill`]).
    fn drawn(mut self, built: &Built, seed: u64, order: Order) -> Self {
        fill(
            built,
            seed,
            order,
            ColumnsMut {
                positions: &mut self.positions,
                normals: &mut self.normals,
                face_ids: &mut self.face_ids,
                barycentrics: &mut self.barycentrics,
                major_axes: &mut self.major_axes,
                spacings: &mut self.spacings,
                segments: &mut self.segments,
                ranks: &mut self.ranks,
            },
        );
        self
    }
}

/// The columns of `n` samples to write, `n = face_ids.len()` (the others in
/// proportion).
struct ColumnsMut<'a> {
    positions: &'a mut [f32],
    normals: &'a mut [f32],
    face_ids: &'a mut [u32],
    barycentrics: &'a mut [f32],
    major_axes: &'a mut [f32],
    spacings: &'a mut [f32],
    segments: &'a mut [u32],
    ranks: &'a mut [u32],
}

/// Samples drawn by the engine a block at a time (the same bits as one call for all
/// `n`: `sample_range_into`, `progressive_into` from the block's first rank) and
/// written straight into the columns, in parallel over blocks; each worker reuses one
/// block of records, so no `n`-record buffer is made.
fn fill(built: &Built, seed: u64, order: Order, c: ColumnsMut<'_>) {
    let n = c.face_ids.len();
    let sampler = &built.sampler;
    c.positions
        .par_chunks_mut(3 * BLOCK)
        .zip(c.normals.par_chunks_mut(3 * BLOCK))
        .zip(c.barycentrics.par_chunks_mut(3 * BLOCK))
        .zip(c.major_axes.par_chunks_mut(3 * BLOCK))
        .zip(c.spacings.par_chunks_mut(2 * BLOCK))
        .zip(c.face_ids.par_chunks_mut(BLOCK))
        .zip(c.segments.par_chunks_mut(BLOCK))
        .zip(c.ranks.par_chunks_mut(BLOCK))
        .enumerate()
        .for_each_init(
            || vec![Sample::default(); BLOCK],
            |buf, (k, (((((((p, nr), b), m), sp), f), seg), r))| {
                let block = &mut buf[..f.len()];
                let start = k * BLOCK;
                match order {
                    Order::Stratified => {
                        sampler.sample_range_into(seed, n as u64, start as u64, block)
                    }
                    // Ranks fit in u32: n does (checked by the caller).
                    Order::Progressive => sampler.progressive_into(seed, start as u32, block),
                }
                for (i, x) in block.iter().enumerate() {
                    p[3 * i..3 * i + 3].copy_from_slice(&x.position);
                    nr[3 * i..3 * i + 3].copy_from_slice(&x.normal);
                    m[3 * i..3 * i + 3].copy_from_slice(&x.major_axis);
                    b[3 * i..3 * i + 3].copy_from_slice(&barycentric(x.bary));
                    sp[2 * i..2 * i + 2].copy_from_slice(&x.spacing);
                    f[i] = x.face;
                    seg[i] = x.segment;
                    r[i] = x.index;
                }
            },
        );
}

/// The three barycentric coordinates from the engine's two (corners 1 and 2).
fn barycentric(b: [f32; 2]) -> [f32; 3] {
    [1.0 - b[0] - b[1], b[0], b[1]]
}

impl Columns {
    /// The columns as numpy arrays over the same buffers, each handed back to `pool`
    /// when numpy frees it.
    fn into_samples(self, py: Python<'_>, pool: &Arc<Pool>) -> PyResult<Samples> {
        let n = self.n;
        let mat = |v: Vec<f32>, cols: usize| -> PyResult<Py<PyArray2<f32>>> {
            Ok(pool::array(py, v, Ix2(n, cols), pool)?.unbind())
        };
        let vec = |v: Vec<u32>| -> PyResult<Py<PyArray1<u32>>> {
            Ok(pool::array(py, v, Ix1(n), pool)?.unbind())
        };
        Ok(Samples {
            positions: mat(self.positions, 3)?,
            normals: mat(self.normals, 3)?,
            barycentrics: mat(self.barycentrics, 3)?,
            major_axes: mat(self.major_axes, 3)?,
            spacings: mat(self.spacings, 2)?,
            face_ids: vec(self.face_ids)?,
            segments: vec(self.segments)?,
            ranks: vec(self.ranks)?,
            len: n,
        })
    }
}
