//! What the subcommands share: the segmentation options, loading a mesh with its report,
//! running the segmentation with progress, and error formatting.
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail};
use bvseg_core::{
    Cancel, Kinds, Mesh, Params, Sampling, Segmentation, Segmenter, SkeletonMode, Step, Target,
};
use bvseg_io::export::{OutputFormat, UpAxis, UsdOptions};
use bvseg_io::{LoadOptions, LoadedMesh};
use clap::Args;

use crate::progress::Progress;

/// The mesh used when none is given, as it sits in the source tree.
const BUNDLED_MESH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");
/// How messages name the bundled mesh (the absolute source path would only confuse).
const BUNDLED_NAME: &str = "assets/meshes/bunny.obj";
/// The same mesh compiled in, so that an installed binary works away from the source tree.
const BUNDLED_BYTES: &[u8] = include_bytes!("../../../assets/meshes/bunny.obj");

/// Default of `--max-triangles`: beyond it a run takes minutes and gigabytes.
pub const DEFAULT_MAX_TRIANGLES: usize = 5_000_000;
/// Default of `--max-samples`.
pub const DEFAULT_MAX_SAMPLES: usize = 5_000_000;

/// Which part of the file to read, and how large it may be.
#[derive(Args, Debug, Clone, Default)]
pub struct InputArgs {
    /// OBJ: segment only the object or group with this name.
    #[arg(long, value_name = "NAME")]
    pub object: Option<String>,

    /// glTF/GLB: segment only the scene nodes whose mesh has this name.
    #[arg(long = "mesh", value_name = "NAME")]
    pub mesh_name: Option<String>,

    /// Refuse meshes with more triangles than this.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_TRIANGLES)]
    pub max_triangles: usize,
}

/// What a `.usda` output declares: the stage's up axis and units, and whether its root is a
/// rigid body. The volumes are written in the mesh's own coordinates either way.
#[derive(Args, Debug, Clone)]
pub struct UsdArgs {
    /// USD output: the stage's upAxis, Y or Z. It declares the mesh's convention and does
    /// not rotate anything (glTF files are Y-up; URDF, MuJoCo and many CAD exports Z-up).
    #[arg(long, value_name = "Y|Z", value_parser = parse_up_axis, default_value = "Y")]
    pub up_axis: UpAxis,

    /// USD output: the stage's metersPerUnit, the length of one mesh unit in meters (0.01
    /// for a mesh in centimeters). It declares the units and does not scale anything.
    #[arg(long, value_name = "M", value_parser = parse_meters_per_unit, default_value_t = 1.0)]
    pub meters_per_unit: f64,

    /// USD output: make the root prim a rigid body (PhysicsRigidBodyAPI), its colliders one
    /// compound; without it they are static colliders.
    #[arg(long)]
    pub usd_rigid_body: bool,
}

impl UsdArgs {
    /// The writer's options.
    pub fn options(&self) -> UsdOptions {
        UsdOptions {
            up_axis: self.up_axis,
            meters_per_unit: self.meters_per_unit,
            rigid_body: self.usd_rigid_body,
        }
    }
}

fn parse_up_axis(s: &str) -> Result<UpAxis, String> {
    match s {
        "Y" | "y" => Ok(UpAxis::Y),
        "Z" | "z" => Ok(UpAxis::Z),
        _ => Err(format!("expected Y or Z, got {s:?}")),
    }
}

fn parse_meters_per_unit(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(m) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(format!("expected a number above 0, got {s:?}")),
    }
}

/// The segmentation's parameters.
#[derive(Args, Debug, Clone)]
pub struct ParamArgs {
    /// Exactly this many parts, instead of refining until the tolerances hold.
    #[arg(long, value_name = "K", conflicts_with_all = ["tov", "mov", "max_protrusion", "max_protrusion_abs"])]
    pub k: Option<usize>,

    /// Tolerance on the total outside volume TOV (relative to the mesh's volume).
    #[arg(long, value_name = "T", default_value_t = Params::default().tov)]
    pub tov: f64,

    /// Tolerance on the protrusion (how far the volumes reach beyond the surface), as a
    /// fraction of the mesh's bounding-box diagonal.
    #[arg(long, value_name = "D", default_value_t = Params::default().max_protrusion)]
    pub max_protrusion: f64,

    /// Tolerance on the protrusion in mesh units (instead of --max-protrusion).
    #[arg(long, value_name = "D", conflicts_with = "max_protrusion")]
    pub max_protrusion_abs: Option<f64>,

    /// Also refine until the largest per-part outside volume MOV is below M (the paper's
    /// sigma_L; off by default: flat ends and pointed tips keep MOV above 0.5 whatever k).
    #[arg(long, value_name = "M")]
    pub mov: Option<f64>,

    /// Largest number of parts the tolerance loop may reach.
    #[arg(long, value_name = "N", default_value_t = Params::default().max_k)]
    pub max_k: usize,

    /// How the mesh is bounded: `auto` (the default) partitions the sampled interior of a
    /// closed solid (the paper's method) and fits clusters of triangles where there is no
    /// interior to sample (open or thin pieces, props made of pieces one volume each holds,
    /// skinned characters); `lattice` or `surface` forces one (docs/method.md).
    #[arg(long, value_name = "auto|lattice|surface", default_value_t = Params::default().route)]
    pub route: bvseg_core::Route,

    /// Most volumes per bone of a skinned character (surface route): 1 gives one volume per
    /// bone that moves triangles, a ragdoll. Default 3.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub per_bone: Option<u64>,

    /// Kinds of volume a part may get, as a comma list of ellipsoid, obb (or box), sphere,
    /// capsule, cylinder, hull; mixed = ellipsoid,obb. Each part gets the kind that adds the
    /// least outside volume. Default: every primitive (no hull).
    #[arg(long = "bv", value_name = "KINDS", value_parser = parse_kinds, default_value_t = Params::default().kinds)]
    pub bv: Kinds,

    /// The kinds an engine takes natively: mujoco, gltf, parry (rapier, avian), physx
    /// (isaac) or usd; NAME-hull adds convex hulls (e.g. parry-hull).
    #[arg(long, value_name = "NAME", value_parser = parse_target, conflicts_with = "bv")]
    pub target: Option<Kinds>,

    /// Most vertices of a hull volume (engines cap convex meshes; PhysX at 255).
    #[arg(long, value_name = "N", default_value_t = Params::default().max_hull_vertices)]
    pub max_hull_vertices: usize,

    /// Target number of interior samples.
    #[arg(long, value_name = "N", default_value_t = Params::default().samples)]
    pub samples: usize,

    /// Refuse a --samples above this (memory and time grow with it).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_SAMPLES)]
    pub max_samples: usize,

    /// Seed of the initialisation with --k (the tolerance mode does not use it); equal seeds give identical results.
    #[arg(long, value_name = "S", default_value_t = Params::default().seed)]
    pub seed: u64,

    /// Number of worker threads (default: one per core). The result does not depend on it.
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub threads: Option<u64>,

    /// Do not merge adjacent parts at the end of the tolerance loop.
    #[arg(long)]
    pub no_merge: bool,

    /// Do not tighten: no moves of boundary layers between parts to lower the outside volume
    /// (during refinement and before the final step) and no reshaping or change of kind of
    /// the output volumes. The moves that lower F while the parts are optimised still run.
    #[arg(long, alias = "no-polish")]
    pub no_tighten: bool,

    /// JSON output: leave the bounding-volume hierarchy empty instead of building it (about a
    /// sixth of a default run's time).
    #[arg(long)]
    pub no_hierarchy: bool,

    /// Exit with code 3 when the tolerances are not met within --max-k.
    #[arg(long)]
    pub strict: bool,

    /// Grow every volume outward by D (mesh units), so that engines that store the volumes or
    /// the mesh in f32 keep the enclosure (see the docs: about 1e-6 of the largest coordinate).
    #[arg(long, value_name = "D", default_value_t = Params::default().margin)]
    pub margin: f64,

    /// Where the first parts are seeded from (the paper's section 6.1): `rig` (the default)
    /// uses the mesh's own skeleton when it has one (a skinned glTF's), `auto` computes an
    /// approximate curve skeleton, `none` grows parts from one, and any other value is the
    /// path of a `bvseg.skeleton/1` file (docs/formats.md) for an unskinned mesh, used as its
    /// own (`segment` only; write `./auto` for a file named `auto`). A skinned mesh's volumes
    /// follow its animation whichever start is chosen.
    #[arg(long, value_name = "rig|auto|none|FILE", default_value = "rig", value_parser = parse_skeleton)]
    pub skeleton: SkeletonArg,

    /// How the inside is sampled (the paper's section 6.2): `regular`, one sample per cell of
    /// a lattice, or `adaptive`, a finer lattice whose thick inside is gathered into weighted
    /// blocks, so that thin features get more samples at the same --samples
    #[arg(long, value_name = "regular|adaptive", default_value = "regular", value_parser = str::parse::<Sampling>)]
    pub sampling: Sampling,

    /// Give up after this many seconds of segmentation: exit 2, write nothing.
    #[arg(long, value_name = "SECONDS", value_parser = parse_timeout)]
    pub timeout: Option<f64>,
}

/// A `--skeleton` value: a start mode, or a skeleton file to attach to the mesh.
#[derive(Debug, Clone, PartialEq)]
pub enum SkeletonArg {
    /// `rig` (or `skin`, its former name), `auto` or `none`.
    Mode(SkeletonMode),
    /// A `bvseg.skeleton/1` file, attached to the mesh as its rig (the start is then
    /// [`SkeletonMode::Rig`]).
    Path(PathBuf),
}

impl SkeletonArg {
    /// The start mode the core runs with: a file's skeleton is the mesh's own once attached.
    pub fn mode(&self) -> SkeletonMode {
        match self {
            Self::Mode(m) => *m,
            Self::Path(_) => SkeletonMode::Rig,
        }
    }
}

/// A `--skeleton` value: a mode name, else a path.
fn parse_skeleton(s: &str) -> Result<SkeletonArg, String> {
    if s.is_empty() {
        return Err("expected rig, auto, none or the path of a skeleton file".into());
    }
    Ok(s.parse()
        .map_or_else(|_| SkeletonArg::Path(s.into()), SkeletonArg::Mode))
}

/// A positive number of seconds, at most a year.
fn parse_timeout(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t > 0.0 && t <= 3.2e7 => Ok(t),
        Ok(_) => Err("must be a number of seconds above 0 (and at most a year)".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// A `--bv` list.
fn parse_kinds(s: &str) -> Result<Kinds, String> {
    s.parse::<Kinds>().map_err(|e| e.to_string())
}

/// A `--target` name.
fn parse_target(s: &str) -> Result<Kinds, String> {
    Target::kinds_of(s).ok_or_else(|| {
        let names: Vec<&str> = Target::ALL.iter().map(|t| t.as_str()).collect();
        format!(
            "unknown target {s:?}: expected one of {} (or rapier, avian, isaac), \
             optionally with -hull",
            names.join(", ")
        )
    })
}

impl ParamArgs {
    /// `mesh` with the skeleton `--skeleton FILE` names attached (unchanged for a mode).
    pub fn rigged(&self, mesh: &Mesh) -> anyhow::Result<Mesh> {
        let SkeletonArg::Path(path) = &self.skeleton else {
            return Ok(mesh.clone());
        };
        if mesh.rig().is_some_and(|r| r.skin.is_some()) {
            bail!(
                "--skeleton {}: the mesh is skinned and uses its own skin's skeleton; \
                 a skeleton file is for unskinned meshes (use --skeleton rig, auto or none)",
                path.display()
            );
        }
        let skeleton = bvseg_io::read_skeleton(path)?;
        let rig = bvseg_core::Rig {
            skeleton,
            skin: None,
        };
        mesh.clone()
            .with_rig(rig)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// An error when `--skeleton` names a file: `command` segments many meshes and attaches
    /// no skeleton file.
    pub fn no_skeleton_file(&self, command: &str) -> anyhow::Result<()> {
        if let SkeletonArg::Path(path) = &self.skeleton {
            bail!(
                "--skeleton {}: `bvseg {command}` takes rig, auto or none; a skeleton file is \
                 for `bvseg segment` on one unskinned mesh",
                path.display()
            );
        }
        Ok(())
    }

    /// The core's parameters, validated, and within `--max-samples`, for a run that writes
    /// `formats` (the hierarchy is built only when one of them carries it).
    pub fn params(&self, formats: &[OutputFormat]) -> anyhow::Result<Params> {
        if self.samples > self.max_samples {
            bail!(
                "--samples {} is above --max-samples {}; raise --max-samples if you mean it",
                self.samples,
                self.max_samples
            );
        }
        let params = Params {
            samples: self.samples,
            seed: self.seed,
            kinds: self.target.unwrap_or(self.bv),
            max_hull_vertices: self.max_hull_vertices,
            k: self.k,
            tov: self.tov,
            mov: self.mov,
            max_protrusion: self.max_protrusion,
            max_protrusion_abs: self.max_protrusion_abs,
            max_k: self.max_k,
            merge: !self.no_merge,
            tighten: !self.no_tighten,
            margin: self.margin,
            hierarchy: !self.no_hierarchy && formats.iter().any(|f| f.carries_hierarchy()),
            // A skeleton file is attached to the mesh (see `rigged`) and used as its own.
            skeleton: self.skeleton.mode(),
            sampling: self.sampling,
            route: self.route,
            per_bone: self.per_bone.map(|n| n as usize),
            ..Params::default()
        };
        params.validate()?;
        Ok(params)
    }
}

/// Loads `path` (or the bundled mesh), enforcing `--max-triangles`. Returns the name
/// messages use and the mesh with its report.
pub fn load(
    path: Option<&Path>,
    input: &InputArgs,
    quiet: bool,
) -> anyhow::Result<(String, LoadedMesh)> {
    let options = LoadOptions {
        object: input.object.clone(),
        mesh: input.mesh_name.clone(),
    };
    let (name, loaded) = match path {
        Some(path) => (path.display().to_string(), bvseg_io::load(path, &options)?),
        None => {
            if !quiet {
                eprintln!("bvseg: no mesh given; using the bundled {BUNDLED_NAME}");
            }
            let loaded = if Path::new(BUNDLED_MESH).is_file() {
                bvseg_io::load(BUNDLED_MESH, &options)
            } else {
                bvseg_io::load_bytes(BUNDLED_BYTES, BUNDLED_NAME, &options)
            };
            (BUNDLED_NAME.to_owned(), loaded?)
        }
    };
    let n = loaded.mesh.triangles().len();
    if n > input.max_triangles {
        bail!(
            "{name}: {n} triangles is above --max-triangles {}; raise it to proceed \
             (or decimate the mesh)",
            input.max_triangles
        );
    }
    Ok((name, loaded))
}

/// Like [`load`], also refusing a mesh that encloses no volume, before any warning about
/// it is printed: the user gets the one line that matters.
pub fn load_solid(
    path: Option<&Path>,
    input: &InputArgs,
    quiet: bool,
) -> anyhow::Result<(String, LoadedMesh)> {
    let (name, loaded) = load(path, input, quiet)?;
    if loaded.encloses_no_volume() {
        let r = &loaded.report;
        bail!(
            "{name}: the mesh encloses no volume (flat, open or degenerate: {} triangles, {} open edges)",
            r.triangles,
            r.open_edges
        );
    }
    Ok((name, loaded))
}

/// When and how a run gives up.
#[derive(Debug, Clone, Copy, Default)]
pub struct Deadline {
    /// Seconds the run may take (`--timeout`).
    pub seconds: Option<f64>,
    /// Whether to end the whole process if the run does not stop soon after its time is up
    /// (one run per process: `segment`; not `batch`, whose other files go on).
    pub exit_when_stuck: bool,
}

/// Runs the segmentation with progress display, in a pool of `threads` when given, giving
/// up at the deadline.
pub fn run_segmentation(
    name: &str,
    mesh: &Mesh,
    params: &Params,
    threads: Option<u64>,
    deadline: Deadline,
    progress: &Progress,
    on_step: impl FnMut(&Step) + Send,
) -> anyhow::Result<Segmentation> {
    let cancel = Cancel::new();
    let timeout = deadline.seconds;
    let timer = timeout.map(|t| Timer::start(t, name, cancel.clone(), deadline.exit_when_stuck));
    let failed = |e: bvseg_core::Error| match (e, timeout) {
        (bvseg_core::Error::Cancelled, Some(t)) => {
            anyhow!("{name}: gave up after {t} s (--timeout); nothing written")
        }
        (e, _) => anyhow!("{name}: {e}"),
    };
    let work = || -> anyhow::Result<Segmentation> {
        let mut on_step = on_step;
        progress.sampling();
        let mut seg = Segmenter::with_cancel(mesh, params, cancel.clone()).map_err(failed)?;
        progress.refining(params);
        while let Some(step) = seg.step() {
            progress.step(&step);
            on_step(&step);
        }
        progress.done();
        seg.finish().map_err(failed)
    };
    let result = in_pool(threads, work);
    drop(timer);
    result
}

/// Sets a [`Cancel`] flag when its time is up, unless dropped first. The run checks the flag
/// between bounded pieces of work; should one of them still be running a few seconds later,
/// the timer ends the process itself (exit code 2, nothing written: outputs are written
/// after the run, and the timer is dropped before).
pub struct Timer {
    _disarm: std::sync::mpsc::Sender<()>,
}

/// How long the timer waits for the run to notice the flag before ending the process.
const TIMEOUT_GRACE: std::time::Duration = std::time::Duration::from_secs(3);

impl Timer {
    /// Sets `cancel` after `seconds`; with `exit_when_stuck`, also ends the process (exit code
    /// 2, a line naming `name`) when the run has not stopped a few seconds later.
    pub fn start(seconds: f64, name: &str, cancel: Cancel, exit_when_stuck: bool) -> Self {
        let (tx, rx) = std::sync::mpsc::channel::<()>();
        let name = name.to_owned();
        let limit = std::time::Duration::from_secs_f64(seconds);
        std::thread::spawn(move || {
            use std::sync::mpsc::RecvTimeoutError::Timeout;
            if rx.recv_timeout(limit) != Err(Timeout) {
                return;
            }
            cancel.cancel();
            if exit_when_stuck && rx.recv_timeout(TIMEOUT_GRACE) == Err(Timeout) {
                eprintln!(
                    "bvseg: error: {name}: gave up after {seconds} s (--timeout); nothing written"
                );
                std::process::exit(2);
            }
        });
        Self { _disarm: tx }
    }
}

#[cfg(feature = "parallel")]
pub fn in_pool<T: Send>(
    threads: Option<u64>,
    work: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    let Some(threads) = threads else {
        return work();
    };
    use anyhow::Context;
    let pool = rayon::ThreadPoolBuilder::new()
        // Bounded to 4096 by the argument parser.
        .num_threads(threads as usize)
        .build()
        .with_context(|| format!("cannot start {threads} threads"))?;
    pool.install(work)
}

#[cfg(not(feature = "parallel"))]
pub fn in_pool<T: Send>(
    _threads: Option<u64>,
    work: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    work()
}

/// Checks that `out` can be written: a known format (when `check_format`) in an existing
/// directory. Done before the run, so that a typo does not cost the whole run.
pub fn check_output(out: &Path, check_format: bool) -> anyhow::Result<()> {
    if check_format {
        bvseg_io::export::OutputFormat::from_path(out)?;
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

/// The error and its causes on one line. Our errors often already quote their cause (an
/// `IoError` names the OS error it wraps), so a cause already in the text is not repeated.
pub fn one_line(e: &anyhow::Error) -> String {
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

/// Paths as strings for JSON and CSV.
pub fn shown(p: &[PathBuf]) -> Vec<String> {
    p.iter().map(|p| p.display().to_string()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvseg_io::IoError;

    #[test]
    fn embedded_mesh_equals_the_file() {
        let options = LoadOptions::default();
        let disk = bvseg_io::load(BUNDLED_MESH, &options).unwrap();
        let embedded = bvseg_io::load_bytes(BUNDLED_BYTES, BUNDLED_NAME, &options).unwrap();
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

    #[test]
    fn outputs_are_checked_before_the_run() {
        assert!(check_output(Path::new("out.json"), true).is_ok());
        assert!(check_output(Path::new("OUT.GLB"), true).is_ok());
        assert!(check_output(Path::new("m.xml"), true).is_ok());
        let e = check_output(Path::new("out.ply"), true)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "out.ply: unsupported output format '.ply' (supported: .json, .glb, .xml (MJCF), .obj, \
             .usda)"
        );
        let e = check_output(Path::new("no/such/dir/out.json"), true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not exist"), "{e}");
    }
}
