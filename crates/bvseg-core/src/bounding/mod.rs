//! Stage 6: bounding volumes of a part's points, one file per kind.
//!
//! - [`mvee`]: the minimum-volume enclosing ellipsoid.
//! - [`obb`]: a tight oriented bounding box.
//! - [`ball`]: the minimum enclosing ball (and circle).
//! - [`axial`]: near-minimum capsules and cylinders.
//! - [`polyhedron`]: an enclosing convex hull with few vertices.
//! - [`hull`]: the convex hull, which all of the above work on.
pub mod axial;
pub mod ball;
pub mod hull;
pub mod mvee;
pub mod obb;
pub mod polyhedron;

use glam::DVec3;

use crate::volume::{BoundingVolume, Shape};

/// The volume of kind `shape` fitted to `points` (the vertices of their convex hull, for the
/// ellipsoid's sake), no radius below `min_r`, a hull with at most `max_hull_vertices`.
pub fn fit(shape: Shape, points: &[DVec3], min_r: f64, max_hull_vertices: usize) -> BoundingVolume {
    match shape {
        Shape::Ellipsoid => mvee::mvee_of_hull(points, crate::fitting::MVEE_TOL, min_r),
        Shape::Obb => obb::min_obb(points, min_r),
        Shape::Sphere => ball::min_ball(points, min_r),
        Shape::Capsule => axial::min_axial(points, axial::Axial::Capsule, min_r),
        Shape::Cylinder => axial::min_axial(points, axial::Axial::Cylinder, min_r),
        Shape::Hull => polyhedron::few_vertex_hull(points, max_hull_vertices, min_r),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recorded bits of every new kind's fit, the same native and on wasm32 (see
    /// `scripts/wasm_tests.sh`, which runs the tests named `same_bits`).
    #[test]
    fn new_kinds_same_bits_on_every_platform_and_thread() {
        let pts = hull::hull_points(&mvee::tests::portable_blob(11, 2000));
        let digest = || {
            [Shape::Sphere, Shape::Capsule, Shape::Cylinder, Shape::Hull]
                .map(|s| fit(s, &pts, 1e-6, 32).bits_digest())
                .into_iter()
                .fold(0u64, |h, d| h.rotate_left(17) ^ d)
        };
        let here = mvee::tests::same_on_threads(digest);
        assert_eq!(here, GOLDEN, "digest {here:#x}");
    }

    const GOLDEN: u64 = 0xf0a3_9b7b_3ac2_fe12;
}
