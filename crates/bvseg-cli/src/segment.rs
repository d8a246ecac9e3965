//! `bvseg segment`: one mesh in, the volumes out in every format asked for.
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use bvseg_core::{Params, Segmentation, Tolerance, BUDGET_WARNING};
use bvseg_io::export::{write_labels, write_output, ExportOptions, OutputFormat};
use bvseg_io::{CliSummary, LoadedMesh, RunSummary};
use clap::Args;

use crate::common::{self, InputArgs, ParamArgs, UsdArgs};
use crate::progress::Progress;
use crate::EXIT_TOLERANCE;

#[derive(Args, Debug)]
pub struct SegmentArgs {
    /// Mesh file (.obj, .gltf, .glb, .stl). Without it, the bundled Stanford bunny is used.
    #[arg(value_name = "MESH")]
    pub mesh: Option<PathBuf>,

    #[command(flatten)]
    pub input: InputArgs,

    #[command(flatten)]
    pub params: ParamArgs,

    /// Write the volumes here; the extension picks the format: .json (bvseg.volumes/1),
    /// .glb (glTF with colliders), .xml (MuJoCo MJCF), .obj (proxy meshes), .usda (USD with
    /// UsdPhysics colliders). Repeatable.
    #[arg(short, long, value_name = "FILE")]
    pub output: Vec<PathBuf>,

    /// GLB output: also include the input mesh, with vertex colours by part.
    #[arg(long)]
    pub with_mesh: bool,

    #[command(flatten)]
    pub usd: UsdArgs,

    /// Write one part index per triangle of the file to this text file (-1 for triangles
    /// dropped as degenerate).
    #[arg(long, value_name = "FILE.txt")]
    pub labels: Option<PathBuf>,

    /// Plot TOV and MOV against k over the refinement, with the tolerances, as SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,

    /// Print a machine-readable summary (JSON) on stdout instead of the text one.
    #[arg(long)]
    pub json: bool,

    /// Print nothing on stderr but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: &SegmentArgs) -> anyhow::Result<ExitCode> {
    check_outputs(args)?;
    let formats: Vec<OutputFormat> = args
        .output
        .iter()
        .filter_map(|o| OutputFormat::from_path(o).ok())
        .collect();
    let params = args.params.params(&formats)?;

    let (name, loaded) = common::load_solid(args.mesh.as_deref(), &args.input, args.quiet)?;
    let mut warnings = loaded.warnings();
    if !args.quiet {
        for w in &warnings {
            eprintln!("bvseg: warning: {name}: {w}");
        }
    }
    let LoadedMesh { mesh, .. } = &loaded;
    let mesh = &args.params.rigged(mesh)?;

    let start = Instant::now();
    let progress = Progress::new(args.quiet);
    let seg = common::run_segmentation(
        &name,
        mesh,
        &params,
        args.params.threads,
        common::Deadline {
            seconds: args.params.timeout,
            exit_when_stuck: true,
        },
        &progress,
        |_| {},
    )?;
    let seconds = start.elapsed().as_secs_f64();
    if seg.budget_exhausted {
        let w = BUDGET_WARNING.to_owned();
        if !args.quiet {
            eprintln!("bvseg: warning: {name}: {w}");
        }
        warnings.push(w);
    }

    let options = ExportOptions {
        mesh: args.with_mesh.then_some(mesh),
        skinning: loaded.skinning.as_deref(),
        usd: args.usd.options(),
    };
    for out in &args.output {
        write_output(out, &seg, &options)?;
    }
    if let Some(path) = &args.labels {
        write_labels(path, &seg, &loaded.dropped)?;
    }
    if let Some(path) = &args.plot {
        let svg = crate::plot::svg(&seg, &params, &name);
        bvseg_io::write_atomic(path, svg.as_bytes())?;
    }

    let met = seg.tolerances_met(&params);
    if args.json {
        print_json(
            &name,
            &loaded,
            &seg,
            &params,
            seconds,
            &args.output,
            &warnings,
        )?;
    } else {
        print_summary(&name, &loaded, &seg, seconds, &args.output)?;
    }
    if met == Some(false) {
        let (what, hint) = unmet_message(&seg, &params);
        if args.params.strict {
            eprintln!("bvseg: error: {name}: {what}");
            return Ok(ExitCode::from(EXIT_TOLERANCE));
        }
        if !args.quiet {
            eprintln!("bvseg: warning: {what}; {hint}");
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// What a tolerance-mode run left unmet, naming only the tolerances it was asked for, and
/// what would help.
pub fn unmet_message(seg: &Segmentation, params: &Params) -> (String, String) {
    let m = &seg.metrics;
    let unmet = seg.unmet(params);
    let parts: Vec<String> = unmet
        .iter()
        .map(|u| {
            let (value, tol) = (u.value, u.limit);
            match u.tolerance {
                Tolerance::Tov => format!("TOV {value:.3} vs {tol}"),
                Tolerance::Protrusion => format!(
                    "protrusion {:.4} vs {:.4} of the diagonal",
                    value / m.diagonal,
                    tol / m.diagonal
                ),
                _ => format!("MOV {value:.3} vs {tol}"),
            }
        })
        .collect();
    let what = format!("tolerances not met at k = {} ({})", m.k, parts.join(", "));
    let mov_only = unmet.iter().all(|u| u.tolerance == Tolerance::Mov);
    let surface = seg.route == bvseg_core::Route::Surface;
    let hint = if surface && seg.skeleton.is_some() {
        "each bone's volumes enclose its triangles in every pose, which keeps them loose at \
         rest; raise --per-bone, or loosen --max-protrusion"
    } else if surface && m.k < params.max_k {
        "splitting stopped paying: what protrudes is single triangles (or pieces) that no \
         volume of these kinds holds more tightly; add hull to --bv, or loosen \
         --max-protrusion"
    } else if surface {
        "the part budget ran out: raise --max-k, or loosen --max-protrusion"
    } else if mov_only {
        "flat ends and pointed tips keep MOV up whatever k (docs/method.md, \"What MOV can \
         reach\"); raise --mov or leave it out"
    } else if m.k < params.max_k {
        "splitting stopped paying: the last splits did not bring the missed figures down, so \
         more parts would not either; a finer lattice (--samples), hulls (--bv with hull) or \
         looser --tov or --max-protrusion may"
    } else {
        "the part budget ran out: raise --max-k, or loosen --tov or --max-protrusion"
    };
    (what, hint.to_owned())
}

/// Every output checked before the (possibly long) run.
fn check_outputs(args: &SegmentArgs) -> anyhow::Result<()> {
    for out in &args.output {
        common::check_output(out, true)?;
    }
    let glb = args
        .output
        .iter()
        .any(|o| matches!(OutputFormat::from_path(o), Ok(OutputFormat::Glb)));
    if args.with_mesh && !glb {
        bail!("--with-mesh applies to a .glb output; none was given with -o");
    }
    if let Some(l) = &args.labels {
        common::check_output(l, false)?;
    }
    if let Some(p) = &args.plot {
        if bvseg_io::extension(p).as_deref() != Some("svg") {
            bail!("{}: --plot writes SVG; name the file .svg", p.display());
        }
        common::check_output(p, false)?;
    }
    let mut seen: Vec<&Path> = Vec::new();
    let all = args.output.iter().chain(&args.labels).chain(&args.plot);
    for p in all {
        if seen.contains(&p.as_path()) {
            bail!("{}: named twice as an output", p.display());
        }
        seen.push(p);
    }
    Ok(())
}

fn print_summary(
    name: &str,
    loaded: &LoadedMesh,
    seg: &Segmentation,
    seconds: f64,
    outputs: &[PathBuf],
) -> anyhow::Result<()> {
    let m = &seg.metrics;
    let written = if outputs.is_empty() {
        "not written (use -o FILE.json, .glb, .xml, .obj or .usda)".to_owned()
    } else {
        common::shown(outputs).join(", ")
    };
    if seg.route == bvseg_core::Route::Surface {
        let text = format!(
            "mesh       {name}\n\
             triangles  {}\n\
             route      surface (clusters of triangles; no interior sampled, TOV not measured)\n\
             k          {} ({})\n\
             protrusion {:.6} of the diagonal ({:.6})\n\
             time       {seconds:.2} s\n\
             output     {written}\n",
            loaded.mesh.triangles().len(),
            m.k,
            shape_counts(seg),
            m.protrusion_rel,
            m.protrusion,
        );
        return write_stdout(&text);
    }
    let text = format!(
        "mesh       {name}\n\
         triangles  {}\n\
         samples    {}\n\
         k          {} ({})\n\
         F          {:.6}\n\
         TOV        {:.6}\n\
         protrusion {:.6} of the diagonal ({:.6})\n\
         MOV        {:.6}\n\
         time       {seconds:.2} s\n\
         output     {written}\n",
        loaded.mesh.triangles().len(),
        m.samples,
        m.k,
        shape_counts(seg),
        m.f,
        m.tov,
        m.protrusion_rel,
        m.protrusion,
        m.mov,
    );
    write_stdout(&text)
}

/// How many volumes of each shape, most first: `12 capsule, 10 ellipsoid`.
fn shape_counts(seg: &bvseg_core::Segmentation) -> String {
    let mut counts: Vec<(usize, bvseg_core::Shape)> = bvseg_core::Shape::ALL
        .into_iter()
        .map(|s| (seg.parts.iter().filter(|p| p.volume.shape == s).count(), s))
        .filter(|c| c.0 > 0)
        .collect();
    counts.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let parts: Vec<String> = counts
        .iter()
        .map(|(n, s)| format!("{n} {}", s.as_str()))
        .collect();
    parts.join(", ")
}

fn print_json(
    name: &str,
    loaded: &LoadedMesh,
    seg: &Segmentation,
    params: &Params,
    seconds: f64,
    outputs: &[PathBuf],
    warnings: &[String],
) -> anyhow::Result<()> {
    let summary = RunSummary {
        cli: Some(CliSummary::new(
            seg,
            params,
            loaded.mesh.triangles().len(),
            seconds,
            common::shown(outputs),
            warnings.to_vec(),
        )),
        ..RunSummary::new(name, seg)
    };
    // Keys sorted, as this summary has always been printed.
    write_stdout(&format!("{}\n", summary.to_json_sorted()))
}

pub fn write_stdout(text: &str) -> anyhow::Result<()> {
    // A closed stdout (e.g. `| head -1`) is not worth a panic, but is worth saying so.
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write to stdout")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::parse_segment as parse;
    use bvseg_core::{Kinds, Shape};

    #[test]
    fn the_hint_says_what_ended_the_run() {
        // Out of parts: a torus in one part.
        let torus = bvseg_core::shapes::torus(glam::DVec3::ZERO, 2.0, 0.5, 24);
        let params = Params {
            samples: 2000,
            max_k: 1,
            ..Params::default()
        };
        let seg = bvseg_core::segment(&torus, &params).unwrap();
        assert_eq!(seg.tolerances_met(&params), Some(false));
        assert!(unmet_message(&seg, &params)
            .1
            .contains("part budget ran out"));
        // A lone right triangle: no box holds it within the tolerance, and it cannot be cut.
        let v = vec![
            glam::DVec3::ZERO,
            glam::DVec3::new(1.0, 0.0, 0.0),
            glam::DVec3::new(0.0, 1.0, 0.0),
        ];
        let tri = bvseg_core::Mesh::new(v, vec![[0, 1, 2]]).unwrap();
        let params = Params::default();
        let seg = bvseg_core::segment(&tri, &params).unwrap();
        assert_eq!(seg.route, bvseg_core::Route::Surface);
        assert_eq!(seg.tolerances_met(&params), Some(false));
        let (what, hint) = unmet_message(&seg, &params);
        assert!(
            what.contains("protrusion") && !what.contains("TOV"),
            "{what}"
        );
        assert!(hint.contains("single triangles"), "{hint}");
    }

    #[test]
    fn defaults_come_from_the_core() {
        let a = parse(&[]).unwrap();
        let d = Params::default();
        let p = &a.params;
        assert_eq!(
            (p.tov, p.mov, p.max_k, p.samples, p.seed),
            (d.tov, d.mov, d.max_k, d.samples, d.seed)
        );
        assert_eq!(p.params(&[]).unwrap().kinds, d.kinds);
        assert_eq!(p.max_hull_vertices, d.max_hull_vertices);
        assert!(a.mesh.is_none() && p.k.is_none() && a.output.is_empty() && p.threads.is_none());
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
            "-o",
            "x.glb",
            "--no-merge",
            "--no-polish",
            "-q",
            "--samples",
            "5000",
            "--seed",
            "7",
            "--max-k",
            "9",
            "--strict",
            "--json",
            "--object",
            "body",
        ])
        .unwrap();
        assert_eq!(a.mesh.as_deref(), Some(Path::new("m.obj")));
        let p = &a.params;
        assert_eq!(p.bv, Kinds::MIXED);
        assert_eq!(p.threads, Some(3));
        assert!(p.no_merge && p.no_tighten && a.quiet && p.strict && a.json);
        assert_eq!((p.samples, p.seed, p.max_k), (5000, 7, 9));
        assert_eq!(a.output.len(), 2);
        assert_eq!(a.input.object.as_deref(), Some("body"));
        assert!(parse(&["--threads", "0"]).is_err());
        assert!(parse(&["--bv", "torus"]).is_err());
        let caps = parse(&["--bv", "obb,capsule"])
            .unwrap()
            .params
            .params(&[])
            .unwrap();
        assert_eq!(caps.kinds, Kinds::OBB.with(Shape::Capsule));
        let parry = parse(&["--target", "parry"])
            .unwrap()
            .params
            .params(&[])
            .unwrap();
        assert!(!parry.kinds.contains(Shape::Ellipsoid) && !parry.kinds.contains(Shape::Hull));
        let hull = parse(&["--target", "avian-hull", "--max-hull-vertices", "64"]).unwrap();
        let hp = hull.params.params(&[]).unwrap();
        assert!(hp.kinds.contains(Shape::Hull) && hp.max_hull_vertices == 64);
        assert!(parse(&["--target", "unity"]).is_err());
        assert!(parse(&["--target", "parry", "--bv", "sphere"]).is_err());
        let few = parse(&["--max-hull-vertices", "3"])
            .unwrap()
            .params
            .params(&[]);
        assert!(few.unwrap_err().to_string().contains("max_hull_vertices"));
    }

    #[test]
    fn no_tighten_has_the_former_name_as_an_alias() {
        for flag in ["--no-tighten", "--no-polish"] {
            let p = parse(&[flag]).unwrap().params.params(&[]).unwrap();
            assert!(!p.tighten, "{flag}");
        }
        assert!(parse(&[]).unwrap().params.params(&[]).unwrap().tighten);
    }

    #[test]
    fn skeleton_is_a_mode_or_a_file() {
        use crate::common::SkeletonArg;
        use bvseg_core::SkeletonMode;
        let skeleton = |args: &[&str]| parse(args).unwrap().params.skeleton;
        assert_eq!(skeleton(&[]), SkeletonArg::Mode(SkeletonMode::Rig));
        for (name, mode) in [
            ("rig", SkeletonMode::Rig),
            ("skin", SkeletonMode::Rig),
            ("auto", SkeletonMode::Auto),
            ("none", SkeletonMode::None),
        ] {
            assert_eq!(skeleton(&["--skeleton", name]), SkeletonArg::Mode(mode));
        }
        let file = parse(&["--skeleton", "./auto"]).unwrap().params;
        assert_eq!(file.skeleton, SkeletonArg::Path("./auto".into()));
        assert_eq!(file.params(&[]).unwrap().skeleton, SkeletonMode::Rig);
        let e = file.no_skeleton_file("batch").unwrap_err().to_string();
        assert!(e.contains("`bvseg batch` takes rig, auto or none"), "{e}");
        assert!(parse(&["--skeleton", ""]).is_err());
    }

    #[test]
    fn the_hierarchy_is_built_only_for_an_output_that_carries_it() {
        let p = parse(&[]).unwrap().params;
        let with = |formats: &[OutputFormat]| p.params(formats).unwrap().hierarchy;
        assert!(!with(&[]));
        assert!(!with(&[
            OutputFormat::Glb,
            OutputFormat::Mjcf,
            OutputFormat::Obj
        ]));
        assert!(with(&[OutputFormat::Glb, OutputFormat::Json]));
        let without = parse(&["--no-hierarchy"]).unwrap().params;
        assert!(!without.params(&[OutputFormat::Json]).unwrap().hierarchy);
    }

    #[test]
    fn sample_limit_is_enforced() {
        let a = parse(&["--samples", "20000", "--max-samples", "10000"]).unwrap();
        let e = a.params.params(&[]).unwrap_err().to_string();
        assert!(e.contains("above --max-samples 10000"), "{e}");
    }
}
