//! The small dense algebra of the ellipsoid fit ([`crate::bounding::mvee`]): fixed-size
//! arrays, N <= 4 for the lifted points and K <= 10 for the barrier's Newton systems.
// Small dense matrix code (N <= 4, K <= 10) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use crate::math;

/// Overwrites the lower triangle of a symmetric `a` with its Cholesky factor; `false` (and
/// `a` partly overwritten) unless `a` is positive definite.
fn cholesky<const K: usize>(a: &mut [[f64; K]; K]) -> bool {
    for j in 0..K {
        let mut d = a[j][j];
        for p in 0..j {
            d -= a[j][p] * a[j][p];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..K {
            let mut v = a[i][j];
            for p in 0..j {
                v -= a[i][p] * a[j][p];
            }
            a[i][j] = v / d;
        }
    }
    true
}

/// Solves `A x = b` for a symmetric positive definite `A` given by its lower triangle
/// (overwritten by its Cholesky factor).
pub fn cholesky_solve<const K: usize>(a: &mut [[f64; K]; K], b: &[f64; K]) -> Option<[f64; K]> {
    if !cholesky(a) {
        return None;
    }
    let mut x = *b;
    for i in 0..K {
        for p in 0..i {
            x[i] -= a[i][p] * x[p];
        }
        x[i] /= a[i][i];
    }
    for i in (0..K).rev() {
        for p in i + 1..K {
            x[i] -= a[p][i] * x[p];
        }
        x[i] /= a[i][i];
    }
    Some(x)
}

/// `log det` of a symmetric matrix, `None` unless it is positive definite.
pub fn log_det<const N: usize>(mut a: [[f64; N]; N]) -> Option<f64> {
    if !cholesky(&mut a) {
        return None;
    }
    let mut ld = 0.0;
    for (j, row) in a.iter().enumerate() {
        ld += 2.0 * math::ln(row[j]);
    }
    Some(ld)
}

/// The dot product of `a` and `b` (over the shorter's length).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    // Four independent accumulators, so that the sum vectorises into packed operations.
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut rest = 0.0;
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        rest += x * y;
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3]) + rest
}

/// `x^T A x`.
#[inline]
pub fn quad<const N: usize>(a: &[[f64; N]; N], x: &[f64; N]) -> f64 {
    let mut s = 0.0;
    for r in 0..N {
        let mut t = 0.0;
        for c in 0..N {
            t += a[r][c] * x[c];
        }
        s += x[r] * t;
    }
    s
}

/// Inverse by Gauss–Jordan elimination with partial pivoting; `None` if (nearly) singular.
/// Not nalgebra's 4x4 inverse, though faster: that one fails only at a zero determinant,
/// and the ellipsoid fit relies on `None` for a nearly singular moment matrix to fall back.
pub fn invert<const N: usize>(mut m: [[f64; N]; N]) -> Option<[[f64; N]; N]> {
    let mut inv = [[0.0; N]; N];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let scale = m.iter().flatten().fold(0.0, |a, &b| math::max(a, b.abs()));
    for col in 0..N {
        let piv = (col..N).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        let pv = m[piv][col].abs();
        if pv.is_nan() || pv <= scale * 1e-14 {
            return None;
        }
        m.swap(col, piv);
        inv.swap(col, piv);
        let p = 1.0 / m[col][col];
        for c in 0..N {
            m[col][c] *= p;
            inv[col][c] *= p;
        }
        for r in 0..N {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    for c in 0..N {
                        m[r][c] -= f * m[col][c];
                        inv[r][c] -= f * inv[col][c];
                    }
                }
            }
        }
    }
    inv.iter().flatten().all(|x| x.is_finite()).then_some(inv)
}
