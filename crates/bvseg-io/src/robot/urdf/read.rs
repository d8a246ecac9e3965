//! Reading a URDF: its links with their mesh collisions (or visuals) placed in the link's
//! frame, its joints, and where the writer will splice.
use std::path::Path;

use glam::{DAffine3, DVec3};

use super::{LinkSites, Source};
use crate::robot::geometry::{rpy_quat, vec3};
use crate::robot::model::{self, Joint, JointKind, Link, MeshRef, Robot};
use crate::robot::paths::resolve_mesh;
use crate::robot::{MeshSource, RobotFormat};
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
    let mut sites = Vec::new();
    let mut joints = Vec::new();
    let mut warnings = Vec::new();
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
                };
                let mut at = LinkSites::default();
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
                    let mut readable = false;
                    if tag == want {
                        let given = mesh.attribute("filename").ok_or_else(|| {
                            bad(format!("link {:?}: a <mesh> has no filename", link.name))
                        })?;
                        let path = resolve_mesh(dir, given, name, &link.name)?;
                        if let Some(w) = model::unreadable(&path) {
                            warnings.push(format!(
                                "{name}: link {:?}: mesh {given:?}: {w}: its {tag} is left as it is",
                                link.name
                            ));
                        } else {
                            readable = true;
                            let scale =
                                vec3(mesh.attribute("scale"), DVec3::ONE, "mesh scale", name)?;
                            let origin =
                                origin(el.children().find(|n| n.has_tag_name("origin")), name)?;
                            link.meshes.push(MeshRef {
                                path,
                                given: given.to_owned(),
                                reference: None,
                                scale,
                                origin,
                            });
                        }
                    }
                    if tag == "collision" {
                        // A collision whose own mesh cannot be read stays; with the visuals
                        // as the source, every mesh collision gives way to their volumes.
                        let replace = source == MeshSource::Visual || readable;
                        at.collisions.push((el.range(), replace));
                    }
                }
                // Before `</link>`, at the indentation of the link's other children.
                let r = node.range();
                if let Some(close) = text[r.clone()].rfind("</") {
                    at.insert_at = Some(r.start + close);
                }
                links.push(link);
                sites.push(at);
            }
            "joint" => joints.push(joint(node, name)?),
            _ => {}
        }
    }
    let robot_name = root.attribute("name").unwrap_or("robot").to_owned();
    drop(doc);
    Ok(Robot {
        name: robot_name,
        file: name.to_owned(),
        format: RobotFormat::Urdf,
        links,
        joints,
        warnings,
        source: model::Source::Urdf(Source { text, links: sites }),
    })
}

fn joint(node: roxmltree::Node, name: &str) -> Result<Joint, IoError> {
    let bad = |message: String| IoError::Robot {
        name: name.to_owned(),
        message,
    };
    let joint_name = node.attribute("name").unwrap_or("");
    let get = |tag: &str| -> Result<String, IoError> {
        node.children()
            .find(|n| n.has_tag_name(tag))
            .and_then(|n| n.attribute("link"))
            .map(str::to_owned)
            .ok_or_else(|| bad(format!("joint {joint_name:?} has no <{tag} link=...>")))
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
    let t = node.attribute("type").unwrap_or("fixed");
    let kind = JointKind::from_urdf(t).ok_or_else(|| {
        bad(format!(
            "joint {joint_name:?}: type {t:?} is not one of revolute, continuous, prismatic, \
             fixed, floating, planar"
        ))
    })?;
    Ok(Joint {
        name: joint_name.to_owned(),
        kind,
        parent: get("parent")?,
        child: get("child")?,
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
