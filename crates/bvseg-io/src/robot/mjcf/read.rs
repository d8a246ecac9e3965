//! Reading an MJCF robot as MuJoCo compiles it: the world body and every body as links (the
//! world first, as `world`), each body's first joint as the joint to its parent, and the
//! body's geoms ([`super::geom`]). Followed as MuJoCo follows them: `<include>`s, `<compiler angle eulerseq meshdir assetdir
//! strippath autolimits inertiafromgeom inertiagrouprange>`, nested `<default>` classes with
//! `class` and `childclass` (geom, mesh and joint defaults), `<frame>`s, mesh `scale`,
//! `refpos` and `refquat`.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use glam::{DAffine3, DQuat, DVec3};
use roxmltree::Node;

use super::files::{self, File};
use super::orient::{euler_sequence, Angles};
use super::{DirAttr, Insert, Site, Source};
use crate::robot::geometry::{numbers, vec3};
use crate::robot::model::{self, Joint, JointKind, Link, Robot};
use crate::robot::{MeshSource, RobotFormat};
use crate::IoError;

/// Reads the MJCF robot at `path` (its text `text`, named `name` in messages).
pub(crate) fn parse(
    path: &Path,
    name: &str,
    text: String,
    source: MeshSource,
) -> Result<Robot, IoError> {
    let files = files::load(path, name, text)?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let read = {
        let tree = Tree::new(&files)?;
        let root = tree.root();
        if root.1.tag_name().name() != "mujoco" {
            return Err(IoError::Robot {
                name: name.to_owned(),
                message: format!(
                    "the root element is <{}>, not <mujoco>",
                    root.1.tag_name().name()
                ),
            });
        }
        let ctx = Ctx::new(&tree, name, &dir, source)?;
        let mut out = Out::default();
        ctx.world(&mut out)?;
        let model = root.1.attribute("model").unwrap_or("robot").to_owned();
        (model, ctx.dirs, ctx.has_meshdir, ctx.has_texturedir, out)
    };
    let (model, dirs, has_meshdir, has_texturedir, out) = read;
    Ok(Robot {
        name: model,
        file: name.to_owned(),
        format: RobotFormat::Mjcf,
        links: out.links,
        joints: out.joints,
        warnings: out.warnings,
        source: model::Source::Mjcf(Source {
            files,
            dir: canonical_dir(&dir),
            sites: out.sites,
            inserts: out.inserts,
            from_geoms: out.from_geoms,
            dirs,
            has_meshdir,
            has_texturedir,
            names: out.names,
        }),
    })
}

/// The files parsed, walked as one document.
struct Tree<'t> {
    files: &'t [File],
    docs: Vec<roxmltree::Document<'t>>,
}

/// An element, and the index of the file it is written in.
pub(super) type El<'d, 't> = (usize, Node<'d, 't>);

impl<'t> Tree<'t> {
    fn new(files: &'t [File]) -> Result<Self, IoError> {
        let docs = files
            .iter()
            .map(|f| {
                roxmltree::Document::parse(&f.text).map_err(|e| IoError::Robot {
                    name: f.name.clone(),
                    message: e.to_string(),
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { files, docs })
    }

    fn root(&self) -> El<'_, 't> {
        (0, self.docs[0].root_element())
    }

    /// The child elements of an element, each `<include>` replaced by the children of the
    /// included file's root.
    fn kids<'d>(&'d self, (f, node): El<'d, 't>) -> Vec<El<'d, 't>> {
        let mut out = Vec::new();
        for c in node.children().filter(|n| n.is_element()) {
            if !c.has_tag_name("include") {
                out.push((f, c));
                continue;
            }
            if let Some(inc) = self.files[f]
                .includes
                .iter()
                .find(|i| i.element == c.range())
            {
                let root = self.docs[inc.file].root_element();
                out.extend(self.kids((inc.file, root)));
            }
        }
        out
    }
}

/// The attributes a default class gives geoms, meshes and joints (a class inherits its
/// parent's).
#[derive(Debug, Clone, Default)]
pub(super) struct Defaults {
    pub(super) geom: BTreeMap<String, String>,
    mesh: BTreeMap<String, String>,
    joint: BTreeMap<String, String>,
}

/// A `<mesh>` asset.
#[derive(Debug, Clone)]
pub(super) struct Asset {
    /// Its file as written; `None` for a mesh given by vertices in the file.
    pub(super) file: Option<String>,
    pub(super) scale: DVec3,
    /// Its `refpos` and `refquat`: file coordinates `v` are taken as `refquat⁻¹ (v - refpos)`.
    pub(super) reference: Option<DAffine3>,
}

/// What the whole model sets, read before the bodies.
pub(super) struct Ctx<'d, 't> {
    tree: &'d Tree<'t>,
    pub(super) name: &'d str,
    pub(super) source: MeshSource,
    pub(super) angles: Angles,
    pub(super) autolimits: bool,
    pub(super) meshdir: PathBuf,
    pub(super) strippath: bool,
    /// `inertiafromgeom`: `Some(true)` always, `Some(false)` never, `None` for bodies
    /// without an `<inertial>` (MuJoCo's `auto`).
    pub(super) inertia_from_geoms: Option<bool>,
    pub(super) inertia_groups: (i64, i64),
    pub(super) classes: BTreeMap<String, Defaults>,
    pub(super) assets: BTreeMap<String, Asset>,
    pub(super) dirs: Vec<DirAttr>,
    pub(super) has_meshdir: bool,
    pub(super) has_texturedir: bool,
}

/// What reading the bodies gives.
#[derive(Default)]
pub(super) struct Out {
    pub(super) links: Vec<Link>,
    pub(super) joints: Vec<Joint>,
    pub(super) warnings: Vec<String>,
    pub(super) sites: Vec<Site>,
    pub(super) inserts: Vec<Option<Insert>>,
    pub(super) from_geoms: Vec<bool>,
    pub(super) names: BTreeSet<String>,
}

impl<'d, 't> Ctx<'d, 't> {
    fn new(
        tree: &'d Tree<'t>,
        name: &'d str,
        dir: &Path,
        source: MeshSource,
    ) -> Result<Self, IoError> {
        let bad = |message: String| IoError::Robot {
            name: name.to_owned(),
            message,
        };
        let top = tree.kids(tree.root());
        // Every <compiler> counts, a later attribute over an earlier one.
        let mut compiler: BTreeMap<&str, &str> = BTreeMap::new();
        let mut dirs = Vec::new();
        for (f, c) in top.iter().filter(|(_, n)| n.has_tag_name("compiler")) {
            for a in c.attributes() {
                compiler.insert(a.name(), a.value());
                if matches!(a.name(), "meshdir" | "texturedir" | "assetdir") {
                    dirs.push(DirAttr {
                        file: *f,
                        value: a.range_value(),
                        text: a.value().to_owned(),
                    });
                }
            }
        }
        let get = |a: &str| compiler.get(a).copied();
        let seq = get("eulerseq").unwrap_or("xyz");
        let angles = Angles {
            degrees: get("angle") != Some("radian"),
            eulerseq: euler_sequence(seq).ok_or_else(|| {
                bad(format!(
                    "compiler eulerseq {seq:?}: expected three of x, y, z, X, Y, Z"
                ))
            })?,
        };
        let meshdir = get("meshdir")
            .or(get("assetdir"))
            .map_or(dir.to_path_buf(), |m| dir.join(m));
        let inertia_groups = match get("inertiagrouprange") {
            Some(r) => match numbers(r, "compiler inertiagrouprange", name)?[..] {
                [a, b] => (a as i64, b as i64),
                _ => {
                    return Err(bad(format!(
                        "compiler inertiagrouprange {r:?}: expected 2 numbers"
                    )))
                }
            },
            None => (0, 5),
        };
        let mut classes = BTreeMap::new();
        for d in top.iter().filter(|(_, n)| n.has_tag_name("default")) {
            defaults(tree, *d, &Defaults::default(), &mut classes);
        }
        let mut ctx = Ctx {
            tree,
            name,
            source,
            angles,
            autolimits: get("autolimits") != Some("false"),
            meshdir,
            strippath: get("strippath") == Some("true"),
            inertia_from_geoms: match get("inertiafromgeom") {
                Some("true") => Some(true),
                Some("false") => Some(false),
                _ => None,
            },
            inertia_groups,
            classes,
            assets: BTreeMap::new(),
            has_meshdir: get("meshdir").or(get("assetdir")).is_some(),
            has_texturedir: get("texturedir").or(get("assetdir")).is_some(),
            dirs,
        };
        for (_, m) in top
            .iter()
            .filter(|(_, n)| n.has_tag_name("asset"))
            .flat_map(|a| tree.kids(*a))
            .filter(|(_, n)| n.has_tag_name("mesh"))
        {
            let class = m.attribute("class").unwrap_or("main");
            let d = ctx.class(class, "mesh asset")?;
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
            let scale = vec3(attr("scale"), DVec3::ONE, "mesh scale", name)?;
            let refpos = vec3(attr("refpos"), DVec3::ZERO, "mesh refpos", name)?;
            let refquat = match attr("refquat") {
                Some(q) => ctx
                    .angles
                    .orientation(|a| (a == "quat").then_some(q), name)?,
                None => DQuat::IDENTITY,
            };
            let reference = (refpos != DVec3::ZERO || refquat != DQuat::IDENTITY).then(|| {
                let inv = refquat.inverse();
                DAffine3::from_rotation_translation(inv, -(inv * refpos))
            });
            let asset = Asset {
                file: file.map(str::to_owned),
                scale,
                reference,
            };
            ctx.assets.insert(mesh_name, asset);
        }
        Ok(ctx)
    }

    pub(super) fn bad(&self, message: String) -> IoError {
        IoError::Robot {
            name: self.name.to_owned(),
            message,
        }
    }

    /// The defaults of `class` (`what` names who asks, for the message).
    pub(super) fn class(&self, class: &str, what: &str) -> Result<&Defaults, IoError> {
        static NONE: std::sync::OnceLock<Defaults> = std::sync::OnceLock::new();
        match self.classes.get(class) {
            Some(d) => Ok(d),
            None if class == "main" => Ok(NONE.get_or_init(Defaults::default)),
            None => Err(self.bad(format!("{what}: unknown default class {class:?}"))),
        }
    }

    /// The world body (link `world`) and the bodies in it.
    fn world(&self, out: &mut Out) -> Result<(), IoError> {
        let worlds: Vec<El> = self
            .tree
            .kids(self.tree.root())
            .into_iter()
            .filter(|(_, n)| n.has_tag_name("worldbody"))
            .collect();
        if worlds.is_empty() {
            return Err(self.bad("no <worldbody>".into()));
        }
        out.links.push(Link {
            name: "world".into(),
            meshes: Vec::new(),
            kept: Vec::new(),
        });
        out.inserts.push(None);
        out.from_geoms.push(false);
        for w in worlds {
            self.walk(w, 0, DAffine3::IDENTITY, "main", out)?;
        }
        Ok(())
    }

    /// Reads the children of `el` (a body, the world body or a `<frame>`) into link `link`:
    /// its geoms, placed by `frame` (the element's frame in the link's), its `<frame>`s with
    /// their transform and `childclass`, its child bodies.
    fn walk(
        &self,
        el: El<'d, 't>,
        link: usize,
        frame: DAffine3,
        class: &str,
        out: &mut Out,
    ) -> Result<(), IoError> {
        for kid in self.tree.kids(el) {
            match kid.1.tag_name().name() {
                "geom" => self.geom(kid, link, frame, class, out)?,
                "frame" => {
                    let f = frame * self.angles.frame(|a| kid.1.attribute(a), self.name)?;
                    let cc = kid.1.attribute("childclass").unwrap_or(class);
                    self.class(cc, &format!("body {:?}", out.links[link].name))?;
                    self.walk(kid, link, f, cc, out)?;
                }
                "body" => self.body(kid, link, frame, class, out)?,
                tag @ ("replicate" | "attach") => out.warnings.push(format!(
                    "{}: body {:?}: <{tag}> is not read: the collision meshes it makes are left \
                     as they are",
                    self.name, out.links[link].name
                )),
                _ => {}
            }
        }
        Ok(())
    }

    /// A body: a link, the joint to its parent `parent` (placed by `frame`, the frame its
    /// `pos` is given in, in the parent's), and what it holds.
    fn body(
        &self,
        el: El<'d, 't>,
        parent: usize,
        frame: DAffine3,
        class: &str,
        out: &mut Out,
    ) -> Result<(), IoError> {
        let node = el.1;
        let link_name = node
            .attribute("name")
            .map(str::to_owned)
            .unwrap_or_else(|| format!("body_{}", out.links.len()));
        let class = node.attribute("childclass").unwrap_or(class);
        self.class(class, &format!("body {link_name:?}"))?;
        let origin = frame * self.angles.frame(|a| node.attribute(a), self.name)?;
        let index = out.links.len();
        let kids = self.tree.kids(el);
        out.links.push(Link {
            name: link_name.clone(),
            meshes: Vec::new(),
            kept: Vec::new(),
        });
        // Only the visual meshes' volumes may need a place of their own (in a body whose
        // colliding geoms are all primitives).
        let text = &self.tree.files[el.0].text;
        out.inserts.push(
            text[node.range()]
                .rfind("</")
                .filter(|_| self.source == MeshSource::Visual)
                .map(|close| Insert {
                    file: el.0,
                    at: node.range().start + close,
                }),
        );
        let has_inertial = kids.iter().any(|(_, n)| n.has_tag_name("inertial"));
        out.from_geoms
            .push(self.inertia_from_geoms.unwrap_or(!has_inertial));
        let joints: Vec<El> = kids
            .iter()
            .copied()
            .filter(|(_, n)| n.has_tag_name("joint") || n.has_tag_name("freejoint"))
            .collect();
        let parent_name = out.links[parent].name.clone();
        let mut joint = Joint {
            name: format!("{link_name}_joint"),
            kind: JointKind::Fixed,
            parent: parent_name,
            child: link_name.clone(),
            origin,
            axis: DVec3::Z,
            limit: None,
        };
        if let Some(&(_, j)) = joints.first() {
            self.joint(j, class, &link_name, &mut joint)?;
        }
        if joints.len() > 1 {
            out.warnings.push(format!(
                "{}: body {link_name:?} has {} joints: the URDF output keeps the first ({:?})",
                self.name,
                joints.len(),
                joint.name
            ));
        }
        out.joints.push(joint);
        self.walk(el, index, DAffine3::IDENTITY, class, out)
    }

    /// A body's joint (`<joint>` or `<freejoint>`) into `joint`: its name, kind, axis and
    /// range, with its class's defaults.
    fn joint(&self, j: Node, class: &str, link: &str, joint: &mut Joint) -> Result<(), IoError> {
        if let Some(n) = j.attribute("name") {
            joint.name = n.to_owned();
        }
        if j.has_tag_name("freejoint") {
            joint.kind = JointKind::Floating;
            return Ok(());
        }
        let class = j.attribute("class").unwrap_or(class);
        let d = &self.class(class, &format!("body {link:?}"))?.joint;
        let attr = |a: &str| j.attribute(a).or(d.get(a).map(String::as_str));
        let t = attr("type").unwrap_or("hinge");
        joint.axis = vec3(attr("axis"), DVec3::Z, "joint axis", self.name)?;
        let range = match attr("range") {
            Some(r) => match numbers(r, "joint range", self.name)?[..] {
                [lo, hi] if t == "hinge" => {
                    Some((self.angles.radians(lo), self.angles.radians(hi)))
                }
                [lo, hi] => Some((lo, hi)),
                _ => return Err(self.bad(format!("joint range {r:?}: expected 2 numbers"))),
            },
            None => None,
        };
        let limited = match attr("limited") {
            Some("true") => true,
            Some("false") => false,
            _ => self.autolimits && range.is_some(),
        };
        joint.limit = range.filter(|_| limited);
        joint.kind = match t {
            "hinge" if joint.limit.is_some() => JointKind::Revolute,
            "hinge" => JointKind::Continuous,
            "slide" => JointKind::Prismatic,
            "ball" | "free" => JointKind::Floating,
            other => {
                return Err(self.bad(format!(
                    "body {link:?}: joint type {other:?} is not one of hinge, slide, ball, free"
                )))
            }
        };
        Ok(())
    }
}

/// Reads a `<default>` element (class `main` when it has no name) and its nested classes
/// into `classes`, each over the attributes it inherits.
fn defaults(tree: &Tree, el: El, inherited: &Defaults, classes: &mut BTreeMap<String, Defaults>) {
    let mut d = inherited.clone();
    let kids = tree.kids(el);
    for (tag, map) in [
        ("geom", &mut d.geom),
        ("mesh", &mut d.mesh),
        ("joint", &mut d.joint),
    ] {
        for (_, g) in kids.iter().filter(|(_, n)| n.has_tag_name(tag)) {
            for a in g.attributes() {
                map.insert(a.name().to_owned(), a.value().to_owned());
            }
        }
    }
    for c in kids.iter().filter(|(_, n)| n.has_tag_name("default")) {
        defaults(tree, *c, &d, classes);
    }
    let class = el.1.attribute("class").unwrap_or("main").to_owned();
    classes.insert(class, d);
}

/// The files an MJCF file includes, directly or not (canonical paths), as far as they can
/// be read.
pub(crate) fn included_files(path: &Path, text: String) -> Vec<PathBuf> {
    let name = path.display().to_string();
    files::load(path, &name, text)
        .map(|files| {
            files
                .iter()
                .skip(1)
                .map(|f| f.path.canonicalize().unwrap_or_else(|_| f.path.clone()))
                .collect()
        })
        .unwrap_or_default()
}

/// A directory as a canonical path when it can be (`""`, a bare file's directory, is `.`).
fn canonical_dir(dir: &Path) -> PathBuf {
    let d = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    d.canonicalize().unwrap_or_else(|_| dir.to_path_buf())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::robot::{read_robot, JointKind};

    /// A mesh with `refpos`, `refquat` and `scale`, turned by its class, in a body inside a
    /// `<frame>`: its file's vertices land where MuJoCo 4.0.0 puts them (`mesh_vert` placed by
    /// `geom_xpos` and `geom_xmat`, less the body's place: figures printed by MuJoCo).
    #[test]
    fn meshes_are_placed_as_mujoco_places_them() {
        let dir = bvseg_testkit::scratch("mjcf_placed");
        std::fs::write(
            dir.join("m.obj"),
            "v 2 0 0\nv 2 1 0\nv 2 0 1\nv 3 0 0\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("t.xml"),
            r#"<mujoco><compiler angle="degree"/>
  <default><default class="c"><geom type="mesh" euler="0 0 90"/></default></default>
  <asset><mesh name="m" file="m.obj" scale="2 2 2" refpos="1 0 0"
    refquat="0.7071067811865476 0 0 0.7071067811865476"/></asset>
  <worldbody><frame pos="0 0 1"><body name="b" pos="1 0 0">
    <joint name="j" range="-90 90"/><geom class="c" mesh="m" pos="0 0 0.5"/>
  </body></frame></worldbody></mujoco>"#,
        )
        .unwrap();
        let robot = read_robot(dir.join("t.xml"), MeshSource::Collision).unwrap();
        assert_eq!(robot.links[0].name, "world");
        let m = &robot.links[1].meshes[0];
        let mujoco = [
            ([2.0, 0.0, 0.0], [2.0, 0.0, 0.5]),
            ([2.0, 1.0, 0.0], [2.0, 2.0, 0.5]),
            ([2.0, 0.0, 1.0], [2.0, 0.0, 2.5]),
            ([3.0, 0.0, 0.0], [4.0, 0.0, 0.5]),
        ];
        for (file, want) in mujoco {
            let got = m.place(DVec3::from_array(file));
            assert!((got - DVec3::from_array(want)).length() < 1e-12, "{got}");
        }
        let j = &robot.joints[0];
        assert_eq!((j.name.as_str(), j.parent.as_str()), ("j", "world"));
        assert_eq!(j.kind, JointKind::Revolute);
        assert!((j.origin.translation - DVec3::new(1.0, 0.0, 1.0)).length() < 1e-12);
        let (lo, hi) = j.limit.unwrap();
        assert!((hi - std::f64::consts::FRAC_PI_2).abs() < 1e-12 && lo == -hi);
    }
}
