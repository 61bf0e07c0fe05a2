//! Compressed sparse row matrices: assembly from triplets, products, and the Galerkin
//! triple product of the multigrid hierarchy.
//!
//! From [`PARALLEL_ROWS`] rows the products and the renumbering run on every thread, in
//! blocks of whole rows. Each row is computed by the same operations in the same order
//! as on one thread, so the results are bit for bit those of a sequential run, whatever
//! the thread count.

use std::ops::Range;

use rayon::prelude::*;

use super::scalar::{Scalar, Vector};

/// Matrices with at least this many rows multiply and renumber on every thread (below
/// it the rayon hand-off costs more than it saves).
pub const PARALLEL_ROWS: usize = 32_768;

/// Rows per block of a parallel pass, at least.
const MIN_BLOCK_ROWS: usize = 4096;

/// Rows per block of a parallel pass over `rows` rows: a few blocks per thread so that
/// work stealing can even out uneven rows. The results never depend on the cut.
fn block_rows(rows: usize) -> usize {
    let blocks = 4 * rayon::current_num_threads().max(1);
    rows.div_ceil(blocks).max(MIN_BLOCK_ROWS)
}

/// The rows `0..rows` cut into consecutive blocks of [`block_rows`] rows.
fn row_blocks(rows: usize) -> Vec<Range<usize>> {
    let size = block_rows(rows);
    (0..rows)
        .step_by(size)
        .map(|start| start..(start + size).min(rows))
        .collect()
}

/// Rows made by one block of a parallel pass: each row's end within the block's entries.
struct RowBlock<S> {
    ends: Vec<usize>,
    indices: Vec<u32>,
    values: Vec<S>,
}

impl<S> RowBlock<S> {
    fn with_rows(rows: usize) -> Self {
        Self {
            ends: Vec::with_capacity(rows),
            indices: Vec::new(),
            values: Vec::new(),
        }
    }
}

/// A sparse matrix in compressed sparse row form, with sorted, unique columns per row.
#[derive(Clone, Debug, PartialEq)]
pub struct Csr<S> {
    rows: usize,
    cols: usize,
    starts: Vec<usize>,
    indices: Vec<u32>,
    values: Vec<S>,
}

impl<S: Scalar> Csr<S> {
    /// The `rows x cols` matrix with the sum of the values given at each position
    /// (`(row, col, value)`; entries out of range are a caller bug and panic).
    /// Deterministic: duplicates are summed in the order given.
    pub fn from_triplets(rows: usize, cols: usize, triplets: &[(usize, usize, S)]) -> Self {
        let mut counts = vec![0usize; rows + 1];
        for &(r, c, _) in triplets {
            assert!(
                r < rows && c < cols,
                "triplet ({r}, {c}) outside {rows} x {cols}"
            );
            counts[r + 1] += 1;
        }
        for r in 0..rows {
            counts[r + 1] += counts[r];
        }
        let mut next = counts.clone();
        let mut order = vec![(0u32, S::ZERO); triplets.len()];
        for &(r, c, v) in triplets {
            order[next[r]] = (c as u32, v);
            next[r] += 1;
        }
        let mut starts = Vec::with_capacity(rows + 1);
        let mut indices = Vec::with_capacity(triplets.len());
        let mut values = Vec::with_capacity(triplets.len());
        starts.push(0);
        for r in 0..rows {
            let row = &mut order[counts[r]..counts[r + 1]];
            // A stable sort keeps duplicates in the given order, so their sum is too.
            row.sort_by_key(|&(c, _)| c);
            for &(c, v) in row.iter() {
                if indices.len() > starts[r] && indices[indices.len() - 1] == c {
                    let last = values.len() - 1;
                    values[last] += v;
                } else {
                    indices.push(c);
                    values.push(v);
                }
            }
            starts.push(indices.len());
        }
        Self {
            rows,
            cols,
            starts,
            indices,
            values,
        }
    }

    /// The `rows x cols` matrix of the given compressed rows: `starts` (one more than
    /// the rows, from 0, non-decreasing, ending at the entries), and per entry its
    /// column (increasing within each row, below `cols`) and value. Panics where they
    /// break that form (a caller bug, as an out-of-range triplet is).
    pub fn from_sorted_rows(
        rows: usize,
        cols: usize,
        starts: Vec<usize>,
        indices: Vec<u32>,
        values: Vec<S>,
    ) -> Self {
        assert!(
            starts.len() == rows + 1
                && starts.first() == Some(&0)
                && starts.last() == Some(&indices.len())
                && indices.len() == values.len()
                && starts.windows(2).all(|w| w[0] <= w[1]),
            "compressed rows of inconsistent lengths"
        );
        assert!(
            starts.windows(2).all(|w| {
                let row = &indices[w[0]..w[1]];
                row.windows(2).all(|c| c[0] < c[1])
                    && row.last().is_none_or(|&c| (c as usize) < cols)
            }),
            "compressed rows with unsorted or out-of-range columns"
        );
        Self {
            rows,
            cols,
            starts,
            indices,
            values,
        }
    }

    /// Rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row `r`'s columns and values.
    pub fn row(&self, r: usize) -> (&[u32], &[S]) {
        let range = self.starts[r]..self.starts[r + 1];
        (&self.indices[range.clone()], &self.values[range])
    }

    /// Row `r`'s columns and mutable values.
    pub fn row_mut(&mut self, r: usize) -> (&[u32], &mut [S]) {
        let range = self.starts[r]..self.starts[r + 1];
        (&self.indices[range.clone()], &mut self.values[range])
    }

    /// The diagonal entry of row `r` (zero if absent).
    pub fn diagonal(&self, r: usize) -> S {
        let (cols, vals) = self.row(r);
        cols.binary_search(&(r as u32)).map_or(S::ZERO, |k| vals[k])
    }

    /// `y = A x` (on every thread from [`PARALLEL_ROWS`] rows), `x` and `y` of scalars
    /// or of several columns side by side ([`Vector`]).
    pub fn mul_into<V: Vector<S>>(&self, x: &[V], y: &mut [V]) {
        let y = &mut y[..self.rows];
        let rows_from = |first: usize, out: &mut [V]| {
            for (k, out) in out.iter_mut().enumerate() {
                let (cols, vals) = self.row(first + k);
                let mut sum = V::zero();
                for (&c, &v) in cols.iter().zip(vals) {
                    sum += V::times(v, x[c as usize]);
                }
                *out = sum;
            }
        };
        if self.rows < PARALLEL_ROWS {
            rows_from(0, y);
        } else {
            let size = block_rows(self.rows);
            y.par_chunks_mut(size)
                .enumerate()
                .for_each(|(b, out)| rows_from(b * size, out));
        }
    }

    /// The matrix made of `rows` rows, each written by `row(r, indices, values)` (which
    /// appends row `r`'s sorted columns and values), on every thread from
    /// [`PARALLEL_ROWS`] rows with one `state` per block.
    fn from_rows<T>(
        rows: usize,
        cols: usize,
        state: impl Fn() -> T + Sync,
        row: impl Fn(&mut T, usize, &mut Vec<u32>, &mut Vec<S>) + Sync,
    ) -> Self {
        let block = |range: Range<usize>| {
            let mut state = state();
            let mut out = RowBlock::with_rows(range.len());
            for r in range {
                row(&mut state, r, &mut out.indices, &mut out.values);
                out.ends.push(out.indices.len());
            }
            out
        };
        let blocks: Vec<RowBlock<S>> = if rows < PARALLEL_ROWS {
            vec![block(0..rows)]
        } else {
            row_blocks(rows).into_par_iter().map(block).collect()
        };
        let nnz = blocks.iter().map(|b| b.indices.len()).sum();
        let mut starts = Vec::with_capacity(rows + 1);
        let mut indices = Vec::with_capacity(nnz);
        let mut values = Vec::with_capacity(nnz);
        starts.push(0);
        for b in blocks {
            let offset = indices.len();
            starts.extend(b.ends.iter().map(|e| e + offset));
            indices.extend_from_slice(&b.indices);
            values.extend_from_slice(&b.values);
        }
        Self {
            rows,
            cols,
            starts,
            indices,
            values,
        }
    }

    /// `A^H` (the conjugate transpose).
    pub fn adjoint(&self) -> Self {
        let mut counts = vec![0usize; self.cols + 1];
        for &c in &self.indices {
            counts[c as usize + 1] += 1;
        }
        for c in 0..self.cols {
            counts[c + 1] += counts[c];
        }
        let mut next = counts.clone();
        let mut indices = vec![0u32; self.nnz()];
        let mut values = vec![S::ZERO; self.nnz()];
        // Rows in increasing order, so every output row comes out sorted.
        for r in 0..self.rows {
            let (cols, vals) = self.row(r);
            for (&c, &v) in cols.iter().zip(vals) {
                let k = next[c as usize];
                indices[k] = r as u32;
                values[k] = v.conj();
                next[c as usize] += 1;
            }
        }
        Self {
            rows: self.cols,
            cols: self.rows,
            starts: counts,
            indices,
            values,
        }
    }

    /// `A B` (Gustavson's row-by-row product with a dense accumulator; on every thread
    /// from [`PARALLEL_ROWS`] rows).
    pub fn matmul(&self, b: &Self) -> Self {
        assert_eq!(
            self.cols, b.rows,
            "matmul of {}x{} by {}x{}",
            self.rows, self.cols, b.rows, b.cols
        );
        // Per block: the dense accumulator, which columns it holds, and their list.
        let state = || {
            (
                vec![S::ZERO; b.cols],
                vec![false; b.cols],
                Vec::<u32>::new(),
            )
        };
        Self::from_rows(
            self.rows,
            b.cols,
            state,
            |(accumulator, seen, pattern), r, indices, values| {
                let (cols, vals) = self.row(r);
                for (&k, &a) in cols.iter().zip(vals) {
                    let (bc, bv) = b.row(k as usize);
                    for (&c, &v) in bc.iter().zip(bv) {
                        let c = c as usize;
                        if !seen[c] {
                            seen[c] = true;
                            pattern.push(c as u32);
                        }
                        accumulator[c] += a * v;
                    }
                }
                pattern.sort_unstable();
                for &c in pattern.iter() {
                    indices.push(c);
                    values.push(accumulator[c as usize]);
                    accumulator[c as usize] = S::ZERO;
                    seen[c as usize] = false;
                }
                pattern.clear();
            },
        )
    }

    /// `Q A Q^T` for the permutation taking old index `order[k]` to new index `k`
    /// (`position[order[k]] == k`; on every thread from [`PARALLEL_ROWS`] rows).
    pub fn permuted(&self, order: &[u32], position: &[u32]) -> Self {
        Self::from_rows(
            self.rows,
            self.cols,
            Vec::<(u32, S)>::new,
            |row, k, indices, values| {
                let (cols, vals) = self.row(order[k] as usize);
                row.clear();
                row.extend(
                    cols.iter()
                        .zip(vals)
                        .map(|(&c, &v)| (position[c as usize], v)),
                );
                row.sort_unstable_by_key(|&(c, _)| c);
                for &(c, v) in row.iter() {
                    indices.push(c);
                    values.push(v);
                }
            },
        )
    }

    /// A breadth-first (Cuthill-McKee) order of the rows of a square matrix, each
    /// connected part from its lowest row: neighbours end up near each other, which
    /// keeps the solvers' memory accesses local whatever the input order. `order[k]` is
    /// the old index of new row `k`.
    pub fn breadth_first_order(&self) -> Vec<u32> {
        breadth_first(self.rows, |r| self.row(r).0.iter().copied())
    }
}

/// A breadth-first (Cuthill-McKee) order of a graph of `n` nodes, `neighbours(v)`
/// listing node `v`'s: each connected part from its lowest node, neighbours visited in
/// the order listed. `order[k]` is the node visited `k`-th. O(nodes + edges).
pub fn breadth_first<I: IntoIterator<Item = u32>>(
    n: usize,
    neighbours: impl Fn(usize) -> I,
) -> Vec<u32> {
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    for start in 0..n {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let mut head = order.len();
        order.push(start as u32);
        while head < order.len() {
            let v = order[head] as usize;
            head += 1;
            for w in neighbours(v) {
                if !visited[w as usize] {
                    visited[w as usize] = true;
                    order.push(w);
                }
            }
        }
    }
    order
}
