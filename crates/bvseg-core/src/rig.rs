//! What a character's rig tells the segmentation: a skeleton to seed parts from (the paper's
//! section 6.1) and, for a skinned mesh, how the mesh moves, so that each part's volume can
//! follow its bone and still enclose its triangles in every pose.
//!
//! The rig is attached to the [`crate::Mesh`] ([`crate::Mesh::with_rig`]); the mesh's own
//! vertices are the rest pose. Readers of skinned files (`bvseg-io`) build it by posing the
//! file's animations; a plain skeleton (joints and parents) needs no skin.
use glam::{DMat4, DVec3};

use crate::error::RigError;

/// One joint of a [`Skeleton`], in the model space of the rest pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// The joint's name (a glTF node's name, or the skeleton file's), for people.
    pub name: String,
    /// The parent joint (an index into [`Skeleton::joints`]), `None` for a root.
    pub parent: Option<usize>,
    /// The joint's world matrix in the rest pose: its frame is the bone's frame, and its
    /// translation is the joint's position. Any invertible affine matrix.
    pub rest: DMat4,
    /// The glTF node the joint is, when it came from a glTF file: what the volumes files
    /// write as a volume's `bone`.
    pub node: Option<usize>,
}

impl Joint {
    /// The joint's position in the rest pose.
    #[must_use]
    pub fn position(&self) -> DVec3 {
        self.rest.w_axis.truncate()
    }
}

/// A skeleton: joints in a forest (every parent before or after its children, no cycles).
/// Each joint with a child is a *link* from the joint to that child, and a link belongs to
/// the bone of the joint it starts at.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Skeleton {
    /// The joints.
    pub joints: Vec<Joint>,
}

impl Skeleton {
    /// Check that every parent exists and that the parents form no cycle.
    ///
    /// # Errors
    ///
    /// [`RigError::Parent`] for a parent out of range, [`RigError::Cycle`] for a cycle,
    /// [`RigError::BadJoint`] for a non-finite or singular rest matrix.
    pub fn validate(&self) -> Result<(), RigError> {
        let n = self.joints.len();
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(p) = j.parent.filter(|&p| p >= n) {
                return Err(RigError::Parent {
                    joint: i,
                    parent: p,
                    count: n,
                });
            }
            if !j.rest.is_finite() || j.rest.determinant().abs() < 1e-300 {
                return Err(RigError::BadJoint { joint: i });
            }
        }
        for start in 0..n {
            // A path longer than n joints revisits one.
            let mut at = start;
            for _ in 0..=n {
                match self.joints[at].parent {
                    Some(p) => at = p,
                    None => break,
                }
            }
            if self.joints[at].parent.is_some() {
                return Err(RigError::Cycle {
                    joint: self.joints[start].name.clone(),
                });
            }
        }
        Ok(())
    }

    /// The links, as `(joint, child)` index pairs, in joint order.
    #[must_use]
    pub fn links(&self) -> Vec<(usize, usize)> {
        let mut out: Vec<(usize, usize)> = self
            .joints
            .iter()
            .enumerate()
            .filter_map(|(c, j)| j.parent.map(|p| (p, c)))
            .collect();
        out.sort_unstable();
        out
    }
}

/// One sampled pose of a skinned mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Which animation the pose is of (poses of one animation are listed in time order, so
    /// that the segmentation can bound how far a point moves between two of them).
    pub animation: usize,
    /// The time of the pose in its animation, in seconds.
    pub time: f64,
    /// Each joint's world matrix in this pose (one per [`Skeleton::joints`]).
    pub joints: Vec<DMat4>,
    /// The posed positions of [`Skin::corners`]'s vertices.
    pub vertices: Vec<DVec3>,
}

/// How a skinned mesh moves: its skin weights and the poses its volumes must hold in.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Skin {
    /// For each vertex of the mesh, up to four `(joint, weight)` pairs (weights at least 0,
    /// summing to 1; unused pairs have weight 0). Parts formed by splits are bound to the
    /// joint carrying most of their triangles' weight.
    pub weights: Vec<[(u32, f32); 4]>,
    /// For each triangle of the mesh, its corners' indices into every [`Pose::vertices`]
    /// (vertices the loader welded at rest may move apart in a pose).
    pub corners: Vec<[u32; 3]>,
    /// The poses (besides the rest pose, which is the mesh itself) in which every volume
    /// must enclose its triangles, after moving with its bone.
    pub poses: Vec<Pose>,
}

/// A mesh's rig: a skeleton, and for a skinned mesh its skin.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Rig {
    /// The skeleton (may be empty when only the skin matters).
    pub skeleton: Skeleton,
    /// The skin, if the mesh moves.
    pub skin: Option<Skin>,
}

impl Rig {
    /// Check the rig against a mesh of `vertices` vertices and `triangles` triangles.
    ///
    /// # Errors
    ///
    /// The skeleton's errors ([`Skeleton::validate`]), and [`RigError::Skin`] for a skin
    /// whose sizes do not match the mesh, the skeleton or each other, whose joints are out
    /// of range, whose weights are negative, not finite or all zero, or whose poses are not
    /// finite.
    pub fn validate(&self, vertices: usize, triangles: usize) -> Result<(), RigError> {
        self.skeleton.validate()?;
        let Some(skin) = &self.skin else {
            return Ok(());
        };
        let joints = self.skeleton.joints.len();
        let bad = |message: String| Err(RigError::Skin { message });
        if skin.weights.len() != vertices {
            return bad(format!(
                "{} skin weights for {vertices} vertices",
                skin.weights.len()
            ));
        }
        for (v, w) in skin.weights.iter().enumerate() {
            if w.iter()
                .any(|&(j, x)| !(x.is_finite() && x >= 0.0) || (x > 0.0 && j as usize >= joints))
            {
                return bad(format!(
                    "vertex {v} has a negative or non-finite weight, or a joint out of range"
                ));
            }
            if w.iter().all(|&(_, x)| x == 0.0) {
                return bad(format!("vertex {v}'s skin weights are all zero"));
            }
        }
        if skin.corners.len() != triangles {
            return bad(format!(
                "{} skinned triangles for {triangles} triangles",
                skin.corners.len()
            ));
        }
        let posed = skin.poses.first().map_or(0, |p| p.vertices.len());
        for (i, p) in skin.poses.iter().enumerate() {
            if p.joints.len() != joints || p.vertices.len() != posed {
                return bad(format!(
                    "pose {i} has the wrong number of joints or vertices"
                ));
            }
            if !p.joints.iter().all(DMat4::is_finite) || !p.vertices.iter().all(|v| v.is_finite()) {
                return bad(format!("pose {i} is not finite"));
            }
        }
        if !skin.poses.is_empty() && skin.corners.iter().flatten().any(|&c| c as usize >= posed) {
            return bad("a triangle corner refers to no posed vertex".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(name: &str, parent: Option<usize>, at: DVec3) -> Joint {
        Joint {
            name: name.into(),
            parent,
            rest: DMat4::from_translation(at),
            node: None,
        }
    }

    #[test]
    fn links_and_cycles() {
        let mut s = Skeleton {
            joints: vec![
                joint("hip", None, DVec3::ZERO),
                joint("knee", Some(0), DVec3::Y),
                joint("foot", Some(1), DVec3::X),
                joint("spine", Some(0), DVec3::Z),
            ],
        };
        assert_eq!(s.validate(), Ok(()));
        assert_eq!(s.links(), vec![(0, 1), (0, 3), (1, 2)]);
        s.joints[0].parent = Some(2);
        assert!(matches!(s.validate(), Err(RigError::Cycle { .. })));
        s.joints[0].parent = Some(9);
        assert!(matches!(
            s.validate(),
            Err(RigError::Parent { parent: 9, .. })
        ));
    }

    #[test]
    fn a_skin_must_match_the_mesh() {
        let rig = Rig {
            skeleton: Skeleton {
                joints: vec![joint("root", None, DVec3::ZERO)],
            },
            skin: Some(Skin {
                weights: vec![[(0, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)]; 3],
                corners: vec![[0, 1, 2]],
                poses: vec![],
            }),
        };
        assert_eq!(rig.validate(3, 1), Ok(()));
        assert!(rig.validate(4, 1).is_err());
        let mut zero = rig.clone();
        if let Some(s) = zero.skin.as_mut() {
            s.weights[1][0].1 = 0.0;
        }
        assert!(matches!(zero.validate(3, 1), Err(RigError::Skin { .. })));
    }
}
