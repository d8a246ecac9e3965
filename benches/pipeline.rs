//! Criterion benchmarks of the bvseg pipeline and its hot stages.
//!
//! Run everything with `cargo bench --bench pipeline` (about 5 minutes on 2 cores), or one
//! group with e.g. `cargo bench --bench pipeline -- assign/`. `scripts/bench_scaling.sh`
//! runs them and prints the medians as a table.
//!
//! | id | what is timed | bar (2 cores) |
//! |---|---|---|
//! | `sampling/bunny_20k` | `Grid::from_mesh` alone | - |
//! | `optimize/k20_n15000` | `optimize` (Lloyd + boundary moves) from a CVT start, k = 20 | <= 30 ms |
//! | `pipeline/auto_bunny_20k`, `pipeline/auto_<mesh>` | `segment` with `Params::default()` | <= 0.5 s near 30 parts |
//! | `assign/threads_{1,2}` | one assignment sweep, 100k samples x 32 parts | speedup >= 1.6x |
//! | `scaling_n/{10k,100k,1M}` | `segment`, bunny, k = 16 | - |
//! | `scaling_k/{8,16,32,64}` | `segment`, bunny, 20k samples | - |
//!
//! Meshes come from `assets/meshes` (always present). When the shared test set is present
//! (`../shared/meshes` next to the workspace, or the directory in `BVSEG_SHARED_MESHES`),
//! `optimize/` uses `human_1.obj` (the paper's human case) and `pipeline/` adds
//! `auto_human_1`; otherwise `optimize/` falls back to the bunny and the extra pipeline case
//! is skipped. Set `BVSEG_BENCH_SKIP_1M=1` to leave out `scaling_n/1M` (the slowest case).
//!
//! All set-up (loading, sampling, CVT initialisation) happens outside the timed closures, and
//! lazily, so that a filtered run only prepares what it measures.
// Tests and benchmarks state their expectations by panicking.
// criterion_group! defines undocumented public functions.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use std::cell::{Cell, OnceCell};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use bvseg::internals::cvt;
use bvseg::internals::optimize;
use bvseg::internals::Grid;
use bvseg::internals::{assign, PartMetric, Rule};
use bvseg::internals::{Partition, Solid};
use bvseg::{segment, Mesh, Params};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, SamplingMode};

/// Seed of every CVT initialisation here (and `Params::default().seed` for `segment`).
const SEED: u64 = 0;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/meshes")
        .join(name)
}

fn load(path: &Path) -> Mesh {
    bvseg::io::load(path, &bvseg::io::LoadOptions::default())
        .unwrap_or_else(|e| panic!("loading {}: {e}", path.display()))
        .mesh
}

fn bunny() -> Mesh {
    load(&asset("bunny.obj"))
}

/// The shared mesh directory, when present.
fn shared_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("BVSEG_SHARED_MESHES") {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes"),
    };
    dir.is_dir().then_some(dir)
}

/// `name` (e.g. `"human_1"`) from the shared set, when present.
fn shared_mesh(name: &str) -> Option<Mesh> {
    let path = shared_dir()?.join(format!("{name}.obj"));
    path.is_file().then(|| load(&path))
}

/// A sampled solid with its components and a CVT partition into `k` parts.
struct Prepared {
    solid: Solid,
    part: Partition,
}

fn prepare(mesh: &Mesh, samples: usize, k: usize) -> Prepared {
    let grid = Grid::from_mesh(mesh, samples).expect("sampling");
    let solid = Solid::new(grid);
    let part = cvt(&solid, k, SEED);
    Prepared { solid, part }
}

fn bench_sampling(c: &mut Criterion) {
    let mut g = c.benchmark_group("sampling");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let mesh = OnceCell::new();
    g.bench_function("bunny_20k", |b| {
        let mesh = mesh.get_or_init(bunny);
        b.iter(|| Grid::from_mesh(black_box(mesh), 20_000).unwrap())
    });
    g.finish();
}

fn bench_optimize(c: &mut Criterion) {
    let mut g = c.benchmark_group("optimize");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let prep = OnceCell::new();
    g.bench_function("k20_n15000", |b| {
        let p: &Prepared = prep.get_or_init(|| {
            let (name, mesh) = match shared_mesh("human_1") {
                Some(m) => ("human_1", m),
                None => ("bunny", bunny()),
            };
            let p = prepare(&mesh, 15_000, 20);
            let mut probe = p.part.clone();
            let st = optimize(&p.solid, &mut probe, None, None, 100);
            eprintln!(
                "optimize/k20_n15000: mesh {name}, {} samples, k {}, {} sweeps, {} boundary moves, F {:.4} -> {:.4}",
                p.solid.len(),
                p.part.k(),
                st.sweeps,
                st.moves,
                st.f_before,
                st.f_after
            );
            p
        });
        b.iter_batched(
            || p.part.clone(),
            |mut part| {
                optimize(&p.solid, &mut part, None, None, 100);
                part
            },
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

fn bench_pipeline(c: &mut Criterion) {
    let mut g = c.benchmark_group("pipeline");
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    let params = Params::default();
    let mut cases: Vec<(String, Box<dyn Fn() -> Mesh>)> =
        vec![("auto_bunny_20k".into(), Box::new(bunny))];
    if shared_dir().is_some_and(|d| d.join("human_1.obj").is_file()) {
        cases.push((
            "auto_human_1".into(),
            Box::new(|| shared_mesh("human_1").unwrap()),
        ));
    }
    for (id, make) in cases {
        let mesh = OnceCell::new();
        // The last timed run's outcome, reported once the case is measured (so the report
        // costs no extra run; recording it is a few copies per 0.1-1 s iteration).
        let outcome = Cell::new(None);
        g.bench_function(id.as_str(), |b| {
            let mesh = mesh.get_or_init(&make);
            b.iter(|| {
                let seg = segment(black_box(mesh), &params).unwrap();
                let m = &seg.metrics;
                outcome.set(Some((m.k, m.tov, m.mov, m.samples, seg.history.len())));
                seg
            })
        });
        if let Some((k, tov, mov, samples, steps)) = outcome.get() {
            eprintln!(
                "pipeline/{id}: ends with k = {k} (TOV {tov:.3}, MOV {mov:.3}, {samples} samples, {steps} steps)"
            );
        }
    }
    g.finish();
}

fn bench_assign(c: &mut Criterion) {
    let mut g = c.benchmark_group("assign");
    g.sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let prep = OnceCell::new();
    let setup = || {
        let p = prepare(&bunny(), 100_000, 32);
        let metrics: Vec<PartMetric> = p.part.parts.iter().map(PartMetric::new).collect();
        let all: Vec<u32> = (0..p.solid.len() as u32).collect();
        let cand: Vec<u32> = (0..metrics.len() as u32).collect();
        eprintln!(
            "assign: {} samples x {} parts (bunny, CVT start)",
            all.len(),
            cand.len()
        );
        (p.solid, metrics, all, cand)
    };
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        g.bench_function(format!("threads_{threads}"), |b| {
            let (solid, metrics, all, cand) = prep.get_or_init(setup);
            // The whole timing loop runs inside the pool, so `assign`'s parallel iterator
            // uses exactly `threads` workers and no per-call injection cost is measured.
            pool.install(|| b.iter(|| assign(solid, all, metrics, cand, Rule::Paper)))
        });
    }
    g.finish();
}

fn bench_scaling(c: &mut Criterion) {
    let mesh = OnceCell::new();
    let skip_1m = std::env::var_os("BVSEG_BENCH_SKIP_1M").is_some_and(|v| v != "0");

    let mut g = c.benchmark_group("scaling_n");
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500));
    for (id, n) in [("10k", 10_000usize), ("100k", 100_000), ("1M", 1_000_000)] {
        if n == 1_000_000 && skip_1m {
            continue;
        }
        // Criterion takes at least 10 samples; for 1M that is ~10 runs whatever the budget,
        // so the budget only has to be small enough not to ask for more.
        g.measurement_time(Duration::from_secs(match n {
            10_000 => 3,
            100_000 => 10,
            _ => 1,
        }));
        let params = Params {
            samples: n,
            k: Some(16),
            ..Params::default()
        };
        g.bench_function(id, |b| {
            let mesh = mesh.get_or_init(bunny);
            b.iter(|| segment(black_box(mesh), &params).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("scaling_k");
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    for k in [8usize, 16, 32, 64] {
        let params = Params {
            samples: 20_000,
            k: Some(k),
            ..Params::default()
        };
        g.bench_function(k.to_string(), |b| {
            let mesh = mesh.get_or_init(bunny);
            b.iter(|| segment(black_box(mesh), &params).unwrap())
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_sampling,
    bench_optimize,
    bench_pipeline,
    bench_assign,
    bench_scaling
);
criterion_main!(benches);
