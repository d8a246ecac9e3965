//! `bvseg`: wrap a mesh in a few tight ellipsoids, boxes, spheres, capsules, cylinders or convex hulls.
//!
//! Exit codes: 0 on success; 2 on any error (bad input, bad usage, or a file that cannot be
//! written), with one line on stderr, `bvseg: error: <message>`; 3 with `--strict` when the
//! tolerances were not met within `--max-k`; `verify` exits 1 when some triangle escapes the
//! volumes.
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod batch;
mod common;
mod info;
mod plot;
mod progress;
mod robot;
mod segment;
mod verify;

#[derive(Parser, Debug)]
#[command(
    name = "bvseg",
    version,
    about = "Wrap a 3D mesh in a few tight ellipsoids, boxes, spheres, capsules, cylinders or convex hulls"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Segment a closed mesh's volume and bound each part.
    Segment(segment::SegmentArgs),
    /// Load a mesh and report what bvseg sees: size, pieces, holes, orientation, volume.
    Info(info::InfoArgs),
    /// Segment every mesh in a directory, in parallel, skipping finished ones.
    Batch(batch::BatchArgs),
    /// Check a volumes file against a mesh: enclosure of every triangle, TOV and MOV.
    Verify(verify::VerifyArgs),
    /// Segment every link of a robot (URDF or MJCF) and write it back with primitive
    /// colliders: URDF, MJCF, cuRobo spheres and a volumes file per link.
    Robot(robot::RobotArgs),
}

/// Exit code when `--strict` was given and the tolerances were not met.
pub const EXIT_TOLERANCE: u8 = 3;

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("bvseg: error: {}", common::one_line(&e));
            ExitCode::from(2)
        }
    }
}

/// Parses the command line and runs the subcommand. Usage errors exit through clap (code 2).
fn run() -> anyhow::Result<ExitCode> {
    let cli = Cli::parse();
    match cli.command {
        Command::Segment(args) => segment::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Batch(args) => batch::run(&args),
        Command::Verify(args) => verify::run(&args),
        Command::Robot(args) => robot::run(&args),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    pub(crate) fn parse_segment(args: &[&str]) -> Result<segment::SegmentArgs, clap::Error> {
        let mut v = vec!["bvseg", "segment"];
        v.extend_from_slice(args);
        Cli::try_parse_from(v).map(|c| match c.command {
            Command::Segment(a) => a,
            _ => unreachable!("parsed as segment"),
        })
    }
}
