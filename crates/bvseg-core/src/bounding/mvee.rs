//! Minimum-volume enclosing ellipsoid (to be written).
use glam::{DMat3, DVec3};

use crate::volume::{BoundingVolume, Shape};

/// Minimum-volume enclosing ellipsoid of `points`, then scaled so every point is inside.
/// Radii are at least `min_radius` (for flat or tiny sets).
pub fn mvee(points: &[DVec3], tol: f64, min_radius: f64) -> BoundingVolume {
    let _ = tol;
    let c = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    BoundingVolume {
        shape: Shape::Ellipsoid,
        center: c,
        axes: DMat3::IDENTITY,
        radii: DVec3::splat(min_radius.max(1e-12)),
    }
    .scaled_to_contain(points.iter().copied())
}
