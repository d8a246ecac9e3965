//! MuJoCo MJCF output: one static body with one geom per volume, or for a character (parts
//! bound to the bones of a skeleton) a ragdoll, one body per joint nested like the skeleton.
//! MuJoCo has native ellipsoid, box, sphere, capsule and cylinder geoms (`size`: semi-axes,
//! half-extents, radius, or radius and half-length along the geom's Z), so those volumes are
//! written exactly; a hull becomes a mesh asset of its vertices, which MuJoCo collides as
//! their convex hull, placed by its vertices in the body's frame.
use std::fmt::Write;

use bvseg_core::{BoundingVolume, Segmentation, Shape, ShapeView, Skeleton};
use glam::DAffine3;

use super::proxy::{part_color, volume_rotation};
use crate::xml::escape;

/// The segmentation as an MJCF document; `model` names the model and its body. When the
/// parts are bound to the bones of a skeleton ([`Segmentation::skeleton`]), a ragdoll instead:
/// one body per joint in the rest pose, nested like the joints, each with a `ball` joint (a
/// root with a free joint), holding the geoms of the parts bound to it in its frame.
pub fn to_mjcf(seg: &Segmentation, model: &str) -> String {
    if let Some(sk) = seg
        .skeleton
        .as_ref()
        .filter(|_| seg.parts.iter().any(|p| p.bone.is_some()))
    {
        return ragdoll(seg, sk, model);
    }
    let model = name(model);
    let mut s = String::new();
    let _ = writeln!(s, "<mujoco model=\"{model}\">");
    let _ = writeln!(
        s,
        "  <!-- {}: {} {} volumes, TOV {} MOV {} -->",
        crate::GENERATOR,
        seg.parts.len(),
        seg.kinds,
        seg.metrics.tov,
        seg.metrics.mov
    );
    let hulls: Vec<usize> = (0..seg.parts.len())
        .filter(|&i| seg.parts[i].volume.shape == Shape::Hull)
        .collect();
    if !hulls.is_empty() {
        s.push_str("  <asset>\n");
        for &i in &hulls {
            let pts = seg.parts[i].volume.hull_points();
            let coords: Vec<String> = pts
                .iter()
                .map(|p| format!("{} {} {}", p.x, p.y, p.z))
                .collect();
            let _ = writeln!(
                s,
                "    <mesh name=\"part_{i}_hull\" vertex=\"{}\"/>",
                coords.join("  ")
            );
        }
        s.push_str("  </asset>\n");
    }
    s.push_str("  <worldbody>\n");
    // A body without a joint is welded to the world; add a <freejoint/> to let it move.
    let _ = writeln!(s, "    <body name=\"{model}\">");
    for (i, part) in seg.parts.iter().enumerate() {
        let v = &part.volume;
        let [r, g, b] = part_color(i);
        let rgba = format!("{r:.3} {g:.3} {b:.3} 0.6");
        if v.shape == Shape::Hull {
            let _ = writeln!(
                s,
                "      <geom name=\"part_{i}\" type=\"mesh\" mesh=\"part_{i}_hull\" rgba=\"{rgba}\"/>"
            );
            continue;
        }
        let (kind, size) = match v.view() {
            ShapeView::Ellipsoid { radii: e, .. } => {
                ("ellipsoid", format!("{} {} {}", e.x, e.y, e.z))
            }
            ShapeView::Obb {
                half_extents: e, ..
            } => ("box", format!("{} {} {}", e.x, e.y, e.z)),
            ShapeView::Sphere { radius, .. } => ("sphere", format!("{radius}")),
            // MuJoCo wants a capsule's half-length above 0.
            ShapeView::Capsule {
                half_length,
                radius,
                ..
            } if half_length <= 0.0 => ("sphere", format!("{radius}")),
            ShapeView::Capsule {
                half_length,
                radius,
                ..
            } => ("capsule", format!("{radius} {half_length}")),
            ShapeView::Cylinder {
                half_length,
                radius,
                ..
            } => ("cylinder", format!("{radius} {half_length}")),
            // Written as a mesh above.
            ShapeView::Hull { .. } => continue,
        };
        let q = volume_rotation(v);
        let _ = writeln!(
            s,
            "      <geom name=\"part_{i}\" type=\"{kind}\" size=\"{size}\" pos=\"{} {} {}\" \
             quat=\"{} {} {} {}\" rgba=\"{rgba}\"/>",
            v.center.x, v.center.y, v.center.z, q.w, q.x, q.y, q.z,
        );
    }
    s.push_str("    </body>\n  </worldbody>\n</mujoco>\n");
    s
}

/// `s` escaped for an attribute, `bvseg` when empty: the export's names come from file
/// names and a skeleton's joints, which may have none.
fn name(s: &str) -> String {
    let out = escape(s);
    if out.is_empty() {
        "bvseg".to_owned()
    } else {
        out
    }
}

/// One volume as an MJCF `<geom>` line (no indentation, no newline) named `name`; a hull
/// refers to the mesh asset `mesh`, which [`hull_asset`] writes. For writers that place
/// volumes in bodies of their own (the robot writer).
pub(crate) fn geom_element(
    v: &bvseg_core::BoundingVolume,
    name: &str,
    mesh: &str,
    rgba: &str,
) -> String {
    if v.shape == Shape::Hull {
        return format!("<geom name=\"{name}\" type=\"mesh\" mesh=\"{mesh}\" rgba=\"{rgba}\"/>");
    }
    let (kind, size) = match v.shape {
        Shape::Ellipsoid => (
            "ellipsoid",
            format!("{} {} {}", v.radii.x, v.radii.y, v.radii.z),
        ),
        Shape::Obb => ("box", format!("{} {} {}", v.radii.x, v.radii.y, v.radii.z)),
        Shape::Sphere => ("sphere", format!("{}", v.radius())),
        Shape::Capsule if v.half_length() <= 0.0 => ("sphere", format!("{}", v.radius())),
        Shape::Capsule => ("capsule", format!("{} {}", v.radius(), v.half_length())),
        Shape::Cylinder | Shape::Hull => {
            ("cylinder", format!("{} {}", v.radius(), v.half_length()))
        }
    };
    let q = volume_rotation(v);
    format!(
        "<geom name=\"{name}\" type=\"{kind}\" size=\"{size}\" pos=\"{} {} {}\" \
         quat=\"{} {} {} {}\" rgba=\"{rgba}\"/>",
        v.center.x, v.center.y, v.center.z, q.w, q.x, q.y, q.z,
    )
}

/// The mesh asset line of a hull volume for [`geom_element`].
pub(crate) fn hull_asset(v: &bvseg_core::BoundingVolume, mesh: &str) -> String {
    let coords: Vec<String> = v
        .hull_points()
        .iter()
        .map(|p| format!("{} {} {}", p.x, p.y, p.z))
        .collect();
    format!("<mesh name=\"{mesh}\" vertex=\"{}\"/>", coords.join("  "))
}

/// The ragdoll layout of [`to_mjcf`]. A body's frame is its joint's rest frame without the
/// scale (MuJoCo's bodies are rigid), so the volumes keep their size and place: at `qpos0`
/// every geom is where its volume is in the rest pose.
fn ragdoll(seg: &Segmentation, sk: &Skeleton, model: &str) -> String {
    let frames: Vec<DAffine3> = sk
        .joints
        .iter()
        .map(|j| {
            let (_, r, t) = j.rest.to_scale_rotation_translation();
            DAffine3::from_rotation_translation(r, t)
        })
        .collect();
    // Names unique among bodies (and joints, which take their body's name).
    let mut seen = std::collections::BTreeSet::new();
    let names: Vec<String> = sk
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let n = name(&j.name);
            if seen.insert(n.clone()) {
                n
            } else {
                format!("{n}_{i}")
            }
        })
        .collect();
    let mut children = vec![Vec::new(); sk.joints.len()];
    let mut roots = Vec::new();
    for (i, j) in sk.joints.iter().enumerate() {
        match j.parent {
            Some(p) => children[p].push(i),
            None => roots.push(i),
        }
    }
    let mut geoms = vec![Vec::new(); sk.joints.len()];
    let mut world_geoms = Vec::new();
    let mut assets = Vec::new();
    for (i, part) in seg.parts.iter().enumerate() {
        let [r, g, b] = part_color(i);
        let rgba = format!("{r:.3} {g:.3} {b:.3} 0.6");
        let (name, mesh) = (format!("part_{i}"), format!("part_{i}_hull"));
        let local = match part.bone.filter(|&b| b < frames.len()) {
            Some(b) => in_frame(&part.volume, frames[b].inverse()),
            None => part.volume.clone(),
        };
        if local.shape == Shape::Hull {
            assets.push(hull_asset(&local, &mesh));
        }
        // The volumes of neighbouring bones overlap: they collide with the world (a floor of
        // the default contype and conaffinity 1), not with each other.
        let geom = geom_element(&local, &name, &mesh, &rgba).replacen(
            "<geom ",
            "<geom contype=\"1\" conaffinity=\"0\" ",
            1,
        );
        match part.bone.filter(|&b| b < frames.len()) {
            Some(b) => geoms[b].push(geom),
            None => world_geoms.push(geom),
        }
    }
    // Whether a joint's subtree holds any volume.
    let mut carries: Vec<bool> = geoms.iter().map(|g| !g.is_empty()).collect();
    for j in post_order(&roots, &children) {
        if let Some(p) = sk.joints[j].parent {
            carries[p] |= carries[j];
        }
    }
    let mut s = String::new();
    let _ = writeln!(s, "<mujoco model=\"{}\">", name(model));
    let _ = writeln!(
        s,
        "  <!-- {}: {} {} volumes on {} bones, TOV {} MOV {} -->",
        crate::GENERATOR,
        seg.parts.len(),
        seg.kinds,
        sk.joints.len(),
        seg.metrics.tov,
        seg.metrics.mov
    );
    if !assets.is_empty() {
        s.push_str("  <asset>\n");
        for a in &assets {
            let _ = writeln!(s, "    {a}");
        }
        s.push_str("  </asset>\n");
    }
    s.push_str("  <worldbody>\n");
    for g in &world_geoms {
        let _ = writeln!(s, "    {g}");
    }
    // Depth-first, each body placed relative to its parent's frame.
    let mut stack: Vec<(usize, usize, bool)> = roots.iter().rev().map(|&r| (r, 2, false)).collect();
    while let Some((j, depth, close)) = stack.pop() {
        let pad = "  ".repeat(depth);
        if close {
            let _ = writeln!(s, "{pad}</body>");
            continue;
        }
        let rel = match sk.joints[j].parent {
            Some(p) => frames[p].inverse() * frames[j],
            None => frames[j],
        };
        let (_, q, t) = rel.to_scale_rotation_translation();
        let q = if q.w < 0.0 { -q } else { q };
        let _ = writeln!(
            s,
            "{pad}<body name=\"{}\" pos=\"{} {} {}\" quat=\"{} {} {} {}\">",
            names[j], t.x, t.y, t.z, q.w, q.x, q.y, q.z
        );
        // A bone without volumes has no mass to move: it stays welded to its parent, where a
        // joint of its own would make the inertia singular (its child's ball joint at the
        // same place moves the same).
        match sk.joints[j].parent {
            Some(_) if !geoms[j].is_empty() => {
                let _ = writeln!(s, "{pad}  <joint name=\"{}\" type=\"ball\"/>", names[j]);
            }
            None if carries[j] => {
                let _ = writeln!(s, "{pad}  <freejoint name=\"{}\"/>", names[j]);
                if geoms[j].is_empty() {
                    // MuJoCo wants mass on every moving body: a thousandth of the volumes'
                    // (at MuJoCo's default density), in a ball of a hundredth of the size.
                    let volume: f64 = seg.parts.iter().map(|p| p.volume.volume()).sum();
                    let mass = 1e-3 * 1000.0 * volume;
                    let r = 1e-2 * seg.metrics.diagonal;
                    let i = 0.4 * mass * r * r;
                    let _ = writeln!(
                        s,
                        "{pad}  <inertial pos=\"0 0 0\" mass=\"{mass}\" diaginertia=\"{i} {i} {i}\"/>"
                    );
                }
            }
            _ => {}
        }
        for g in &geoms[j] {
            let _ = writeln!(s, "{pad}  {g}");
        }
        stack.push((j, depth, true));
        stack.extend(children[j].iter().rev().map(|&c| (c, depth + 1, false)));
    }
    s.push_str("  </worldbody>\n</mujoco>\n");
    s
}

/// `v` in the frame whose inverse is `to_local` (a rotation and translation).
fn in_frame(v: &BoundingVolume, to_local: DAffine3) -> BoundingVolume {
    if v.shape == Shape::Hull {
        let points: Vec<_> = v
            .hull_points()
            .iter()
            .map(|&p| to_local.transform_point3(p))
            .collect();
        return BoundingVolume::hull(&points).unwrap_or_else(|| v.clone());
    }
    let mut out = v.clone();
    out.center = to_local.transform_point3(v.center);
    out.axes = to_local.matrix3 * v.axes;
    out
}

/// The joints of the forest `roots` / `children`, every child before its parent.
fn post_order(roots: &[usize], children: &[Vec<usize>]) -> Vec<usize> {
    let mut pre = Vec::new();
    let mut stack: Vec<usize> = roots.to_vec();
    while let Some(j) = stack.pop() {
        pre.push(j);
        stack.extend(&children[j]);
    }
    pre.reverse();
    pre
}

#[cfg(test)]
mod tests {
    use super::name;

    #[test]
    fn names_are_escaped_and_never_empty() {
        assert_eq!(name(""), "bvseg");
        assert_eq!(name("a\"b"), "a&quot;b");
        assert_eq!(name("hip"), "hip");
    }
}
