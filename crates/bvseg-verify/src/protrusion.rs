//! The protrusion, measured apart from the core's own figure: the one-way Hausdorff distance
//! from the union's boundary to the mesh surface, as the largest distance to the nearest
//! triangle of pseudo-random points on the volumes' boundaries (each volume gets points in
//! proportion to its area; a point strictly inside another volume is not on the union's
//! boundary and is dropped). Distances come from a uniform grid of triangle buckets searched
//! ring by ring: no tree, no code shared with the core.
use glam::DVec3;

use crate::mesh::MeshRef;
use crate::parallel;
use crate::vol::Vol;

/// A triangle that would fall in more buckets than this is checked on every query instead.
const MAX_BUCKETS_PER_TRIANGLE: usize = 512;

/// The largest distance found, and the number of boundary points it was taken over.
pub(crate) fn protrusion(
    mesh: &MeshRef,
    vols: &[Vol],
    points: usize,
    seed: u64,
    threads: usize,
) -> (f64, usize) {
    let buckets = Buckets::new(mesh);
    let areas: Vec<f64> = vols.iter().map(Vol::area).collect();
    let total: f64 = areas.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let counts: Vec<usize> = areas
        .iter()
        .map(|a| ((points as f64 * a / total).round() as usize).max(16))
        .collect();
    let per = parallel::map_range(vols.len(), 1, threads, |i| {
        let mut best = 0.0f64;
        let mut kept = 0usize;
        for n in 0..counts[i] {
            let z = seed ^ ((i as u64) << 32) ^ n as u64;
            let r = [unit(mix(z)), unit(mix(z ^ 0x5555)), unit(mix(z ^ 0xaaaa))];
            let p = vols[i].boundary_point(r);
            if vols
                .iter()
                .enumerate()
                .any(|(j, v)| j != i && v.strictly_inside(p))
            {
                continue;
            }
            kept += 1;
            best = best.max(buckets.distance(mesh, p));
        }
        (best, kept)
    });
    per.iter()
        .fold((0.0, 0), |(b, k), &(bi, ki)| (f64::max(b, bi), k + ki))
}

fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

fn unit(z: u64) -> f64 {
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// Triangles bucketed by the grid cells their boxes overlap.
struct Buckets {
    lo: DVec3,
    cell: DVec3,
    dims: [usize; 3],
    start: Vec<usize>,
    items: Vec<u32>,
    /// Triangles too large for buckets: checked on every query.
    big: Vec<u32>,
}

impl Buckets {
    fn new(mesh: &MeshRef) -> Self {
        let (lo, hi) = mesh.bbox();
        let n = mesh.triangles().len().max(1);
        let ext = (hi - lo).max(DVec3::splat(1e-300));
        // About one triangle per cell.
        let side = (ext.x * ext.y * ext.z / n as f64)
            .cbrt()
            .max(ext.max_element() / 512.0);
        let dims = [0, 1, 2].map(|d| ((ext[d] / side).ceil() as usize).clamp(1, 512));
        let cell = DVec3::new(
            ext.x / dims[0] as f64,
            ext.y / dims[1] as f64,
            ext.z / dims[2] as f64,
        );
        let index = |p: DVec3, d: usize| -> usize {
            (((p[d] - lo[d]) / cell[d]).floor().max(0.0) as usize).min(dims[d] - 1)
        };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut big = Vec::new();
        for t in 0..mesh.triangles().len() {
            let c = mesh.corners(t);
            let (tlo, thi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
            let a = [0, 1, 2].map(|d| index(tlo, d));
            let b = [0, 1, 2].map(|d| index(thi, d));
            let span = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
            if span > MAX_BUCKETS_PER_TRIANGLE {
                big.push(t as u32);
                continue;
            }
            for k in a[2]..=b[2] {
                for j in a[1]..=b[1] {
                    for i in a[0]..=b[0] {
                        lists[i + dims[0] * (j + dims[1] * k)].push(t as u32);
                    }
                }
            }
        }
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        for l in &lists {
            start.push(items.len());
            items.extend_from_slice(l);
        }
        start.push(items.len());
        Self {
            lo,
            cell,
            dims,
            start,
            items,
            big,
        }
    }

    /// Distance from `p` to the nearest triangle.
    fn distance(&self, mesh: &MeshRef, p: DVec3) -> f64 {
        let tri = |t: u32| triangle_distance_squared(p, mesh.corners(t as usize));
        let mut best = self
            .big
            .iter()
            .map(|&t| tri(t))
            .fold(f64::INFINITY, f64::min);
        let hi = self.lo
            + self.cell
                * DVec3::new(
                    self.dims[0] as f64,
                    self.dims[1] as f64,
                    self.dims[2] as f64,
                );
        let outside = (self.lo - p).max(p - hi).max(DVec3::ZERO).length();
        let home = [0, 1, 2].map(|d| {
            (((p[d] - self.lo[d]) / self.cell[d]).floor().max(0.0) as usize).min(self.dims[d] - 1)
        });
        let cmin = self.cell.min_element();
        let rmax = self.dims.iter().copied().max().unwrap_or(1);
        for r in 0..=rmax {
            // Every cell of ring r is at least (r - 1) cells from p's cell.
            let bound = outside + (r as f64 - 1.0).max(0.0) * cmin;
            if bound * bound >= best {
                break;
            }
            let range = |d: usize| {
                let c = home[d] as i64;
                (c - r as i64).max(0) as usize..=((c + r as i64) as usize).min(self.dims[d] - 1)
            };
            for k in range(2) {
                for j in range(1) {
                    for i in range(0) {
                        let ring = [i, j, k]
                            .iter()
                            .zip(home)
                            .map(|(&a, b)| a.abs_diff(b))
                            .max()
                            .unwrap_or(0);
                        if ring != r {
                            continue;
                        }
                        let c = i + self.dims[0] * (j + self.dims[1] * k);
                        for &t in &self.items[self.start[c]..self.start[c + 1]] {
                            best = best.min(tri(t));
                        }
                    }
                }
            }
        }
        best.sqrt()
    }
}

/// Squared distance from `p` to triangle `[a, b, c]`: the nearest of the plane's foot (when
/// inside the triangle) and the three edges.
pub(crate) fn triangle_distance_squared(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let seg = |u: DVec3, v: DVec3| {
        let d = v - u;
        let l = d.length_squared();
        let t = if l > 0.0 {
            ((p - u).dot(d) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (u + d * t - p).length_squared()
    };
    let edges = seg(a, b).min(seg(b, c)).min(seg(c, a));
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    if nn <= 0.0 || !nn.is_finite() {
        return edges;
    }
    let foot = p - n * ((p - a).dot(n) / nn);
    // Inside if the foot is on the inner side of every edge.
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(foot - u).dot(n) >= 0.0);
    if inside {
        edges.min((p - foot).length_squared())
    } else {
        edges
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{cuboid, obb};
    use glam::DMat3;

    #[test]
    fn a_box_around_a_cube_protrudes_by_its_corner_gap() {
        // A unit cube in a box 1.2 times its size: the corners are 0.2 sqrt 3 out; random
        // points get close to that near the corners.
        let (v, t) = cuboid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY);
        let mesh = MeshRef::new(&v, &t).unwrap();
        let b = |h: f64| Vol::new(&obb(DVec3::ZERO, DVec3::splat(h), DMat3::IDENTITY)).unwrap();
        let vols = [b(1.2)];
        let (p, n) = protrusion(&mesh, &vols, 20_000, 1, 2);
        let want = 0.2 * 3f64.sqrt();
        assert!(p <= want + 1e-12 && p > 0.95 * want, "{p} vs {want}");
        assert!(n >= 19_000);
        // Inside a larger box, the first adds nothing to the union's boundary.
        let both = [b(1.2), b(2.0)];
        let (p2, _) = protrusion(&mesh, &both, 20_000, 1, 2);
        assert!((p2 - 3f64.sqrt()).abs() < 0.05 * 3f64.sqrt(), "{p2}");
    }

    #[test]
    fn triangle_distance_by_region() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let d = |p: DVec3| triangle_distance_squared(p, t).sqrt();
        assert!((d(DVec3::new(0.2, 0.2, 3.0)) - 3.0).abs() < 1e-12);
        assert!((d(DVec3::new(-1.0, -1.0, 0.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert!((d(DVec3::new(1.0, 1.0, 0.0)) - 0.5f64.sqrt()).abs() < 1e-12);
    }
}
