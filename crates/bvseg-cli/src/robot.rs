//! `bvseg robot`: a URDF or MJCF in, each link segmented in its own frame, and the robot out
//! with primitive colliders (URDF, MJCF, cuRobo spheres, a volumes document per link). The
//! work is `bvseg_io::robot::segment_robot`'s; this adds the options, the timeout and the
//! progress lines (and `bvseg batch` runs robots through [`run_robot`] too).
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::anyhow;
use bvseg_core::{Cancel, Params};
use bvseg_io::export::OutputFormat;
use bvseg_io::robot::{
    self, MeshSource, PartBudget, RobotEvent, RobotOptions, RobotRun, DEFAULT_PARTS_PER_LINK,
    DEFAULT_SPHERES_PER_LINK,
};
use clap::{Args, ValueEnum};

use crate::common::{self, ParamArgs, Timer};

/// Which meshes of a link to segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SourceArg {
    /// URDF `<collision>` meshes; MJCF mesh geoms that collide.
    Collision,
    /// URDF `<visual>` meshes; every MJCF mesh geom.
    Visual,
}

/// The options of a robot run besides the segmentation's (shared by `robot` and `batch`).
#[derive(Args, Debug, Clone)]
pub struct RobotBudgetArgs {
    /// Robots: which meshes of each link to segment.
    #[arg(long, value_enum, default_value_t = SourceArg::Collision)]
    pub source: SourceArg,

    /// Robots: most parts per link (each link's --max-k is the smaller of this and --max-k).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_PARTS_PER_LINK as u64, conflicts_with = "total_parts", value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub max_parts: u64,

    /// Robots: most parts for the whole robot, shared among links by their volume (each at
    /// least 1).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub total_parts: Option<u64>,

    /// Robots: most spheres per link in curobo.yml.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SPHERES_PER_LINK as u64, value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub spheres_per_link: u64,

    /// Robots: write capsules as URDF 1.1 <capsule> elements (otherwise no capsules).
    #[arg(long)]
    pub urdf_capsules: bool,
}

impl RobotBudgetArgs {
    /// The library's options, with the segmentation's `params`.
    pub fn options(&self, params: Params) -> RobotOptions {
        // The ranges are bounded by the parser, so the conversions hold.
        RobotOptions {
            source: match self.source {
                SourceArg::Collision => MeshSource::Collision,
                SourceArg::Visual => MeshSource::Visual,
            },
            params,
            parts: match self.total_parts {
                Some(n) => PartBudget::Total(n as usize),
                None => PartBudget::PerLink(self.max_parts as usize),
            },
            spheres_per_link: self.spheres_per_link as usize,
            urdf_capsules: self.urdf_capsules,
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct RobotArgs {
    /// Robot file: URDF (.urdf) or MJCF (.xml).
    #[arg(value_name = "ROBOT")]
    pub robot: PathBuf,

    /// Directory to write <robot>.urdf, <robot>.xml, curobo.yml, links/<link>.json and
    /// manifest.json (last) in (created if missing).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,

    #[command(flatten)]
    pub budget: RobotBudgetArgs,

    #[command(flatten)]
    pub params: ParamArgs,

    /// Print nothing on stderr but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: &RobotArgs) -> anyhow::Result<ExitCode> {
    let start = Instant::now();
    args.params.no_skeleton_file("robot")?;
    // Each link's volumes go to a JSON document, the one format that carries the hierarchy.
    let options = args
        .budget
        .options(args.params.params(&[OutputFormat::Json])?);
    let run = run_robot(
        &args.robot,
        &options,
        args.params.threads,
        args.params.timeout,
        args.quiet,
    )?;
    run.write(&args.output)?;
    if !args.quiet {
        for w in &run.warnings {
            eprintln!("bvseg: warning: {w}");
        }
        eprintln!(
            "bvseg: {}: {} links, {} parts, {} spheres in {:.1} s -> {}",
            args.robot.display(),
            run.links_segmented(),
            run.total_parts(),
            run.total_spheres(),
            start.elapsed().as_secs_f64(),
            args.output.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Runs `bvseg_io::robot::segment_robot` in a pool of `threads` (when given), giving up
/// after `timeout` seconds for the whole robot; unless `quiet`, one line per finished link.
pub fn run_robot(
    path: &Path,
    options: &RobotOptions,
    threads: Option<u64>,
    timeout: Option<f64>,
    quiet: bool,
) -> anyhow::Result<RobotRun> {
    let name = path.display().to_string();
    let cancel = Cancel::new();
    let timer = timeout.map(|t| Timer::start(t, &name, cancel.clone(), false));
    let result = common::in_pool(threads, || {
        robot::segment_robot(path, options, &cancel, |e| {
            if let (false, RobotEvent::Done { link, result }) = (quiet, e) {
                eprintln!(
                    "bvseg: link {link}: {} parts ({}), {} spheres",
                    result.parts.parts.len(),
                    result.parts.kinds,
                    result.spheres.parts.len()
                );
            }
        })
        .map_err(|e| match timeout {
            Some(t) if e.is_cancelled() => {
                anyhow!("{name}: gave up after {t} s (--timeout); nothing written")
            }
            _ => anyhow!(e),
        })
    });
    drop(timer);
    result
}
