//! A mesh's vertex graph as the pattern of the multigrid systems, already in the
//! hierarchy's breadth-first order, so that each real or complex matrix of the field
//! solves is filled row by row in place instead of sorted from triplets and then
//! renumbered (at 1.1M faces the two took 0.18 s for the real system and 0.23 + 0.15 s
//! for the complex one).
//!
//! Row `k` is vertex `order[k]`: its diagonal and one entry per incident edge, columns
//! sorted. The order is the one [`Csr::breadth_first_order`] gives the matrix assembled
//! in vertex order (each connected part from its lowest vertex, neighbours in increasing
//! index), so a hierarchy made from it ([`Amg::ordered`]) is the one [`Amg::new`] makes,
//! bit for bit. [`TriMesh::edges`] lists sorted pairs in lexicographic order, so one
//! pass over the edges lists every vertex's neighbours sorted, without a sort.

use rayon::prelude::*;

use crate::linalg::{Amg, AmgOptions, Csr, LinalgError, Scalar, breadth_first};
use crate::mesh::TriMesh;

/// The source of an entry that is a diagonal, not an edge.
const DIAGONAL: u32 = u32::MAX;

/// Rows per block of the parallel passes (a fixed cut: the results never depend on it).
const BLOCK_ROWS: usize = 8192;

/// The vertex graph of a mesh in breadth-first order (see the [module docs](self)).
#[derive(Debug)]
pub(crate) struct VertexGraph {
    /// `order[k]`: the vertex of row `k`.
    order: Vec<u32>,
    /// Per row, where its entries start (one more than the rows).
    starts: Vec<usize>,
    /// Per entry, its column (a row number).
    columns: Vec<u32>,
    /// Per entry, its edge, or [`DIAGONAL`].
    sources: Vec<u32>,
}

impl VertexGraph {
    /// The graph of `mesh`. O(V + E).
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let n = mesh.vertex_count();
        let edges = mesh.edges();
        // Neighbours per vertex in increasing index (see the module docs), with their
        // edges.
        let mut first = vec![0usize; n + 1];
        for &[a, b] in edges {
            first[a as usize + 1] += 1;
            first[b as usize + 1] += 1;
        }
        for v in 0..n {
            first[v + 1] += first[v];
        }
        let mut fill = first.clone();
        let mut neighbours = vec![(0u32, 0u32); first[n]];
        for (e, &[a, b]) in edges.iter().enumerate() {
            neighbours[fill[a as usize]] = (b, e as u32);
            fill[a as usize] += 1;
            neighbours[fill[b as usize]] = (a, e as u32);
            fill[b as usize] += 1;
        }
        let around = |v: usize| &neighbours[first[v]..first[v + 1]];
        let order = breadth_first(n, |v| around(v).iter().map(|&(w, _)| w));
        let mut position = vec![0u32; n];
        for (k, &v) in order.iter().enumerate() {
            position[v as usize] = k as u32;
        }
        let mut starts = Vec::with_capacity(n + 1);
        starts.push(0);
        for &v in &order {
            let v = v as usize;
            starts.push(starts.last().copied().unwrap_or(0) + first[v + 1] - first[v] + 1);
        }
        let entries = starts[n];
        let mut columns = vec![0u32; entries];
        let mut sources = vec![0u32; entries];
        let rows = |block: usize, columns: &mut [u32], sources: &mut [u32]| {
            let mut row: Vec<(u32, u32)> = Vec::new();
            let base = starts[block * BLOCK_ROWS];
            let end = ((block + 1) * BLOCK_ROWS).min(n);
            for k in block * BLOCK_ROWS..end {
                let v = order[k] as usize;
                row.clear();
                row.push((k as u32, DIAGONAL));
                row.extend(around(v).iter().map(|&(w, e)| (position[w as usize], e)));
                row.sort_unstable_by_key(|&(c, _)| c);
                for (j, &(c, e)) in (starts[k] - base..).zip(&row) {
                    columns[j] = c;
                    sources[j] = e;
                }
            }
        };
        if n <= BLOCK_ROWS {
            rows(0, &mut columns, &mut sources);
        } else {
            // Cut the entries at the blocks' first rows.
            let cuts: Vec<usize> = (BLOCK_ROWS..n)
                .step_by(BLOCK_ROWS)
                .map(|k| starts[k])
                .collect();
            let column_blocks = split_at_cuts(&mut columns, &cuts);
            let source_blocks = split_at_cuts(&mut sources, &cuts);
            column_blocks
                .into_par_iter()
                .zip(source_blocks)
                .enumerate()
                .for_each(|(block, (c, s))| rows(block, c, s));
        }
        Self {
            order,
            starts,
            columns,
            sources,
        }
    }

    /// Rows (vertices).
    pub(crate) fn len(&self) -> usize {
        self.order.len()
    }

    /// The matrix, in this graph's order, with `diagonal(v)` on vertex `v`'s diagonal and
    /// `off(e, larger)` at edge `e`'s entries: `larger` is whether the entry's row is the
    /// edge's larger vertex (its lower-triangle entry in vertex order).
    pub(crate) fn matrix<S: Scalar>(
        &self,
        diagonal: impl Fn(usize) -> S + Sync,
        off: impl Fn(usize, bool) -> S + Sync,
        mesh: &TriMesh,
    ) -> Csr<S> {
        let edges = mesh.edges();
        let mut values = vec![S::ZERO; self.columns.len()];
        let fill = |k: usize, values: &mut [S], base: usize| {
            let v = self.order[k];
            for j in self.starts[k]..self.starts[k + 1] {
                let e = self.sources[j];
                values[j - base] = if e == DIAGONAL {
                    diagonal(v as usize)
                } else {
                    off(e as usize, edges[e as usize][1] == v)
                };
            }
        };
        let n = self.len();
        if n <= BLOCK_ROWS {
            (0..n).for_each(|k| fill(k, &mut values, 0));
        } else {
            let cuts: Vec<usize> = (BLOCK_ROWS..n)
                .step_by(BLOCK_ROWS)
                .map(|k| self.starts[k])
                .collect();
            split_at_cuts(&mut values, &cuts)
                .into_par_iter()
                .enumerate()
                .for_each(|(block, values)| {
                    let first = block * BLOCK_ROWS;
                    let base = self.starts[first];
                    for k in first..(first + BLOCK_ROWS).min(n) {
                        fill(k, values, base);
                    }
                });
        }
        Csr::from_sorted_rows(n, n, self.starts.clone(), self.columns.clone(), values)
    }

    /// The multigrid hierarchy of the matrix of [`matrix`](Self::matrix)'s arguments,
    /// in the caller's (vertex) numbering: what [`Amg::new`] makes of the same matrix
    /// in vertex order.
    pub(crate) fn hierarchy<S: Scalar>(
        &self,
        diagonal: impl Fn(usize) -> S + Sync,
        off: impl Fn(usize, bool) -> S + Sync,
        mesh: &TriMesh,
    ) -> Result<Amg<S>, LinalgError> {
        let matrix = self.matrix(diagonal, off, mesh);
        Amg::ordered(matrix, self.order.clone(), None, &AmgOptions::default())
    }
}

/// `data` cut before each of the increasing offsets `cuts`.
fn split_at_cuts<'a, T>(mut data: &'a mut [T], cuts: &[usize]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(cuts.len() + 1);
    let mut done = 0;
    for &cut in cuts {
        let (head, tail) = data.split_at_mut(cut - done);
        parts.push(head);
        data = tail;
        done = cut;
    }
    parts.push(data);
    parts
}

#[cfg(test)]
mod tests {
    use faer::c64;

    use super::*;
    use crate::mesh::{loop_subdivide, shapes};

    /// The matrix in vertex order from triplets, as the solvers assembled it before.
    fn from_triplets<S: Scalar>(
        mesh: &TriMesh,
        diagonal: impl Fn(usize) -> S,
        off: impl Fn(usize, bool) -> S,
    ) -> Csr<S> {
        let n = mesh.vertex_count();
        let mut t: Vec<(usize, usize, S)> = (0..n).map(|v| (v, v, diagonal(v))).collect();
        for (e, &[a, b]) in mesh.edges().iter().enumerate() {
            t.push((b as usize, a as usize, off(e, true)));
            t.push((a as usize, b as usize, off(e, false)));
        }
        Csr::from_triplets(n, n, &t)
    }

    #[test]
    fn the_ordered_matrix_is_the_renumbered_vertex_matrix_at_every_block_cut() {
        // The torus fits one block; subdivided twice it spans several block cuts. The
        // values tell every entry apart.
        let torus = shapes::torus(1.0, 0.4, 32).expect("valid test input");
        let twice = loop_subdivide(&loop_subdivide(&torus).expect("valid test input"))
            .expect("valid test input");
        assert!(torus.vertex_count() <= BLOCK_ROWS && twice.vertex_count() > 2 * BLOCK_ROWS);
        for mesh in [torus, twice] {
            let diagonal = |v: usize| c64::new(v as f64 + 0.5, 0.0);
            let off = |e: usize, larger: bool| {
                let c = c64::new(-(e as f64) - 1.0, e as f64 * 0.25);
                if larger { c } else { c.conj() }
            };
            let graph = VertexGraph::new(&mesh);
            let reference = from_triplets(&mesh, diagonal, off);
            let order = reference.breadth_first_order();
            assert_eq!(graph.order, order, "{} vertices", mesh.vertex_count());
            let mut position = vec![0u32; order.len()];
            for (k, &v) in order.iter().enumerate() {
                position[v as usize] = k as u32;
            }
            assert_eq!(
                graph.matrix(diagonal, off, &mesh),
                reference.permuted(&order, &position)
            );
        }
    }

    #[test]
    fn its_hierarchy_solves_as_the_one_made_from_triplets() {
        let mesh = shapes::torus(1.0, 0.4, 48).expect("valid test input");
        let n = mesh.vertex_count();
        let diagonal = |v: usize| 6.0 + (v % 7) as f64 * 0.01;
        let off = |_: usize, _: bool| -1.0;
        let graph = VertexGraph::new(&mesh);
        let ordered = graph
            .hierarchy(diagonal, off, &mesh)
            .expect("valid test input");
        let plain = Amg::new(
            from_triplets(&mesh, diagonal, off),
            None,
            &AmgOptions::default(),
        )
        .expect("valid test input");
        let b: Vec<f64> = (0..n).map(|v| ((v * 7919) % 31) as f64 - 15.0).collect();
        let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
        ordered.apply(&b, &mut x, &mut ordered.workspace());
        plain.apply(&b, &mut y, &mut plain.workspace());
        assert!(x.iter().zip(&y).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert_eq!(ordered.level_sizes(), plain.level_sizes());
    }
}
