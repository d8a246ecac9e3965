//! Replays every input the fuzzers (`fuzz/`) ever crashed or hung on, saved under
//! `tests/data/fuzz-regressions/<target>/`, through the same checks as the fuzz targets.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#[path = "support/fuzz_input.rs"]
mod fuzz_input;

use std::path::Path;

/// Runs `check` on every file of `fuzz/seeds/<target>/` and
/// `tests/data/fuzz-regressions/<target>/`, in name order; returns how many there were.
/// Fails when there are none: a replay that finds nothing checks nothing.
fn replay(target: &str, check: impl Fn(&[u8])) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for dir in [
        root.join("fuzz/seeds").join(target),
        root.join("tests/data/fuzz-regressions").join(target),
    ] {
        if let Ok(entries) = std::fs::read_dir(&dir) {
            paths.extend(entries.filter_map(|e| e.ok().map(|e| e.path())));
        }
    }
    paths.sort();
    assert!(
        !paths.is_empty(),
        "no seeds or regression inputs for {target}"
    );
    for p in &paths {
        eprintln!("replaying {}", p.display());
        check(&std::fs::read(p).expect("readable regression input"));
    }
    paths.len()
}

#[test]
fn obj_regressions() {
    replay("obj", fuzz_input::check_obj);
}

#[test]
fn volumes_json_regressions() {
    replay("volumes_json", fuzz_input::check_volumes_json);
}

#[test]
fn gltf_regressions() {
    replay("gltf", fuzz_input::check_gltf);
}

#[test]
fn stl_regressions() {
    replay("stl", fuzz_input::check_stl);
}

/// The glTF and STL fuzz seeds are valid meshes, so the targets' checks on a loaded mesh run.
#[test]
fn gltf_and_stl_seeds_load() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    for (dir, files) in [
        ("gltf", &["tet.glb", "tet.gltf"][..]),
        ("stl", &["tet_binary.stl", "tet_ascii.stl"][..]),
    ] {
        for f in files {
            let bytes = std::fs::read(seeds.join(dir).join(f)).expect("seed present");
            let loaded = bvseg_io::load_bytes(&bytes, f, &bvseg_io::LoadOptions::default())
                .unwrap_or_else(|e| panic!("seed {f}: {e}"));
            assert_eq!(loaded.mesh.triangles().len(), 4, "{f}");
        }
    }
}

#[test]
fn pipeline_regressions() {
    let decoded = std::sync::atomic::AtomicUsize::new(0);
    let n = replay("pipeline", |data| {
        let (mesh, params) =
            fuzz_input::pipeline_case(data).expect("every saved pipeline input decodes");
        fuzz_input::check_pipeline(&mesh, &params);
        decoded.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    });
    // Two seeds and at least the two saved slow units.
    assert!(n >= 4, "only {n} pipeline inputs");
    assert_eq!(decoded.into_inner(), n);
}
