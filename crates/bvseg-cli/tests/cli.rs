//! End-to-end runs of the `bvseg` binary.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;
use std::process::Output;

use bvseg_testkit::{files, scratch, stderr, BUNNY};

const BIN: &str = env!("CARGO_BIN_EXE_bvseg");
/// Small enough to keep each run well under a second in debug builds.
const FAST: [&str; 2] = ["--samples", "2000"];

fn bvseg(dir: &Path, args: &[&str]) -> Output {
    bvseg_testkit::run(BIN, dir, args)
}

fn segment(dir: &Path, args: &[&str]) -> Output {
    let mut v = vec!["segment"];
    v.extend_from_slice(&FAST);
    v.extend_from_slice(args);
    bvseg(dir, &v)
}

/// Exit code 2, exactly one stderr line `bvseg: error: ...` containing `needle`.
fn assert_fails(o: &Output, needle: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert_eq!(err.lines().count(), 1, "expected one line, got: {err}");
    assert!(err.starts_with("bvseg: error: "), "{err}");
    assert!(err.contains(needle), "{needle:?} not in {err:?}");
    assert!(
        o.stdout.is_empty(),
        "stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
}

fn parse(path: &Path) -> serde_json::Value {
    serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn bundled_mesh_k2_writes_the_schema() {
    let dir = scratch("bundled_mesh_k2_writes_the_schema");
    let o = segment(&dir, &["--k", "2", "--bv", "ellipsoid", "-o", "out.json"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("no mesh given; using the bundled assets/meshes/bunny.obj"),
        "{err}"
    );
    let out = String::from_utf8(o.stdout).unwrap();
    for key in [
        "mesh",
        "triangles  3674",
        "samples",
        "k ",
        "F ",
        "TOV",
        "MOV",
        "time",
        "output     out.json",
    ] {
        assert!(out.contains(key), "{key:?} not in summary:\n{out}");
    }

    let doc = parse(&dir.join("out.json"));
    assert_eq!(doc["schema"], "bvseg.volumes/1");
    assert_eq!(doc["kind"], "ellipsoid");
    assert!(doc["generator"].as_str().unwrap().starts_with("bvseg "));
    let vols = doc["volumes"].as_array().unwrap();
    assert!(!vols.is_empty());
    assert_eq!(doc["metrics"]["k"].as_u64().unwrap() as usize, vols.len());
    for key in ["tov", "mov", "samples", "f"] {
        assert!(doc["metrics"][key].is_number(), "metrics.{key}");
    }
    let sum: f64 = vols.iter().map(|v| v["fraction"].as_f64().unwrap()).sum();
    assert!((sum - 1.0).abs() < 1e-3, "fractions sum to {sum}");
    for v in vols {
        assert_eq!(v["shape"], "ellipsoid");
        assert_eq!(v["axes"].as_array().unwrap().len(), 3);
        assert!(v["radii"]
            .as_array()
            .unwrap()
            .iter()
            .all(|r| r.as_f64().unwrap() > 0.0));
    }
    assert!(doc.get("triangle_parts").is_none());
    assert_eq!(files(&dir), ["out.json"]);
}

#[test]
fn explicit_mesh_and_kinds() {
    let dir = scratch("explicit_mesh_and_kinds");
    let mesh = BUNNY;
    for kind in ["obb", "mixed"] {
        let out = format!("{kind}.json");
        let o = segment(
            &dir,
            &[mesh, "--k", "2", "--bv", kind, "-o", &out, "--quiet"],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(o.stderr.is_empty(), "--quiet printed: {}", stderr(&o));
        assert_eq!(parse(&dir.join(&out))["kind"], kind);
    }
}

#[test]
fn same_run_twice_is_byte_identical() {
    let dir = scratch("same_run_twice_is_byte_identical");
    for out in ["a.json", "b.json"] {
        let o = segment(&dir, &["--k", "2", "-o", out, "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(
        fs::read(dir.join("a.json")).unwrap(),
        fs::read(dir.join("b.json")).unwrap()
    );
}

#[test]
fn thread_count_does_not_change_the_file() {
    let dir = scratch("thread_count_does_not_change_the_file");
    for t in ["1", "2"] {
        let out = format!("t{t}.json");
        let o = segment(&dir, &["--k", "2", "--threads", t, "-o", &out, "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(
        fs::read(dir.join("t1.json")).unwrap(),
        fs::read(dir.join("t2.json")).unwrap()
    );
}

#[test]
fn tolerance_mode_runs() {
    let dir = scratch("tolerance_mode_runs");
    let o = segment(
        &dir,
        &[
            "--tov", "0.5", "--mov", "0.8", "--max-k", "4", "-o", "v.json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(parse(&dir.join("v.json"))["metrics"]["k"].as_u64().unwrap() <= 4);
}

/// The README's first command, as a new user runs it: the defaults on the bundled bunny end
/// with every tolerance met, and nothing on stderr but the note about the bundled mesh.
#[test]
fn the_first_run_ends_met_without_a_warning() {
    let dir = scratch("the_first_run_ends_met_without_a_warning");
    let o = bvseg(&dir, &["segment", "--json", "-o", "v.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(!err.contains("warning"), "{err}");
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["tolerances_met"], true, "{summary}");
    let t = &summary["tolerances"];
    assert!(summary["tov"].as_f64().unwrap() < t["tov"].as_f64().unwrap());
    assert!(summary["protrusion"].as_f64().unwrap() < t["protrusion"].as_f64().unwrap());
    assert!(t["mov"].is_null());
    // --strict agrees: exit 0.
    let o = bvseg(&dir, &["segment", "--strict", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// A tolerance the run cannot meet is named in the warning with what would help; a
/// tolerance nobody asked for (MOV, by default) is not mentioned.
#[test]
fn an_unmet_tolerance_is_named_with_a_hint() {
    let dir = scratch("an_unmet_tolerance_is_named_with_a_hint");
    let o = segment(&dir, &["--max-k", "2", "--max-protrusion", "0.001"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let warning = |err: &str| {
        err.lines()
            .find(|l| l.starts_with("bvseg: warning: tolerances not met at k = "))
            .map(str::to_owned)
            .unwrap_or_else(|| panic!("no warning in {err}"))
    };
    let w = warning(&err);
    assert!(w.contains("protrusion") && w.contains("--max-k"), "{w}");
    assert!(!w.contains("MOV"), "{w}");
    let o = segment(
        &dir,
        &["--max-k", "2", "--max-protrusion", "0.001", "--strict"],
    );
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    // Asked for, MOV is judged too.
    let o = segment(&dir, &["--max-k", "2", "--mov", "0.01"]);
    let w = warning(&stderr(&o));
    assert!(w.contains("MOV ") && w.contains(" vs 0.01"), "{w}");
}

#[test]
fn missing_mesh_fails_cleanly() {
    let dir = scratch("missing_mesh_fails_cleanly");
    let o = segment(&dir, &["missing.obj", "-o", "out.json"]);
    assert_fails(&o, "missing.obj: cannot open");
    assert!(files(&dir).is_empty());
}

#[test]
fn garbage_mesh_fails_cleanly() {
    let dir = scratch("garbage_mesh_fails_cleanly");
    fs::write(dir.join("garbage.obj"), "this is\nnot a mesh\n").unwrap();
    let o = segment(&dir, &["garbage.obj", "-o", "out.json"]);
    assert_fails(&o, "garbage.obj: no triangles");

    let bytes: Vec<u8> = (0..5000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 11) as u8)
        .collect();
    fs::write(dir.join("binary.obj"), bytes).unwrap();
    let o = segment(&dir, &["binary.obj", "-o", "out.json"]);
    assert_fails(&o, "binary.obj: ");

    fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n").unwrap();
    let o = segment(&dir, &["bad.obj", "-o", "out.json"]);
    assert_fails(&o, "bad.obj: line 3: bad vertex");

    fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = segment(&dir, &["flat.obj", "-o", "out.json"]);
    assert_fails(&o, "flat.obj: the mesh encloses no volume");
    assert_eq!(
        files(&dir),
        ["bad.obj", "binary.obj", "flat.obj", "garbage.obj"]
    );
}

#[test]
fn unsupported_formats_fail_cleanly() {
    let dir = scratch("unsupported_formats_fail_cleanly");
    fs::write(dir.join("part.ply"), "ply\n").unwrap();
    let o = segment(&dir, &["part.ply", "-o", "out.json"]);
    assert_fails(&o, "part.ply: unsupported mesh format '.ply'");

    let o = segment(&dir, &["--k", "2", "-o", "out.ply"]);
    assert_fails(&o, "out.ply: unsupported output format '.ply'");

    let o = segment(&dir, &["--k", "2", "-o", "nodir/out.json"]);
    assert_fails(&o, "does not exist");
    assert_eq!(files(&dir), ["part.ply"]);
}

#[test]
fn bad_parameters_fail_cleanly() {
    let dir = scratch("bad_parameters_fail_cleanly");
    let o = segment(&dir, &["--k", "0", "-o", "out.json"]);
    assert_fails(&o, "k must be at least 1");
    let o = segment(&dir, &["--tov", "-1", "-o", "out.json"]);
    assert_eq!(o.status.code(), Some(2));
    let o = segment(&dir, &["--tov", "nan", "-o", "out.json"]);
    assert_fails(&o, "tolerances must be finite");
    let o = bvseg(&dir, &["segment", "--samples", "10", "-o", "out.json"]);
    assert_fails(&o, "samples must be between");
    assert!(files(&dir).is_empty());
}

#[test]
fn other_kinds_write_schema_2_with_their_fields() {
    let dir = scratch("other_kinds_write_schema_2_with_their_fields");
    let o = segment(&dir, &["--k", "4", "--bv", "capsule", "-o", "caps.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc = parse(&dir.join("caps.json"));
    assert_eq!(doc["schema"], "bvseg.volumes/2");
    assert_eq!(doc["kind"], "capsule");
    assert_eq!(doc["kinds"], "capsule");
    for v in doc["volumes"].as_array().unwrap() {
        assert_eq!(v["shape"], "capsule");
        for key in ["center", "axis", "half_length", "radius", "fraction"] {
            assert!(v.get(key).is_some(), "{key} missing: {v}");
        }
        assert!(v.get("axes").is_none() && v.get("radii").is_none());
    }
    // An engine's set: no ellipsoid in a parry file; hulls on request, within the limit.
    let o = segment(
        &dir,
        &[
            "--k",
            "6",
            "--target",
            "parry-hull",
            "--max-hull-vertices",
            "12",
            "-o",
            "p.json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let doc = parse(&dir.join("p.json"));
    for v in doc["volumes"].as_array().unwrap() {
        assert_ne!(v["shape"], "ellipsoid");
        if v["shape"] == "hull" {
            let n = v["points"].as_array().unwrap().len();
            assert!((4..=12).contains(&n), "{n} hull points");
        }
    }
    // The independent check reads the file and finds every triangle enclosed.
    let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");
    let o = bvseg(&dir, &["verify", bunny, "p.json", "--points", "20000"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    assert!(out.contains("triangles enclosed"), "{out}");
}

#[test]
fn usage_errors_exit_2() {
    let dir = scratch("usage_errors_exit_2");
    for args in [
        &["segment", "--k", "2", "--tov", "0.2"][..],
        &["segment", "--k", "2", "--mov", "0.2"],
        &["segment", "--bv", "torus"],
        &["segment", "--target", "unity"],
        &["segment", "--target", "parry", "--bv", "obb"],
        &["segment", "--threads", "0"],
        &["segment", "--k", "two"],
        &["segment", "--frobnicate"],
        &["frobnicate"],
        &[],
    ] {
        let o = bvseg(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    assert!(files(&dir).is_empty());
    let o = bvseg(&dir, &["--version"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("bvseg "));
}

#[test]
fn timeout_exits_2_and_writes_nothing() {
    let dir = scratch("timeout_exits_2_and_writes_nothing");
    // The default sample count: far more than a millisecond of work.
    let o = bvseg(
        &dir,
        &[
            "segment",
            "--timeout",
            "0.001",
            "-o",
            "v.json",
            "-o",
            "v.glb",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("--timeout"), "{err}");
    assert!(files(&dir).is_empty(), "{:?}", files(&dir));
    // A generous timeout changes nothing.
    let o = segment(&dir, &["--timeout", "600", "-o", "v.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for bad in ["0", "-1", "nan", "soon"] {
        let o = segment(&dir, &["--timeout", bad]);
        assert_eq!(o.status.code(), Some(2), "--timeout {bad}");
    }
}

#[test]
fn margin_grows_the_volumes() {
    let dir = scratch("margin_grows_the_volumes");
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&fs::read_to_string(dir.join(name)).unwrap()).unwrap()
    };
    let o = segment(&dir, &["--k", "4", "--bv", "obb", "-o", "a.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = segment(
        &dir,
        &[
            "--k", "4", "--bv", "obb", "--margin", "0.01", "-o", "b.json",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (a, b) = (read("a.json"), read("b.json"));
    for (va, vb) in a["volumes"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["volumes"].as_array().unwrap())
    {
        for j in 0..3 {
            let (ra, rb) = (
                va["radii"][j].as_f64().unwrap(),
                vb["radii"][j].as_f64().unwrap(),
            );
            assert!((rb - ra - 0.01).abs() < 1e-12, "{ra} -> {rb}");
        }
    }
    let o = segment(&dir, &["--margin", "-1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
