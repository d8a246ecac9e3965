//! `bvseg`: wrap a mesh in a few tight ellipsoids or oriented boxes.
//!
//! Exit codes: 0 on success, 2 on any error (bad input, bad usage, or a file that cannot be
//! written); errors are one line on stderr, `bvseg: error: <message>`.
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{anyhow, bail, Context};
use bvseg_core::{segment_with, BoundingKind, Mesh, Params, Segmentation, Step};
use bvseg_io::{IoError, LoadedMesh};
use clap::{Args, Parser, Subcommand, ValueEnum};

mod verify;

/// The mesh used when none is given, as it sits in the source tree.
const BUNDLED_MESH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");
/// How messages name the bundled mesh (the absolute source path would only confuse).
const BUNDLED_NAME: &str = "assets/meshes/bunny.obj";
/// The same mesh compiled in, so that an installed binary works away from the source tree.
const BUNDLED_BYTES: &[u8] = include_bytes!("../../../assets/meshes/bunny.obj");

#[derive(Parser, Debug)]
#[command(
    name = "bvseg",
    version,
    about = "Wrap a 3D mesh in a few tight ellipsoids or oriented boxes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Segment a closed mesh's volume and bound each part.
    Segment(SegmentArgs),
    /// Check a volumes file against a mesh: enclosure of every triangle, TOV and MOV.
    Verify(verify::VerifyArgs),
}

#[derive(Args, Debug)]
struct SegmentArgs {
    /// Mesh file (.obj). Without it, the bundled Stanford bunny is used.
    #[arg(value_name = "MESH")]
    mesh: Option<PathBuf>,

    /// Exactly this many parts, instead of refining until the tolerances hold.
    #[arg(long, value_name = "K", conflicts_with_all = ["tov", "mov"])]
    k: Option<usize>,

    /// Tolerance on the total outside volume TOV (relative to the mesh's volume).
    #[arg(long, value_name = "T", default_value_t = Params::default().tov)]
    tov: f64,

    /// Tolerance on the largest per-part outside volume MOV.
    #[arg(long, value_name = "M", default_value_t = Params::default().mov)]
    mov: f64,

    /// Largest number of parts the tolerance loop may reach.
    #[arg(long, value_name = "N", default_value_t = Params::default().max_k)]
    max_k: usize,

    /// Bounding volume of each part (mixed: whichever of the two is smaller).
    #[arg(long = "bv", value_enum, default_value_t = Bv::Ellipsoid)]
    bv: Bv,

    /// Target number of interior samples.
    #[arg(long, value_name = "N", default_value_t = Params::default().samples)]
    samples: usize,

    /// Seed of the initialisation; equal seeds give identical results.
    #[arg(long, value_name = "S", default_value_t = Params::default().seed)]
    seed: u64,

    /// Number of worker threads (default: one per core). The result does not depend on it.
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u64).range(1..=4096))]
    threads: Option<u64>,

    /// Write the volumes to this file (`.json`: the bvseg.volumes/1 schema).
    #[arg(short, long, value_name = "FILE.json")]
    output: Option<PathBuf>,

    /// Do not merge adjacent parts at the end of the tolerance loop.
    #[arg(long)]
    no_merge: bool,

    /// Do not polish part boundaries to lower the outside volume.
    #[arg(long)]
    no_polish: bool,

    /// Print nothing on stderr but errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Bv {
    Ellipsoid,
    Obb,
    Mixed,
}

impl From<Bv> for BoundingKind {
    fn from(bv: Bv) -> Self {
        match bv {
            Bv::Ellipsoid => BoundingKind::Ellipsoid,
            Bv::Obb => BoundingKind::Obb,
            Bv::Mixed => BoundingKind::Mixed,
        }
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("bvseg: error: {}", one_line(&e));
            ExitCode::from(2)
        }
    }
}

/// Parses the command line and runs the subcommand. Usage errors exit through clap (code 2).
fn run() -> anyhow::Result<ExitCode> {
    let cli = Cli::parse();
    match cli.command {
        Command::Segment(args) => segment(&args),
        Command::Verify(args) => verify::run(&args),
    }
}

/// The error and its causes on one line. Our errors often already quote their cause (an
/// `IoError` names the OS error it wraps), so a cause already in the text is not repeated.
fn one_line(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg.replace(['\n', '\r'], " ")
}

fn segment(args: &SegmentArgs) -> anyhow::Result<ExitCode> {
    let params = Params {
        samples: args.samples,
        seed: args.seed,
        bounding: args.bv.into(),
        k: args.k,
        tov: args.tov,
        mov: args.mov,
        max_k: args.max_k,
        merge: !args.no_merge,
        polish: !args.no_polish,
        ..Params::default()
    };
    params.validate()?;
    // Checked before the (possibly long) run, so that a typo does not cost the whole run.
    if let Some(out) = &args.output {
        check_output(out)?;
    }

    let (name, loaded) = load_input(args)?;
    let LoadedMesh { mesh, stats } = loaded;
    if !args.quiet && (stats.welded > 0 || stats.degenerate > 0) {
        eprintln!(
            "bvseg: {name}: welded {} coincident vertices, dropped {} degenerate triangles",
            stats.welded, stats.degenerate
        );
    }

    let start = Instant::now();
    let quiet = args.quiet;
    let mut steps = 0usize;
    let on_step = move |s: &Step| {
        steps += 1;
        if !quiet {
            eprintln!(
                "[{steps:3}] {:<9} k={:<3} F={:.6}  TOV={:.6}  MOV={:.6}",
                s.kind.as_str(),
                s.k,
                s.f,
                s.tov,
                s.mov
            );
        }
    };
    let seg = run_segmentation(&mesh, &params, args.threads, quiet, on_step)
        .map_err(|e| anyhow!("{name}: {e}"))?;
    let elapsed = start.elapsed();

    let written = match &args.output {
        Some(out) => {
            bvseg_io::write_json(out, &seg)?;
            out.display().to_string()
        }
        None => "not written (use -o FILE.json)".into(),
    };
    print_summary(&name, &mesh, &seg, elapsed.as_secs_f64(), &written)?;
    let m = seg.metrics;
    if params.k.is_none() && !quiet && !(m.tov < params.tov && m.mov < params.mov) {
        eprintln!(
            "bvseg: warning: tolerances not met at k = {} (TOV {:.3} vs {}, MOV {:.3} vs {}); \
             raise --max-k or the tolerances, or see BENCHMARKS.md on MOV",
            m.k, m.tov, params.tov, m.mov, params.mov
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Only JSON can be written so far; the directory must exist.
fn check_output(out: &Path) -> anyhow::Result<()> {
    if bvseg_io::extension(out).as_deref() != Some("json") {
        return Err(IoError::UnsupportedFormat {
            name: out.display().to_string(),
            what: "output",
            ext: bvseg_io::extension(out),
            supported: ".json",
        }
        .into());
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!(
                "{}: the directory {} does not exist",
                out.display(),
                dir.display()
            );
        }
    }
    Ok(())
}

/// The mesh named on the command line, or the bundled one: from the source tree when it is
/// there, else the copy compiled into the binary.
fn load_input(args: &SegmentArgs) -> anyhow::Result<(String, LoadedMesh)> {
    if let Some(path) = &args.mesh {
        return Ok((
            path.display().to_string(),
            bvseg_io::load_mesh_detailed(path)?,
        ));
    }
    if !args.quiet {
        eprintln!("bvseg: no mesh given; using the bundled {BUNDLED_NAME}");
    }
    let loaded = if Path::new(BUNDLED_MESH).is_file() {
        bvseg_io::load_obj_detailed(BUNDLED_MESH)
    } else {
        bvseg_io::load_obj_from_bytes_detailed(BUNDLED_BYTES, BUNDLED_NAME)
    };
    Ok((BUNDLED_NAME.to_owned(), loaded?))
}

#[cfg(feature = "parallel")]
fn run_segmentation(
    mesh: &Mesh,
    params: &Params,
    threads: Option<u64>,
    _quiet: bool,
    on_step: impl FnMut(&Step) + Send,
) -> anyhow::Result<Segmentation> {
    let Some(threads) = threads else {
        return Ok(segment_with(mesh, params, on_step)?);
    };
    let pool = rayon::ThreadPoolBuilder::new()
        // Bounded to 4096 by the argument parser.
        .num_threads(threads as usize)
        .build()
        .with_context(|| format!("cannot start {threads} threads"))?;
    Ok(pool.install(|| segment_with(mesh, params, on_step))?)
}

#[cfg(not(feature = "parallel"))]
fn run_segmentation(
    mesh: &Mesh,
    params: &Params,
    threads: Option<u64>,
    quiet: bool,
    on_step: impl FnMut(&Step) + Send,
) -> anyhow::Result<Segmentation> {
    if threads.is_some_and(|t| t > 1) && !quiet {
        eprintln!("bvseg: built without the `parallel` feature; --threads is ignored");
    }
    Ok(segment_with(mesh, params, on_step)?)
}

fn print_summary(
    name: &str,
    mesh: &Mesh,
    seg: &Segmentation,
    seconds: f64,
    written: &str,
) -> anyhow::Result<()> {
    let m = &seg.metrics;
    let text = format!(
        "mesh       {name}\n\
         triangles  {}\n\
         samples    {}\n\
         k          {} ({})\n\
         F          {:.6}\n\
         TOV        {:.6}\n\
         MOV        {:.6}\n\
         time       {seconds:.2} s\n\
         output     {written}\n",
        mesh.triangles().len(),
        m.samples,
        m.k,
        seg.kind.as_str(),
        m.f,
        m.tov,
        m.mov,
    );
    // A closed stdout (e.g. `| head -1`) is not worth a panic, but is worth saying so.
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write to stdout")
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    fn parse(args: &[&str]) -> Result<SegmentArgs, clap::Error> {
        let mut v = vec!["bvseg", "segment"];
        v.extend_from_slice(args);
        Cli::try_parse_from(v).map(|c| match c.command {
            Command::Segment(a) => a,
            _ => unreachable!("parsed as segment"),
        })
    }

    #[test]
    fn defaults_come_from_the_core() {
        let a = parse(&[]).unwrap();
        let d = Params::default();
        assert_eq!(
            (a.tov, a.mov, a.max_k, a.samples, a.seed),
            (d.tov, d.mov, d.max_k, d.samples, d.seed)
        );
        assert_eq!(BoundingKind::from(a.bv), d.bounding);
        assert!(a.mesh.is_none() && a.k.is_none() && a.output.is_none() && a.threads.is_none());
    }

    #[test]
    fn k_conflicts_with_tolerances() {
        assert!(parse(&["--k", "3"]).is_ok());
        assert!(parse(&["--tov", "0.2", "--mov", "0.4"]).is_ok());
        for extra in [["--tov", "0.2"], ["--mov", "0.4"]] {
            let e = parse(&["--k", "3", extra[0], extra[1]]).unwrap_err();
            assert_eq!(e.kind(), clap::error::ErrorKind::ArgumentConflict);
            assert_eq!(e.exit_code(), 2);
        }
    }

    #[test]
    fn options_parse() {
        let a = parse(&[
            "m.obj",
            "--bv",
            "mixed",
            "--threads",
            "3",
            "-o",
            "x.json",
            "--no-merge",
            "--no-polish",
            "-q",
            "--samples",
            "5000",
            "--seed",
            "7",
            "--max-k",
            "9",
        ])
        .unwrap();
        assert_eq!(a.mesh.as_deref(), Some(Path::new("m.obj")));
        assert_eq!(a.bv, Bv::Mixed);
        assert_eq!(a.threads, Some(3));
        assert!(a.no_merge && a.no_polish && a.quiet);
        assert_eq!((a.samples, a.seed, a.max_k), (5000, 7, 9));
        assert!(parse(&["--threads", "0"]).is_err());
        assert!(parse(&["--bv", "sphere"]).is_err());
    }

    #[test]
    fn output_must_be_json_in_an_existing_directory() {
        assert!(check_output(Path::new("out.json")).is_ok());
        assert!(check_output(Path::new("OUT.JSON")).is_ok());
        let e = check_output(Path::new("out.ply")).unwrap_err().to_string();
        assert_eq!(
            e,
            "out.ply: unsupported output format '.ply' (supported: .json)"
        );
        let e = check_output(Path::new("no/such/dir/out.json"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not exist"), "{e}");
    }

    #[test]
    fn embedded_mesh_equals_the_file() {
        let disk = bvseg_io::load_obj(BUNDLED_MESH).unwrap();
        let embedded = bvseg_io::load_obj_from_bytes(BUNDLED_BYTES, BUNDLED_NAME).unwrap();
        assert_eq!(disk, embedded);
    }

    #[test]
    fn causes_are_not_repeated() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e: anyhow::Error = IoError::Io {
            name: "a.obj".into(),
            action: "open",
            source: io,
        }
        .into();
        assert_eq!(one_line(&e), "a.obj: cannot open: gone");
        let e = anyhow!("multi\nline").context("outer");
        assert_eq!(one_line(&e), "outer: multi line");
    }
}
