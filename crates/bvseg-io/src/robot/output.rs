//! What a robot run gives back: one result per link, and the files written from them (the
//! robot with primitive colliders as URDF and MJCF, the colliders as USD, cuRobo's spheres, a
//! volumes document per link), with a manifest written last that says they are all there.
use std::path::{Path, PathBuf};

use bvseg_core::Segmentation;
use serde::Serialize;

use super::model::{Robot, Source};
use super::paths::{file_safe, relative};
use super::{curobo, mjcf, urdf, usd};
use crate::IoError;

/// The file [`RobotRun::write`] writes last, once every other output is in place (each
/// written atomically): a robot's outputs are complete when it exists, which is how a batch
/// knows a robot is done. It lists the files and what each link got.
pub const DONE_FILE: &str = "manifest.json";

/// What one link got.
#[derive(Debug, Clone)]
pub struct LinkResult {
    /// Its primitives, in the link's frame.
    pub parts: Segmentation,
    /// Its cuRobo spheres, in the link's frame.
    pub spheres: Segmentation,
    /// The triangles of its meshes, after loading.
    pub triangles: usize,
    /// Whether the primitives' run met its tolerances (`None` with a fixed `k`).
    pub tolerances_met: Option<bool>,
}

/// A robot with its links segmented ([`super::segment_robot`]), ready to be written.
#[derive(Debug, Clone)]
pub struct RobotRun {
    /// The robot as read.
    pub robot: Robot,
    /// The outputs' file stem: the robot's name made safe for a file name, else the file's.
    pub stem: String,
    /// By link index: what the link got; `None` for a link that was not segmented (no
    /// meshes, or meshes that enclose no volume).
    pub links: Vec<Option<LinkResult>>,
    /// What was left as it was and why, one line each (the robot's read warnings first).
    pub warnings: Vec<String>,
    /// Whether capsules are written as URDF 1.1 `<capsule>`.
    pub urdf_capsules: bool,
}

impl RobotRun {
    /// Every output for the directory `dir`, as a path relative to it and its bytes, in
    /// writing order: `links/<link>.json` for each segmented link, `<stem>.urdf`,
    /// `<stem>.xml` (for an MJCF input, then the files it includes, under their own names),
    /// `<stem>.usda`, `curobo.yml`, and [`DONE_FILE`] last. `dir` matters for an MJCF input only, whose
    /// relative asset directories are made to lead from `dir` back to the input's.
    pub fn files(&self, dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        let parts: Vec<Option<&Segmentation>> = self
            .links
            .iter()
            .map(|l| l.as_ref().map(|l| &l.parts))
            .collect();
        let spheres: Vec<Option<&Segmentation>> = self
            .links
            .iter()
            .map(|l| l.as_ref().map(|l| &l.spheres))
            .collect();
        let mut files = Vec::new();
        for (i, l) in self.links.iter().enumerate() {
            if let (Some(l), Some(rel)) = (l, self.volumes_file(i)) {
                files.push((rel, crate::to_json_string(&l.parts).into_bytes()));
            }
        }
        let (urdf_name, xml_name) = (format!("{}.urdf", self.stem), format!("{}.xml", self.stem));
        let usd_name = format!("{}.usda", self.stem);
        files.push((
            PathBuf::from(&urdf_name),
            urdf::to_urdf(&self.robot, &parts, self.urdf_capsules).into_bytes(),
        ));
        match &self.robot.source {
            Source::Mjcf(source) => {
                let rebase = match dir.canonicalize() {
                    Ok(here) => relative(&here, &source.dir),
                    Err(_) => source.dir.clone(),
                };
                let taken = [
                    urdf_name,
                    usd_name.clone(),
                    "curobo.yml".to_owned(),
                    DONE_FILE.to_owned(),
                    "links".to_owned(),
                ];
                for (name, text) in
                    mjcf::to_mjcf_files(&self.robot, source, &parts, &xml_name, &taken, &rebase)
                {
                    files.push((PathBuf::from(name), text.into_bytes()));
                }
            }
            Source::Urdf(_) => files.push((
                PathBuf::from(xml_name),
                mjcf::to_mjcf_robot(&self.robot, &parts).into_bytes(),
            )),
        }
        files.push((
            PathBuf::from(usd_name),
            usd::to_usda_robot(&self.robot, &parts).into_bytes(),
        ));
        files.push((
            PathBuf::from("curobo.yml"),
            curobo::to_curobo(&self.robot, &spheres).into_bytes(),
        ));
        let listed: Vec<String> = files
            .iter()
            .map(|(p, _)| p.to_string_lossy().replace('\\', "/"))
            .collect();
        files.push((PathBuf::from(DONE_FILE), self.manifest(listed).into_bytes()));
        files
    }

    /// The manifest ([`DONE_FILE`]) listing `files`.
    fn manifest(&self, files: Vec<String>) -> String {
        #[derive(Serialize)]
        struct Manifest<'a> {
            generator: &'a str,
            robot: &'a str,
            input: &'a str,
            format: &'a str,
            files: Vec<String>,
            parts: usize,
            spheres: usize,
            links: Vec<LinkEntry<'a>>,
            warnings: &'a [String],
        }
        #[derive(Serialize)]
        struct LinkEntry<'a> {
            name: &'a str,
            meshes: usize,
            kept: usize,
            triangles: usize,
            parts: usize,
            shapes: Vec<&'static str>,
            spheres: usize,
            tolerances_met: Option<bool>,
            volumes: Option<String>,
        }
        let links = self
            .robot
            .links
            .iter()
            .zip(&self.links)
            .enumerate()
            .map(|(i, (link, r))| LinkEntry {
                name: &link.name,
                meshes: link.meshes.len(),
                kept: link.kept.len(),
                triangles: r.as_ref().map_or(0, |r| r.triangles),
                parts: r.as_ref().map_or(0, |r| r.parts.parts.len()),
                shapes: r.as_ref().map_or(Vec::new(), |r| {
                    r.parts
                        .parts
                        .iter()
                        .map(|p| p.volume.shape.as_str())
                        .collect()
                }),
                spheres: r.as_ref().map_or(0, |r| r.spheres.parts.len()),
                tolerances_met: r.as_ref().and_then(|r| r.tolerances_met),
                volumes: self
                    .volumes_file(i)
                    .map(|p| p.to_string_lossy().replace('\\', "/")),
            })
            .collect();
        let m = Manifest {
            generator: crate::GENERATOR,
            robot: &self.robot.name,
            input: &self.robot.file,
            format: match self.robot.format {
                super::RobotFormat::Urdf => "urdf",
                super::RobotFormat::Mjcf => "mjcf",
            },
            files,
            parts: self.total_parts(),
            spheres: self.total_spheres(),
            links,
            warnings: &self.warnings,
        };
        // Plain data: serialising it cannot fail.
        let mut s = serde_json::to_string_pretty(&m).unwrap_or_default();
        s.push('\n');
        s
    }

    /// The volumes document of link `link` (by index), relative to the output directory:
    /// `links/<link>.json` with the name made safe for a file; `None` for a link that was
    /// not segmented.
    pub fn volumes_file(&self, link: usize) -> Option<PathBuf> {
        let l = self.robot.links.get(link)?;
        self.links.get(link)?.as_ref()?;
        Some(Path::new("links").join(format!("{}.json", file_safe(&l.name))))
    }

    /// Writes every output of [`RobotRun::files`] under `dir` (created if missing), each
    /// atomically, [`DONE_FILE`] last; returns the paths written.
    ///
    /// # Errors
    ///
    /// [`IoError::Io`] when a directory cannot be created or a file written;
    /// [`IoError::BadPath`] when an output would replace one of the robot's own files (the
    /// robot file, a file it includes, a mesh): nothing is written then.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, IoError> {
        let inputs = self.robot.inputs();
        for (rel, _) in &self.files(dir) {
            let path = dir.join(rel);
            if let Ok(p) = path.canonicalize() {
                if inputs.contains(&p) {
                    return Err(IoError::BadPath {
                        name: path.display().to_string(),
                        message: "is one of the robot's own files: write the outputs to \
                                  another directory"
                            .into(),
                    });
                }
            }
        }
        let links = dir.join("links");
        std::fs::create_dir_all(&links)
            .map_err(|e| IoError::io(&links.display().to_string(), "create the directory", e))?;
        let mut written = Vec::new();
        // Again, now that `dir` exists: the MJCF's directories lead back from it.
        for (rel, bytes) in self.files(dir) {
            let path = dir.join(rel);
            crate::write_atomic(&path, &bytes)?;
            written.push(path);
        }
        Ok(written)
    }

    /// The number of links segmented.
    pub fn links_segmented(&self) -> usize {
        self.links.iter().flatten().count()
    }

    /// Parts over all links.
    pub fn total_parts(&self) -> usize {
        self.links
            .iter()
            .flatten()
            .map(|l| l.parts.parts.len())
            .sum()
    }

    /// Spheres over all links.
    pub fn total_spheres(&self) -> usize {
        self.links
            .iter()
            .flatten()
            .map(|l| l.spheres.parts.len())
            .sum()
    }

    /// Triangles over all links.
    pub fn total_triangles(&self) -> usize {
        self.links.iter().flatten().map(|l| l.triangles).sum()
    }
}
