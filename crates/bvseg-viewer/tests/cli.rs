//! The native binary's command line (only the paths that exit before a window opens).
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::process::Command;

fn viewer(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_bvseg-viewer"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_mesh_is_a_one_line_error_naming_the_file() {
    let dir = bvseg_testkit::scratch("bad_mesh_is_a_one_line_error_naming_the_file");
    let bad = dir.join("broken.obj");
    std::fs::write(&bad, "v 0 0 0\nf 1 2 3\n").unwrap();
    let bad = bad.to_str().unwrap();
    let (code, _, err) = viewer(&[bad]);
    assert_eq!(code, 2);
    assert!(
        err.starts_with("bvseg-viewer: error: ") && err.contains(bad),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");

    let missing = dir.join("missing.obj");
    let (code, _, err) = viewer(&[missing.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("missing.obj"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn usage_errors_and_help() {
    let (code, _, err) = viewer(&["--frobnicate"]);
    assert_eq!(code, 2);
    assert!(err.contains("--frobnicate"), "{err}");
    let (code, out, _) = viewer(&["--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("usage: bvseg-viewer"), "{out}");
    assert!(
        out.contains("--bv KINDS") && out.contains("NAME-hull"),
        "{out}"
    );
    // Kinds that do not parse stop the viewer before its window opens.
    for args in [&["--bv", "torus"][..], &["--bv=obb,torus"], &["--bv"]] {
        let (code, _, err) = viewer(args);
        assert_eq!(code, 2, "{args:?}");
        assert!(err.starts_with("bvseg-viewer: error: --bv"), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}
