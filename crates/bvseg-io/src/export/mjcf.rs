//! MuJoCo MJCF output: one static body with one geom per volume. MuJoCo has native
//! ellipsoid, box, sphere, capsule and cylinder geoms (`size`: semi-axes, half-extents,
//! radius, or radius and half-length along the geom's Z), so those volumes are written
//! exactly; a hull becomes a mesh asset of its vertices, which MuJoCo collides as their
//! convex hull, placed by its vertices in the body's frame.
use std::fmt::Write;

use bvseg_core::{Segmentation, Shape, ShapeView};

use super::proxy::{part_color, volume_rotation};

/// The segmentation as an MJCF document; `model` names the model and its body.
pub fn to_mjcf(seg: &Segmentation, model: &str) -> String {
    let model = escape(model);
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

/// Escapes text for an XML attribute.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push('_'),
            c => out.push(c),
        }
    }
    if out.is_empty() {
        out.push_str("bvseg");
    }
    out
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
