//! The bounding-volume type shared by every stage: an ellipsoid, an oriented box, a sphere,
//! a capsule, a cylinder or a convex hull.
//!
//! All six are one affine frame (`center`, orthonormal `axes`, positive `radii`) over a unit
//! shape in local coordinates `t_j = axes_j . (x - center) / radii_j`, so the stages that
//! scan lattices, scale volumes or sample their boundaries need one code path with a
//! per-shape inside test. A hull carries its polyhedron in those local coordinates.
mod ball_cover;
mod polytope;

pub use ball_cover::BALL_COVER_VERTICES;

use crate::math;
use std::sync::Arc;

use glam::{DMat3, DVec3};

pub(crate) use polytope::PlanesAlong;
pub use polytope::Polytope;

/// The kind of a single bounding volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Shape {
    /// Solid ellipsoid: `sum_j t_j^2 <= 1`.
    Ellipsoid,
    /// Oriented box: `max_j |t_j| <= 1`.
    Obb,
    /// Ball: an ellipsoid with three equal radii.
    Sphere,
    /// Capsule: the points within `radius` of a segment. Its axis is `axes.z_axis`, `radii`
    /// are `(radius, radius, half_length)`.
    Capsule,
    /// Solid circular cylinder, axis `axes.z_axis`, `radii = (radius, radius, half_length)`.
    Cylinder,
    /// Convex hull of a few points (see [`BoundingVolume::polytope`]); `axes` is the identity
    /// and the three radii are one scale.
    Hull,
}

impl Shape {
    /// Every shape, in the order of [`crate::Kinds`] and of ties between equally good fits.
    pub const ALL: [Shape; 6] = [
        Shape::Ellipsoid,
        Shape::Obb,
        Shape::Sphere,
        Shape::Capsule,
        Shape::Cylinder,
        Shape::Hull,
    ];

    /// The name used in the `bvseg.volumes` JSON schemas.
    pub fn as_str(self) -> &'static str {
        match self {
            Shape::Ellipsoid => "ellipsoid",
            Shape::Obb => "obb",
            Shape::Sphere => "sphere",
            Shape::Capsule => "capsule",
            Shape::Cylinder => "cylinder",
            Shape::Hull => "hull",
        }
    }

    /// The shape named `name` (as [`Shape::as_str`] writes it; `box` also names the OBB).
    pub fn from_name(name: &str) -> Option<Shape> {
        match name {
            "box" => Some(Shape::Obb),
            _ => Shape::ALL.into_iter().find(|s| s.as_str() == name),
        }
    }

    /// Whether schema 1 (`bvseg.volumes/1`) has this shape.
    pub fn in_schema_v1(self) -> bool {
        matches!(self, Shape::Ellipsoid | Shape::Obb)
    }
}

/// A bounding volume: `center`, an orthonormal right-handed frame `axes` (columns) and
/// `radii`, one per axis, over a unit shape in local coordinates
/// `t_j = axes_j . (x - center) / radii_j` (see [`Shape`] for each one's; for a capsule, the
/// hemispherical ends make the unit shape depend on `radii.z / radii.x`). A hull also has its
/// polyhedron in local coordinates ([`BoundingVolume::polytope`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BoundingVolume {
    /// The kind.
    pub shape: Shape,
    /// Centre.
    pub center: DVec3,
    /// Orthonormal frame; column `j` is axis `j`.
    pub axes: DMat3,
    /// Semi-axes (ellipsoid, sphere), half-extents (box), or `(radius, radius, half_length)`
    /// (capsule, cylinder), or the scale of a hull's polyhedron; all positive.
    pub radii: DVec3,
    /// The polyhedron of a hull, `None` for every other shape.
    pub polytope: Option<Arc<Polytope>>,
}

/// A [`BoundingVolume`]'s parameters as its shape has them (see [`BoundingVolume::view`]):
/// what each of the frame's `radii` means, said once here so that no caller interprets them
/// by shape. Lengths are in mesh units; axes are unit vectors in mesh coordinates. Exhaustive
/// like [`Shape`], so that a new kind makes every match on it say what to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShapeView<'a> {
    /// The solid ellipsoid with semi-axes `radii[j]` along the columns `j` of `axes`.
    Ellipsoid {
        /// Centre.
        center: DVec3,
        /// Orthonormal, right-handed; column `j` is the axis of `radii[j]`.
        axes: DMat3,
        /// The semi-axes.
        radii: DVec3,
    },
    /// The oriented box with half-extents `half_extents[j]` along the columns `j` of `axes`.
    Obb {
        /// Centre.
        center: DVec3,
        /// Orthonormal, right-handed; column `j` is the axis of `half_extents[j]`.
        axes: DMat3,
        /// The half-extents.
        half_extents: DVec3,
    },
    /// The ball of radius `radius` about `center`.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// The points within `radius` of the segment `center ± half_length * axis` (0 for a
    /// capsule as short as a ball).
    Capsule {
        /// The segment's midpoint.
        center: DVec3,
        /// The segment's direction, a unit vector.
        axis: DVec3,
        /// Half the segment's length.
        half_length: f64,
        /// Radius.
        radius: f64,
    },
    /// The solid circular cylinder of radius `radius` around the segment
    /// `center ± half_length * axis`.
    Cylinder {
        /// The axis segment's midpoint.
        center: DVec3,
        /// The axis, a unit vector.
        axis: DVec3,
        /// Half the height.
        half_length: f64,
        /// Radius.
        radius: f64,
    },
    /// A convex hull: `polytope` in local coordinates `t`, the world point
    /// `center + scale * t` (see [`BoundingVolume::world`], [`BoundingVolume::hull_points`]).
    Hull {
        /// The origin of the local coordinates.
        center: DVec3,
        /// The scale from local to world coordinates.
        scale: f64,
        /// The polyhedron; `None` only for a hull built field by field without one.
        polytope: Option<&'a Polytope>,
    },
}

/// Shortest capsule half-length relative to its radius: a capsule with a shorter segment is
/// stored with this one (a ball, to within round-off), so that local coordinates stay finite.
const MIN_CAPSULE_LENGTH: f64 = 1e-9;

impl BoundingVolume {
    /// An ellipsoid or box (`shape` one of the two; other shapes get their own constructors).
    pub fn frame(shape: Shape, center: DVec3, axes: DMat3, radii: DVec3) -> Self {
        Self {
            shape,
            center,
            axes,
            radii,
            polytope: None,
        }
    }

    /// A ball.
    pub fn sphere(center: DVec3, radius: f64) -> Self {
        Self::frame(Shape::Sphere, center, DMat3::IDENTITY, DVec3::splat(radius))
    }

    /// A capsule around the segment `center +- half_length * axis` (`axis` a unit vector).
    pub fn capsule(center: DVec3, axis: DVec3, half_length: f64, radius: f64) -> Self {
        let h = math::max(half_length, MIN_CAPSULE_LENGTH * radius);
        Self::frame(
            Shape::Capsule,
            center,
            frame_from_z(axis),
            DVec3::new(radius, radius, h),
        )
    }

    /// A cylinder of half-height `half_length` along the unit vector `axis`.
    pub fn cylinder(center: DVec3, axis: DVec3, half_length: f64, radius: f64) -> Self {
        Self::frame(
            Shape::Cylinder,
            center,
            frame_from_z(axis),
            DVec3::new(radius, radius, half_length),
        )
    }

    /// The convex hull of `points`, or `None` when they span no volume.
    pub fn hull(points: &[DVec3]) -> Option<Self> {
        let finite: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
        if finite.len() < 4 {
            return None;
        }
        let mean = finite.iter().copied().sum::<DVec3>() / finite.len() as f64;
        let scale = finite
            .iter()
            .map(|&p| (p - mean).length())
            .fold(0.0f64, math::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        let local: Vec<DVec3> = finite.iter().map(|&p| (p - mean) / scale).collect();
        // Centre the polyhedron on its vertices' mean, so that the origin is well inside.
        let first = Polytope::new(&local)?;
        let shift = first.vertices().iter().copied().sum::<DVec3>() / first.vertices().len() as f64;
        let centred: Vec<DVec3> = first.vertices().iter().map(|&v| v - shift).collect();
        let poly = Polytope::new(&centred)?;
        Some(Self {
            shape: Shape::Hull,
            center: mean + shift * scale,
            axes: DMat3::IDENTITY,
            radii: DVec3::splat(scale),
            polytope: Some(Arc::new(poly)),
        })
    }

    /// The volume's parameters as its shape has them, so that no caller reads `radii` by
    /// shape: e.g. a sphere's centre and radius, a capsule's centre, axis, half-length and
    /// radius, a hull's polyhedron.
    #[must_use]
    pub fn view(&self) -> ShapeView<'_> {
        let center = self.center;
        match self.shape {
            Shape::Ellipsoid => ShapeView::Ellipsoid {
                center,
                axes: self.axes,
                radii: self.radii,
            },
            Shape::Obb => ShapeView::Obb {
                center,
                axes: self.axes,
                half_extents: self.radii,
            },
            Shape::Sphere => ShapeView::Sphere {
                center,
                radius: self.radius(),
            },
            Shape::Capsule => ShapeView::Capsule {
                center,
                axis: self.axis(),
                half_length: self.half_length(),
                radius: self.radius(),
            },
            Shape::Cylinder => ShapeView::Cylinder {
                center,
                axis: self.axis(),
                half_length: self.half_length(),
                radius: self.radius(),
            },
            Shape::Hull => ShapeView::Hull {
                center,
                scale: self.radii.x,
                polytope: self.polytope(),
            },
        }
    }

    /// The polyhedron of a hull, in local coordinates.
    pub fn polytope(&self) -> Option<&Polytope> {
        self.polytope.as_deref()
    }

    /// A hull's vertices in world coordinates (empty for the other shapes).
    pub fn hull_points(&self) -> Vec<DVec3> {
        self.polytope()
            .map(|p| p.vertices().iter().map(|&t| self.world(t)).collect())
            .unwrap_or_default()
    }

    /// The radius of a sphere, capsule or cylinder (for the others, the first radius).
    pub fn radius(&self) -> f64 {
        self.radii.x
    }

    /// The half-length of a capsule's segment or a cylinder's height (for the others, the
    /// third radius). A capsule as short as a ball reads 0.
    pub fn half_length(&self) -> f64 {
        if self.shape == Shape::Capsule && self.radii.z <= 2.0 * MIN_CAPSULE_LENGTH * self.radii.x {
            0.0
        } else {
            self.radii.z
        }
    }

    /// The axis of a capsule or cylinder (for the others, the third axis).
    pub fn axis(&self) -> DVec3 {
        self.axes.z_axis
    }

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

    /// The world point of local coordinates `t`.
    #[inline]
    pub fn world(&self, t: DVec3) -> DVec3 {
        self.center + self.axes * (t * self.radii)
    }

    /// A capsule's half-length over its radius.
    #[inline]
    fn capsule_ratio(&self) -> f64 {
        self.radii.z / self.radii.x
    }

    /// The gauge of `p`: <= 1 inside, > 1 outside; scaling the radii by `s` divides it by `s`
    /// (for the ellipsoid it is `sqrt(sum t^2)`, for the box `max |t|`).
    #[inline]
    pub fn gauge(&self, p: DVec3) -> f64 {
        self.gauge_local(self.local(p))
    }

    /// [`BoundingVolume::gauge`] of local coordinates `t`.
    #[inline]
    pub fn gauge_local(&self, t: DVec3) -> f64 {
        match self.shape {
            Shape::Ellipsoid | Shape::Sphere => t.length(),
            Shape::Obb => t.abs().max_element(),
            Shape::Cylinder => math::max(t.truncate().length(), t.z.abs()),
            Shape::Capsule => {
                // In units of the radius: rho from the axis, zeta along it, l the half-length.
                let l = self.capsule_ratio();
                let rho = t.truncate().length();
                let zeta = t.z.abs() * l;
                if rho * l >= zeta {
                    rho
                } else {
                    // The scale s with (zeta - s l)^2 + rho^2 = s^2 (the point on the scaled
                    // end cap), in the form that stays stable for every l.
                    let q = zeta * zeta + rho * rho;
                    q / (zeta * l + math::max(q - rho * rho * l * l, 0.0).sqrt())
                }
            }
            Shape::Hull => self.polytope().map_or(f64::INFINITY, |p| p.gauge(t)),
        }
    }

    /// Whether `p` is inside, with a relative slack of `1e-9` as in the JSON schema's test.
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        let t = self.local(p);
        match self.shape {
            Shape::Ellipsoid | Shape::Sphere => t.length_squared() <= 1.0 + 1e-9,
            Shape::Obb => t.abs().max_element() <= 1.0 + 1e-9,
            Shape::Cylinder => {
                t.truncate().length_squared() <= 1.0 + 1e-9 && t.z.abs() <= 1.0 + 1e-9
            }
            Shape::Capsule => {
                let l = self.capsule_ratio();
                let e = math::max(t.z.abs() * l - l, 0.0);
                t.truncate().length_squared() + e * e <= 1.0 + 1e-9
            }
            Shape::Hull => self.gauge_local(t) <= 1.0 + 1e-9,
        }
    }

    /// Volume.
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        let r = self.radii;
        let p = r.x * r.y * r.z;
        match self.shape {
            Shape::Ellipsoid | Shape::Sphere => 4.0 / 3.0 * PI * p,
            Shape::Obb => 8.0 * p,
            Shape::Cylinder => 2.0 * PI * p,
            Shape::Capsule => PI * r.x * r.x * (2.0 * self.half_length() + 4.0 / 3.0 * r.x),
            Shape::Hull => self.polytope().map_or(0.0, Polytope::volume) * p,
        }
    }

    /// The volume grown outward by at least `d` everywhere: it holds every point within
    /// distance `d` of this one (its Minkowski sum with a ball of radius `d`). A box's
    /// half-extents, a sphere's, capsule's or cylinder's radius and a cylinder's half-height
    /// grow by `d`; a hull is scaled about its centre until its nearest face has moved out by
    /// `d`. An ellipsoid's semi-axes cannot simply grow by `d` (the result would miss the
    /// offset near the ends of its long axes); of two ellipsoids with the same centre and axes
    /// that hold the offset, the smaller is taken: all semi-axes scaled by `1 + d / a_min`, or
    /// `a_j -> sqrt(a_j^2 + 2 d a_max + d^2)` (its support function is at least `h + d` since
    /// `sum_j a_max u_j^2 = a_max >= h` for a unit direction `u`).
    #[must_use]
    pub fn grown(mut self, d: f64) -> Self {
        if d.is_nan() || d <= 0.0 {
            return self;
        }
        self.radii = match self.shape {
            Shape::Obb | Shape::Sphere | Shape::Cylinder => self.radii + DVec3::splat(d),
            Shape::Capsule => self.radii + DVec3::new(d, d, 0.0),
            Shape::Hull => {
                let nearest = self.polytope().map_or(1.0, Polytope::min_offset) * self.radii.x;
                self.radii * (1.0 + d / nearest)
            }
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

    /// A digest of the exact bits of the volume (FNV-1a over centre, axes, radii and a hull's
    /// vertices), for tests that results are the same on every platform and thread count.
    #[doc(hidden)]
    pub fn bits_digest(&self) -> u64 {
        let hull: Vec<f64> = self
            .polytope()
            .map(|p| p.vertices().iter().flat_map(|v| v.to_array()).collect())
            .unwrap_or_default();
        let words = self
            .center
            .to_array()
            .into_iter()
            .chain(self.axes.to_cols_array())
            .chain(self.radii.to_array())
            .chain(hull);
        words.fold(0xcbf2_9ce4_8422_2325, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        })
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn aabb(&self) -> (DVec3, DVec3) {
        let a = self.axes;
        let r = self.radii;
        // Row i of the frame, the world axis i in local terms.
        let row = |i: usize| DVec3::new(a.x_axis[i], a.y_axis[i], a.z_axis[i]);
        let half = match self.shape {
            Shape::Ellipsoid | Shape::Sphere => {
                DVec3::from_array(std::array::from_fn(|i| (row(i) * r).length()))
            }
            Shape::Obb => {
                DVec3::from_array(std::array::from_fn(|i| (row(i) * r).abs().element_sum()))
            }
            Shape::Cylinder => DVec3::from_array(std::array::from_fn(|i| {
                let c = row(i).z;
                r.z * c.abs() + r.x * math::max(1.0 - c * c, 0.0).sqrt()
            })),
            Shape::Capsule => {
                DVec3::from_array(std::array::from_fn(|i| r.z * row(i).z.abs() + r.x))
            }
            Shape::Hull => {
                let pts = self.hull_points();
                if pts.is_empty() {
                    return (self.center, self.center);
                }
                let lo = pts.iter().copied().fold(DVec3::INFINITY, DVec3::min);
                let hi = pts.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
                return (lo, hi);
            }
        };
        (self.center - half, self.center + half)
    }

    /// Scale the radii uniformly so that every point of `points` satisfies `gauge <= 1`
    /// (exactly, up to a relative margin of 1e-12), keeping the shape if it already holds them.
    #[must_use]
    pub fn scaled_to_contain(mut self, points: impl IntoIterator<Item = DVec3>) -> Self {
        let g = points
            .into_iter()
            .map(|p| self.gauge(p))
            .fold(0.0f64, math::max);
        if g > 1.0 {
            self.radii *= g * (1.0 + 1e-12);
        }
        self
    }
}

/// A right-handed orthonormal frame whose third axis is the unit vector `z`.
fn frame_from_z(z: DVec3) -> DMat3 {
    let z = z.try_normalize().unwrap_or(DVec3::Z);
    let x = z.any_orthonormal_vector();
    DMat3::from_cols(x, z.cross(x), z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_names_each_shapes_parameters() {
        let c = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(
            BoundingVolume::sphere(c, 0.5).view(),
            ShapeView::Sphere {
                center: c,
                radius: 0.5
            }
        );
        let cap = BoundingVolume::capsule(c, DVec3::Y, 2.0, 0.25);
        let ShapeView::Capsule {
            center,
            axis,
            half_length,
            radius,
        } = cap.view()
        else {
            panic!("a capsule's view is a capsule");
        };
        assert_eq!((center, half_length, radius), (c, 2.0, 0.25));
        assert!((axis - DVec3::Y).length() < 1e-12);
        // A capsule as short as a ball reads half-length 0, as `half_length()` does.
        let ball = BoundingVolume::capsule(c, DVec3::Z, 0.0, 1.0);
        assert!(
            matches!(ball.view(), ShapeView::Capsule { half_length, .. } if half_length == 0.0)
        );
        let cube: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64))
            .collect();
        let hull = BoundingVolume::hull(&cube).unwrap();
        let ShapeView::Hull {
            scale, polytope, ..
        } = hull.view()
        else {
            panic!("a hull's view is a hull");
        };
        assert_eq!(scale, hull.radii.x);
        assert_eq!(polytope.map(|p| p.vertices().len()), Some(8));
    }

    #[test]
    fn aabb_of_rotated_box_holds_corners() {
        let axes = DMat3::from_euler(glam::EulerRot::XYZ, 0.4, 0.2, -0.7);
        let v = BoundingVolume::frame(
            Shape::Obb,
            DVec3::new(1.0, 2.0, 3.0),
            axes,
            DVec3::new(1.0, 0.5, 2.0),
        );
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
