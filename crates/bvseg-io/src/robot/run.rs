//! A whole robot run: read the robot, segment each link's meshes in the link's frame (the
//! primitives for the URDF and MJCF, spheres for cuRobo), one result per link. The command
//! line (`bvseg robot`, robots in `bvseg batch`) and the Python package (`bvseg.robot`) all
//! go through [`segment_robot`], then [`RobotRun::write`].
use std::path::Path;

use bvseg_core::{Cancel, Kinds, Params, Segmentation, Segmenter, Shape, Step};

use super::output::{LinkResult, RobotRun};
use super::paths::file_safe;
use super::{read_robot, share_parts, MeshSource, Robot};
use crate::IoError;

/// Default of [`RobotOptions::spheres_per_link`].
pub const DEFAULT_SPHERES_PER_LINK: usize = 16;

/// Default per-link budget ([`PartBudget::PerLink`]): engines and planners want a few
/// primitives per link, and on the measured robots (docs/robots.md, "Budgets") more parts
/// per link tighten the colliders less than each costs.
pub const DEFAULT_PARTS_PER_LINK: usize = 4;

/// How many parts the links get.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PartBudget {
    /// At most this many per link (each link's `max_k` is the smaller of this and the
    /// parameters' `max_k`).
    PerLink(usize),
    /// At most this many for the whole robot, shared among its links by their volume, each
    /// at least one ([`share_parts`]).
    Total(usize),
}

impl Default for PartBudget {
    fn default() -> Self {
        PartBudget::PerLink(DEFAULT_PARTS_PER_LINK)
    }
}

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
    /// How many parts the links get (default: [`DEFAULT_PARTS_PER_LINK`] per link).
    pub parts: PartBudget,
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
            parts: PartBudget::default(),
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
        /// Its result.
        result: &'a LinkResult,
    },
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
/// `options.parts`), and its spheres for cuRobo (at most `spheres_per_link`, without
/// hierarchy). A link whose meshes enclose no volume is not segmented: its collisions stay
/// as they are, and the run's warnings say so. `cancel` stops the run at the next check;
/// `on_event` hears each start, refinement step and finished link. Run it inside a rayon pool
/// to bound its threads.
///
/// # Errors
///
/// [`RobotError::Io`] for the robot file or a link's mesh (one line naming the file, and the
/// link), [`RobotError::Options`] or [`RobotError::Params`] for options out of range,
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
    if matches!(options.parts, PartBudget::PerLink(0) | PartBudget::Total(0)) {
        return Err(RobotError::Options(
            "the parts budget (max parts, total parts) must be at least 1".into(),
        ));
    }
    options.params.validate().map_err(RobotError::Params)?;
    let robot = read_robot(path, options.source)?;
    let stem = robot_stem(&robot)?;
    let mut warnings = robot.warnings.clone();
    let mut meshes = Vec::with_capacity(robot.links.len());
    for link in &robot.links {
        let mut m = robot.link_mesh(link)?;
        if let Some(mesh) = &m {
            if mesh.encloses_no_volume() {
                warnings.push(format!(
                    "{}: link {:?}: its meshes enclose no volume (flat, open or degenerate: {} \
                     triangles, {} open edges): its collisions are left as they are",
                    robot.file, link.name, mesh.report.triangles, mesh.report.open_edges
                ));
                m = None;
            }
        }
        meshes.push(m);
    }
    let budgets: Vec<usize> = match options.parts {
        PartBudget::Total(total) => {
            let volumes: Vec<Option<f64>> = meshes
                .iter()
                .map(|m| m.as_ref().map(|m| m.report.volume))
                .collect();
            share_parts(&volumes, total)
        }
        PartBudget::PerLink(n) => vec![n; meshes.len()],
    };
    let base = &options.params;
    let mut links = Vec::with_capacity(robot.links.len());
    for (i, (link, mesh)) in robot.links.iter().zip(&meshes).enumerate() {
        let Some(mesh) = mesh else {
            links.push(None);
            continue;
        };
        let mut p = Params {
            kinds: urdf_kinds(base.kinds, options.urdf_capsules),
            ..base.clone()
        };
        p.max_k = p.max_k.min(budgets[i]).max(1);
        p.k = p.k.map(|k| k.min(p.max_k));
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
        let parts = one(&p, false)?;
        let spheres = one(&sp, true)?;
        let result = LinkResult {
            tolerances_met: parts.tolerances_met(&p),
            triangles: mesh.mesh.triangles().len(),
            parts,
            spheres,
        };
        on_event(RobotEvent::Done {
            link: &link.name,
            result: &result,
        });
        links.push(Some(result));
    }
    Ok(RobotRun {
        robot,
        stem,
        links,
        warnings,
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
}
