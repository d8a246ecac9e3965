//! The geoms of an MJCF body, as MuJoCo compiles them: a colliding mesh geom is a mesh to
//! segment and a place for the new geoms, a colliding primitive a collider the link keeps, a
//! geom that does not collide nothing (but, with the visual meshes as the source, its mesh).
use std::collections::BTreeMap;
use std::path::Path;

use bvseg_core::{BoundingVolume, Shape};
use glam::{DAffine3, DMat3, DVec3};
use roxmltree::Node;

use super::orient::{z_to, ORIENTATIONS};
use super::read::{Ctx, El, Out};
use super::Site;
use crate::robot::geometry::numbers;
use crate::robot::model::{self, MeshRef};
use crate::robot::paths::resolve_mesh;
use crate::robot::MeshSource;
use crate::IoError;

/// The primitive geom types a link keeps (planes, height fields and SDFs are not a link's
/// solid).
const PRIMITIVES: [&str; 5] = ["sphere", "capsule", "cylinder", "box", "ellipsoid"];

impl<'d, 't> Ctx<'d, 't> {
    /// One geom of link `link`, in the frame `frame`: a mesh to segment (and, when it
    /// collides, a site the new geoms replace), a colliding primitive to keep, or nothing.
    pub(super) fn geom(
        &self,
        (f, g): El<'d, 't>,
        link: usize,
        frame: DAffine3,
        class: &str,
        out: &mut Out,
    ) -> Result<(), IoError> {
        if let Some(n) = g.attribute("name") {
            out.names.insert(n.to_owned());
        }
        let link_name = out.links[link].name.clone();
        let class = g.attribute("class").unwrap_or(class);
        let d = &self.class(class, &format!("body {link_name:?}"))?.geom;
        let attr = |a: &str| g.attribute(a).or(d.get(a).map(String::as_str));
        let kind = attr("type").unwrap_or("sphere");
        let flag = |a: &str| -> Result<i64, IoError> {
            match attr(a) {
                None => Ok(1),
                Some(s) => s.trim().parse::<i64>().map_err(|_| {
                    self.bad(format!(
                        "body {link_name:?}: geom {a} {s:?} is not an integer"
                    ))
                }),
            }
        };
        let collides = flag("contype")? != 0 || flag("conaffinity")? != 0;
        let wanted = collides || self.source == MeshSource::Visual;
        let is_mesh = kind == "mesh";
        let fitted = PRIMITIVES.contains(&kind) && attr("mesh").is_some();
        if !(is_mesh || fitted) {
            if collides && PRIMITIVES.contains(&kind) {
                let v = self.primitive(g, d, kind, frame, &link_name)?;
                out.links[link].kept.push(v);
            }
            return Ok(());
        }
        if !wanted {
            return Ok(());
        }
        let mesh = attr("mesh")
            .ok_or_else(|| self.bad(format!("body {link_name:?}: a mesh geom names no mesh")))?;
        let asset = self.assets.get(mesh).ok_or_else(|| {
            self.bad(format!(
                "body {link_name:?}: geom names the mesh {mesh:?}, which no <mesh> asset defines"
            ))
        })?;
        // Geoms take their place from their class too (MuJoCo's element orientation wins
        // over the class's, whichever attribute gives it).
        let own = ORIENTATIONS.iter().any(|a| g.attribute(*a).is_some());
        let placed = frame
            * self.angles.frame(
                |a| {
                    if ORIENTATIONS.contains(&a) && own {
                        g.attribute(a)
                    } else {
                        attr(a)
                    }
                },
                self.name,
            )?;
        let mut segmented = false;
        match &asset.file {
            None => out.warnings.push(format!(
                "{}: body {link_name:?}: mesh {mesh:?} is given by vertices in the file, which \
                 bvseg does not read: its geom is left as it is",
                self.name
            )),
            Some(file) => {
                let file = if self.strippath {
                    Path::new(file)
                        .file_name()
                        .map_or(file.clone(), |n| n.to_string_lossy().into_owned())
                } else {
                    file.clone()
                };
                let path = resolve_mesh(&self.meshdir, &file, self.name, &link_name)?;
                if let Some(why) = model::unreadable(&path) {
                    out.warnings.push(format!(
                        "{}: body {link_name:?}: mesh {file:?}: {why}: its geom is left as it is",
                        self.name
                    ));
                } else {
                    out.links[link].meshes.push(MeshRef {
                        path,
                        given: file,
                        reference: asset.reference,
                        scale: asset.scale,
                        origin: placed,
                    });
                    segmented = true;
                }
            }
        }
        // A primitive sized from a mesh is MuJoCo's own primitive: it stays, and only the
        // outputs that do not have it (URDF, cuRobo) get its mesh's volumes.
        if !is_mesh || !collides {
            return Ok(());
        }
        let mut replace = self.source == MeshSource::Visual || segmented;
        if replace {
            if let Some(a) = ["mesh", "fromto"].into_iter().find(|a| d.contains_key(*a)) {
                out.warnings.push(format!(
                    "{}: body {link_name:?}: geom of mesh {mesh:?}: its default class {class:?} \
                     sets {a}, which a primitive geom cannot have: the geom is left as it is",
                    self.name
                ));
                replace = false;
            }
        }
        let group = attr("group")
            .and_then(|s| s.trim().parse::<i64>().ok())
            .unwrap_or(0);
        let zero = |a: &str| attr(a).and_then(|s| s.trim().parse::<f64>().ok()) == Some(0.0);
        let massless = zero("mass") || (attr("mass").is_none() && zero("density"));
        let (lo, hi) = self.inertia_groups;
        let carrier = out.from_geoms[link] && !massless && (lo..=hi).contains(&group);
        out.sites.push(Site {
            link,
            file: f,
            range: g.range(),
            parent: frame,
            attrs: g
                .attributes()
                .map(|a| (a.name().to_owned(), a.value().to_owned()))
                .collect(),
            collision_attrs: g
                .attributes()
                .filter(|a| matches!(a.name(), "contype" | "conaffinity"))
                .map(|a| a.range())
                .collect(),
            replace,
            carrier,
        });
        Ok(())
    }

    /// A colliding primitive geom as a volume in the link's frame.
    fn primitive(
        &self,
        g: Node,
        d: &BTreeMap<String, String>,
        kind: &str,
        frame: DAffine3,
        link: &str,
    ) -> Result<BoundingVolume, IoError> {
        let attr = |a: &str| g.attribute(a).or(d.get(a).map(String::as_str));
        let what = |m: &str| self.bad(format!("body {link:?}: {kind} geom: {m}"));
        let mut size = [0.0; 3];
        if let Some(s) = attr("size") {
            for (i, x) in numbers(s, "geom size", self.name)?
                .into_iter()
                .take(3)
                .enumerate()
            {
                size[i] = x;
            }
        }
        // `fromto` (capsule, cylinder, box, ellipsoid) gives the Z axis and half-length.
        let own = ORIENTATIONS.iter().any(|a| g.attribute(*a).is_some());
        let (local, half) = match (attr("fromto"), kind) {
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
                (
                    DAffine3::from_rotation_translation(z_to(axis), (from + to) * 0.5),
                    Some((to - from).length() * 0.5),
                )
            }
            _ => (
                self.angles.frame(
                    |a| {
                        if ORIENTATIONS.contains(&a) && own {
                            g.attribute(a)
                        } else {
                            attr(a)
                        }
                    },
                    self.name,
                )?,
                None,
            ),
        };
        let f = frame * local;
        let center = f.translation;
        let axes = DMat3::from_cols(
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
