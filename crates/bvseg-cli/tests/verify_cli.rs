//! End-to-end runs of `bvseg verify`: exit 0 when enclosed, 1 when not, 2 on bad input.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_bvseg");

const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\nf 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n";

/// A fresh directory for one test, holding `cube.obj`.
fn scratch(test: &str) -> PathBuf {
    let dir = bvseg_testkit::scratch(test);
    fs::write(dir.join("cube.obj"), CUBE).unwrap();
    dir
}

fn bvseg(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A volumes file with one box of half-extent `half` around the cube's centre.
fn one_box(half: f64) -> String {
    format!(
        r#"{{"schema":"bvseg.volumes/1","kind":"obb","metrics":{{"k":1,"tov":0,"mov":0,"samples":1}},
"volumes":[{{"shape":"obb","center":[0.5,0.5,0.5],"axes":[[1,0,0],[0,1,0],[0,0,1]],"radii":[{half},{half},{half}],"fraction":1}}]}}"#
    )
}

#[test]
fn a_segmentation_verifies_and_a_small_box_does_not() {
    let dir = scratch("verdicts");
    let o = bvseg(
        &dir,
        &[
            "segment",
            "-q",
            "--samples",
            "2000",
            "--k",
            "3",
            "--bv",
            "obb",
            "cube.obj",
            "-o",
            "v.json",
        ],
    );
    assert_eq!(o.status.code(), Some(0));
    let o = bvseg(&dir, &["verify", "cube.obj", "v.json", "--points", "20000"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("all 12 triangles enclosed"), "{out}");

    let o = bvseg(
        &dir,
        &[
            "verify", "cube.obj", "v.json", "--points", "20000", "--json",
        ],
    );
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["enclosed"], true);
    assert_eq!(v["k"], 3);
    // Three boxes fit a cube exactly.
    assert!(v["tov"].as_f64().unwrap() < 0.01, "{v}");

    fs::write(dir.join("small.json"), one_box(0.4)).unwrap();
    let o = bvseg(
        &dir,
        &[
            "verify",
            "cube.obj",
            "small.json",
            "--points",
            "20000",
            "--json",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["enclosed"], false);
    assert_eq!(v["triangles_unenclosed"], 12);
    // The farthest corner is 0.1 sqrt(3) from the box; the diagonal is sqrt(3).
    assert!((v["max_escape_rel"].as_f64().unwrap() - 0.1).abs() < 1e-9);

    fs::write(dir.join("exact.json"), one_box(0.5)).unwrap();
    let o = bvseg(
        &dir,
        &["verify", "cube.obj", "exact.json", "--points", "20000"],
    );
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let dir = scratch("bad");
    fs::write(dir.join("good.json"), one_box(0.6)).unwrap();
    fs::write(
        dir.join("bad.json"),
        one_box(0.6).replace("\"obb\",\"center\"", "\"ball\",\"center\""),
    )
    .unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["verify", "cube.obj", "bad.json"],
            "bad.json: volume 0: shape",
        ),
        (
            &["verify", "cube.obj", "missing.json"],
            "missing.json: cannot open",
        ),
        (&["verify", "missing.obj", "good.json"], "missing.obj"),
        (
            &["verify", "cube.obj", "good.json", "--points", "10"],
            "points",
        ),
    ];
    for (args, needle) in cases {
        let o = bvseg(&dir, args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with("bvseg: error: ") && err.contains(needle),
            "{needle}: {err}"
        );
    }
}
