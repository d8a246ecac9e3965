//! Bounding-volume stage: convex hull, minimum-volume enclosing ellipsoid and tight oriented
//! box of 10,000-point parts (the MVEE and OBB times include their hull).
// Tests and benchmarks state their expectations by panicking.
// criterion_group! defines undocumented public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use bvseg::internals::Rng;
use bvseg::internals::{convex_hull, min_obb, mvee};
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::{DMat3, DVec3, EulerRot};

/// Grid-cell centres inside a rotated ellipsoid whose radius wobbles with direction (an
/// irregular blob, with the many coplanar ties of a lattice), jittered by a little noise.
fn lattice_blob(n_target: usize) -> Vec<DVec3> {
    let radii = DVec3::new(2.0, 1.2, 0.7);
    // Cells of side h so that about n_target centres fall inside.
    let vol = 4.0 / 3.0 * std::f64::consts::PI * radii.element_product();
    let h = (vol / n_target as f64).cbrt();
    let rot = DMat3::from_euler(EulerRot::ZYX, 0.6, -0.35, 1.1);
    let mut rng = Rng::new(42);
    let mut pts = Vec::new();
    let n = (radii / h).ceil().as_ivec3();
    for i in -n.x..=n.x {
        for j in -n.y..=n.y {
            for k in -n.z..=n.z {
                let p = DVec3::new(i as f64, j as f64, k as f64) * h;
                let u = p / radii;
                let wobble = 1.0 + 0.15 * (3.0 * u.x).sin() * (2.0 * u.y).cos() + 0.1 * u.z;
                if u.length() <= wobble {
                    let noise = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
                    pts.push(rot * (p + noise * (0.02 * h)) + DVec3::new(3.0, -1.0, 0.5));
                }
            }
        }
    }
    pts
}

/// Points uniform in a rotated, stretched ball: a hull with many vertices, all near the
/// MVEE (the hard case for its solver).
fn ball(n: usize) -> Vec<DVec3> {
    let rot = DMat3::from_euler(EulerRot::XYZ, 0.3, 0.5, -0.2);
    let mut rng = Rng::new(7);
    let mut pts = Vec::with_capacity(n);
    while pts.len() < n {
        let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
        if p.length_squared() <= 1.0 {
            pts.push(rot * (p * DVec3::new(3.0, 1.0, 0.5)));
        }
    }
    pts
}

fn bench(c: &mut Criterion) {
    let sets = [
        ("lattice_blob_10k", lattice_blob(10_000)),
        ("ball_10k", ball(10_000)),
    ];
    for (name, pts) in &sets {
        let h = convex_hull(pts);
        eprintln!(
            "{name}: {} points, {} hull vertices",
            pts.len(),
            h.vertices.len()
        );
        c.bench_function(&format!("hull/{name}"), |b| {
            b.iter(|| convex_hull(black_box(pts)))
        });
        c.bench_function(&format!("mvee/{name}"), |b| {
            b.iter(|| mvee(black_box(pts), 1e-3, 1e-6))
        });
        c.bench_function(&format!("obb/{name}"), |b| {
            b.iter(|| min_obb(black_box(pts), 1e-6))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
