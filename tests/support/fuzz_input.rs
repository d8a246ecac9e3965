//! How the fuzz targets turn bytes into inputs and what they check, shared by
//! `fuzz/fuzz_targets/*.rs` and the regression replay (`tests/fuzz_regressions.rs`), so that
//! a saved crashing input is replayed exactly as the fuzzer ran it.
#![allow(dead_code)]
#[path = "verify_input.rs"]
mod verify_input;

use bvseg_core::{segment, shapes, Kinds, Mesh, Params, Shape};
use bvseg_verify::{VerifyOptions, Volume, Volumes};
use glam::{DMat3, DVec3};

/// Up to 16 vertices of 3 x i8 and up to 32 triangles of 3 index bytes.
fn raw_mesh(data: &[u8]) -> Option<Mesh> {
    let nv = (*data.first()? as usize % 16) + 1;
    let vb = data.get(1..1 + 3 * nv)?;
    let v: Vec<DVec3> = vb
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0] as i8 as f64, c[1] as i8 as f64, c[2] as i8 as f64))
        .collect();
    let t: Vec<[u32; 3]> = data[1 + 3 * nv..]
        .chunks_exact(3)
        .take(32)
        .map(|c| [c[0], c[1], c[2]].map(|i| (i as usize % nv) as u32))
        .collect();
    Mesh::new(v, t).ok()
}

/// A union of up to 4 boxes / ellipsoids / capsules, 8 bytes each.
fn solid_union(data: &[u8]) -> Option<Mesh> {
    let f = |b: u8| b as f64 / 32.0;
    let parts: Vec<Mesh> = data
        .chunks_exact(8)
        .take(4)
        .map(|c| {
            let at = DVec3::new(f(c[1]), f(c[2]), f(c[3]));
            let size = DVec3::new(f(c[4]), f(c[5]), f(c[6])) + 0.05;
            let rot = DMat3::from_euler(glam::EulerRot::XYZ, f(c[7]), 0.5 * f(c[7]), 0.0);
            match c[0] % 3 {
                0 => shapes::cuboid(at, size, rot),
                1 => shapes::ellipsoid(at, size, rot, 8 + (c[7] % 8) as usize),
                _ => shapes::capsule(at, at + size, 0.2 + 0.1 * f(c[4]), 8),
            }
        })
        .collect();
    if parts.is_empty() {
        return None;
    }
    Some(shapes::union(&parts))
}

/// The pipeline target's input: 4 header bytes (samples, k, bounding kind, mode), then raw
/// geometry (mode even) or a union of solids (mode odd).
pub fn pipeline_case(data: &[u8]) -> Option<(Mesh, Params)> {
    if data.len() < 4 {
        return None;
    }
    let k = match data[1] % 8 {
        0 => None,
        k => Some(k as usize),
    };
    let bounding = [Kinds::ELLIPSOID, Kinds::OBB, Kinds::MIXED][data[2] as usize % 3];
    let mesh = if data[3] & 1 == 0 {
        raw_mesh(&data[4..])
    } else {
        solid_union(&data[4..])
    };
    let params = Params {
        samples: 100 + data[0] as usize,
        k,
        kinds: bounding,
        max_k: 6,
        seed: data[3] as u64,
        ..Params::default()
    };
    Some((mesh?, params))
}

/// Segments (errors are fine: bad input) and checks that every triangle is enclosed, by the
/// segmentation's own assignment and by the independent verifier (on the written file,
/// which it must accept).
pub fn check_pipeline(mesh: &Mesh, params: &Params) {
    let Ok(seg) = segment(mesh, params) else {
        return;
    };
    let vols: Vec<_> = seg.parts.iter().map(|p| p.volume.clone()).collect();
    for (t, &p) in seg.triangle_parts.iter().enumerate() {
        for c in mesh.corners(t) {
            assert!(
                vols[p as usize].contains(c),
                "triangle {t} escapes part {p}"
            );
        }
    }
    let opts = VerifyOptions {
        points: 1000,
        ..VerifyOptions::default()
    };
    if let Ok(r) = verify_input::verify_segmentation(mesh, &seg, &opts) {
        assert!(r.all_enclosed(), "verify: {r:?}");
    }
}

/// OBJ loading: a mesh or a one-line error.
pub fn check_obj(data: &[u8]) {
    match bvseg_io::load_bytes(data, "fuzz.obj", &bvseg_io::LoadOptions::default()) {
        Ok(loaded) => {
            let mesh = loaded.mesh;
            let _ = mesh.bbox();
            let _ = mesh.signed_volume();
        }
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
}

/// The volumes reader, the verifier's own reader (which must accept what the first accepts,
/// and read the same volumes), and the verifier on whatever they accept.
pub fn check_volumes_json(data: &[u8]) {
    let theirs = std::str::from_utf8(data).map(Volumes::from_json);
    if let Ok(Err(e)) = &theirs {
        assert!(!e.to_string().contains('\n'), "multi-line error: {e}");
    }
    match bvseg_io::parse_volumes(data, "fuzz.json") {
        Ok(file) => {
            let volumes = match theirs {
                Ok(Ok(v)) => v,
                other => panic!("bvseg-io accepts, bvseg-verify does not: {other:?}"),
            };
            assert_eq!(volumes.fractions.as_ref(), Some(&file.fractions));
            assert_eq!(volumes.volumes.len(), file.volumes.len());
            for (v, w) in volumes.volumes.iter().zip(&file.volumes) {
                let frame = match *v {
                    Volume::Ellipsoid {
                        center,
                        axes,
                        radii,
                    } => Some((Shape::Ellipsoid, center, axes, radii)),
                    Volume::Obb {
                        center,
                        axes,
                        half_extents,
                    } => Some((Shape::Obb, center, axes, half_extents)),
                    _ => None,
                };
                assert_eq!(v.shape_name(), w.shape.as_str());
                match (frame, v) {
                    (Some((shape, center, axes, radii)), _) => {
                        // The file's rows are the core's matrix columns.
                        let rows =
                            [w.axes.x_axis, w.axes.y_axis, w.axes.z_axis].map(|a| a.to_array());
                        assert_eq!(shape, w.shape);
                        assert_eq!(center, w.center.to_array());
                        assert_eq!(axes, rows);
                        assert_eq!(radii, w.radii.to_array());
                    }
                    (None, Volume::Sphere { center, radius }) => {
                        assert_eq!(*center, w.center.to_array());
                        assert_eq!(*radius, w.radius());
                    }
                    (
                        None,
                        Volume::Capsule { center, radius, .. }
                        | Volume::Cylinder { center, radius, .. },
                    ) => {
                        assert_eq!(*center, w.center.to_array());
                        assert_eq!(*radius, w.radius());
                    }
                    // Both readers take the hull of the points; their own constructions.
                    _ => {}
                }
            }
            let mesh = shapes::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), DMat3::IDENTITY);
            let opts = VerifyOptions {
                points: 2000,
                ..VerifyOptions::default()
            };
            let _ = verify_input::verify(&mesh, &volumes, &opts);
        }
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
}

/// A loaded mesh's cheap invariants: finite coordinates, indices in range, no repeated
/// corner, and the dropped-triangle list increasing.
fn check_loaded(loaded: &bvseg_io::LoadedMesh) {
    let mesh = &loaded.mesh;
    let nv = mesh.vertices().len();
    assert!(
        nv > 0 && !mesh.triangles().is_empty(),
        "empty mesh accepted"
    );
    assert!(
        mesh.vertices().iter().all(|v| v.is_finite()),
        "non-finite vertex"
    );
    for t in mesh.triangles() {
        assert!(
            t.iter().all(|&i| (i as usize) < nv),
            "index out of range: {t:?}"
        );
    }
    assert!(loaded.dropped.windows(2).all(|w| w[0] < w[1]));
    let _ = mesh.bbox();
    let _ = mesh.signed_volume();
}

/// Mesh loading from bytes under `name` (its extension picks the reader): a mesh passing
/// [`check_loaded`] or a one-line error.
fn check_mesh_bytes(data: &[u8], name: &str) {
    match bvseg_io::load_bytes(data, name, &bvseg_io::LoadOptions::default()) {
        Ok(loaded) => check_loaded(&loaded),
        Err(e) => assert!(!e.to_string().contains('\n'), "multi-line error: {e}"),
    }
}

/// glTF loading: the same bytes read as a GLB container and as a JSON glTF document.
pub fn check_gltf(data: &[u8]) {
    check_mesh_bytes(data, "fuzz.glb");
    check_mesh_bytes(data, "fuzz.gltf");
}

/// STL loading (binary or ASCII, as the reader decides).
pub fn check_stl(data: &[u8]) {
    check_mesh_bytes(data, "fuzz.stl");
}
