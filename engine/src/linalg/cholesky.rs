//! Sparse Cholesky factors whose memory outlives them: the field solves factor two or
//! three matrices of one pattern in a row, and on the bunny zeroing a fresh 29 MB factor
//! (the page faults of a new allocation) cost about as much as a third of the
//! factorization itself. A [`Cholesky`] hands its buffers back as [`Storage`] for the
//! next factorization to reuse. The parameterization's sparse solves
//! (`param::spd`) and the random walker of the segmentation (`segment::graph_walk`)
//! factor and solve with it too, on their own symbolic factorizations.
//!
//! Input: a symbolic factorization (AMD ordering, faer's supernodal layout) shared by
//! every matrix of the pattern, and a Hermitian matrix's lower triangle. Output: the
//! factor, solving in place without allocating once its scratch is sized. Sequential
//! (`Par::Seq`): faer's parallel factorization was no faster on 2 cores (bench/README
//! "Field design").

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::SparseColMatRef;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side};

use super::error::LinalgError;

/// A shared symbolic factorization (fill-reducing ordering and supernodes).
pub(crate) type Symbolic = Arc<SymbolicCholesky<usize>>;

/// The symbolic factorization of a pattern's lower triangle, AMD-ordered.
pub(crate) fn symbolic(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Result<Symbolic, LinalgError> {
    factorize_symbolic_cholesky(
        pattern,
        Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .map(Arc::new)
    .map_err(|_| LinalgError::Factorization {
        stage: "symbolic factorization",
    })
}

/// The buffers of a factor, kept for the next one.
pub(crate) struct Storage<T> {
    values: Vec<T>,
    scratch: MemBuffer,
}

impl<T: ComplexField> Storage<T> {
    /// Buffers for a factor of `symbolic`, with every page of the values written (so a
    /// second thread can take the page faults ahead of the factorization); `None` when
    /// the memory is not available (the factorization then reports it).
    pub(crate) fn allocate(symbolic: &Symbolic) -> Option<Self> {
        let len = symbolic.len_val();
        let mut values = Vec::new();
        values.try_reserve_exact(len).ok()?;
        values.resize(len, T::zero_impl());
        let scratch = MemBuffer::try_new(scratch_req::<T>(symbolic)).ok()?;
        Some(Self { values, scratch })
    }
}

/// The scratch of a factorization of `symbolic` and of a one-column solve.
fn scratch_req<T: ComplexField>(symbolic: &Symbolic) -> StackReq {
    symbolic
        .factorize_numeric_llt_scratch::<T>(Par::Seq, Default::default())
        .or(symbolic.solve_in_place_scratch::<T>(1, Par::Seq))
}

/// A numeric `L L^H` factor and the scratch its solves use.
pub(crate) struct Cholesky<T> {
    symbolic: Symbolic,
    values: Vec<T>,
    scratch: MemBuffer,
}

impl<T> std::fmt::Debug for Cholesky<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("unknowns", &self.symbolic.nrows())
            .field("factor_entries", &self.values.len())
            .finish_non_exhaustive()
    }
}

/// `buffer`, or a new one when it cannot hold `req`.
fn sized(buffer: Option<MemBuffer>, req: StackReq) -> Result<MemBuffer, LinalgError> {
    if let Some(mut b) = buffer
        && MemStack::new(&mut b).can_hold(req)
    {
        return Ok(b);
    }
    MemBuffer::try_new(req).map_err(|_| LinalgError::Factorization {
        stage: "factor workspace (out of memory)",
    })
}

impl<T: ComplexField> Cholesky<T> {
    /// Factors `matrix` (lower triangle read) with `symbolic`, reusing `storage`'s
    /// buffers when given.
    pub(crate) fn new(
        symbolic: Symbolic,
        matrix: SparseColMatRef<'_, usize, T>,
        storage: Option<Storage<T>>,
    ) -> Result<Self, LinalgError> {
        let par = Par::Seq;
        let len = symbolic.len_val();
        let (mut values, scratch) = match storage {
            Some(s) => (s.values, Some(s.scratch)),
            None => (Vec::new(), None),
        };
        if values.len() != len {
            values.clear();
            values
                .try_reserve_exact(len)
                .map_err(|_| LinalgError::Factorization {
                    stage: "factor values (out of memory)",
                })?;
            // The supernodal factorization zeroes the values itself; this only sets the
            // length (a reused buffer of the right length is written over as it is).
            values.resize(len, T::zero_impl());
        }
        let mut scratch = sized(scratch, scratch_req::<T>(&symbolic))?;
        symbolic
            .factorize_numeric_llt::<T>(
                &mut values,
                matrix,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|_| LinalgError::Factorization {
                stage: "numeric factorization (matrix not positive definite)",
            })?;
        Ok(Self {
            symbolic,
            values,
            scratch,
        })
    }

    /// Solves `A X = B` in place for the columns of `rhs`.
    pub(crate) fn solve(&mut self, mut rhs: MatMut<'_, T>) -> Result<(), LinalgError> {
        let par = Par::Seq;
        let req = self.symbolic.solve_in_place_scratch::<T>(rhs.ncols(), par);
        let scratch = std::mem::replace(&mut self.scratch, MemBuffer::new(StackReq::EMPTY));
        self.scratch = sized(Some(scratch), req)?;
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs.as_mut(),
            par,
            MemStack::new(&mut self.scratch),
        );
        Ok(())
    }

    /// Solves `A X = B` in place for the columns of `rhs` with scratch of its own, so
    /// that several threads can solve with one factor at once.
    ///
    /// # Panics
    /// If the scratch cannot be allocated.
    pub(crate) fn solve_shared(&self, mut rhs: MatMut<'_, T>) {
        let par = Par::Seq;
        let mut scratch =
            MemBuffer::new(self.symbolic.solve_in_place_scratch::<T>(rhs.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs.as_mut(),
            par,
            MemStack::new(&mut scratch),
        );
    }

    /// Unknowns.
    pub(crate) fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// The buffers, for the next factorization.
    pub(crate) fn into_storage(self) -> Storage<T> {
        Storage {
            values: self.values,
            scratch: self.scratch,
        }
    }
}

#[cfg(test)]
mod tests {
    use faer::c64;
    use faer::sparse::{SparseColMat, Triplet};

    use super::*;
    use crate::mesh::shapes;

    /// The lower triangle of `L + shift I` on the mesh's vertex graph (`L` the graph
    /// Laplacian), complex with unit-modulus couplings `-e^(i phase)` (per edge `e`):
    /// Hermitian positive definite for a positive shift.
    fn matrix(
        edges: &[[u32; 2]],
        degree: &[f64],
        shift: f64,
        phase: f64,
    ) -> SparseColMat<usize, c64> {
        let mut t: Vec<_> = (0..degree.len())
            .map(|v| Triplet::new(v, v, c64::new(degree[v] + shift, 0.0)))
            .collect();
        for (e, &[a, b]) in edges.iter().enumerate() {
            let (lo, hi) = (a.min(b) as usize, a.max(b) as usize);
            let w = -c64::new((phase * e as f64).cos(), (phase * e as f64).sin());
            // Row `hi`, column `lo`: the coupling of the higher vertex to the lower.
            t.push(Triplet::new(hi, lo, if a < b { w } else { w.conj() }));
        }
        SparseColMat::try_new_from_triplets(degree.len(), degree.len(), &t)
            .expect("valid test input")
    }

    fn solve_with(
        edges: &[[u32; 2]],
        symbolic: &Symbolic,
        shift: f64,
        phase: f64,
        degree: &[f64],
        storage: Option<Storage<c64>>,
    ) -> (Vec<c64>, Storage<c64>) {
        let a = matrix(edges, degree, shift, phase);
        let mut llt =
            Cholesky::new(symbolic.clone(), a.as_ref(), storage).expect("valid test input");
        let n = degree.len();
        let mut z: Vec<c64> = (0..n).map(|v| c64::new(v as f64, 1.0)).collect();
        let mut shared = z.clone();
        llt.solve(MatMut::from_column_major_slice_mut(&mut z, n, 1))
            .expect("valid test input");
        llt.solve_shared(MatMut::from_column_major_slice_mut(&mut shared, n, 1));
        assert_eq!(z, shared);
        (z, llt.into_storage())
    }

    #[test]
    fn reused_buffers_give_the_same_bits_as_fresh_ones() {
        let mesh = shapes::sphere(1.0, 4).expect("valid test input");
        let edges = mesh.edges();
        let mut degree = vec![0.0; mesh.vertex_count()];
        for &[a, b] in edges {
            degree[a as usize] += 1.0;
            degree[b as usize] += 1.0;
        }
        let pattern = matrix(edges, &degree, 1.0, 0.0);
        let symbolic = symbolic(pattern.symbolic()).expect("valid test input");
        let (fresh, _) = solve_with(edges, &symbolic, 0.5, 0.3, &degree, None);
        // Buffers of another matrix's factor, and buffers allocated (touched) ahead.
        let (_, used) = solve_with(edges, &symbolic, 2.0, 1.1, &degree, None);
        let (reused, _) = solve_with(edges, &symbolic, 0.5, 0.3, &degree, Some(used));
        let ahead = Storage::allocate(&symbolic).expect("valid test input");
        let (allocated, _) = solve_with(edges, &symbolic, 0.5, 0.3, &degree, Some(ahead));
        assert_eq!(fresh, reused);
        assert_eq!(fresh, allocated);
        // And the solve is right: the residual of A z = b is round-off.
        let mut az: Vec<c64> = (0..degree.len())
            .map(|v| c64::new(degree[v] + 0.5, 0.0) * fresh[v])
            .collect();
        for (e, &[a, b]) in edges.iter().enumerate() {
            let (lo, hi) = (a.min(b) as usize, a.max(b) as usize);
            let w = -c64::new((0.3 * e as f64).cos(), (0.3 * e as f64).sin());
            let lower = if a < b { w } else { w.conj() };
            az[hi] += lower * fresh[lo];
            az[lo] += lower.conj() * fresh[hi];
        }
        for (v, r) in az.iter().enumerate() {
            assert!((*r - c64::new(v as f64, 1.0)).norm() < 1e-9, "row {v}: {r}");
        }
    }

    #[test]
    fn an_indefinite_matrix_is_an_error() {
        let t: Vec<_> = (0..4).map(|v| Triplet::new(v, v, -1.0f64)).collect();
        let a = SparseColMat::try_new_from_triplets(4, 4, &t).expect("valid test input");
        let symbolic = symbolic(a.symbolic()).expect("valid test input");
        let err = Cholesky::new(symbolic, a.as_ref(), None).err();
        assert!(
            matches!(err, Some(LinalgError::Factorization { stage }) if stage.starts_with("numeric")),
            "{err:?}"
        );
    }
}
