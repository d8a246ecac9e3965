//! The core's linear algebra beyond glam, in one place. Here the 3x3 symmetric
//! eigen-decomposition (principal frames of parts, boxes, capsules and cylinders); in
//! [`dense`], the small fixed-size systems of the ellipsoid fit (Cholesky solves, log
//! determinants, inverses).
//!
//! What is nalgebra's and what is hand-written was decided by `cargo bench --bench linalg`
//! (docs/development.md has the figures): the eigen-decomposition is nalgebra's, whose
//! fixed-size version was faster; the dense algebra is the core's own, faster or needed for
//! its semantics. Every step here is an IEEE operation or [`crate::math`]'s, so the bits are
//! the same natively and in WebAssembly (`scripts/wasm_tests.sh` checks the recorded bits).
pub mod dense;

use glam::{DMat3, DVec3};
use nalgebra::Matrix3;

/// Eigen-decomposition of a symmetric 3x3 matrix (nalgebra's symmetric QR iteration).
///
/// Returns eigenvalues in descending order and a rotation matrix (right-handed, det = +1)
/// whose columns are the matching unit eigenvectors.
pub fn sym_eigen(m: DMat3) -> (DVec3, DMat3) {
    // Symmetrised, so that round-off in the caller cannot tilt the frame.
    let a = Matrix3::from_fn(|i, j| 0.5 * (m.col(j)[i] + m.col(i)[j]));
    let e = a.symmetric_eigen();
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| e.eigenvalues[j].total_cmp(&e.eigenvalues[i]));
    let vals = DVec3::new(
        e.eigenvalues[idx[0]],
        e.eigenvalues[idx[1]],
        e.eigenvalues[idx[2]],
    );
    let col = |c: usize| {
        let v = e.eigenvectors.column(c);
        DVec3::new(v[0], v[1], v[2]).normalize()
    };
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
