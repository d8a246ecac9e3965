//! An MJCF made for a robot read from URDF: one body per link, nested by the joints, with a
//! native geom per volume.
use std::fmt::Write;

use bvseg_core::Segmentation;

use crate::export::mjcf::{geom_element, hull_asset};
use crate::export::part_color;
use crate::robot::model::{JointKind, Robot};
use crate::xml::escape;

/// The robot as MJCF: one body per link, nested by the joints (each child body placed by its
/// joint's origin, with a hinge, slide or free joint as the joint's type says; fixed joints
/// weld), and in each body a native geom per volume of the link's segmentation (`parts`, by
/// link index) and per kept primitive.
pub(crate) fn to_mjcf_robot(robot: &Robot, parts: &[Option<&Segmentation>]) -> String {
    let model = escape(&robot.name);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<mujoco model=\"{model}\">\n  <!-- {} -->",
        crate::GENERATOR
    );
    let mut assets = Vec::new();
    for (i, link) in robot.links.iter().enumerate() {
        if let Some(seg) = parts.get(i).copied().flatten() {
            for (k, p) in seg.parts.iter().enumerate() {
                if p.volume.shape == bvseg_core::Shape::Hull {
                    let mesh = format!("{}_bvseg_{k}_hull", escape(&link.name));
                    assets.push(hull_asset(&p.volume, &mesh));
                }
            }
        }
    }
    if !assets.is_empty() {
        s.push_str("  <asset>\n");
        for a in assets {
            let _ = writeln!(s, "    {a}");
        }
        s.push_str("  </asset>\n");
    }
    s.push_str("  <worldbody>\n");
    let tree = robot.tree();
    // Depth of each link in the tree, to close bodies in order.
    let mut depth_of = vec![0usize; robot.links.len()];
    let mut open: Vec<usize> = Vec::new();
    for &(i, joint) in &tree {
        let depth = match joint {
            Some(j) => robot
                .link_index(&robot.joints[j].parent)
                .map_or(0, |p| depth_of[p] + 1),
            None => 0,
        };
        depth_of[i] = depth;
        while open.len() > depth {
            open.pop();
            let _ = writeln!(s, "{}</body>", "  ".repeat(open.len() + 2));
        }
        let pad = "  ".repeat(depth + 2);
        let link = &robot.links[i];
        let mut head = format!("{pad}<body name=\"{}\"", escape(&link.name));
        if let Some(j) = joint.map(|j| &robot.joints[j]) {
            let (_, q, t) = j.origin.to_scale_rotation_translation();
            let _ = write!(
                head,
                " pos=\"{} {} {}\" quat=\"{} {} {} {}\"",
                t.x, t.y, t.z, q.w, q.x, q.y, q.z
            );
        }
        let _ = writeln!(s, "{head}>");
        let mut has_geom = false;
        if let Some(j) = joint.map(|j| &robot.joints[j]) {
            let a = j.axis;
            let range = j
                .limit
                .map(|(lo, hi)| format!(" range=\"{lo} {hi}\""))
                .unwrap_or_default();
            let jn = escape(&j.name);
            let axis = format!("axis=\"{} {} {}\"", a.x, a.y, a.z);
            match j.kind {
                JointKind::Revolute => {
                    let _ = writeln!(
                        s,
                        "{pad}  <joint name=\"{jn}\" type=\"hinge\" {axis}{range}/>"
                    );
                }
                JointKind::Continuous => {
                    let _ = writeln!(s, "{pad}  <joint name=\"{jn}\" type=\"hinge\" {axis}/>");
                }
                JointKind::Prismatic => {
                    let _ = writeln!(
                        s,
                        "{pad}  <joint name=\"{jn}\" type=\"slide\" {axis}{range}/>"
                    );
                }
                JointKind::Floating if depth == 1 => {
                    let _ = writeln!(s, "{pad}  <freejoint name=\"{jn}\"/>");
                }
                _ => {}
            }
        }
        if let Some(seg) = parts.get(i).copied().flatten() {
            for (k, p) in seg.parts.iter().enumerate() {
                let [r, g, b] = part_color(k);
                let name = format!("{}_bvseg_{k}", escape(&link.name));
                let mesh = format!("{name}_hull");
                let rgba = format!("{r:.3} {g:.3} {b:.3} 0.6");
                let _ = writeln!(s, "{pad}  {}", geom_element(&p.volume, &name, &mesh, &rgba));
                has_geom = true;
            }
        }
        for (k, v) in link.kept.iter().enumerate() {
            // The original's own primitives, in grey.
            let name = format!("{}_kept_{k}", escape(&link.name));
            let _ = writeln!(
                s,
                "{pad}  {}",
                geom_element(v, &name, "", "0.5 0.5 0.5 0.6")
            );
            has_geom = true;
        }
        if !has_geom {
            // A moving body needs mass; a link without meshes gets a token one.
            let _ = writeln!(
                s,
                "{pad}  <inertial pos=\"0 0 0\" mass=\"0.001\" diaginertia=\"1e-6 1e-6 1e-6\"/>"
            );
        }
        open.push(i);
    }
    while open.pop().is_some() {
        let _ = writeln!(s, "{}</body>", "  ".repeat(open.len() + 2));
    }
    s.push_str("  </worldbody>\n</mujoco>\n");
    s
}
