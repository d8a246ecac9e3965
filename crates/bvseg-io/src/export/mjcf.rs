//! MuJoCo MJCF output: one static body with one geom per volume. MuJoCo has native
//! ellipsoid and box geoms whose `size` is the semi-axes / half-extents, so the volumes are
//! written exactly.
use std::fmt::Write;

use bvseg_core::{Segmentation, Shape};

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
        seg.kind.as_str(),
        seg.metrics.tov,
        seg.metrics.mov
    );
    s.push_str("  <worldbody>\n");
    // A body without a joint is welded to the world; add a <freejoint/> to let it move.
    let _ = writeln!(s, "    <body name=\"{model}\">");
    for (i, part) in seg.parts.iter().enumerate() {
        let v = &part.volume;
        let kind = match v.shape {
            Shape::Ellipsoid => "ellipsoid",
            Shape::Obb => "box",
        };
        let q = volume_rotation(v);
        let [r, g, b] = part_color(i);
        let _ = writeln!(
            s,
            "      <geom name=\"part_{i}\" type=\"{kind}\" size=\"{} {} {}\" pos=\"{} {} {}\" \
             quat=\"{} {} {} {}\" rgba=\"{:.3} {:.3} {:.3} 0.6\"/>",
            v.radii.x,
            v.radii.y,
            v.radii.z,
            v.center.x,
            v.center.y,
            v.center.z,
            q.w,
            q.x,
            q.y,
            q.z,
            r,
            g,
            b
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
