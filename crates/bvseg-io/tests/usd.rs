//! The USD output read back by a small reader of the USDA it writes: one collider prim per
//! volume of the native kind, the transforms UsdPhysics accepts, and every volume inside its
//! prim as the prim's attributes place it.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::collections::BTreeMap;
use std::fs;

use bvseg_core::{
    BoundingVolume, Joint, Kinds, Metrics, Part, Segmentation, Shape, Skeleton, BALL_COVER_VERTICES,
};
use bvseg_io::export::{to_usda, write_output, ExportOptions, UpAxis, UsdOptions};
use glam::{DMat3, DMat4, DQuat, DVec3, EulerRot};

fn rot(euler: (f64, f64, f64)) -> DMat3 {
    DMat3::from_quat(DQuat::from_euler(EulerRot::XYZ, euler.0, euler.1, euler.2))
}

fn part(volume: BoundingVolume) -> Part {
    Part {
        volume,
        fraction: 1.0 / 6.0,
        samples: 100,
        ov: 0.1,
        e: 1.0,
        protrusion: 0.1,
        bone: None,
    }
}

/// One volume of each kind, rotated and off the origin (a hull far from it, where rounding
/// its points to `f32` matters most), and a capsule as short as a ball.
fn volumes() -> Vec<BoundingVolume> {
    let hull_points: Vec<DVec3> = (0..12)
        .map(|i| {
            let a = i as f64 * 2.4;
            DVec3::new(300.0 + a.cos(), a.sin() * 0.7, 0.3 * i as f64)
        })
        .collect();
    vec![
        BoundingVolume::frame(
            Shape::Ellipsoid,
            DVec3::new(1.0, 2.0, 3.0),
            rot((0.3, -0.2, 1.0)),
            DVec3::new(0.5, 1.0, 2.0),
        ),
        BoundingVolume::frame(
            Shape::Obb,
            DVec3::new(-1.0, 0.0, 0.5),
            rot((1.2, 0.4, -0.7)),
            DVec3::new(0.25, 0.75, 1.5),
        ),
        BoundingVolume::sphere(DVec3::new(0.5, -2.0, 1.0), 0.75),
        BoundingVolume::capsule(
            DVec3::new(2.0, 1.0, -1.0),
            rot((0.2, 0.9, -0.4)).z_axis,
            1.25,
            0.4,
        ),
        BoundingVolume::cylinder(
            DVec3::new(-2.0, 1.5, 0.0),
            rot((-0.6, 0.1, 0.8)).z_axis,
            0.8,
            0.3,
        ),
        BoundingVolume::hull(&hull_points).unwrap(),
        BoundingVolume::capsule(DVec3::new(0.0, 5.0, 0.0), DVec3::X, 0.0, 0.5),
    ]
}

fn seg(volumes: Vec<BoundingVolume>) -> Segmentation {
    Segmentation {
        kinds: Kinds::PRIMITIVES.with(Shape::Hull),
        parts: volumes.into_iter().map(part).collect(),
        metrics: Metrics {
            k: 7,
            f: 1.1,
            tov: 0.2,
            mov: 0.3,
            protrusion: 0.1,
            protrusion_rel: 0.02,
            diagonal: 5.0,
            samples: 200,
        },
        history: vec![],
        hierarchy: vec![],
        triangle_parts: vec![0, 1],
        sample_parts: vec![],
        cell_size: 0.1,
        budget_exhausted: false,
        skeleton: None,
        route: bvseg_core::Route::Lattice,
    }
}

/// A prim as the file writes it: its type, name, API schemas and attributes (name to the
/// value's text), and the depth it is at.
#[derive(Debug, Default)]
struct Prim {
    kind: String,
    name: String,
    depth: usize,
    schemas: Vec<String>,
    attrs: BTreeMap<String, String>,
}

/// The layer metadata and the prims, in file order. Only what the writer writes: one
/// attribute a line, `def TYPE "name"` with an optional metadata block of `apiSchemas`.
fn parse(text: &str) -> (BTreeMap<String, String>, Vec<Prim>) {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("#usda 1.0"));
    assert_eq!(lines.next(), Some("("));
    let mut meta = BTreeMap::new();
    for l in lines.by_ref() {
        if l == ")" {
            break;
        }
        let (k, v) = l.trim().split_once(" = ").unwrap();
        meta.insert(k.to_owned(), v.to_owned());
    }
    let mut prims: Vec<Prim> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    for l in lines {
        let t = l.trim();
        if let Some(rest) = t.strip_prefix("def ") {
            let (kind, name) = rest.split_once(' ').unwrap();
            prims.push(Prim {
                kind: kind.to_owned(),
                name: name.trim_end_matches(" (").trim_matches('"').to_owned(),
                depth: open.len(),
                ..Prim::default()
            });
        } else if let Some(list) = t.strip_prefix("prepend apiSchemas = ") {
            let p = prims.last_mut().unwrap();
            p.schemas = list
                .trim_matches(['[', ']'])
                .split(", ")
                .map(|s| s.trim_matches('"').to_owned())
                .collect();
        } else if t == "{" {
            open.push(prims.len() - 1);
        } else if t == "}" {
            open.pop().unwrap();
        } else if let Some((k, v)) = t.split_once(" = ") {
            let p = &mut prims[*open.last().unwrap()];
            // `uniform double3 xformOp:translate` -> `xformOp:translate`
            let key = k.rsplit(' ').next().unwrap();
            p.attrs.insert(key.to_owned(), v.to_owned());
        } else {
            assert!(t.is_empty() || t == ")", "unexpected line {t:?}");
        }
    }
    assert!(open.is_empty(), "unbalanced braces");
    (meta, prims)
}

/// The numbers of a value: `(1, 2), (3, 4)` -> `[1, 2, 3, 4]`.
fn numbers(v: &str) -> Vec<f64> {
    v.split(|c: char| !(c.is_ascii_digit() || "-.e".contains(c)))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect()
}

fn vec3(v: &str) -> DVec3 {
    let n = numbers(v);
    assert_eq!(n.len(), 3, "{v}");
    DVec3::new(n[0], n[1], n[2])
}

/// The prim's local-to-parent transform from its xform ops, checking their order.
fn transform(p: &Prim) -> DMat4 {
    let order = p.attrs["xformOpOrder"].clone();
    let mut m = DMat4::IDENTITY;
    for op in order.trim_matches(['[', ']']).split(", ") {
        let op = op.trim_matches('"');
        let v = &p.attrs[op];
        m *= match op {
            "xformOp:translate" => DMat4::from_translation(vec3(v)),
            "xformOp:orient" => {
                let n = numbers(v);
                let q = DQuat::from_xyzw(n[1], n[2], n[3], n[0]);
                assert!((q.length() - 1.0).abs() < 1e-12, "{v}");
                DMat4::from_quat(q)
            }
            "xformOp:scale" => DMat4::from_scale(vec3(v)),
            _ => panic!("unknown op {op}"),
        };
    }
    m
}

/// Whether world point `x` is inside collider `p` placed by `world` (tolerance `tol` in
/// the prim's local units).
fn inside(p: &Prim, world: DMat4, x: DVec3, tol: f64) -> bool {
    let q = world.inverse().transform_point3(x);
    let num = |k: &str| numbers(&p.attrs[k])[0];
    let along = |q: DVec3| -> (f64, f64) {
        match p.attrs["axis"].as_str() {
            "\"X\"" => (q.x, q.y.hypot(q.z)),
            "\"Y\"" => (q.y, q.x.hypot(q.z)),
            _ => (q.z, q.x.hypot(q.y)),
        }
    };
    match p.kind.as_str() {
        "Cube" => q.abs().max_element() <= num("size") / 2.0 + tol,
        "Sphere" => q.length() <= num("radius") + tol,
        "Cylinder" => {
            let (a, r) = along(q);
            a.abs() <= num("height") / 2.0 + tol && r <= num("radius") + tol
        }
        "Capsule" => {
            let (a, r) = along(q);
            let beyond = (a.abs() - num("height") / 2.0).max(0.0);
            beyond.hypot(r) <= num("radius") + tol
        }
        "Mesh" => {
            let pts: Vec<DVec3> = numbers(&p.attrs["points"])
                .chunks(3)
                .map(|c| DVec3::new(c[0], c[1], c[2]))
                .collect();
            let hull = BoundingVolume::hull(&pts).unwrap();
            hull.polytope()
                .unwrap()
                .planes()
                .iter()
                .all(|&(n, d)| n.dot(q - hull.center) <= d * hull.radii.x + tol)
        }
        k => panic!("not a collider kind: {k}"),
    }
}

/// Points on the boundary of `v` in many directions from its centre.
fn boundary(v: &BoundingVolume) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..400 {
        // A Fibonacci spiral of directions.
        let z = 1.0 - (2 * i + 1) as f64 / 400.0;
        let a = i as f64 * 2.399_963_229_728_653;
        let u = DVec3::new(
            (1.0 - z * z).sqrt() * a.cos(),
            (1.0 - z * z).sqrt() * a.sin(),
            z,
        );
        let g = v.gauge(v.center + u);
        out.push(v.center + u / g);
    }
    if let Some(p) = v.polytope() {
        out.extend(p.vertices().iter().map(|&t| v.world(t)));
    }
    out
}

#[test]
fn one_native_collider_per_volume() {
    let volumes = volumes();
    let text = to_usda(
        &seg(volumes.clone()),
        "my colliders",
        &UsdOptions::default(),
    );
    let (meta, prims) = parse(&text);
    assert_eq!(meta["defaultPrim"], "\"my_colliders\"");
    assert_eq!(meta["upAxis"], "\"Y\"");
    assert_eq!(meta["metersPerUnit"], "1");
    assert_eq!(
        (
            prims[0].kind.as_str(),
            prims[0].name.as_str(),
            prims[0].depth
        ),
        ("Xform", "my_colliders", 0)
    );
    assert!(prims[0].schemas.is_empty(), "static unless asked");
    let colliders = &prims[1..];
    assert_eq!(colliders.len(), volumes.len());
    let mut counts = BTreeMap::new();
    for p in colliders {
        *counts.entry(p.kind.as_str()).or_insert(0) += 1;
    }
    // The ellipsoid and the hull are meshes; the short capsule is a sphere.
    assert_eq!(
        counts,
        BTreeMap::from([
            ("Capsule", 1),
            ("Cube", 1),
            ("Cylinder", 1),
            ("Mesh", 2),
            ("Sphere", 2)
        ])
    );
    for (i, p) in colliders.iter().enumerate() {
        assert_eq!(p.name, format!("part_{i}"));
        assert_eq!(p.depth, 1);
        assert!(
            p.schemas.contains(&"PhysicsCollisionAPI".to_owned()),
            "{p:?}"
        );
        assert_eq!(p.attrs["purpose"], "\"guide\"");
        assert_eq!(numbers(&p.attrs["extent"]).len(), 6);
        match p.kind.as_str() {
            // No scale at all on the shapes PhysX takes only uniformly scaled.
            "Sphere" | "Capsule" | "Cylinder" => {
                assert!(!p.attrs.contains_key("xformOp:scale"), "{p:?}");
                assert!(!p.attrs["xformOpOrder"].contains("scale"), "{p:?}");
            }
            "Cube" => assert_eq!(p.attrs["size"], "2"),
            "Mesh" => {
                assert!(p.schemas.contains(&"PhysicsMeshCollisionAPI".to_owned()));
                assert_eq!(p.attrs["physics:approximation"], "\"convexHull\"");
                let points = numbers(&p.attrs["points"]).len() / 3;
                assert!(points <= BALL_COVER_VERTICES, "{points} points");
                let indices = numbers(&p.attrs["faceVertexIndices"]);
                let counts = numbers(&p.attrs["faceVertexCounts"]);
                assert_eq!(indices.len(), 3 * counts.len());
                assert!(indices.iter().all(|&i| (i as usize) < points));
            }
            k => panic!("unexpected {k}"),
        }
    }
}

#[test]
fn every_volume_is_inside_its_prim_and_its_extent() {
    let volumes = volumes();
    let text = to_usda(&seg(volumes.clone()), "c", &UsdOptions::default());
    let (_, prims) = parse(&text);
    for (v, p) in volumes.iter().zip(&prims[1..]) {
        let world = transform(p);
        let ext = numbers(&p.attrs["extent"]);
        let (lo, hi) = (
            DVec3::new(ext[0], ext[1], ext[2]),
            DVec3::new(ext[3], ext[4], ext[5]),
        );
        let scale = v.radii.max_element();
        for x in boundary(v) {
            assert!(
                inside(p, world, x, 1e-9 * scale),
                "{:?} {}: {x} outside",
                v.shape,
                p.name
            );
            let q = world.inverse().transform_point3(x);
            assert!(q.cmpge(lo - 1e-9 * scale).all() && q.cmple(hi + 1e-9 * scale).all());
        }
    }
    // And the prims are not loose: a box's corner is on its cube, a sphere's radius is its.
    let cube = &prims[2];
    let corner = volumes[1].world(DVec3::ONE);
    assert!(!inside(
        cube,
        transform(cube),
        corner * 1.001 - volumes[1].center * 0.001,
        0.0
    ));
    assert_eq!(numbers(&prims[3].attrs["radius"])[0], 0.75);
}

#[test]
fn options_and_bones_are_written() {
    let mut s = seg(volumes());
    s.skeleton = Some(Skeleton {
        joints: vec![Joint {
            name: "hip \"L\"".into(),
            parent: None,
            rest: DMat4::IDENTITY,
            node: None,
        }],
    });
    s.parts[1].bone = Some(0);
    let options = UsdOptions {
        up_axis: UpAxis::Z,
        meters_per_unit: 0.01,
        rigid_body: true,
    };
    let (meta, prims) = parse(&to_usda(&s, "9lives", &options));
    assert_eq!(meta["defaultPrim"], "\"_9lives\"");
    assert_eq!(meta["upAxis"], "\"Z\"");
    assert_eq!(meta["metersPerUnit"], "0.01");
    assert_eq!(prims[0].schemas, ["PhysicsRigidBodyAPI"]);
    assert_eq!(prims[2].attrs["bvseg:bone"], "\"hip \\\"L\\\"\"");
    assert!(!prims[1].attrs.contains_key("bvseg:bone"));

    let dir = bvseg_testkit::scratch("usd_options_and_bones");
    let out = |mpu: f64| ExportOptions {
        usd: UsdOptions {
            meters_per_unit: mpu,
            ..UsdOptions::default()
        },
        ..ExportOptions::default()
    };
    write_output(dir.join("a.usda"), &s, &out(1.0)).unwrap();
    let text = fs::read_to_string(dir.join("a.usda")).unwrap();
    assert!(text.contains("defaultPrim = \"a\""));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = write_output(dir.join("b.usda"), &s, &out(bad)).unwrap_err();
        assert!(e.to_string().contains("meters per unit"), "{e}");
    }
    assert!(!dir.join("b.usda").exists());
}
