//! The core's small linear algebra, hand-written, against nalgebra's fixed-size types, on the
//! sizes the core uses: the 3x3 symmetric eigen-decomposition (every part's principal frame,
//! boxes, capsules, cylinders), and the ellipsoid fit's 10x10 Cholesky solve, 4x4 log
//! determinant and 4x4 inverse. Each benchmark runs the same 256 random well-conditioned
//! matrices per iteration, so the two sides of a pair compare as a ratio in one run. The
//! figures decide which the core uses (docs/development.md): the eigen-decomposition is
//! nalgebra's (`sym_eigen_3x3/bvseg` times the core's function around it), and the cyclic
//! Jacobi it replaced is kept here (`sym_eigen_3x3/jacobi`) so that the choice can be
//! measured again.
//!
//! `cargo bench --bench linalg`
// Benchmarks state their expectations by panicking; criterion_group! defines undocumented
// public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
// Matrices as nested arrays read best with explicit indices.
#![allow(clippy::needless_range_loop)]

use bvseg::internals::{cholesky_solve, invert, log_det, sym_eigen, Rng};
use criterion::measurement::WallTime;
use criterion::{black_box, criterion_group, criterion_main, BenchmarkGroup, Criterion};
use glam::{DMat3, DVec3};
use nalgebra::{Matrix3, SMatrix, SVector};

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

/// The core's eigen-decomposition before nalgebra's: cyclic Jacobi rotations, eigenvalues in
/// descending order, a right-handed frame of unit eigenvectors.
fn jacobi_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut a = [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z],
    ];
    // Symmetrise so that round-off in the caller cannot make Jacobi drift.
    for i in 0..3 {
        for j in (i + 1)..3 {
            let s = 0.5 * (a[i][j] + a[j][i]);
            a[i][j] = s;
            a[j][i] = s;
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let diag = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-300 || off <= diag * 1e-17 {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let vkp = row[p];
                let vkq = row[q];
                row[p] = c * vkp - s * vkq;
                row[q] = s * vkp + c * vkq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let vals = DVec3::new(a[idx[0]][idx[0]], a[idx[1]][idx[1]], a[idx[2]][idx[2]]);
    let col = |c: usize| DVec3::new(v[0][c], v[1][c], v[2][c]).normalize();
    let e0 = col(idx[0]);
    let e1 = col(idx[1]);
    // Rebuild the third axis so the frame is exactly orthonormal and right-handed.
    let e1 = (e1 - e0 * e0.dot(e1)).normalize();
    let e2 = e0.cross(e1);
    (vals, DMat3::from_cols(e0, e1, e2))
}

fn na<const N: usize>(a: &[[f64; N]; N]) -> SMatrix<f64, N, N> {
    SMatrix::from_fn(|i, j| a[i][j])
}

/// Times `f` on each of `inputs` in turn, as one iteration.
fn each<T, R>(g: &mut BenchmarkGroup<'_, WallTime>, name: &str, inputs: &[T], f: impl Fn(&T) -> R) {
    g.bench_function(name, |bch| {
        bch.iter(|| {
            for x in inputs {
                black_box(f(black_box(x)));
            }
        });
    });
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
        let jacobi = jacobi_eigen(DMat3::from_cols_array_2d(a)).0;
        assert!((ours - jacobi).abs().max_element() <= 1e-9 * ours.abs().max_element().max(1.0));
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

    let sys: Vec<([[f64; 10]; 10], [f64; 10])> = m10.iter().copied().zip(rhs).collect();
    let mut g = c.benchmark_group("linalg");
    each(&mut g, "sym_eigen_3x3/bvseg", &m3, |a| {
        sym_eigen(DMat3::from_cols_array_2d(a))
    });
    each(&mut g, "sym_eigen_3x3/jacobi", &m3, |a| {
        jacobi_eigen(DMat3::from_cols_array_2d(a))
    });
    each(&mut g, "sym_eigen_3x3/nalgebra", &m3, |a| {
        na(a).symmetric_eigen()
    });
    each(&mut g, "cholesky_solve_10x10/bvseg", &sys, |(a, b)| {
        cholesky_solve(&mut a.clone(), b)
    });
    each(&mut g, "cholesky_solve_10x10/nalgebra", &sys, |(a, b)| {
        na(a).cholesky().map(|ch| ch.solve(&SVector::from(*b)))
    });
    each(&mut g, "log_det_4x4/bvseg", &m4, |a| log_det(*a));
    each(&mut g, "log_det_4x4/nalgebra", &m4, |a| {
        na(a).cholesky().map(|ch| {
            let l = ch.l_dirty();
            (0..4).map(|i| 2.0 * l[(i, i)].ln()).sum::<f64>()
        })
    });
    each(&mut g, "invert_4x4/bvseg", &m4, |a| invert(*a));
    each(&mut g, "invert_4x4/nalgebra", &m4, |a| na(a).try_inverse());
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
