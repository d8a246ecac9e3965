//! The volumes as a Wavefront OBJ: one object `part_<i>` per volume: a UV sphere, a box, a
//! cylinder, a capsule or the hull's triangles.
use std::fmt::Write;

use bvseg_core::Segmentation;

use super::proxy::world_triangles;

/// The segmentation's volumes as triangle meshes in one OBJ text.
pub fn to_obj(seg: &Segmentation) -> String {
    let mut s = format!("# {} volumes from {}\n", seg.parts.len(), crate::GENERATOR);
    let mut base = 1usize;
    for (i, part) in seg.parts.iter().enumerate() {
        let (positions, triangles) = world_triangles(&part.volume, 32);
        let _ = writeln!(s, "o part_{i}");
        for p in &positions {
            let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
        }
        for t in &triangles {
            let [a, b, c] = t.map(|k| base + k as usize);
            let _ = writeln!(s, "f {a} {b} {c}");
        }
        base += positions.len();
    }
    s
}
