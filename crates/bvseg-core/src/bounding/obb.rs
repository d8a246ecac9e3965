//! Tight oriented bounding box (to be written).
use glam::{DMat3, DVec3};

use crate::volume::{BoundingVolume, Shape};

/// A tight oriented bounding box of `points` holding all of them; half-extents at least
/// `min_radius`.
pub fn min_obb(points: &[DVec3], min_radius: f64) -> BoundingVolume {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    BoundingVolume {
        shape: Shape::Obb,
        center: 0.5 * (lo + hi),
        axes: DMat3::IDENTITY,
        radii: (0.5 * (hi - lo)).max(DVec3::splat(min_radius.max(1e-12))),
    }
}
