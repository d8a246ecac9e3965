//! Robots: a URDF or MJCF file read into links (each with the meshes it collides with, placed
//! in the link's frame) and the joints between them ([`read_robot`]), and the files written
//! once each link is segmented: the URDF with primitive collisions ([`to_urdf`]), an MJCF
//! with native geoms ([`to_mjcf_robot`]) and cuRobo's collision spheres ([`to_curobo`]).
//!
//! Reading checks everything a run needs before any segmentation: every mesh file exists
//! and has a format [`crate::load`] reads, link names are unique, every joint joins two
//! links, MJCF includes do not cycle.
mod curobo;
mod mjcf;
mod run;
mod urdf;

use std::ops::Range;
use std::path::{Path, PathBuf};

use bvseg_core::{BoundingVolume, Segmentation};
use glam::{DAffine3, DMat3, DQuat, DVec3};

use crate::{IoError, LoadOptions, LoadedMesh};

pub use curobo::to_curobo;
pub use mjcf::to_mjcf_robot;
pub use run::{
    segment_robot, RobotError, RobotEvent, RobotOptions, RobotRun, DEFAULT_SPHERES_PER_LINK,
    DONE_FILE,
};
pub use urdf::to_urdf;

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
    /// URDF `<collision>` meshes; MJCF mesh geoms that collide (not `contype="0"
    /// conaffinity="0"`).
    #[default]
    Collision,
    /// URDF `<visual>` meshes; every MJCF mesh geom.
    Visual,
}

/// One mesh of a link, as the robot file places it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshRef {
    /// The file, resolved to a path that exists.
    pub path: PathBuf,
    /// The file name as the robot file gives it (for messages).
    pub given: String,
    /// Scale applied to the mesh's coordinates before `origin`.
    pub scale: DVec3,
    /// The mesh's frame in the link's frame.
    pub origin: DAffine3,
}

/// A link (URDF) or body (MJCF).
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Its name (for an unnamed MJCF body, `body_<n>`).
    pub name: String,
    /// The meshes to segment, in file order.
    pub meshes: Vec<MeshRef>,
    /// MJCF: the body's colliding primitive geoms (sphere, capsule, cylinder, box,
    /// ellipsoid), in its frame, which the outputs keep beside the new volumes. (A URDF's
    /// primitive collisions stay in its text.)
    pub kept: Vec<BoundingVolume>,
    /// MJCF: a root body's frame in the world (identity for every other link).
    pub placement: DAffine3,
    /// URDF: byte ranges of the mesh `<collision>` elements to replace.
    pub(crate) replace: Vec<Range<usize>>,
    /// URDF: where new collisions go when there is nothing to replace (before `</link>`).
    pub(crate) insert_at: Option<usize>,
}

/// A joint between two links.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Its name.
    pub name: String,
    /// URDF's type: `revolute`, `continuous`, `prismatic`, `fixed`, `floating`, `planar`.
    pub kind: String,
    /// The parent link.
    pub parent: String,
    /// The child link.
    pub child: String,
    /// The child link's frame in the parent's.
    pub origin: DAffine3,
    /// The joint's axis in the child's frame.
    pub axis: DVec3,
    /// Lower and upper limits, when the file gives them.
    pub limit: Option<(f64, f64)>,
}

/// A robot read by [`read_robot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// The robot's (model's) name.
    pub name: String,
    /// The file it was read from, as the caller named it.
    pub file: String,
    /// The kind of file.
    pub format: RobotFormat,
    /// The links, in file order.
    pub links: Vec<Link>,
    /// The joints, in file order.
    pub joints: Vec<Joint>,
    /// The file's text (URDF: what [`to_urdf`] splices).
    pub(crate) text: String,
}

/// The per-link results the writers take, by link index (`None` for a link without meshes).
pub type LinkResults<'a> = &'a [Option<Segmentation>];

/// Reads a URDF (`.urdf`) or MJCF (`.xml`, MJCF's `<include>`s followed) robot file.
///
/// # Errors
///
/// An [`IoError`] of one line: the file cannot be read ([`IoError::Io`]), is not well-formed
/// or not a robot ([`IoError::Robot`]), repeats a link name ([`IoError::DuplicateLink`]), has
/// a joint whose parent or child is no link ([`IoError::UnknownLink`]), a mesh file that does
/// not exist ([`IoError::MissingMesh`]) or cannot be read ([`IoError::Link`]), or an include
/// cycle ([`IoError::IncludeCycle`]).
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
    check(&robot)?;
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
            out.extend(mjcf::included_files(path, &text));
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

/// Unique link names, joints between links, readable mesh formats.
fn check(robot: &Robot) -> Result<(), IoError> {
    let mut names = std::collections::BTreeSet::new();
    for link in &robot.links {
        if !names.insert(link.name.as_str()) {
            return Err(IoError::DuplicateLink {
                name: robot.file.clone(),
                link: link.name.clone(),
            });
        }
        for m in &link.meshes {
            let ext = crate::extension(&m.path);
            if !crate::MESH_EXTENSIONS.contains(&ext.as_deref().unwrap_or("")) {
                return Err(IoError::Link {
                    name: robot.file.clone(),
                    link: link.name.clone(),
                    source: Box::new(IoError::UnsupportedFormat {
                        name: m.path.display().to_string(),
                        what: "mesh",
                        ext,
                        supported: crate::SUPPORTED,
                    }),
                });
            }
        }
    }
    for j in &robot.joints {
        for (role, link) in [("parent", &j.parent), ("child", &j.child)] {
            if !names.contains(link.as_str()) {
                return Err(IoError::UnknownLink {
                    name: robot.file.clone(),
                    joint: j.name.clone(),
                    role,
                    link: link.clone(),
                });
            }
        }
    }
    Ok(())
}

impl Robot {
    /// The link's meshes loaded, scaled and placed in its frame, merged into one mesh;
    /// `None` for a link without meshes.
    ///
    /// # Errors
    ///
    /// [`IoError::Link`] naming the link, around the loader's error naming the file.
    pub fn link_mesh(&self, link: &Link) -> Result<Option<LoadedMesh>, IoError> {
        if link.meshes.is_empty() {
            return Ok(None);
        }
        let wrap = |e: IoError| IoError::Link {
            name: self.file.clone(),
            link: link.name.clone(),
            source: Box::new(e),
        };
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for m in &link.meshes {
            let loaded = crate::load(&m.path, &LoadOptions::default()).map_err(wrap)?;
            let base = positions.len();
            // A negative scale mirrors the mesh: flip the triangles so it still faces out.
            let mirrored = m.scale.x * m.scale.y * m.scale.z < 0.0;
            positions.extend(
                loaded
                    .mesh
                    .vertices()
                    .iter()
                    .map(|&v| m.origin.transform_point3(v * m.scale)),
            );
            triangles.extend(loaded.mesh.triangles().iter().map(|t| {
                let t = [
                    t[0] as usize + base,
                    t[1] as usize + base,
                    t[2] as usize + base,
                ];
                if mirrored {
                    [t[0], t[2], t[1]]
                } else {
                    t
                }
            }));
        }
        let name = format!("{} (link {})", self.file, link.name);
        crate::load_arrays(positions, triangles, &name)
            .map(Some)
            .map_err(wrap)
    }

    /// The index of the link named `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// The links in tree order: each root link (no joint names it as child), then its
    /// children depth-first in joint order.
    pub(crate) fn tree(&self) -> Vec<(usize, Option<usize>)> {
        let mut out = Vec::new();
        let mut seen = vec![false; self.links.len()];
        let is_child = |i: usize| self.joints.iter().any(|j| j.child == self.links[i].name);
        for root in 0..self.links.len() {
            if is_child(root) || seen[root] {
                continue;
            }
            let mut stack = vec![(root, None)];
            while let Some((i, joint)) = stack.pop() {
                if std::mem::replace(&mut seen[i], true) {
                    continue;
                }
                out.push((i, joint));
                let kids: Vec<(usize, Option<usize>)> = self
                    .joints
                    .iter()
                    .enumerate()
                    .filter(|(_, j)| j.parent == self.links[i].name)
                    .filter_map(|(ji, j)| self.link_index(&j.child).map(|c| (c, Some(ji))))
                    .collect();
                stack.extend(kids.into_iter().rev());
            }
        }
        out
    }

    /// For each link, the links it shares a joint with (parents first), in link order.
    pub fn adjacent(&self) -> Vec<(String, Vec<String>)> {
        self.links
            .iter()
            .map(|l| {
                let mut adj: Vec<String> = Vec::new();
                for j in &self.joints {
                    let other = if j.child == l.name {
                        &j.parent
                    } else if j.parent == l.name {
                        &j.child
                    } else {
                        continue;
                    };
                    if !adj.contains(other) && *other != l.name {
                        adj.push(other.clone());
                    }
                }
                (l.name.clone(), adj)
            })
            .collect()
    }
}

/// Shares `total` parts among links by their volumes, in proportion, each link with a mesh
/// getting at least one (largest remainders break the rounding; ties go to the earlier link).
pub fn share_parts(volumes: &[Option<f64>], total: usize) -> Vec<usize> {
    let n = volumes.iter().filter(|v| v.is_some()).count();
    let mut out = vec![0; volumes.len()];
    if n == 0 {
        return out;
    }
    let spare = total.saturating_sub(n);
    let sum: f64 = volumes.iter().flatten().map(|v| v.abs()).sum();
    let mut rem = Vec::new();
    let mut given = 0;
    for (i, v) in volumes.iter().enumerate() {
        if let Some(v) = v {
            let exact = if sum > 0.0 {
                spare as f64 * v.abs() / sum
            } else {
                spare as f64 / n as f64
            };
            let whole = exact.floor() as usize;
            out[i] = 1 + whole;
            given += whole;
            rem.push((exact - whole as f64, i));
        }
    }
    rem.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for &(_, i) in rem.iter().take(spare.saturating_sub(given)) {
        out[i] += 1;
    }
    out
}

/// [`resolve`] for link `link` of robot `robot`: a file not found is
/// [`IoError::MissingMesh`], naming every path tried.
pub(crate) fn resolve_mesh(
    dir: &Path,
    given: &str,
    robot: &str,
    link: &str,
) -> Result<PathBuf, IoError> {
    resolve(dir, given).map_err(|tried| IoError::MissingMesh {
        name: robot.to_owned(),
        link: link.to_owned(),
        file: given.to_owned(),
        tried: tried
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// Resolves a mesh file name of a robot file: `file://` and `package://NAME/` prefixes
/// dropped, relative names read from `dir`, then from each of its parents (a ROS package's
/// meshes often sit beside or above the robot file), and for `package://` also as
/// `NAME/rest` there. Returns the path found, or the paths tried.
fn resolve(dir: &Path, given: &str) -> Result<PathBuf, Vec<PathBuf>> {
    let (rest, package) = if let Some(r) = given.strip_prefix("package://") {
        match r.split_once('/') {
            Some((pkg, rest)) => (rest, Some(pkg)),
            None => (r, None),
        }
    } else {
        (given.strip_prefix("file://").unwrap_or(given), None)
    };
    let rel = Path::new(rest);
    let mut tried = Vec::new();
    if rel.is_absolute() {
        if rel.is_file() {
            return Ok(rel.to_path_buf());
        }
        return Err(vec![rel.to_path_buf()]);
    }
    let mut at = Some(dir);
    while let Some(d) = at {
        let mut candidates = vec![d.join(rel)];
        if let Some(pkg) = package {
            candidates.push(d.join(pkg).join(rel));
        }
        for c in candidates {
            if c.is_file() {
                return Ok(c);
            }
            tried.push(c);
        }
        // Give up above the package's likely root instead of walking to `/`.
        if tried.len() >= 8 || d.as_os_str().is_empty() {
            break;
        }
        at = d.parent();
    }
    Err(tried)
}

/// `x y z` numbers, or `default` when absent.
pub(crate) fn vec3(
    s: Option<&str>,
    default: DVec3,
    what: &str,
    name: &str,
) -> Result<DVec3, IoError> {
    let Some(s) = s else { return Ok(default) };
    let v = numbers(s, what, name)?;
    match v[..] {
        [x, y, z] => Ok(DVec3::new(x, y, z)),
        [x] if what.ends_with("scale") => Ok(DVec3::splat(x)),
        _ => Err(IoError::Robot {
            name: name.to_owned(),
            message: format!("{what} {s:?}: expected 3 numbers"),
        }),
    }
}

/// Whitespace-separated finite numbers.
pub(crate) fn numbers(s: &str, what: &str, name: &str) -> Result<Vec<f64>, IoError> {
    s.split_whitespace()
        .map(|t| match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(IoError::Robot {
                name: name.to_owned(),
                message: format!("{what} {s:?}: {t:?} is not a finite number"),
            }),
        })
        .collect()
}

/// URDF's roll-pitch-yaw: about fixed X, then Y, then Z.
pub(crate) fn rpy_quat(rpy: DVec3) -> DQuat {
    DQuat::from_rotation_z(rpy.z) * DQuat::from_rotation_y(rpy.y) * DQuat::from_rotation_x(rpy.x)
}

/// The roll-pitch-yaw of a rotation matrix (the inverse of [`rpy_quat`]).
pub(crate) fn matrix_rpy(m: DMat3) -> DVec3 {
    let r = |row: usize, col: usize| m.col(col)[row];
    let sp = (-r(2, 0)).clamp(-1.0, 1.0);
    let pitch = sp.asin();
    if sp.abs() > 1.0 - 1e-12 {
        // Gimbal lock: roll and yaw turn about the same axis; put it all in yaw.
        return DVec3::new(0.0, pitch, (-r(0, 1)).atan2(r(1, 1)));
    }
    DVec3::new(r(2, 1).atan2(r(2, 2)), pitch, r(1, 0).atan2(r(0, 0)))
}

/// The rotation of a volume's axes, made proper (see [`crate::export::volume_rotation`]).
pub(crate) fn proper_axes(axes: DMat3) -> DMat3 {
    let mut axes = axes;
    if axes.determinant() < 0.0 {
        axes.z_axis = -axes.z_axis;
    }
    axes
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn rpy_round_trips() {
        for rpy in [
            DVec3::new(0.1, -0.4, 2.0),
            DVec3::new(-3.0, 1.2, 0.3),
            DVec3::ZERO,
        ] {
            let m = DMat3::from_quat(rpy_quat(rpy));
            let back = DMat3::from_quat(rpy_quat(matrix_rpy(m)));
            assert!((m - back).abs().to_cols_array().iter().all(|&d| d < 1e-12));
        }
    }

    #[test]
    fn parts_are_shared_by_volume() {
        assert_eq!(
            share_parts(&[Some(3.0), None, Some(1.0)], 10),
            vec![7, 0, 3]
        );
        assert_eq!(share_parts(&[Some(1.0), Some(0.0)], 1), vec![1, 1]);
        let s = share_parts(&[Some(1.0), Some(1.0), Some(1.0)], 10);
        assert_eq!(s.iter().sum::<usize>(), 10);
    }
}
