//! 3D convex hull (to be written).
use glam::DVec3;

/// The vertices of the convex hull of `points` (a subset of them). Degenerate inputs
/// (fewer than 4 points, coplanar or collinear sets) return the extreme points they have.
pub fn hull_points(points: &[DVec3]) -> Vec<DVec3> {
    points.to_vec()
}
