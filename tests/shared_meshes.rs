//! Enclosure on real meshes, with every bounding kind: every triangle lies in the volume of
//! its part, and no gap is left inside the solid between parts. Always on the bundled meshes
//! (`assets/meshes`); on the shared test set (`../shared/meshes`, beside the repository, or
//! `$BVSEG_SHARED/meshes`) with `--ignored`, which `.ci/run` passes when that set is there.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use bvseg::internals::Grid;
use bvseg::{segment, Kinds, Params};
use std::path::{Path, PathBuf};

#[test]
fn every_bundled_mesh_is_enclosed_with_every_bounding_kind() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/meshes");
    let n = check_folder(&dir);
    assert_eq!(n, 3, "the three bundled meshes");
}

#[test]
#[ignore = "needs the shared meshes beside the repository; .ci/run runs it when they are there"]
fn every_shared_mesh_is_enclosed_with_every_bounding_kind() {
    let dir = std::env::var_os("BVSEG_SHARED").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"),
        PathBuf::from,
    );
    let n = check_folder(&dir.join("meshes"));
    assert!(n >= 21, "only {n} shared meshes");
}

/// Checks every `.obj` of `dir`; returns how many. Fails if there is none.
fn check_folder(dir: &Path) -> usize {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "obj"))
        .collect();
    paths.sort();
    assert!(!paths.is_empty(), "no meshes in {}", dir.display());
    let count = paths.len();
    for path in paths {
        let mesh = bvseg::io::load(&path, &bvseg::io::LoadOptions::default())
            .expect("shared mesh loads")
            .mesh;
        for kinds in [
            Kinds::ELLIPSOID,
            Kinds::OBB,
            Kinds::MIXED,
            Kinds::PRIMITIVES,
            Kinds::HULL,
        ] {
            let params = Params {
                samples: 4_000,
                k: Some(8),
                kinds,
                ..Params::default()
            };
            let seg = segment(&mesh, &params).expect("segments");
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            for (t, &p) in seg.triangle_parts.iter().enumerate() {
                let v = &seg.parts[p as usize].volume;
                for c in mesh.corners(t) {
                    assert!(v.contains(c), "{name:?} {kinds}: triangle {t} escapes");
                }
            }
            // Interior points of a finer, differently aligned lattice are all covered. Hulls,
            // the tightest kind, leave thin cracks inside the solid where three or more parts
            // meet (the shared faces' centres join neighbouring hulls, their corners do not):
            // 0.99983 on teddy_1 at k = 8. The surface is enclosed all the same (above).
            let bound = if kinds == Kinds::HULL { 0.9995 } else { 0.9999 };
            let fine = Grid::from_mesh(&mesh, 30_000).expect("fine grid");
            let missed = fine
                .points
                .iter()
                .filter(|&&p| !seg.parts.iter().any(|part| part.volume.contains(p)))
                .count();
            let cov = 1.0 - missed as f64 / fine.len() as f64;
            assert!(cov >= bound, "{name:?} {kinds}: interior coverage {cov}");
        }
    }
    count
}
