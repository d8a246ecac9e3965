//! The volumes as [parry3d](https://parry.rs) shapes, for rapier, Avian and anything else
//! built on parry (the `parry` feature).
//!
//! Spheres, boxes, capsules and cylinders become parry's own [`Ball`], [`Cuboid`],
//! [`Capsule`] and [`Cylinder`]; hulls become [`ConvexPolyhedron`]s; parry has no ellipsoid,
//! so an ellipsoid becomes a convex polyhedron that encloses it (62 vertices, faces touching
//! it from outside), never an inscribed one.
//!
//! parry stores shapes in f32, and rounding a volume's centre, rotation and sizes to f32
//! moves its boundary by up to an ulp or so of its coordinates. So that the enclosure
//! survives the rounding, every volume is first grown by [`f32_margin`] (about `5e-7` of the
//! volume's distance from the origin plus its size); the growth is far below anything a
//! physics engine resolves.
//!
//! parry's point test on a convex polyhedron (`contains_point`, GJK in f32) calls a point
//! within about `1e-3` of the polyhedron's size of its boundary touching rather than inside,
//! whatever the polyhedron. On the 21 shared meshes with `--target parry-hull`, that turned
//! 1 vertex in 1,480-24,000 on 3 meshes into "outside" although the exact face-plane test
//! puts it inside (by the f32 margin); balls, cuboids and capsules have exact point tests.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use parry3d::math::{Pose, Vector};
//! use parry3d::query::PointQuery;
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/meshes/bunny.obj");
//! let loaded = bvseg::io::load(path, &bvseg::io::LoadOptions::default())?;
//! let params = bvseg::Params { k: Some(8), kinds: bvseg::Target::Parry.kinds(), ..Default::default() };
//! let seg = bvseg::segment(&loaded.mesh, &params)?;
//! let compound = bvseg::parry::to_compound(&seg);
//! let v = loaded.mesh.vertices()[0].as_vec3();
//! assert!(compound.contains_point(&Pose::IDENTITY, Vector::new(v.x, v.y, v.z)));
//! # Ok(())
//! # }
//! ```
//!
//! [`Ball`]: parry3d::shape::Ball
//! [`Cuboid`]: parry3d::shape::Cuboid
//! [`Capsule`]: parry3d::shape::Capsule
//! [`Cylinder`]: parry3d::shape::Cylinder
//! [`ConvexPolyhedron`]: parry3d::shape::ConvexPolyhedron
use bvseg_core::{BoundingVolume, Segmentation, Shape};
use glam::Vec3;
use parry3d::math::Pose;
use parry3d::shape::SharedShape;

use crate::io::export::{enclosing_points, volume_rotation, y_up_rotation};

/// Relative f32 rounding allowance: eight units of f32's 24-bit mantissa. Rounding the
/// centre costs at most half an ulp per coordinate of `|centre|`, the unit quaternion's
/// rounding turns a point at distance `R` by a few ulps of `R`, and parry's own f32 point
/// test adds about as much again.
const F32_SLACK: f64 = 8.0 / (1u64 << 24) as f64;

/// How far [`to_shapes`] grows `v` before rounding it to f32: [`F32_SLACK`] times the
/// volume's largest centre coordinate plus its largest extent, in mesh units.
#[must_use]
pub fn f32_margin(v: &BoundingVolume) -> f64 {
    let (lo, hi) = v.aabb();
    let extent = (hi - lo).max_element();
    F32_SLACK * (v.center.abs().max_element() + extent)
}

/// Each part's volume as a parry shape with its pose, in part order: native balls,
/// cuboids, capsules and cylinders, convex polyhedra for hulls and (enclosing) for
/// ellipsoids. For engines that take one collider per part (rapier's `ColliderBuilder::new`
/// with the shape and `.position(pose)`).
#[must_use]
pub fn to_shapes(seg: &Segmentation) -> Vec<(Pose, SharedShape)> {
    seg.parts.iter().map(|p| to_shape(&p.volume)).collect()
}

/// The whole union as one parry compound shape (a rigid body's single collider): the
/// shapes of [`to_shapes`], each placed at its pose.
///
/// # Panics
///
/// If `seg` has no parts; a [`Segmentation`] from [`crate::segment`] always has at least one.
#[must_use]
pub fn to_compound(seg: &Segmentation) -> SharedShape {
    let shapes = to_shapes(seg);
    assert!(
        !shapes.is_empty(),
        "bvseg::parry::to_compound: the segmentation has no parts"
    );
    SharedShape::compound(shapes)
}

/// One volume as a parry shape and the pose that places it.
fn to_shape(volume: &BoundingVolume) -> (Pose, SharedShape) {
    let v = volume.clone().grown(f32_margin(volume));
    let center = v.center.as_vec3();
    let placed = |rotation: glam::DQuat| Pose::from_parts(center, rotation.as_quat());
    match v.shape {
        Shape::Sphere => (
            Pose::from_translation(center),
            SharedShape::ball(up(v.radius())),
        ),
        Shape::Obb => {
            let r = v.radii;
            let shape = SharedShape::cuboid(up(r.x), up(r.y), up(r.z));
            (placed(volume_rotation(&v)), shape)
        }
        Shape::Capsule => {
            // parry's capsules run between two points: the segment along local Y.
            let h = up(v.half_length());
            let shape = SharedShape::capsule(
                Vec3::new(0.0, -h, 0.0),
                Vec3::new(0.0, h, 0.0),
                up(v.radius()),
            );
            (placed(y_up_rotation(&v)), shape)
        }
        Shape::Cylinder => {
            let shape = SharedShape::cylinder(up(v.half_length()), up(v.radius()));
            (placed(y_up_rotation(&v)), shape)
        }
        Shape::Ellipsoid | Shape::Hull => {
            let points: Vec<Vec3> = enclosing_points(&v).iter().map(|p| p.as_vec3()).collect();
            let shape = SharedShape::convex_hull(&points).unwrap_or_else(|| flat_box(&points));
            (Pose::from_translation(center), shape)
        }
    }
}

/// The box around a flat (or degenerate) point set, which parry cannot hull: it encloses
/// the same points, and a flat hull has no inside for a point test to find anyway.
fn flat_box(points: &[Vec3]) -> SharedShape {
    let half = points
        .iter()
        .fold(Vec3::ZERO, |m, p| m.max(p.abs()))
        .max(Vec3::splat(f32::MIN_POSITIVE));
    SharedShape::cuboid(half.x, half.y, half.z)
}

/// `x` as the nearest f32 at least `x`: sizes never shrink in the conversion.
fn up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x && f.is_finite() {
        // The next f32 above a finite positive value (f32::next_up needs Rust 1.86).
        if f > 0.0 {
            f32::from_bits(f.to_bits() + 1)
        } else {
            f32::MIN_POSITIVE
        }
    } else {
        f
    }
}
