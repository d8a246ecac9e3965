//! The core's own linear algebra, in one place: what glam does not provide. Here the 3x3
//! symmetric eigen-decomposition (principal frames of parts, boxes, capsules and cylinders);
//! in [`dense`], the small fixed-size systems of the ellipsoid fit (Cholesky solves, log
//! determinants, inverses).
//!
//! Hand-written rather than nalgebra's fixed-size types, because a criterion run found these
//! faster on the sizes the core uses (`cargo bench --bench linalg`; BENCHMARKS.md has no row
//! for it, docs/development.md has the figures), and because every step here is an IEEE
//! operation or [`crate::math`]'s, so the bits are the same natively and in WebAssembly.
pub mod dense;

use glam::{DMat3, DVec3};

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.
///
/// Returns eigenvalues in descending order and a rotation matrix (right-handed, det = +1)
/// whose columns are the matching unit eigenvectors.
pub fn sym_eigen(m: DMat3) -> (DVec3, DMat3) {
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

/// Re-orthonormalise a nearly orthonormal frame (columns), keeping the first column's direction.
pub fn orthonormalize(m: DMat3) -> DMat3 {
    let e0 = m.x_axis.normalize();
    let e1 = (m.y_axis - e0 * e0.dot(m.y_axis)).normalize();
    let e2 = e0.cross(e1);
    DMat3::from_cols(e0, e1, e2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_of_rotated_diagonal() {
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let d = DMat3::from_diagonal(DVec3::new(1.0, 4.0, 9.0));
        let m = r * d * r.transpose();
        let (vals, vecs) = sym_eigen(m);
        assert!((vals - DVec3::new(9.0, 4.0, 1.0)).abs().max_element() < 1e-12);
        let back = vecs * DMat3::from_diagonal(vals) * vecs.transpose();
        assert!((back - m).to_cols_array().iter().all(|x| x.abs() < 1e-12));
        assert!((vecs.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn eigen_of_repeated_values() {
        let (vals, vecs) = sym_eigen(DMat3::from_diagonal(DVec3::new(2.0, 2.0, 2.0)));
        assert_eq!(vals, DVec3::splat(2.0));
        assert!((vecs.determinant() - 1.0).abs() < 1e-12);
    }
}
