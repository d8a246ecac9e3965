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

use crate::bounding::hull::hull_points;
use crate::partition::Solid;
use crate::sampling::{Grid, NONE};
use crate::Mesh;

/// Above this many distinct corners, a sample keeps only those on their convex hull.
const MANY_CORNERS: usize = 64;

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
    /// CSR lists of the distinct corners of the triangles whose nearest sample is each
    /// sample, sorted. Distinct, so that a file that repeats faces costs the fits nothing.
    offsets: Vec<u32>,
    corners: Vec<u32>,
}

impl Enclosure {
    /// Find each triangle's nearest sample.
    pub fn new(mesh: &Mesh, solid: &Solid) -> Self {
        let triangle_sample = nearest_samples(mesh, solid);
        let n = solid.len();
        let mut start = vec![0usize; n + 1];
        for &s in &triangle_sample {
            start[s as usize + 1] += 3;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut all = vec![0u32; start[n]];
        for (t, &s) in triangle_sample.iter().enumerate() {
            let at = fill[s as usize];
            all[at..at + 3].copy_from_slice(&mesh.triangles()[t]);
            fill[s as usize] += 3;
        }
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut corners = Vec::with_capacity(all.len());
        for s in 0..n {
            let list = &mut all[start[s]..start[s + 1]];
            list.sort_unstable();
            let from = corners.len();
            corners.extend(
                list.iter()
                    .enumerate()
                    .filter(|&(i, &v)| i == 0 || list[i - 1] != v)
                    .map(|(_, &v)| v),
            );
            if corners.len() - from > MANY_CORNERS {
                // Only the corners on their own hull can be on the part's: the hull of a
                // union is the hull of the members' hulls. Most samples have a handful of
                // corners; a mesh far finer than the lattice, or one of stacked layers,
                // has hundreds, which every fit of the part would otherwise take in.
                let own = &corners[from..];
                let pts: Vec<DVec3> = own.iter().map(|&v| mesh.vertices()[v as usize]).collect();
                let hull = hull_points(&pts);
                // The hull's vertices come in input order: a subsequence of `own`.
                let mut next = hull.iter().peekable();
                let kept: Vec<u32> = own
                    .iter()
                    .zip(&pts)
                    .filter(|&(_, p)| next.next_if(|h| *h == p).is_some())
                    .map(|(&v, _)| v)
                    .collect();
                corners.truncate(from);
                corners.extend_from_slice(&kept);
            }
            // At most 3 x the triangles, which are u32-indexed.
            offsets.push(corners.len() as u32);
        }
        Self {
            triangle_sample,
            offsets,
            corners,
        }
    }

    /// The part of each triangle under `labels`.
    pub fn triangle_parts(&self, labels: &[u32]) -> Vec<u32> {
        self.triangle_sample
            .iter()
            .map(|&s| labels[s as usize])
            .collect()
    }

    /// The distinct corners, sorted, of the triangles whose nearest sample is `s`.
    pub fn corners_of(&self, s: usize) -> &[u32] {
        &self.corners[self.offsets[s] as usize..self.offsets[s + 1] as usize]
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

    /// Like [`Enclosure::points`], with the labelling given as a function. `members` are
    /// samples that `label_of` maps to `label`, usually all of them. A neighbour outside
    /// `members` counts as another part's: for a subset of the part, the result then also
    /// has the centres of the faces between the subset and the rest of the part, which lie
    /// inside the part's hull (the tightening relies on this to add a layer to a part).
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
        // Membership as a bitmap over the members' index range: `label_of` may be costly
        // (a search in a move's layer), and each member asks about six neighbours.
        let first = members.iter().copied().min().unwrap_or(0) as usize;
        let last = members.iter().copied().max().unwrap_or(0) as usize;
        debug_assert!(members.iter().all(|&s| label_of(s as usize) == label));
        let mut bits = vec![0u64; (last - first) / 64 + 1];
        for &s in members {
            let i = s as usize - first;
            bits[i / 64] |= 1 << (i % 64);
        }
        let member = |t: usize| {
            let i = t.wrapping_sub(first);
            i <= last - first && bits[i / 64] & (1 << (i % 64)) != 0
        };
        let blocks = g.has_blocks();
        for &s in members {
            let s = s as usize;
            if blocks {
                cell_points(g, s, &member, &mut lat);
                verts.extend_from_slice(self.corners_of(s));
                continue;
            }
            let c = g.coords[s].map(|x| 2 * x as i64);
            let mut interior = true;
            for &t in g.neighbors(s) {
                if t == NONE {
                    interior = false;
                } else if !member(t as usize) {
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
            verts.extend_from_slice(self.corners_of(s));
        }
        crate::work::add(members.len() + verts.len());
        sort_dedup(&mut verts, mesh.vertices().len());
        let lat = extreme_on_lines(&lat);
        let mut pts = Vec::with_capacity(lat.len() + verts.len());
        pts.extend(
            lat.iter()
                .map(|c| g.origin + 0.5 * g.h * DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
        );
        pts.extend(verts.iter().map(|&v| mesh.vertices()[v as usize]));
        pts
    }
}

/// The lattice points sample `s` of an adaptive grid adds to its part's (see
/// [`Enclosure::points_with`]), cell by cell, in doubled lattice coordinates: each of its
/// cells that touches a cell of another sample not in the part (`member`), or outside the
/// solid, and the centres of the faces it shares with other parts' cells. Blocks lie deep
/// inside, so only their faces on other parts add points.
fn cell_points(g: &Grid, s: usize, member: &impl Fn(usize) -> bool, lat: &mut Vec<[i64; 3]>) {
    const STEPS: [[i64; 3]; 6] = [
        [-1, 0, 0],
        [1, 0, 0],
        [0, -1, 0],
        [0, 1, 0],
        [0, 0, -1],
        [0, 0, 1],
    ];
    for cell in g.cells_of(s) {
        let c = cell.map(i64::from);
        let mut interior = true;
        for d in STEPS {
            let t = g.sample_at(c[0] + d[0], c[1] + d[1], c[2] + d[2]);
            if t == NONE {
                interior = false;
            } else if t as usize != s && !member(t as usize) {
                interior = false;
                lat.push([0, 1, 2].map(|a| 2 * c[a] + d[a]));
            }
        }
        if !interior {
            lat.push(c.map(|x| 2 * x));
        }
    }
}

/// Sorts `v` and removes duplicates, for values below `n`: by a bitmap of `0..n` when that is
/// small against `v` (the usual case: a part's triangle corners among the mesh's vertices),
/// by sorting otherwise.
fn sort_dedup(v: &mut Vec<u32>, n: usize) {
    let words = n.div_ceil(64);
    if words > 2 * v.len() + 64 {
        v.sort_unstable();
        v.dedup();
        return;
    }
    let mut bits = vec![0u64; words];
    for &x in v.iter() {
        bits[x as usize / 64] |= 1 << (x % 64);
    }
    v.clear();
    for (w, &b) in bits.iter().enumerate() {
        let mut b = b;
        while b != 0 {
            v.push((w * 64) as u32 + b.trailing_zeros());
            b &= b - 1;
        }
    }
}

/// The distinct lattice points of `lat` that are the first or last of the set on each of
/// their three lattice lines (along x, y and z), in increasing `(x, y, z)` order. Any other
/// point lies strictly between two points of the set, so it cannot be a vertex of their
/// convex hull: a cheap, exact prefilter for the hull.
///
/// The first and last point of every line are found in dense tables over the points'
/// bounding box; a set too sparse in its box for those tables falls back to sorting, and
/// filters along z only.
fn extreme_on_lines(lat: &[[i64; 3]]) -> Vec<[i64; 3]> {
    let Some(&first) = lat.first() else {
        return Vec::new();
    };
    let (mut lo, mut hi) = (first, first);
    for p in lat {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let w = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
    let cells = w[0] * w[1] + w[1] * w[2] + w[0] * w[2];
    if cells > 16 * lat.len() + 4096 {
        return extreme_on_z_lines(lat);
    }
    // Per line, the least and greatest coordinate along it, relative to `lo`.
    const EMPTY: [u32; 2] = [u32::MAX, 0];
    let mut zl = vec![EMPTY; w[0] * w[1]];
    let mut xl = vec![EMPTY; w[1] * w[2]];
    let mut yl = vec![EMPTY; w[0] * w[2]];
    let rel = |p: &[i64; 3]| [0, 1, 2].map(|a| (p[a] - lo[a]) as u32);
    let widen = |e: &mut [u32; 2], v: u32| {
        e[0] = e[0].min(v);
        e[1] = e[1].max(v);
    };
    for p in lat {
        let [x, y, z] = rel(p);
        let (x, y, z) = (x as usize, y as usize, z as usize);
        widen(&mut zl[x * w[1] + y], z as u32);
        widen(&mut xl[y * w[2] + z], x as u32);
        widen(&mut yl[x * w[2] + z], y as u32);
    }
    // Every kept point is the first or last on its z line: walking the z lines in (x, y)
    // order yields them sorted and once each.
    let mut out = Vec::new();
    for x in 0..w[0] {
        for y in 0..w[1] {
            let [z0, z1] = zl[x * w[1] + y];
            if z0 > z1 {
                continue;
            }
            let ends = [z0, z1];
            for &z in &ends[..if z0 == z1 { 1 } else { 2 }] {
                let ex = xl[y * w[2] + z as usize];
                let ey = yl[x * w[2] + z as usize];
                if (ex[0] == x as u32 || ex[1] == x as u32)
                    && (ey[0] == y as u32 || ey[1] == y as u32)
                {
                    out.push([x as i64 + lo[0], y as i64 + lo[1], z as i64 + lo[2]]);
                }
            }
        }
    }
    out
}

/// The lattice points that are the first or last of the set on their lattice line along z,
/// sorted and deduplicated (the sparse case of [`extreme_on_lines`]).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounding::hull::convex_hull;
    use crate::rng::Rng;

    /// Random lattice sets: a blob in a box (dense, the table path) or scattered points in a
    /// wide box (sparse, the sorting path).
    fn random_set(rng: &mut Rng, n: usize, side: i64) -> Vec<[i64; 3]> {
        let mut v: Vec<[i64; 3]> = (0..n)
            .map(|_| [0; 3].map(|_| (rng.next_f64() * side as f64) as i64 - side / 3))
            .collect();
        // Duplicates, as the enclosure may produce.
        let dup: Vec<[i64; 3]> = v.iter().step_by(7).copied().collect();
        v.extend(dup);
        v
    }

    fn is_between(p: &[i64; 3], set: &[[i64; 3]], axes: &[usize]) -> bool {
        axes.iter().any(|&a| {
            let on_line = |q: &&[i64; 3]| (0..3).all(|b| b == a || q[b] == p[b]);
            let below = set.iter().filter(on_line).any(|q| q[a] < p[a]);
            let above = set.iter().filter(on_line).any(|q| q[a] > p[a]);
            below && above
        })
    }

    #[test]
    fn extreme_on_lines_keeps_exactly_the_line_extremes() {
        let mut rng = Rng::new(23);
        for (n, side) in [(1, 3), (40, 4), (400, 8), (2000, 12), (300, 400)] {
            let set = random_set(&mut rng, n, side);
            let out = extreme_on_lines(&set);
            assert!(out.windows(2).all(|w| w[0] < w[1]), "sorted, no duplicates");
            assert!(out.iter().all(|p| set.contains(p)));
            let dense = side < 100;
            let axes: &[usize] = if dense { &[0, 1, 2] } else { &[2] };
            for p in &set {
                assert_eq!(out.contains(p), !is_between(p, &set, axes), "{p:?}");
            }
        }
        assert!(extreme_on_lines(&[]).is_empty());
    }

    /// The hull of the filtered points is the hull of all of them: every point is inside it
    /// (up to round-off), and its vertices are input points.
    #[test]
    fn filtered_hull_is_the_full_hull() {
        let mut rng = Rng::new(5);
        for (n, side) in [(50, 5), (600, 10), (3000, 16), (200, 300)] {
            let mut set = random_set(&mut rng, n, side);
            // A lattice ball too: many coplanar and collinear ties.
            let r = (side / 2).min(6);
            for x in -r..=r {
                for y in -r..=r {
                    for z in -r..=r {
                        if x * x + y * y + z * z <= r * r {
                            set.push([x + 2 * side, y, z]);
                        }
                    }
                }
            }
            let to_world = |c: &[i64; 3]| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * 0.3;
            let all: Vec<DVec3> = set.iter().map(to_world).collect();
            let kept: Vec<DVec3> = extreme_on_lines(&set).iter().map(to_world).collect();
            assert!(kept.len() < all.len());
            let h = convex_hull(&kept);
            let full = convex_hull(&all);
            for (a, b) in [(&h, &all), (&full, &kept)] {
                for f in 0..a.faces.len() {
                    let (nrm, _) = a.face_normal_area(f);
                    let v0 = a.vertices[a.faces[f][0] as usize];
                    for p in b.iter() {
                        assert!(nrm.dot(*p - v0) <= 1e-9, "outside by {}", nrm.dot(*p - v0));
                    }
                }
            }
        }
    }

    #[test]
    fn sort_dedup_both_ways() {
        let mut rng = Rng::new(9);
        for (len, n) in [(0, 10), (50, 100), (50, 1_000_000), (3000, 5000)] {
            let v: Vec<u32> = (0..len)
                .map(|_| (rng.next_f64() * n as f64) as u32)
                .collect();
            let mut want = v.clone();
            want.sort_unstable();
            want.dedup();
            let mut got = v;
            sort_dedup(&mut got, n);
            assert_eq!(got, want);
        }
    }
}
