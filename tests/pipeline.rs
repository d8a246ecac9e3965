//! End-to-end properties of the segmentation on analytic shapes and the bundled meshes.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use bvseg::internals::Grid;
use bvseg::internals::{is_connected, solid_components};
use bvseg::shapes::{capsule, ellipsoid, union};
use bvseg::{segment, Kinds, Mesh, Params, Sampling, Segmentation, SkeletonMode};
use glam::{DMat3, DVec3};

fn bundled(name: &str) -> Mesh {
    bvseg::io::load(
        bvseg_testkit::bundled_mesh(name),
        &bvseg::io::LoadOptions::default(),
    )
    .expect("bundled mesh loads")
    .mesh
}

/// Every triangle lies in the volume of its part (its three corners are inside, and the
/// volume is convex), and every sample lies in the volume of its part.
/// `segment` in a pool of `threads` threads.
fn on_threads(threads: usize, mesh: &Mesh, params: &Params) -> Segmentation {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| segment(mesh, params).unwrap())
}

fn assert_encloses(mesh: &Mesh, seg: &Segmentation, grid: &Grid) {
    for (t, &p) in seg.triangle_parts.iter().enumerate() {
        let v = &seg.parts[p as usize].volume;
        for c in mesh.corners(t) {
            assert!(v.contains(c), "triangle {t} corner {c} escapes volume {p}");
        }
    }
    for (s, &p) in seg.sample_parts.iter().enumerate() {
        assert!(seg.parts[p as usize].volume.contains(grid.points[s]));
    }
}

/// Fraction of the points of a finer, shifted lattice inside the solid that some volume
/// holds: the check that no gap is left between neighbouring parts.
fn interior_coverage(mesh: &Mesh, seg: &Segmentation, samples: usize) -> f64 {
    let fine = Grid::from_mesh(mesh, samples).expect("fine grid");
    let covered = fine
        .points
        .iter()
        .filter(|&&p| seg.parts.iter().any(|part| part.volume.contains(p)))
        .count();
    covered as f64 / fine.len() as f64
}

#[test]
fn two_disjoint_ellipsoids_give_two_tight_parts() {
    let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, 0.5, 0.1);
    let mesh = union(&[
        ellipsoid(
            DVec3::new(-3.0, 0.0, 0.0),
            DVec3::new(1.5, 0.8, 0.5),
            rot,
            48,
        ),
        ellipsoid(
            DVec3::new(3.0, 1.0, 0.0),
            DVec3::new(0.7, 1.2, 0.9),
            DMat3::IDENTITY,
            48,
        ),
    ]);
    let seg = segment(&mesh, &Params::default()).unwrap();
    assert_eq!(seg.metrics.k, 2);
    assert!(seg.metrics.f < 1.03, "F = {}", seg.metrics.f);
    assert!(seg.metrics.f >= 0.99, "F = {}", seg.metrics.f);
    assert!(seg.metrics.tov < 0.15, "TOV = {}", seg.metrics.tov);
}

#[test]
fn dumbbell_splits_at_its_neck() {
    let mesh = union(&[
        ellipsoid(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::splat(1.0),
            DMat3::IDENTITY,
            48,
        ),
        ellipsoid(
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::splat(1.0),
            DMat3::IDENTITY,
            48,
        ),
        capsule(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            0.3,
            32,
        ),
    ]);
    let params = Params {
        k: Some(2),
        samples: 10_000,
        ..Params::default()
    };
    let seg = segment(&mesh, &params).unwrap();
    let grid = Grid::from_mesh(&mesh, params.samples).unwrap();
    assert_eq!(seg.sample_parts.len(), grid.len());
    let left = seg.sample_parts[grid
        .points
        .iter()
        .position(|p| p.x < -2.5)
        .expect("a left sample")];
    for (s, p) in grid.points.iter().enumerate() {
        // Everything beyond the neck's middle third belongs to its own ball's part.
        if p.x < -0.7 {
            assert_eq!(seg.sample_parts[s], left, "sample at {p}");
        } else if p.x > 0.7 {
            assert_ne!(seg.sample_parts[s], left, "sample at {p}");
        }
    }
    assert_encloses(&mesh, &seg, &grid);
}

#[test]
fn parts_are_connected_cover_every_sample_and_enclose_the_mesh() {
    let mesh = bundled("bunny.obj");
    for kinds in [
        Kinds::ELLIPSOID,
        Kinds::OBB,
        Kinds::MIXED,
        Kinds::SPHERE,
        Kinds::CAPSULE,
        Kinds::CYLINDER,
        Kinds::HULL,
        Kinds::PRIMITIVES,
    ] {
        let params = Params {
            k: Some(12),
            samples: 8_000,
            kinds,
            ..Params::default()
        };
        let seg = segment(&mesh, &params).unwrap();
        let grid = Grid::from_mesh(&mesh, params.samples).unwrap();
        assert_eq!(seg.parts.len(), 12);
        assert_eq!(seg.sample_parts.len(), grid.len());
        // Each sample in exactly one part: the counts add up.
        let total: usize = seg.parts.iter().map(|p| p.samples).sum();
        assert_eq!(total, grid.len());
        let fsum: f64 = seg.parts.iter().map(|p| p.fraction).sum();
        assert!((fsum - 1.0).abs() < 1e-9);
        let (comps, _) = solid_components(&grid);
        assert!(is_connected(&grid, &seg.sample_parts, &comps));
        assert!(seg.metrics.f >= 1.0);
        assert_encloses(&mesh, &seg, &grid);
        let cov = interior_coverage(&mesh, &seg, 60_000);
        assert!(cov >= 0.9999, "{kinds}: interior coverage {cov}");
        // Each part's volume is of a kind of the set.
        assert!(seg.parts.iter().all(|p| kinds.contains(p.volume.shape)));
    }
}

/// Tolerance mode splits while a tolerance is unmet, and no longer once they are met; it
/// stops unmet only at max_k or when splits stop helping (the last ones were undone). The
/// result reports the final step's figures and judges them by the run's tolerances. Spot at
/// 8000 samples and max_k = 24: at the defaults it reaches max_k unmet; at TOV 0.5 its
/// protrusion splits stop helping at k = 21; with the protrusion at 0.1 too it meets both.
#[test]
fn auto_mode_stops_only_when_tolerances_are_met_or_k_is_exhausted() {
    use bvseg::StepKind::{Backtrack, Final, Initial, Merge, Split};
    let mesh = bundled("spot.obj");
    let defaults = Params::default();
    // (TOV, protrusion, whether the result meets them, whether k reaches max_k)
    for (tov, protrusion, meets, at_max_k) in [
        (defaults.tov, defaults.max_protrusion, false, true),
        (0.5, defaults.max_protrusion, false, false),
        (0.5, 0.1, true, false),
    ] {
        let params = Params {
            samples: 8_000,
            max_k: 24,
            tov,
            max_protrusion: protrusion,
            ..Params::default()
        };
        let what = format!("TOV {tov}, protrusion {protrusion}");
        let seg = segment(&mesh, &params).unwrap();
        let m = seg.metrics;
        let h = &seg.history;
        // The refinement ran and reported every step, from the start to the final volumes,
        // whose figures are the result's.
        assert!(h.len() >= 3, "{what}: {} steps", h.len());
        assert_eq!(h[0].kind, Initial);
        let last = h[h.len() - 1];
        assert_eq!(last.kind, Final);
        assert_eq!((last.k, last.tov, last.mov), (m.k, m.tov, m.mov));
        assert_eq!(last.protrusion, m.protrusion);
        assert_eq!(seg.parts.len(), m.k);
        assert!(h.iter().all(|s| (1..=params.max_k).contains(&s.k)));
        let pr_tol = params.max_protrusion * m.diagonal;
        let met = |s: &bvseg::Step| s.tov < params.tov && s.protrusion < pr_tol;
        // No split once a step has met the tolerances.
        if let Some(first) = h.iter().position(met) {
            assert!(
                h[first + 1..].iter().all(|s| s.kind != Split),
                "{what}: a split after step {first} met the tolerances"
            );
        }
        // The result meets them, or k reached max_k, or the last splits were undone.
        let final_met = met(&last);
        let peak = h.iter().map(|s| s.k).max().unwrap_or(0);
        assert_eq!(
            (final_met, peak == params.max_k),
            (meets, at_max_k),
            "{what}: {m:?}"
        );
        let gave_up = h
            .iter()
            .rfind(|s| matches!(s.kind, Split | Backtrack))
            .is_some_and(|s| s.kind == Backtrack);
        assert!(
            final_met || peak == params.max_k || gave_up,
            "{what}: stopped at k {peak} without meeting the tolerances"
        );
        // Merges never break tolerances that were met.
        for w in h.windows(2) {
            if w[1].kind == Merge && met(&w[0]) {
                assert!(met(&w[1]), "{what}");
            }
        }
        // The report's rule is the same, by the run's tolerances.
        assert_eq!(seg.tolerances_met(&params), Some(final_met));
        assert_eq!(seg.unmet(&params).is_empty(), final_met);
    }
}

/// Adaptive sampling: weighted blocks fill the thick inside, and every promise of the regular
/// lattice still holds: the parts cover every sample and every cell of its block, they are
/// connected, enclose every triangle, leave no gap inside, and their fractions (by cells) sum
/// to one; the same on one and two threads, with the auto skeleton's start too.
#[test]
fn adaptive_sampling_keeps_every_promise() {
    let mesh = bundled("spot.obj");
    for skeleton in [SkeletonMode::None, SkeletonMode::Auto] {
        let params = Params {
            samples: 6_000,
            sampling: Sampling::Adaptive,
            skeleton,
            ..Params::default()
        };
        let grid = Grid::sampled(&mesh, params.samples, params.sampling).unwrap();
        assert!(grid.has_blocks());
        let regular = Grid::from_mesh(&mesh, params.samples).unwrap();
        assert!(grid.h < 0.9 * regular.h, "{} vs {}", grid.h, regular.h);
        let run = |threads| on_threads(threads, &mesh, &params);
        let seg = run(1);
        assert_eq!(seg, run(2), "{skeleton:?}");
        assert_eq!(seg.sample_parts.len(), grid.len());
        let total: usize = seg.parts.iter().map(|p| p.samples).sum();
        assert_eq!(total, grid.len());
        let fsum: f64 = seg.parts.iter().map(|p| p.fraction).sum();
        assert!((fsum - 1.0).abs() < 1e-9);
        let (comps, _) = solid_components(&grid);
        assert!(is_connected(&grid, &seg.sample_parts, &comps));
        assert_encloses(&mesh, &seg, &grid);
        for (s, &p) in seg.sample_parts.iter().enumerate() {
            for [i, j, k] in grid.cells_of(s) {
                let c = grid.cell_center(i64::from(i), i64::from(j), i64::from(k));
                assert!(
                    seg.parts[p as usize].volume.contains(c),
                    "cell {c} of sample {s}"
                );
            }
        }
        let cov = interior_coverage(&mesh, &seg, 60_000);
        assert!(cov >= 0.9999, "interior coverage {cov}");
        assert!(seg.metrics.tov < 0.3, "TOV {}", seg.metrics.tov);
    }
}

#[test]
fn same_seed_gives_identical_results_on_one_and_two_threads() {
    let mesh = bundled("spot.obj");
    let params = Params {
        samples: 6_000,
        ..Params::default()
    };
    let run = |threads| on_threads(threads, &mesh, &params);
    let a = run(1);
    let b = run(2);
    assert_eq!(a, b);
    let c = run(2);
    assert_eq!(b, c);
}

/// Float32 inputs: the volumes enclose the mesh as read. A mesh stored in f32 (STL, glTF)
/// is that rounding of the modeller's f64 mesh; `margin` grows every volume by at least the
/// rounding, so the f64 original stays enclosed too.
#[test]
fn a_margin_keeps_the_f64_original_of_an_f32_mesh_enclosed() {
    // Far from the origin, so that f32 rounding is large against the mesh (ulp 2^-10 at 1000).
    let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
    let original = ellipsoid(
        DVec3::new(1000.1, -1500.3, 700.7),
        DVec3::new(3.0, 1.5, 1.0),
        rot,
        24,
    );
    let rounded: Vec<DVec3> = original
        .vertices()
        .iter()
        .map(|v| v.as_vec3().as_dvec3())
        .collect();
    let err = original
        .vertices()
        .iter()
        .zip(&rounded)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(err > 1e-5, "the rounding should matter here ({err})");
    let mesh32 = Mesh::new(rounded, original.triangles().to_vec()).expect("valid mesh");
    let escapes = |seg: &Segmentation| {
        (0..original.triangles().len())
            .filter(|&t| {
                let v = &seg.parts[seg.triangle_parts[t] as usize].volume;
                original.corners(t).iter().any(|&c| !v.contains(c))
            })
            .count()
    };
    let params = Params {
        samples: 3_000,
        k: Some(6),
        kinds: Kinds::MIXED,
        ..Params::default()
    };
    let plain = segment(&mesh32, &params).expect("segments");
    let grid = Grid::from_mesh(&mesh32, params.samples).expect("grid");
    assert_encloses(&mesh32, &plain, &grid);
    assert!(
        escapes(&plain) > 0,
        "without a margin some f64 corner should fall outside (the test would prove nothing)"
    );
    let margin = Params {
        margin: 2.0 * err,
        ..params
    };
    let grown = segment(&mesh32, &margin).expect("segments");
    assert_eq!(escapes(&grown), 0, "a margin of twice the rounding error");
    // The hierarchy's volumes grow too: the root holds every original vertex.
    let root = &grown.hierarchy.last().expect("a root").volume;
    assert!(original.vertices().iter().all(|&v| root.contains(v)));
    assert!(grown.metrics.tov >= plain.metrics.tov);
}

#[test]
fn a_cancelled_run_ends_with_cancelled() {
    let mesh = bundled("bunny.obj");
    let cancel = bvseg::Cancel::new();
    let mut seg =
        bvseg::Segmenter::with_cancel(&mesh, &Params::default(), cancel.clone()).expect("samples");
    assert!(seg.step().is_some());
    cancel.cancel();
    assert_eq!(seg.step(), None);
    assert_eq!(seg.finish().err(), Some(bvseg::Error::Cancelled));
    // Set before the run: it does not even sample.
    assert_eq!(
        bvseg::Segmenter::with_cancel(&mesh, &Params::default(), cancel).err(),
        Some(bvseg::Error::Cancelled)
    );
}

#[test]
fn the_hierarchy_is_optional_and_changes_nothing_else() {
    let mesh = union(&[
        capsule(DVec3::ZERO, DVec3::new(3.0, 0.0, 0.0), 0.5, 12),
        capsule(DVec3::ZERO, DVec3::new(0.0, 2.5, 0.0), 0.4, 12),
    ]);
    let params = Params {
        samples: 3_000,
        k: Some(5),
        ..Params::default()
    };
    let with = segment(&mesh, &params).expect("segments");
    let without = segment(
        &mesh,
        &Params {
            hierarchy: false,
            ..params
        },
    )
    .expect("segments");
    assert_eq!(with.hierarchy.len(), 2 * with.parts.len() - 1);
    assert!(without.hierarchy.is_empty());
    // Built afterwards, on demand, it is the one the run would have built.
    let mut run = bvseg::Segmenter::new(
        &mesh,
        &Params {
            hierarchy: false,
            ..params.clone()
        },
    )
    .expect("samples");
    assert!(run.hierarchy().is_empty());
    assert_eq!(run.take_result().as_ref(), Ok(&without));
    assert_eq!(run.hierarchy(), with.hierarchy);
    assert!(matches!(run.take_result(), Err(bvseg::Error::Internal(_))));
    assert_eq!(
        Segmentation {
            hierarchy: Vec::new(),
            ..with
        },
        without
    );
}
