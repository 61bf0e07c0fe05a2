//! # strata-engine
//!
//! The pure algorithms of strata: anisotropic, density-controlled, stratified sampling
//! of triangle-mesh surfaces (Quinn et al., "Generalized Anisotropic Stratified Surface
//! Sampling"; see `DESIGN.md`). Every stage is a plain function or a small struct from
//! plain data to plain data; there is no ECS, no GPU and no file watching here.
//!
//! | module | stage |
//! | --- | --- |
//! | [`mesh`] | `TriMesh` with adjacency; OBJ/PLY loading, writing, built-in shapes |
//! | [`io`] | OBJ/PLY readers, PLY/CSV writers for meshes and samples |
//! | [`field`] | per-vertex tensor fields and their sources |
//! | [`linalg`] | sparse matrices, algebraic multigrid and preconditioned conjugate gradients |
//! | [`segment`] | field-driven segmentation into singularity-free discs |
//! | [`param`] | field-aligned parameterization of one segment, with its validity |
//! | [`curve`] | Hilbert curves and adaptive Hilbert cells with measures |
//! | [`surface`] | the front door: planar fast path or segmentation + parameterization (with splitting) + cells |
//! | [`planar`] | flat domains as one segment, by one linear map |
//! | [`sample`] | 1D stratified sequences mapped through the cells to surface samples |
//! | [`analysis`] | discrepancy and other quality measures |
//! | [`rng`] | counter-based random numbers (thread-count independent) |

pub mod analysis;
mod cpu;
pub mod curve;
mod fast_map;
pub mod field;
#[cfg(any(test, feature = "fixtures"))]
pub mod fixtures;
pub mod io;
pub mod linalg;
pub mod mesh;
pub mod param;
pub mod planar;
pub mod rng;
pub mod sample;
pub mod segment;
pub mod surface;

/// Runs `f` on a new rayon pool of `threads` threads: the tests' check that results do
/// not depend on the thread count.
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}
