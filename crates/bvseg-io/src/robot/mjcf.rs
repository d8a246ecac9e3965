//! MJCF in (bodies as links, their mesh geoms, joints from the body tree; `<include>`s
//! followed, `meshdir` honoured) and out (a body tree with native geoms per link).
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use glam::{DAffine3, DQuat, DVec3};

use super::{
    escape, numbers, read_text, resolve, vec3, Joint, Link, LinkResults, MeshRef, MeshSource,
    Robot, RobotFormat,
};
use crate::export::mjcf::{geom_element, hull_asset};
use crate::export::part_color;
use crate::IoError;

/// The text with every `<include file=...>` replaced by the children of the included file's
/// root, recursively; `chain` holds the files being expanded, to find cycles.
fn expand(path: &Path, text: &str, chain: &mut Vec<PathBuf>) -> Result<String, IoError> {
    let name = path.display().to_string();
    let doc = roxmltree::Document::parse(text).map_err(|e| IoError::Robot {
        name: name.clone(),
        message: e.to_string(),
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = String::with_capacity(text.len());
    let mut pos = 0;
    for node in doc.descendants().filter(|n| n.has_tag_name("include")) {
        let r = node.range();
        if r.start < pos {
            continue;
        }
        let file = node.attribute("file").ok_or_else(|| IoError::Robot {
            name: name.clone(),
            message: "an <include> has no file".into(),
        })?;
        let inc = dir.join(file);
        let key = inc.canonicalize().unwrap_or_else(|_| inc.clone());
        if chain.contains(&key) {
            let mut names: Vec<String> = chain.iter().map(|p| p.display().to_string()).collect();
            names.push(key.display().to_string());
            return Err(IoError::IncludeCycle {
                name,
                chain: names.join(" -> "),
            });
        }
        let inc_name = inc.display().to_string();
        let inc_text = read_text(&inc, &inc_name)?;
        chain.push(key);
        let inner = expand(&inc, &inc_text, chain)?;
        chain.pop();
        let inner_doc = roxmltree::Document::parse(&inner).map_err(|e| IoError::Robot {
            name: inc_name.clone(),
            message: e.to_string(),
        })?;
        let root = inner_doc.root_element();
        let body = match (root.first_child(), root.last_child()) {
            (Some(a), Some(b)) => &inner[a.range().start..b.range().end],
            _ => "",
        };
        out.push_str(&text[pos..r.start]);
        out.push_str(body);
        pos = r.end;
    }
    out.push_str(&text[pos..]);
    Ok(out)
}

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
    let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let text = expand(path, &text, &mut vec![key])?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| bad(e.to_string()))?;
    let root = doc.root_element();
    if root.tag_name().name() != "mujoco" {
        return Err(bad(format!(
            "the root element is <{}>, not <mujoco>",
            root.tag_name().name()
        )));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let compiler = root.descendants().find(|n| n.has_tag_name("compiler"));
    let degrees = compiler.and_then(|c| c.attribute("angle")) != Some("radian");
    let meshdir = compiler
        .and_then(|c| c.attribute("meshdir").or(c.attribute("assetdir")))
        .map_or(dir.clone(), |m| dir.join(m));
    // Geom attributes of each default class (a class inherits its parent's).
    let mut classes: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    fn defaults<'a>(
        node: roxmltree::Node<'a, 'a>,
        inherited: &BTreeMap<String, String>,
        classes: &mut BTreeMap<String, BTreeMap<String, String>>,
    ) {
        let mut attrs = inherited.clone();
        if let Some(g) = node.children().find(|n| n.has_tag_name("geom")) {
            for a in g.attributes() {
                attrs.insert(a.name().to_owned(), a.value().to_owned());
            }
        }
        let class = node.attribute("class").unwrap_or("main").to_owned();
        for c in node.children().filter(|n| n.has_tag_name("default")) {
            defaults(c, &attrs, classes);
        }
        classes.insert(class, attrs);
    }
    for d in root.children().filter(|n| n.has_tag_name("default")) {
        defaults(d, &BTreeMap::new(), &mut classes);
    }
    let mut assets: BTreeMap<String, (String, DVec3)> = BTreeMap::new();
    for m in root
        .children()
        .filter(|n| n.has_tag_name("asset"))
        .flat_map(|a| a.children().filter(|n| n.has_tag_name("mesh")))
    {
        let Some(file) = m.attribute("file") else {
            continue;
        };
        let mesh_name = m.attribute("name").map(str::to_owned).unwrap_or_else(|| {
            Path::new(file)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        let scale = vec3(m.attribute("scale"), DVec3::ONE, "mesh scale", name)?;
        assets.insert(mesh_name, (file.to_owned(), scale));
    }
    let world = root
        .descendants()
        .find(|n| n.has_tag_name("worldbody"))
        .ok_or_else(|| bad("no <worldbody>".into()))?;
    let mut robot = Robot {
        name: root.attribute("model").unwrap_or("robot").to_owned(),
        file: name.to_owned(),
        format: RobotFormat::Mjcf,
        links: Vec::new(),
        joints: Vec::new(),
        text: String::new(),
    };
    let ctx = Ctx {
        name,
        degrees,
        meshdir: &meshdir,
        classes: &classes,
        assets: &assets,
        source,
    };
    for b in world.children().filter(|n| n.has_tag_name("body")) {
        body(&ctx, b, None, "main", &mut robot)?;
    }
    Ok(robot)
}

struct Ctx<'a> {
    name: &'a str,
    degrees: bool,
    meshdir: &'a Path,
    classes: &'a BTreeMap<String, BTreeMap<String, String>>,
    assets: &'a BTreeMap<String, (String, DVec3)>,
    source: MeshSource,
}

impl Ctx<'_> {
    /// A geom's attribute, else its class's default.
    fn attr<'n>(&'n self, node: roxmltree::Node<'n, 'n>, class: &str, a: &str) -> Option<&'n str> {
        node.attribute(a).or_else(|| {
            let c = node.attribute("class").unwrap_or(class);
            self.classes
                .get(c)
                .and_then(|m| m.get(a))
                .map(String::as_str)
        })
    }

    /// An element's `pos` and orientation (`quat`, `euler` as XYZ, `axisangle`).
    fn frame(&self, node: roxmltree::Node) -> Result<DAffine3, IoError> {
        let pos = vec3(node.attribute("pos"), DVec3::ZERO, "pos", self.name)?;
        let angle = |x: f64| if self.degrees { x.to_radians() } else { x };
        let rot = if let Some(q) = node.attribute("quat") {
            match numbers(q, "quat", self.name)?[..] {
                [w, x, y, z] => DQuat::from_xyzw(x, y, z, w).normalize(),
                _ => return Err(self.bad(format!("quat {q:?}: expected 4 numbers"))),
            }
        } else if let Some(e) = node.attribute("euler") {
            let v = vec3(Some(e), DVec3::ZERO, "euler", self.name)?;
            // MJCF's default sequence `xyz`: intrinsic rotations about moving axes.
            DQuat::from_rotation_x(angle(v.x))
                * DQuat::from_rotation_y(angle(v.y))
                * DQuat::from_rotation_z(angle(v.z))
        } else if let Some(aa) = node.attribute("axisangle") {
            match numbers(aa, "axisangle", self.name)?[..] {
                [x, y, z, a] => DQuat::from_axis_angle(DVec3::new(x, y, z).normalize(), angle(a)),
                _ => return Err(self.bad(format!("axisangle {aa:?}: expected 4 numbers"))),
            }
        } else {
            DQuat::IDENTITY
        };
        Ok(DAffine3::from_rotation_translation(rot, pos))
    }

    fn bad(&self, message: String) -> IoError {
        IoError::Robot {
            name: self.name.to_owned(),
            message,
        }
    }
}

fn body(
    ctx: &Ctx,
    node: roxmltree::Node,
    parent: Option<&str>,
    class: &str,
    robot: &mut Robot,
) -> Result<(), IoError> {
    let link_name = node
        .attribute("name")
        .map(str::to_owned)
        .unwrap_or_else(|| format!("body_{}", robot.links.len()));
    let class = node.attribute("childclass").unwrap_or(class);
    let mut link = Link {
        name: link_name.clone(),
        meshes: Vec::new(),
        replace: Vec::new(),
        insert_at: None,
    };
    for g in node.children().filter(|n| n.has_tag_name("geom")) {
        let mesh = ctx.attr(g, class, "mesh");
        let kind =
            ctx.attr(g, class, "type")
                .unwrap_or(if mesh.is_some() { "mesh" } else { "sphere" });
        let (Some(mesh), "mesh") = (mesh, kind) else {
            continue;
        };
        let off = |a: &str| ctx.attr(g, class, a).map(str::trim) == Some("0");
        if ctx.source == MeshSource::Collision && off("contype") && off("conaffinity") {
            continue;
        }
        let (file, scale) = ctx.assets.get(mesh).ok_or_else(|| {
            ctx.bad(format!(
                "body {link_name:?}: geom names the mesh {mesh:?}, which no <mesh> asset defines"
            ))
        })?;
        let path = resolve(ctx.meshdir, file).map_err(|tried| IoError::MissingMesh {
            name: ctx.name.to_owned(),
            link: link_name.clone(),
            file: file.clone(),
            tried: tried
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
        link.meshes.push(MeshRef {
            path,
            given: file.clone(),
            scale: *scale,
            origin: ctx.frame(g)?,
        });
    }
    robot.links.push(link);
    if let Some(parent) = parent {
        let origin = ctx.frame(node)?;
        let (kind, axis, limit) = if node.children().any(|n| n.has_tag_name("freejoint")) {
            ("floating".to_owned(), DVec3::Z, None)
        } else if let Some(j) = node.children().find(|n| n.has_tag_name("joint")) {
            let t = j.attribute("type").unwrap_or("hinge");
            let axis = vec3(j.attribute("axis"), DVec3::Z, "joint axis", ctx.name)?;
            let limited = j.attribute("limited") != Some("false");
            let range = match (limited, j.attribute("range")) {
                (true, Some(r)) => match numbers(r, "joint range", ctx.name)?[..] {
                    [lo, hi] if t == "hinge" && ctx.degrees => {
                        Some((lo.to_radians(), hi.to_radians()))
                    }
                    [lo, hi] => Some((lo, hi)),
                    _ => return Err(ctx.bad(format!("joint range {r:?}: expected 2 numbers"))),
                },
                _ => None,
            };
            let kind = match (t, range) {
                ("hinge", Some(_)) => "revolute",
                ("hinge", None) => "continuous",
                ("slide", _) => "prismatic",
                ("ball", _) => "floating",
                ("free", _) => "floating",
                _ => "fixed",
            };
            (kind.to_owned(), axis, range)
        } else {
            ("fixed".to_owned(), DVec3::Z, None)
        };
        robot.joints.push(Joint {
            name: format!("{link_name}_joint"),
            kind,
            parent: parent.to_owned(),
            child: link_name.clone(),
            origin,
            axis,
            limit,
        });
    }
    for b in node.children().filter(|n| n.has_tag_name("body")) {
        body(ctx, b, Some(&link_name), class, robot)?;
    }
    Ok(())
}

/// The robot as MJCF: one body per link, nested by the joints (each child body placed by its
/// joint's origin, with a hinge, slide or free joint as the joint's type says; fixed joints
/// weld), and in each body a native geom per volume of the link's segmentation (`results`,
/// by link index).
pub fn to_mjcf_robot(robot: &Robot, results: LinkResults) -> String {
    let model = escape(&robot.name);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<mujoco model=\"{model}\">\n  <!-- {} -->",
        crate::GENERATOR
    );
    let mut assets = Vec::new();
    for (i, link) in robot.links.iter().enumerate() {
        if let Some(Some(seg)) = results.get(i) {
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
            match j.kind.as_str() {
                "revolute" => {
                    let _ = writeln!(
                        s,
                        "{pad}  <joint name=\"{jn}\" type=\"hinge\" axis=\"{} {} {}\"{range}/>",
                        a.x, a.y, a.z
                    );
                }
                "continuous" => {
                    let _ = writeln!(
                        s,
                        "{pad}  <joint name=\"{jn}\" type=\"hinge\" axis=\"{} {} {}\"/>",
                        a.x, a.y, a.z
                    );
                }
                "prismatic" => {
                    let _ = writeln!(
                        s,
                        "{pad}  <joint name=\"{jn}\" type=\"slide\" axis=\"{} {} {}\"{range}/>",
                        a.x, a.y, a.z
                    );
                }
                "floating" if depth == 1 => {
                    let _ = writeln!(s, "{pad}  <freejoint name=\"{jn}\"/>");
                }
                _ => {}
            }
        }
        if let Some(Some(seg)) = results.get(i) {
            for (k, p) in seg.parts.iter().enumerate() {
                let [r, g, b] = part_color(k);
                let name = format!("{}_bvseg_{k}", escape(&link.name));
                let mesh = format!("{name}_hull");
                let rgba = format!("{r:.3} {g:.3} {b:.3} 0.6");
                let _ = writeln!(s, "{pad}  {}", geom_element(&p.volume, &name, &mesh, &rgba));
                has_geom = true;
            }
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
