//! A whole robot run: read the robot, segment each link's meshes in the link's frame (the
//! primitives for the URDF and MJCF, spheres for cuRobo), and render every output. The
//! command line (`bvseg robot`, robots in `bvseg batch`) and the Python package
//! (`bvseg.robot`) all go through [`segment_robot`] and [`RobotRun::write`].
use std::path::{Path, PathBuf};

use bvseg_core::{Cancel, Kinds, Params, Segmentation, Segmenter, Shape, Step};

use super::{read_robot, share_parts, to_curobo, to_mjcf_robot, to_urdf, MeshSource, Robot};
use crate::IoError;

/// Default of [`RobotOptions::spheres_per_link`].
pub const DEFAULT_SPHERES_PER_LINK: usize = 16;

/// The output written last by [`RobotRun::write`]: a robot's outputs are all there when it
/// exists (each file is written atomically), which is how a batch knows a robot is done.
pub const DONE_FILE: &str = "curobo.yml";

/// What [`segment_robot`] does. Write it as a struct literal ending in
/// `..RobotOptions::default()`, so that the code keeps compiling when fields are added.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotOptions {
    /// Which meshes of each link are segmented.
    pub source: MeshSource,
    /// The segmentation's parameters for each link. Its `kinds` are narrowed to those URDF
    /// has (box, sphere, cylinder, and capsule with `urdf_capsules`), so that the URDF and
    /// the MJCF hold the same volumes; boxes when none of them is asked for.
    pub params: Params,
    /// Most parts per link (each link's `max_k`, and `k` at most this).
    pub max_parts: Option<usize>,
    /// Most parts for the whole robot, shared among its links by volume, each at least one
    /// ([`share_parts`]); instead of `max_parts`.
    pub total_parts: Option<usize>,
    /// Most spheres per link in `curobo.yml`.
    pub spheres_per_link: usize,
    /// Write capsules as URDF 1.1 `<capsule>` (otherwise URDF gets no capsules).
    pub urdf_capsules: bool,
}

impl Default for RobotOptions {
    fn default() -> Self {
        Self {
            source: MeshSource::Collision,
            params: Params::default(),
            max_parts: None,
            total_parts: None,
            spheres_per_link: DEFAULT_SPHERES_PER_LINK,
            urdf_capsules: false,
        }
    }
}

/// What went wrong in [`segment_robot`]. Every message is one line. More variants may be
/// added: a `match` on it needs a `_` arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// The robot file or a link's mesh cannot be read or is not usable.
    #[error(transparent)]
    Io(#[from] IoError),
    /// An option is out of its range (the message names it).
    #[error("{0}")]
    Options(String),
    /// The segmentation's parameters are invalid (the message names the parameter).
    #[error("{0}")]
    Params(#[source] bvseg_core::ParamError),
    /// A link's meshes, placed in its frame, enclose no volume.
    #[error("{file}: link {link:?}: its meshes enclose no volume (flat, open or degenerate: {triangles} triangles, {open_edges} open edges)")]
    NoVolume {
        /// The robot file.
        file: String,
        /// The link.
        link: String,
        /// Its triangles.
        triangles: usize,
        /// Its open edges.
        open_edges: usize,
    },
    /// A link's segmentation failed, or was cancelled ([`bvseg_core::Error::Cancelled`]).
    #[error("{file}: link {link:?}: {source}")]
    Segment {
        /// The robot file.
        file: String,
        /// The link.
        link: String,
        /// The core's error.
        source: bvseg_core::Error,
    },
}

impl RobotError {
    /// Whether the run stopped because its [`Cancel`] flag was set.
    pub fn is_cancelled(&self) -> bool {
        matches!(
            self,
            RobotError::Segment {
                source: bvseg_core::Error::Cancelled,
                ..
            }
        )
    }
}

/// What [`segment_robot`] reports while it runs.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub enum RobotEvent<'a> {
    /// A link's segmentation starts: its primitives, or (`spheres`) its cuRobo spheres.
    Start {
        /// The link.
        link: &'a str,
        /// The parameters of this segmentation.
        params: &'a Params,
        /// Whether these are the spheres.
        spheres: bool,
    },
    /// A refinement step of the current segmentation.
    Step(&'a Step),
    /// A link is done.
    Done {
        /// The link.
        link: &'a str,
        /// Its primitives.
        parts: &'a Segmentation,
        /// Its spheres.
        spheres: &'a Segmentation,
    },
}

/// A robot with its links segmented ([`segment_robot`]), ready to be written.
#[derive(Debug, Clone)]
pub struct RobotRun {
    /// The robot as read.
    pub robot: Robot,
    /// The outputs' file stem: the robot's name made safe for a file name, else the file's.
    pub stem: String,
    /// Each link's primitives, by link index (`None` for a link without meshes).
    pub parts: Vec<Option<Segmentation>>,
    /// Each link's cuRobo spheres, by link index.
    pub spheres: Vec<Option<Segmentation>>,
    /// Each link's triangles (after loading), by link index (0 without meshes).
    pub triangles: Vec<usize>,
    /// Whether each link's tolerance-mode run met its tolerances (`None` with a fixed `k`
    /// or without meshes), by link index.
    pub tolerances_met: Vec<Option<bool>>,
    /// Whether capsules are written as URDF 1.1 `<capsule>` ([`RobotOptions::urdf_capsules`]).
    pub urdf_capsules: bool,
}

impl RobotRun {
    /// Every output, as a path relative to the output directory and its bytes, in writing
    /// order: `links/<link>.json` for each segmented link, `<stem>.urdf`, `<stem>.xml`, and
    /// [`DONE_FILE`] last.
    pub fn files(&self) -> Vec<(PathBuf, Vec<u8>)> {
        let mut files = Vec::new();
        for (i, seg) in self.parts.iter().enumerate() {
            if let (Some(seg), Some(rel)) = (seg, self.volumes_file(i)) {
                files.push((rel, crate::to_json_string(seg).into_bytes()));
            }
        }
        files.push((
            PathBuf::from(format!("{}.urdf", self.stem)),
            to_urdf(&self.robot, &self.parts, self.urdf_capsules).into_bytes(),
        ));
        files.push((
            PathBuf::from(format!("{}.xml", self.stem)),
            to_mjcf_robot(&self.robot, &self.parts).into_bytes(),
        ));
        files.push((
            PathBuf::from(DONE_FILE),
            to_curobo(&self.robot, &self.spheres).into_bytes(),
        ));
        files
    }

    /// The volumes document of link `link` (by index), relative to the output directory:
    /// `links/<link>.json` with the name made safe for a file; `None` for a link that was
    /// not segmented.
    pub fn volumes_file(&self, link: usize) -> Option<PathBuf> {
        let l = self.robot.links.get(link)?;
        self.parts.get(link)?.as_ref()?;
        Some(Path::new("links").join(format!("{}.json", file_safe(&l.name))))
    }

    /// Writes every output of [`RobotRun::files`] under `dir` (created if missing), each
    /// atomically, [`DONE_FILE`] last; returns the paths written.
    ///
    /// # Errors
    ///
    /// [`IoError::Io`] when a directory cannot be created or a file written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, IoError> {
        let links = dir.join("links");
        std::fs::create_dir_all(&links)
            .map_err(|e| IoError::io(&links.display().to_string(), "create the directory", e))?;
        let mut written = Vec::new();
        for (rel, bytes) in self.files() {
            let path = dir.join(rel);
            crate::write_atomic(&path, &bytes)?;
            written.push(path);
        }
        Ok(written)
    }

    /// The number of links with meshes.
    pub fn links_segmented(&self) -> usize {
        self.parts.iter().flatten().count()
    }

    /// Parts over all links.
    pub fn total_parts(&self) -> usize {
        self.parts.iter().flatten().map(|s| s.parts.len()).sum()
    }

    /// Spheres over all links.
    pub fn total_spheres(&self) -> usize {
        self.spheres.iter().flatten().map(|s| s.parts.len()).sum()
    }
}

/// The kinds of `kinds` that URDF has (box, sphere, cylinder, and capsule with `capsules`);
/// boxes, the closest to every other kind, when none of them is asked for.
fn urdf_kinds(kinds: Kinds, capsules: bool) -> Kinds {
    let mut allowed = vec![Shape::Obb, Shape::Sphere, Shape::Cylinder];
    if capsules {
        allowed.push(Shape::Capsule);
    }
    let mut k: Option<Kinds> = None;
    for s in kinds.shapes().filter(|s| allowed.contains(s)) {
        k = Some(k.map_or(Kinds::only(s), |k| k.with(s)));
    }
    k.unwrap_or(Kinds::OBB)
}

/// Reads the robot at `path` ([`read_robot`]), loads every link's meshes (so that a bad one
/// fails before any slow work), and segments each link with meshes twice in its own frame:
/// its primitives with `options.params` (kinds narrowed to URDF's, budgets from
/// `max_parts` or `total_parts`), and its spheres for cuRobo (at most `spheres_per_link`,
/// without hierarchy). `cancel` stops the run at the next check; `on_event` hears each start,
/// refinement step and finished link. Run it inside a rayon pool to bound its threads.
///
/// # Errors
///
/// [`RobotError::Io`] for the robot file or a link's mesh (one line naming the file, and the
/// link), [`RobotError::Options`] or [`RobotError::Params`] for options out of range,
/// [`RobotError::NoVolume`] for a link whose meshes enclose no volume,
/// [`RobotError::Segment`] when a link's segmentation fails or is cancelled.
pub fn segment_robot(
    path: impl AsRef<Path>,
    options: &RobotOptions,
    cancel: &Cancel,
    mut on_event: impl FnMut(RobotEvent<'_>),
) -> Result<RobotRun, RobotError> {
    if options.spheres_per_link == 0 {
        return Err(RobotError::Options(
            "spheres per link must be at least 1".into(),
        ));
    }
    if options.max_parts == Some(0) || options.total_parts == Some(0) {
        return Err(RobotError::Options(
            "the parts budget (max parts, total parts) must be at least 1".into(),
        ));
    }
    if options.max_parts.is_some() && options.total_parts.is_some() {
        return Err(RobotError::Options(
            "max parts and total parts cannot be combined: give a budget per link or for the robot"
                .into(),
        ));
    }
    options.params.validate().map_err(RobotError::Params)?;
    let robot = read_robot(path, options.source)?;
    let stem = robot_stem(&robot)?;
    let mut meshes = Vec::with_capacity(robot.links.len());
    for link in &robot.links {
        let m = robot.link_mesh(link)?;
        if let Some(m) = &m {
            if m.encloses_no_volume() {
                return Err(RobotError::NoVolume {
                    file: robot.file.clone(),
                    link: link.name.clone(),
                    triangles: m.report.triangles,
                    open_edges: m.report.open_edges,
                });
            }
        }
        meshes.push(m);
    }
    let budgets: Vec<Option<usize>> = match options.total_parts {
        Some(total) => {
            let volumes: Vec<Option<f64>> = meshes
                .iter()
                .map(|m| m.as_ref().map(|m| m.report.volume))
                .collect();
            share_parts(&volumes, total).into_iter().map(Some).collect()
        }
        None => vec![options.max_parts; meshes.len()],
    };
    let base = &options.params;
    let n = robot.links.len();
    let (mut parts, mut spheres) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut triangles, mut tolerances_met) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (i, (link, mesh)) in robot.links.iter().zip(&meshes).enumerate() {
        let Some(mesh) = mesh else {
            parts.push(None);
            spheres.push(None);
            triangles.push(0);
            tolerances_met.push(None);
            continue;
        };
        let mut p = Params {
            kinds: urdf_kinds(base.kinds, options.urdf_capsules),
            ..base.clone()
        };
        if let Some(b) = budgets[i] {
            p.max_k = b.max(1);
            p.k = p.k.map(|k| k.min(p.max_k));
        }
        let sp = Params {
            kinds: Kinds::SPHERE,
            max_k: options.spheres_per_link,
            k: base.k.map(|k| k.min(options.spheres_per_link)),
            hierarchy: false,
            ..base.clone()
        };
        let mut one = |params: &Params, spheres: bool| {
            on_event(RobotEvent::Start {
                link: &link.name,
                params,
                spheres,
            });
            segment_link(&mesh.mesh, params, cancel, &mut on_event).map_err(|source| match source {
                bvseg_core::Error::InvalidParams(p) => RobotError::Params(p),
                _ => RobotError::Segment {
                    file: robot.file.clone(),
                    link: link.name.clone(),
                    source,
                },
            })
        };
        let seg = one(&p, false)?;
        let sph = one(&sp, true)?;
        on_event(RobotEvent::Done {
            link: &link.name,
            parts: &seg,
            spheres: &sph,
        });
        triangles.push(mesh.mesh.triangles().len());
        tolerances_met.push(seg.tolerances_met(&p));
        parts.push(Some(seg));
        spheres.push(Some(sph));
    }
    Ok(RobotRun {
        robot,
        stem,
        parts,
        spheres,
        triangles,
        tolerances_met,
        urdf_capsules: options.urdf_capsules,
    })
}

fn segment_link(
    mesh: &bvseg_core::Mesh,
    params: &Params,
    cancel: &Cancel,
    on_event: &mut impl FnMut(RobotEvent<'_>),
) -> Result<Segmentation, bvseg_core::Error> {
    let mut s = Segmenter::with_cancel(mesh, params, cancel.clone())?;
    while let Some(step) = s.step() {
        on_event(RobotEvent::Step(&step));
    }
    s.finish()
}

/// The robot's name as a file stem: its own name, else the file's stem.
fn robot_stem(robot: &Robot) -> Result<String, RobotError> {
    let n = file_safe(&robot.name);
    if !n.is_empty() {
        return Ok(n);
    }
    let stem = Path::new(&robot.file)
        .file_stem()
        .map(|s| file_safe(&s.to_string_lossy()))
        .unwrap_or_default();
    if stem.is_empty() {
        return Err(RobotError::Options(format!(
            "{}: cannot name the outputs (no robot name, no file stem)",
            robot.file
        )));
    }
    Ok(stem)
}

/// A name with path separators and other awkward characters replaced by `_`, without
/// leading dots (no hidden files, no `..`).
pub(crate) fn file_safe(s: &str) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urdf_gets_only_its_kinds() {
        let k = urdf_kinds(Params::default().kinds, false);
        assert_eq!(k, Kinds::OBB.with(Shape::Sphere).with(Shape::Cylinder));
        assert!(urdf_kinds(Params::default().kinds, true)
            .shapes()
            .any(|s| s == Shape::Capsule));
        assert_eq!(urdf_kinds(Kinds::only(Shape::Ellipsoid), false), Kinds::OBB);
    }

    #[test]
    fn names_are_safe_for_files() {
        assert_eq!(file_safe("../a b/c"), "_a_b_c");
        assert_eq!(file_safe("link_1.x"), "link_1.x");
    }
}
