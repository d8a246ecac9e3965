//! Closed shells too small to hold a cell centre still get a sample.
//!
//! Without one, a piece of the object smaller than a grid cell (a rivet, an eye) has no
//! part of its own: its triangles go to the part of the nearest sample, however far, and
//! that part's volume stretches across the gap to swallow it. With one sample, the piece
//! is its own connected component of the solid, and so its own part in tolerance mode.
use glam::DVec3;

use crate::Mesh;

/// For every closed shell of `mesh` (triangles connected through shared vertices, every
/// directed edge matched by its reverse, non-zero volume) whose bounding box holds no
/// inside cell centre, marks the cell nearest its centre as inside in `mask` (cells of the
/// lattice `origin`, `h`, `dims`, indexed `i + nx * (j + ny * k)` as in [`super::Grid`]).
pub(crate) fn mark_sub_cell_shells(
    mesh: &Mesh,
    origin: DVec3,
    h: f64,
    dims: [usize; 3],
    mask: &mut [bool],
) {
    let tris = mesh.triangles();
    let verts = mesh.vertices();
    // Union-find over vertices: shells are the triangle sets sharing vertices.
    let mut parent: Vec<u32> = (0..verts.len() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for t in tris {
        let a = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = find(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut shell_of: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    let mut shells: Vec<Vec<usize>> = Vec::new();
    for (i, t) in tris.iter().enumerate() {
        let root = find(&mut parent, t[0]);
        let s = *shell_of.entry(root).or_insert_with(|| {
            shells.push(Vec::new());
            shells.len() - 1
        });
        shells[s].push(i);
    }
    if shells.len() < 2 {
        // One shell: the sampling's own retries make sure it holds samples.
        return;
    }
    let [nx, ny, nz] = dims;
    for shell in &shells {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut edges = Vec::with_capacity(3 * shell.len());
        let mut rev = Vec::with_capacity(3 * shell.len());
        for &t in shell {
            for e in 0..3 {
                let (a, b) = (tris[t][e], tris[t][(e + 1) % 3]);
                edges.push((a, b));
                rev.push((b, a));
                lo = lo.min(verts[a as usize]);
                hi = hi.max(verts[a as usize]);
            }
        }
        edges.sort_unstable();
        rev.sort_unstable();
        let c = 0.5 * (lo + hi);
        let vol: f64 = shell
            .iter()
            .map(|&t| {
                let [a, b, d] = mesh.corners(t);
                (a - c).dot((b - c).cross(d - c))
            })
            .sum();
        if edges != rev || vol == 0.0 {
            continue;
        }
        // Lattice range of the centres inside the shell's box.
        let to_cell = |x: f64, o: f64, n: usize, up: bool| -> usize {
            let t = (x - o) / h;
            let t = if up { t.floor() } else { t.ceil() };
            t.clamp(0.0, (n - 1) as f64) as usize
        };
        let (i0, i1) = (
            to_cell(lo.x, origin.x, nx, false),
            to_cell(hi.x, origin.x, nx, true),
        );
        let (j0, j1) = (
            to_cell(lo.y, origin.y, ny, false),
            to_cell(hi.y, origin.y, ny, true),
        );
        let (k0, k1) = (
            to_cell(lo.z, origin.z, nz, false),
            to_cell(hi.z, origin.z, nz, true),
        );
        let inside_box = |i: usize, j: usize, k: usize| {
            let p = origin + h * DVec3::new(i as f64, j as f64, k as f64);
            p.cmpge(lo).all() && p.cmple(hi).all()
        };
        let has_sample = (k0..=k1).any(|k| {
            (j0..=j1).any(|j| (i0..=i1).any(|i| mask[i + nx * (j + ny * k)] && inside_box(i, j, k)))
        });
        if !has_sample {
            let t = ((c - origin) / h).round();
            let cell = |x: f64, n: usize| x.clamp(0.0, (n - 1) as f64) as usize;
            let (i, j, k) = (cell(t.x, nx), cell(t.y, ny), cell(t.z, nz));
            mask[i + nx * (j + ny * k)] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::sampling::Grid;
    use crate::shapes;
    use glam::{DMat3, DVec3};

    #[test]
    fn a_shell_smaller_than_a_cell_gets_one_sample() {
        let big = shapes::ellipsoid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY, 16);
        let tiny = shapes::cuboid(
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::splat(0.001),
            DMat3::IDENTITY,
        );
        let g = Grid::from_mesh(&shapes::union(&[big.clone(), tiny]), 1000).unwrap();
        let near = g
            .points
            .iter()
            .filter(|p| (**p - DVec3::new(3.0, 0.0, 0.0)).length() < g.h);
        assert_eq!(near.count(), 1);
        // A lone mesh is left to the sampling's own retries.
        let alone = Grid::from_mesh(&big, 1000).unwrap();
        assert!(alone.points.iter().all(|p| p.length() < 1.0));
    }
}
