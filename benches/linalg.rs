//! The core's hand-written small linear algebra against nalgebra's fixed-size types, on the
//! sizes the core uses: the 3x3 symmetric eigen-decomposition (every part's principal frame,
//! boxes, capsules, cylinders), and the ellipsoid fit's 10x10 Cholesky solve, 4x4 log
//! determinant and 4x4 inverse. Each benchmark runs the same 256 random well-conditioned
//! matrices per iteration, so the two sides of a pair compare as a ratio in one run.
//!
//! `cargo bench --bench linalg`
// Benchmarks state their expectations by panicking; criterion_group! defines undocumented
// public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
// Matrices as nested arrays read best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bvseg::internals::{cholesky_solve, invert, log_det, sym_eigen, Rng};
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::DMat3;
use nalgebra::{Matrix3, Matrix4, SMatrix, SVector};

const COUNT: usize = 256;

/// `count` symmetric positive definite `N`x`N` matrices: `B B^T + N I` for random `B`.
fn spd<const N: usize>(rng: &mut Rng, count: usize) -> Vec<[[f64; N]; N]> {
    (0..count)
        .map(|_| {
            let mut b = [[0.0; N]; N];
            for row in &mut b {
                for x in row.iter_mut() {
                    *x = rng.next_f64() * 2.0 - 1.0;
                }
            }
            let mut a = [[0.0; N]; N];
            for i in 0..N {
                for j in 0..N {
                    a[i][j] = (0..N).map(|p| b[i][p] * b[j][p]).sum::<f64>();
                }
                a[i][i] += N as f64;
            }
            a
        })
        .collect()
}

fn na<const N: usize>(a: &[[f64; N]; N]) -> SMatrix<f64, N, N> {
    SMatrix::from_fn(|i, j| a[i][j])
}

fn bench(c: &mut Criterion) {
    let mut rng = Rng::new(7);
    let m3 = spd::<3>(&mut rng, COUNT);
    let m4 = spd::<4>(&mut rng, COUNT);
    let m10 = spd::<10>(&mut rng, COUNT);
    let rhs: Vec<[f64; 10]> = (0..COUNT)
        .map(|_| std::array::from_fn(|_| rng.next_f64()))
        .collect();

    // The two sides agree before they are timed.
    for a in &m3 {
        let ours = sym_eigen(DMat3::from_cols_array_2d(a)).0;
        let mut theirs: Vec<f64> = Matrix3::from_fn(|i, j| a[i][j])
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .collect();
        theirs.sort_by(|x, y| y.total_cmp(x));
        for (o, t) in ours.to_array().iter().zip(&theirs) {
            assert!((o - t).abs() <= 1e-9 * t.abs().max(1.0));
        }
    }
    for (a, b) in m10.iter().zip(&rhs) {
        let ours = cholesky_solve(&mut a.clone(), b).unwrap();
        let theirs = na(a).cholesky().unwrap().solve(&SVector::from(*b));
        for (o, t) in ours.iter().zip(theirs.iter()) {
            assert!((o - t).abs() <= 1e-9 * t.abs().max(1.0));
        }
    }

    let mut g = c.benchmark_group("linalg");
    g.bench_function("sym_eigen_3x3/bvseg", |bch| {
        bch.iter(|| {
            for a in &m3 {
                black_box(sym_eigen(DMat3::from_cols_array_2d(black_box(a))));
            }
        });
    });
    g.bench_function("sym_eigen_3x3/nalgebra", |bch| {
        bch.iter(|| {
            for a in &m3 {
                let m: Matrix3<f64> = na(black_box(a));
                black_box(m.symmetric_eigen());
            }
        });
    });
    g.bench_function("cholesky_solve_10x10/bvseg", |bch| {
        bch.iter(|| {
            for (a, b) in m10.iter().zip(&rhs) {
                let mut a = *black_box(a);
                black_box(cholesky_solve(&mut a, black_box(b)));
            }
        });
    });
    g.bench_function("cholesky_solve_10x10/nalgebra", |bch| {
        bch.iter(|| {
            for (a, b) in m10.iter().zip(&rhs) {
                let m = na(black_box(a));
                let x = m
                    .cholesky()
                    .map(|ch| ch.solve(&SVector::from(*black_box(b))));
                black_box(x);
            }
        });
    });
    g.bench_function("log_det_4x4/bvseg", |bch| {
        bch.iter(|| {
            for a in &m4 {
                black_box(log_det(*black_box(a)));
            }
        });
    });
    g.bench_function("log_det_4x4/nalgebra", |bch| {
        bch.iter(|| {
            for a in &m4 {
                let m: Matrix4<f64> = na(black_box(a));
                let ld = m.cholesky().map(|ch| {
                    let l = ch.l_dirty();
                    (0..4).map(|i| 2.0 * l[(i, i)].ln()).sum::<f64>()
                });
                black_box(ld);
            }
        });
    });
    g.bench_function("invert_4x4/bvseg", |bch| {
        bch.iter(|| {
            for a in &m4 {
                black_box(invert(*black_box(a)));
            }
        });
    });
    g.bench_function("invert_4x4/nalgebra", |bch| {
        bch.iter(|| {
            for a in &m4 {
                let m: Matrix4<f64> = na(black_box(a));
                black_box(m.try_inverse());
            }
        });
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
