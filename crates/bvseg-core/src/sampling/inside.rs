//! The inside test (to be written).
use glam::DVec3;

use crate::Mesh;

/// For every cell centre `origin + h * (i, j, k)` of a `dims` lattice, whether it lies inside
/// the solid bounded by `mesh`. Index `i + nx * (j + ny * k)`.
pub fn inside_cells(mesh: &Mesh, origin: DVec3, h: f64, dims: [usize; 3]) -> Vec<bool> {
    let _ = (mesh, origin, h);
    vec![false; dims[0] * dims[1] * dims[2]]
}
