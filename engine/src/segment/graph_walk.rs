//! Grady's random walker on a weighted graph in compressed rows: the solver behind
//! [`WalkSystem`](super::WalkSystem) (the face graph of a mask) and behind the
//! multilevel walk (its aggregated graphs and local refinement problems).
//!
//! With `L` the graph's weighted Laplacian, split into unknown nodes `U` and seed
//! nodes, the probability `x_k` that a walk from each unknown node reaches seed `k`
//! first solves `L_U x_k = b_k`, `b_k[i]` the total weight of edges from unknown `i`
//! to seed `k`. One sparse Cholesky factorization (`linalg::cholesky`: faer, AMD
//! ordering, sequential) serves every seed; right-hand sides are solved in blocks of
//! [`RHS_BLOCK`] columns.

use std::collections::VecDeque;
use std::ops::Range;

use faer::Mat;
use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;

use super::SegmentError;
use crate::linalg::cholesky::{self, Cholesky};
use crate::mesh::NONE;

/// Right-hand sides (seeds) solved together. Measured on the bunny (69k unknowns, 1.9M
/// nonzeros in the factor), per right-hand side on one core: 4.7 ms one at a time,
/// 1.5 ms in blocks of 8, 1.3 ms in blocks of 16, 1.7 ms in blocks of 32 and more (a
/// block then outgrows the cache: 69k x 32 x 8 bytes = 18 MB).
pub const RHS_BLOCK: usize = 16;

/// An undirected graph with positive edge weights in compressed rows: node `v`'s
/// neighbours are `targets[offsets[v]..offsets[v + 1]]`, with the same-index
/// `weights`. Every edge is listed from both ends with the same weight.
///
/// Not a [`Csr`](crate::linalg::Csr): a row keeps its neighbours in the order they were
/// met (a face's edge order, or first meeting when coarsening), not sorted by column,
/// and the walk's sums (the Laplacian's diagonal, the coarse weights) run in that
/// order, so sorting the rows would change the labels' bits.
#[derive(Debug, Clone, Default)]
pub(crate) struct WalkGraph {
    pub offsets: Vec<usize>,
    pub targets: Vec<u32>,
    pub weights: Vec<f64>,
}

impl WalkGraph {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The `(neighbour, weight)` pairs of node `v`, in stored order.
    pub fn neighbors(&self, v: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.offsets[v]..self.offsets[v + 1];
        self.targets[r.clone()]
            .iter()
            .copied()
            .zip(self.weights[r].iter().copied())
    }
}

/// The lowest node that no seed reaches, if any (its walk system would be singular).
pub(crate) fn first_unseeded(graph: &WalkGraph, seeds: &[u32]) -> Option<usize> {
    let mut reached = vec![false; graph.node_count()];
    for &s in seeds {
        reached[s as usize] = true;
    }
    let mut queue: VecDeque<u32> = seeds.iter().copied().collect();
    while let Some(v) = queue.pop_front() {
        for (u, _) in graph.neighbors(v as usize) {
            if !reached[u as usize] {
                reached[u as usize] = true;
                queue.push_back(u);
            }
        }
    }
    reached.iter().position(|&r| !r)
}

/// The factored random-walk system of a graph and its seed nodes.
#[derive(Debug)]
pub(crate) struct GraphWalk {
    node_count: usize,
    seed_count: usize,
    /// Per node: its row among the unknowns, or `NONE` (a seed).
    row_of_node: Vec<u32>,
    /// Per node: its seed index, or `NONE`.
    seed_of_node: Vec<u32>,
    /// Per seed `k`, `rhs[rhs_offsets[k]..rhs_offsets[k + 1]]` are the `(row, weight)`
    /// entries of `b_k`.
    rhs_offsets: Vec<usize>,
    rhs: Vec<(u32, f64)>,
    /// The Cholesky factor of `L_U` (absent when there are no unknowns).
    factor: Option<Cholesky<f64>>,
}

/// Why a [`GraphWalk`] could not be built.
#[derive(Debug)]
pub(crate) enum GraphWalkError {
    /// This node (the lowest such) is reached from no seed: its system is singular.
    Unseeded(usize),
    /// The factorization failed.
    Solver(SegmentError),
}

impl GraphWalk {
    /// Assembles `L_U` and factors it.
    ///
    /// # Panics
    /// If a seed is out of range or repeated.
    pub fn build(graph: &WalkGraph, seeds: &[u32]) -> Result<Self, GraphWalkError> {
        let n = graph.node_count();
        let mut seed_of_node = vec![NONE; n];
        for (k, &s) in seeds.iter().enumerate() {
            assert!((s as usize) < n, "seed {s} is out of range");
            assert_eq!(seed_of_node[s as usize], NONE, "seed {s} is repeated");
            seed_of_node[s as usize] = k as u32;
        }

        if let Some(v) = first_unseeded(graph, seeds) {
            return Err(GraphWalkError::Unseeded(v));
        }

        // Rows in ascending node order over the non-seed nodes.
        let mut row_of_node = vec![NONE; n];
        let mut unknowns = 0u32;
        for (row, &seed) in row_of_node.iter_mut().zip(&seed_of_node) {
            if seed == NONE {
                *row = unknowns;
                unknowns += 1;
            }
        }
        let unknowns = unknowns as usize;

        // Lower triangle of L_U (row >= column) and the seeds' right-hand sides.
        let mut triplets = Vec::with_capacity(3 * unknowns);
        let mut rhs_pairs: Vec<(u32, u32, f64)> = Vec::new();
        for v in 0..n {
            let i = row_of_node[v];
            if i == NONE {
                continue;
            }
            let mut diagonal = 0.0;
            for (u, w) in graph.neighbors(v) {
                diagonal += w;
                let j = row_of_node[u as usize];
                if j != NONE {
                    if j < i {
                        triplets.push(Triplet::new(i as usize, j as usize, -w));
                    }
                } else {
                    rhs_pairs.push((seed_of_node[u as usize], i, w));
                }
            }
            triplets.push(Triplet::new(i as usize, i as usize, diagonal));
        }
        // Group right-hand-side entries by seed (stable: rows stay ascending).
        rhs_pairs.sort_by_key(|&(k, _, _)| k);
        let mut rhs_offsets = vec![0usize; seeds.len() + 1];
        for &(k, _, _) in &rhs_pairs {
            rhs_offsets[k as usize + 1] += 1;
        }
        for k in 0..seeds.len() {
            rhs_offsets[k + 1] += rhs_offsets[k];
        }
        let rhs = rhs_pairs.into_iter().map(|(_, i, w)| (i, w)).collect();

        let factor = if unknowns == 0 {
            None
        } else {
            Some(factorize(unknowns, &triplets).map_err(GraphWalkError::Solver)?)
        };
        Ok(Self {
            node_count: n,
            seed_count: seeds.len(),
            row_of_node,
            seed_of_node,
            rhs_offsets,
            rhs,
            factor,
        })
    }

    /// Number of unknowns (nodes that are not seeds).
    pub fn unknown_count(&self) -> usize {
        self.factor.as_ref().map_or(0, Cholesky::dim)
    }

    /// Solves `L_U x_k = b_k` for the seeds in `seeds` (one block), as columns of a
    /// dense matrix over the unknowns.
    fn solve_block(&self, seeds: Range<usize>) -> Mat<f64> {
        let unknowns = self.unknown_count();
        let mut x = Mat::<f64>::zeros(unknowns, seeds.len());
        let Some(factor) = &self.factor else {
            return x;
        };
        for (c, k) in seeds.enumerate() {
            for &(i, w) in &self.rhs[self.rhs_offsets[k]..self.rhs_offsets[k + 1]] {
                x[(i as usize, c)] += w;
            }
        }
        factor.solve_shared(x.as_mut());
        x
    }

    /// The probability that a walk from each node reaches each seed of `seeds` first,
    /// column-major over nodes: entry `c * node_count + v` is for seed
    /// `seeds.start + c` and node `v`. Seed nodes have 1 for themselves and 0 for the
    /// others.
    ///
    /// # Panics
    /// If `seeds` reaches past the seed count.
    pub fn probabilities(&self, seeds: Range<usize>) -> Vec<f64> {
        assert!(seeds.end <= self.seed_count, "seed range out of bounds");
        let n = self.node_count;
        let mut out = vec![0.0; n * seeds.len()];
        for start in seeds.clone().step_by(RHS_BLOCK) {
            let block = start..(start + RHS_BLOCK).min(seeds.end);
            let x = self.solve_block(block.clone());
            for (c, k) in block.enumerate() {
                let column = &mut out[(k - seeds.start) * n..(k - seeds.start + 1) * n];
                let per_node = self.row_of_node.iter().zip(&self.seed_of_node);
                for (p, (&row, &seed)) in column.iter_mut().zip(per_node) {
                    *p = if row != NONE {
                        x[(row as usize, c)]
                    } else if seed == k as u32 {
                        1.0
                    } else {
                        0.0
                    };
                }
            }
        }
        out
    }

    /// Per node, the index of the seed with the largest probability (ties: the lower
    /// seed index); seeds get themselves. Blocks of [`RHS_BLOCK`] seeds are solved in
    /// parallel with rayon and merged in seed order, so the result does not depend on
    /// the thread count.
    pub fn labels(&self) -> Vec<u32> {
        let unknowns = self.unknown_count();
        let blocks: Vec<Range<usize>> = (0..self.seed_count)
            .step_by(RHS_BLOCK)
            .map(|s| s..(s + RHS_BLOCK).min(self.seed_count))
            .collect();
        // Per block, each unknown's best probability and seed within the block; blocks
        // are combined in seed order (rayon's `reduce` never reorders), keeping the
        // earlier block on ties, so ties go to the lower seed whatever the threads.
        let (_, arg) = blocks
            .into_par_iter()
            .map(|block| {
                let x = self.solve_block(block.clone());
                let mut best = vec![f64::NEG_INFINITY; unknowns];
                let mut arg = vec![NONE; unknowns];
                for (c, k) in block.enumerate() {
                    let column = x.col(c);
                    for ((b, a), &p) in best.iter_mut().zip(&mut arg).zip(column.iter()) {
                        if p > *b {
                            *b = p;
                            *a = k as u32;
                        }
                    }
                }
                (best, arg)
            })
            .reduce(
                || (vec![f64::NEG_INFINITY; unknowns], vec![NONE; unknowns]),
                |(mut best, mut arg), (later_best, later_arg)| {
                    for i in 0..unknowns {
                        if later_best[i] > best[i] {
                            best[i] = later_best[i];
                            arg[i] = later_arg[i];
                        }
                    }
                    (best, arg)
                },
            );
        self.row_of_node
            .iter()
            .zip(&self.seed_of_node)
            .map(|(&row, &seed)| if row != NONE { arg[row as usize] } else { seed })
            .collect()
    }
}

/// Assembles the `n x n` lower triangle from `triplets` and factors it.
fn factorize(
    n: usize,
    triplets: &[Triplet<usize, usize, f64>],
) -> Result<Cholesky<f64>, SegmentError> {
    let solver = |what: String| SegmentError::Solver { what };
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, triplets)
        .map_err(|e| solver(format!("assembling L_U: {e:?}")))?;
    let symbolic = cholesky::symbolic(a.symbolic()).map_err(|e| solver(e.to_string()))?;
    Cholesky::new(symbolic, a.as_ref(), None).map_err(|e| solver(e.to_string()))
}
