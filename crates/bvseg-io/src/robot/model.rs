//! The robot as bvseg sees it, whatever file it came from: links with the meshes they collide
//! with (placed in the link's frame) and the primitives they keep, and the joints between
//! them. The text each reader keeps for its writer lives beside it, in [`Robot`]'s private
//! `source`.
use std::path::PathBuf;

use bvseg_core::BoundingVolume;
use glam::{DAffine3, DVec3};

use super::{mjcf, urdf, RobotFormat};
use crate::{IoError, LoadOptions, LoadedMesh};

/// A robot read by [`super::read_robot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// The robot's (model's) name.
    pub name: String,
    /// The file it was read from, as the caller named it.
    pub file: String,
    /// The kind of file.
    pub format: RobotFormat,
    /// The links, in file order (an MJCF's world body first, as the link `world`).
    pub links: Vec<Link>,
    /// The joints, in file order.
    pub joints: Vec<Joint>,
    /// What the reader left as it was and why, one line each (a mesh of a format bvseg
    /// cannot read stays the file's collision; an MJCF body's second joint is not in the
    /// URDF output, ...).
    pub warnings: Vec<String>,
    /// The file's text and where the writers edit it.
    pub(crate) source: Source,
}

/// What a reader keeps of the file for its writer.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Source {
    Urdf(urdf::Source),
    Mjcf(mjcf::Source),
}

/// A link (URDF) or body (MJCF).
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Its name (for an unnamed MJCF body, `body_<n>`).
    pub name: String,
    /// The meshes to segment, in file order.
    pub meshes: Vec<MeshRef>,
    /// MJCF: the body's colliding primitive geoms (sphere, capsule, cylinder, box,
    /// ellipsoid), in its frame, which every output keeps. (A URDF's primitive collisions
    /// stay in its text.)
    pub kept: Vec<BoundingVolume>,
}

/// One mesh of a link, as the robot file places it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshRef {
    /// The file, resolved to a path that exists.
    pub path: PathBuf,
    /// The file name as the robot file gives it (for messages).
    pub given: String,
    /// MJCF: the mesh's `refpos` and `refquat` (its coordinates are taken relative to
    /// them), applied before `scale`; `None` for none.
    pub reference: Option<DAffine3>,
    /// Scale applied to the mesh's coordinates before `origin`.
    pub scale: DVec3,
    /// The mesh's frame in the link's frame.
    pub origin: DAffine3,
}

impl MeshRef {
    /// A point of the mesh file in the link's frame.
    pub fn place(&self, p: DVec3) -> DVec3 {
        let p = self.reference.map_or(p, |r| r.transform_point3(p));
        self.origin.transform_point3(p * self.scale)
    }
}

/// A joint's type, as URDF names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// A hinge with limits (MJCF `hinge` with a range).
    Revolute,
    /// A hinge without limits.
    Continuous,
    /// A slider (MJCF `slide`).
    Prismatic,
    /// No motion (an MJCF body without joints).
    Fixed,
    /// Free motion (MJCF `free`; `ball`, which URDF lacks, is written as this too).
    Floating,
    /// Motion in a plane.
    Planar,
}

impl JointKind {
    /// The URDF `type` attribute.
    pub fn as_str(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
            JointKind::Floating => "floating",
            JointKind::Planar => "planar",
        }
    }

    /// The kind of a URDF `type` attribute; `None` for a name URDF does not define.
    pub fn from_urdf(name: &str) -> Option<Self> {
        Some(match name {
            "revolute" => JointKind::Revolute,
            "continuous" => JointKind::Continuous,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            "floating" => JointKind::Floating,
            "planar" => JointKind::Planar,
            _ => return None,
        })
    }
}

/// A joint between two links.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Its name.
    pub name: String,
    /// What motion it allows.
    pub kind: JointKind,
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

impl Robot {
    /// The link's meshes loaded and placed in its frame, merged into one mesh; `None` for a
    /// link without meshes.
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
            positions.extend(loaded.mesh.vertices().iter().map(|&v| m.place(v)));
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
    /// children depth-first in joint order; with the joint that leads to each.
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

    /// The robot's own files, as canonical paths: the robot file, the files it includes, the
    /// meshes it segments.
    pub(crate) fn inputs(&self) -> Vec<PathBuf> {
        let mut out = vec![PathBuf::from(&self.file)];
        if let Source::Mjcf(s) = &self.source {
            out.extend(s.files.iter().map(|f| f.path.clone()));
        }
        out.extend(
            self.links
                .iter()
                .flat_map(|l| l.meshes.iter().map(|m| m.path.clone())),
        );
        out.iter().filter_map(|p| p.canonicalize().ok()).collect()
    }

    /// Unique link names, and joints between links.
    pub(crate) fn check(&self) -> Result<(), IoError> {
        let mut names = std::collections::BTreeSet::new();
        for link in &self.links {
            if !names.insert(link.name.as_str()) {
                return Err(IoError::DuplicateLink {
                    name: self.file.clone(),
                    link: link.name.clone(),
                });
            }
        }
        for j in &self.joints {
            for (role, link) in [("parent", &j.parent), ("child", &j.child)] {
                if !names.contains(link.as_str()) {
                    return Err(IoError::UnknownLink {
                        name: self.file.clone(),
                        joint: j.name.clone(),
                        role,
                        link: link.clone(),
                    });
                }
            }
        }
        Ok(())
    }
}

/// Why bvseg cannot read the mesh file at `path` (its format), or `None` when it can.
pub(crate) fn unreadable(path: &std::path::Path) -> Option<String> {
    let ext = crate::extension(path);
    if crate::MESH_EXTENSIONS.contains(&ext.as_deref().unwrap_or("")) {
        return None;
    }
    Some(match ext {
        Some(e) => format!(
            "unsupported mesh format '.{e}' (bvseg reads {})",
            crate::SUPPORTED
        ),
        None => format!("no file extension (bvseg reads {})", crate::SUPPORTED),
    })
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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn joint_kinds_round_trip() {
        for k in [
            JointKind::Revolute,
            JointKind::Continuous,
            JointKind::Prismatic,
            JointKind::Fixed,
            JointKind::Floating,
            JointKind::Planar,
        ] {
            assert_eq!(JointKind::from_urdf(k.as_str()), Some(k));
        }
        assert_eq!(JointKind::from_urdf("hinge"), None);
    }
}
