//! The inside test of the solid S and its closedness and exact volume.
//!
//! These are the verifier's own, deliberately not shared with the segmentation's (its
//! lattice sweep, `Mesh::signed_volume`, its loaders' checks): an independent checker must
//! not inherit the bugs of what it checks, so the crate graph keeps bvseg-core out and the
//! definitions here follow the external judge (`shared/tools/bveval.py`) instead.
use glam::{DVec2, DVec3};

use crate::mesh::MeshRef;

/// A triangle projected along a ray axis.
struct Projected {
    /// Corners in the plane across the axis.
    a: [DVec2; 3],
    /// Corners' coordinates along the axis.
    h: [f64; 3],
    /// Twice the projected signed area.
    area2: f64,
}

/// Triangles projected along one axis and bucketed on a 2D grid, for signed ray counts.
struct RayIndex {
    axis: usize,
    tris: Vec<Projected>,
    lo: DVec2,
    hi: DVec2,
    cell: DVec2,
    g: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Sign of the edge function of `p` against the edge `p0 -> p1`, with ties broken by the
/// perturbation `p + (ε, ε²)`: consistent for all triangles at once, so a ray through an
/// edge or a vertex is counted exactly once by the triangles around it.
#[inline]
fn edge_sign(p0: DVec2, p1: DVec2, p: DVec2) -> f64 {
    let d = p1 - p0;
    let e = d.x * (p.y - p0.y) - d.y * (p.x - p0.x);
    if e != 0.0 {
        e.signum()
    } else if d.y != 0.0 {
        -d.y.signum()
    } else {
        d.x.signum()
    }
}

impl RayIndex {
    fn new(mesh: &MeshRef<'_>, axis: usize) -> Self {
        let (u, v) = [(1, 2), (2, 0), (0, 1)][axis];
        let mut tris = Vec::new();
        for t in 0..mesh.triangles().len() {
            let c = mesh.corners(t);
            let a = c.map(|p| DVec2::new(p[u], p[v]));
            let area2 = (a[1] - a[0]).perp_dot(a[2] - a[0]);
            // Triangles seen edge-on cover no area: no ray crosses them (up to measure zero).
            if area2 != 0.0 && area2.is_finite() {
                tris.push(Projected {
                    a,
                    h: c.map(|p| p[axis]),
                    area2,
                });
            }
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for t in &tris {
            for p in t.a {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let n = tris.len();
        let mut g = ((1.5 * (n as f64).sqrt()) as usize).clamp(8, 2048);
        // Long thin triangles could span many cells each: coarsen until the index is small.
        loop {
            let cell = ((hi - lo) / g as f64).max(DVec2::splat(f64::MIN_POSITIVE));
            let entries: usize = tris
                .iter()
                .map(|t| {
                    let (c0, c1) = Self::span(t, lo, cell, g);
                    (c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1)
                })
                .sum();
            if entries <= 8 * n + 4_000_000 || g <= 1 {
                break;
            }
            g /= 2;
        }
        let cell = ((hi - lo) / g as f64).max(DVec2::splat(f64::MIN_POSITIVE));
        let mut count = vec![0u32; g * g + 1];
        for t in &tris {
            let (c0, c1) = Self::span(t, lo, cell, g);
            for x in c0[0]..=c1[0] {
                for y in c0[1]..=c1[1] {
                    count[x * g + y + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let start = count.clone();
        let mut fill = count;
        let mut items = vec![0u32; start[g * g] as usize];
        for (ti, t) in tris.iter().enumerate() {
            let (c0, c1) = Self::span(t, lo, cell, g);
            for x in c0[0]..=c1[0] {
                for y in c0[1]..=c1[1] {
                    let b = x * g + y;
                    items[fill[b] as usize] = ti as u32;
                    fill[b] += 1;
                }
            }
        }
        Self {
            axis,
            tris,
            lo,
            hi,
            cell,
            g,
            start,
            items,
        }
    }

    fn bucket(p: DVec2, lo: DVec2, cell: DVec2, g: usize) -> [usize; 2] {
        let q = (p - lo) / cell;
        let clamp = |x: f64| (x.max(0.0) as usize).min(g - 1);
        [clamp(q.x), clamp(q.y)]
    }

    fn span(t: &Projected, lo: DVec2, cell: DVec2, g: usize) -> ([usize; 2], [usize; 2]) {
        let tlo = t.a[0].min(t.a[1]).min(t.a[2]);
        let thi = t.a[0].max(t.a[1]).max(t.a[2]);
        (
            Self::bucket(tlo, lo, cell, g),
            Self::bucket(thi, lo, cell, g),
        )
    }

    /// Half the signed crossings above `p` minus half those below: the winding number of a
    /// closed mesh, the two-ray average of an open one.
    fn crossings(&self, p: DVec3) -> f64 {
        let (u, v) = [(1, 2), (2, 0), (0, 1)][self.axis];
        let q = DVec2::new(p[u], p[v]);
        if !(q.cmpge(self.lo).all() && q.cmple(self.hi).all()) || self.tris.is_empty() {
            return 0.0;
        }
        let [bx, by] = Self::bucket(q, self.lo, self.cell, self.g);
        let b = bx * self.g + by;
        let mut w = 0.0;
        for &ti in &self.items[self.start[b] as usize..self.start[b + 1] as usize] {
            let t = &self.tris[ti as usize];
            let s = t.area2.signum();
            let s0 = edge_sign(t.a[1], t.a[2], q) * s;
            let s1 = edge_sign(t.a[2], t.a[0], q) * s;
            let s2 = edge_sign(t.a[0], t.a[1], q) * s;
            if s0 < 0.0 || s1 < 0.0 || s2 < 0.0 {
                continue;
            }
            // Barycentric height of the crossing.
            let l0 = (t.a[2] - t.a[1]).perp_dot(q - t.a[1]);
            let l1 = (t.a[0] - t.a[2]).perp_dot(q - t.a[2]);
            let l2 = (t.a[1] - t.a[0]).perp_dot(q - t.a[0]);
            let h = (l0 * t.h[0] + l1 * t.h[1] + l2 * t.h[2]) / t.area2;
            w += if h > p[self.axis] { 0.5 * s } else { -0.5 * s };
        }
        w
    }
}

/// The inside test of S: signed crossings along z (closed) or the average over x, y, z.
pub(crate) struct InsideTest {
    rays: Vec<RayIndex>,
    /// +1 or -1: the mesh's orientation, so that inward-facing meshes count as solids.
    orient: f64,
    lo: DVec3,
    hi: DVec3,
}

impl InsideTest {
    pub(crate) fn new(mesh: &MeshRef<'_>, closed: bool, orient: f64) -> Self {
        let axes: &[usize] = if closed { &[2] } else { &[0, 1, 2] };
        let (lo, hi) = mesh.bbox();
        Self {
            rays: axes.iter().map(|&a| RayIndex::new(mesh, a)).collect(),
            orient,
            lo,
            hi,
        }
    }

    pub(crate) fn inside(&self, p: DVec3) -> bool {
        if !(p.cmpge(self.lo).all() && p.cmple(self.hi).all()) {
            return false;
        }
        let w: f64 = self.rays.iter().map(|r| r.crossings(p)).sum::<f64>() / self.rays.len() as f64;
        w * self.orient > 0.5
    }
}

/// Whether every directed edge is matched by its reverse, vertices compared by position.
pub(crate) fn is_closed(mesh: &MeshRef<'_>) -> bool {
    let vs = mesh.vertices();
    let mut order: Vec<u32> = (0..vs.len() as u32).collect();
    let key = |i: u32| {
        let p = vs[i as usize];
        // +0.0 and -0.0 are the same position.
        [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits)
    };
    order.sort_by_key(|&i| key(i));
    let mut canon = vec![0u32; vs.len()];
    let mut id = 0u32;
    for (n, &i) in order.iter().enumerate() {
        if n > 0 && key(order[n - 1]) != key(i) {
            id += 1;
        }
        canon[i as usize] = id;
    }
    let mut fwd = Vec::with_capacity(3 * mesh.triangles().len());
    let mut rev = Vec::with_capacity(3 * mesh.triangles().len());
    for t in mesh.triangles() {
        let c = t.map(|v| canon[v as usize]);
        for e in 0..3 {
            let (a, b) = (c[e], c[(e + 1) % 3]);
            fwd.push((a, b));
            rev.push((b, a));
        }
    }
    fwd.sort_unstable();
    rev.sort_unstable();
    fwd == rev
}

/// Signed volume by tetrahedra from the centre of the box of the vertices used (exact for a
/// closed mesh, whatever the centre; the centre limits cancellation).
pub(crate) fn signed_volume(mesh: &MeshRef<'_>) -> f64 {
    let (lo, hi) = mesh.bbox();
    let c = 0.5 * (lo + hi);
    let mut sum = 0.0;
    for t in 0..mesh.triangles().len() {
        let [a, b, d] = mesh.corners(t);
        sum += (a - c).dot((b - c).cross(d - c));
    }
    sum / 6.0
}
