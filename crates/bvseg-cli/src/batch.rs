//! `bvseg batch DIR -o OUTDIR`: every mesh and robot in a directory, in parallel across files.
//!
//! Outputs are written atomically, so an output that exists is complete: a file whose
//! outputs all exist is skipped, which makes an interrupted batch resumable (a robot, whose
//! outputs fill a directory, is done when the file its run writes last exists). The summary
//! (`OUTDIR/summary.csv`, sorted by file name) holds no timings, so equal runs give equal
//! files.
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{bail, Context};
use bvseg_io::export::{write_output, ExportOptions, OutputFormat};
use bvseg_io::robot::RobotOptions;
use clap::Args;

use crate::common::{self, InputArgs, ParamArgs, UsdArgs};
use crate::progress::{batch_bar, Progress};
use crate::robot::{run_robot, RobotBudgetArgs};
use crate::EXIT_TOLERANCE;

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// Directory of meshes (.obj, .gltf, .glb, .stl) and robots (.urdf, MJCF .xml), not
    /// searched recursively. Each robot's outputs go to OUTDIR/<name>/, as `bvseg robot`
    /// writes them.
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,

    /// Directory for the outputs (created if missing).
    #[arg(short, long, value_name = "OUTDIR")]
    pub output: PathBuf,

    /// Output formats, by extension: json, glb, xml (MJCF), obj, usda.
    #[arg(
        long,
        value_name = "EXT",
        value_delimiter = ',',
        default_value = "json"
    )]
    pub formats: Vec<String>,

    /// Redo files whose outputs already exist.
    #[arg(long)]
    pub force: bool,

    #[command(flatten)]
    pub input: InputArgs,

    #[command(flatten)]
    pub params: ParamArgs,

    #[command(flatten)]
    pub robot: RobotBudgetArgs,

    #[command(flatten)]
    pub usd: UsdArgs,

    /// Print nothing on stderr but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// One input of a batch.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Input {
    path: PathBuf,
    robot: bool,
}

/// The outcome of one file, one CSV row.
struct Row {
    file: String,
    status: &'static str,
    triangles: String,
    k: String,
    tov: String,
    mov: String,
    tolerances_met: String,
    message: String,
}

pub fn run(args: &BatchArgs) -> anyhow::Result<ExitCode> {
    let mut exts = Vec::new();
    let mut formats = Vec::new();
    for f in &args.formats {
        let ext = f.trim().trim_start_matches('.').to_ascii_lowercase();
        let format = OutputFormat::from_path(Path::new(&format!("x.{ext}")))
            .with_context(|| format!("--formats: '{f}'"))?;
        if !exts.contains(&ext) {
            exts.push(ext);
            formats.push(format);
        }
    }
    args.params.no_skeleton_file("batch")?;
    let params = args.params.params(&formats)?;
    // A robot's links always get a JSON document, the format that carries the hierarchy.
    let robot_options = args
        .robot
        .options(args.params.params(&[OutputFormat::Json])?);
    let inputs = list_inputs(&args.dir)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create the directory", args.output.display()))?;
    let files: Vec<PathBuf> = inputs.iter().map(|i| i.path.clone()).collect();
    let bases = output_bases(&files);

    let start = Instant::now();
    let bar = batch_bar(files.len(), args.quiet);
    let done = AtomicUsize::new(0);
    let one = |(input, base): (&Input, &String)| -> Row {
        let path = &input.path;
        let row = if input.robot {
            let dir = args.output.join(base);
            if !args.force && dir.join(bvseg_io::robot::DONE_FILE).is_file() {
                skipped(path, None)
            } else {
                match process_robot(path, &dir, base, &robot_options, args) {
                    Ok(row) => row,
                    Err(e) => failed(path, &common::one_line(&e)),
                }
            }
        } else {
            let outs: Vec<PathBuf> = exts
                .iter()
                .map(|e| args.output.join(format!("{base}.{e}")))
                .collect();
            if !args.force && outs.iter().all(|o| o.is_file()) {
                skipped(path, Some(&args.output.join(format!("{base}.json"))))
            } else {
                match process(path, &outs, args, &params) {
                    Ok(row) => row,
                    Err(e) => failed(path, &common::one_line(&e)),
                }
            }
        };
        bar.inc(1);
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if !args.quiet && bar.is_hidden() {
            eprintln!(
                "[{n}/{}] {} {}{}",
                files.len(),
                row.status,
                row.file,
                if row.message.is_empty() {
                    String::new()
                } else {
                    format!(": {}", row.message)
                }
            );
        }
        row
    };
    let work: Vec<(&Input, &String)> = inputs.iter().zip(&bases).collect();
    let mut rows = common::in_pool(args.params.threads, || Ok(map(work, one)))?;
    bar.finish_and_clear();
    rows.sort_by(|a, b| a.file.cmp(&b.file));

    let csv = to_csv(&rows);
    let summary = args.output.join("summary.csv");
    bvseg_io::write_atomic(&summary, csv.as_bytes())?;
    let count = |s: &str| rows.iter().filter(|r| r.status == s).count();
    let (errors, unmet) = (
        count("error"),
        rows.iter().filter(|r| r.tolerances_met == "false").count(),
    );
    if !args.quiet {
        eprintln!(
            "bvseg: batch: {} done, {} skipped, {} failed, {} short of the tolerances in {:.1} s; summary in {}",
            count("done"),
            count("skipped"),
            errors,
            unmet,
            start.elapsed().as_secs_f64(),
            summary.display()
        );
    }
    if errors > 0 {
        return Ok(ExitCode::from(2));
    }
    if unmet > 0 && args.params.strict {
        return Ok(ExitCode::from(EXIT_TOLERANCE));
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(feature = "parallel")]
fn map<T: Send, R: Send>(items: Vec<T>, f: impl Fn(T) -> R + Sync + Send) -> Vec<R> {
    use rayon::prelude::*;
    items.into_par_iter().map(f).collect()
}

#[cfg(not(feature = "parallel"))]
fn map<T: Send, R: Send>(items: Vec<T>, f: impl Fn(T) -> R + Sync + Send) -> Vec<R> {
    items.into_iter().map(f).collect()
}

/// The mesh and robot files directly in `dir`, sorted: meshes by extension, robots as
/// `bvseg_io::robot::robot_format` tells them (every `.urdf`; an `.xml` whose root is
/// `<mujoco>` and that bvseg did not write), less the files a robot uses (its meshes, the
/// MJCF files it includes).
fn list_inputs(dir: &Path) -> anyhow::Result<Vec<Input>> {
    let entries = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read the directory", dir.display()))?;
    let mut files = Vec::new();
    for e in entries {
        let p = e
            .with_context(|| format!("{}: cannot read the directory", dir.display()))?
            .path();
        if !p.is_file() {
            continue;
        }
        let mesh = bvseg_io::extension(&p)
            .is_some_and(|e| bvseg_io::MESH_EXTENSIONS.contains(&e.as_str()));
        if mesh {
            files.push(Input {
                path: p,
                robot: false,
            });
        } else if bvseg_io::robot::robot_format(&p).is_some() {
            files.push(Input {
                path: p,
                robot: true,
            });
        }
    }
    // A robot's own meshes and included files are part of it, not inputs of their own.
    let used: std::collections::BTreeSet<PathBuf> = files
        .iter()
        .filter(|i| i.robot)
        .flat_map(|i| bvseg_io::robot::robot_uses(&i.path))
        .collect();
    files.retain(|i| i.path.canonicalize().map_or(true, |c| !used.contains(&c)));
    files.sort();
    if files.is_empty() {
        bail!(
            "{}: no mesh files ({}) nor robots (.urdf, MJCF .xml) in the directory",
            dir.display(),
            bvseg_io::MESH_EXTENSIONS.join(", ")
        );
    }
    Ok(files)
}

/// Output names: the file's stem, or its whole name where two inputs share a stem
/// (`part.obj` and `part.stl` give `part.obj.json` and `part.stl.json`).
fn output_bases(files: &[PathBuf]) -> Vec<String> {
    let stem = |p: &PathBuf| {
        p.file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned()
    };
    let mut count: HashMap<String, usize> = HashMap::new();
    for f in files {
        *count.entry(stem(f)).or_default() += 1;
    }
    files
        .iter()
        .map(|f| {
            let s = stem(f);
            if count[&s] > 1 {
                f.file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned()
            } else {
                s
            }
        })
        .collect()
}

fn process(
    path: &Path,
    outs: &[PathBuf],
    args: &BatchArgs,
    params: &bvseg_core::Params,
) -> anyhow::Result<Row> {
    let (name, loaded) = common::load_solid(Some(path), &args.input, true)?;
    // One file's steps would interleave with the others': no per-step display here.
    let deadline = common::Deadline {
        seconds: args.params.timeout,
        exit_when_stuck: false,
    };
    let seg = common::run_segmentation(
        &name,
        &loaded.mesh,
        params,
        None,
        deadline,
        &Progress::Quiet,
        |_| {},
    )?;
    for o in outs {
        let options = ExportOptions {
            usd: args.usd.options(),
            ..ExportOptions::default()
        };
        write_output(o, &seg, &options)?;
    }
    let m = seg.metrics;
    let met = seg.tolerances_met(params);
    let warnings = loaded.warnings();
    Ok(Row {
        file: file_name(path),
        status: "done",
        triangles: loaded.mesh.triangles().len().to_string(),
        k: m.k.to_string(),
        tov: m.tov.to_string(),
        mov: m.mov.to_string(),
        tolerances_met: met.map(|b| b.to_string()).unwrap_or_default(),
        message: warnings.join("; "),
    })
}

/// One robot into `dir` (`OUTDIR/<base>`): its row has the links' triangles, their parts,
/// and whether every link met its tolerances.
fn process_robot(
    path: &Path,
    dir: &Path,
    base: &str,
    options: &RobotOptions,
    args: &BatchArgs,
) -> anyhow::Result<Row> {
    // Several files run at once: no per-link lines, and the batch's pool for threads.
    let run = run_robot(path, options, None, args.params.timeout, true)?;
    run.write(dir)?;
    let met: Vec<Option<bool>> = run
        .links
        .iter()
        .flatten()
        .map(|l| l.tolerances_met)
        .collect();
    let tolerances_met = if met.contains(&Some(false)) {
        "false"
    } else if met.contains(&Some(true)) {
        "true"
    } else {
        ""
    };
    Ok(Row {
        file: file_name(path),
        status: "done",
        triangles: run.total_triangles().to_string(),
        k: run.total_parts().to_string(),
        tov: String::new(),
        mov: String::new(),
        tolerances_met: tolerances_met.to_owned(),
        message: std::iter::once(format!(
            "robot: {} links segmented, {} spheres, outputs in {base}/",
            run.links_segmented(),
            run.total_spheres()
        ))
        .chain(run.warnings.iter().cloned())
        .collect::<Vec<_>>()
        .join("; "),
    })
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

fn failed(path: &Path, message: &str) -> Row {
    Row {
        file: file_name(path),
        status: "error",
        triangles: String::new(),
        k: String::new(),
        tov: String::new(),
        mov: String::new(),
        tolerances_met: String::new(),
        message: message.to_owned(),
    }
}

/// A skipped file's row, with the figures of its existing JSON output when there is one.
fn skipped(path: &Path, json: Option<&Path>) -> Row {
    let mut row = failed(path, "outputs exist");
    row.status = "skipped";
    let doc: Option<serde_json::Value> = json
        .and_then(|j| std::fs::read_to_string(j).ok())
        .and_then(|t| serde_json::from_str(&t).ok());
    if let Some(m) = doc.as_ref().map(|d| &d["metrics"]) {
        let field = |k: &str| m.get(k).map(|v| v.to_string()).unwrap_or_default();
        row.k = field("k");
        row.tov = field("tov");
        row.mov = field("mov");
    }
    row
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from("file,status,triangles,k,tov,mov,tolerances_met,message\n");
    for r in rows {
        let fields = [
            &r.file,
            r.status,
            &r.triangles,
            &r.k,
            &r.tov,
            &r.mov,
            &r.tolerances_met,
            &r.message,
        ];
        let line: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_stems_keep_their_extension() {
        let files: Vec<PathBuf> = ["a.obj", "a.stl", "b.glb"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(output_bases(&files), ["a.obj", "a.stl", "b"]);
        assert_eq!(csv_field("x, \"y\""), "\"x, \"\"y\"\"\"");
    }
}
