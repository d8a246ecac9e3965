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
    // Inside cells in each box of the lattice in O(1), so that many large shells cost no
    // more than a few small ones. Built lazily: most meshes have no closed small shell.
    let mut counts: Option<BoxCounts> = None;
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
        // The lattice range of the centres inside the shell's box, per axis: a centre's
        // coordinate `origin + h i` is monotone in `i`, so the box test is separable.
        let range = |a: usize, n: usize| -> Option<(usize, usize)> {
            let at = |i: usize| origin[a] + h * i as f64;
            let t = ((lo[a] - origin[a]) / h).ceil().clamp(0.0, n as f64) as usize;
            let mut first = t;
            while first > 0 && at(first - 1) >= lo[a] {
                first -= 1;
            }
            while first < n && at(first) < lo[a] {
                first += 1;
            }
            let mut end = ((hi[a] - origin[a]) / h)
                .floor()
                .clamp(-1.0, n as f64 - 1.0) as i64
                + 1;
            while end > 0 && at(end as usize - 1) > hi[a] {
                end -= 1;
            }
            while (end as usize) < n && at(end as usize) <= hi[a] {
                end += 1;
            }
            (first < end as usize).then_some((first, end as usize))
        };
        let has_sample = match (range(0, nx), range(1, ny), range(2, nz)) {
            (Some(x), Some(y), Some(z)) => counts
                .get_or_insert_with(|| BoxCounts::new(mask, dims))
                .any(x, y, z),
            _ => false,
        };
        if !has_sample {
            let t = ((c - origin) / h).round();
            let cell = |x: f64, n: usize| x.clamp(0.0, (n - 1) as f64) as usize;
            let (i, j, k) = (cell(t.x, nx), cell(t.y, ny), cell(t.z, nz));
            mask[i + nx * (j + ny * k)] = true;
        }
    }
}

/// A summed-volume table of an inside mask: `s[(i, j, k)]` is the number of inside cells
/// with all coordinates below `(i, j, k)`.
struct BoxCounts {
    s: Vec<u32>,
    dims: [usize; 3],
}

impl BoxCounts {
    fn new(mask: &[bool], dims: [usize; 3]) -> Self {
        let [nx, ny, nz] = dims.map(|n| n + 1);
        let mut s = vec![0u32; nx * ny * nz];
        let at = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        for k in 1..nz {
            for j in 1..ny {
                for i in 1..nx {
                    let m = u32::from(mask[(i - 1) + dims[0] * ((j - 1) + dims[1] * (k - 1))]);
                    // Inclusion-exclusion; the intermediate may wrap, the result cannot.
                    s[at(i, j, k)] = m
                        .wrapping_add(s[at(i - 1, j, k)])
                        .wrapping_add(s[at(i, j - 1, k)])
                        .wrapping_add(s[at(i, j, k - 1)])
                        .wrapping_sub(s[at(i - 1, j - 1, k)])
                        .wrapping_sub(s[at(i - 1, j, k - 1)])
                        .wrapping_sub(s[at(i, j - 1, k - 1)])
                        .wrapping_add(s[at(i - 1, j - 1, k - 1)]);
                }
            }
        }
        Self { s, dims }
    }

    /// Whether a cell of the box `[x0, x1) x [y0, y1) x [z0, z1)` is inside.
    fn any(
        &self,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
        (z0, z1): (usize, usize),
    ) -> bool {
        let (nx, ny) = (self.dims[0] + 1, self.dims[1] + 1);
        let s = |i: usize, j: usize, k: usize| self.s[i + nx * (j + ny * k)];
        let n = s(x1, y1, z1)
            .wrapping_sub(s(x0, y1, z1))
            .wrapping_sub(s(x1, y0, z1))
            .wrapping_sub(s(x1, y1, z0))
            .wrapping_add(s(x0, y0, z1))
            .wrapping_add(s(x0, y1, z0))
            .wrapping_add(s(x1, y0, z0))
            .wrapping_sub(s(x0, y0, z0));
        n > 0
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
