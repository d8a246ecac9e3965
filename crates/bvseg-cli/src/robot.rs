//! `bvseg robot`: a URDF or MJCF in, each link segmented in its own frame, and the robot out
//! with primitive colliders (URDF, MJCF, cuRobo spheres, a volumes document per link).
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use bvseg_core::{Kinds, Params, Segmentation, Shape};
use bvseg_io::export::OutputFormat;
use bvseg_io::robot::{self, MeshSource, Robot};
use clap::{Args, ValueEnum};

use crate::common::{self, Deadline, ParamArgs};
use crate::progress::Progress;

/// Which meshes of a link to segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SourceArg {
    /// URDF `<collision>` meshes; MJCF mesh geoms that collide.
    Collision,
    /// URDF `<visual>` meshes; every MJCF mesh geom.
    Visual,
}

#[derive(Args, Debug, Clone)]
pub struct RobotArgs {
    /// Robot file: URDF (.urdf) or MJCF (.xml).
    #[arg(value_name = "ROBOT")]
    pub robot: PathBuf,

    /// Directory to write <robot>.urdf, <robot>.xml, curobo.yml and links/<link>.json in
    /// (created if missing).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,

    /// Which meshes of each link to segment.
    #[arg(long, value_enum, default_value_t = SourceArg::Collision)]
    pub source: SourceArg,

    /// Most parts per link (sets --max-k for each link).
    #[arg(long, value_name = "N", conflicts_with = "total_parts")]
    pub max_parts: Option<usize>,

    /// Most parts for the whole robot, shared among links by their volume (each at least 1).
    #[arg(long, value_name = "N")]
    pub total_parts: Option<usize>,

    /// Most spheres per link in curobo.yml.
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub spheres_per_link: usize,

    /// Write capsules as URDF 1.1 <capsule> elements (otherwise no capsules in the URDF).
    #[arg(long)]
    pub urdf_capsules: bool,

    #[command(flatten)]
    pub params: ParamArgs,

    /// Print nothing on stderr but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Every output file and its bytes, computed before any is written.
pub struct RobotOutputs {
    /// (path, content), in writing order.
    pub files: Vec<(PathBuf, Vec<u8>)>,
    /// Parts per link, for the summary.
    pub parts: usize,
    /// Spheres over all links.
    pub spheres: usize,
    /// Links segmented.
    pub links: usize,
}

pub fn run(args: &RobotArgs) -> anyhow::Result<ExitCode> {
    let start = Instant::now();
    let out = compute(&args.robot, &args.output, args)?;
    write(&args.output, &out)?;
    if !args.quiet {
        eprintln!(
            "bvseg: {}: {} links, {} parts, {} spheres in {:.1} s -> {}",
            args.robot.display(),
            out.links,
            out.parts,
            out.spheres,
            start.elapsed().as_secs_f64(),
            args.output.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The URDF's kinds: those of `kinds` that URDF has (box, sphere, cylinder, and capsule with
/// `capsules`).
fn urdf_kinds(kinds: Kinds, capsules: bool) -> Kinds {
    let mut allowed = vec![Shape::Obb, Shape::Sphere, Shape::Cylinder];
    if capsules {
        allowed.push(Shape::Capsule);
    }
    let mut k: Option<Kinds> = None;
    for s in kinds.shapes().filter(|s| allowed.contains(s)) {
        k = Some(k.map_or(Kinds::only(s), |k| k.with(s)));
    }
    // None of the asked kinds exists in URDF: boxes, the closest to every other kind.
    k.unwrap_or(Kinds::OBB)
}

/// Reads the robot, segments every link with meshes, and renders every output.
pub fn compute(path: &Path, dir: &Path, args: &RobotArgs) -> anyhow::Result<RobotOutputs> {
    let source = match args.source {
        SourceArg::Collision => MeshSource::Collision,
        SourceArg::Visual => MeshSource::Visual,
    };
    let base = args.params.params(&[OutputFormat::Json])?;
    if args.spheres_per_link == 0 {
        bail!("--spheres-per-link must be at least 1");
    }
    let robot = robot::read_robot(path, source)?;
    let name = robot_file_name(&robot)?;
    // Every mesh is loaded (and so checked) before the first, slow, segmentation.
    let mut meshes = Vec::with_capacity(robot.links.len());
    for link in &robot.links {
        let m = robot.link_mesh(link)?;
        if let Some(m) = &m {
            if m.encloses_no_volume() {
                bail!(
                    "{}: link {:?}: its meshes enclose no volume",
                    robot.file,
                    link.name
                );
            }
        }
        meshes.push(m);
    }
    let budgets: Vec<Option<usize>> = match (args.total_parts, args.max_parts) {
        (Some(total), _) => {
            let volumes: Vec<Option<f64>> = meshes
                .iter()
                .map(|m| m.as_ref().map(|m| m.report.volume))
                .collect();
            robot::share_parts(&volumes, total)
                .into_iter()
                .map(Some)
                .collect()
        }
        (None, max) => vec![max; meshes.len()],
    };
    let progress = Progress::new(true);
    let mut prims: Vec<Option<Segmentation>> = Vec::new();
    let mut spheres: Vec<Option<Segmentation>> = Vec::new();
    let (mut parts, mut nspheres, mut links) = (0, 0, 0);
    for (i, (link, mesh)) in robot.links.iter().zip(&meshes).enumerate() {
        let Some(mesh) = mesh else {
            prims.push(None);
            spheres.push(None);
            continue;
        };
        let label = format!("{}: link {}", robot.file, link.name);
        let mut p = Params {
            kinds: urdf_kinds(base.kinds, args.urdf_capsules),
            ..base.clone()
        };
        if let Some(n) = budgets[i] {
            p.max_k = n.max(1);
            p.k = p.k.map(|k| k.min(p.max_k));
        }
        p.validate()?;
        let seg = segment(&label, &mesh.mesh, &p, args, &progress)?;
        let mut sp = Params {
            kinds: Kinds::SPHERE,
            max_k: args.spheres_per_link,
            k: base.k.map(|k| k.min(args.spheres_per_link)),
            hierarchy: false,
            ..base.clone()
        };
        sp.max_k = sp.max_k.max(1);
        sp.validate()?;
        let sph = segment(&label, &mesh.mesh, &sp, args, &progress)?;
        if !args.quiet {
            eprintln!(
                "bvseg: link {}: {} parts ({}), {} spheres",
                link.name,
                seg.parts.len(),
                seg.kinds,
                sph.parts.len()
            );
        }
        parts += seg.parts.len();
        nspheres += sph.parts.len();
        links += 1;
        prims.push(Some(seg));
        spheres.push(Some(sph));
    }
    let mut files = vec![
        (
            dir.join(format!("{name}.urdf")),
            robot::to_urdf(&robot, &prims, args.urdf_capsules).into_bytes(),
        ),
        (
            dir.join(format!("{name}.xml")),
            robot::to_mjcf_robot(&robot, &prims).into_bytes(),
        ),
        (
            dir.join("curobo.yml"),
            robot::to_curobo(&robot, &spheres).into_bytes(),
        ),
    ];
    for (link, seg) in robot.links.iter().zip(&prims) {
        if let Some(seg) = seg {
            files.push((
                dir.join("links")
                    .join(format!("{}.json", file_safe(&link.name))),
                bvseg_io::to_json_string(seg).into_bytes(),
            ));
        }
    }
    Ok(RobotOutputs {
        files,
        parts,
        spheres: nspheres,
        links,
    })
}

fn segment(
    label: &str,
    mesh: &bvseg_core::Mesh,
    params: &Params,
    args: &RobotArgs,
    progress: &Progress,
) -> anyhow::Result<Segmentation> {
    common::run_segmentation(
        label,
        mesh,
        params,
        args.params.threads,
        Deadline {
            seconds: args.params.timeout,
            exit_when_stuck: false,
        },
        progress,
        |_| {},
    )
}

/// The robot's name as a file name: its own name, else the file's stem.
fn robot_file_name(robot: &Robot) -> anyhow::Result<String> {
    let n = file_safe(&robot.name);
    if !n.is_empty() {
        return Ok(n);
    }
    let stem = Path::new(&robot.file)
        .file_stem()
        .map(|s| file_safe(&s.to_string_lossy()))
        .unwrap_or_default();
    if stem.is_empty() {
        bail!("{}: cannot name the outputs", robot.file);
    }
    Ok(stem)
}

/// A name with path separators and other awkward characters replaced by `_`.
fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect::<String>()
        .trim_start_matches('.')
        .to_owned()
}

/// Writes every output (each atomically), creating the directories.
pub fn write(dir: &Path, out: &RobotOutputs) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir.join("links"))
        .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
    for (path, bytes) in &out.files {
        bvseg_io::write_atomic(path, bytes)?;
    }
    Ok(())
}
