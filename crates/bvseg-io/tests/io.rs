//! File-level behaviour of bvseg-io: loading from paths, atomic writes, JSON files.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;

use bvseg_core::{segment, Params};
use bvseg_io::{
    load, load_bytes, write_atomic, write_json, CliSummary, IoError, LoadOptions, RunSummary,
    MAX_INPUT_BYTES,
};
use bvseg_testkit::{files as entries, scratch, BUNNY};

fn load_all(path: impl AsRef<Path>) -> Result<bvseg_io::LoadedMesh, IoError> {
    load(path, &LoadOptions::default())
}

#[test]
fn loads_the_bundled_bunny_from_disk() {
    let l = load_all(BUNNY).unwrap();
    assert_eq!(l.mesh.triangles().len(), 3674);
    assert_eq!(l.stats.degenerate, 0);
    assert!(l.mesh.signed_volume().abs() > 0.0);
    let bytes = fs::read(BUNNY).unwrap();
    assert_eq!(
        load_bytes(&bytes, "bunny.obj", &LoadOptions::default()).unwrap(),
        l
    );
}

#[test]
fn extension_is_case_insensitive() {
    let dir = scratch("extension_is_case_insensitive");
    let p = dir.join("tri.OBJ");
    fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(load_all(&p).unwrap().mesh.triangles().len(), 1);
}

#[test]
fn load_errors_name_the_file_in_one_line() {
    let dir = scratch("load_errors_name_the_file_in_one_line");
    let missing = dir.join("missing.obj");
    let e = load_all(&missing).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }));
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}: cannot open: ", missing.display())),
        "{msg}"
    );

    let stl = dir.join("part.ply");
    fs::write(&stl, "ply\n").unwrap();
    let msg = load_all(&stl).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!(
            "{}: unsupported mesh format '.ply' (supported: .obj, .gltf, .glb, .stl)",
            stl.display()
        )
    );

    let bare = dir.join("README");
    fs::write(&bare, "hello").unwrap();
    let msg = load_all(&bare).unwrap_err().to_string();
    assert!(
        msg.ends_with(
            "unsupported mesh format (no file extension) (supported: .obj, .gltf, .glb, .stl)"
        ),
        "{msg}"
    );

    let sub = dir.join("folder.obj");
    fs::create_dir(&sub).unwrap();
    let msg = load_all(&sub).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!("{}: is a directory, not a mesh file", sub.display())
    );

    for e in [missing, stl, bare, sub] {
        assert!(!load_all(&e).unwrap_err().to_string().contains('\n'));
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
    let e = load_all(&p).unwrap_err();
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
    let mesh = load_all(BUNNY).unwrap().mesh;
    // Ellipsoids only: a schema-1 file of one kind.
    let params = Params {
        samples: 2000,
        k: Some(2),
        kinds: bvseg_core::Kinds::ELLIPSOID,
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

#[test]
fn run_summary_keeps_each_front_end_s_keys_and_order() {
    let mesh = load_all(BUNNY).unwrap().mesh;
    let fixed = Params {
        samples: 2000,
        k: Some(2),
        ..Params::default()
    };
    let seg = segment(&mesh, &fixed).unwrap();
    let m = seg.metrics;
    let keys = |text: &str| -> Vec<String> {
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        // serde_json's map is sorted here, so the order is read from the text itself.
        let mut found: Vec<(usize, String)> = v
            .as_object()
            .unwrap()
            .keys()
            .map(|k| (text.find(&format!("\"{k}\":")).unwrap(), k.clone()))
            .collect();
        found.sort();
        found.into_iter().map(|(_, k)| k).collect()
    };

    // The command line: keys sorted, the tolerances null with a fixed k.
    let cli = RunSummary {
        cli: Some(CliSummary::new(
            &seg,
            &fixed,
            3674,
            1.5,
            vec!["v.json".into()],
            vec![],
        )),
        ..RunSummary::new("a \"b\"\n.obj", &seg)
    };
    let text = cli.to_json_sorted();
    assert_eq!(
        keys(&text),
        [
            "f",
            "k",
            "kind",
            "mesh",
            "mov",
            "outputs",
            "protrusion",
            "protrusion_rel",
            "samples",
            "seconds",
            "tolerances",
            "tolerances_met",
            "tov",
            "triangles",
            "warnings"
        ]
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["mesh"], "a \"b\"\n.obj");
    assert_eq!(v["k"], 2);
    assert_eq!(v["tov"].as_f64(), Some(m.tov));
    assert!(v["tolerances"].is_null() && v["tolerances_met"].is_null());
    assert!(!text.contains('\n'));

    // In tolerance mode they are there, and met follows the core's rule.
    let tol = Params {
        samples: 2000,
        k: None,
        max_k: 3,
        ..Params::default()
    };
    let seg_t = segment(&mesh, &tol).unwrap();
    let cli = RunSummary {
        cli: Some(CliSummary::new(&seg_t, &tol, 3674, 1.5, vec![], vec![])),
        ..RunSummary::new("bunny.obj", &seg_t)
    };
    let text = cli.to_json_sorted();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let t = &v["tolerances"];
    assert_eq!(t["tov"].as_f64(), Some(tol.tov), "{text}");
    assert!(t["mov"].is_null(), "MOV is not checked by default: {text}");
    let d = seg_t.metrics.diagonal;
    assert_eq!(t["protrusion"].as_f64(), Some(tol.max_protrusion * d));
    assert!(
        text.contains("\"tolerances\":{\"mov\":null,\"protrusion\":"),
        "keys sorted: {text}"
    );
    assert_eq!(v["tolerances_met"].as_bool(), seg_t.tolerances_met(&tol));
}
