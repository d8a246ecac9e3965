//! An MJCF robot given back as it was written, but for its colliding mesh geoms: in each
//! segmented body, the first of them becomes the body's new primitive geoms (in the frame the
//! mesh geom was written in, with its class and every attribute but its shape and mass), the
//! others go. Nothing else changes but what the files' new place needs: the files it includes
//! are written beside it (their `<include>`s renamed), and relative directories of
//! `<compiler>` lead back to the input's.
use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::Path;

use bvseg_core::{BoundingVolume, Segmentation, Shape};
use glam::{DAffine3, DMat3, DQuat, DVec3};

use super::{Site, Source};
use crate::robot::model::Robot;
use crate::robot::text::{indent_at, line_start, Edits};
use crate::xml::escape;

/// The attributes of a mesh geom that its primitives do not take: what names, shapes,
/// places and weighs it.
const NOT_COPIED: [&str; 17] = [
    "name",
    "class",
    "type",
    "mesh",
    "size",
    "pos",
    "quat",
    "euler",
    "axisangle",
    "xyaxes",
    "zaxis",
    "fromto",
    "fitscale",
    "mass",
    "density",
    "shellinertia",
    "hfield",
];

/// The MJCF files of a robot read from MJCF, with the primitives of `parts` (by link index)
/// in place of its colliding mesh geoms: `(file name, text)`, the main file (`main`) first,
/// then each included file under a name of its own (none of `taken`). `rebase` leads from
/// the directory they are written in to the input's directory.
pub(crate) fn to_mjcf_files(
    robot: &Robot,
    source: &Source,
    parts: &[Option<&Segmentation>],
    main: &str,
    taken: &[String],
    rebase: &Path,
) -> Vec<(String, String)> {
    let names = include_names(source, main, taken);
    let rebase = slashes(rebase);
    let mut edits: Vec<Edits> = source.files.iter().map(|_| Edits::default()).collect();
    for (f, file) in source.files.iter().enumerate() {
        let e = &mut edits[f];
        let mut head = format!("\n  <!-- {} -->", crate::GENERATOR);
        if f == 0 && !rebase.is_empty() {
            let mut attrs = String::new();
            if !source.has_meshdir {
                let _ = write!(attrs, " meshdir=\"{}\"", escape(&rebase));
            }
            if !source.has_texturedir {
                let _ = write!(attrs, " texturedir=\"{}\"", escape(&rebase));
            }
            if !attrs.is_empty() {
                let _ = write!(head, "\n  <compiler{attrs}/>");
            }
        }
        e.replace(file.root_open, file.root_open, head);
        for inc in &file.includes {
            e.replace(inc.value.start, inc.value.end, escape(&names[inc.file]));
        }
    }
    if !rebase.is_empty() {
        for d in &source.dirs {
            if !Path::new(&d.text).is_absolute() {
                let new = if d.text.is_empty() {
                    rebase.clone()
                } else {
                    format!("{rebase}/{}", d.text)
                };
                edits[d.file].replace(d.value.start, d.value.end, escape(&new));
            }
        }
    }
    let mut used = source.names.clone();
    for (i, link) in robot.links.iter().enumerate() {
        let Some(seg) = parts.get(i).copied().flatten() else {
            continue;
        };
        let volumes: Vec<&BoundingVolume> = seg.parts.iter().map(|p| &p.volume).collect();
        let from_geoms = source.from_geoms.get(i).copied().unwrap_or(false);
        let sites: Vec<&Site> = source
            .sites
            .iter()
            .filter(|s| s.link == i && s.replace)
            .collect();
        if let Some(first) = sites.first() {
            let text = &source.files[first.file].text;
            let indent = indent_at(text, first.range.start);
            let stem = first
                .attrs
                .iter()
                .find(|(k, _)| k == "name")
                .map_or(link.name.as_str(), |(_, v)| v.as_str());
            let geoms = geoms(&volumes, first, stem, from_geoms, &mut used);
            let new = geoms.join(&format!("\n{indent}"));
            for (k, site) in sites.iter().enumerate() {
                let e = &mut edits[site.file];
                let text = &source.files[site.file].text;
                if site.carrier {
                    // Stays for its mass, no longer colliding.
                    let name_end = site.range.start + "<geom".len();
                    e.replace(
                        name_end,
                        name_end,
                        " contype=\"0\" conaffinity=\"0\"".into(),
                    );
                    for r in &site.collision_attrs {
                        e.replace(r.start, r.end, String::new());
                    }
                    if k == 0 {
                        e.replace(site.range.end, site.range.end, format!("\n{indent}{new}"));
                    }
                } else if k == 0 {
                    e.replace(site.range.start, site.range.end, new.clone());
                } else {
                    e.replace_lines(text, site.range.start, site.range.end, String::new());
                }
            }
        } else if let Some(Some(at)) = source.inserts.get(i) {
            // A body that had no colliding mesh (its visuals were the source): new geoms
            // that collide whatever its class says, before its end tag.
            let text = &source.files[at.file].text;
            let s = line_start(text, at.at);
            let indent = format!("{}  ", &text[s..at.at]);
            let site = Site {
                link: i,
                file: at.file,
                range: at.at..at.at,
                parent: DAffine3::IDENTITY,
                attrs: vec![
                    ("contype".into(), "1".into()),
                    ("conaffinity".into(), "1".into()),
                ],
                collision_attrs: Vec::new(),
                replace: true,
                carrier: false,
            };
            let mut new = String::new();
            for g in geoms(&volumes, &site, &link.name, from_geoms, &mut used) {
                let _ = writeln!(new, "{indent}{g}");
            }
            edits[at.file].replace(s, s, new);
        }
    }
    source
        .files
        .iter()
        .zip(edits)
        .enumerate()
        .map(|(f, (file, e))| {
            let name = if f == 0 {
                main.to_owned()
            } else {
                names[f].clone()
            };
            (name, e.apply(&file.text))
        })
        .collect()
}

/// A file name for each included file: its own when no other output has it, else with its
/// index before it.
fn include_names(source: &Source, main: &str, taken: &[String]) -> Vec<String> {
    let mut seen: BTreeSet<String> = taken.iter().cloned().collect();
    seen.insert(main.to_owned());
    let mut names = vec![main.to_owned()];
    for (f, file) in source.files.iter().enumerate().skip(1) {
        let own = file
            .path
            .file_name()
            .map(|n| crate::robot::paths::file_safe(&n.to_string_lossy()))
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| "include.xml".into());
        let mut name = own.clone();
        if seen.contains(&name) {
            name = format!("{f}_{own}");
        }
        seen.insert(name.clone());
        names.push(name);
    }
    names
}

/// A path as MJCF writes it: `/` between its parts.
fn slashes(p: &Path) -> String {
    if p.is_absolute() {
        return p.to_string_lossy().into_owned();
    }
    let parts: Vec<String> = p
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

/// The `<geom>` elements of `volumes` (in the link's frame) written where `site` is: in its
/// parent's frame, with its class and its attributes but those of [`NOT_COPIED`]; named
/// `<stem>_bvseg_<k>` (made unique among `used`), weightless when the body's inertia comes
/// from its geoms.
fn geoms(
    volumes: &[&BoundingVolume],
    site: &Site,
    stem: &str,
    weightless: bool,
    used: &mut BTreeSet<String>,
) -> Vec<String> {
    let to_parent = site.parent.inverse();
    let class = site.attrs.iter().find(|(k, _)| k == "class");
    let copied: String = site
        .attrs
        .iter()
        .filter(|(k, _)| !NOT_COPIED.contains(&k.as_str()))
        .map(|(k, v)| format!(" {k}=\"{}\"", escape(v)))
        .collect();
    volumes
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let mut name = format!("{stem}_bvseg_{k}");
            let mut n = 1;
            while used.contains(&name) {
                name = format!("{stem}_bvseg_{k}_{n}");
                n += 1;
            }
            used.insert(name.clone());
            let mut s = format!("<geom name=\"{}\"", escape(&name));
            if let Some((_, c)) = class {
                let _ = write!(s, " class=\"{}\"", escape(c));
            }
            let (kind, size, center, rot) = primitive(v, &to_parent);
            let _ = write!(
                s,
                " type=\"{kind}\" size=\"{size}\" pos=\"{} {} {}\" quat=\"{} {} {} {}\"",
                center.x, center.y, center.z, rot.w, rot.x, rot.y, rot.z
            );
            if weightless {
                s.push_str(" mass=\"0\"");
            }
            s.push_str(&copied);
            s.push_str("/>");
            s
        })
        .collect()
}

/// A volume as a MuJoCo primitive placed by `to_parent`: its type, size, centre and
/// rotation. A hull, which needs a mesh, becomes its bounding box.
fn primitive(v: &BoundingVolume, to_parent: &DAffine3) -> (&'static str, String, DVec3, DQuat) {
    let rotation = |axes: DMat3| {
        let mut axes = to_parent.matrix3 * axes;
        if axes.determinant() < 0.0 {
            axes.z_axis = -axes.z_axis;
        }
        DQuat::from_mat3(&axes).normalize()
    };
    let place = |c: DVec3| to_parent.transform_point3(c);
    let r = v.radius();
    match v.shape {
        Shape::Sphere => ("sphere", format!("{r}"), place(v.center), DQuat::IDENTITY),
        Shape::Capsule if v.half_length() <= 0.0 => {
            ("sphere", format!("{r}"), place(v.center), DQuat::IDENTITY)
        }
        Shape::Capsule => (
            "capsule",
            format!("{r} {}", v.half_length()),
            place(v.center),
            rotation(v.axes),
        ),
        Shape::Cylinder => (
            "cylinder",
            format!("{r} {}", v.half_length()),
            place(v.center),
            rotation(v.axes),
        ),
        Shape::Ellipsoid | Shape::Obb => {
            let kind = if v.shape == Shape::Obb {
                "box"
            } else {
                "ellipsoid"
            };
            let h = v.radii;
            (
                kind,
                format!("{} {} {}", h.x, h.y, h.z),
                place(v.center),
                rotation(v.axes),
            )
        }
        Shape::Hull => {
            let (lo, hi) = v.aabb();
            let h = (hi - lo) * 0.5;
            (
                "box",
                format!("{} {} {}", h.x, h.y, h.z),
                place((lo + hi) * 0.5),
                rotation(DMat3::IDENTITY),
            )
        }
    }
}
