use faer::c64;

use super::*;

/// The `k x k` grid graph Laplacian plus `mass` on the diagonal, with each edge
/// `(a, b)` carrying the rotation `rotation(a, b)`: entry `(b, a) = -r`, `(a, b) = -conj r`.
fn grid<S: Scalar>(k: usize, mass: f64, rotation: impl Fn(usize, usize) -> S) -> Csr<S> {
    let n = k * k;
    let mut t = Vec::new();
    let mut diagonal = vec![mass; n];
    let mut edge = |a: usize, b: usize, t: &mut Vec<(usize, usize, S)>| {
        let r = rotation(a, b);
        t.push((b, a, -r));
        t.push((a, b, -r.conj()));
        diagonal[a] += 1.0;
        diagonal[b] += 1.0;
    };
    for i in 0..k {
        for j in 0..k {
            let v = i * k + j;
            if j + 1 < k {
                edge(v, v + 1, &mut t);
            }
            if i + 1 < k {
                edge(v, v + k, &mut t);
            }
        }
    }
    t.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(v, &d)| (v, v, S::real(d))),
    );
    Csr::from_triplets(n, n, &t)
}

fn rhs<S: Scalar>(n: usize, make: impl Fn(f64, f64) -> S) -> Vec<S> {
    (0..n)
        .map(|v| {
            make(
                ((v * 7919) % 31) as f64 - 15.0,
                ((v * 104_729) % 17) as f64 - 8.0,
            )
        })
        .collect()
}

/// `|b - A x| / |b|`, computed independently of the solver.
fn residual<S: Scalar>(a: &Csr<S>, x: &[S], b: &[S]) -> f64 {
    let mut ax = vec![S::ZERO; x.len()];
    a.mul_into(x, &mut ax);
    let r: Vec<S> = ax.iter().zip(b).map(|(l, r)| *r - *l).collect();
    (norm2(&r) / norm2(b)).sqrt()
}

/// A pseudo-random phase per vertex (a gauge).
fn gauge(v: usize) -> f64 {
    (v as f64 * 0.754_877_666_246_692_8).fract() * std::f64::consts::TAU
}

#[test]
fn triplets_sum_duplicates_and_sort_rows() {
    let a = Csr::from_triplets(2, 3, &[(0, 2, 1.0), (0, 0, 2.0), (0, 2, 3.0), (1, 1, 5.0)]);
    assert_eq!(a.row(0), (&[0u32, 2][..], &[2.0, 4.0][..]));
    assert_eq!(a.row(1), (&[1u32][..], &[5.0][..]));
    assert_eq!(a.nnz(), 3);
    assert_eq!(a.diagonal(1), 5.0);
    assert_eq!(a.diagonal(0), 2.0);
}

#[test]
fn matmul_and_adjoint_match_dense_products() {
    // Small complex matrices with a fixed pattern; compare with dense arithmetic.
    let (m, k, n) = (5, 4, 6);
    let entry = |seed: usize, r: usize, c: usize| {
        let h = (seed * 31 + r * 7 + c * 13) % 11;
        (!h.is_multiple_of(3)).then(|| c64::new(h as f64 - 5.0, (h * h % 7) as f64 - 3.0))
    };
    let triplets = |seed, rows, cols| {
        let mut t = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if let Some(v) = entry(seed, r, c) {
                    t.push((r, c, v));
                }
            }
        }
        t
    };
    let a = Csr::from_triplets(m, k, &triplets(1, m, k));
    let b = Csr::from_triplets(k, n, &triplets(2, k, n));
    let ab = a.matmul(&b);
    let dense = |x: &Csr<c64>, r: usize, c: usize| {
        let (cols, vals) = x.row(r);
        cols.iter()
            .position(|&k| k as usize == c)
            .map_or(c64::new(0.0, 0.0), |k| vals[k])
    };
    for r in 0..m {
        for c in 0..n {
            let expected = (0..k).fold(c64::new(0.0, 0.0), |s, j| {
                s + dense(&a, r, j) * dense(&b, j, c)
            });
            assert!((dense(&ab, r, c) - expected).norm() < 1e-12, "({r}, {c})");
        }
    }
    let h = a.adjoint();
    assert_eq!((h.rows(), h.cols()), (k, m));
    for r in 0..m {
        for c in 0..k {
            assert_eq!(dense(&h, c, r), dense(&a, r, c).conj());
        }
    }
}

#[test]
fn permutation_round_trips() {
    let a = grid(6, 0.5, |_, _| 1.0);
    let order = a.breadth_first_order();
    let mut sorted = order.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..36).collect::<Vec<u32>>(), "a permutation");
    let mut position = vec![0u32; 36];
    for (k, &o) in order.iter().enumerate() {
        position[o as usize] = k as u32;
    }
    let p = a.permuted(&order, &position);
    let back = p.permuted(&position, &order);
    assert_eq!(back, a);
    // Breadth-first: each row after the first has an earlier neighbour.
    for k in 1..36 {
        assert!(p.row(k).0.iter().any(|&c| (c as usize) < k), "row {k}");
    }
}

#[test]
fn dense_cholesky_solves_and_rejects_indefinite() {
    let n = 12;
    // A = B^H B + I for a fixed complex B: Hermitian positive definite.
    let b = |r: usize, c: usize| {
        c64::new(
            ((r * 3 + c * 5) % 7) as f64 - 3.0,
            ((r + 2 * c) % 5) as f64 - 2.0,
        )
    };
    let a = |i: usize, j: usize| {
        let s = (0..n).fold(c64::new(0.0, 0.0), |s, k| s + b(k, i).conj() * b(k, j));
        if i == j { s + c64::new(1.0, 0.0) } else { s }
    };
    let chol = DenseCholesky::new(n, a).expect("positive definite");
    let x_true: Vec<c64> = (0..n).map(|i| c64::new(i as f64, 1.0 - i as f64)).collect();
    let mut x: Vec<c64> = (0..n)
        .map(|i| (0..n).fold(c64::new(0.0, 0.0), |s, j| s + a(i, j) * x_true[j]))
        .collect();
    chol.solve(&mut x);
    for (l, r) in x.iter().zip(&x_true) {
        assert!((l - r).norm() < 1e-9, "{l} vs {r}");
    }
    let indefinite = DenseCholesky::new(2, |i, j| if i == j { 1.0 } else { 2.0 });
    assert_eq!(
        indefinite.err(),
        Some(LinalgError::NotPositiveDefinite { pivot: 1 })
    );
}

#[test]
fn multigrid_solves_a_laplacian_in_few_iterations_at_any_size() {
    let mut counts = Vec::new();
    for k in [32, 64, 128] {
        let a = grid(k, 1e-4, |_, _| 1.0);
        let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("hierarchy");
        assert!(amg.level_sizes().len() >= 2, "{:?}", amg.level_sizes());
        assert!(
            amg.operator_complexity() < 2.0,
            "{}",
            amg.operator_complexity()
        );
        let b = rhs(k * k, |x, _| x);
        let mut x = vec![0.0; k * k];
        let report = pcg::solve(&amg, &b, &mut x, 1e-10, 200).expect("converges");
        assert!(residual(&a, &x, &b) < 2e-10);
        counts.push(report.iterations);
    }
    // Multigrid: the iteration count hardly grows with 16x the unknowns (plain
    // conjugate gradients would need about 4x as many).
    assert!(counts[2] <= counts[0] + 8 && counts[2] < 40, "{counts:?}");
}

#[test]
fn multigrid_transports_the_near_null_vector_along_a_connection() {
    // A flat connection in a random gauge: r_ab = e^(i (phi_b - phi_a)). Its near-null
    // vector e^(i phi) is as smooth as the constant is for the real Laplacian, once
    // the aggregates transport phases; without phases the coarse space would miss it.
    let k = 96;
    let real = grid(k, 1e-4, |_, _| 1.0);
    let complex = grid(k, 1e-4, |a, b| c64::from_polar(1.0, gauge(b) - gauge(a)));
    let amg_real = Amg::new(real, None, &AmgOptions::default()).expect("real");
    let amg = Amg::new(complex.clone(), None, &AmgOptions::default()).expect("complex");
    let b_real = rhs(k * k, |x, _| x);
    let b: Vec<c64> = b_real
        .iter()
        .enumerate()
        .map(|(v, x)| c64::from_polar(*x, gauge(v)))
        .collect();
    let mut x_real = vec![0.0; k * k];
    let mut x = vec![c64::new(0.0, 0.0); k * k];
    let real_report = pcg::solve(&amg_real, &b_real, &mut x_real, 1e-9, 300).expect("real");
    let report = pcg::solve(&amg, &b, &mut x, 1e-9, 300).expect("complex");
    assert!(residual(&complex, &x, &b) < 2e-9);
    // The gauge-transformed problem is the same problem: same iterations, and the
    // solution is the real one in the gauge.
    assert!(
        report.iterations.abs_diff(real_report.iterations) <= 1,
        "{report:?} vs {real_report:?}"
    );
    for (v, (z, r)) in x.iter().zip(&x_real).enumerate() {
        assert!((z - c64::from_polar(*r, gauge(v))).norm() < 1e-6 * (1.0 + r.abs()));
    }
}

#[test]
fn multigrid_reports_indefinite_and_unconverged_systems() {
    // Laplacian minus a shift above its smallest eigenvalue: indefinite.
    let a = grid(40, -0.05, |_, _| 1.0);
    let b = rhs(1600, |x, _| x);
    let mut x = vec![0.0; 1600];
    let err = Amg::new(a, None, &AmgOptions::default())
        .and_then(|amg| pcg::solve(&amg, &b, &mut x, 1e-10, 500).map(|_| ()))
        .expect_err("indefinite");
    assert!(
        matches!(
            err,
            LinalgError::Indefinite { .. } | LinalgError::NotPositiveDefinite { .. }
        ),
        "{err}"
    );
    let a = grid(40, 1e-4, |_, _| 1.0);
    let amg = Amg::new(a, None, &AmgOptions::default()).expect("hierarchy");
    let err = pcg::solve(&amg, &b, &mut x, 1e-14, 2).expect_err("budget of 2");
    assert!(
        matches!(err, LinalgError::NotConverged { iterations: 2, .. }),
        "{err}"
    );
    let mut bad = b.clone();
    bad[3] = f64::NAN;
    assert_eq!(
        pcg::solve(&amg, &bad, &mut x, 1e-8, 10).err(),
        Some(LinalgError::NonFinite)
    );
}

#[test]
fn multigrid_handles_isolated_unknowns_and_is_deterministic() {
    // A grid plus 500 unknowns coupled to nothing: they are left to the smoother.
    let k = 48;
    let g = grid(k, 1e-3, |_, _| 1.0);
    let n = k * k + 500;
    let mut t = Vec::new();
    for r in 0..k * k {
        let (cols, vals) = g.row(r);
        t.extend(cols.iter().zip(vals).map(|(&c, &v)| (r, c as usize, v)));
    }
    t.extend((k * k..n).map(|v| (v, v, 2.0)));
    let a = Csr::from_triplets(n, n, &t);
    let b = rhs(n, |x, _| x);
    let solve = || {
        let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("hierarchy");
        let mut x = vec![0.0; n];
        pcg::solve(&amg, &b, &mut x, 1e-10, 100).expect("converges");
        x
    };
    let x = solve();
    assert!(residual(&a, &x, &b) < 2e-10);
    assert!(
        x[k * k..]
            .iter()
            .zip(&b[k * k..])
            .all(|(x, b)| (x - b / 2.0).abs() < 1e-9)
    );
    assert_eq!(x, solve(), "bit-identical on a second run");
}

#[test]
fn positive_couplings_do_not_flip_a_real_near_null_vector() {
    // A cotangent Laplacian has positive couplings across obtuse corners. Make every
    // fifth horizontal coupling of a grid slightly positive (still positive definite):
    // the constant stays the near-null vector, so multigrid converges as on the grid.
    let k = 64;
    let n = k * k;
    let mut t = Vec::new();
    let mut diagonal = vec![1e-4; n];
    for i in 0..k {
        for j in 0..k {
            let v = i * k + j;
            let mut couple = |a: usize, b: usize, w: f64| {
                t.push((a, b, -w));
                t.push((b, a, -w));
                diagonal[a] += w.abs();
                diagonal[b] += w.abs();
            };
            if j + 1 < k {
                couple(v, v + 1, if v % 5 == 0 { -0.6 } else { 1.0 });
            }
            if i + 1 < k {
                couple(v, v + k, 1.0);
            }
        }
    }
    t.extend(diagonal.iter().enumerate().map(|(v, &d)| (v, v, d)));
    let a = Csr::from_triplets(n, n, &t);
    let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("hierarchy");
    let b = rhs(n, |x, _| x);
    let mut x = vec![0.0; n];
    let report = pcg::solve(&amg, &b, &mut x, 1e-10, 200).expect("converges");
    assert!(residual(&a, &x, &b) < 2e-10);
    let plain = grid(k, 1e-4, |_, _| 1.0);
    let plain_amg = Amg::new(plain, None, &AmgOptions::default()).expect("hierarchy");
    let mut y = vec![0.0; n];
    let plain_report = pcg::solve(&plain_amg, &b, &mut y, 1e-10, 200).expect("converges");
    println!("with positive couplings {report:?}, plain grid {plain_report:?}");
    assert!(
        report.iterations <= plain_report.iterations + 4,
        "{report:?} vs {plain_report:?}"
    );
}

#[test]
fn parallel_products_equal_one_thread_bit_for_bit() {
    // A complex connection-like matrix big enough for the parallel passes, with a
    // pseudo-random rotation per edge and a scrambled renumbering.
    let k = 200;
    let n = k * k;
    assert!(n >= PARALLEL_ROWS);
    let a = grid(k, 0.3, |a, b| {
        c64::from_polar(1.0, gauge(a) - gauge(b) + 0.01 * (a % 7) as f64)
    });
    let order: Vec<u32> = (0..n as u32)
        .map(|v| v.wrapping_mul(7919) % n as u32)
        .collect();
    let mut position = vec![0u32; n];
    for (new, &old) in order.iter().enumerate() {
        position[old as usize] = new as u32;
    }
    let x = rhs(n, c64::new);
    let run = |threads: usize| {
        crate::on_threads(threads, || {
            let p = a.permuted(&order, &position);
            let product = p.matmul(&a.adjoint()).matmul(&p);
            let mut y = vec![c64::new(0.0, 0.0); n];
            product.mul_into(&x, &mut y);
            (p, product, y)
        })
    };
    let one = run(1);
    assert_eq!(one, run(3));
    // The products equal their definitions, summed in the same order: the triplets of
    // every `a_rk b_kc` in row order, then `k`'s row order.
    let (p, _, _) = &one;
    let b = a.adjoint();
    let mut t = Vec::new();
    for r in 0..n {
        let (cols, vals) = p.row(r);
        for (&kk, &v) in cols.iter().zip(vals) {
            let (bc, bv) = b.row(kk as usize);
            t.extend(bc.iter().zip(bv).map(|(&c, &w)| (r, c as usize, v * w)));
        }
    }
    assert_eq!(p.matmul(&b), Csr::from_triplets(n, n, &t));
    for r in [0, 1, n / 2, n - 1] {
        let (cols, vals) = p.row(r);
        let (old_cols, old_vals) = a.row(order[r] as usize);
        assert_eq!(cols.len(), old_cols.len());
        for (&c, &v) in cols.iter().zip(vals) {
            let at = old_cols
                .iter()
                .position(|&o| position[o as usize] == c)
                .expect("column");
            assert_eq!(v, old_vals[at]);
        }
    }
}

#[test]
fn a_hierarchy_preconditions_the_same_matrix_with_another_diagonal() {
    // A connection Laplacian (a flat gauge: smallest eigenvalue the shift 1e-4), and
    // the same with a varying diagonal of up to three times that added: what the
    // line-field solver's shifted system adds to lambda_1's matrix, in the regime its
    // gate lets through (z^H K z / z^H A z within [1, 4]).
    let k = 48;
    let n = k * k;
    let a = grid(k, 1e-4, |u, v| c64::cis(gauge(v) - gauge(u)));
    let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("hierarchy");
    let delta: Vec<f64> = (0..n)
        .map(|v| 3e-4 * ((v * 37) % 11) as f64 / 10.0)
        .collect();
    let with: Vec<(usize, usize, c64)> = (0..n)
        .flat_map(|r| {
            let (cols, vals) = a.row(r);
            let extra = delta[r];
            cols.iter().zip(vals).map(move |(&c, &v)| {
                let v = if c as usize == r {
                    v + c64::new(extra, 0.0)
                } else {
                    v
                };
                (r, c as usize, v)
            })
        })
        .collect();
    let shifted = Csr::from_triplets(n, n, &with);
    let b = rhs(n, c64::new);
    let mut reused = vec![c64::new(0.0, 0.0); n];
    let report =
        pcg::solve_with_diagonal(&amg, &delta, &b, &mut reused, 1e-10, 200).expect("converges");
    // The residual of the shifted system itself, not of the hierarchy's matrix.
    assert!(residual(&shifted, &reused, &b) < 2e-10);
    // The same solution as with the shifted matrix's own hierarchy, in a few more
    // iterations at most.
    let own = Amg::new(shifted, None, &AmgOptions::default()).expect("hierarchy");
    let mut fresh = vec![c64::new(0.0, 0.0); n];
    let fresh_report = pcg::solve(&own, &b, &mut fresh, 1e-10, 200).expect("converges");
    let gap: f64 = reused
        .iter()
        .zip(&fresh)
        .map(|(x, y)| (*x - *y).norm())
        .fold(0.0, f64::max);
    let size: f64 = fresh.iter().map(|x| x.norm()).fold(0.0, f64::max);
    assert!(gap < 1e-7 * size, "{gap} vs {size}");
    assert!(
        report.iterations <= 2 * fresh_report.iterations + 5,
        "{} vs {}",
        report.iterations,
        fresh_report.iterations
    );
    // A diagonal that makes the sum indefinite is reported, not solved.
    let minus: Vec<f64> = vec![-10.0; n];
    let mut x = vec![c64::new(0.0, 0.0); n];
    assert!(pcg::solve_with_diagonal(&amg, &minus, &b, &mut x, 1e-10, 200).is_err());
}

#[test]
fn blocked_sweeps_keep_the_cycle_symmetric_and_thread_independent() {
    // Big enough for several smoother blocks on the finest level.
    let k = 300;
    let n = k * k;
    assert!(n > 2 * PARALLEL_ROWS);
    let a = grid(k, 1e-4, |u, v| c64::cis(gauge(v) - gauge(u)));
    let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("hierarchy");
    let x = rhs(n, c64::new);
    let y = rhs(n, |u, v| c64::new(v * v - u, 0.5 - u * v));
    let cycle = |b: &[c64], threads: usize| {
        crate::on_threads(threads, || {
            let mut out = vec![c64::new(0.0, 0.0); n];
            amg.cycle(b, &mut out, &mut amg.workspace());
            out
        })
    };
    let cx = cycle(&x, 1);
    assert_eq!(
        cx,
        cycle(&x, 3),
        "the sweep's blocks do not follow the threads"
    );
    // Forward and backward sweeps over the same blocks are adjoint: <y, C x> = <C y, x>.
    let cy = cycle(&y, 2);
    let (left, right) = (dot(&y, &cx), dot(&cy, &x));
    assert!(
        (left - right).norm() <= 1e-10 * left.norm(),
        "{left:?} against {right:?}"
    );
    // And it still smooths like Gauss-Seidel: 16 iterations here, as with one block
    // (measured with the block size raised above the grid).
    let b = rhs(n, |u, v| c64::new(v, u));
    let mut z = vec![c64::new(0.0, 0.0); n];
    let report = pcg::solve(&amg, &b, &mut z, 1e-10, 200).expect("converges");
    assert!(residual(&a, &z, &b) < 2e-10);
    assert!(report.iterations <= 17, "{report:?}");
}

#[test]
fn three_columns_solve_as_three_single_solves_to_the_bit() {
    // 200 x 200 = 40,000 unknowns: the parallel products, sweeps and updates run.
    let a = grid(200, 0.01, |_, _| 1.0);
    let n = a.rows();
    let amg = Amg::new(a.clone(), None, &AmgOptions::default()).expect("valid test input");
    let columns = [
        rhs(n, |x, _| x),
        rhs(n, |_, y| y),
        // A smooth right-hand side needs another number of iterations, so a column
        // stops while another goes on.
        (0..n).map(|v| 1.0 + (v % 200) as f64 * 1e-3).collect(),
    ];
    let b: Vec<glam::DVec3> = (0..n)
        .map(|v| glam::DVec3::new(columns[0][v], columns[1][v], columns[2][v]))
        .collect();
    let mut x = vec![glam::DVec3::ZERO; n];
    let reports = pcg::solve_three(&amg, &b, &mut x, 1e-8, 200).expect("converges");
    for (k, column) in columns.iter().enumerate() {
        let mut alone = vec![0.0; n];
        let report = pcg::solve(&amg, column, &mut alone, 1e-8, 200).expect("converges");
        assert_eq!(reports[k], report, "column {k}");
        assert!(
            x.iter()
                .zip(&alone)
                .all(|(x, y)| x[k].to_bits() == y.to_bits()),
            "column {k} differs from its own solve"
        );
        assert!(residual(&a, &alone, column) <= 1e-8);
    }
    assert!(
        reports[2].iterations != reports[0].iterations,
        "{reports:?}: a column should stop before another"
    );
    // A zero column stays zero and takes no iteration.
    let zero: Vec<glam::DVec3> = b.iter().map(|v| glam::DVec3::new(v.x, 0.0, v.z)).collect();
    let mut y = vec![glam::DVec3::ONE; n];
    let reports = pcg::solve_three(&amg, &zero, &mut y, 1e-8, 200).expect("converges");
    assert_eq!(reports[1].iterations, 0);
    assert!(y.iter().all(|v| v.y == 0.0));
}
