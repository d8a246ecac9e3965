//! Replays every input the fuzzers (`fuzz/`) ever crashed or hung on, saved under
//! `tests/data/fuzz-regressions/<target>/`, through the same checks as the fuzz targets.
#[path = "support/fuzz_input.rs"]
mod fuzz_input;

use std::path::Path;

fn replay(target: &str, check: impl Fn(&[u8])) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz-regressions")
        .join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return 0;
    };
    let mut paths: Vec<_> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
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
            let loaded = bvseg_io::load_mesh_from_bytes(&bytes, f)
                .unwrap_or_else(|e| panic!("seed {f}: {e}"));
            assert_eq!(loaded.mesh.triangles().len(), 4, "{f}");
        }
    }
}

#[test]
fn pipeline_regressions() {
    let n = replay("pipeline", |data| {
        if let Some((mesh, params)) = fuzz_input::pipeline_case(data) {
            fuzz_input::check_pipeline(&mesh, &params);
        }
    });
    assert!(n > 0, "the pipeline regressions are missing");
}
