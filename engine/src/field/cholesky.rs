//! Sparse Cholesky factors whose memory outlives them: the field solves factor two or
//! three matrices of one pattern in a row, and on the bunny zeroing a fresh 29 MB factor
//! (the page faults of a new allocation) cost about as much as a third of the
//! factorization itself. A [`Cholesky`] hands its buffers back as [`Storage`] for the
//! next factorization to reuse. The parameterization's sparse solves
//! (`param::spd`) factor and solve with it too, on their own symbolic factorization.
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

use super::line_field::LineFieldError;

/// A shared symbolic factorization (fill-reducing ordering and supernodes).
pub(crate) type Symbolic = Arc<SymbolicCholesky<usize>>;

/// The symbolic factorization of a pattern's lower triangle, AMD-ordered.
pub(crate) fn symbolic(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Result<Symbolic, LineFieldError> {
    factorize_symbolic_cholesky(
        pattern,
        Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .map(Arc::new)
    .map_err(|_| LineFieldError::Factorization {
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

/// `buffer`, or a new one when it cannot hold `req`.
fn sized(buffer: Option<MemBuffer>, req: StackReq) -> Result<MemBuffer, LineFieldError> {
    if let Some(mut b) = buffer
        && MemStack::new(&mut b).can_hold(req)
    {
        return Ok(b);
    }
    MemBuffer::try_new(req).map_err(|_| LineFieldError::Factorization {
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
    ) -> Result<Self, LineFieldError> {
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
                .map_err(|_| LineFieldError::Factorization {
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
            .map_err(|_| LineFieldError::Factorization {
                stage: "numeric factorization (matrix not positive definite)",
            })?;
        Ok(Self {
            symbolic,
            values,
            scratch,
        })
    }

    /// Solves `A X = B` in place for the columns of `rhs`.
    pub(crate) fn solve(&mut self, mut rhs: MatMut<'_, T>) -> Result<(), LineFieldError> {
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

    use super::*;
    use crate::field::pattern::VertexPattern;
    use crate::mesh::shapes;

    /// `L + shift I` on the mesh's vertex graph (`L` the graph Laplacian), complex
    /// with unit-modulus couplings `-e^(i phase)`: Hermitian positive definite.
    fn solve_with(
        pattern: &VertexPattern,
        symbolic: &Symbolic,
        shift: f64,
        phase: f64,
        degree: &[f64],
        storage: Option<Storage<c64>>,
    ) -> (Vec<c64>, Storage<c64>) {
        let values = pattern.values(
            |v| c64::new(degree[v] + shift, 0.0),
            |e| -c64::new((phase * e as f64).cos(), (phase * e as f64).sin()),
        );
        let mut llt = Cholesky::new(symbolic.clone(), pattern.matrix(&values), storage)
            .expect("valid test input");
        let n = degree.len();
        let mut z: Vec<c64> = (0..n).map(|v| c64::new(v as f64, 1.0)).collect();
        llt.solve(MatMut::from_column_major_slice_mut(&mut z, n, 1))
            .expect("valid test input");
        (z, llt.into_storage())
    }

    #[test]
    fn reused_buffers_give_the_same_bits_as_fresh_ones() {
        let mesh = shapes::sphere(1.0, 4).expect("valid test input");
        let pattern = VertexPattern::new(&mesh).expect("valid test input");
        let symbolic = symbolic(pattern.symbolic()).expect("valid test input");
        let mut degree = vec![0.0; mesh.vertex_count()];
        for &[a, b] in mesh.edges() {
            degree[a as usize] += 1.0;
            degree[b as usize] += 1.0;
        }
        let (fresh, _) = solve_with(&pattern, &symbolic, 0.5, 0.3, &degree, None);
        // Buffers of another matrix's factor, and buffers allocated (touched) ahead.
        let (_, used) = solve_with(&pattern, &symbolic, 2.0, 1.1, &degree, None);
        let (reused, _) = solve_with(&pattern, &symbolic, 0.5, 0.3, &degree, Some(used));
        let ahead = Storage::allocate(&symbolic).expect("valid test input");
        let (allocated, _) = solve_with(&pattern, &symbolic, 0.5, 0.3, &degree, Some(ahead));
        assert_eq!(fresh, reused);
        assert_eq!(fresh, allocated);
        // And the solve is right: the residual of A z = b is round-off.
        let mut az: Vec<c64> = (0..degree.len())
            .map(|v| c64::new(degree[v] + 0.5, 0.0) * fresh[v])
            .collect();
        for (e, &[a, b]) in mesh.edges().iter().enumerate() {
            let (a, b) = (a as usize, b as usize);
            let lower = -c64::new((0.3 * e as f64).cos(), (0.3 * e as f64).sin());
            az[b] += lower * fresh[a];
            az[a] += lower.conj() * fresh[b];
        }
        for (v, r) in az.iter().enumerate() {
            assert!((*r - c64::new(v as f64, 1.0)).norm() < 1e-9, "row {v}: {r}");
        }
    }

    #[test]
    fn an_indefinite_matrix_is_an_error() {
        let mesh = shapes::sphere(1.0, 3).expect("valid test input");
        let pattern = VertexPattern::new(&mesh).expect("valid test input");
        let symbolic = symbolic(pattern.symbolic()).expect("valid test input");
        let values = pattern.values(|_| -1.0f64, |_| 0.0);
        assert!(Cholesky::new(symbolic, pattern.matrix(&values), None).is_err());
    }
}
