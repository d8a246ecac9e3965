//! Writes the awkward input files of `tests/support/hostile.rs` (the families the linear-cost
//! test checks) into a directory, each family at about the given size, for timing the CLI on
//! them (`scripts/bench_hostile.sh`).
//!
//! `cargo run --release --example hostile_inputs -- OUT_DIR [BYTES]` (default 10,000,000).
// An example stops at the first error, with its message.
#![allow(clippy::unwrap_used, clippy::expect_used)]
#[path = "../tests/support/hostile.rs"]
mod hostile;

use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(dir) = args.next() else {
        eprintln!("usage: hostile_inputs OUT_DIR [BYTES]");
        return ExitCode::from(2);
    };
    let target: usize = match args.next().map(|a| a.parse()) {
        None => 10_000_000,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("hostile_inputs: BYTES: {e}");
            return ExitCode::from(2);
        }
    };
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("hostile_inputs: {dir}: {e}");
        return ExitCode::from(2);
    }
    for &(family, build) in hostile::FAMILIES {
        // Sizes grow linearly with n: measure one, scale to the target.
        let per = build(1000).0.len().max(1) as f64 / 1000.0;
        let mut n = ((target as f64 / per) as usize).max(1);
        let (mut bytes, mut name) = build(n);
        if bytes.len() > target {
            n = (n as f64 * target as f64 / bytes.len() as f64) as usize;
            (bytes, name) = build(n.max(1));
        }
        let path = std::path::Path::new(&dir).join(format!(
            "{family}.{}",
            name.rsplit('.').next().unwrap_or("obj")
        ));
        if let Err(e) = std::fs::write(&path, &bytes) {
            eprintln!("hostile_inputs: {}: {e}", path.display());
            return ExitCode::from(2);
        }
        println!("{}\t{}\t{n}", path.display(), bytes.len());
    }
    ExitCode::SUCCESS
}
