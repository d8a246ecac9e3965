//! The convex polyhedron of a hull volume, in the volume's local coordinates.
use crate::math;
use glam::DVec3;

use crate::bounding::hull::convex_hull;

/// A convex polyhedron around the origin: its vertices, outward triangles and face planes,
/// all in the local coordinates of its [`crate::BoundingVolume`] (world = centre + scale *
/// local). The origin lies strictly inside, so every plane offset is positive and the gauge
/// is `max_f n_f . t / d_f`.
#[derive(Debug, Clone, PartialEq)]
pub struct Polytope {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// `(n, d)` per triangle: unit outward normal and offset, `n . t <= d` inside.
    planes: Vec<(DVec3, f64)>,
}

impl Polytope {
    /// The convex hull of `points` (local coordinates, around the origin), or `None` when it
    /// is flat or does not hold the origin strictly inside.
    pub fn new(points: &[DVec3]) -> Option<Self> {
        let hull = convex_hull(points);
        if hull.dim != 3 || hull.faces.len() < 4 {
            return None;
        }
        let size = hull
            .vertices
            .iter()
            .map(|v| v.length())
            .fold(0.0f64, math::max);
        let mut planes = Vec::with_capacity(hull.faces.len());
        for f in 0..hull.faces.len() {
            let (n, area) = hull.face_normal_area(f);
            // A sliver of nearly collinear corners bounds nothing its neighbours do not, and
            // its normal is noise: it takes no plane.
            if area <= 1e-12 * size * size {
                continue;
            }
            let d = n.dot(hull.vertices[hull.faces[f][0] as usize]);
            if d.is_nan() || d <= 1e-9 * size {
                return None;
            }
            planes.push((n, d));
        }
        if planes.len() < 4 {
            return None;
        }
        Some(Self {
            vertices: hull.vertices,
            triangles: hull.faces,
            planes,
        })
    }

    /// The octahedron `|x| + |y| + |z| <= sqrt(3)`, whose faces touch the unit ball: the
    /// fallback of [`Polytope::around_unit_ball`], built without a hull so that it cannot
    /// fail.
    pub(super) fn octahedron_around_unit_ball() -> Self {
        let r = 3f64.sqrt();
        let vertices = vec![
            DVec3::X * r,
            -DVec3::X * r,
            DVec3::Y * r,
            -DVec3::Y * r,
            DVec3::Z * r,
            -DVec3::Z * r,
        ];
        // Each octant's face, wound outward (x, y, z in the octant's signs).
        let mut triangles = Vec::with_capacity(8);
        let mut planes = Vec::with_capacity(8);
        for s in 0..8u32 {
            let (x, y, z) = (s & 1, 2 + ((s >> 1) & 1), 4 + ((s >> 2) & 1));
            let sign = |i: u32| if i % 2 == 0 { 1.0 } else { -1.0 };
            let n = DVec3::new(sign(x), sign(y), sign(z)) / r;
            // (x, y, z) is counter-clockwise seen from outside when the octant is even.
            let odd = (s & 1) ^ ((s >> 1) & 1) ^ ((s >> 2) & 1);
            triangles.push(if odd == 0 { [x, y, z] } else { [x, z, y] });
            planes.push((n, 1.0));
        }
        Self {
            vertices,
            triangles,
            planes,
        }
    }

    /// The vertices.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// Outward triangles over [`Polytope::vertices`].
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Face planes `(n, d)`: unit outward normal, positive offset.
    pub fn planes(&self) -> &[(DVec3, f64)] {
        &self.planes
    }

    /// The gauge of local point `t`: <= 1 inside, scaling the polytope by `s` divides it by `s`.
    #[inline]
    pub fn gauge(&self, t: DVec3) -> f64 {
        self.planes
            .iter()
            .map(|&(n, d)| n.dot(t) / d)
            .fold(f64::NEG_INFINITY, math::max)
    }

    /// The volume (the origin is inside, so every tetrahedron to it counts positively).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// The smallest face offset: how far the nearest face is from the origin.
    pub fn min_offset(&self) -> f64 {
        self.planes
            .iter()
            .map(|p| p.1)
            .fold(f64::INFINITY, math::min)
    }

    /// The range of `k` with `a + k b` inside, or `None`.
    pub fn interval(&self, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
        self.planes_along(b).interval(a)
    }

    /// The face planes prepared for lines along `b`: what [`Polytope::interval`] needs of
    /// them, for many lines at once.
    pub(crate) fn planes_along(&self, b: DVec3) -> PlanesAlong {
        PlanesAlong(self.planes.iter().map(|&(n, d)| (n, d, n.dot(b))).collect())
    }
}

/// A polytope's face planes prepared for many lines along one direction `b`: each plane's
/// normal, offset, and the normal's component along `b`, computed once for all the lines.
#[derive(Debug, Clone)]
pub(crate) struct PlanesAlong(Vec<(DVec3, f64, f64)>);

impl PlanesAlong {
    /// The range of `k` with `a + k b` inside, or `None`.
    #[inline]
    pub(crate) fn interval(&self, a: DVec3) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for &(n, d, nb) in &self.0 {
            let na = n.dot(a);
            if nb.abs() < 1e-300 {
                if na > d {
                    return None;
                }
            } else {
                let k = (d - na) / nb;
                if nb > 0.0 {
                    hi = math::min(hi, k);
                } else {
                    lo = math::max(lo, k);
                }
                // The range only narrows: once empty, it stays so.
                if lo > hi {
                    return None;
                }
            }
        }
        Some((lo, hi))
    }
}
