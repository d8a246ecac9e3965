//! Bounding-volume fitting on real part point sets: the convex hull of a part's enclosure
//! points, the MVEE of that hull, and the two together as `Fitter` does them.
//!
//! The parts come from the pipeline's own first stages on real meshes (the bunny, and the
//! shared `human_1` when it is there): a 20k-sample grid, a 16-part CVT, Lloyd + boundary moves, then
//! each part's enclosure points (boundary samples, shared cell-face centres and mesh vertices).
//! Each benchmark fits every part once per iteration; the throughput line gives fits per
//! second, and the per-fit time is the iteration time divided by the part count printed
//! before it. `make_hull_then_fit` is what `Fitter` does for a part (less the outside-cell
//! count): `hull_points`, then `Fitter::fit_points` on the hull. `min_capsule`, `min_cylinder`,
//! `min_capsule_and_cylinder` and `min_obb` time those kinds' searches on the parts' hulls.
// Tests and benchmarks state their expectations by panicking.
// criterion_group! defines undocumented public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use std::path::{Path, PathBuf};

use bvseg::internals::hull_points;
use bvseg::internals::mvee_of_hull;
use bvseg::internals::Enclosure;
use bvseg::internals::Grid;
use bvseg::internals::Solid;
use bvseg::internals::{min_axial, min_capsule_and_cylinder, min_obb, Axial};
use bvseg::internals::{Fitter, MVEE_TOL};
use bvseg::{Kinds, Mesh};
use criterion::measurement::WallTime;
use criterion::{
    black_box, criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput,
};
use glam::DVec3;

/// A mesh, its solid, and the enclosure points of each part of an optimised 16-part CVT.
struct Case {
    name: String,
    mesh: Mesh,
    solid: Solid,
    parts: Vec<Vec<DVec3>>,
}

fn case(path: &Path) -> Option<Case> {
    let mesh = bvseg::io::load(path, &bvseg::io::LoadOptions::default())
        .ok()?
        .mesh;
    let grid = Grid::from_mesh(&mesh, 20_000).ok()?;
    let solid = Solid::new(grid);
    let mut part = bvseg::internals::cvt(&solid, 16, 0);
    bvseg::internals::optimize(&solid, &mut part, None, None, 100);
    let enc = Enclosure::new(&mesh, &solid);
    let members = part.members();
    let parts: Vec<Vec<DVec3>> = (0..members.len())
        .map(|i| enc.points(&mesh, &solid, &part.labels, &members[i], i as u32))
        .collect();
    let name = path.file_stem()?.to_string_lossy().into_owned();
    Some(Case {
        name,
        mesh,
        solid,
        parts,
    })
}

fn cases() -> Vec<Case> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    [
        root.join("assets/meshes/bunny.obj"),
        root.join("../shared/meshes/human_1.obj"),
    ]
    .iter()
    .filter(|p| p.exists())
    .filter_map(|p| case(p))
    .collect()
}

/// Benchmark `fit` applied to every hull, once per iteration.
fn each_hull<T>(
    g: &mut BenchmarkGroup<WallTime>,
    name: &str,
    hulls: &[Vec<DVec3>],
    fit: impl Fn(&[DVec3]) -> T,
) {
    g.bench_function(name, |b| {
        b.iter(|| {
            for h in hulls {
                black_box(fit(black_box(h)));
            }
        })
    });
}

fn bench(c: &mut Criterion) {
    for cs in cases() {
        let min_r = 0.5 * cs.solid.grid.h;
        let hulls: Vec<Vec<DVec3>> = cs.parts.iter().map(|p| hull_points(p)).collect();
        let n = cs.parts.len();
        let pts: Vec<usize> = cs.parts.iter().map(Vec::len).collect();
        let hv: Vec<usize> = hulls.iter().map(Vec::len).collect();
        println!(
            "{}: {} samples, {n} parts; points per part {:?}; hull vertices {:?}",
            cs.name,
            cs.solid.len(),
            pts,
            hv
        );
        let fitter = Fitter::new(&cs.mesh, &cs.solid, Kinds::ELLIPSOID);

        let mut g = c.benchmark_group(format!("fit/{}", cs.name));
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function("hull_points", |b| {
            b.iter(|| {
                for p in &cs.parts {
                    black_box(hull_points(black_box(p)));
                }
            })
        });
        for tol in [1e-4, 1e-3] {
            each_hull(&mut g, &format!("mvee_of_hull_tol{tol:e}"), &hulls, |h| {
                mvee_of_hull(h, tol, min_r)
            });
        }
        g.bench_function("make_hull_then_fit", |b| {
            b.iter(|| {
                for p in &cs.parts {
                    let h = hull_points(black_box(p));
                    black_box(fitter.fit_points(&cs.solid, &h));
                }
            })
        });
        // The capsule and cylinder searches, on the parts' hulls (each alone, and the two
        // sharing their circles as a fit of every primitive does).
        for (name, kind) in [("capsule", Axial::Capsule), ("cylinder", Axial::Cylinder)] {
            each_hull(&mut g, &format!("min_{name}"), &hulls, |h| {
                min_axial(h, kind, min_r)
            });
        }
        each_hull(&mut g, "min_capsule_and_cylinder", &hulls, |h| {
            min_capsule_and_cylinder(h, min_r)
        });
        each_hull(&mut g, "min_obb", &hulls, |h| min_obb(h, min_r));
        g.finish();

        // One part alone, the one with the most points.
        let big = (0..n).max_by_key(|&i| pts[i]).unwrap_or(0);
        println!(
            "{}: largest part {} points, {} hull vertices",
            cs.name, pts[big], hv[big]
        );
        let mut g = c.benchmark_group(format!("fit/{}/largest_part", cs.name));
        g.bench_function("hull_points", |b| {
            b.iter(|| hull_points(black_box(&cs.parts[big])))
        });
        g.bench_function("mvee_of_hull", |b| {
            b.iter(|| mvee_of_hull(black_box(&hulls[big]), MVEE_TOL, min_r))
        });
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
