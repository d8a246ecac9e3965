//! Sampling stage: `Grid::from_mesh` (and the inside test alone) on a ~50k-triangle sphere.
// Tests and benchmarks state their expectations by panicking.
// criterion_group! defines undocumented public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use std::collections::HashMap;

use bvseg::internals::{inside_cells, Grid};
use bvseg::Mesh;
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::DVec3;

/// Geodesic icosphere: each icosahedron face split into `m * m` triangles (20 m^2 in all),
/// points shared between faces by their integer barycentric key.
fn icosphere(m: usize) -> Mesh {
    let (base, faces) = bvseg_testkit::geometry::icosahedron();
    let base: Vec<DVec3> = base.iter().map(|&p| DVec3::from_array(p)).collect();
    let mut ids: HashMap<Vec<(usize, usize)>, u32> = HashMap::new();
    let mut verts = Vec::new();
    let mut point = |f: [usize; 3], w: [usize; 3]| {
        let mut key: Vec<(usize, usize)> =
            (0..3).filter(|&i| w[i] > 0).map(|i| (f[i], w[i])).collect();
        key.sort_unstable();
        *ids.entry(key.clone()).or_insert_with(|| {
            let p: DVec3 = key.iter().map(|&(v, w)| base[v] * w as f64).sum();
            verts.push(p.normalize());
            verts.len() as u32 - 1
        })
    };
    let mut tris = Vec::new();
    for f in faces {
        for i in 0..m {
            for j in 0..m - i {
                let k = m - i - j;
                let a = point(f, [i, j, k]);
                let b = point(f, [i + 1, j, k - 1]);
                let c = point(f, [i, j + 1, k - 1]);
                tris.push([a, b, c]);
                if j + 1 < m - i {
                    let d = point(f, [i + 1, j + 1, k - 2]);
                    tris.push([b, d, c]);
                }
            }
        }
    }
    Mesh::new(verts, tris).unwrap()
}

fn bench(c: &mut Criterion) {
    let mesh = icosphere(50);
    assert_eq!(mesh.triangles().len(), 50_000);
    for target in [20_000, 1_000_000] {
        c.bench_function(&format!("grid_from_mesh_50k_tris_{target}_samples"), |b| {
            b.iter(|| Grid::from_mesh(black_box(&mesh), target).unwrap())
        });
        let grid = Grid::from_mesh(&mesh, target).unwrap();
        println!(
            "target {target}: {} samples, dims {:?}",
            grid.len(),
            grid.dims
        );
        c.bench_function(&format!("inside_cells_50k_tris_{target}_samples"), |b| {
            b.iter(|| inside_cells(black_box(&mesh), grid.origin, grid.h, grid.dims).unwrap())
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
