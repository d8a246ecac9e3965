//! 3D convex hull (quickhull) with exact orientation tests.
//!
//! The points are first snapped to an integer grid of 2^40 steps across their bounding box.
//! On that grid the orientation of four points is an exact `i128` determinant, so the
//! visibility decisions that shape the hull's topology are always consistent: the horizon is
//! always one simple loop and the algorithm can neither corrupt its mesh nor loop. A point is
//! only *added* to the hull when it lies more than a small relative tolerance outside a face;
//! points closer than that (the many coplanar ties of lattice inputs, or round-off noise on a
//! rotated lattice) are dropped. Dropped points are at most that tolerance outside the hull,
//! which the callers absorb by rescaling their volumes over all the input points.
//!
//! Here the snapping and the output; quickhull itself in `quickhull.rs`, the tests that cull
//! most points before the exact ones in `cull.rs`.
mod cull;
mod quickhull;

use crate::math;
use glam::DVec3;

use quickhull::QuickHull;

/// A convex hull: its vertices and outward-facing triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hull {
    /// The hull's vertices (a subset of the input points), in increasing input order.
    pub vertices: Vec<DVec3>,
    /// For each vertex, its index in the input slice.
    pub indices: Vec<usize>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside. Empty when
    /// the hull is a point or a segment. A flat hull (`dim == 2`) lists each triangle once per
    /// side, so the surface is still closed. Also empty, with all the finite input points as
    /// `vertices`, in the never observed case that the construction fails (or that the
    /// points' extent overflows `f64`).
    pub faces: Vec<[u32; 3]>,
    /// Affine dimension of the hull: 0 (one point, or none), 1 (segment), 2 (polygon) or 3.
    pub dim: usize,
}

impl Hull {
    /// The enclosed volume (0 for a flat or smaller hull).
    pub fn volume(&self) -> f64 {
        if self.dim < 3 {
            return 0.0;
        }
        let Some(&o) = self.vertices.first() else {
            return 0.0;
        };
        let six: f64 = self
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| self.vertices[i as usize] - o);
                a.dot(b.cross(c))
            })
            .sum();
        math::max(six / 6.0, 0.0)
    }

    /// Unit outward normal and area of face `f` (zero normal for a degenerate triangle).
    pub fn face_normal_area(&self, f: usize) -> (DVec3, f64) {
        let [a, b, c] = self.faces[f].map(|i| self.vertices[i as usize]);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len > 0.0 && len.is_finite() {
            (n / len, 0.5 * len)
        } else {
            (DVec3::ZERO, 0.0)
        }
    }
}

/// The vertices of the convex hull of `points`, in increasing input order.
///
/// Degenerate inputs return what their hull has: the polygon's corners for coplanar points,
/// the two ends of a collinear set, one point for duplicates of one point, nothing for an empty
/// input. Non-finite points are ignored.
pub fn hull_points(points: &[DVec3]) -> Vec<DVec3> {
    hull(points, false).vertices
}

/// Relative tolerance (of the bounding box's largest side) below which a point outside a face
/// counts as on it. Far above round-off in the inputs, far below any geometric feature.
const EPS_REL: f64 = 1e-10;
/// Grid resolution: coordinates become integers in `0..=2^40`, so that a 3x3 determinant of
/// coordinate differences (< 2^123) fits in an `i128`.
const GRID: f64 = (1u64 << 40) as f64;
/// Bound on the relative error of the floating-point orientation (a few ulps of the
/// determinant's permanent), above which its sign is certain.
const ORIENT_ERR: f64 = 1e-15;
/// Inputs up to this many points skip the [`DirMap`].
const DIRMAP_MIN_POINTS: usize = 2000;

/// The convex hull of `points` (see `Hull`). Deterministic: the same input gives the same
/// output, vertex and face order included. Non-finite points are ignored.
pub fn convex_hull(points: &[DVec3]) -> Hull {
    hull(points, true)
}

/// [`convex_hull`], without the 3D faces unless `with_faces`.
fn hull(points: &[DVec3], with_faces: bool) -> Hull {
    let idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].is_finite())
        .collect();
    let Some(&first) = idx.first() else {
        return Hull::default();
    };
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &i in &idx {
        lo = lo.min(points[i]);
        hi = hi.max(points[i]);
    }
    let ext = (hi - lo).max_element();
    if ext.is_nan() || ext <= 0.0 {
        return single(points, first);
    }
    if !ext.is_finite() {
        // The extent overflows: no grid can hold these points; all of them are a superset.
        return Hull {
            vertices: idx.iter().map(|&i| points[i]).collect(),
            indices: idx,
            faces: Vec::new(),
            dim: 3,
        };
    }
    let scale = GRID / ext;
    // Truncation of a non-negative value plus one half rounds it, without a libm call.
    let q: Vec<DVec3> = idx
        .iter()
        .map(|&i| {
            let t = (points[i] - lo) * scale + 0.5;
            DVec3::new(t.x as i64 as f64, t.y as i64 as f64, t.z as i64 as f64)
        })
        .collect();
    // Round-off already present in the input grows with the coordinates' magnitude, not just
    // with the extent; the grid snapping adds at most one unit.
    let mag = lo.abs().max(hi.abs()).max_element();
    let eps = GRID * EPS_REL + 64.0 * f64::EPSILON * mag * scale + 2.0;
    let mut qh = QuickHull::new(&q, eps);
    let raw = qh.run();
    let mut out = match raw {
        Raw::Point(a) => single(points, idx[a]),
        Raw::Segment(a, b) => from_vertices(points, &idx, &[a, b], &[], 1),
        Raw::Polygon(poly) => {
            // Fan triangulation, once per side.
            let mut faces = Vec::new();
            for k in 1..poly.len().saturating_sub(1) {
                faces.push([poly[0], poly[k], poly[k + 1]]);
                faces.push([poly[0], poly[k + 1], poly[k]]);
            }
            from_vertices(points, &idx, &poly, &faces, 2)
        }
        Raw::Polytope(faces) => {
            let verts: Vec<usize> = faces.iter().flatten().copied().collect();
            let faces = if with_faces { &faces[..] } else { &[] };
            from_vertices(points, &idx, &verts, faces, 3)
        }
        Raw::Cloud(verts) => from_vertices(points, &idx, &verts, &[], 3),
    };
    out.vertices.shrink_to_fit();
    out
}

fn single(points: &[DVec3], i: usize) -> Hull {
    Hull {
        vertices: vec![points[i]],
        indices: vec![i],
        faces: Vec::new(),
        dim: 0,
    }
}

/// Builds the output from hull vertices and faces given as indices into the filtered points.
fn from_vertices(
    points: &[DVec3],
    idx: &[usize],
    verts: &[usize],
    faces: &[[usize; 3]],
    dim: usize,
) -> Hull {
    // Position of each used vertex among the used ones, in increasing index order.
    let mut remap = vec![u32::MAX; idx.len()];
    for &v in verts {
        remap[v] = 0;
    }
    let mut used: Vec<usize> = Vec::with_capacity(verts.len().min(idx.len()));
    for (v, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = used.len() as u32;
            used.push(v);
        }
    }
    let remap = |v: usize| remap[v];
    Hull {
        vertices: used.iter().map(|&v| points[idx[v]]).collect(),
        indices: used.iter().map(|&v| idx[v]).collect(),
        faces: faces.iter().map(|f| f.map(remap)).collect(),
        dim,
    }
}

/// What the hull computation found, as indices into the snapped points.
enum Raw {
    Point(usize),
    Segment(usize, usize),
    Polygon(Vec<usize>),
    Polytope(Vec<[usize; 3]>),
    /// Vertices without faces (only if the mesh were ever found inconsistent).
    Cloud(Vec<usize>),
}

#[cfg(test)]
mod tests {
    use super::cull::DirMap;
    use super::*;
    use crate::rng::Rng;
    use glam::DMat3;

    fn lattice(n: usize, h: f64) -> Vec<DVec3> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    v.push(DVec3::new(i as f64, j as f64, k as f64) * h);
                }
            }
        }
        v
    }

    fn sorted(mut v: Vec<DVec3>) -> Vec<[f64; 3]> {
        let mut a: Vec<[f64; 3]> = v.drain(..).map(|p| p.to_array()).collect();
        a.sort_by(|x, y| x.partial_cmp(y).unwrap_or(std::cmp::Ordering::Equal));
        a
    }

    fn corners(lo: f64, hi: f64) -> Vec<[f64; 3]> {
        let v = (0..8)
            .map(|i| {
                let s = |b: usize| if i & b == 0 { lo } else { hi };
                DVec3::new(s(1), s(2), s(4))
            })
            .collect();
        sorted(v)
    }

    /// Every input point is on the inner side of every face, and the surface is a closed
    /// triangulated sphere (V - E + F = 2 with E = 3F/2).
    fn check_hull(points: &[DVec3], h: &Hull) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &p in points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let tol = 1e-9 * (hi - lo).max_element();
        for f in 0..h.faces.len() {
            let (n, area) = h.face_normal_area(f);
            assert!(area > 0.0);
            let a = h.vertices[h.faces[f][0] as usize];
            for &p in points {
                assert!(
                    n.dot(p - a) <= tol,
                    "point outside face by {}",
                    n.dot(p - a)
                );
            }
        }
        if h.dim == 3 {
            assert_eq!(h.faces.len(), 2 * h.vertices.len() - 4);
            let mut edges: Vec<(u32, u32)> = Vec::new();
            for f in &h.faces {
                for e in 0..3 {
                    edges.push((f[e], f[(e + 1) % 3]));
                }
            }
            edges.sort_unstable();
            let n = edges.len();
            edges.dedup();
            assert_eq!(n, edges.len(), "an oriented edge is used twice");
            for &(a, b) in &edges {
                assert!(edges.binary_search(&(b, a)).is_ok(), "open edge");
            }
        }
        for (v, &i) in h.vertices.iter().zip(&h.indices) {
            assert_eq!(*v, points[i]);
        }
    }

    #[test]
    fn cube_lattice_gives_corners() {
        let pts = lattice(6, 0.2);
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.dim, 3);
        assert_eq!(sorted(h.vertices.clone()), corners(0.0, 1.0));
        assert_eq!(h.faces.len(), 12);
    }

    #[test]
    fn rotated_offset_lattice_gives_corners() {
        let r = DMat3::from_euler(glam::EulerRot::ZYX, 0.3, -0.7, 1.1);
        let t = DVec3::new(1e5, -3e4, 2e5);
        let pts: Vec<DVec3> = lattice(9, 0.125).iter().map(|&p| r * p + t).collect();
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.vertices.len(), 8);
    }

    #[test]
    fn random_points_are_inside_every_face() {
        let mut rng = Rng::new(7);
        for n in [5, 50, 2000] {
            let pts: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(rng.next_f64(), rng.next_f64() * 3.0, rng.next_f64() - 2.0))
                .collect();
            let h = convex_hull(&pts);
            check_hull(&pts, &h);
            assert_eq!(h.dim, 3);
        }
    }

    #[test]
    fn points_on_a_sphere_are_all_vertices() {
        let mut rng = Rng::new(3);
        let pts: Vec<DVec3> = (0..500)
            .map(|_| {
                let z = 2.0 * rng.next_f64() - 1.0;
                let a = std::f64::consts::TAU * rng.next_f64();
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * a.cos(), r * a.sin(), z)
            })
            .collect();
        let h = convex_hull(&pts);
        check_hull(&pts, &h);
        assert_eq!(h.vertices.len(), 500);
    }

    #[test]
    fn round_off_below_tolerance_is_flat() {
        // A square lattice whose points are off its plane by round-off only.
        let mut rng = Rng::new(5);
        let pts: Vec<DVec3> = (0..100)
            .map(|i| {
                let z = 1e-14 * (rng.next_f64() - 0.5);
                DVec3::new((i % 10) as f64, (i / 10) as f64, z) + DVec3::splat(100.0)
            })
            .collect();
        let h = convex_hull(&pts);
        assert_eq!((h.dim, h.vertices.len()), (2, 4));
        check_hull(&pts, &h);
    }

    #[test]
    fn deterministic_and_order_independent_vertex_set() {
        let mut rng = Rng::new(11);
        let mut pts: Vec<DVec3> = (0..3000)
            .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
            .collect();
        pts.extend(lattice(5, 0.25));
        let a = convex_hull(&pts);
        assert_eq!(a, convex_hull(&pts));
        let mut rev = pts.clone();
        rev.reverse();
        assert_eq!(sorted(a.vertices), sorted(convex_hull(&rev).vertices));
    }

    #[test]
    fn degenerate_inputs() {
        assert!(hull_points(&[]).is_empty());
        let p = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(hull_points(&[p]), vec![p]);
        assert_eq!(hull_points(&[p, p, p]), vec![p]);
        assert_eq!(hull_points(&[p, DVec3::NAN, p]), vec![p]);
        // Collinear with duplicates: the two ends.
        let line: Vec<DVec3> = (0..20)
            .map(|i| p + DVec3::new(1.0, -2.0, 0.5) * ((i % 7) as f64))
            .collect();
        let h = convex_hull(&line);
        assert_eq!(h.dim, 1);
        assert_eq!(
            sorted(h.vertices),
            sorted(vec![p, p + DVec3::new(6.0, -12.0, 3.0)])
        );
        // A tilted square lattice: its four corners, and a closed two-sided surface.
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.2, 0.9, -0.4);
        let sq: Vec<DVec3> = (0..49)
            .map(|i| r * DVec3::new((i % 7) as f64, (i / 7) as f64, 0.0) + p)
            .chain([r * DVec3::new(3.0, 3.0, 0.0) + p; 3])
            .collect();
        let h = convex_hull(&sq);
        check_hull(&sq, &h);
        assert_eq!(h.dim, 2);
        assert_eq!(h.vertices.len(), 4);
        assert_eq!(h.faces.len(), 4);
        // A triangle and a tetrahedron.
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(convex_hull(&tri).vertices.len(), 3);
        let tet = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let h = convex_hull(&tet);
        check_hull(&tet, &h);
        assert_eq!((h.vertices.len(), h.faces.len()), (4, 4));
    }

    /// The ray from the centre in any direction leaves through a face that the direction
    /// map lists for that direction.
    #[test]
    fn direction_map_lists_the_exit_face() {
        let mut rng = Rng::new(5);
        for n in [6usize, 20, 100, 400] {
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    let d = DVec3::new(
                        rng.next_f64() - 0.5,
                        rng.next_f64() * 3.0 - 1.5,
                        rng.next_f64() - 0.5,
                    );
                    d.normalize() * (1.0 + rng.next_f64())
                })
                .collect();
            let h = convex_hull(&pts);
            let c = h.vertices.iter().copied().sum::<DVec3>() / h.vertices.len() as f64;
            let map = DirMap::new(c, h.faces.iter().map(|f| f.map(|i| h.vertices[i as usize])));
            for _ in 0..5000 {
                let d = DVec3::new(
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                );
                // The exit face: the first face plane the ray meets.
                let mut exit = (f64::INFINITY, 0);
                for (k, f) in h.faces.iter().enumerate() {
                    let [a, b, e] = f.map(|i| h.vertices[i as usize]);
                    let nrm = (b - a).cross(e - a);
                    if nrm.dot(d) > 0.0 {
                        let t = nrm.dot(a - c) / nrm.dot(d);
                        if t < exit.0 {
                            exit = (t, k as u32);
                        }
                    }
                }
                assert!(map.faces(d).contains(&exit.1), "n {n}, direction {d}");
            }
        }
    }

    /// Cell centres and cell-face centres of a voxelised ball, plus points on its sphere:
    /// the many coplanar and collinear ties of the pipeline's inputs. The hull of the returned
    /// vertices is the same polytope (up to the tolerance).
    #[test]
    fn lattice_ball_with_surface_points() {
        let mut rng = Rng::new(17);
        let h = 0.1;
        let inside = |i: i32, j: i32, k: i32| (i * i + j * j + k * k) as f64 * h * h <= 1.0;
        let mut pts = Vec::new();
        for i in -11..=11 {
            for j in -11..=11 {
                for k in -11..=11 {
                    if !inside(i, j, k) {
                        continue;
                    }
                    let p = DVec3::new(i as f64, j as f64, k as f64) * h;
                    pts.push(p);
                    if !inside(i + 1, j, k) {
                        pts.push(p + DVec3::X * (0.5 * h));
                    }
                    if !inside(i, j, k - 1) {
                        pts.push(p - DVec3::Z * (0.5 * h));
                    }
                }
            }
        }
        for _ in 0..300 {
            let d = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            if d.z > 0.0 {
                pts.push(d.normalize() * 1.02);
            }
        }
        let hull = convex_hull(&pts);
        check_hull(&pts, &hull);
        assert_eq!(hull.dim, 3);
        // Hulling the vertices again keeps their hull: it may only drop vertices within the
        // tolerance of the others' hull (which ones depends on the order points are added).
        let again = convex_hull(&hull.vertices);
        check_hull(&hull.vertices, &again);
        assert!(again.vertices.iter().all(|v| hull.vertices.contains(v)));
        assert!(again.vertices.len() + 4 >= hull.vertices.len());
        assert_eq!(hull, convex_hull(&pts));
    }
}
