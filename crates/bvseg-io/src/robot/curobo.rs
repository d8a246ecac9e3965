//! cuRobo's robot file fragment: collision spheres per link and the adjacent links to ignore.
use std::fmt::Write;

use bvseg_core::Segmentation;

use super::Robot;

/// A YAML key, quoted when it is not a plain word.
fn key(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
    {
        s.to_owned()
    } else {
        format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
    }
}

/// `collision_spheres: {LINK: [{center: [x, y, z], radius: r}]}` in each link's frame, from
/// `spheres` (each link's sphere-only segmentation, by link index) and the link's kept
/// primitives (a volume that is not a sphere is written as the sphere around its bounding
/// box), and `self_collision_ignore: {LINK: [...]}` listing each link's parent and children.
pub(crate) fn to_curobo(robot: &Robot, spheres: &[Option<&Segmentation>]) -> String {
    let mut s = format!(
        "# {}: collision spheres for {}\ncollision_spheres:\n",
        crate::GENERATOR,
        robot.name
    );
    for (i, link) in robot.links.iter().enumerate() {
        let seg = spheres.get(i).copied().flatten();
        let volumes: Vec<&bvseg_core::BoundingVolume> = seg
            .into_iter()
            .flat_map(|s| s.parts.iter().map(|p| &p.volume))
            .chain(&link.kept)
            .collect();
        if volumes.is_empty() {
            continue;
        }
        let _ = writeln!(s, "  {}:", key(&link.name));
        for v in volumes {
            let (c, r) = if v.shape == bvseg_core::Shape::Sphere {
                (v.center, v.radius())
            } else {
                let (lo, hi) = v.aabb();
                ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
            };
            let _ = writeln!(
                s,
                "    - center: [{}, {}, {}]\n      radius: {}",
                c.x, c.y, c.z, r
            );
        }
    }
    s.push_str("self_collision_ignore:\n");
    for (name, adj) in robot.adjacent() {
        let list: Vec<String> = adj.iter().map(|a| key(a)).collect();
        let _ = writeln!(s, "  {}: [{}]", key(&name), list.join(", "));
    }
    s
}
