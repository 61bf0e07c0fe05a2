//! Sparse linear algebra that scales linearly with the mesh: compressed sparse row
//! matrices ([`Csr`]), a smoothed-aggregation algebraic multigrid hierarchy ([`Amg`])
//! and conjugate gradients preconditioned by it ([`pcg::solve`]), for Hermitian
//! positive definite systems over `f64` or `c64` ([`Scalar`]).
//!
//! Sparse Cholesky (faer) is exact and fast on small meshes, but its fill and work
//! grow faster than the mesh (on the bunny Loop-subdivided twice, 556k vertices, the
//! factor of a Laplacian holds 51M non-zeros, 92 per vertex, against 52 at 35k). A
//! multigrid-preconditioned solve costs a bounded number of linear-time cycles.
//!
//! The crate's other linear algebra lives here too: the sparse Cholesky factor whose
//! buffers are reused across factorizations (`cholesky`, faer's supernodal `L L^H`,
//! used by the field design, the parameterization and the segmentation's random
//! walker), and the Rayleigh-Ritz eigensolver for the smallest eigenpair of a pencil
//! `A z = lambda M z` with diagonal `M` (`lanczos`). Every part reports one error type,
//! [`LinalgError`], which each stage maps into its own.
//!
//! ```
//! use strata_engine::linalg::{Amg, AmgOptions, Csr, pcg};
//! // The 1D Laplacian plus a small mass: tridiagonal, positive definite.
//! let n = 1000;
//! let mut t = Vec::new();
//! for i in 0..n {
//!     t.push((i, i, 2.001));
//!     if i + 1 < n {
//!         t.push((i, i + 1, -1.0));
//!         t.push((i + 1, i, -1.0));
//!     }
//! }
//! let a = Csr::from_triplets(n, n, &t);
//! let amg = Amg::new(a.clone(), None, &AmgOptions::default())?;
//! let b = vec![1.0; n];
//! let mut x = vec![0.0; n];
//! let report = pcg::solve(&amg, &b, &mut x, 1e-10, 100)?;
//! let mut ax = vec![0.0; n];
//! a.mul_into(&x, &mut ax);
//! assert!(ax.iter().zip(&b).all(|(l, r)| (l - r).abs() < 1e-8));
//! assert!(report.iterations < 30);
//! # Ok::<(), strata_engine::linalg::LinalgError>(())
//! ```

mod amg;
pub(crate) mod cholesky;
mod csr;
mod dense;
pub mod dissection;
mod error;
pub(crate) mod lanczos;
pub mod pcg;
mod scalar;

pub use amg::{Amg, AmgOptions, Workspace};
pub use csr::{Csr, PARALLEL_ROWS, breadth_first};
pub use dense::DenseCholesky;
pub use error::LinalgError;
pub use scalar::{Scalar, Vector, dot, norm2};

#[cfg(test)]
mod tests;
