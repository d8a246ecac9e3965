//! MJCF in (bodies as links, their mesh geoms, joints from the body tree; `<include>`s
//! followed, `meshdir` honoured) and out (a body tree with native geoms per link).
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use bvseg_core::{BoundingVolume, Shape};
use glam::{DAffine3, DQuat, DVec3};

use super::{
    numbers, read_text, resolve_mesh, vec3, Joint, Link, LinkResults, MeshRef, MeshSource, Robot,
    RobotFormat,
};
use crate::export::mjcf::{geom_element, hull_asset};
use crate::export::part_color;
use crate::xml::escape;
use crate::IoError;

/// The text with every `<include file=...>` replaced by the children of the included file's
/// root, recursively; an included name is looked up, as MuJoCo does, in the main file's
/// directory `main_dir`, then beside the including file. `chain` holds the files being
/// expanded (canonical path, and as named), to find cycles; `included` gets every file
/// included.
fn expand(
    path: &Path,
    main_dir: &Path,
    text: &str,
    chain: &mut Vec<(PathBuf, String)>,
    included: &mut Vec<PathBuf>,
) -> Result<String, IoError> {
    let name = path.display().to_string();
    let doc = roxmltree::Document::parse(text).map_err(|e| IoError::Robot {
        name: name.clone(),
        message: e.to_string(),
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
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
        let inc = [main_dir.join(file), dir.join(file)]
            .into_iter()
            .find(|p| p.is_file())
            .unwrap_or_else(|| main_dir.join(file));
        let key = inc.canonicalize().unwrap_or_else(|_| inc.clone());
        let inc_name = inc.display().to_string();
        if chain.iter().any(|(k, _)| *k == key) {
            let mut names: Vec<&str> = chain.iter().map(|(_, n)| n.as_str()).collect();
            names.push(&inc_name);
            return Err(IoError::IncludeCycle {
                name: chain[0].1.clone(),
                chain: names.join(" -> "),
            });
        }
        let inc_text = read_text(&inc, &inc_name)?;
        included.push(key.clone());
        chain.push((key, inc_name.clone()));
        let inner = expand(&inc, main_dir, &inc_text, chain, included)?;
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

/// The files an MJCF file includes, directly or not (canonical paths), as far as they can
/// be read.
pub(crate) fn included_files(path: &Path, text: &str) -> Vec<PathBuf> {
    let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut included = Vec::new();
    let name = path.display().to_string();
    let _ = expand(path, &dir, text, &mut vec![(key, name)], &mut included);
    included
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
    // Empty for a bare file name: paths joined to it stay as short as the user gave them.
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let text = expand(
        path,
        &dir,
        &text,
        &mut vec![(key, name.to_owned())],
        &mut Vec::new(),
    )?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| bad(e.to_string()))?;
    let root = doc.root_element();
    if root.tag_name().name() != "mujoco" {
        return Err(bad(format!(
            "the root element is <{}>, not <mujoco>",
            root.tag_name().name()
        )));
    }
    // Every <compiler> counts, a later attribute over an earlier one (includes may add one).
    let mut compiler: BTreeMap<&str, &str> = BTreeMap::new();
    for c in root.children().filter(|n| n.has_tag_name("compiler")) {
        for a in c.attributes() {
            compiler.insert(a.name(), a.value());
        }
    }
    let degrees = compiler.get("angle").copied() != Some("radian");
    let eulerseq =
        euler_sequence(compiler.get("eulerseq").copied().unwrap_or("xyz")).ok_or_else(|| {
            bad(format!(
                "compiler eulerseq {:?}: expected three of x, y, z, X, Y, Z",
                compiler.get("eulerseq").copied().unwrap_or_default()
            ))
        })?;
    let meshdir = compiler
        .get("meshdir")
        .or(compiler.get("assetdir"))
        .map_or(dir.clone(), |m| dir.join(m));
    let mut classes: BTreeMap<String, Defaults> = BTreeMap::new();
    for d in root.children().filter(|n| n.has_tag_name("default")) {
        defaults(d, &Defaults::default(), &mut classes);
    }
    let no_defaults = Defaults::default();
    let mut assets: BTreeMap<String, (String, DVec3)> = BTreeMap::new();
    for m in root
        .children()
        .filter(|n| n.has_tag_name("asset"))
        .flat_map(|a| a.children().filter(|n| n.has_tag_name("mesh")))
    {
        let class = m.attribute("class").unwrap_or("main");
        let d = match classes.get(class) {
            Some(d) => d,
            None if class == "main" => &no_defaults,
            None => return Err(bad(format!("mesh asset: unknown default class {class:?}"))),
        };
        let attr = |a: &str| m.attribute(a).or(d.mesh.get(a).map(String::as_str));
        let file = attr("file");
        let mesh_name = match (m.attribute("name"), file) {
            (Some(n), _) => n.to_owned(),
            (None, Some(f)) => Path::new(f)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            (None, None) => continue,
        };
        // A mesh given by its vertices in the file (no file) is recorded as such, so that a
        // geom using it gets a message that says so.
        let scale = vec3(attr("scale"), DVec3::ONE, "mesh scale", name)?;
        assets.insert(mesh_name, (file.unwrap_or_default().to_owned(), scale));
    }
    let world = root
        .children()
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
        eulerseq,
        meshdir: &meshdir,
        classes: &classes,
        assets: &assets,
        source,
    };
    // The world's own geoms are not a link's; its bodies (also inside <frame>s) are roots.
    let mut scratch = Link {
        name: "world".into(),
        meshes: Vec::new(),
        kept: Vec::new(),
        placement: DAffine3::IDENTITY,
        replace: Vec::new(),
        insert_at: None,
    };
    let mut roots = Vec::new();
    ctx.children(
        world,
        DAffine3::IDENTITY,
        "main",
        &mut scratch,
        &mut roots,
        false,
    )?;
    for (b, frame, class) in roots {
        body(&ctx, b, None, frame, &class, &mut robot)?;
    }
    Ok(robot)
}

/// The geom and mesh attributes of a default class (a class inherits its parent's).
#[derive(Debug, Clone, Default)]
struct Defaults {
    geom: BTreeMap<String, String>,
    mesh: BTreeMap<String, String>,
}

fn defaults(node: roxmltree::Node, inherited: &Defaults, classes: &mut BTreeMap<String, Defaults>) {
    let mut d = inherited.clone();
    for (tag, map) in [("geom", &mut d.geom), ("mesh", &mut d.mesh)] {
        if let Some(g) = node.children().find(|n| n.has_tag_name(tag)) {
            for a in g.attributes() {
                map.insert(a.name().to_owned(), a.value().to_owned());
            }
        }
    }
    for c in node.children().filter(|n| n.has_tag_name("default")) {
        defaults(c, &d, classes);
    }
    let class = node.attribute("class").unwrap_or("main").to_owned();
    classes.insert(class, d);
}

/// A compiler `eulerseq`: three axes, lower case for axes that turn with the frame
/// (intrinsic), upper case for fixed ones (extrinsic).
fn euler_sequence(s: &str) -> Option<[u8; 3]> {
    match s.as_bytes() {
        &[a, b, c] if [a, b, c].iter().all(|x| b"xyzXYZ".contains(x)) => Some([a, b, c]),
        _ => None,
    }
}

struct Ctx<'a> {
    name: &'a str,
    degrees: bool,
    eulerseq: [u8; 3],
    meshdir: &'a Path,
    classes: &'a BTreeMap<String, Defaults>,
    assets: &'a BTreeMap<String, (String, DVec3)>,
    source: MeshSource,
}

/// A child body to read: its element, the frame its `pos` and orientation are given in
/// (the parent body's, or a `<frame>` inside it), and its default class.
type Pending<'a, 'i> = (roxmltree::Node<'a, 'i>, DAffine3, String);

impl Ctx<'_> {
    /// A geom's attribute, else its class's default.
    fn attr<'n>(
        &'n self,
        node: roxmltree::Node<'n, 'n>,
        d: &'n Defaults,
        a: &str,
    ) -> Option<&'n str> {
        node.attribute(a)
            .or_else(|| d.geom.get(a).map(String::as_str))
    }

    /// An element's `pos` and orientation (`quat`, `axisangle`, `euler` in the compiler's
    /// `eulerseq`, `xyaxes`, `zaxis`; angles in the compiler's unit).
    fn frame(&self, node: roxmltree::Node) -> Result<DAffine3, IoError> {
        let pos = vec3(node.attribute("pos"), DVec3::ZERO, "pos", self.name)?;
        Ok(DAffine3::from_rotation_translation(
            self.orientation(node)?,
            pos,
        ))
    }

    fn orientation(&self, node: roxmltree::Node) -> Result<DQuat, IoError> {
        let angle = |x: f64| if self.degrees { x.to_radians() } else { x };
        let unit = |v: DVec3, what: &str| {
            let n = v.normalize_or_zero();
            if n == DVec3::ZERO {
                Err(self.bad(format!("{what}: a zero vector")))
            } else {
                Ok(n)
            }
        };
        if let Some(q) = node.attribute("quat") {
            return match numbers(q, "quat", self.name)?[..] {
                [w, x, y, z] if (w, x, y, z) != (0.0, 0.0, 0.0, 0.0) => {
                    Ok(DQuat::from_xyzw(x, y, z, w).normalize())
                }
                _ => Err(self.bad(format!("quat {q:?}: expected 4 numbers, not all 0"))),
            };
        }
        if let Some(aa) = node.attribute("axisangle") {
            return match numbers(aa, "axisangle", self.name)?[..] {
                [x, y, z, a] => Ok(DQuat::from_axis_angle(
                    unit(DVec3::new(x, y, z), "axisangle")?,
                    angle(a),
                )),
                _ => Err(self.bad(format!("axisangle {aa:?}: expected 4 numbers"))),
            };
        }
        if let Some(e) = node.attribute("euler") {
            let v = vec3(Some(e), DVec3::ZERO, "euler", self.name)?;
            let mut q = DQuat::IDENTITY;
            for (i, &c) in self.eulerseq.iter().enumerate() {
                let axis = match c.to_ascii_lowercase() {
                    b'x' => DVec3::X,
                    b'y' => DVec3::Y,
                    _ => DVec3::Z,
                };
                let r = DQuat::from_axis_angle(axis, angle(v[i]));
                // Lower case: about the turned frame's axis (intrinsic), upper: the fixed one.
                q = if c.is_ascii_lowercase() { q * r } else { r * q };
            }
            return Ok(q);
        }
        if let Some(xy) = node.attribute("xyaxes") {
            return match numbers(xy, "xyaxes", self.name)?[..] {
                [a, b, c, d, e, f] => {
                    let x = unit(DVec3::new(a, b, c), "xyaxes")?;
                    let y = DVec3::new(d, e, f);
                    let y = unit(y - x * x.dot(y), "xyaxes")?;
                    Ok(DQuat::from_mat3(&glam::DMat3::from_cols(x, y, x.cross(y))).normalize())
                }
                _ => Err(self.bad(format!("xyaxes {xy:?}: expected 6 numbers"))),
            };
        }
        if let Some(z) = node.attribute("zaxis") {
            let z = unit(vec3(Some(z), DVec3::Z, "zaxis", self.name)?, "zaxis")?;
            return Ok(z_to(z));
        }
        Ok(DQuat::IDENTITY)
    }

    fn bad(&self, message: String) -> IoError {
        IoError::Robot {
            name: self.name.to_owned(),
            message,
        }
    }

    /// The defaults of `class`.
    fn class(&self, class: &str, link: &str) -> Result<&Defaults, IoError> {
        static NONE: std::sync::OnceLock<Defaults> = std::sync::OnceLock::new();
        match self.classes.get(class) {
            Some(d) => Ok(d),
            None if class == "main" => Ok(NONE.get_or_init(Defaults::default)),
            None => Err(self.bad(format!("body {link:?}: unknown default class {class:?}"))),
        }
    }

    /// Reads the geoms of `node` (a body, the world body or a `<frame>`) into `link`, placed
    /// by `frame` (the node's frame in the link's), and lists its child bodies in `bodies`;
    /// `<frame>`s are followed with their transform and `childclass`. `geoms`: whether the
    /// geoms count (not the world's).
    fn children<'a, 'i>(
        &self,
        node: roxmltree::Node<'a, 'i>,
        frame: DAffine3,
        class: &str,
        link: &mut Link,
        bodies: &mut Vec<Pending<'a, 'i>>,
        geoms: bool,
    ) -> Result<(), IoError> {
        for c in node.children().filter(|n| n.is_element()) {
            match c.tag_name().name() {
                "geom" if geoms => self.geom(c, frame, class, link)?,
                "frame" => {
                    let f = frame * self.frame(c)?;
                    let cc = c.attribute("childclass").unwrap_or(class);
                    self.class(cc, &link.name)?;
                    self.children(c, f, cc, link, bodies, geoms)?;
                }
                "body" => bodies.push((c, frame, class.to_owned())),
                _ => {}
            }
        }
        Ok(())
    }

    /// One geom: a mesh to segment, a colliding primitive to keep, or nothing.
    fn geom(
        &self,
        g: roxmltree::Node,
        frame: DAffine3,
        class: &str,
        link: &mut Link,
    ) -> Result<(), IoError> {
        let class = g.attribute("class").unwrap_or(class);
        let d = self.class(class, &link.name)?;
        let attr = |a: &str| self.attr(g, d, a);
        let kind = attr("type").unwrap_or("sphere");
        let off = |a: &str| attr(a).map(str::trim) == Some("0");
        let collides = !(off("contype") && off("conaffinity"));
        let mesh = attr("mesh");
        // A primitive with a mesh is sized by MuJoCo from that mesh: segment the mesh.
        if let Some(mesh) = mesh.filter(|_| kind == "mesh" || PRIMITIVES.contains(&kind)) {
            if self.source == MeshSource::Collision && !collides {
                return Ok(());
            }
            let (file, scale) = self.assets.get(mesh).ok_or_else(|| {
                self.bad(format!(
                    "body {:?}: geom names the mesh {mesh:?}, which no <mesh> asset defines",
                    link.name
                ))
            })?;
            if file.is_empty() {
                return Err(self.bad(format!(
                    "body {:?}: mesh {mesh:?} is given by its vertices in the file, which bvseg \
                     does not read (give it a file)",
                    link.name
                )));
            }
            let path = resolve_mesh(self.meshdir, file, self.name, &link.name)?;
            link.meshes.push(MeshRef {
                path,
                given: file.clone(),
                scale: *scale,
                origin: frame * self.frame(g)?,
            });
            return Ok(());
        }
        if collides && PRIMITIVES.contains(&kind) {
            link.kept
                .push(self.primitive(g, d, kind, frame, &link.name)?);
        }
        Ok(())
    }

    /// A colliding primitive geom as a volume in the link's frame.
    fn primitive(
        &self,
        g: roxmltree::Node,
        d: &Defaults,
        kind: &str,
        frame: DAffine3,
        link: &str,
    ) -> Result<BoundingVolume, IoError> {
        let what = |m: &str| self.bad(format!("body {link:?}: {kind} geom: {m}"));
        let mut size = [0.0; 3];
        if let Some(s) = self.attr(g, d, "size") {
            for (i, x) in numbers(s, "geom size", self.name)?
                .into_iter()
                .take(3)
                .enumerate()
            {
                size[i] = x;
            }
        }
        // `fromto` (capsule, cylinder, box, ellipsoid) gives the Z axis and half-length.
        let (local, half) = match (self.attr(g, d, "fromto"), kind) {
            (Some(ft), "capsule" | "cylinder" | "box" | "ellipsoid") => {
                let v = numbers(ft, "geom fromto", self.name)?;
                let [a, b, c, x, y, z] = v[..] else {
                    return Err(what(&format!("fromto {ft:?}: expected 6 numbers")));
                };
                let (from, to) = (DVec3::new(a, b, c), DVec3::new(x, y, z));
                let axis = (to - from).normalize_or_zero();
                if axis == DVec3::ZERO {
                    return Err(what("fromto: its two ends coincide"));
                }
                let rot = z_to(axis);
                (
                    DAffine3::from_rotation_translation(rot, (from + to) * 0.5),
                    Some((to - from).length() * 0.5),
                )
            }
            _ => (self.frame(g)?, None),
        };
        let f = frame * local;
        let center = f.translation;
        let axes = glam::DMat3::from_cols(
            f.matrix3.x_axis.normalize(),
            f.matrix3.y_axis.normalize(),
            f.matrix3.z_axis.normalize(),
        );
        let (r, h) = (size[0], half.unwrap_or(size[1]));
        let positive = |xs: &[f64]| xs.iter().all(|x| *x > 0.0 && x.is_finite());
        let v = match kind {
            "sphere" if positive(&[r]) => BoundingVolume::sphere(center, r),
            "capsule" if positive(&[r, h]) => BoundingVolume::capsule(center, axes.z_axis, h, r),
            "capsule" if positive(&[r]) => BoundingVolume::sphere(center, r),
            "cylinder" if positive(&[r, h]) => BoundingVolume::cylinder(center, axes.z_axis, h, r),
            "box" | "ellipsoid" => {
                let e = DVec3::new(size[0], size[1], half.unwrap_or(size[2]));
                if !positive(&e.to_array()) {
                    return Err(what(&format!("size {e}: expected positive sizes")));
                }
                let shape = if kind == "box" {
                    Shape::Obb
                } else {
                    Shape::Ellipsoid
                };
                BoundingVolume::frame(shape, center, axes, e)
            }
            _ => return Err(what(&format!("size {size:?}: expected positive sizes"))),
        };
        Ok(v)
    }
}

/// The rotation that turns Z to the unit vector `v` about their common normal, as MuJoCo
/// makes it for `zaxis` and `fromto` (for `v = -Z`: half a turn about X), so that the frame's
/// X and Y axes are MuJoCo's too.
fn z_to(v: DVec3) -> DQuat {
    let axis = DVec3::Z.cross(v);
    let s = axis.length();
    if s < 1e-14 {
        return if v.z < 0.0 {
            DQuat::from_xyzw(1.0, 0.0, 0.0, 0.0)
        } else {
            DQuat::IDENTITY
        };
    }
    DQuat::from_axis_angle(axis / s, s.atan2(v.z))
}

/// The primitive geom types bvseg keeps (planes, height fields and SDFs are not a link's
/// solid).
const PRIMITIVES: [&str; 5] = ["sphere", "capsule", "cylinder", "box", "ellipsoid"];

fn body(
    ctx: &Ctx,
    node: roxmltree::Node,
    parent: Option<&str>,
    frame: DAffine3,
    class: &str,
    robot: &mut Robot,
) -> Result<(), IoError> {
    let link_name = node
        .attribute("name")
        .map(str::to_owned)
        .unwrap_or_else(|| format!("body_{}", robot.links.len()));
    let class = node.attribute("childclass").unwrap_or(class);
    // The body's frame in its parent's (or, for a root, in the world).
    let origin = frame * ctx.frame(node)?;
    let mut link = Link {
        name: link_name.clone(),
        meshes: Vec::new(),
        kept: Vec::new(),
        placement: if parent.is_none() {
            origin
        } else {
            DAffine3::IDENTITY
        },
        replace: Vec::new(),
        insert_at: None,
    };
    ctx.class(class, &link_name)?;
    let mut kids = Vec::new();
    ctx.children(node, DAffine3::IDENTITY, class, &mut link, &mut kids, true)?;
    robot.links.push(link);
    if let Some(parent) = parent {
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
    for (b, f, c) in kids {
        body(ctx, b, Some(&link_name), f, &c, robot)?;
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
        let origin = match joint.map(|j| &robot.joints[j]) {
            Some(j) => Some(j.origin),
            None => (link.placement != DAffine3::IDENTITY).then_some(link.placement),
        };
        if let Some(origin) = origin {
            let (_, q, t) = origin.to_scale_rotation_translation();
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    /// The body quaternions MuJoCo 4.0.0 compiles (`MjModel.body_quat`, w x y z) for
    /// `euler="10 20 30"` in degrees under each `eulerseq`, and for the other orientations.
    #[test]
    fn orientations_are_mujocos() {
        let eulers = [
            (
                "xyz",
                [
                    0.943_714_364_147_489,
                    0.127_679_440_695_780_63,
                    0.144_878_125_417_369_14,
                    0.268_535_822_751_569_2,
                ],
            ),
            (
                "zyx",
                [
                    0.951_548_524_643_788_5,
                    0.239_298_337_744_730_3,
                    0.189_307_857_412,
                    0.038_134_576_474_850_15,
                ],
            ),
            (
                "XYZ",
                [
                    0.951_548_524_643_788_5,
                    0.038_134_576_474_850_15,
                    0.189_307_857_412,
                    0.239_298_337_744_730_3,
                ],
            ),
            (
                "zYx",
                [
                    0.943_714_364_147_489,
                    0.268_535_822_751_569_2,
                    0.189_307_857_412,
                    0.038_134_576_474_850_15,
                ],
            ),
        ];
        let others = [
            (
                r#"xyaxes="0 1 0 -1 0 0""#,
                [FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2],
            ),
            (
                r#"zaxis="0 1 1""#,
                [0.923_879_532_511_286_7, -0.382_683_432_365_089_8, 0.0, 0.0],
            ),
            (
                r#"axisangle="0 1 0 20""#,
                [0.984_807_753_012_208, 0.0, 0.173_648_177_666_930_33, 0.0],
            ),
            (r#"zaxis="0 0 -1""#, [0.0, 1.0, 0.0, 0.0]),
        ];
        let cases = eulers
            .iter()
            .map(|(seq, q)| (*seq, r#"euler="10 20 30""#.to_owned(), *q))
            .chain(others.iter().map(|(a, q)| ("xyz", (*a).to_owned(), *q)));
        for (seq, attr, [w, x, y, z]) in cases {
            let xml = format!("<body {attr}/>");
            let doc = roxmltree::Document::parse(&xml).unwrap();
            let ctx = Ctx {
                name: "t.xml",
                degrees: true,
                eulerseq: euler_sequence(seq).unwrap(),
                meshdir: Path::new("."),
                classes: &BTreeMap::new(),
                assets: &BTreeMap::new(),
                source: MeshSource::Collision,
            };
            let q = ctx.orientation(doc.root_element()).unwrap();
            let want = DQuat::from_xyzw(x, y, z, w);
            // The same rotation: q and -q are one.
            let d = (q - want).length().min((q + want).length());
            assert!(d < 1e-12, "{seq} {attr}: {q} != {want}");
        }
        assert!(euler_sequence("xyw").is_none() && euler_sequence("xy").is_none());
    }
}
