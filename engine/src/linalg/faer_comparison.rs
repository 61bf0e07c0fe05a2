//! The measurement behind keeping [`pcg`](super::pcg) rather than faer 0.24's
//! matrix-free conjugate gradient (`faer::matrix_free::conjugate_gradient`): both
//! preconditioned by the same V-cycle ([`Amg`]) on a connection-like Hermitian system
//! of the bunny (its vertex graph with unit-modulus couplings `-e^(i phase)`, plus a
//! small mass), timed and hashed on 1 and 2 threads; and [`DenseCholesky`](super::DenseCholesky)
//! against faer's dense `llt` on a coarsest-level-sized matrix. The results are
//! written in the docs of `pcg.rs` and `dense.rs`. Run it with
//! `cargo test --release -p strata-engine --lib linalg::faer_comparison -- --ignored --nocapture`.

use std::sync::Mutex;
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::matrix_free::conjugate_gradient::{
    CgParams, conjugate_gradient, conjugate_gradient_scratch,
};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::{MatMut, MatRef, Par, c64};

use super::{Amg, AmgOptions, Csr, Workspace, pcg};

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

#[test]
#[ignore = "a measurement: run by hand (module docs)"]
fn ours_against_faers_conjugate_gradient() {
    let Some(mesh) = crate::io::shared_mesh("stanford-bunny.obj") else {
        return;
    };
    let mesh = crate::mesh::loop_subdivide(&mesh).expect("subdivide");
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
    let a = Csr::from_triplets(n, n, &t);
    let b: Vec<c64> = (0..n)
        .map(|v| c64::new((v % 7) as f64 - 3.0, (v % 5) as f64 - 2.0))
        .collect();
    let tolerance = 1e-6;
    for threads in [1, 2] {
        crate::on_threads(threads, || {
            let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("amg");
            let start = Instant::now();
            let mut x = vec![c64::new(0.0, 0.0); n];
            let report = pcg::solve(&amg, &b, &mut x, tolerance, 200).expect("pcg");
            let ours = start.elapsed();

            let cycle = Cycle {
                amg: &amg,
                work: Mutex::new(amg.workspace()),
            };
            let op = Operator(&a);
            let params = CgParams {
                initial_guess: InitialGuessStatus::Zero,
                rel_tolerance: tolerance,
                max_iters: 200,
                ..Default::default()
            };
            // faer is built without its rayon feature: its own kernels run on one thread.
            let par = Par::Seq;
            let mut mem = MemBuffer::new(conjugate_gradient_scratch(&cycle, &op, 1, par));
            let start = Instant::now();
            let mut y = faer::Mat::<c64>::zeros(n, 1);
            let bm = MatRef::from_column_major_slice(&b, n, 1);
            let info = conjugate_gradient(
                y.as_mut(),
                &cycle,
                &op,
                bm,
                params,
                |_| {},
                par,
                MemStack::new(&mut mem),
            )
            .expect("faer cg");
            let theirs = start.elapsed();
            let y: Vec<c64> = (0..n).map(|i| y[(i, 0)]).collect();
            let diff = x
                .iter()
                .zip(&y)
                .map(|(p, q)| (*p - *q).norm())
                .fold(0.0, f64::max);
            println!(
                "{n} unknowns, {threads} threads: ours {} iterations {:.1} ms hash {:016x}; \
                 faer {} iterations {:.1} ms hash {:016x}; largest difference {diff:.2e}",
                report.iterations,
                ours.as_secs_f64() * 1e3,
                hash(&x),
                info.iter_count,
                theirs.as_secs_f64() * 1e3,
                hash(&y),
            );
        });
    }
}

#[test]
#[ignore = "a measurement: run by hand (module docs)"]
fn dense_cholesky_against_faers_llt() {
    use super::DenseCholesky;
    // A coarsest-level-sized Hermitian positive definite matrix: a ring's Laplacian
    // with complex couplings and chords, plus a mass.
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
    let ours = DenseCholesky::new(n, |i, j| m[(i, j)]).expect("factor");
    let mut x = b.clone();
    ours.solve(&mut x);
    let llt = m.llt(faer::Side::Lower).expect("faer llt");
    let rhs = faer::Mat::<c64>::from_fn(n, 1, |i, _| b[i]);
    let y = llt.solve(&rhs);
    let y: Vec<c64> = (0..n).map(|i| y[(i, 0)]).collect();
    let diff = x
        .iter()
        .zip(&y)
        .map(|(p, q)| (*p - *q).norm())
        .fold(0.0, f64::max);
    let same = x.iter().zip(&y).filter(|(p, q)| p == q).count();
    println!(
        "dense {n}x{n}: {same} of {n} entries bit-identical, largest difference {diff:.2e}; \
         hashes {:016x} {:016x}",
        hash(&x),
        hash(&y)
    );
}
