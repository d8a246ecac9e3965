//! `bvseg::parry`: the compound holds every mesh vertex, with parry's own shape of each kind.
#![cfg(feature = "parry")]
// Test helpers outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bvseg::{Kinds, Params, Segmentation, Shape, Target};
use bvseg_testkit::bundled_mesh;
use parry3d::math::{Pose, Vector};
use parry3d::shape::{ShapeType, SharedShape};

fn segment(file: &str, kinds: Kinds, k: usize) -> (bvseg::Mesh, Segmentation) {
    let loaded = bvseg::io::load(bundled_mesh(file), &bvseg::io::LoadOptions::default()).unwrap();
    let params = Params {
        k: Some(k),
        kinds,
        samples: 8_000,
        ..Default::default()
    };
    let seg = bvseg::segment(&loaded.mesh, &params).unwrap();
    (loaded.mesh, seg)
}

fn vertices_outside(mesh: &bvseg::Mesh, shape: &SharedShape) -> usize {
    mesh.vertices()
        .iter()
        .filter(|v| {
            let p = v.as_vec3();
            !shape.contains_point(&Pose::IDENTITY, Vector::new(p.x, p.y, p.z))
        })
        .count()
}

/// The parry shape type each bvseg kind must become.
fn parry_type(shape: Shape) -> ShapeType {
    match shape {
        Shape::Sphere => ShapeType::Ball,
        Shape::Obb => ShapeType::Cuboid,
        Shape::Capsule => ShapeType::Capsule,
        Shape::Cylinder => ShapeType::Cylinder,
        Shape::Ellipsoid | Shape::Hull => ShapeType::ConvexPolyhedron,
    }
}

#[test]
fn every_vertex_is_inside_the_compound_for_every_kind_set() {
    let sets = [
        Target::Parry.kinds(),
        Target::kinds_of("parry-hull").unwrap(),
        Kinds::ELLIPSOID,
        Kinds::HULL,
        Kinds::CAPSULE,
        Kinds::CYLINDER,
        Kinds::SPHERE,
        Kinds::OBB,
    ];
    for file in ["bunny.obj", "spot.obj"] {
        for kinds in sets {
            let (mesh, seg) = segment(file, kinds, 10);
            let shapes = bvseg::parry::to_shapes(&seg);
            assert_eq!(shapes.len(), seg.parts.len());
            for (part, (_, shape)) in seg.parts.iter().zip(&shapes) {
                assert_eq!(
                    shape.shape_type(),
                    parry_type(part.volume.shape),
                    "{file} {kinds}"
                );
            }
            let compound = bvseg::parry::to_compound(&seg);
            assert_eq!(compound.shape_type(), ShapeType::Compound);
            assert_eq!(vertices_outside(&mesh, &compound), 0, "{file} {kinds}");
        }
    }
}

#[test]
fn each_shape_matches_its_volume() {
    // Points just inside each volume are inside its parry shape, points well outside it are
    // not: the pose and sizes are the volume's, not merely something large.
    let (_, seg) = segment("bunny.obj", Target::kinds_of("parry-hull").unwrap(), 12);
    let mut probes = 0;
    for (part, (pose, shape)) in seg.parts.iter().zip(bvseg::parry::to_shapes(&seg)) {
        let v = &part.volume;
        let (lo, hi) = v.aabb();
        let size = (hi - lo).max_element();
        for i in 0..400 {
            // A deterministic spread of directions.
            let t = i as f64 * 0.618_033_988_749_895;
            let z = 1.0 - 2.0 * ((i as f64 + 0.5) / 400.0);
            let r = (1.0 - z * z).sqrt();
            let d = glam::DVec3::new(
                r * (t * std::f64::consts::TAU).cos(),
                r * (t * std::f64::consts::TAU).sin(),
                z,
            );
            // March out from the centre to the boundary along d.
            let (mut a, mut b) = (0.0, size);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if v.contains(v.center + d * m) {
                    a = m;
                } else {
                    b = m;
                }
            }
            // 1 % inside: parry's point test on convex polyhedra (GJK in f32) calls points
            // within about 1e-3 of the shape's size of its boundary touching, not inside.
            let inside = (v.center + d * (a * 0.99)).as_vec3();
            let outside = (v.center + d * (a + 0.02 * size)).as_vec3();
            let q = |p: glam::Vec3| shape.contains_point(&pose, Vector::new(p.x, p.y, p.z));
            assert!(
                q(inside),
                "{:?}: a point inside is outside its shape",
                v.shape
            );
            if v.shape != Shape::Ellipsoid {
                // The ellipsoid's enclosing polyhedron reaches further (its corners).
                assert!(
                    !q(outside),
                    "{:?}: a point outside is inside its shape",
                    v.shape
                );
            }
            probes += 1;
        }
    }
    assert!(probes > 0);
}
