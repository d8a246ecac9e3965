//! Robots: a URDF or MJCF file read into a model ([`read_robot`]: links with the meshes they
//! collide with, placed in the link's frame, and the joints between them), each link
//! segmented ([`segment_robot`]: one [`LinkResult`] per link), and the robot written back
//! ([`RobotRun::write`]): the input file as it was but for its collision meshes, replaced by
//! primitives (URDF and MJCF alike), the other format made from the links, the colliders as
//! USD, cuRobo's collision spheres, and a manifest written last.
//!
//! - `model`: the robot, whatever file it came from; `paths`, `geometry`: what both
//!   readers need;
//! - `urdf` and `mjcf`: each format's reader and writers (the writers edit the text the
//!   reader kept, through `text`); `curobo`: the spheres; `usd`: the colliders as USD;
//! - `run`: the run, `output`: its result and files.
//!
//! Reading checks everything a run needs before any segmentation: every mesh file exists,
//! link names are unique, every joint joins two links, MJCF includes do not cycle. What it
//! leaves as it is (a mesh of a format bvseg cannot read) it says in [`Robot::warnings`].
mod curobo;
mod geometry;
mod mjcf;
mod model;
mod output;
mod paths;
mod run;
mod text;
mod urdf;
mod usd;

use std::path::{Path, PathBuf};

use crate::IoError;

pub use model::{share_parts, Joint, JointKind, Link, MeshRef, Robot};
pub use output::{LinkResult, RobotRun, DONE_FILE};
pub use run::{
    segment_robot, PartBudget, RobotError, RobotEvent, RobotOptions, DEFAULT_PARTS_PER_LINK,
    DEFAULT_SPHERES_PER_LINK,
};

/// The robot file extensions [`read_robot`] reads (compared case-insensitively): `.urdf`,
/// and `.xml` (or `.mjcf`) for MJCF.
pub const ROBOT_EXTENSIONS: &[&str] = &["urdf", "xml", "mjcf"];

/// The kind of robot file `path` is, reading no more than its start: a `.urdf` file, or an
/// `.xml` or `.mjcf` file whose root element is `<mujoco>` and that bvseg did not write (its
/// MJCF outputs open with its generator comment). `None` for anything else, and for a file
/// that cannot be read. For listing a directory; [`read_robot`] does not need it.
pub fn robot_format(path: &Path) -> Option<RobotFormat> {
    use std::io::Read;
    match crate::extension(path).as_deref() {
        Some("urdf") => return path.is_file().then_some(RobotFormat::Urdf),
        Some("xml") | Some("mjcf") => {}
        _ => return None,
    }
    let mut head = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(1 << 16)
        .read_to_end(&mut head)
        .ok()?;
    let text = String::from_utf8_lossy(&head);
    let mut rest = text.trim_start_matches('\u{feff}').trim_start();
    // The prolog: declarations, comments, a doctype.
    while let Some(r) = rest.strip_prefix("<?").or_else(|| rest.strip_prefix("<!")) {
        let end = if r.starts_with("--") {
            r.find("-->")? + 3
        } else {
            r.find('>')? + 1
        };
        rest = r[end..].trim_start();
    }
    let tag = rest.strip_prefix("<mujoco")?;
    if !tag.starts_with(|c: char| c.is_whitespace() || c == '>' || c == '/') {
        return None;
    }
    let after = tag[tag.find('>')? + 1..].trim_start();
    // Any version's: `GENERATOR` is "bvseg <version>".
    (!after.starts_with("<!-- bvseg ")).then_some(RobotFormat::Mjcf)
}

/// The kind of robot file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RobotFormat {
    /// ROS's Unified Robot Description Format (`.urdf`).
    Urdf,
    /// MuJoCo's MJCF (`.xml`).
    Mjcf,
}

/// Which of a link's meshes are segmented.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum MeshSource {
    /// URDF `<collision>` meshes; MJCF mesh geoms that collide (`contype` or `conaffinity`
    /// not 0, after defaults).
    #[default]
    Collision,
    /// URDF `<visual>` meshes; every MJCF mesh geom.
    Visual,
}

/// Reads a URDF (`.urdf`) or MJCF (`.xml`, MJCF's `<include>`s followed) robot file.
///
/// # Errors
///
/// An [`IoError`] of one line: the file cannot be read ([`IoError::Io`]), is not well-formed
/// or not a robot ([`IoError::Robot`]), repeats a link name ([`IoError::DuplicateLink`]), has
/// a joint whose parent or child is no link ([`IoError::UnknownLink`]), a mesh file that does
/// not exist ([`IoError::MissingMesh`]), or an include cycle ([`IoError::IncludeCycle`]).
pub fn read_robot(path: impl AsRef<Path>, source: MeshSource) -> Result<Robot, IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = read_text(path, &name)?;
    let robot = match crate::extension(path).as_deref() {
        Some("urdf") => urdf::parse(path, &name, text, source)?,
        Some("xml") | Some("mjcf") => mjcf::parse(path, &name, text, source)?,
        ext => {
            return Err(IoError::UnsupportedFormat {
                name,
                what: "robot",
                ext: ext.map(str::to_owned),
                supported: ".urdf, .xml (MJCF)",
            })
        }
    };
    robot.check()?;
    Ok(robot)
}

/// The files a robot file uses besides itself, as canonical paths: its links' mesh files
/// (collision and visual, those that exist) and the files an MJCF includes. Best effort: what
/// cannot be read is left out. A batch does not take these as inputs of their own: they are
/// the robot's.
pub fn robot_uses(path: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for source in [MeshSource::Collision, MeshSource::Visual] {
        if let Ok(robot) = read_robot(path, source) {
            out.extend(
                robot
                    .links
                    .iter()
                    .flat_map(|l| &l.meshes)
                    .filter_map(|m| m.path.canonicalize().ok()),
            );
        }
    }
    if robot_format(path) == Some(RobotFormat::Mjcf) {
        if let Ok(text) = read_text(path, &path.display().to_string()) {
            out.extend(mjcf::included_files(path, text));
        }
    }
    out.sort();
    out.dedup();
    out
}

pub(crate) fn read_text(path: &Path, name: &str) -> Result<String, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(name, "read", e))?;
    if bytes.len() as u64 > crate::MAX_INPUT_BYTES {
        return Err(IoError::TooLarge {
            name: name.to_owned(),
            limit: crate::MAX_INPUT_BYTES,
        });
    }
    String::from_utf8(bytes).map_err(|_| IoError::Robot {
        name: name.to_owned(),
        message: "not UTF-8 text".into(),
    })
}
