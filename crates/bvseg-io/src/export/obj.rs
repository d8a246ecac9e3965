//! The volumes as a Wavefront OBJ: one object `part_<i>` per volume, a UV sphere or a box.
use std::fmt::Write;

use bvseg_core::{Segmentation, Shape};

use super::proxy::{unit_cube, unit_sphere, world_mesh};

/// The segmentation's volumes as triangle meshes in one OBJ text.
pub fn to_obj(seg: &Segmentation) -> String {
    let sphere = unit_sphere(32);
    let cube = unit_cube();
    let mut s = format!("# {} volumes from {}\n", seg.parts.len(), crate::GENERATOR);
    let mut base = 1usize;
    for (i, part) in seg.parts.iter().enumerate() {
        let unit = match part.volume.shape {
            Shape::Ellipsoid => &sphere,
            Shape::Obb => &cube,
        };
        let _ = writeln!(s, "o part_{i}");
        for p in world_mesh(&part.volume, unit) {
            let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
        }
        for t in &unit.triangles {
            let [a, b, c] = t.map(|k| base + k as usize);
            let _ = writeln!(s, "f {a} {b} {c}");
        }
        base += unit.positions.len();
    }
    s
}
