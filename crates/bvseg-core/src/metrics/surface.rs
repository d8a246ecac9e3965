//! Exact distances from points to the mesh surface, through a bounding-volume hierarchy of
//! its triangles: what the protrusion ([`super::protrusion`]) is measured with.
//!
//! A tree rather than a grid of triangle buckets: a hostile mesh of a few huge triangles would
//! put each of them in every bucket. The build is `O(n log n)` whatever the triangles' sizes,
//! and deterministic (ties between centroids are broken by index).
use crate::math;
use glam::DVec3;

use crate::geometry::closest_on_segment;
use crate::Mesh;

/// No triangle yet, for the start of a search (see [`SurfaceDistance::distance_within`]).
pub const NO_TRIANGLE: u32 = u32::MAX;

/// Triangles per leaf.
const LEAF: usize = 4;

/// Entries of a query's stack: the tree of at most `2^32` triangles, split at the median, has
/// fewer than 33 levels.
const STACK: usize = 72;

#[derive(Debug, Clone)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// A leaf (`count > 0`) holds the triangles `start..start + count`. An inner node's left
    /// child is the node after it, its right child node `start`.
    start: u32,
    count: u32,
}

/// The mesh's triangles in a tree, for nearest-point queries.
#[derive(Debug, Clone)]
pub struct SurfaceDistance {
    tris: Vec<[DVec3; 3]>,
    nodes: Vec<Node>,
}

impl SurfaceDistance {
    /// The tree of `mesh`'s triangles.
    pub fn new(mesh: &Mesh) -> Self {
        // A face repeated (as hostile files do, thousands of times) is one face to the
        // distance, and would make every query near it visit each copy.
        let mut faces: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .map(|t| {
                let mut t = *t;
                t.sort_unstable();
                t
            })
            .collect();
        faces.sort_unstable();
        faces.dedup();
        let v = mesh.vertices();
        let mut tris: Vec<[DVec3; 3]> = faces.iter().map(|t| t.map(|i| v[i as usize])).collect();
        crate::work::add(tris.len());
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        if !tris.is_empty() {
            let n = tris.len();
            build(&mut tris, 0, n, &mut nodes);
        }
        Self { tris, nodes }
    }

    /// Distance from `p` to the nearest point of the surface (infinite for an empty mesh).
    #[cfg(test)]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.distance_squared(p).sqrt()
    }

    /// [`SurfaceDistance::distance`], adding the nodes and triangles it visits to `spent`;
    /// `None` (without searching) once `spent` exceeds `cap`. `bound` is an upper bound of
    /// the distance (infinite if none is known): with a good one, the search prunes most of
    /// the tree, and the result is exact either way (if no triangle is nearer than the bound,
    /// the distance is the bound). A caller that needs the distance only when it exceeds
    /// `floor` gets, when it does not, some value at most `floor` (an upper bound of the
    /// distance, found without proving it the nearest): most of a query's work is that proof.
    /// `near` is a triangle (an index of this tree's, as the last query left it) to try
    /// first: queries at nearby points have nearby nearest triangles, and one close enough
    /// settles a query below the floor at once. The query leaves its nearest triangle there.
    /// The caller adds `spent` to [`crate::work`], once, rather than every query contending
    /// for that shared counter.
    pub fn distance_within(
        &self,
        p: DVec3,
        (bound, floor): (f64, f64),
        near: &std::cell::Cell<u32>,
        spent: &std::cell::Cell<u64>,
        cap: u64,
    ) -> Option<f64> {
        if spent.get() > cap {
            return None;
        }
        // Below this squared distance the root is below `floor` for certain (the factor
        // covers the rounding of the square and of the root).
        let stop = if floor > 0.0 {
            floor * floor * (1.0 - 1e-12)
        } else {
            f64::NEG_INFINITY
        };
        let (d, visited) = self.search(p, (bound * bound, stop), near);
        spent.set(spent.get() + visited as u64);
        Some(d.sqrt())
    }

    /// Squared [`SurfaceDistance::distance`].
    #[cfg(test)]
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let near = std::cell::Cell::new(NO_TRIANGLE);
        self.search(p, (f64::INFINITY, f64::NEG_INFINITY), &near).0
    }

    /// The squared distance (at most `bound`) and the number of nodes and triangles visited;
    /// once a triangle at most `stop` away is found, that triangle's instead. Starts from
    /// triangle `near` and leaves the nearest found there. The nearest triangle gives the
    /// same minimum whichever is tried first: a start only prunes nodes that cannot hold a
    /// nearer one.
    fn search(
        &self,
        p: DVec3,
        (bound, stop): (f64, f64),
        near: &std::cell::Cell<u32>,
    ) -> (f64, usize) {
        let mut best = bound;
        if self.nodes.is_empty() || best <= stop {
            return (best, 0);
        }
        let mut visited = 0usize;
        if let Some(t) = self.tris.get(near.get() as usize) {
            visited += 1;
            best = math::min(best, distance_squared_to(p, t));
            if best <= stop {
                return (best, visited);
            }
        }
        // The tree is balanced (median splits), so the stack holds at most one node per level
        // plus one: a fixed array, where a vector cost an allocation per query.
        let mut stack = [(0u32, 0.0f64); STACK];
        stack[0] = (0, box_distance_squared(&self.nodes[0], p));
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (i, d) = stack[top];
            if d >= best {
                continue;
            }
            visited += 1;
            let node = &self.nodes[i as usize];
            if node.count > 0 {
                let (s, c) = (node.start as usize, node.count as usize);
                visited += c;
                for (j, t) in self.tris[s..s + c].iter().enumerate() {
                    let d = distance_squared_to(p, t);
                    if d < best {
                        best = d;
                        near.set((s + j) as u32);
                    }
                }
                if best <= stop {
                    return (best, visited);
                }
            } else {
                let (l, r) = (i + 1, node.start);
                let dl = box_distance_squared(&self.nodes[l as usize], p);
                let dr = box_distance_squared(&self.nodes[r as usize], p);
                // The nearer child is searched first (pushed last).
                let pair = if dl <= dr {
                    [(r, dr), (l, dl)]
                } else {
                    [(l, dl), (r, dr)]
                };
                stack[top..top + 2].copy_from_slice(&pair);
                top += 2;
            }
        }
        (best, visited)
    }
}

/// Builds the subtree of `tris[a..b]` (reordered in place); returns its node's index.
fn build(tris: &mut [[DVec3; 3]], a: usize, b: usize, nodes: &mut Vec<Node>) -> u32 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for t in &tris[a..b] {
        for &v in t {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let c = centroid(t);
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let me = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        start: a as u32,
        count: (b - a) as u32,
    });
    let ext = chi - clo;
    if b - a <= LEAF || ext.max_element() <= 0.0 {
        return me;
    }
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = a + (b - a) / 2;
    tris[a..b].select_nth_unstable_by(mid - a, |x, y| {
        centroid(x)[axis].total_cmp(&centroid(y)[axis])
    });
    build(tris, a, mid, nodes);
    let right = build(tris, mid, b, nodes);
    let node = &mut nodes[me as usize];
    node.start = right;
    node.count = 0;
    me
}

fn centroid(t: &[DVec3; 3]) -> DVec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

fn box_distance_squared(n: &Node, p: DVec3) -> f64 {
    let d = (n.lo - p).max(p - n.hi).max(DVec3::ZERO);
    d.length_squared()
}

fn distance_squared_to(p: DVec3, t: &[DVec3; 3]) -> f64 {
    (closest_on_triangle(p, t) - p).length_squared()
}

/// The point of triangle `t` nearest `p` (Ericson, *Real-Time Collision Detection*, 5.1.5).
fn closest_on_triangle(p: DVec3, [a, b, c]: &[DVec3; 3]) -> DVec3 {
    let (a, b, c) = (*a, *b, *c);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE || !denom.is_finite() {
        // A degenerate triangle: the nearest of its edges' points.
        let seg = |u: DVec3, v: DVec3| closest_on_segment(p, u, v);
        return [seg(a, b), seg(b, c), seg(c, a)]
            .into_iter()
            .min_by(|x, y| {
                (*x - p)
                    .length_squared()
                    .total_cmp(&(*y - p).length_squared())
            })
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::shapes;
    use glam::DMat3;

    fn brute(mesh: &Mesh, p: DVec3) -> f64 {
        (0..mesh.triangles().len())
            .map(|t| (closest_on_triangle(p, &mesh.corners(t)) - p).length_squared())
            .fold(f64::INFINITY, math::min)
            .sqrt()
    }

    #[test]
    fn tree_agrees_with_brute_force() {
        let mesh = shapes::union(&[
            shapes::ellipsoid(DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5), DMat3::IDENTITY, 24),
            shapes::cuboid(
                DVec3::new(1.5, 0.0, 0.0),
                DVec3::splat(0.4),
                DMat3::IDENTITY,
            ),
        ]);
        let tree = SurfaceDistance::new(&mesh);
        let mut rng = Rng::new(7);
        for _ in 0..500 {
            let p = DVec3::new(
                rng.next_f64() * 6.0 - 3.0,
                rng.next_f64() * 4.0 - 2.0,
                rng.next_f64() * 4.0 - 2.0,
            );
            // Equal up to rounding: the tree stores each face's corners in another order.
            let (t, b) = (tree.distance(p), brute(&mesh, p));
            assert!(
                (t - b).abs() <= 1e-12 * math::max(b, 1.0),
                "{p}: {t} vs {b}"
            );
        }
    }

    /// With a floor, a distance above it is the exact one, bit for bit, and one at or below
    /// it is any value from the distance up to the floor, found with less work.
    #[test]
    fn a_floor_keeps_the_distances_above_it_exact() {
        let mesh = shapes::ellipsoid(DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5), DMat3::IDENTITY, 24);
        let tree = SurfaceDistance::new(&mesh);
        let mut rng = Rng::new(3);
        let (mut above, mut below, mut saved) = (0, 0, 0u64);
        for _ in 0..500 {
            let p = DVec3::new(
                rng.next_f64() * 6.0 - 3.0,
                rng.next_f64() * 4.0 - 2.0,
                rng.next_f64() * 4.0 - 2.0,
            );
            let floor = rng.next_f64() * 1.5;
            let (plain, with) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
            let near = || std::cell::Cell::new(NO_TRIANGLE);
            let all = (f64::INFINITY, f64::NEG_INFINITY);
            let exact = tree.distance_within(p, all, &near(), &plain, u64::MAX);
            let got = tree.distance_within(p, (f64::INFINITY, floor), &near(), &with, u64::MAX);
            let (exact, got) = (exact.unwrap(), got.unwrap());
            assert!(with.get() <= plain.get());
            if exact > floor {
                assert_eq!(got.to_bits(), exact.to_bits(), "{p}, floor {floor}");
                above += 1;
            } else {
                assert!(
                    got >= exact && got <= floor,
                    "{p}: {got} vs {exact}, floor {floor}"
                );
                below += 1;
                saved += plain.get() - with.get();
            }
        }
        assert!(above > 50 && below > 50, "{above} above, {below} below");
        assert!(saved > 0);
    }

    #[test]
    fn distances_to_a_cube_face_edge_and_corner() {
        let mesh = shapes::cuboid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY);
        let tree = SurfaceDistance::new(&mesh);
        let close = |p: DVec3, d: f64| (tree.distance(p) - d).abs() < 1e-12;
        assert!(close(DVec3::new(3.0, 0.2, -0.1), 2.0));
        assert!(close(DVec3::new(2.0, 2.0, 0.0), 2f64.sqrt()));
        assert!(close(DVec3::splat(2.0), 3f64.sqrt()));
        assert!(
            close(DVec3::new(0.0, 0.0, 0.5), 0.5),
            "inside: to the nearest face"
        );
    }
}
