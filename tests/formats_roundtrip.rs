//! The same solid as OBJ, as STL and as GLB under a non-trivial node transform gives the same
//! volumes, up to that transform.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;

use bvseg::shapes::{capsule, ellipsoid, union};
use bvseg::{segment, Kinds, Mesh, Params, Segmentation};
use glam::{DMat3, DMat4, DQuat, DVec3};

/// A dumbbell whose vertices are multiples of 2^-10, so that f32 (STL, glTF) and decimal
/// text (OBJ) hold them exactly.
fn dumbbell() -> Mesh {
    let m = union(&[
        ellipsoid(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(1.2, 1.0, 0.8),
            DMat3::IDENTITY,
            32,
        ),
        ellipsoid(
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(1.0, 0.7, 1.1),
            DMat3::IDENTITY,
            32,
        ),
        capsule(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            0.3,
            16,
        ),
    ]);
    let q = |x: f64| (x * 1024.0).round() / 1024.0;
    let v = m
        .vertices()
        .iter()
        .map(|p| DVec3::new(q(p.x), q(p.y), q(p.z)))
        .collect();
    Mesh::new(v, m.triangles().to_vec()).unwrap()
}

fn write_obj(m: &Mesh) -> String {
    let mut s = String::new();
    for p in m.vertices() {
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in m.triangles() {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

fn write_stl(m: &Mesh) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend((m.triangles().len() as u32).to_le_bytes());
    for t in 0..m.triangles().len() {
        b.extend([0u8; 12]);
        for c in m.corners(t) {
            for x in c.to_array() {
                b.extend((x as f32).to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

/// A GLB with the mesh under a child node with `matrix`, under a translated parent.
fn write_glb(m: &Mesh, matrix: &DMat4, parent_translation: DVec3) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    for p in m.vertices() {
        for x in p.to_array() {
            bin.extend((x as f32).to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for i in m.triangles().iter().flatten() {
        bin.extend(i.to_le_bytes());
    }
    let (lo, hi) = m.bbox();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"children":[1],"translation":{:?}}},{{"mesh":0,"matrix":{:?}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":{:?},"max":{:?}}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        parent_translation.to_array(),
        matrix.to_cols_array(),
        bin.len(),
        bin.len() - pos_len,
        m.vertices().len(),
        lo.as_vec3().to_array(),
        hi.as_vec3().to_array(),
        3 * m.triangles().len()
    );
    let mut j = json.into_bytes();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn params(kind: Kinds) -> Params {
    Params {
        samples: 6000,
        k: Some(2),
        kinds: kind,
        ..Params::default()
    }
}

/// Volumes of `a` mapped by the rigid-plus-uniform-scale `xf` match those of `b` (in some
/// order) to within `tol` of the solid's size.
fn assert_same_volumes(a: &Segmentation, xf: &DMat4, scale: f64, b: &Segmentation, tol: f64) {
    assert_eq!(a.parts.len(), b.parts.len());
    let rot = DMat3::from_mat4(*xf) / scale;
    for pa in &a.parts {
        let va = &pa.volume;
        let c = xf.transform_point3(va.center);
        let pb = b
            .parts
            .iter()
            .min_by(|x, y| {
                let dx = (x.volume.center - c).length();
                let dy = (y.volume.center - c).length();
                dx.total_cmp(&dy)
            })
            .unwrap();
        let vb = &pb.volume;
        assert_eq!(va.shape, vb.shape);
        assert!(
            (vb.center - c).length() < tol * scale,
            "{c} vs {}",
            vb.center
        );
        // Compare the shapes as the images of unit vectors: radii along matched axes.
        for j in 0..3 {
            let axis = rot * va.axes.col(j);
            // The extent of b's volume along that direction (support function).
            let support = (DMat3::from_cols(vb.axes.x_axis, vb.axes.y_axis, vb.axes.z_axis)
                .transpose()
                * axis
                * vb.radii)
                .length();
            let want = va.radii[j] * scale;
            if va.shape == bvseg::Shape::Ellipsoid {
                assert!(
                    (support - want).abs() < tol * want.max(1.0),
                    "{support} vs {want}"
                );
            }
        }
        assert!((vb.volume() - va.volume() * scale.powi(3)).abs() < 3.0 * tol * vb.volume());
    }
    assert!(
        (a.metrics.tov - b.metrics.tov).abs() < 0.05,
        "{} vs {}",
        a.metrics.tov,
        b.metrics.tov
    );
}

#[test]
fn obj_stl_and_transformed_glb_give_the_same_volumes() {
    let dir = bvseg_testkit::scratch("obj_stl_and_transformed_glb_give_the_same_volumes");
    let mesh = dumbbell();
    fs::write(dir.join("d.obj"), write_obj(&mesh)).unwrap();
    fs::write(dir.join("d.stl"), write_stl(&mesh)).unwrap();
    // 90 degrees about z, uniform scale 2 (both exact in binary), then two translations.
    let scale = 2.0;
    let child = DMat4::from_scale_rotation_translation(
        DVec3::splat(scale),
        DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
        DVec3::new(0.5, -1.0, 0.25),
    );
    // Round the rotation's cos(90) ~ 6e-17 to 0 so that the f32 matrix is exact.
    let child =
        DMat4::from_cols_array(
            &child
                .to_cols_array()
                .map(|x| if x.abs() < 1e-9 { 0.0 } else { x }),
        );
    let parent = DVec3::new(3.0, 4.0, -2.0);
    fs::write(dir.join("d.glb"), write_glb(&mesh, &child, parent)).unwrap();
    let xf = DMat4::from_translation(parent) * child;

    let load = |f: &str| {
        bvseg::io::load(dir.join(f), &bvseg::io::LoadOptions::default())
            .unwrap()
            .mesh
    };
    let (obj, stl, glb) = (load("d.obj"), load("d.stl"), load("d.glb"));
    // The readers agree exactly: STL equals OBJ, GLB equals the transformed OBJ.
    assert_eq!(obj, stl);
    // (The OBJ reader numbers vertices in order of first use, the glTF one keeps the
    // file's order, so triangles are compared by their corners.)
    let corners = |m: &Mesh, xf: &DMat4| {
        let mut v: Vec<[[u64; 3]; 3]> = (0..m.triangles().len())
            .map(|t| {
                m.corners(t)
                    .map(|c| xf.transform_point3(c).to_array().map(f64::to_bits))
            })
            .collect();
        v.sort();
        v
    };
    assert!(
        corners(&glb, &DMat4::IDENTITY) == corners(&obj, &xf),
        "GLB is not the transformed OBJ"
    );

    for kind in [Kinds::ELLIPSOID, Kinds::OBB] {
        let p = params(kind);
        let (so, ss, sg) = (
            segment(&obj, &p).unwrap(),
            segment(&stl, &p).unwrap(),
            segment(&glb, &p).unwrap(),
        );
        assert_eq!(so, ss, "OBJ and STL: identical meshes, identical results");
        // The lattice is not tied to the frame, so agreement is up to sampling (here, a
        // quarter turn about z and a power-of-two scale, it is in fact near exact).
        assert_same_volumes(&so, &xf, scale, &sg, 0.01);
    }
}
