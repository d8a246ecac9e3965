//! URDF in (links, their mesh collisions or visuals, joints) and out: the original text with
//! each link's mesh collisions replaced by primitives, everything else byte for byte.
use std::fmt::Write;
use std::path::Path;

use bvseg_core::{BoundingVolume, Segmentation, Shape};
use glam::{DAffine3, DMat3, DVec3};

use super::{
    matrix_rpy, proper_axes, resolve_mesh, rpy_quat, vec3, Joint, Link, LinkResults, MeshRef,
    MeshSource, Robot, RobotFormat,
};
use crate::xml::escape;
use crate::IoError;

pub(crate) fn parse(
    path: &Path,
    name: &str,
    text: String,
    source: MeshSource,
) -> Result<Robot, IoError> {
    let bad = |message: String| IoError::Robot {
        name: name.to_owned(),
        message,
    };
    let doc = roxmltree::Document::parse(&text).map_err(|e| bad(e.to_string()))?;
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(bad(format!(
            "the root element is <{}>, not <robot>",
            root.tag_name().name()
        )));
    }
    // Empty for a bare file name: paths joined to it stay as short as the user gave them.
    let dir = path.parent().unwrap_or(Path::new(""));
    let want = match source {
        MeshSource::Collision => "collision",
        MeshSource::Visual => "visual",
    };
    let mut links = Vec::new();
    let mut joints = Vec::new();
    for node in root.children().filter(|n| n.is_element()) {
        match node.tag_name().name() {
            "link" => {
                let link_name = node
                    .attribute("name")
                    .ok_or_else(|| bad("a <link> has no name".into()))?
                    .to_owned();
                let mut link = Link {
                    name: link_name,
                    meshes: Vec::new(),
                    kept: Vec::new(),
                    placement: DAffine3::IDENTITY,
                    replace: Vec::new(),
                    insert_at: None,
                };
                for el in node.children().filter(|n| n.is_element()) {
                    let tag = el.tag_name().name();
                    if tag != "collision" && tag != "visual" {
                        continue;
                    }
                    let Some(mesh) = el
                        .children()
                        .find(|n| n.has_tag_name("geometry"))
                        .and_then(|g| g.children().find(|n| n.has_tag_name("mesh")))
                    else {
                        continue;
                    };
                    if tag == "collision" {
                        link.replace.push(el.range());
                    }
                    if tag != want {
                        continue;
                    }
                    let given = mesh.attribute("filename").ok_or_else(|| {
                        bad(format!("link {:?}: a <mesh> has no filename", link.name))
                    })?;
                    let path = resolve_mesh(dir, given, name, &link.name)?;
                    let scale = vec3(mesh.attribute("scale"), DVec3::ONE, "mesh scale", name)?;
                    let origin = origin(el.children().find(|n| n.has_tag_name("origin")), name)?;
                    link.meshes.push(MeshRef {
                        path,
                        given: given.to_owned(),
                        scale,
                        origin,
                    });
                }
                // Before `</link>`, at the indentation of the link's other children.
                let r = node.range();
                if let Some(close) = text[r.clone()].rfind("</") {
                    link.insert_at = Some(r.start + close);
                }
                links.push(link);
            }
            "joint" => {
                let get = |tag: &str, what: &str| -> Result<String, IoError> {
                    node.children()
                        .find(|n| n.has_tag_name(tag))
                        .and_then(|n| n.attribute("link"))
                        .map(str::to_owned)
                        .ok_or_else(|| {
                            bad(format!(
                                "joint {:?} has no <{tag} link=...> ({what})",
                                node.attribute("name").unwrap_or("")
                            ))
                        })
                };
                let limit = node.children().find(|n| n.has_tag_name("limit"));
                let lim = |a: &str| -> Result<Option<f64>, IoError> {
                    match limit.and_then(|l| l.attribute(a)) {
                        Some(s) => s
                            .trim()
                            .parse::<f64>()
                            .map(Some)
                            .map_err(|_| bad(format!("joint limit {a}={s:?} is not a number"))),
                        None => Ok(None),
                    }
                };
                let range = match (lim("lower")?, lim("upper")?) {
                    (Some(l), Some(u)) => Some((l, u)),
                    _ => None,
                };
                joints.push(Joint {
                    name: node.attribute("name").unwrap_or("").to_owned(),
                    kind: node.attribute("type").unwrap_or("fixed").to_owned(),
                    parent: get("parent", "parent")?,
                    child: get("child", "child")?,
                    origin: origin(node.children().find(|n| n.has_tag_name("origin")), name)?,
                    axis: vec3(
                        node.children()
                            .find(|n| n.has_tag_name("axis"))
                            .and_then(|n| n.attribute("xyz")),
                        DVec3::X,
                        "joint axis",
                        name,
                    )?,
                    limit: range,
                });
            }
            _ => {}
        }
    }
    Ok(Robot {
        name: root.attribute("name").unwrap_or("robot").to_owned(),
        file: name.to_owned(),
        format: RobotFormat::Urdf,
        links,
        joints,
        text,
    })
}

/// An `<origin xyz rpy>` as a transform (identity when absent).
fn origin(node: Option<roxmltree::Node>, name: &str) -> Result<DAffine3, IoError> {
    let Some(node) = node else {
        return Ok(DAffine3::IDENTITY);
    };
    let xyz = vec3(node.attribute("xyz"), DVec3::ZERO, "origin xyz", name)?;
    let rpy = vec3(node.attribute("rpy"), DVec3::ZERO, "origin rpy", name)?;
    Ok(DAffine3::from_rotation_translation(rpy_quat(rpy), xyz))
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

/// The robot as URDF with each segmented link's mesh collisions replaced by the primitives of
/// its segmentation (`results`, by link index), in the link's frame; capsules are written as
/// URDF 1.1 `<capsule>` only with `capsules` (boxes otherwise). A URDF input keeps the rest
/// of its text byte for byte; an MJCF input gets a URDF made of its links and joints.
pub fn to_urdf(robot: &Robot, results: LinkResults, capsules: bool) -> String {
    if robot.format == RobotFormat::Urdf {
        return splice(robot, results, capsules);
    }
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<!-- {} -->\n<robot name=\"{}\">\n",
        crate::GENERATOR,
        escape(&robot.name)
    );
    for (i, link) in robot.links.iter().enumerate() {
        let _ = writeln!(s, "  <link name=\"{}\">", escape(&link.name));
        let seg = results.get(i).and_then(Option::as_ref);
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
            escape(&j.kind)
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
        if j.kind != "fixed" {
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

fn splice(robot: &Robot, results: LinkResults, capsules: bool) -> String {
    let text = &robot.text;
    // (start, end, replacement), applied in order of position.
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    for (i, link) in robot.links.iter().enumerate() {
        let Some(Some(seg)) = results.get(i) else {
            continue;
        };
        // Whole lines: from the start of the element's line, when only blanks precede it.
        let line_start = |at: usize| {
            let s = text[..at].rfind('\n').map_or(0, |p| p + 1);
            if text[s..at].chars().all(|c| c == ' ' || c == '\t') {
                s
            } else {
                at
            }
        };
        let line_end = |at: usize| {
            let rest = &text[at..];
            let blank = rest.len() - rest.trim_start_matches([' ', '\t']).len();
            if rest[blank..].starts_with('\n') {
                at + blank + 1
            } else {
                at
            }
        };
        let (at, indent) = match (link.replace.first(), link.insert_at) {
            (Some(r), _) => {
                let s = line_start(r.start);
                (s, text[s..r.start].to_owned())
            }
            (None, Some(at)) => {
                let s = line_start(at);
                (s, format!("{}  ", &text[s..at]))
            }
            (None, None) => continue,
        };
        let new = collisions(Some(seg), link, &indent, capsules);
        let mut first = true;
        for r in &link.replace {
            let s = line_start(r.start);
            let e = line_end(r.end);
            edits.push((s, e, if first { new.clone() } else { String::new() }));
            first = false;
        }
        if link.replace.is_empty() {
            edits.push((at, at, new));
        }
    }
    edits.sort_by_key(|e| (e.0, e.1));
    let mut out = String::with_capacity(text.len());
    let mut pos = 0;
    for (s, e, new) in edits {
        if s < pos {
            continue;
        }
        out.push_str(&text[pos..s]);
        out.push_str(&new);
        pos = e;
    }
    out.push_str(&text[pos..]);
    out
}
