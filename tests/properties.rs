//! Property-based tests: random unions of boxes, ellipsoids and capsules under random affine
//! maps, random seeds and thread counts, against the invariants bvseg promises.
//!
//! Case counts are small (each case runs whole segmentations); proptest shrinks any failure
//! to a small reproducible case.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#[path = "support/verify_input.rs"]
mod verify_input;

use bvseg::internals::{
    cvt, lloyd, move_boundary_samples, mvee, sym_eigen, Grid, Partition, Solid, NONE,
};
use bvseg::{segment, shapes, BoundingVolume, Kinds, Mesh, Params, Segmentation, Shape};
use bvseg_verify::VerifyOptions;
use glam::{DMat3, DVec3};
use proptest::prelude::*;

/// One primitive solid: kind, centre, size, rotation angles.
#[derive(Debug, Clone)]
struct Prim {
    kind: u8,
    at: [f64; 3],
    size: [f64; 3],
    angles: [f64; 3],
}

fn prim() -> impl Strategy<Value = Prim> {
    (
        0u8..3,
        prop::array::uniform3(-0.6f64..0.6),
        prop::array::uniform3(0.25f64..0.9),
        prop::array::uniform3(-3.2f64..3.2),
    )
        .prop_map(|(kind, at, size, angles)| Prim {
            kind,
            at,
            size,
            angles,
        })
}

/// A connected-or-not union of 1 to 3 primitives (they overlap often, not always).
fn solid() -> impl Strategy<Value = Vec<Prim>> {
    prop::collection::vec(prim(), 1..=3)
}

fn build(prims: &[Prim]) -> Mesh {
    let meshes: Vec<Mesh> = prims
        .iter()
        .map(|p| {
            let at = DVec3::from_array(p.at);
            let size = DVec3::from_array(p.size);
            let rot = DMat3::from_euler(glam::EulerRot::XYZ, p.angles[0], p.angles[1], p.angles[2]);
            match p.kind {
                0 => shapes::cuboid(at, size, rot),
                1 => shapes::ellipsoid(at, size, rot, 20),
                _ => shapes::capsule(
                    at,
                    at + rot * DVec3::new(size.x, 0.0, 0.0),
                    0.5 * size.y,
                    16,
                ),
            }
        })
        .collect();
    shapes::union(&meshes)
}

/// A random affine map: rotation, scales in [0.3, 3], a mild shear and a translation.
#[derive(Debug, Clone)]
struct Affine {
    angles: [f64; 3],
    scale: [f64; 3],
    shear: f64,
    shift: [f64; 3],
}

fn affine() -> impl Strategy<Value = Affine> {
    (
        prop::array::uniform3(-3.2f64..3.2),
        prop::array::uniform3(0.3f64..3.0),
        -0.5f64..0.5,
        prop::array::uniform3(-100.0f64..100.0),
    )
        .prop_map(|(angles, scale, shear, shift)| Affine {
            angles,
            scale,
            shear,
            shift,
        })
}

fn apply(a: &Affine, m: &Mesh) -> Mesh {
    let rot = DMat3::from_euler(glam::EulerRot::XYZ, a.angles[0], a.angles[1], a.angles[2]);
    let shear = DMat3::from_cols(DVec3::X, DVec3::new(a.shear, 1.0, 0.0), DVec3::Z);
    let lin = rot * shear * DMat3::from_diagonal(DVec3::from_array(a.scale));
    let t = DVec3::from_array(a.shift);
    let v = m.vertices().iter().map(|&p| lin * p + t).collect();
    // A map with negative determinant turns the mesh inside out; keep it outward.
    let flip = lin.determinant() < 0.0;
    let tris = m
        .triangles()
        .iter()
        .map(|&[x, y, z]| if flip { [x, z, y] } else { [x, y, z] })
        .collect();
    Mesh::new(v, tris).expect("an affine image of a valid mesh is valid")
}

/// Own connectivity check (not the library's): BFS over face neighbours within a part.
fn parts_connected_per_piece(grid: &Grid, labels: &[u32]) -> Result<(), String> {
    let n = labels.len();
    // Pieces of the solid.
    let mut piece = vec![u32::MAX; n];
    let mut npieces = 0;
    for s in 0..n {
        if piece[s] == u32::MAX {
            flood(grid, s, &mut piece, npieces, |_| true);
            npieces += 1;
        }
    }
    // Regions of each part within each piece: at most one per (part, piece).
    let mut region = vec![u32::MAX; n];
    let mut seen = std::collections::HashSet::new();
    let mut r = 0;
    for s in 0..n {
        if region[s] == u32::MAX {
            let l = labels[s];
            flood(grid, s, &mut region, r, |t| labels[t] == l);
            r += 1;
            if !seen.insert((l, piece[s])) {
                return Err(format!("part {l} has two regions in piece {}", piece[s]));
            }
        }
    }
    Ok(())
}

fn flood(grid: &Grid, s: usize, mark: &mut [u32], id: u32, ok: impl Fn(usize) -> bool) {
    let mut stack = vec![s];
    mark[s] = id;
    while let Some(a) = stack.pop() {
        for &b in grid.neighbors(a) {
            if b != NONE && mark[b as usize] == u32::MAX && ok(b as usize) {
                mark[b as usize] = id;
                stack.push(b as usize);
            }
        }
    }
}

fn kind_of(i: u8) -> Kinds {
    [
        Kinds::ELLIPSOID,
        Kinds::OBB,
        Kinds::MIXED,
        Kinds::SPHERE,
        Kinds::CAPSULE,
        Kinds::CYLINDER,
        Kinds::HULL,
        Kinds::PRIMITIVES,
    ][i as usize % 8]
}

fn check_segmentation(
    mesh: &Mesh,
    params: &Params,
    seg: &Segmentation,
) -> Result<(), TestCaseError> {
    let k = seg.parts.len();
    prop_assert!(k >= 1);
    // Every sample in exactly one part: one label each, in range, and the counts agree.
    prop_assert_eq!(seg.sample_parts.len(), seg.metrics.samples);
    let mut count = vec![0usize; k];
    for &l in &seg.sample_parts {
        prop_assert!((l as usize) < k);
        count[l as usize] += 1;
    }
    for (i, p) in seg.parts.iter().enumerate() {
        prop_assert_eq!(p.samples, count[i], "part {} sample count", i);
        prop_assert!(p.samples > 0);
    }
    // The same lattice the segmentation used (sampling is deterministic).
    let grid = Grid::from_mesh(mesh, params.samples).expect("grid");
    prop_assert_eq!(grid.len(), seg.sample_parts.len());
    if let Err(e) = parts_connected_per_piece(&grid, &seg.sample_parts) {
        return Err(TestCaseError::fail(e));
    }
    // Every volume holds its part's samples and triangles.
    for (s, &l) in seg.sample_parts.iter().enumerate() {
        prop_assert!(
            seg.parts[l as usize].volume.contains(grid.points[s]),
            "sample {} outside part {}",
            s,
            l
        );
    }
    for (t, &l) in seg.triangle_parts.iter().enumerate() {
        for c in mesh.corners(t) {
            prop_assert!(
                seg.parts[l as usize].volume.contains(c),
                "triangle {} outside part {}",
                t,
                l
            );
        }
    }
    // The union encloses the mesh, by the independent verifier, on the written file.
    let opts = VerifyOptions {
        points: 20_000,
        ..VerifyOptions::default()
    };
    let r = verify_input::verify_segmentation(mesh, seg, &opts).expect("verify runs");
    prop_assert!(
        r.all_enclosed(),
        "verify: {} escaping, max {}",
        r.unenclosed,
        r.max_escape_rel
    );
    prop_assert!(seg.metrics.f >= 0.97, "F = {}", seg.metrics.f);
    Ok(())
}

/// `n` cases from a fixed seed, so that CI runs the same cases every time; for longer bug
/// hunts set `PROPTEST_CASES` and `PROPTEST_RNG_SEED`.
fn config(n: u32) -> ProptestConfig {
    let mut c = ProptestConfig::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = n;
    }
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        c.rng_seed = proptest::test_runner::RngSeed::Fixed(0x5EED);
    }
    // Failures print their minimal input; no regression files beside the sources.
    c.failure_persistence = None;
    c
}

proptest! {
    #![proptest_config(config(32))]

    /// Samples partitioned, parts connected, volumes hold their parts, union encloses the mesh.
    #[test]
    fn segmentation_invariants(
        prims in solid(),
        map in affine(),
        k in prop::option::of(1usize..7),
        kind in 0u8..3,
        seed in any::<u64>(),
    ) {
        let mesh = apply(&map, &build(&prims));
        let params = Params {
            samples: 1500,
            k,
            seed,
            kinds: kind_of(kind),
            max_k: 8,
            ..Params::default()
        };
        let seg = segment(&mesh, &params).expect("segments");
        check_segmentation(&mesh, &params, &seg)?;
    }

    /// Byte-identical output, and identical verification, whatever the thread count.
    #[test]
    fn identical_across_thread_counts(
        prims in solid(),
        k in prop::option::of(2usize..6),
        kind in 0u8..3,
        seed in any::<u64>(),
    ) {
        let mesh = build(&prims);
        let params = Params {
            samples: 1200,
            k,
            seed,
            kinds: kind_of(kind),
            max_k: 6,
            ..Params::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let seg = pool.install(|| segment(&mesh, &params).expect("segments"));
            // The verifier runs on its own threads.
            let opts = VerifyOptions { points: 5000, threads: Some(threads), ..VerifyOptions::default() };
            let report = verify_input::verify_segmentation(&mesh, &seg, &opts).expect("verify runs");
            (seg, report)
        };
        let (one, one_report) = run(1);
        let json = bvseg::io::to_json_string(&one);
        for threads in [2, 4] {
            let (other, report) = run(threads);
            prop_assert_eq!(&report, &one_report);
            prop_assert_eq!(&other.sample_parts, &one.sample_parts);
            prop_assert_eq!(&other.triangle_parts, &one.triangle_parts);
            prop_assert!(bvseg::io::to_json_string(&other) == json, "JSON differs with {} threads", threads);
        }
    }

    /// F never increases during the fixed-k optimisation and stays >= 1 up to sampling error.
    #[test]
    fn f_never_increases(prims in solid(), k in 1usize..8, seed in any::<u64>()) {
        let mesh = build(&prims);
        let grid = Grid::from_mesh(&mesh, 2000).expect("grid");
        let solid = Solid::new(grid);
        let mut part = cvt(&solid, k, seed);
        let mut f = part.f();
        prop_assert!(f >= 0.97, "F = {}", f);
        for _ in 0..30 {
            let kept = lloyd(&solid, &mut part, None, 1);
            let g = part.f();
            prop_assert!(g <= f, "a sweep raised F from {} to {}", f, g);
            f = g;
            if kept == 0 {
                break;
            }
        }
        move_boundary_samples(&solid, &mut part, None);
        let g = part.f();
        prop_assert!(g <= f, "the boundary moves raised F from {} to {}", f, g);
        prop_assert!(g >= 0.97, "F = {}", g);
    }

    /// e (and so F) is affine invariant: the same solid under a random affine map, sampled
    /// afresh, has the same e up to sampling error.
    #[test]
    fn e_is_affine_invariant(prims in solid(), map in affine()) {
        let e_of = |m: &Mesh| {
            let solid = Solid::new(Grid::from_mesh(m, 20_000).expect("grid"));
            let n = solid.len();
            Partition::from_labels(&solid, vec![0; n], 1).e(0)
        };
        let mesh = build(&prims);
        let a = e_of(&mesh);
        let b = e_of(&apply(&map, &mesh));
        prop_assert!((a - b).abs() <= 0.03 * a, "e = {} before, {} after the map", a, b);
    }

    /// The minimum-volume ellipsoid is never larger than the scaled Legendre ellipsoid of the
    /// same points (up to the MVEE's own tolerance, 1e-4).
    #[test]
    fn mvee_never_larger_than_scaled_legendre(prims in solid(), map in affine(), k in 1usize..5, seed in any::<u64>()) {
        let mesh = apply(&map, &build(&prims));
        let grid = Grid::from_mesh(&mesh, 3000).expect("grid");
        let solid = Solid::new(grid);
        let part = cvt(&solid, k, seed);
        let members = part.members();
        for (i, _) in part.parts.iter().enumerate() {
            let pts: Vec<DVec3> = members[i].iter().map(|&s| solid.grid.points[s as usize]).collect();
            let leg = scaled_legendre(&pts, solid.grid.h);
            let e = mvee(&pts, 1e-4, 0.5 * solid.grid.h);
            for &p in &pts {
                prop_assert!(e.contains(p) && leg.contains(p));
            }
            prop_assert!(
                e.volume() <= leg.volume() * (1.0 + 1e-4),
                "part {}: MVEE {} > Legendre {}", i, e.volume(), leg.volume()
            );
        }
    }
}

/// The paper's refinement volume: the Legendre ellipsoid of `pts` (each standing for a cell
/// of side `h`), scaled uniformly until it holds them.
fn scaled_legendre(pts: &[DVec3], h: f64) -> BoundingVolume {
    let n = pts.len() as f64;
    let c = pts.iter().copied().sum::<DVec3>() / n;
    let mut cov = glam::DMat3::from_diagonal(DVec3::splat(h * h / 12.0));
    for &p in pts {
        let d = p - c;
        cov += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z) / n;
    }
    let (vals, axes) = sym_eigen(cov);
    BoundingVolume::frame(
        Shape::Ellipsoid,
        c,
        axes,
        DVec3::new(vals.x.sqrt(), vals.y.sqrt(), vals.z.sqrt()),
    )
    .scaled_to_contain(pts.iter().copied())
}

/// The case proptest found: two parts of one piece whose volumes' boxes overlapped, but which
/// did not touch, were merged into one part of two separate regions.
#[test]
fn merge_keeps_parts_connected_regression() {
    let prims = vec![
        Prim {
            kind: 0,
            at: [
                0.0070597779823092024,
                -0.3922565500553068,
                -0.40897385365012534,
            ],
            size: [0.25, 0.34124447332654173, 0.7848654919781596],
            angles: [-2.00526087567311, 0.0, 2.4614326369792523],
        },
        Prim {
            kind: 0,
            at: [0.3958690498345309, 0.0, 0.1621185211237387],
            size: [0.25, 0.4664921615023037, 0.2564904686716467],
            angles: [-2.064933832453733, 0.0, 0.0],
        },
    ];
    let map = Affine {
        angles: [0.19827001143741754, 0.0, 0.0],
        scale: [1.1080278580316145, 1.4488061430013064, 2.2155372099991797],
        shear: -0.33176297078092054,
        shift: [77.70305834854972, 29.19120246752928, -53.97523471500941],
    };
    let mesh = apply(&map, &build(&prims));
    let params = Params {
        samples: 1500,
        seed: 1764072409045963465,
        kinds: Kinds::OBB,
        max_k: 8,
        ..Params::default()
    };
    let seg = segment(&mesh, &params).expect("segments");
    assert!(seg.history.iter().any(|s| s.kind == bvseg::StepKind::Merge));
    check_segmentation(&mesh, &params, &seg).unwrap();
}
