//! Fast bounding volumes used while refining: the part's Legendre ellipsoid scaled
//! uniformly until it holds the part (the paper's choice), and its box counterpart (the
//! principal-axes box, for OBB output). Both come from the moments in O(1) plus one pass
//! over the part's points for the scale.
use glam::{DMat3, DVec3};

use crate::linalg::sym_eigen;
use crate::moments::Moments;
use crate::partition::{Solid, CELL_VAR};
use crate::volume::{BoundingVolume, Shape};

/// The scaled Legendre ellipsoid (`shape = Ellipsoid`) or principal-axes box (`Obb`) of a
/// part with moments `m` (lattice units) and world-space points `points`.
pub fn fast_volume(
    solid: &Solid,
    m: &Moments,
    shape: Shape,
    points: impl Iterator<Item = DVec3> + Clone,
) -> BoundingVolume {
    let h = solid.grid.h;
    let (vals, axes) = sym_eigen(m.cov(CELL_VAR));
    let center = solid.to_world(m.mean());
    match shape {
        Shape::Ellipsoid => {
            // L = 5 C: semi-axes sqrt(5 lambda), in world units.
            let radii = DVec3::new(
                (5.0 * vals.x).sqrt(),
                (5.0 * vals.y).sqrt(),
                (5.0 * vals.z).sqrt(),
            ) * h;
            BoundingVolume {
                shape,
                center,
                axes,
                radii,
            }
            .scaled_to_contain(points)
        }
        Shape::Obb => principal_box(center, axes, points, 0.5 * h),
    }
}

/// The box with frame `axes` holding `points` (half-extents at least `min_half`).
pub fn principal_box(
    center: DVec3,
    axes: DMat3,
    points: impl Iterator<Item = DVec3>,
    min_half: f64,
) -> BoundingVolume {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let at = axes.transpose();
    for p in points {
        let t = at * (p - center);
        lo = lo.min(t);
        hi = hi.max(t);
    }
    if !lo.is_finite() {
        lo = DVec3::ZERO;
        hi = DVec3::ZERO;
    }
    let mid = 0.5 * (lo + hi);
    BoundingVolume {
        shape: Shape::Obb,
        center: center + axes * mid,
        axes,
        radii: (0.5 * (hi - lo)).max(DVec3::splat(min_half)) * (1.0 + 1e-12),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounding::mvee::mvee;
    use crate::partition::Partition;
    use crate::sampling::Grid;

    #[test]
    fn mvee_is_never_larger_than_the_scaled_legendre_ellipsoid() {
        let shapes: [&dyn Fn(DVec3) -> bool; 3] = [
            &|p: DVec3| p.length() <= 1.0,
            &|p: DVec3| p.abs().max_element() <= 0.8 && p.x + p.y < 0.5,
            &|p: DVec3| (p.x * p.x + 4.0 * p.y * p.y) <= 1.0 && p.z.abs() < 0.3 && p.x > -0.2,
        ];
        for inside in shapes {
            let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.1, inside);
            let solid = Solid::new(g);
            let part = Partition::from_labels(&solid, vec![0; solid.len()], 1);
            let pts = &solid.grid.points;
            let leg = fast_volume(
                &solid,
                &part.parts[0],
                Shape::Ellipsoid,
                pts.iter().copied(),
            );
            let box_ = fast_volume(&solid, &part.parts[0], Shape::Obb, pts.iter().copied());
            let e = mvee(pts, 1e-4, 0.05);
            for &p in pts {
                assert!(leg.contains(p) && box_.contains(p) && e.contains(p));
            }
            assert!(e.volume() <= leg.volume() * (1.0 + 1e-9));
        }
    }
}
