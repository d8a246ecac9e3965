//! Segments a mesh several times in one process, with the defaults and one thread, and prints
//! each run's time: the later runs are what an engine's optimised code takes. Built for
//! `wasm32-wasip1` and run under Node.js, it times the core in the browser's WebAssembly engine
//! without a browser around it (`scripts/wasm_vs_native.sh`).
//!
//! `cargo run --release --example repeat_runs -- MESH [RUNS]` (default 3 runs).
// An example stops at the first error, with its message.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: repeat_runs MESH [RUNS]");
        return ExitCode::from(2);
    };
    let runs: usize = match args.next().map(|a| a.parse()) {
        None => 3,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("repeat_runs: RUNS: {e}");
            return ExitCode::from(2);
        }
    };
    let loaded = match bvseg::io::load(&path, &bvseg::io::LoadOptions::default()) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("repeat_runs: {e}");
            return ExitCode::from(1);
        }
    };
    // The page's job: no hierarchy, which it builds only for a JSON export.
    let params = bvseg::Params {
        hierarchy: false,
        ..Default::default()
    };
    let one = || {
        for _ in 0..runs {
            let t0 = Instant::now();
            let seg = bvseg::segment(&loaded.mesh, &params).expect("segment");
            println!(
                "run {:.3} s, k = {}",
                t0.elapsed().as_secs_f64(),
                seg.parts.len()
            );
        }
    };
    #[cfg(feature = "parallel")]
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool")
        .install(one);
    #[cfg(not(feature = "parallel"))]
    one();
    ExitCode::SUCCESS
}
