//! The work of loading and segmenting a file grows at most linearly with the file, for every
//! family of awkward inputs in `support/hostile.rs`. Work is counted, not timed
//! (`bvseg::internals::work`: lattice columns scanned by the inside test, points fitted, outside cells
//! counted, vertices welded and triangles checked), so the test is exact on any machine; wall times
//! are in `benches/hostile.rs`.
//!
//! The counter is per thread and each run is made on the test's own thread (a one-thread pool
//! that uses it), so other tests of this binary, running meanwhile, do not add to the count.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#[path = "support/hostile.rs"]
mod hostile;

use bvseg::{segment, Params};

/// Largest extra work per extra byte of input between the two sizes of a family. Loading
/// costs a few units per byte; the first versions of the inside test, which rasterised every
/// copy of a repeated face, cost over a thousand.
const UNITS_PER_BYTE: f64 = 8.0;

/// Loads and segments one file in `pool`; the work it took and whether it was refused.
fn work(pool: &rayon::ThreadPool, bytes: &[u8], name: &str) -> (u64, Result<(), String>) {
    pool.install(|| work_here(bytes, name))
}

fn work_here(bytes: &[u8], name: &str) -> (u64, Result<(), String>) {
    let before = bvseg::internals::work::total();
    let outcome = bvseg::io::load_bytes(bytes, name, &bvseg::io::LoadOptions::default())
        .map_err(|e| e.to_string())
        .and_then(|loaded| {
            let params = Params {
                samples: 4_000,
                ..Params::default()
            };
            segment(&loaded.mesh, &params)
                .map(|_| ())
                .map_err(|e| e.to_string())
        });
    (bvseg::internals::work::total() - before, outcome)
}

#[test]
fn work_grows_at_most_linearly_with_the_input() {
    // One thread, the test's own (a thread joins one pool only): all the work of a run is
    // counted on it.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .unwrap();
    let (mut report, mut failures) = (Vec::new(), Vec::new());
    for &(family, build) in hostile::FAMILIES {
        let (small, name_s) = build(5_000);
        let (large, name_l) = build(20_000);
        let (ws, rs) = work(&pool, &small, &name_s);
        let (wl, rl) = work(&pool, &large, &name_l);
        for (r, name) in [(&rs, &name_s), (&rl, &name_l)] {
            if let Err(e) = r {
                assert!(!e.contains('\n'), "{name}: a multi-line error: {e}");
            }
        }
        // Nothing counted would mean the work ran on other threads, uncounted.
        assert!(ws > 0 && wl > 0, "{family}: no work counted on this thread");
        let per_byte = (wl as f64 - ws as f64) / (large.len() - small.len()) as f64;
        report.push(format!(
            "{family}: {} B -> {ws} units ({}), {} B -> {wl} units ({}); {per_byte:.2} units per extra byte",
            small.len(),
            if rs.is_ok() { "segmented" } else { "refused" },
            large.len(),
            if rl.is_ok() { "segmented" } else { "refused" },
        ));
        // Linear: k times the input (the families grow their files about 4 times) costs at
        // most k times the work, up to 10 % (the two sizes get different partitions and kinds:
        // slivers 4.31 times the work for 4.28 times the bytes), and each byte adds a bounded
        // amount, the sharp test.
        let ratio = large.len() as f64 / small.len() as f64;
        if wl as f64 > 1.1 * ratio * ws.max(1) as f64 || per_byte > UNITS_PER_BYTE {
            failures.push(family);
        }
    }
    eprintln!("{}", report.join("\n"));
    assert!(
        failures.is_empty(),
        "superlinear or too costly: {failures:?}"
    );
}
