//! The sparsity pattern of a mesh's vertex graph as the lower triangle of a compressed
//! sparse column matrix, with the value slot of every vertex and edge, so that each
//! matrix of the field solves is filled in O(V + E) instead of sorted from triplets.
//!
//! Column `j` holds the diagonal `j` and then the rows `k > j` of the edges `[j, k]`.
//! [`TriMesh::edges`] lists its edges as sorted pairs in lexicographic order, so the
//! rows of every column come out sorted without a sort.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};

use crate::field::LineFieldError;
use crate::mesh::TriMesh;

/// The lower-triangle pattern of a mesh's vertex graph (see the [module docs](self)).
#[derive(Debug)]
pub(crate) struct VertexPattern {
    symbolic: SymbolicSparseColMat<usize>,
    /// Per vertex, the slot of its diagonal entry.
    diagonal: Vec<usize>,
    /// Per edge, the slot of its entry `(larger vertex, smaller vertex)`.
    edges: Vec<usize>,
}

impl VertexPattern {
    /// The pattern of `mesh`. Errors ("assembly") only if the mesh's edge list breaks its
    /// documented order, which [`TriMesh`] construction rules out.
    pub(crate) fn new(mesh: &TriMesh) -> Result<Self, LineFieldError> {
        let n = mesh.vertex_count();
        let list = mesh.edges();
        let broken = || LineFieldError::Factorization { stage: "assembly" };
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(n + list.len());
        let mut diagonal = Vec::with_capacity(n);
        let mut edges = Vec::with_capacity(list.len());
        let mut next = 0;
        for j in 0..n {
            col_ptr.push(row_idx.len());
            diagonal.push(row_idx.len());
            row_idx.push(j);
            let mut last = j;
            while let Some(&[a, b]) = list.get(next) {
                let (a, b) = (a as usize, b as usize);
                if a != j {
                    break;
                }
                if b <= last || b >= n {
                    return Err(broken());
                }
                edges.push(row_idx.len());
                row_idx.push(b);
                last = b;
                next += 1;
            }
        }
        if next != list.len() {
            return Err(broken());
        }
        col_ptr.push(row_idx.len());
        Ok(Self {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            diagonal,
            edges,
        })
    }

    /// The pattern, for the symbolic factorization.
    pub(crate) fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }

    /// The values of the matrix with `diagonal(v)` at `(v, v)` and `off(e)` at edge
    /// `e`'s lower entry `(larger vertex, smaller vertex)`, in slot order.
    pub(crate) fn values<T: Copy + Default>(
        &self,
        diagonal: impl Fn(usize) -> T,
        off: impl Fn(usize) -> T,
    ) -> Vec<T> {
        let mut values = vec![T::default(); self.symbolic.row_idx().len()];
        for (v, &slot) in self.diagonal.iter().enumerate() {
            values[slot] = diagonal(v);
        }
        for (e, &slot) in self.edges.iter().enumerate() {
            values[slot] = off(e);
        }
        values
    }

    /// The matrix of `values` (from [`values`](Self::values)).
    pub(crate) fn matrix<'a, T>(&'a self, values: &'a [T]) -> SparseColMatRef<'a, usize, T> {
        SparseColMatRef::new(self.symbolic.as_ref(), values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    #[test]
    fn the_pattern_holds_every_edge_once_below_the_diagonal() {
        let mesh = shapes::torus(1.0, 0.4, 8).expect("valid test input");
        let pattern = VertexPattern::new(&mesh).expect("valid test input");
        let n = mesh.vertex_count();
        let s = pattern.symbolic();
        assert_eq!(s.row_idx().len(), n + mesh.edge_count());
        // Fill with distinct values and read them back by position.
        let values = pattern.values(|v| v as f64, |e| -(e as f64) - 1.0);
        let matrix = pattern.matrix(&values);
        for j in 0..n {
            let rows = matrix.symbolic().row_idx_of_col_raw(j);
            let vals = matrix.val_of_col(j);
            assert_eq!((rows[0], vals[0]), (j, j as f64));
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "column {j} unsorted");
        }
        for (e, &[a, b]) in mesh.edges().iter().enumerate() {
            let (a, b) = (a as usize, b as usize);
            let rows = matrix.symbolic().row_idx_of_col_raw(a);
            let k = rows.iter().position(|&r| r == b).expect("valid test input");
            assert_eq!(matrix.val_of_col(a)[k], -(e as f64) - 1.0);
        }
    }
}
