//! Small geometric helpers that several stages share.
use glam::DVec3;

/// The point of the segment `[a, b]` nearest to `p` (`a` when the segment is a point).
#[inline]
pub(crate) fn closest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + t * d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_points_of_a_segment() {
        let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
        // Beside the middle, before the start, past the end, and on a point segment.
        let inner = closest_on_segment(DVec3::new(0.5, 3.0, 0.0), a, b);
        assert_eq!(inner, DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(closest_on_segment(DVec3::new(-1.0, 1.0, 0.0), a, b), a);
        assert_eq!(closest_on_segment(DVec3::new(5.0, -1.0, 2.0), a, b), b);
        assert_eq!(closest_on_segment(DVec3::ONE, a, a), a);
    }
}
