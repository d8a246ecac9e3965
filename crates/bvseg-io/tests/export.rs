//! The engine-ready outputs read back: GLB through the `gltf` crate, MJCF as XML, OBJ through
//! our own reader.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)]
use std::fs;

use bvseg_core::{BoundingVolume, Kinds, Metrics, Part, Segmentation, Shape};
use bvseg_io::export::{to_glb, to_labels, to_mjcf, to_obj, write_output, ExportOptions};
use glam::{DMat3, DQuat, DVec3, EulerRot};

fn rot(euler: (f64, f64, f64)) -> DMat3 {
    DMat3::from_quat(DQuat::from_euler(EulerRot::XYZ, euler.0, euler.1, euler.2))
}

fn part(shape: Shape, center: DVec3, radii: DVec3, euler: (f64, f64, f64)) -> Part {
    with_volume(BoundingVolume::frame(shape, center, rot(euler), radii))
}

fn with_volume(volume: BoundingVolume) -> Part {
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

/// Six parts, one of each shape, over a two-triangle "mesh".
fn seg() -> Segmentation {
    let hull_points: Vec<DVec3> = (0..10)
        .map(|i| {
            let a = i as f64 * 2.4;
            DVec3::new(3.0 + a.cos(), a.sin() * 0.7, 0.3 * i as f64)
        })
        .collect();
    Segmentation {
        kinds: Kinds::PRIMITIVES.with(Shape::Hull),
        parts: vec![
            part(
                Shape::Ellipsoid,
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::new(0.5, 1.0, 2.0),
                (0.3, -0.2, 1.0),
            ),
            part(
                Shape::Obb,
                DVec3::new(-1.0, 0.0, 0.5),
                DVec3::new(0.25, 0.75, 1.5),
                (1.2, 0.4, -0.7),
            ),
            with_volume(BoundingVolume::sphere(DVec3::new(0.5, -2.0, 1.0), 0.75)),
            with_volume(BoundingVolume::capsule(
                DVec3::new(2.0, 1.0, -1.0),
                rot((0.2, 0.9, -0.4)).z_axis,
                1.25,
                0.4,
            )),
            with_volume(BoundingVolume::cylinder(
                DVec3::new(-2.0, 1.5, 0.0),
                rot((-0.6, 0.1, 0.8)).z_axis,
                0.8,
                0.3,
            )),
            with_volume(BoundingVolume::hull(&hull_points).unwrap()),
        ],
        metrics: Metrics {
            k: 2,
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

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[test]
fn glb_has_one_node_per_volume_and_colliders() {
    let seg = seg();
    let mesh = bvseg_core::Mesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
        vec![[0, 2, 1], [0, 1, 3]],
    )
    .unwrap();
    let bytes = to_glb(&seg, Some(&mesh));
    assert_eq!(bytes, to_glb(&seg, Some(&mesh)), "deterministic");
    // Full validation, including the accessor bounds the spec requires.
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let scene = g.default_scene().unwrap();
    let root = scene.nodes().next().unwrap();
    let parts: Vec<_> = root
        .children()
        .filter(|n| {
            n.name()
                .is_some_and(|s| s.starts_with("part_") && !s.contains("_collider"))
        })
        .collect();
    assert_eq!(parts.len(), seg.parts.len());
    for (i, n) in parts.iter().enumerate() {
        let v = &seg.parts[i].volume;
        assert_eq!(n.name(), Some(format!("part_{i}").as_str()));
        let (t, r, s) = n.transform().decomposed();
        let q = DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64);
        for j in 0..3 {
            assert!(close(t[j] as f64, v.center[j], 1e-6));
        }
        match v.shape {
            Shape::Ellipsoid | Shape::Obb | Shape::Sphere => {
                for j in 0..3 {
                    assert!(close(s[j] as f64, v.radii[j], 1e-6));
                }
                assert!((q * DVec3::Y - v.axes.y_axis).length() < 1e-6);
            }
            Shape::Cylinder => {
                let want = [v.radius(), v.half_length(), v.radius()];
                for j in 0..3 {
                    assert!(close(s[j] as f64, want[j], 1e-6));
                }
                assert!((q * DVec3::Y - v.axis()).length() < 1e-6);
            }
            Shape::Capsule => {
                assert_eq!(s, [1.0; 3]);
                assert!((q * DVec3::Y - v.axis()).length() < 1e-6);
            }
            Shape::Hull => assert_eq!(s, [1.0; 3]),
        }
        assert!(n.mesh().is_some());
    }
    // Colliders: unscaled; a box shape of the exact size, a hull enclosing the ellipsoid.
    let json = g.document.as_json();
    let shapes = &g.extension_value("KHR_implicit_shapes").unwrap()["shapes"];
    for n in root
        .children()
        .filter(|n| n.name().is_some_and(|s| s.ends_with("_collider")))
    {
        let i: usize = n.name().unwrap()["part_".len()..]
            .trim_end_matches("_collider")
            .parse()
            .unwrap();
        let v = &seg.parts[i].volume;
        assert_eq!(n.transform().decomposed().2, [1.0; 3]);
        let geom = &n.extension_value("KHR_physics_rigid_bodies").unwrap()["collider"]["geometry"];
        let shape = |kind: &str| &shapes[geom["shape"].as_u64().unwrap() as usize][kind];
        let (_, r, _) = n.transform().decomposed();
        let q = DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64);
        match v.shape {
            Shape::Obb => {
                let size = &shape("box")["size"];
                for j in 0..3 {
                    assert!(close(size[j].as_f64().unwrap(), 2.0 * v.radii[j], 1e-6));
                }
            }
            Shape::Sphere => {
                assert!(close(
                    shape("sphere")["radius"].as_f64().unwrap(),
                    v.radius(),
                    1e-6
                ));
            }
            Shape::Capsule | Shape::Cylinder => {
                let name = v.shape.as_str();
                let c = shape(name);
                assert_eq!(
                    shapes[geom["shape"].as_u64().unwrap() as usize]["type"],
                    name
                );
                // Along the node's Y; height: the segment (capsule) or the whole (cylinder).
                assert!((q * DVec3::Y - v.axis()).length() < 1e-6);
                assert!(close(
                    c["height"].as_f64().unwrap(),
                    2.0 * v.half_length(),
                    1e-6
                ));
                for key in ["radiusTop", "radiusBottom"] {
                    assert!(close(c[key].as_f64().unwrap(), v.radius(), 1e-6));
                }
            }
            Shape::Hull => {
                assert_eq!(geom["convexHull"], true);
                let hull = g
                    .nodes()
                    .nth(geom["node"].as_u64().unwrap() as usize)
                    .unwrap();
                let prim = hull.mesh().unwrap().primitives().next().unwrap();
                let data = g.blob.as_deref().unwrap();
                let p: Vec<DVec3> = prim
                    .reader(|_| Some(data))
                    .read_positions()
                    .unwrap()
                    .map(|p| DVec3::from_array(p.map(f64::from)))
                    .collect();
                // The hull's own vertices, around the collider node's translation.
                let want = v.hull_points();
                assert_eq!(p.len(), want.len());
                for (a, b) in p.iter().zip(&want) {
                    assert!((*a + v.center - *b).length() < 1e-5);
                }
            }
            Shape::Ellipsoid => {
                assert_eq!(geom["convexHull"], true);
                let hull = g
                    .nodes()
                    .nth(geom["node"].as_u64().unwrap() as usize)
                    .unwrap();
                let prim = hull.mesh().unwrap().primitives().next().unwrap();
                let data = g.blob.as_deref().unwrap();
                let r = prim.reader(|_| Some(data));
                let p: Vec<DVec3> = r
                    .read_positions()
                    .unwrap()
                    .map(|p| DVec3::from_array(p.map(f64::from)))
                    .collect();
                let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
                // Each face plane lies beyond the ellipsoid's support in its normal direction.
                for t in idx.chunks(3) {
                    let [a, b, c] = [0, 1, 2].map(|k| p[t[k] as usize]);
                    let nrm = (b - a).cross(c - a).normalize();
                    let support = (nrm * v.radii).length();
                    assert!(
                        nrm.dot(a) >= support * (1.0 - 1e-6),
                        "{} < {support}",
                        nrm.dot(a)
                    );
                }
                let extras: serde_json::Value =
                    serde_json::from_str(n.extras().as_ref().unwrap().get()).unwrap();
                assert_eq!(extras["shape"], "ellipsoid");
                assert_eq!(extras["radii"][2].as_f64(), Some(v.radii.z));
            }
        }
    }
    let input = root
        .children()
        .find(|n| n.name() == Some("input_mesh"))
        .unwrap();
    let prim = input.mesh().unwrap().primitives().next().unwrap();
    assert!(prim.get(&gltf::Semantic::Colors(0)).is_some());
    assert_eq!(prim.get(&gltf::Semantic::Positions).unwrap().count(), 6);
    assert!(json
        .extensions_used
        .contains(&"KHR_physics_rigid_bodies".to_string()));
    // Our own reader takes it too (the proxies and the input mesh).
    assert!(bvseg_io::load_bytes(&bytes, "x.glb", &bvseg_io::LoadOptions::default()).is_ok());
}

#[test]
fn mjcf_has_one_geom_per_volume_with_exact_sizes() {
    let seg = seg();
    let text = to_mjcf(&seg, "my <model>");
    let doc = roxmltree::Document::parse(&text).unwrap();
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "mujoco");
    assert_eq!(root.attribute("model"), Some("my <model>"));
    let geoms: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("geom"))
        .collect();
    assert_eq!(geoms.len(), seg.parts.len());
    let meshes: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("mesh"))
        .collect();
    assert_eq!(meshes.len(), 1);
    for (g, p) in geoms.iter().zip(&seg.parts) {
        let v = &p.volume;
        let nums = |a: &str| -> Vec<f64> {
            g.attribute(a)
                .unwrap()
                .split(' ')
                .map(|x| x.parse().unwrap())
                .collect()
        };
        let want = match v.shape {
            Shape::Obb => "box",
            Shape::Hull => "mesh",
            s => s.as_str(),
        };
        assert_eq!(g.attribute("type"), Some(want));
        assert!(g.parent().unwrap().has_tag_name("body"));
        if v.shape == Shape::Hull {
            // The mesh asset lists the hull's vertices in the body's frame.
            let name = g.attribute("mesh").unwrap();
            let m = meshes
                .iter()
                .find(|m| m.attribute("name") == Some(name))
                .unwrap();
            let xyz: Vec<f64> = m
                .attribute("vertex")
                .unwrap()
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            let want: Vec<f64> = v.hull_points().iter().flat_map(|p| p.to_array()).collect();
            assert_eq!(xyz, want);
            continue;
        }
        let size = match v.shape {
            Shape::Sphere => vec![v.radius()],
            Shape::Capsule | Shape::Cylinder => vec![v.radius(), v.half_length()],
            _ => v.radii.to_array().to_vec(),
        };
        assert_eq!(nums("size"), size);
        assert_eq!(nums("pos"), v.center.to_array());
        let q = nums("quat");
        let q = DQuat::from_xyzw(q[1], q[2], q[3], q[0]);
        assert!((q * DVec3::X - v.axes.x_axis).length() < 1e-12);
        // MuJoCo's capsules and cylinders run along the geom's Z.
        assert!((q * DVec3::Z - v.axes.z_axis).length() < 1e-12);
    }
}

#[test]
fn obj_proxies_are_one_object_per_part() {
    let seg = seg();
    let text = to_obj(&seg);
    for (i, p) in seg.parts.iter().enumerate() {
        let opts = bvseg_io::LoadOptions {
            object: Some(format!("part_{i}")),
            ..Default::default()
        };
        let l = bvseg_io::load_bytes(text.as_bytes(), "p.obj", &opts).unwrap();
        assert_eq!(l.report.open_edges, 0);
        let (vol, exact) = (l.report.volume, p.volume.volume());
        match p.volume.shape {
            Shape::Obb | Shape::Hull => assert!(close(vol, exact, 1e-9), "{vol} vs {exact}"),
            // The inscribed meshes of the curved kinds are a little smaller than the solids.
            _ => assert!(
                vol < exact && vol > 0.95 * exact,
                "{:?}: {vol} vs {exact}",
                p.volume.shape
            ),
        }
    }
}

#[test]
fn write_output_picks_the_format_and_refuses_others() {
    let dir = bvseg_testkit::scratch("write_output_picks_the_format_and_refuses_others");
    let seg = seg();
    for f in ["a.json", "a.glb", "a.xml", "a.obj"] {
        write_output(dir.join(f), &seg, &ExportOptions::default()).unwrap();
    }
    assert!(fs::read(dir.join("a.glb")).unwrap().starts_with(b"glTF"));
    assert!(fs::read_to_string(dir.join("a.xml"))
        .unwrap()
        .starts_with("<mujoco model=\"a\">"));
    let e = write_output(dir.join("a.ply"), &seg, &ExportOptions::default()).unwrap_err();
    assert!(
        e.to_string().ends_with(
            "unsupported output format '.ply' (supported: .json, .glb, .xml (MJCF), .obj, \
             .usda)"
        ),
        "{e}"
    );
    assert!(!dir.join("a.ply").exists());
    assert_eq!(to_labels(&seg), "0\n1\n");
    let with = bvseg_io::export::to_labels_with_dropped(&seg, &[0, 2, 4]);
    assert_eq!(with, "-1\n0\n-1\n1\n-1\n");
}

const CESIUM_MAN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../assets/characters/CesiumMan.glb"
);

/// World matrices of a document's nodes from their (f32) transforms.
fn worlds(doc: &gltf::Document) -> (Vec<glam::DMat4>, Vec<Option<usize>>) {
    let n = doc.nodes().count();
    let mut parent = vec![None; n];
    for node in doc.nodes() {
        for c in node.children() {
            parent[c.index()] = Some(node.index());
        }
    }
    let local: Vec<glam::DMat4> = doc
        .nodes()
        .map(|n| glam::Mat4::from_cols_array_2d(&n.transform().matrix()).as_dmat4())
        .collect();
    let world = (0..n)
        .map(|mut i| {
            let mut m = local[i];
            while let Some(p) = parent[i] {
                m = local[p] * m;
                i = p;
            }
            m
        })
        .collect();
    (world, parent)
}

/// CesiumMan's GLB with its mesh: the mesh is skinned by the file's skin (JOINTS_0,
/// WEIGHTS_0, inverse bind matrices) to the output's joint nodes, which its walk animates,
/// and every collider hangs under a joint, placed where its volume is at rest.
#[test]
fn a_skinned_character_is_written_skinned_and_animated() {
    let loaded = bvseg_io::load(CESIUM_MAN, &bvseg_io::LoadOptions::default()).unwrap();
    let skinning = loaded.skinning.as_deref().expect("a skinned file");
    let params = bvseg_core::Params {
        samples: 3000,
        ..bvseg_core::Params::default()
    };
    let seg = bvseg_core::segment(&loaded.mesh, &params).unwrap();
    let bytes = bvseg_io::export::to_glb_skinned(&seg, Some(&loaded.mesh), skinning);
    assert_eq!(
        bytes,
        bvseg_io::export::to_glb_skinned(&seg, Some(&loaded.mesh), skinning),
        "deterministic"
    );
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let input = gltf::Gltf::open(CESIUM_MAN).unwrap();

    // One skin of the file's 19 joints, and the walk's channels, each on one of its joints.
    let skins: Vec<_> = g.skins().collect();
    assert_eq!(skins.len(), 1);
    let joints: std::collections::BTreeSet<usize> = skins[0].joints().map(|j| j.index()).collect();
    assert_eq!(joints.len(), 19);
    let ibm: Vec<[[f32; 4]; 4]> = skins[0]
        .reader(|_| Some(blob))
        .read_inverse_bind_matrices()
        .unwrap()
        .collect();
    assert_eq!(ibm.len(), 19);
    let file_channels: usize = input.animations().map(|a| a.channels().count()).sum();
    let channels: Vec<_> = g.animations().flat_map(|a| a.channels()).collect();
    assert_eq!(g.animations().count(), input.animations().count());
    assert_eq!(channels.len(), file_channels);
    assert!(channels
        .iter()
        .all(|c| joints.contains(&c.target().node().index())));

    // At rest the skinned mesh is the loaded mesh, corner by corner.
    let (world, parent) = worlds(&g.document);
    let node = g
        .nodes()
        .find(|n| n.skin().is_some())
        .expect("a skinned mesh node");
    assert_eq!(node.name(), Some("input_mesh"));
    let prim = node.mesh().unwrap().primitives().next().unwrap();
    let r = prim.reader(|_| Some(blob));
    let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
    let js: Vec<[u16; 4]> = r.read_joints(0).unwrap().into_u16().collect();
    let ws: Vec<[f32; 4]> = r.read_weights(0).unwrap().into_f32().collect();
    let skin_joints: Vec<usize> = skins[0].joints().map(|j| j.index()).collect();
    let m = &loaded.mesh;
    assert_eq!(pos.len(), 3 * m.triangles().len());
    for (k, p) in pos.iter().enumerate() {
        let p = DVec3::from_array(p.map(f64::from));
        let at: DVec3 = (0..4)
            .map(|c| {
                let j = js[k][c] as usize;
                let ibm = glam::Mat4::from_cols_array_2d(&ibm[j]).as_dmat4();
                (world[skin_joints[j]] * ibm).transform_point3(p) * f64::from(ws[k][c])
            })
            .sum();
        let want = m.vertices()[m.triangles()[k / 3][k % 3] as usize];
        assert!((at - want).length() < 1e-5, "corner {k}: {at} vs {want}");
    }

    // Every collider hangs under a joint, and sits at rest where its volume is.
    let mut colliders = 0;
    for n in g.nodes() {
        if !n.name().is_some_and(|s| s.ends_with("_collider")) {
            continue;
        }
        colliders += 1;
        let p = parent[n.index()].unwrap();
        assert!(joints.contains(&p), "{:?} hangs under node {p}", n.name());
        let i: usize = n.name().unwrap()["part_".len()..]
            .trim_end_matches("_collider")
            .parse()
            .unwrap();
        let v = &seg.parts[i].volume;
        assert!((world[n.index()].transform_point3(DVec3::ZERO) - v.center).length() < 1e-4);
    }
    assert_eq!(colliders, seg.parts.len());
}

/// Parses an MJCF attribute of numbers.
fn nums(node: roxmltree::Node, attr: &str) -> Vec<f64> {
    node.attribute(attr)
        .unwrap_or("")
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

/// A three-joint skeleton (turned and scaled rest frames) with parts bound to two of its
/// bones: the MJCF is a ragdoll, a body per joint nested like the joints, a free joint at the
/// root and a ball joint where a bone carries volumes, and composing the bodies' frames puts
/// every geom where its volume is in the rest pose.
#[test]
fn mjcf_of_a_character_is_a_ragdoll_of_its_bones() {
    use bvseg_core::{Joint, Skeleton};
    use glam::DMat4;
    let frame = |euler: (f64, f64, f64), scale: f64, at: DVec3| {
        DMat4::from_scale_rotation_translation(
            DVec3::splat(scale),
            DQuat::from_euler(EulerRot::XYZ, euler.0, euler.1, euler.2),
            at,
        )
    };
    let joint = |name: &str, parent, rest| Joint {
        name: name.into(),
        parent,
        rest,
        node: None,
    };
    let mut seg = seg();
    seg.skeleton = Some(Skeleton {
        joints: vec![
            joint(
                "hip",
                None,
                frame((0.3, 0.1, -0.2), 100.0, DVec3::new(0.0, 1.0, 0.0)),
            ),
            joint(
                "knee",
                Some(0),
                frame((-0.4, 0.6, 0.2), 100.0, DVec3::new(0.2, 0.5, 0.1)),
            ),
            joint(
                "foot",
                Some(1),
                frame((0.1, 0.2, 0.3), 100.0, DVec3::new(0.3, 0.0, 0.4)),
            ),
        ],
    });
    let bones = [0, 1, 1, 0, 0, 1];
    for (p, &b) in seg.parts.iter_mut().zip(&bones) {
        p.bone = Some(b);
    }
    let text = to_mjcf(&seg, "walker");
    let doc = roxmltree::Document::parse(&text).unwrap();
    let bodies: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("body"))
        .collect();
    let names: Vec<_> = bodies
        .iter()
        .map(|b| b.attribute("name").unwrap())
        .collect();
    assert_eq!(names, ["hip", "knee", "foot"]);
    // Nested like the joints.
    assert_eq!(bodies[1].parent(), Some(bodies[0]));
    assert_eq!(bodies[2].parent(), Some(bodies[1]));
    let joint_of = |b: &roxmltree::Node| {
        b.children()
            .find(|c| c.has_tag_name("joint") || c.has_tag_name("freejoint"))
            .map(|j| {
                (
                    j.tag_name().name().to_owned(),
                    j.attribute("type").map(str::to_owned),
                )
            })
    };
    assert_eq!(joint_of(&bodies[0]), Some(("freejoint".into(), None)));
    assert_eq!(
        joint_of(&bodies[1]),
        Some(("joint".into(), Some("ball".into())))
    );
    // The foot carries no volume: welded to the knee.
    assert_eq!(joint_of(&bodies[2]), None);

    // Each geom, composed through its bodies' frames, is its volume at rest.
    let local = |n: roxmltree::Node| {
        let p = nums(n, "pos");
        let q = nums(n, "quat");
        let t = if p.is_empty() {
            DVec3::ZERO
        } else {
            DVec3::new(p[0], p[1], p[2])
        };
        let r = if q.is_empty() {
            DQuat::IDENTITY
        } else {
            DQuat::from_xyzw(q[1], q[2], q[3], q[0])
        };
        glam::DAffine3::from_rotation_translation(r, t)
    };
    let mut seen = 0;
    for g in doc.descendants().filter(|n| n.has_tag_name("geom")) {
        let i: usize = g.attribute("name").unwrap()["part_".len()..]
            .parse()
            .unwrap();
        let body = g.parent().unwrap();
        assert_eq!(body.attribute("name"), Some(names[bones[i]]));
        let mut world = local(g);
        let mut at = Some(body);
        while let Some(b) = at.filter(|b| b.has_tag_name("body")) {
            world = local(b) * world;
            at = b.parent();
        }
        let v = &seg.parts[i].volume;
        if v.shape == Shape::Hull {
            let name = g.attribute("mesh").unwrap();
            let mesh = doc
                .descendants()
                .find(|n| n.has_tag_name("mesh") && n.attribute("name") == Some(name))
                .unwrap();
            let pts: Vec<DVec3> = nums(mesh, "vertex")
                .chunks(3)
                .map(|c| world.transform_point3(DVec3::new(c[0], c[1], c[2])))
                .collect();
            for p in v.hull_points() {
                assert!(pts.iter().any(|q| (*q - p).length() < 1e-9), "part {i}");
            }
        } else {
            assert!((world.translation - v.center).length() < 1e-9, "part {i}");
            // The geom's Z is the capsule's or cylinder's axis, else its third axis.
            let z = world.matrix3.z_axis;
            assert!(z.dot(v.axes.z_axis).abs() > 1.0 - 1e-9, "part {i}");
        }
        assert_eq!(g.attribute("conaffinity"), Some("0"));
        seen += 1;
    }
    assert_eq!(seen, seg.parts.len());
}
