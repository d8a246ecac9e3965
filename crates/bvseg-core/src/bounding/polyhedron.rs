//! An enclosing convex polyhedron with few vertices.
//!
//! The convex hull of a part's points often has hundreds of vertices (every surface triangle
//! contributes its corners), while engines take convex meshes of 32 to 255. Dropping hull
//! vertices would uncover the surface; this cuts corners instead. It starts from the part's
//! tight oriented box (8 vertices) and clips it, one plane at a time, with the supporting
//! plane of the hull face that the current polyhedron crosses deepest, while the vertex count
//! stays within the limit. Every plane supports the hull, so the result always encloses the
//! points. A clip that would put a new vertex within [`MIN_EDGE`] of the diameter of an
//! existing one is skipped, so no sliver face or needle edge appears.
use crate::math;
use std::cmp::{Ordering, Reverse};
use std::collections::{BTreeMap, BinaryHeap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;

use super::hull::convex_hull;
use super::obb::min_obb;
use crate::volume::BoundingVolume;

/// Shortest edge, relative to the hull's diameter, a clip may create.
const MIN_EDGE: f64 = 1e-3;
/// Candidate planes tried per clip, deepest first, before the search stops.
const TRIES: usize = 8;
/// Depth, relative to the diameter, below which the polyhedron counts as the hull itself.
const DONE: f64 = 1e-9;

/// A convex polygon face, counter-clockwise seen from outside.
type Face = Vec<DVec3>;

/// A number totally ordered (a plane's depth in the heap, a coordinate in [`Near`]).
#[derive(Debug, Clone, Copy)]
struct Ordered(f64);

impl PartialEq for Ordered {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// An enclosing hull of `points` with at most `max_vertices` vertices (at least 8 are
/// allowed for, a box's), at least `min_r` across in every direction.
pub fn few_vertex_hull(points: &[DVec3], max_vertices: usize, min_r: f64) -> BoundingVolume {
    let finite: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let hull = convex_hull(&finite);
    let obb = min_obb(&finite, min_r);
    let box_hull = || {
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                let s = DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                obb.world(s)
            })
            .collect();
        BoundingVolume::hull(&corners)
    };
    if hull.dim == 3 && hull.vertices.len() <= max_vertices && !has_close_vertices(&hull.vertices) {
        if let Some(v) = BoundingVolume::hull(&hull.vertices) {
            return v.scaled_to_contain(finite.iter().copied());
        }
    }
    if hull.dim < 3 || max_vertices < 8 {
        // Flat parts get the box, which has the thickness `min_r`; a limit below a box's 8
        // vertices gets the tetrahedron around the box.
        let b = if max_vertices < 8 {
            tetrahedron_around(&obb)
        } else {
            box_hull()
        };
        return b.map_or(obb, |v| v.scaled_to_contain(finite.iter().copied()));
    }
    let diameter = 2.0 * obb.radii.length();
    // The hull's face planes that truly support it: a sliver triangle of nearly collinear
    // corners has no reliable normal (one on the bunny cut a third of its part away).
    let planes: Vec<(DVec3, f64)> = (0..hull.faces.len())
        .filter_map(|f| {
            let (n, area) = hull.face_normal_area(f);
            if area <= 1e-12 * diameter * diameter {
                return None;
            }
            let d = n.dot(hull.vertices[hull.faces[f][0] as usize]);
            let out = hull
                .vertices
                .iter()
                .map(|&v| n.dot(v) - d)
                .fold(f64::NEG_INFINITY, math::max);
            (out <= 1e-9 * diameter).then_some((n, d))
        })
        .collect();
    let mut faces = box_faces(&obb);
    // Each plane's depth below the polyhedron's deepest vertex only falls as the polyhedron
    // shrinks, so the depths found earlier bound the current ones, and a heap of them yields
    // the planes deepest first (ties by index) while measuring only the few near the top.
    let depth_of = |j: usize, verts: &[DVec3]| {
        let (n, d) = planes[j];
        verts
            .iter()
            .map(|&v| n.dot(v) - d)
            .fold(f64::NEG_INFINITY, math::max)
    };
    let mut verts = vertices(&faces, diameter);
    let mut heap: BinaryHeap<(Ordered, Reverse<usize>)> = (0..planes.len())
        .map(|j| (Ordered(depth_of(j, &verts)), Reverse(j)))
        .filter(|&(d, _)| d.0 > DONE * diameter)
        .collect();
    loop {
        let mut clipped = None;
        let mut tries = 0;
        while tries < TRIES {
            let Some((_, Reverse(j))) = heap.pop() else {
                break;
            };
            let depth = Ordered(depth_of(j, &verts));
            if depth.0 <= DONE * diameter {
                // Never deeper again: done with this plane.
                continue;
            }
            if heap.peek().is_some_and(|&top| (depth, Reverse(j)) < top) {
                heap.push((depth, Reverse(j)));
                continue;
            }
            // The deepest plane left; tried once, whatever comes of it.
            tries += 1;
            let (n, d) = planes[j];
            let next = clip(&faces, n, d, diameter);
            let nv = vertices(&next, diameter);
            if nv.len() <= max_vertices && nv.len() >= 4 && !has_close_vertices_d(&nv, diameter) {
                clipped = Some((next, nv));
                break;
            }
        }
        match clipped {
            Some((f, v)) => (faces, verts) = (f, v),
            None => break,
        }
    }
    let clipped = BoundingVolume::hull(&verts).map(|v| v.scaled_to_contain(finite.iter().copied()));
    // Every plane supports the hull, so the clipped box is inside the box; should round-off
    // ever have it otherwise, the box is the safe answer.
    match clipped {
        Some(v) if v.volume() <= obb.volume() * (1.0 + 1e-9) => v,
        _ => box_hull().map_or(obb, |v| v.scaled_to_contain(finite.iter().copied())),
    }
}

/// The regular-ish tetrahedron around a box (its four alternate corners pushed out so that
/// its faces hold the box).
fn tetrahedron_around(obb: &BoundingVolume) -> Option<BoundingVolume> {
    // The tetrahedron with vertices at 3 times the alternate corners holds the unit cube:
    // each face plane sum s_j t_j = -1 (in the unit-corner scale of 3) lies beyond it.
    let corners: Vec<DVec3> = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, -1.0, 1.0),
    ]
    .into_iter()
    .map(|s| obb.world(3.0 * s))
    .collect();
    BoundingVolume::hull(&corners)
}

fn has_close_vertices(v: &[DVec3]) -> bool {
    let (lo, hi) = v
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| {
            (l.min(p), h.max(p))
        });
    has_close_vertices_d(v, (hi - lo).length())
}

fn has_close_vertices_d(v: &[DVec3], diameter: f64) -> bool {
    let r = MIN_EDGE * diameter;
    // A sweep along x: only pairs closer than `r` in x can be closer than `r`.
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].x.total_cmp(&v[b].x));
    (0..order.len()).any(|i| {
        let p = v[order[i]];
        order[i + 1..]
            .iter()
            .map(|&j| v[j])
            .take_while(|q| q.x - p.x <= r)
            .any(|q| (q - p).length_squared() < r * r)
    })
}

/// A hasher for coordinates' bits (multiply-rotate, as rustc's FxHasher): the standard one
/// was a sixth of the time of a 255-vertex fit.
#[derive(Default)]
struct BitsHasher(u64);

impl Hasher for BitsHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// Points ordered by x, to find one within `r` of a point by looking only at those within
/// `r` in x (polyhedra with hundreds of vertices made the pairwise scans the cost of a fit).
#[derive(Default)]
struct Near {
    by_x: BTreeMap<(Ordered, u32), DVec3>,
}

impl Near {
    /// Whether a point within `r` of `p` was inserted.
    fn any_within(&self, p: DVec3, r: f64) -> bool {
        let range = (Ordered(p.x - r), 0)..=(Ordered(p.x + r), u32::MAX);
        self.by_x
            .range(range)
            .any(|(_, &q)| (q - p).length_squared() <= r * r)
    }

    /// Inserts `p` as the point numbered `i`.
    fn insert(&mut self, i: u32, p: DVec3) {
        self.by_x.insert((Ordered(p.x), i), p);
    }
}

/// The six faces of a box.
fn box_faces(b: &BoundingVolume) -> Vec<Face> {
    let c = |sx: f64, sy: f64, sz: f64| b.world(DVec3::new(sx, sy, sz));
    let mut faces = Vec::with_capacity(6);
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            // Corners of the face in the order of its two free axes, turned to face out.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut f: Face = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .into_iter()
                .map(|(a, bb)| {
                    let mut t = [0.0; 3];
                    t[axis] = sign;
                    t[u] = a;
                    t[v] = bb;
                    c(t[0], t[1], t[2])
                })
                .collect();
            if sign < 0.0 {
                f.reverse();
            }
            faces.push(f);
        }
    }
    faces
}

/// The distinct vertices of the faces (points closer than a hair of the diameter are one),
/// in the order they first appear.
fn vertices(faces: &[Face], diameter: f64) -> Vec<DVec3> {
    let eps = 1e-12 * diameter;
    let mut near = Near::default();
    // Most repeats are the same bits (an edge's point is computed once for both its faces).
    let mut seen: HashSet<[u64; 3], BuildHasherDefault<BitsHasher>> = HashSet::default();
    let mut out: Vec<DVec3> = Vec::new();
    for f in faces {
        for &p in f {
            if seen.insert(p.to_array().map(f64::to_bits)) && !near.any_within(p, eps) {
                near.insert(out.len() as u32, p);
                out.push(p);
            }
        }
    }
    out
}

/// The polyhedron `faces` cut by the half-space `n . x <= d`.
fn clip(faces: &[Face], n: DVec3, d: f64, diameter: f64) -> Vec<Face> {
    let eps = 1e-12 * diameter;
    let mut out = Vec::with_capacity(faces.len() + 1);
    let mut cut: Vec<DVec3> = Vec::new();
    for f in faces {
        let mut g: Face = Vec::with_capacity(f.len() + 1);
        for i in 0..f.len() {
            let (a, b) = (f[i], f[(i + 1) % f.len()]);
            let (da, db) = (n.dot(a) - d, n.dot(b) - d);
            if da <= 0.0 {
                g.push(a);
            }
            if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                // Computed from the inside end, so both faces of an edge get the same point.
                let (p, q, dp, dq) = if da < 0.0 {
                    (a, b, da, db)
                } else {
                    (b, a, db, da)
                };
                let x = p + (q - p) * (dp / (dp - dq));
                g.push(x);
                cut.push(x);
            } else if da.abs() <= eps && da > 0.0 {
                cut.push(a);
            }
            if da <= 0.0 && da >= -eps {
                cut.push(a);
            }
        }
        g.dedup_by(|x, y| (*x - *y).length() <= eps);
        if g.len() >= 3 {
            out.push(g);
        }
    }
    // The cap: the cut points in counter-clockwise order seen from outside (along n).
    let mut cap: Vec<DVec3> = Vec::new();
    for p in cut {
        if !cap.iter().any(|&q| (q - p).length() <= eps) {
            cap.push(p);
        }
    }
    if cap.len() >= 3 {
        let mid = cap.iter().copied().sum::<DVec3>() / cap.len() as f64;
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        // By a pseudo-angle (exact arithmetic, the same on every platform, unlike atan2).
        let angle = |p: DVec3| {
            let (x, y) = ((p - mid).dot(u), (p - mid).dot(w));
            let r = x.abs() + y.abs();
            if r <= 0.0 {
                return 0.0;
            }
            let t = y / r;
            if x >= 0.0 {
                t
            } else {
                2.0 - t
            }
        };
        cap.sort_by(|a, b| angle(*a).total_cmp(&angle(*b)));
        out.push(cap);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn blob(seed: u64, n: usize) -> Vec<DVec3> {
        let mut r = Rng::new(seed);
        (0..n)
            .map(|_| {
                let d = DVec3::new(r.next_f64() - 0.5, r.next_f64() - 0.5, r.next_f64() - 0.5)
                    .normalize();
                d * DVec3::new(2.0, 1.0, 0.6) * (0.9 + 0.1 * r.next_f64())
            })
            .collect()
    }

    #[test]
    fn encloses_within_the_vertex_limit_and_beats_the_box() {
        for seed in 0..6 {
            let p = blob(seed, 400);
            let exact = BoundingVolume::hull(&p).unwrap();
            let obb = min_obb(&p, 1e-9);
            for max in [8, 12, 32, 64] {
                let v = few_vertex_hull(&p, max, 1e-9);
                let verts = v.hull_points();
                assert!(verts.len() <= max, "{} > {max}", verts.len());
                assert!(
                    p.iter().all(|&q| v.contains(q)),
                    "seed {seed}: a point escapes"
                );
                assert!(v.volume() >= exact.volume() * (1.0 - 1e-9));
                assert!(v.volume() <= obb.volume() * (1.0 + 1e-9));
                if max >= 32 {
                    assert!(
                        v.volume() < 0.8 * obb.volume(),
                        "seed {seed}, {max} vertices: {} vs box {}",
                        v.volume(),
                        obb.volume()
                    );
                }
                assert!(!has_close_vertices(&verts), "a sliver edge");
            }
        }
    }

    #[test]
    fn a_small_hull_is_kept_exactly() {
        // A box's corners: the hull is the box.
        let p: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    (i & 1) as f64,
                    ((i >> 1) & 1) as f64 * 2.0,
                    ((i >> 2) & 1) as f64,
                )
            })
            .collect();
        let v = few_vertex_hull(&p, 32, 1e-9);
        assert!((v.volume() - 2.0).abs() < 1e-9, "{}", v.volume());
        // Fewer than 8 allowed: the tetrahedron around the box still holds it.
        let t = few_vertex_hull(&p, 4, 1e-9);
        assert_eq!(t.hull_points().len(), 4);
        assert!(p.iter().all(|&q| t.contains(q)));
    }

    #[test]
    fn a_part_from_the_bunny_stays_tight() {
        // The points of a bunny part whose clipped box once grew 70-fold.
        let p = vec![
            DVec3::new(-2.138539917287596, 3.972308533084961, 0.2537757417287594),
            DVec3::new(-2.138539917287596, 4.399054016542481, -0.3863424834575193),
            DVec3::new(-2.138539917287596, 4.612426758271241, -1.026460708643798),
            DVec3::new(-2.031853546423216, 3.972308533084961, 0.3604621125931393),
            DVec3::new(-1.7117944338300766, 1.411835632339846, 0.2537757417287594),
            DVec3::new(-1.7117944338300766, 4.612426758271241, 0.46714848345751925),
            DVec3::new(-1.7117944338300766, 5.679290466915038, -0.5997152251862787),
            DVec3::new(-1.605108062965697, 1.3051492614754663, 0.2537757417287594),
            DVec3::new(-1.605108062965697, 1.411835632339846, 0.3604621125931393),
            DVec3::new(-1.605108062965697, 2.6920720827124036, 0.5738348543218992),
            DVec3::new(-1.605108062965697, 4.612426758271241, 0.5738348543218992),
            DVec3::new(-1.3917353212369372, 1.838581115797365, 0.5738348543218992),
            DVec3::new(-1.3917353212369372, 4.612426758271241, 0.5738348543218992),
            DVec3::new(-1.1783625795081774, 1.3051492614754663, 0.2537757417287594),
            DVec3::new(-1.1783625795081774, 1.5185220032042257, 0.46714848345751925),
            DVec3::new(-1.1783625795081774, 1.6252083740686056, 0.5738348543218992),
            DVec3::new(-0.9649898377794184, 1.5185220032042257, 0.46714848345751925),
            DVec3::new(-0.9649898377794184, 1.6252083740686056, 0.5738348543218992),
            DVec3::new(-0.9649898377794184, 4.185681274813721, 0.5738348543218992),
            DVec3::new(-0.7516170960506585, 1.3051492614754663, -0.8130879669150382),
            DVec3::new(
                -0.7516170960506585,
                1.3051492614754663,
                -0.17296974172875945,
            ),
            DVec3::new(-0.6449307251862786, 1.6252083740686056, 0.2537757417287594),
            DVec3::new(-0.5382443543218987, 1.5185220032042257, 0.04040300000000041),
            DVec3::new(-0.4315579834575187, 1.6252083740686056, 0.04040300000000041),
            DVec3::new(-0.4315579834575187, 4.185681274813721, 0.04040300000000041),
            DVec3::new(-0.3248716125931388, 1.5185220032042257, -0.3863424834575193),
            DVec3::new(
                -0.21818524172875975,
                1.6252083740686056,
                -0.3863424834575193,
            ),
            DVec3::new(-0.21818524172875975, 2.478699340983644, -0.5997152251862787),
            DVec3::new(-0.21818524172875975, 3.545563049627442, -0.8130879669150382),
            DVec3::new(-0.21818524172875975, 3.758935791356202, -0.3863424834575193),
            DVec3::new(-1.13696, 3.194401, -1.513455),
            DVec3::new(-1.001832, 3.590411, -1.545892),
            DVec3::new(-1.821193, 4.366982, -1.266271),
            DVec3::new(-1.915407, 4.693647, -1.151721),
            DVec3::new(-0.579059, 4.042511, -1.540883),
            DVec3::new(-0.693698, 4.478782, -1.369372),
            DVec3::new(-1.001416, 1.298225, -0.904674),
            DVec3::new(-1.248839, 5.959105, 0.041761),
            DVec3::new(-1.002038, 5.794454, -0.187194),
            DVec3::new(-2.120811, 1.836483, -0.62338),
            DVec3::new(-0.823768, 3.788746, -1.567481),
            DVec3::new(-0.76988, 1.508373, -1.419599),
            DVec3::new(-1.728102, 1.110064, -0.635963),
            DVec3::new(-0.801715, 4.973149, -1.068582),
            DVec3::new(-0.71211, 5.341811, -0.803281),
            DVec3::new(-0.822371, 5.517453, -0.605747),
            DVec3::new(-1.880401, 5.583843, -0.696561),
            DVec3::new(-2.025852, 5.089562, -0.980218),
            DVec3::new(-1.776173, 5.287097, -0.89091),
            DVec3::new(-1.600621, 5.962818, -0.188044),
            DVec3::new(-1.600803, 5.785347, -0.491069),
            DVec3::new(-1.588831, 5.615418, -0.665456),
            DVec3::new(-1.370865, 5.838832, -0.341026),
            DVec3::new(-1.964823, 1.464607, -0.58115),
            DVec3::new(-1.916516, 4.054121, -1.301788),
            DVec3::new(-1.931518, 3.062883, -1.197227),
        ];
        let v = few_vertex_hull(&p, 32, 0.1);
        let exact = BoundingVolume::hull(&p).unwrap();
        assert!(v.hull_points().len() <= 32);
        assert!(p.iter().all(|&q| v.contains(q)));
        assert!(
            v.volume() < 3.0 * exact.volume(),
            "{} vs {}",
            v.volume(),
            exact.volume()
        );
    }
}
