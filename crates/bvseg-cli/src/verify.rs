//! `bvseg verify MESH VOLUMES.json`: an independent check of a volumes file against a mesh
//! (the `bvseg-verify` crate, which shares no code with the core or the I/O crate). Exit 0
//! when every triangle is enclosed, 1 when some point of the mesh escapes the union of the
//! volumes, 2 on bad input.
use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{anyhow, Context};
use bvseg_io::VolumesFile;
use bvseg_verify::{verify, ReportContext, VerifyOptions, VerifyReport, Volumes};
use clap::Args;

/// Arguments of `bvseg verify`.
#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// Mesh file (.obj).
    #[arg(value_name = "MESH")]
    mesh: PathBuf,

    /// Volumes file (bvseg.volumes/1 JSON), as `bvseg segment -o` writes it.
    #[arg(value_name = "VOLUMES.json")]
    volumes: PathBuf,

    /// Points of the jittered grid that measures the outside volumes.
    #[arg(long, value_name = "N", default_value_t = VerifyOptions::default().points)]
    points: usize,

    /// Seed of the grid's jitter.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,

    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Runs `bvseg verify`.
pub fn run(args: &VerifyArgs) -> anyhow::Result<ExitCode> {
    let mesh = bvseg_io::load(&args.mesh, &bvseg_io::LoadOptions::default())?.mesh;
    // The file is validated by bvseg-io's reader, as everywhere (its checks and messages),
    // then handed as text to the verifier, which reads it with its own parser.
    let (file, doc) = read_volumes_text(&args.volumes)?;
    let name = args.volumes.display();
    let volumes = Volumes::from_json(&doc).map_err(|e| anyhow!("{name}: {e}"))?;
    let vertices: Vec<[f64; 3]> = mesh.vertices().iter().map(|v| v.to_array()).collect();
    let opts = VerifyOptions {
        points: args.points,
        seed: args.seed,
        threads: threads(),
        ..VerifyOptions::default()
    };
    let report = verify(&vertices, mesh.triangles(), &volumes, &opts)
        .map_err(|e| anyhow!("{}: {e}", args.mesh.display()))?;
    let text = if args.json {
        json_report(args, &file, &report) + "\n"
    } else {
        summary(args, &file, &report)
    };
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write to stdout")?;
    Ok(if report.all_enclosed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The volumes file, validated by [`bvseg_io::read_volumes`] (whose messages name what is
/// wrong), and its text. The text is read once more and validated again, so that what is
/// verified is what was validated even if the file changed in between.
fn read_volumes_text(path: &std::path::Path) -> anyhow::Result<(VolumesFile, String)> {
    bvseg_io::read_volumes(path)?;
    let name = path.display().to_string();
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| {
            f.take(bvseg_io::MAX_VOLUMES_BYTES + 1)
                .read_to_end(&mut bytes)
        })
        .with_context(|| format!("{name}: cannot read"))?;
    let file = bvseg_io::parse_volumes(&bytes, &name)?;
    // Valid JSON, hence UTF-8.
    let text = String::from_utf8(bytes).map_err(|e| anyhow!("{name}: not UTF-8: {e}"))?;
    Ok((file, text))
}

/// The verifier's threads: as many as the segmentation's rayon pool would take by default
/// (`RAYON_NUM_THREADS` when set, else one per core), one without the `parallel` feature.
/// The report does not depend on it.
fn threads() -> Option<usize> {
    if cfg!(feature = "parallel") {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|s| s.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
    } else {
        Some(1)
    }
}

fn reported(x: Option<f64>) -> String {
    x.map(|v| format!("   (file: {v:.4})")).unwrap_or_default()
}

fn summary(args: &VerifyArgs, file: &VolumesFile, r: &VerifyReport) -> String {
    let mut s = format!(
        "mesh        {} ({} triangles, {}, vol(S) = {:.6e} {})\n\
         volumes     {} ({} volumes, {})\n",
        args.mesh.display(),
        r.triangles,
        if r.closed { "closed" } else { "NOT closed" },
        r.volume,
        if r.closed { "exact" } else { "grid estimate" },
        args.volumes.display(),
        file.volumes.len(),
        file.kind.as_str(),
    );
    if r.all_enclosed() {
        s += &format!(
            "enclosure   all {} triangles enclosed ({} in one volume, {} split across volumes, \
             {} down to the tolerance)\n",
            r.triangles, r.single, r.split, r.within_tolerance
        );
    } else {
        s += &format!(
            "enclosure   {} of {} triangles ESCAPE; max escape {:.3e} x diagonal (triangle {})\n",
            r.unenclosed,
            r.triangles,
            r.max_escape_rel,
            r.worst_triangle.map(|t| t.to_string()).unwrap_or_default()
        );
    }
    s += &format!(
        "TOV         {:.4} ± {:.4}{}\n",
        r.tov,
        r.tov_se,
        reported(file.reported.tov)
    );
    if let Some((mov, se, i)) = r.mov {
        s += &format!(
            "MOV         {mov:.4} ± {se:.4} (volume {i}){}\n",
            reported(file.reported.mov)
        );
    }
    if r.boundary_points > 0 {
        s += &format!(
            "protrusion  {:.4} x diagonal, {} points of the union's boundary{}\n",
            r.protrusion_rel,
            r.boundary_points,
            reported(file.reported.protrusion_rel)
        );
    }
    s += &format!(
        "interior    {:.3} % covered\n\
         grid        {} x {} x {} points, seed {}\n",
        100.0 * r.coverage_interior,
        r.grid[0],
        r.grid[1],
        r.grid[2],
        args.seed
    );
    s
}

fn json_report(args: &VerifyArgs, file: &VolumesFile, r: &VerifyReport) -> String {
    r.to_json(&ReportContext {
        mesh: &args.mesh.display().to_string(),
        volumes_file: &args.volumes.display().to_string(),
        kind: &file.kind,
        k: file.volumes.len(),
        reported_protrusion_rel: file.reported.protrusion_rel,
        reported_tov: file.reported.tov,
        reported_mov: file.reported.mov,
        seed: args.seed,
    })
}
