//! The bounding-volume type shared by every stage: an ellipsoid or an oriented box.
use glam::{DMat3, DVec3};

/// The kind of a single bounding volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Solid ellipsoid: `sum_j t_j^2 <= 1`.
    Ellipsoid,
    /// Oriented box: `max_j |t_j| <= 1`.
    Obb,
}

impl Shape {
    /// The name used in the `bvseg.volumes/1` JSON schema.
    pub fn as_str(self) -> &'static str {
        match self {
            Shape::Ellipsoid => "ellipsoid",
            Shape::Obb => "obb",
        }
    }
}

/// An ellipsoid or oriented box: `center`, an orthonormal right-handed frame `axes` (columns)
/// and semi-axes / half-extents `radii`, one per axis. With
/// `t_j = axes_j . (x - center) / radii_j`, a point is inside an ellipsoid iff `sum t_j^2 <= 1`
/// and inside a box iff `max |t_j| <= 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingVolume {
    /// Ellipsoid or box.
    pub shape: Shape,
    /// Centre.
    pub center: DVec3,
    /// Orthonormal frame; column `j` is axis `j`.
    pub axes: DMat3,
    /// Semi-axes (ellipsoid) or half-extents (box), all positive.
    pub radii: DVec3,
}

impl BoundingVolume {
    /// Local coordinates `t` of a point (see the type's docs).
    #[inline]
    pub fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.center;
        DVec3::new(
            self.axes.x_axis.dot(d) / self.radii.x,
            self.axes.y_axis.dot(d) / self.radii.y,
            self.axes.z_axis.dot(d) / self.radii.z,
        )
    }

    /// The gauge of `p`: <= 1 inside, > 1 outside; scaling the radii by `s` divides it by `s`
    /// (for the ellipsoid it is `sqrt(sum t^2)`, for the box `max |t|`).
    #[inline]
    pub fn gauge(&self, p: DVec3) -> f64 {
        let t = self.local(p);
        match self.shape {
            Shape::Ellipsoid => t.length(),
            Shape::Obb => t.abs().max_element(),
        }
    }

    /// Whether `p` is inside, with a relative slack of `1e-9` as in the JSON schema's test.
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        let t = self.local(p);
        match self.shape {
            Shape::Ellipsoid => t.length_squared() <= 1.0 + 1e-9,
            Shape::Obb => t.abs().max_element() <= 1.0 + 1e-9,
        }
    }

    /// Volume.
    pub fn volume(&self) -> f64 {
        let p = self.radii.x * self.radii.y * self.radii.z;
        match self.shape {
            Shape::Ellipsoid => 4.0 / 3.0 * std::f64::consts::PI * p,
            Shape::Obb => 8.0 * p,
        }
    }

    /// The volume grown outward by at least `d` everywhere: it holds every point within
    /// distance `d` of this one (its Minkowski sum with a ball of radius `d`). A box's
    /// half-extents grow by `d`. An ellipsoid's cannot simply grow by `d` (the result would
    /// miss the offset near the ends of its long axes); of two ellipsoids with the same
    /// centre and axes that hold the offset, the smaller is taken: all semi-axes scaled by
    /// `1 + d / a_min`, or `a_j -> sqrt(a_j^2 + 2 d a_max + d^2)` (its support function is at
    /// least `h + d` since `sum_j a_max u_j^2 = a_max >= h` for a unit direction `u`).
    #[must_use]
    pub fn grown(mut self, d: f64) -> Self {
        if d.is_nan() || d <= 0.0 {
            return self;
        }
        self.radii = match self.shape {
            Shape::Obb => self.radii + DVec3::splat(d),
            Shape::Ellipsoid => {
                let r = self.radii;
                let scaled = r * (1.0 + d / r.min_element());
                let c = 2.0 * d * r.max_element() + d * d;
                let offset = DVec3::new(
                    (r.x * r.x + c).sqrt(),
                    (r.y * r.y + c).sqrt(),
                    (r.z * r.z + c).sqrt(),
                );
                if offset.x * offset.y * offset.z < scaled.x * scaled.y * scaled.z {
                    offset
                } else {
                    scaled
                }
            }
        };
        self
    }

    /// A digest of the exact bits of the volume (FNV-1a over centre, axes and radii), for
    /// tests that results are the same on every platform and thread count.
    #[doc(hidden)]
    pub fn bits_digest(&self) -> u64 {
        let words = self
            .center
            .to_array()
            .into_iter()
            .chain(self.axes.to_cols_array())
            .chain(self.radii.to_array());
        words.fold(0xcbf2_9ce4_8422_2325, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        })
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn aabb(&self) -> (DVec3, DVec3) {
        let a = self.axes;
        let r = self.radii;
        // Row i of the frame times the radii gives the half-width along world axis i.
        let half = match self.shape {
            Shape::Ellipsoid => DVec3::new(
                (DVec3::new(a.x_axis.x, a.y_axis.x, a.z_axis.x) * r).length(),
                (DVec3::new(a.x_axis.y, a.y_axis.y, a.z_axis.y) * r).length(),
                (DVec3::new(a.x_axis.z, a.y_axis.z, a.z_axis.z) * r).length(),
            ),
            Shape::Obb => DVec3::new(
                (DVec3::new(a.x_axis.x, a.y_axis.x, a.z_axis.x) * r)
                    .abs()
                    .element_sum(),
                (DVec3::new(a.x_axis.y, a.y_axis.y, a.z_axis.y) * r)
                    .abs()
                    .element_sum(),
                (DVec3::new(a.x_axis.z, a.y_axis.z, a.z_axis.z) * r)
                    .abs()
                    .element_sum(),
            ),
        };
        (self.center - half, self.center + half)
    }

    /// Scale the radii uniformly so that every point of `points` satisfies `gauge <= 1`
    /// (exactly, up to a relative margin of 1e-12), keeping the shape if it already holds them.
    pub fn scaled_to_contain(mut self, points: impl IntoIterator<Item = DVec3>) -> Self {
        let g = points
            .into_iter()
            .map(|p| self.gauge(p))
            .fold(0.0f64, f64::max);
        if g > 1.0 {
            self.radii *= g * (1.0 + 1e-12);
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aabb_of_rotated_box_holds_corners() {
        let axes = DMat3::from_euler(glam::EulerRot::XYZ, 0.4, 0.2, -0.7);
        let v = BoundingVolume {
            shape: Shape::Obb,
            center: DVec3::new(1.0, 2.0, 3.0),
            axes,
            radii: DVec3::new(1.0, 0.5, 2.0),
        };
        let (lo, hi) = v.aabb();
        for s in 0..8 {
            let t = DVec3::new(
                if s & 1 == 0 { -1.0 } else { 1.0 },
                if s & 2 == 0 { -1.0 } else { 1.0 },
                if s & 4 == 0 { -1.0 } else { 1.0 },
            );
            let p = v.center + axes * (t * v.radii);
            assert!(v.contains(p));
            assert!(p.cmpge(lo - 1e-12).all() && p.cmple(hi + 1e-12).all());
        }
    }
}
