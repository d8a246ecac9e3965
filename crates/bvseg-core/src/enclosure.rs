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

/// Which triangles and points each part must enclose.
///
/// A triangle belongs to the part of the sample nearest its centroid (among the grid-nearest
/// samples of the 27 cells around it). That sample does not depend on the partition, so it
/// is found once; a part's triangles are then those of its samples.
#[derive(Debug, Clone)]
pub struct Enclosure {
    /// For each triangle, its nearest sample.
    pub triangle_sample: Vec<u32>,
    /// CSR lists of the triangles whose nearest sample is each sample.
    offsets: Vec<u32>,
    triangles: Vec<u32>,
}

impl Enclosure {
    /// Find each triangle's nearest sample.
    pub fn new(mesh: &Mesh, solid: &Solid) -> Self {
        let triangle_sample = nearest_samples(mesh, solid);
        let n = solid.len();
        let mut offsets = vec![0u32; n + 1];
        for &s in &triangle_sample {
            offsets[s as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut triangles = vec![0u32; triangle_sample.len()];
        for (t, &s) in triangle_sample.iter().enumerate() {
            triangles[fill[s as usize] as usize] = t as u32;
            fill[s as usize] += 1;
        }
        Self {
            triangle_sample,
            offsets,
            triangles,
        }
    }

    /// The part of each triangle under `labels`.
    pub fn triangle_parts(&self, labels: &[u32]) -> Vec<u32> {
        self.triangle_sample
            .iter()
            .map(|&s| labels[s as usize])
            .collect()
    }

    /// The triangles whose nearest sample is `s`.
    pub fn triangles_of(&self, s: usize) -> &[u32] {
        &self.triangles[self.offsets[s] as usize..self.offsets[s + 1] as usize]
    }

    /// The world-space points that part `label` (with samples `members`) must enclose, less
    /// those that cannot be on their convex hull: its samples on the part's boundary (a
    /// sample whose six neighbours are all in the part lies inside their hull), the centres
    /// of the cell faces it shares with other parts, and the corners of its triangles.
    pub fn points(
        &self,
        mesh: &Mesh,
        solid: &Solid,
        labels: &[u32],
        members: &[u32],
        label: u32,
    ) -> Vec<DVec3> {
        self.points_with(mesh, solid, |s| labels[s], members, label)
    }

    /// Like [`Enclosure::points`], with the labelling given as a function.
    pub fn points_with(
        &self,
        mesh: &Mesh,
        solid: &Solid,
        label_of: impl Fn(usize) -> u32,
        members: &[u32],
        label: u32,
    ) -> Vec<DVec3> {
        let g = &solid.grid;
        // Lattice points (samples and shared-face centres) in doubled lattice coordinates, so
        // that face centres are integers too.
        let mut lat: Vec<[i64; 3]> = Vec::new();
        // Triangles share corners: bound each distinct vertex once (the hull is the cost).
        let mut verts: Vec<u32> = Vec::new();
        for &s in members {
            let s = s as usize;
            let c = g.coords[s].map(|x| 2 * x as i64);
            let mut interior = true;
            for &t in &g.neighbors[s] {
                if t == NONE {
                    interior = false;
                } else if label_of(t as usize) != label {
                    interior = false;
                    let d = g.coords[t as usize];
                    lat.push([
                        (c[0] + 2 * d[0] as i64) / 2,
                        (c[1] + 2 * d[1] as i64) / 2,
                        (c[2] + 2 * d[2] as i64) / 2,
                    ]);
                }
            }
            if !interior {
                lat.push(c);
            }
            for &t in self.triangles_of(s) {
                verts.extend_from_slice(&mesh.triangles()[t as usize]);
            }
        }
        verts.sort_unstable();
        verts.dedup();
        let mut pts: Vec<DVec3> = extreme_on_z_lines(&lat)
            .into_iter()
            .map(|c| g.origin + 0.5 * g.h * DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect();
        pts.extend(verts.iter().map(|&v| mesh.vertices()[v as usize]));
        pts
    }
}

/// The lattice points that are the first or last of the set on their lattice line along z.
/// Any other point lies strictly between two points of the set, so it cannot be a vertex of
/// their convex hull: a cheap, exact prefilter for the hull. (Filtering along x and y too
/// removes a few more points but costs more than the hull saves.)
fn extreme_on_z_lines(lat: &[[i64; 3]]) -> Vec<[i64; 3]> {
    let mut pts = lat.to_vec();
    // Sorted by (x, y, z): each z line is a run of equal (x, y).
    pts.sort_unstable();
    pts.dedup();
    let mut out = Vec::with_capacity(pts.len());
    let mut start = 0;
    while start < pts.len() {
        let mut end = start + 1;
        while end < pts.len() && pts[end][0] == pts[start][0] && pts[end][1] == pts[start][1] {
            end += 1;
        }
        out.push(pts[start]);
        if end - start > 1 {
            out.push(pts[end - 1]);
        }
        start = end;
    }
    out
}

/// For each triangle, the sample nearest its centroid (among the grid-nearest samples of the
/// 27 cells around the centroid's cell).
fn nearest_samples(mesh: &Mesh, solid: &Solid) -> Vec<u32> {
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
            best.1
        })
        .collect()
}
