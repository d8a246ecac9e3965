//! Writing a URDF: a URDF input given back with its mesh collisions replaced, or a URDF made
//! from the links and joints of an MJCF.
use std::fmt::Write;

use bvseg_core::{BoundingVolume, Segmentation, Shape};
use glam::{DMat3, DVec3};

use super::Source;
use crate::robot::geometry::{matrix_rpy, proper_axes};
use crate::robot::model::{self, JointKind, Link, Robot};
use crate::robot::text::{indent_at, line_start, Edits};
use crate::xml::escape;

/// The robot as URDF with each segmented link's mesh collisions replaced by the primitives of
/// its segmentation (`parts`, by link index), in the link's frame; capsules are written as
/// URDF 1.1 `<capsule>` only with `capsules` (boxes otherwise). A URDF input keeps the rest
/// of its text byte for byte; an MJCF input gets a URDF made of its links and joints.
pub(crate) fn to_urdf(robot: &Robot, parts: &[Option<&Segmentation>], capsules: bool) -> String {
    match &robot.source {
        model::Source::Urdf(source) => splice(robot, source, parts, capsules),
        model::Source::Mjcf(_) => from_links(robot, parts, capsules),
    }
}

/// The URDF primitive of a volume: its geometry element, and its frame's rotation. Kinds
/// URDF lacks (ellipsoids, hulls; capsules unless `capsules`) become the box of their
/// frame, which encloses them.
fn geometry(v: &BoundingVolume, capsules: bool) -> (String, DMat3) {
    let axes = proper_axes(v.axes);
    match v.shape {
        Shape::Sphere => (format!("<sphere radius=\"{}\"/>", v.radius()), axes),
        Shape::Capsule if v.half_length() <= 0.0 => {
            (format!("<sphere radius=\"{}\"/>", v.radius()), axes)
        }
        Shape::Capsule if capsules => (
            format!(
                "<capsule radius=\"{}\" length=\"{}\"/>",
                v.radius(),
                2.0 * v.half_length()
            ),
            axes,
        ),
        Shape::Cylinder => (
            format!(
                "<cylinder radius=\"{}\" length=\"{}\"/>",
                v.radius(),
                2.0 * v.half_length()
            ),
            axes,
        ),
        Shape::Hull => {
            // The hull's box in its own (identity) frame: its axis-aligned bounds.
            let (lo, hi) = v.aabb();
            let size = hi - lo;
            (
                format!("<box size=\"{} {} {}\"/>", size.x, size.y, size.z),
                DMat3::IDENTITY,
            )
        }
        _ => {
            let h = if v.shape == Shape::Capsule {
                DVec3::new(v.radius(), v.radius(), v.radius() + v.half_length())
            } else {
                v.radii
            };
            (
                format!("<box size=\"{} {} {}\"/>", 2.0 * h.x, 2.0 * h.y, 2.0 * h.z),
                axes,
            )
        }
    }
}

/// The `<collision>` elements of a link: its segmentation's volumes (`<link>_bvseg_<i>`) and
/// its kept primitives (`<link>_kept_<i>`), each line starting with `indent`.
fn collisions(seg: Option<&Segmentation>, link: &Link, indent: &str, capsules: bool) -> String {
    let parts = seg
        .into_iter()
        .flat_map(|s| s.parts.iter().map(|p| &p.volume))
        .enumerate()
        .map(|(i, v)| (format!("bvseg_{i}"), v));
    let kept = link
        .kept
        .iter()
        .enumerate()
        .map(|(i, v)| (format!("kept_{i}"), v));
    let mut s = String::new();
    for (tag, v) in parts.chain(kept) {
        let (geom, axes) = geometry(v, capsules);
        let center = if v.shape == Shape::Hull {
            let (lo, hi) = v.aabb();
            (lo + hi) * 0.5
        } else {
            v.center
        };
        let rpy = matrix_rpy(axes);
        let _ = write!(
            s,
            "{indent}<collision name=\"{}_{tag}\">\n{indent}  <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\n\
             {indent}  <geometry>\n{indent}    {geom}\n{indent}  </geometry>\n{indent}</collision>\n",
            escape(&link.name),
            center.x,
            center.y,
            center.z,
            rpy.x,
            rpy.y,
            rpy.z
        );
    }
    s
}

/// A URDF of the robot's links (each with its volumes and kept primitives) and joints.
fn from_links(robot: &Robot, parts: &[Option<&Segmentation>], capsules: bool) -> String {
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<!-- {} -->\n<robot name=\"{}\">\n",
        crate::GENERATOR,
        escape(&robot.name)
    );
    for (i, link) in robot.links.iter().enumerate() {
        let _ = writeln!(s, "  <link name=\"{}\">", escape(&link.name));
        let seg = parts.get(i).copied().flatten();
        s.push_str(&collisions(seg, link, "    ", capsules));
        s.push_str("  </link>\n");
    }
    for j in &robot.joints {
        let (_, rot, t) = j.origin.to_scale_rotation_translation();
        let rpy = matrix_rpy(DMat3::from_quat(rot));
        let _ = writeln!(
            s,
            "  <joint name=\"{}\" type=\"{}\">",
            escape(&j.name),
            j.kind.as_str()
        );
        let _ = writeln!(
            s,
            "    <parent link=\"{}\"/>\n    <child link=\"{}\"/>",
            escape(&j.parent),
            escape(&j.child)
        );
        let _ = writeln!(
            s,
            "    <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
            t.x, t.y, t.z, rpy.x, rpy.y, rpy.z
        );
        if j.kind != JointKind::Fixed {
            let _ = writeln!(
                s,
                "    <axis xyz=\"{} {} {}\"/>",
                j.axis.x, j.axis.y, j.axis.z
            );
        }
        if let Some((lo, hi)) = j.limit {
            let _ = writeln!(
                s,
                "    <limit lower=\"{lo}\" upper=\"{hi}\" effort=\"0\" velocity=\"0\"/>"
            );
        }
        s.push_str("  </joint>\n");
    }
    s.push_str("</robot>\n");
    s
}

/// The URDF's own text with, in each segmented link, its new collisions where its first
/// replaced mesh collision was (or before `</link>` when it had none) and the other replaced
/// ones gone.
fn splice(
    robot: &Robot,
    source: &Source,
    parts: &[Option<&Segmentation>],
    capsules: bool,
) -> String {
    let text = &source.text;
    let mut edits = Edits::default();
    for (i, (link, at)) in robot.links.iter().zip(&source.links).enumerate() {
        let Some(seg) = parts.get(i).copied().flatten() else {
            continue;
        };
        let replaced: Vec<_> = at.collisions.iter().filter(|c| c.1).collect();
        match (replaced.first(), at.insert_at) {
            (Some((first, _)), _) => {
                let new = collisions(Some(seg), link, indent_at(text, first.start), capsules);
                for (k, (r, _)) in replaced.iter().enumerate() {
                    let new = if k == 0 { new.clone() } else { String::new() };
                    edits.replace_lines(text, r.start, r.end, new);
                }
            }
            (None, Some(close)) => {
                let s = line_start(text, close);
                let indent = format!("{}  ", &text[s..close]);
                edits.replace(s, s, collisions(Some(seg), link, &indent, capsules));
            }
            (None, None) => {}
        }
    }
    edits.apply(text)
}
