//! A robot's colliders as USD: one `Xform` per link at its world pose with every joint at
//! zero (URDF's joint origins, MJCF's `qpos0`), holding the link's colliders in its frame:
//! the volumes of its meshes and, for MJCF, the primitives it kept. The stage is Z-up in
//! meters, as URDF and MuJoCo are. No joints or rigid bodies: it is a collision layer to place
//! over a robot already in USD (Isaac's URDF and MJCF importers make the articulation).
use bvseg_core::Segmentation;
use glam::DAffine3;

use super::Robot;
use crate::export::usd::{
    close_prim, collider, identifier, open_prim, open_xform, stage_header, UpAxis, UsdOptions,
};

/// The USDA document of `robot` with `parts` (each link's volumes, by link index).
pub(crate) fn to_usda_robot(robot: &Robot, parts: &[Option<&Segmentation>]) -> String {
    let root = identifier(&robot.name);
    let options = UsdOptions {
        up_axis: UpAxis::Z,
        ..UsdOptions::default()
    };
    let doc = format!(
        "{}: colliders of {} at zero joint angles",
        crate::GENERATOR,
        robot.name
    );
    let mut s = String::new();
    stage_header(&mut s, &root, &doc, &options);
    open_prim(&mut s, 0, "Xform", &root, &[]);
    let mut seen = std::collections::BTreeSet::new();
    for (i, pose) in world_poses(robot).into_iter().enumerate() {
        let link = &robot.links[i];
        let volumes: Vec<&bvseg_core::BoundingVolume> = parts
            .get(i)
            .copied()
            .flatten()
            .into_iter()
            .flat_map(|s| s.parts.iter().map(|p| &p.volume))
            .chain(&link.kept)
            .collect();
        if volumes.is_empty() {
            continue;
        }
        // Prim names unique among siblings, as link names are among links.
        let mut name = identifier(&link.name);
        if !seen.insert(name.clone()) {
            name = format!("{name}_{i}");
            seen.insert(name.clone());
        }
        let (_, q, t) = pose.to_scale_rotation_translation();
        open_xform(&mut s, 1, &name, t, q);
        for (k, v) in volumes.into_iter().enumerate() {
            collider(&mut s, 2, v, &format!("part_{k}"), &[]);
        }
        close_prim(&mut s, 1);
    }
    close_prim(&mut s, 0);
    s
}

/// Each link's frame in the world with every joint at zero: the product of the joint
/// origins from its root link down (a root link sits at the origin).
fn world_poses(robot: &Robot) -> Vec<DAffine3> {
    let mut poses = vec![DAffine3::IDENTITY; robot.links.len()];
    // Tree order visits a parent before its children.
    for (i, joint) in robot.tree() {
        if let Some(j) = joint.and_then(|j| robot.joints.get(j)) {
            let parent = robot
                .link_index(&j.parent)
                .map_or(DAffine3::IDENTITY, |p| poses[p]);
            poses[i] = parent * j.origin;
        }
    }
    poses
}
