//! strata's linear algebra against faer 0.24's, for the choices written in the docs of
//! `engine/src/linalg/pcg.rs` and `dense.rs`:
//!
//! - the preconditioned conjugate gradient (`linalg::pcg`) against faer's matrix-free
//!   `conjugate_gradient`, both preconditioned by the same V-cycle (`linalg::Amg`), on
//!   a connection-like Hermitian system of the bunny Loop-subdivided once (its vertex
//!   graph with unit-modulus couplings `-e^(i phase)`, plus a small mass), timed and
//!   hashed on 1 and 2 threads;
//! - `linalg::DenseCholesky` against faer's dense `llt` on a coarsest-level-sized
//!   matrix: how many entries of the solution have the same bits.
//!
//! ```text
//! cargo run --release -p strata-bench --bin linalg_faer [repeats]
//! ```
//!
//! faer 0.24's `conjugate_gradient` leaves its residual uninitialised when told the
//! initial guess is zero (`InitialGuessStatus::Zero`: it copies `b` into the residual
//! only for `MaybeNonZero`), so this passes a zeroed guess as `MaybeNonZero`.

use std::sync::Mutex;
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::matrix_free::conjugate_gradient::{
    CgParams, conjugate_gradient, conjugate_gradient_scratch,
};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::{MatMut, MatRef, Par, c64};
use strata_bench::median;
use strata_engine::linalg::{Amg, AmgOptions, Csr, DenseCholesky, Workspace, pcg};

/// `A` as faer's operator.
#[derive(Debug)]
struct Operator<'a>(&'a Csr<c64>);

impl LinOp<c64> for Operator<'_> {
    fn apply_scratch(&self, _: usize, _: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.0.rows()
    }
    fn ncols(&self) -> usize {
        self.0.cols()
    }
    fn apply(&self, mut out: MatMut<'_, c64>, rhs: MatRef<'_, c64>, _: Par, _: &mut MemStack) {
        let n = self.0.rows();
        for j in 0..rhs.ncols() {
            let x: Vec<c64> = (0..n).map(|i| rhs[(i, j)]).collect();
            let mut y = vec![c64::new(0.0, 0.0); n];
            self.0.mul_into(&x, &mut y);
            for (i, v) in y.into_iter().enumerate() {
                out[(i, j)] = v;
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, c64>, rhs: MatRef<'_, c64>, par: Par, s: &mut MemStack) {
        // Hermitian: conj(A) x = conj(A conj(x)); only `apply` is called by CG.
        self.apply(out, rhs, par, s);
    }
}

/// One V-cycle of the hierarchy as faer's preconditioner.
struct Cycle<'a> {
    amg: &'a Amg<c64>,
    work: Mutex<Workspace<c64>>,
}

impl std::fmt::Debug for Cycle<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Cycle")
    }
}

impl LinOp<c64> for Cycle<'_> {
    fn apply_scratch(&self, _: usize, _: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.amg.matrix().rows()
    }
    fn ncols(&self) -> usize {
        self.nrows()
    }
    fn apply(&self, mut out: MatMut<'_, c64>, rhs: MatRef<'_, c64>, _: Par, _: &mut MemStack) {
        let n = self.nrows();
        let mut work = self.work.lock().expect("not poisoned");
        for j in 0..rhs.ncols() {
            let b: Vec<c64> = (0..n).map(|i| rhs[(i, j)]).collect();
            let mut x = vec![c64::new(0.0, 0.0); n];
            self.amg.apply(&b, &mut x, &mut work);
            for (i, v) in x.into_iter().enumerate() {
                out[(i, j)] = v;
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, c64>, rhs: MatRef<'_, c64>, par: Par, s: &mut MemStack) {
        self.apply(out, rhs, par, s);
    }
}

impl Precond<c64> for Cycle<'_> {}

/// FNV-1a of the bits of `x`.
fn hash(x: &[c64]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in x {
        for b in [v.re.to_bits(), v.im.to_bits()] {
            h = (h ^ b).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// The connection-like system of the module docs on `mesh`, and a right-hand side.
fn connection_system(mesh: &strata_engine::mesh::TriMesh) -> (Csr<c64>, Vec<c64>) {
    let n = mesh.vertex_count();
    let mut t = Vec::new();
    let mut degree = vec![0.0; n];
    for (e, &[a, b]) in mesh.edges().iter().enumerate() {
        let w = -c64::new((0.7 * e as f64).cos(), (0.7 * e as f64).sin());
        t.push((a as usize, b as usize, w));
        t.push((b as usize, a as usize, w.conj()));
        degree[a as usize] += 1.0;
        degree[b as usize] += 1.0;
    }
    for (v, d) in degree.iter().enumerate() {
        t.push((v, v, c64::new(d + 1e-3, 0.0)));
    }
    let b = (0..n)
        .map(|v| c64::new((v % 7) as f64 - 3.0, (v % 5) as f64 - 2.0))
        .collect();
    (Csr::from_triplets(n, n, &t), b)
}

/// Our conjugate gradient against faer's on the bunny's connection-like system.
fn conjugate_gradients(repeats: usize) -> Result<(), Box<dyn std::error::Error>> {
    let dir = strata_bench::shared_mesh_dir()?;
    let mesh = strata_engine::io::load(&dir.join("stanford-bunny.obj"))?;
    let mesh = strata_engine::mesh::loop_subdivide(&mesh)?;
    let (a, b) = connection_system(&mesh);
    let n = b.len();
    let tolerance = 1e-6;
    println!(
        "| threads | solver | iterations | ms, median of {repeats} | hash of x | largest difference from ours |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        pool.install(|| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
            let amg = Amg::new(a.clone(), None, &AmgOptions::default())?;
            let cycle = Cycle {
                amg: &amg,
                work: Mutex::new(amg.workspace()),
            };
            let op = Operator(&a);
            // faer is built without its rayon feature: its own kernels run on one thread.
            let par = Par::Seq;
            let mut mem = MemBuffer::new(conjugate_gradient_scratch(&cycle, &op, 1, par));
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            let (mut x, mut y) = (vec![], vec![]);
            let (mut our_iterations, mut their_iterations) = (0, 0);
            for _ in 0..repeats {
                let start = Instant::now();
                x = vec![c64::new(0.0, 0.0); n];
                our_iterations = pcg::solve(&amg, &b, &mut x, tolerance, 200)?.iterations;
                ours.push(start.elapsed().as_secs_f64() * 1e3);

                let start = Instant::now();
                // A zeroed guess passed as `MaybeNonZero` (module docs).
                let mut guess = faer::Mat::<c64>::zeros(n, 1);
                let params = CgParams {
                    initial_guess: InitialGuessStatus::MaybeNonZero,
                    rel_tolerance: tolerance,
                    max_iters: 200,
                    ..Default::default()
                };
                let info = conjugate_gradient(
                    guess.as_mut(),
                    &cycle,
                    &op,
                    MatRef::from_column_major_slice(&b, n, 1),
                    params,
                    |_| {},
                    par,
                    MemStack::new(&mut mem),
                )
                .map_err(|e| format!("faer's conjugate gradient: {e:?}"))?;
                theirs.push(start.elapsed().as_secs_f64() * 1e3);
                their_iterations = info.iter_count;
                y = (0..n).map(|i| guess[(i, 0)]).collect();
            }
            let diff = x
                .iter()
                .zip(&y)
                .map(|(p, q)| (*p - *q).norm())
                .fold(0.0, f64::max);
            println!(
                "| {threads} | strata `pcg::solve` | {our_iterations} | {:.1} | {:016x} | |",
                median(ours),
                hash(&x)
            );
            println!(
                "| {threads} | faer `conjugate_gradient` | {their_iterations} | {:.1} | {:016x} | {diff:.2e} |",
                median(theirs),
                hash(&y)
            );
            Ok(())
        })
        .map_err(|e| e as Box<dyn std::error::Error>)?;
    }
    println!("\n({n} unknowns, relative tolerance {tolerance:e}, the same V-cycle for both.)\n");
    Ok(())
}

/// Our dense Cholesky against faer's `llt` on a coarsest-level-sized matrix.
fn dense_cholesky() -> Result<(), Box<dyn std::error::Error>> {
    // A Hermitian positive definite matrix: a ring's Laplacian with complex couplings
    // and chords, plus a mass.
    let n = 300;
    let mut m = faer::Mat::<c64>::zeros(n, n);
    for i in 0..n {
        for j in [(i + 1) % n, (i + 17) % n] {
            let w = -c64::new((0.3 * (i + j) as f64).cos(), (0.3 * (i + j) as f64).sin());
            m[(i, j)] += w;
            m[(j, i)] += w.conj();
            m[(i, i)] += c64::new(1.0, 0.0);
            m[(j, j)] += c64::new(1.0, 0.0);
        }
        m[(i, i)] += c64::new(0.01, 0.0);
    }
    let b: Vec<c64> = (0..n).map(|v| c64::new(v as f64, 1.0)).collect();
    let ours = DenseCholesky::new(n, |i, j| m[(i, j)])?;
    let mut x = b.clone();
    ours.solve(&mut x);
    let llt = m
        .llt(faer::Side::Lower)
        .map_err(|e| format!("faer's llt: {e:?}"))?;
    let y = llt.solve(faer::Mat::<c64>::from_fn(n, 1, |i, _| b[i]));
    let y: Vec<c64> = (0..n).map(|i| y[(i, 0)]).collect();
    let diff = x
        .iter()
        .zip(&y)
        .map(|(p, q)| (*p - *q).norm())
        .fold(0.0, f64::max);
    let same = x.iter().zip(&y).filter(|(p, q)| p == q).count();
    println!(
        "Dense {n}x{n} Hermitian solve: {same} of {n} entries bit-identical to faer's `llt`, largest difference {diff:.2e}."
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?.max(1);
    conjugate_gradients(repeats)?;
    dense_cholesky()
}
