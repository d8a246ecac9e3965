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

/// The indices of the first least and the last greatest `key` over `items` (by `total_cmp`:
/// the ones `Iterator::min_by` and `max_by` pick), each key computed once; `None` for no
/// items. The fits' searches seed from extreme points along fixed directions.
pub fn extremes<T: Copy>(items: &[T], key: impl Fn(T) -> f64) -> Option<[usize; 2]> {
    let first = key(*items.first()?);
    let (mut lo, mut hi) = ((0, first), (0, first));
    for (i, &x) in items.iter().enumerate().skip(1) {
        let k = key(x);
        if k.total_cmp(&lo.1).is_lt() {
            lo = (i, k);
        }
        if k.total_cmp(&hi.1).is_ge() {
            hi = (i, k);
        }
    }
    Some([lo.0, hi.0])
}

/// The points of `points` least and greatest along `d` (as [`extremes`] picks them), in that
/// order; none for no points.
pub fn extreme_points(points: &[DVec3], d: DVec3) -> impl Iterator<Item = DVec3> + '_ {
    extremes(points, move |p| d.dot(p))
        .into_iter()
        .flatten()
        .map(|i| points[i])
}

/// The volumes of each of `shapes` (in their order) fitted to `points`, as [`fit`] gives
/// them; the kinds are fitted in parallel, the capsule and the cylinder as one search
/// (see [`axial::min_capsule_and_cylinder`]).
pub fn fit_each(
    shapes: &[Shape],
    points: &[DVec3],
    min_r: f64,
    max_hull_vertices: usize,
) -> Vec<BoundingVolume> {
    let both = shapes.contains(&Shape::Capsule) && shapes.contains(&Shape::Cylinder);
    // One job per kind, but one for the pair when both are asked for.
    let jobs: Vec<Shape> = shapes
        .iter()
        .copied()
        .filter(|&s| !(both && s == Shape::Cylinder))
        .collect();
    let fitted = crate::parallel::map(&jobs, |&s| match s {
        Shape::Capsule if both => axial::min_capsule_and_cylinder(points, min_r).to_vec(),
        _ => vec![fit(s, points, min_r, max_hull_vertices)],
    });
    let mut done: Vec<(Shape, BoundingVolume)> = Vec::with_capacity(shapes.len());
    for (&s, vs) in jobs.iter().zip(fitted) {
        let kinds = if vs.len() == 2 {
            [Shape::Capsule, Shape::Cylinder].as_slice()
        } else {
            std::slice::from_ref(&s)
        };
        done.extend(kinds.iter().copied().zip(vs));
    }
    shapes
        .iter()
        .filter_map(|s| done.iter().position(|(d, _)| d == s))
        .map(|i| done[i].1.clone())
        .collect()
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

    #[test]
    fn fitting_kinds_together_gives_each_kind_fitted_alone() {
        let pts = hull::hull_points(&mvee::tests::portable_blob(5, 800));
        let alone = |s: Shape| fit(s, &pts, 1e-6, 32);
        for shapes in [
            Shape::ALL.to_vec(),
            vec![Shape::Cylinder, Shape::Sphere, Shape::Capsule],
            vec![Shape::Capsule],
            vec![Shape::Hull, Shape::Cylinder],
        ] {
            let together = fit_each(&shapes, &pts, 1e-6, 32);
            let each: Vec<BoundingVolume> = shapes.iter().map(|&s| alone(s)).collect();
            assert_eq!(together, each, "{shapes:?}");
        }
    }

    /// The extremes are the ones `min_by` and `max_by` pick, ties and signed zeros included.
    #[test]
    fn extremes_pick_as_min_by_and_max_by() {
        let mut rng = crate::rng::Rng::new(3);
        for n in 0..60 {
            // Few distinct values, so ties are common; both zeros among them.
            let v: Vec<f64> = (0..n)
                .map(|_| [-1.0, -0.0, 0.0, 0.5, 2.0][rng.below(5)])
                .collect();
            let key = |a: &(usize, &f64), b: &(usize, &f64)| a.1.total_cmp(b.1);
            let lo = v.iter().enumerate().min_by(key).map(|x| x.0);
            let hi = v.iter().enumerate().max_by(key).map(|x| x.0);
            let want = lo.zip(hi).map(|(a, b)| [a, b]);
            assert_eq!(extremes(&v, |x| x), want, "{v:?}");
        }
    }

    const GOLDEN: u64 = 0x97fd_8dc0_f8f7_5912;
}
