//! File-level behaviour of bvseg-io: loading from paths, atomic writes, JSON files.
use std::fs;
use std::path::{Path, PathBuf};

use bvseg_core::{segment, Params};
use bvseg_io::{
    load_mesh, load_mesh_detailed, load_obj, write_atomic, write_json, IoError, MAX_INPUT_BYTES,
};

/// A fresh, empty directory for one test.
fn scratch(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("bvseg-io-tests")
        .join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");

#[test]
fn loads_the_bundled_bunny_from_disk() {
    let l = load_mesh_detailed(BUNNY).unwrap();
    assert_eq!(l.mesh.triangles().len(), 3674);
    assert_eq!(l.stats.degenerate, 0);
    assert!(l.mesh.signed_volume().abs() > 0.0);
    assert_eq!(load_obj(BUNNY).unwrap(), l.mesh);
}

#[test]
fn extension_is_case_insensitive() {
    let dir = scratch("extension_is_case_insensitive");
    let p = dir.join("tri.OBJ");
    fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(load_mesh(&p).unwrap().triangles().len(), 1);
}

#[test]
fn load_errors_name_the_file_in_one_line() {
    let dir = scratch("load_errors_name_the_file_in_one_line");
    let missing = dir.join("missing.obj");
    let e = load_mesh(&missing).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }));
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}: cannot open: ", missing.display())),
        "{msg}"
    );

    let stl = dir.join("part.ply");
    fs::write(&stl, "ply\n").unwrap();
    let msg = load_mesh(&stl).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!(
            "{}: unsupported mesh format '.ply' (supported: .obj, .gltf, .glb, .stl)",
            stl.display()
        )
    );

    let bare = dir.join("README");
    fs::write(&bare, "hello").unwrap();
    let msg = load_mesh(&bare).unwrap_err().to_string();
    assert!(
        msg.ends_with(
            "unsupported mesh format (no file extension) (supported: .obj, .gltf, .glb, .stl)"
        ),
        "{msg}"
    );

    let sub = dir.join("folder.obj");
    fs::create_dir(&sub).unwrap();
    let msg = load_mesh(&sub).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!("{}: is a directory, not a mesh file", sub.display())
    );

    for e in [missing, stl, bare, sub] {
        assert!(!load_mesh(&e).unwrap_err().to_string().contains('\n'));
    }
}

#[test]
fn oversized_file_is_refused_before_reading() {
    let dir = scratch("oversized_file_is_refused_before_reading");
    let p = dir.join("huge.obj");
    // Sparse: costs no disk space where the file system supports holes.
    let f = fs::File::create(&p).unwrap();
    f.set_len(MAX_INPUT_BYTES + 1).unwrap();
    drop(f);
    let e = load_mesh(&p).unwrap_err();
    fs::remove_file(&p).unwrap();
    assert!(matches!(e, IoError::TooLarge { .. }), "{e}");
    assert!(e.to_string().contains("larger than"));
}

#[test]
fn write_atomic_creates_and_replaces_without_leftovers() {
    let dir = scratch("write_atomic_creates_and_replaces_without_leftovers");
    let p = dir.join("out.json");
    write_atomic(&p, b"first").unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"first");
    write_atomic(&p, b"second, longer").unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"second, longer");
    assert_eq!(entries(&dir), ["out.json"]);
}

#[test]
fn write_atomic_failure_leaves_nothing_behind() {
    let dir = scratch("write_atomic_failure_leaves_nothing_behind");
    // The directory does not exist: not even the temporary file can be made.
    let e = write_atomic(dir.join("nope").join("out.json"), b"x").unwrap_err();
    assert!(e.to_string().contains("out.json"), "{e}");
    // The target is a directory: the rename fails after the data was written.
    let target = dir.join("taken.json");
    fs::create_dir(&target).unwrap();
    fs::write(target.join("keep"), b"k").unwrap();
    let e = write_atomic(&target, b"x").unwrap_err();
    assert!(
        e.to_string().starts_with(&target.display().to_string()),
        "{e}"
    );
    assert_eq!(entries(&dir), ["taken.json"]);
    assert_eq!(entries(&target), ["keep"]);
}

#[test]
fn json_file_round_trip() {
    let dir = scratch("json_file_round_trip");
    let mesh = load_mesh(BUNNY).unwrap();
    let params = Params {
        samples: 2000,
        k: Some(2),
        ..Params::default()
    };
    let seg = segment(&mesh, &params).unwrap();
    let p = dir.join("v.json");
    write_json(&p, &seg).unwrap();
    let text = fs::read_to_string(&p).unwrap();
    assert_eq!(text, bvseg_io::to_json_string(&seg));
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(doc["schema"], "bvseg.volumes/1");
    assert_eq!(doc["kind"], "ellipsoid");
    let vols = doc["volumes"].as_array().unwrap();
    assert_eq!(vols.len(), seg.parts.len());
    assert_eq!(doc["metrics"]["k"], seg.metrics.k);
    let sum: f64 = vols.iter().map(|v| v["fraction"].as_f64().unwrap()).sum();
    assert!((sum - 1.0).abs() < 1e-9);
    assert_eq!(entries(&dir), ["v.json"]);
}
