//! The mesh readers: the same solid written as OBJ, STL (binary and ASCII) and glTF (every
//! buffer kind, indexed or not, under a node transform) loads as the same mesh.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;

use bvseg_io::{load, load_bytes, LoadOptions};
use bvseg_testkit::scratch;
use glam::{DMat4, DQuat, DVec3};

/// A box [0,2]x[0,1]x[0,1] as 8 vertices and 12 outward triangles.
fn cube() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (v, t) = bvseg_testkit::geometry::cuboid([0.0; 3], [2.0, 1.0, 1.0]);
    (v.iter().map(|p| p.map(|x| x as f32)).collect(), t)
}

fn stl_binary(v: &[[f32; 3]], t: &[[u32; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b[..5].copy_from_slice(b"solid"); // as some exporters write
    b.extend((t.len() as u32).to_le_bytes());
    for tri in t {
        b.extend([0u8; 12]);
        for &i in tri {
            for c in v[i as usize] {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn stl_ascii(v: &[[f32; 3]], t: &[[u32; 3]]) -> String {
    let mut s = String::from("solid cube\n");
    for tri in t {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for &i in tri {
            let [x, y, z] = v[i as usize];
            s += &format!("      vertex {x:e} {y:e} {z:e}\n");
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid cube\n"
}

/// A glTF document with one mesh (named "box") under a node with `matrix`, plus a second,
/// unrelated mesh ("other") on another node; `indexed` chooses indices or a flat list.
fn gltf_doc(uri: Option<&str>, bin_len: usize, matrix: Option<[f64; 16]>, indexed: bool) -> String {
    let (v, t) = cube();
    let uri = uri.map(|u| format!(r#""uri":"{u}","#)).unwrap_or_default();
    let matrix = matrix
        .map(|m| format!(r#","matrix":{:?}"#, m.map(|x| x as f32)))
        .unwrap_or_default();
    let npos = if indexed { v.len() } else { 3 * t.len() };
    let pos_len = 12 * npos;
    let (indices, views, accessors) = if indexed {
        (
            r#","indices":1"#,
            format!(
                r#"{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}"#,
                4 * 3 * t.len()
            ),
            format!(
                r#"{{"bufferView":0,"componentType":5126,"count":{npos},"type":"VEC3"}},{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}"#,
                3 * t.len()
            ),
        )
    } else {
        (
            "",
            format!(r#"{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}}"#),
            format!(r#"{{"bufferView":0,"componentType":5126,"count":{npos},"type":"VEC3"}}"#),
        )
    };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"name":"outer","children":[2]}},{{"mesh":1,"translation":[100,0,0]}},{{"mesh":0{matrix}}}],
"meshes":[{{"name":"box","primitives":[{{"attributes":{{"POSITION":0}}{indices}}}]}},
{{"name":"other","primitives":[{{"attributes":{{"POSITION":0}}{indices}}}]}}],
"buffers":[{{{uri}"byteLength":{bin_len}}}],"bufferViews":[{views}],"accessors":[{accessors}]}}"#
    )
}

fn gltf_bin(indexed: bool) -> Vec<u8> {
    let (v, t) = cube();
    let mut b = Vec::new();
    if indexed {
        for p in &v {
            p.iter().for_each(|c| b.extend(c.to_le_bytes()));
        }
        for i in t.iter().flatten() {
            b.extend(i.to_le_bytes());
        }
    } else {
        for i in t.iter().flatten() {
            v[*i as usize]
                .iter()
                .for_each(|c| b.extend(c.to_le_bytes()));
        }
    }
    b
}

/// Wraps a JSON document and a binary chunk in a GLB container.
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F534Au32.to_le_bytes());
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(0x004E4942u32.to_le_bytes());
    out.extend(bin);
    out
}

fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The (sorted) triangle corner sets of a mesh, for order-independent comparison.
fn corner_sets(m: &bvseg_core::Mesh, xf: &DMat4) -> Vec<[[i64; 3]; 3]> {
    let q = |p: DVec3| {
        let p = xf.transform_point3(p);
        [p.x, p.y, p.z].map(|c| (c * 1e4).round() as i64)
    };
    let mut v: Vec<_> = m
        .triangles()
        .iter()
        .map(|t| {
            let mut c = t.map(|i| q(m.vertices()[i as usize]));
            // Rotate so the smallest corner is first: keeps the winding, drops the start.
            let k = (0..3).min_by_key(|&k| c[k]).unwrap();
            c.rotate_left(k);
            c
        })
        .collect();
    v.sort();
    v
}

#[test]
fn stl_binary_and_ascii_equal_the_obj() {
    let dir = scratch("stl");
    let (v, t) = cube();
    let mut obj = String::new();
    v.iter()
        .for_each(|p| obj += &format!("v {} {} {}\n", p[0], p[1], p[2]));
    t.iter()
        .for_each(|f| obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    fs::write(dir.join("c.obj"), obj).unwrap();
    fs::write(dir.join("c.stl"), stl_binary(&v, &t)).unwrap();
    fs::write(dir.join("a.STL"), stl_ascii(&v, &t)).unwrap();
    let o = load(dir.join("c.obj"), &LoadOptions::default()).unwrap();
    let b = load(dir.join("c.stl"), &LoadOptions::default()).unwrap();
    let a = load(dir.join("a.STL"), &LoadOptions::default()).unwrap();
    assert_eq!(b.stats.vertices_read, 36);
    assert_eq!(b.mesh.vertices().len(), 8, "welded");
    assert_eq!(o.mesh, b.mesh);
    assert_eq!(o.mesh, a.mesh);
    assert_eq!(a.report.open_edges, 0);
    assert_eq!(a.report.components, 1);
    assert!((a.report.volume - 2.0).abs() < 1e-12);
    assert!(a.report.warnings().is_empty());
}

#[test]
fn gltf_buffers_of_every_kind_apply_the_node_transform() {
    let dir = scratch("gltf");
    let rot = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let xf = DMat4::from_scale_rotation_translation(
        DVec3::new(1.5, 0.5, 2.0),
        rot,
        DVec3::new(3.0, -1.0, 0.25),
    );
    // Through f32, as the file stores it.
    let xf = DMat4::from_cols_array(&xf.to_cols_array().map(|x| x as f32 as f64));
    let (v, t) = cube();
    let reference = bvseg_core::Mesh::from_f32(
        &v.iter()
            .map(|p| glam::Vec3::from_array(*p))
            .collect::<Vec<_>>(),
        t.clone(),
    )
    .unwrap();
    let expect = corner_sets(&reference, &xf);
    let box_only = LoadOptions {
        mesh: Some("box".into()),
        ..Default::default()
    };
    for indexed in [true, false] {
        let bin = gltf_bin(indexed);
        let m = Some(xf.to_cols_array());
        // GLB.
        let g = glb(&gltf_doc(None, bin.len(), m, indexed), &bin);
        fs::write(dir.join("c.glb"), &g).unwrap();
        // Embedded data URI.
        let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
        let e = gltf_doc(Some(&uri), bin.len(), m, indexed);
        fs::write(dir.join("e.gltf"), &e).unwrap();
        // External file, with a space in its name.
        fs::write(dir.join("c b.bin"), &bin).unwrap();
        let x = gltf_doc(Some("c%20b.bin"), bin.len(), m, indexed);
        fs::write(dir.join("x.gltf"), &x).unwrap();
        for f in ["c.glb", "e.gltf", "x.gltf"] {
            let l = load(dir.join(f), &box_only).unwrap();
            assert_eq!(
                corner_sets(&l.mesh, &DMat4::IDENTITY),
                expect,
                "{f} indexed={indexed}"
            );
            // Without --mesh both meshes are there: the second is shifted, not transformed.
            let all = load(dir.join(f), &LoadOptions::default()).unwrap();
            assert_eq!(all.report.components, 2);
            assert_eq!(all.mesh.triangles().len(), 24);
        }
        // From bytes: GLB and data URIs work, external files do not.
        assert!(load_bytes(&g, "c.glb", &LoadOptions::default()).is_ok());
        assert!(load_bytes(e.as_bytes(), "e.gltf", &LoadOptions::default()).is_ok());
        let err = load_bytes(x.as_bytes(), "x.gltf", &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("x.gltf: buffer 0 is the external file 'c%20b.bin'"),
            "{err}"
        );
    }
    let err = load(
        dir.join("c.glb"),
        &LoadOptions {
            mesh: Some("nope".into()),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.ends_with("no mesh named 'nope' in the scene (the file has: 'box', 'other')"),
        "{err}"
    );
}

#[test]
fn mirroring_transform_keeps_the_solid_outward() {
    let bin = gltf_bin(true);
    let m = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)).to_cols_array();
    let g = glb(&gltf_doc(None, bin.len(), Some(m), true), &bin);
    let l = load_bytes(&g, "m.glb", &LoadOptions::default()).unwrap();
    assert!(
        !l.report.flipped,
        "the reader itself accounts for the mirror"
    );
    assert!((l.report.volume - 4.0).abs() < 1e-9, "{}", l.report.volume);
}

#[test]
fn obj_object_selection_and_inward_orientation() {
    let (v, t) = cube();
    let mut s = String::new();
    v.iter()
        .for_each(|p| s += &format!("v {} {} {}\n", p[0], p[1], p[2]));
    s += "o first\n";
    // Inward: every triangle reversed.
    t.iter()
        .for_each(|f| s += &format!("f {} {} {}\n", f[0] + 1, f[2] + 1, f[1] + 1));
    s += "o second\nf 1 2 3\n";
    let opts = |o: &str| LoadOptions {
        object: Some(o.into()),
        ..Default::default()
    };
    let l = load_bytes(s.as_bytes(), "t.obj", &opts("first")).unwrap();
    assert_eq!(l.mesh.triangles().len(), 12);
    assert!(l.report.flipped && l.report.volume > 0.0);
    assert!(l.report.warnings().iter().any(|w| w.contains("inward")));
    let e = load_bytes(s.as_bytes(), "t.obj", &opts("third")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.obj: no object or group named 'third' (the file has: 'first', 'second')"
    );
    let e = load_bytes(s.as_bytes(), "t.stl", &opts("first")).unwrap_err();
    assert_eq!(e.to_string(), "t.stl: --object applies only to OBJ files");
}

#[test]
fn report_counts_defects() {
    let (v, mut t) = cube();
    t.pop(); // a hole: 3 open edges
    t.push(t[0]); // a duplicate face: its edges are now used 3 times or so
    let mut s = String::new();
    v.iter()
        .for_each(|p| s += &format!("v {} {} {}\n", p[0], p[1], p[2]));
    t.iter()
        .for_each(|f| s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    let r = load_bytes(s.as_bytes(), "t.obj", &LoadOptions::default())
        .unwrap()
        .report;
    assert_eq!(r.open_edges, 3);
    assert_eq!(r.duplicate_faces, 1);
    assert_eq!(r.non_manifold_edges, 3);
    assert_eq!(r.warnings().len(), 3);
    assert_eq!(
        (r.bbox_min, r.bbox_max),
        (DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0))
    );
}
