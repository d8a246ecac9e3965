//! Stage 7: making the union of volumes truly enclose the object.
//!
//! Samples are cell centres, so bounding each part's samples alone would miss two things:
//!
//! 1. **The surface.** Each triangle is given to a part (the part of the interior sample
//!    nearest its centroid) and its three corners join that part's points. A convex volume
//!    holding the three corners holds the whole triangle, so every triangle is enclosed.
//! 2. **The gaps between parts.** Between two neighbouring cell centres owned by different
//!    parts lies a slab that neither part's samples span. Each part also takes the centre of
//!    every cell face it shares with another part (the midpoint of the two samples), so the
//!    two parts' hulls meet on the shared faces instead of leaving the slab open.
use glam::DVec3;

use crate::partition::Solid;
use crate::sampling::NONE;
use crate::Mesh;

/// For every lattice cell, the sample nearest to it along grid paths (a multi-source BFS
/// from all samples), or [`NONE`] if the grid has no sample.
fn nearest_sample_field(solid: &Solid) -> Vec<u32> {
    let g = &solid.grid;
    let [nx, ny, nz] = g.dims;
    let mut near = g.sample_of_cell.clone();
    let mut frontier: Vec<usize> = (0..near.len()).filter(|&c| near[c] != NONE).collect();
    while !frontier.is_empty() {
        let mut next = Vec::new();
        for &c in &frontier {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            let mut visit = |cc: usize| {
                if near[cc] == NONE {
                    near[cc] = near[c];
                    next.push(cc);
                }
            };
            if i > 0 {
                visit(c - 1);
            }
            if i + 1 < nx {
                visit(c + 1);
            }
            if j > 0 {
                visit(c - nx);
            }
            if j + 1 < ny {
                visit(c + nx);
            }
            if k > 0 {
                visit(c - nx * ny);
            }
            if k + 1 < nz {
                visit(c + nx * ny);
            }
        }
        frontier = next;
    }
    near
}

/// The part of each triangle: the part of the sample nearest the triangle's centroid (among
/// the grid-nearest samples of the 27 cells around it).
pub fn assign_triangles(mesh: &Mesh, solid: &Solid, labels: &[u32]) -> Vec<u32> {
    let g = &solid.grid;
    let near = nearest_sample_field(solid);
    let [nx, ny, nz] = g.dims;
    (0..mesh.triangles().len())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let centroid = (a + b + c) / 3.0;
            let [ci, cj, ck] = g.cell_of(centroid);
            let mut best = (f64::INFINITY, u32::MAX);
            for dk in -1..=1 {
                for dj in -1..=1 {
                    for di in -1..=1 {
                        let (i, j, k) = (ci + di, cj + dj, ck + dk);
                        if i < 0
                            || j < 0
                            || k < 0
                            || i >= nx as i64
                            || j >= ny as i64
                            || k >= nz as i64
                        {
                            continue;
                        }
                        let s = near[i as usize + nx * (j as usize + ny * k as usize)];
                        if s == NONE {
                            continue;
                        }
                        let d = (g.points[s as usize] - centroid).length_squared();
                        if d < best.0 || (d == best.0 && s < best.1) {
                            best = (d, s);
                        }
                    }
                }
            }
            if best.1 == u32::MAX {
                // Only possible when the centroid lies outside the lattice; fall back to a scan.
                best.1 = (0..g.len() as u32)
                    .min_by(|&x, &y| {
                        (g.points[x as usize] - centroid)
                            .length_squared()
                            .total_cmp(&(g.points[y as usize] - centroid).length_squared())
                    })
                    .unwrap_or(0);
            }
            labels[best.1 as usize]
        })
        .collect()
}

/// The world-space points each of the `k` parts must enclose: its samples, the centres of
/// the cell faces it shares with other parts, and the corners of its triangles.
pub fn part_points(
    mesh: &Mesh,
    solid: &Solid,
    labels: &[u32],
    k: usize,
    triangle_parts: &[u32],
) -> Vec<Vec<DVec3>> {
    let g = &solid.grid;
    let mut pts = vec![Vec::new(); k];
    for (s, &l) in labels.iter().enumerate() {
        let p = g.points[s];
        pts[l as usize].push(p);
        for &t in &g.neighbors[s] {
            if t != NONE && labels[t as usize] != l {
                pts[l as usize].push(0.5 * (p + g.points[t as usize]));
            }
        }
    }
    for (t, &l) in triangle_parts.iter().enumerate() {
        pts[l as usize].extend(mesh.corners(t));
    }
    pts
}
