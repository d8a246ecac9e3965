//! The volumes' own inside tests, distances, boxes and boundary samples, by the schema's
//! formulas (`shared/tools/README.md`, schema 2): every shape is convex, and every inside
//! test allows the schema's slack of 1e-9 (on the normalised coordinates of an ellipsoid or
//! a box, on distance over radius for a sphere, a capsule or a cylinder, on a hull's plane
//! offsets relative to its size).
use glam::DVec3;

use crate::hull::convex_hull;
use crate::protrusion::triangle_distance_squared;
use crate::Volume;

/// A volume with what the tests need precomputed: its shape in its own frame, a sphere and
/// an axis-aligned box that hold it.
pub(crate) struct Vol {
    shape: Shape,
    /// A point of the volume: the centre, or the mean of a hull's vertices.
    pub(crate) center: DVec3,
    /// Radius of a sphere about [`Self::center`] holding the volume.
    rmax: f64,
    /// The box around the volume (with room for the slack).
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
}

enum Shape {
    /// An ellipsoid (`obb: false`) or a box, its frame as rows.
    Frame {
        obb: bool,
        rows: [DVec3; 3],
        radii: [f64; 3],
    },
    Sphere {
        radius: f64,
    },
    /// A capsule or (`capped: true`) a cylinder about `axis` (unit), with `u`, `v` completing
    /// the frame.
    Round {
        capped: bool,
        axis: DVec3,
        u: DVec3,
        v: DVec3,
        half: f64,
        radius: f64,
    },
    Hull(Box<HullShape>),
}

/// A convex hull: its facets' planes and triangles.
struct HullShape {
    /// Unit outward normal `n` and offset `d`: inside is `n·(x − center) ≤ d` for all.
    planes: Vec<(DVec3, f64)>,
    /// Boundary triangles, in the world.
    triangles: Vec<[DVec3; 3]>,
    /// Running sums of the triangles' areas (the last is the area).
    cumulative_area: Vec<f64>,
    /// The hull's size: the largest coordinate difference of a vertex from the centre.
    size: f64,
}

/// Slack of the inside test on the normalised coordinates, as in the schema.
const SLACK: f64 = 1e-9;

/// A point whose gauge is below `1 - INNER` is inside a volume by more than rounding.
const INNER: f64 = 1e-7;

/// A unit vector orthogonal to `w` (unit), and a second completing a right-handed frame.
fn complete_frame(w: DVec3) -> (DVec3, DVec3) {
    let t = if w.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = w.cross(t).normalize();
    (u, w.cross(u))
}

impl Vol {
    /// The volume's shape, precomputed; its fields are assumed checked (finite, positive
    /// radii, unit axes).
    ///
    /// # Errors
    ///
    /// A one-line message when a hull has fewer than 4 points or they span no volume.
    pub(crate) fn new(v: &Volume) -> Result<Self, String> {
        match v {
            Volume::Ellipsoid {
                center,
                axes,
                radii,
            } => Ok(Self::frame(*center, *axes, *radii, false)),
            Volume::Obb {
                center,
                axes,
                half_extents,
            } => Ok(Self::frame(*center, *axes, *half_extents, true)),
            Volume::Sphere { center, radius } => {
                let center = DVec3::from_array(*center);
                let half = DVec3::splat(radius * (1.0 + 2.0 * SLACK) + 1e-300);
                Ok(Self {
                    shape: Shape::Sphere { radius: *radius },
                    center,
                    rmax: *radius,
                    lo: center - half,
                    hi: center + half,
                })
            }
            Volume::Capsule {
                center,
                axis,
                half_length,
                radius,
            } => Ok(Self::round(*center, *axis, *half_length, *radius, false)),
            Volume::Cylinder {
                center,
                axis,
                half_length,
                radius,
            } => Ok(Self::round(*center, *axis, *half_length, *radius, true)),
            Volume::Hull { points } => Self::hull(points),
        }
    }

    fn frame(center: [f64; 3], axes: [[f64; 3]; 3], radii: [f64; 3], obb: bool) -> Self {
        let center = DVec3::from_array(center);
        let rows = axes.map(DVec3::from_array);
        // World half-width along axis d: the support of the shape in direction e_d.
        let mut half = DVec3::ZERO;
        for d in 0..3 {
            let comp = DVec3::new(
                rows[0][d] * radii[0],
                rows[1][d] * radii[1],
                rows[2][d] * radii[2],
            );
            half[d] = if obb {
                comp.abs().element_sum()
            } else {
                comp.length()
            };
        }
        // The slack makes the shape slightly larger than its radii.
        let half = half * (1.0 + 2.0 * SLACK) + DVec3::splat(1e-300);
        let r = DVec3::from_array(radii);
        Self {
            shape: Shape::Frame { obb, rows, radii },
            center,
            rmax: if obb { r.length() } else { r.max_element() } * 1.000_001,
            lo: center - half,
            hi: center + half,
        }
    }

    fn round(center: [f64; 3], axis: [f64; 3], half: f64, radius: f64, capped: bool) -> Self {
        let center = DVec3::from_array(center);
        // The schema allows |axis| within 1e-6 of 1; the solid is about its direction.
        let axis = DVec3::from_array(axis).normalize();
        let (u, v) = complete_frame(axis);
        // Support along e_d: the segment's reach plus the disc's (capsule: the ball's).
        let disc = |d: usize| {
            if capped {
                radius * (1.0 - axis[d] * axis[d]).max(0.0).sqrt()
            } else {
                radius
            }
        };
        let h = DVec3::new(
            axis.x.abs() * half + disc(0),
            axis.y.abs() * half + disc(1),
            axis.z.abs() * half + disc(2),
        ) * (1.0 + 2.0 * SLACK)
            + DVec3::splat(1e-300);
        let rmax = if capped {
            half.hypot(radius)
        } else {
            half + radius
        } * 1.000_001;
        Self {
            shape: Shape::Round {
                capped,
                axis,
                u,
                v,
                half,
                radius,
            },
            center,
            rmax,
            lo: center - h,
            hi: center + h,
        }
    }

    fn hull(points: &[[f64; 3]]) -> Result<Self, String> {
        let pts: Vec<DVec3> = points.iter().map(|&p| DVec3::from_array(p)).collect();
        let hull = convex_hull(&pts)?;
        let mut used: Vec<usize> = hull.triangles.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        let center = used.iter().fold(DVec3::ZERO, |s, &i| s + pts[i]) / used.len() as f64;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let (mut size, mut rmax) = (0.0f64, 0.0f64);
        for &i in &used {
            let d = pts[i] - center;
            size = size.max(d.abs().max_element());
            rmax = rmax.max(d.length());
            lo = lo.min(pts[i]);
            hi = hi.max(pts[i]);
        }
        // Planes: the exact normals (rounded), offsets from the triangle's own corners.
        // Coplanar triangles share a plane; keep one of each.
        let mut planes: Vec<(DVec3, f64)> = Vec::with_capacity(hull.triangles.len());
        for (t, &n) in hull.triangles.iter().zip(&hull.normals) {
            let d = t
                .iter()
                .map(|&i| n.dot(pts[i] - center))
                .fold(f64::NEG_INFINITY, f64::max);
            let near = |&(m, e): &(DVec3, f64)| {
                (m - n).abs().max_element() <= 1e-12 && (e - d).abs() <= 1e-12 * size
            };
            match planes.iter_mut().find(|p| near(p)) {
                Some(p) => p.1 = p.1.max(d),
                None => planes.push((n, d)),
            }
        }
        let triangles: Vec<[DVec3; 3]> = hull.triangles.iter().map(|t| t.map(|i| pts[i])).collect();
        let mut cumulative_area = Vec::with_capacity(triangles.len());
        let mut area = 0.0;
        for [a, b, c] in &triangles {
            area += 0.5 * (*b - *a).cross(*c - *a).length();
            cumulative_area.push(area);
        }
        // Beyond a sharp vertex, the slack's offset planes reach a little farther than the
        // slack itself; the box is only a filter, so a generous margin.
        let margin = DVec3::splat(1e-6 * size + 1e-300);
        Ok(Self {
            shape: Shape::Hull(Box::new(HullShape {
                planes,
                triangles,
                cumulative_area,
                size,
            })),
            center,
            rmax: rmax * 1.000_001,
            lo: lo - margin,
            hi: hi + margin,
        })
    }

    /// Coordinates in a frame's volume (not normalised).
    #[inline]
    fn local(rows: &[DVec3; 3], d: DVec3) -> [f64; 3] {
        [rows[0].dot(d), rows[1].dot(d), rows[2].dot(d)]
    }

    /// The gauge of `p`: at most 1 in the volume, above 1 outside (a hull: 1 plus the
    /// largest plane offset over its size). For a capsule, distance to the segment over the
    /// radius; a cylinder, the larger of the axial and radial ratios.
    fn gauge(&self, p: DVec3) -> f64 {
        let d = p - self.center;
        match &self.shape {
            Shape::Frame { obb, rows, radii } => {
                let y = Self::local(rows, d);
                let t = [0, 1, 2].map(|j| y[j] / radii[j]);
                if *obb {
                    t.iter().fold(0.0f64, |m, x| m.max(x.abs()))
                } else {
                    (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()
                }
            }
            Shape::Sphere { radius } => d.length() / radius,
            Shape::Round {
                capped,
                axis,
                u,
                v,
                half,
                radius,
            } => {
                let (z, rho) = (axis.dot(d), u.dot(d).hypot(v.dot(d)));
                if *capped {
                    (rho / radius).max(z.abs() / half)
                } else {
                    let dz = (z.abs() - half).max(0.0);
                    rho.hypot(dz) / radius
                }
            }
            Shape::Hull(h) => 1.0 + h.offset(d) / h.size,
        }
    }

    #[inline]
    pub(crate) fn contains(&self, p: DVec3) -> bool {
        match &self.shape {
            // As the schema writes it: Σ t_j² ≤ 1 + 1e-9 (the gauge squared).
            Shape::Frame {
                obb: false,
                rows,
                radii,
            } => {
                let y = Self::local(rows, p - self.center);
                let t = [0, 1, 2].map(|j| y[j] / radii[j]);
                t[0] * t[0] + t[1] * t[1] + t[2] * t[2] <= 1.0 + SLACK
            }
            // Stops at the first plane the point is beyond.
            Shape::Hull(h) => {
                let d = p - self.center;
                let slack = SLACK * h.size;
                h.planes.iter().all(|&(n, e)| n.dot(d) - e <= slack)
            }
            _ => self.gauge(p) <= 1.0 + SLACK,
        }
    }

    /// Whether `p` is inside the volume by more than rounding (`gauge < 1 - 1e-7`): such a
    /// point of another volume's boundary is not on the union's boundary.
    pub(crate) fn strictly_inside(&self, p: DVec3) -> bool {
        self.gauge(p) < 1.0 - INNER
    }

    /// The boundary's area (Knud Thomsen's formula for the ellipsoid, within 1.1 %).
    pub(crate) fn area(&self) -> f64 {
        use std::f64::consts::PI;
        match &self.shape {
            Shape::Frame { obb, radii, .. } => {
                let [a, b, c] = *radii;
                if *obb {
                    8.0 * (a * b + b * c + a * c)
                } else {
                    let p = 1.6075;
                    4.0 * PI
                        * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0)
                            .powf(1.0 / p)
                }
            }
            Shape::Sphere { radius } => 4.0 * PI * radius * radius,
            Shape::Round {
                capped,
                half,
                radius,
                ..
            } => {
                let ends = if *capped { 2.0 } else { 4.0 };
                4.0 * PI * radius * half + ends * PI * radius * radius
            }
            Shape::Hull(h) => h.cumulative_area.last().copied().unwrap_or(0.0),
        }
    }

    /// The solid's volume (the hull's from its facets).
    #[cfg(test)]
    pub(crate) fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match &self.shape {
            Shape::Frame { obb, radii, .. } => {
                let p = radii[0] * radii[1] * radii[2];
                if *obb {
                    8.0 * p
                } else {
                    4.0 / 3.0 * PI * p
                }
            }
            Shape::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
            Shape::Round {
                capped,
                half,
                radius,
                ..
            } => {
                let side = 2.0 * PI * radius * radius * half;
                if *capped {
                    side
                } else {
                    side + 4.0 / 3.0 * PI * radius.powi(3)
                }
            }
            Shape::Hull(h) => h
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|q| q - self.center);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum(),
        }
    }

    /// A point of the boundary from three numbers in `[0, 1)`, uniform over the boundary's
    /// area when they are uniform (the ellipsoid: the image of a uniform point of the unit
    /// sphere). A box: a face chosen by area, then a point of it; a capsule or a cylinder:
    /// the side or an end chosen by area; a hull: a facet triangle chosen by area.
    pub(crate) fn boundary_point(&self, r: [f64; 3]) -> DVec3 {
        use std::f64::consts::TAU;
        // A uniform point of the unit sphere (Archimedes: z is uniform).
        let sphere = |s: f64, t: f64| {
            let z = 2.0 * s - 1.0;
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = TAU * t;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        };
        match &self.shape {
            Shape::Frame { obb, rows, radii } => {
                let [a, b, c] = *radii;
                let local = if *obb {
                    let faces = [b * c, a * c, a * b];
                    let total = 2.0 * (faces[0] + faces[1] + faces[2]);
                    let mut x = r[0] * total;
                    let mut axis = 0;
                    let mut sign = 1.0;
                    'pick: for (d, &f) in faces.iter().enumerate() {
                        for s in [1.0, -1.0] {
                            if x < f || (d == 2 && s < 0.0) {
                                axis = d;
                                sign = s;
                                break 'pick;
                            }
                            x -= f;
                        }
                    }
                    let mut t = [0.0; 3];
                    t[axis] = sign;
                    t[(axis + 1) % 3] = 2.0 * r[1] - 1.0;
                    t[(axis + 2) % 3] = 2.0 * r[2] - 1.0;
                    [t[0] * a, t[1] * b, t[2] * c]
                } else {
                    let u = sphere(r[0], r[1]);
                    [u.x * a, u.y * b, u.z * c]
                };
                // Back to the world: the rows are the axes.
                self.center + rows[0] * local[0] + rows[1] * local[1] + rows[2] * local[2]
            }
            Shape::Sphere { radius } => self.center + sphere(r[0], r[1]) * *radius,
            Shape::Round {
                capped,
                axis,
                u,
                v,
                half,
                radius,
            } => {
                let side = 4.0 * std::f64::consts::PI * radius * half;
                let total = self.area();
                let x = r[0] * total;
                let (along, across) = if x < side {
                    // The side: the rest of r[0] places the point along the axis.
                    let phi = TAU * r[1];
                    (
                        -half + 2.0 * half * (x / side),
                        (phi.cos(), phi.sin(), *radius),
                    )
                } else if *capped {
                    // A cap: a uniform point of a disc, on the end chosen by the rest of r[0].
                    let end = if (x - side) / (total - side) < 0.5 {
                        1.0
                    } else {
                        -1.0
                    };
                    let phi = TAU * r[2];
                    (end * half, (phi.cos(), phi.sin(), radius * r[1].sqrt()))
                } else {
                    // The two hemispheres make a sphere, each half shifted to its end.
                    let s = sphere(r[1], r[2]);
                    let shift = if s.z >= 0.0 { *half } else { -half };
                    return self.center
                        + *axis * shift
                        + (*u * s.x + *v * s.y + *axis * s.z) * *radius;
                };
                let (c, s, rho) = across;
                self.center + *axis * along + (*u * c + *v * s) * rho
            }
            Shape::Hull(h) => {
                let total = h.cumulative_area.last().copied().unwrap_or(0.0);
                let x = r[0] * total;
                let k = h
                    .cumulative_area
                    .partition_point(|&c| c <= x)
                    .min(h.triangles.len().saturating_sub(1));
                let [a, b, c] = h.triangles[k];
                let s = r[1].sqrt();
                a * (1.0 - s) + b * (s * (1.0 - r[2])) + c * (s * r[2])
            }
        }
    }

    /// Euclidean distance from `p` to the volume (0 inside, with the slack).
    pub(crate) fn distance(&self, p: DVec3) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        let d = p - self.center;
        match &self.shape {
            Shape::Frame { obb, rows, radii } => {
                let y = Self::local(rows, d);
                let r = *radii;
                if *obb {
                    let e = DVec3::new(
                        (y[0].abs() - r[0]).max(0.0),
                        (y[1].abs() - r[1]).max(0.0),
                        (y[2].abs() - r[2]).max(0.0),
                    );
                    return e.length();
                }
                ellipsoid_distance(y, r)
            }
            Shape::Sphere { radius } => (d.length() - radius).max(0.0),
            Shape::Round {
                capped,
                axis,
                u,
                v,
                half,
                radius,
            } => {
                let (z, rho) = (axis.dot(d), u.dot(d).hypot(v.dot(d)));
                let dz = (z.abs() - half).max(0.0);
                if *capped {
                    (rho - radius).max(0.0).hypot(dz)
                } else {
                    (rho.hypot(dz) - radius).max(0.0)
                }
            }
            // Outside a convex solid, the nearest point is on its boundary.
            Shape::Hull(h) => h
                .triangles
                .iter()
                .map(|&t| triangle_distance_squared(p, t))
                .fold(f64::INFINITY, f64::min)
                .sqrt(),
        }
    }
}

impl HullShape {
    /// The largest plane offset of `d` (relative to the centre).
    fn offset(&self, d: DVec3) -> f64 {
        self.planes
            .iter()
            .map(|&(n, e)| n.dot(d) - e)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// Distance from `y` (in the frame) to the ellipsoid of semi-axes `r`, `y` outside: the
/// closest point is `x_j = r_j² y_j / (r_j² + λ)`, where `λ > 0` solves
/// `Σ (r_j y_j / (r_j² + λ))² = 1`; the left side falls with λ, so bisect.
fn ellipsoid_distance(y: [f64; 3], r: [f64; 3]) -> f64 {
    let g = |lam: f64| -> f64 {
        (0..3)
            .map(|j| (r[j] * y[j] / (r[j] * r[j] + lam)).powi(2))
            .sum()
    };
    let ylen = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
    let (mut lo, mut hi) = (0.0f64, ylen * r.iter().fold(0.0f64, |a, &b| a.max(b)));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if g(mid) > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let lam = 0.5 * (lo + hi);
    let mut d2 = 0.0;
    for j in 0..3 {
        let x = r[j] * r[j] * y[j] / (r[j] * r[j] + lam);
        d2 += (y[j] - x) * (y[j] - x);
    }
    d2.sqrt()
}

/// For each volume, a value `>= ` its distance from `p`, exact for the nearest volumes: the
/// distance to the centre stands in for volumes that cannot be the nearest (their bounding
/// sphere is farther than a volume already measured), which keeps both bounds of the search
/// valid and skips most of the costly ellipsoid distances.
pub(crate) fn distances(p: DVec3, vols: &[Vol]) -> Vec<f64> {
    let mut out: Vec<f64> = vols.iter().map(|v| (p - v.center).length()).collect();
    let mut order: Vec<(f64, usize)> = vols
        .iter()
        .enumerate()
        .map(|(j, v)| (out[j] - v.rmax, j))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut nearest = f64::INFINITY;
    for (lower, j) in order {
        if lower > nearest {
            break;
        }
        out[j] = vols[j].distance(p);
        nearest = nearest.min(out[j]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{capsule, cylinder, hull_volume, obb, sphere, SplitMix};
    use glam::DMat3;

    fn ellipsoid(center: DVec3, rot: DMat3, radii: DVec3) -> Volume {
        Volume::Ellipsoid {
            center: center.to_array(),
            axes: [rot.x_axis, rot.y_axis, rot.z_axis].map(|a| a.to_array()),
            radii: radii.to_array(),
        }
    }

    #[test]
    fn ellipsoid_distance_matches_a_dense_search() {
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let v = Vol::new(&ellipsoid(
            DVec3::new(0.2, -0.1, 0.3),
            rot,
            DVec3::new(1.5, 0.7, 0.3),
        ))
        .unwrap();
        let p = DVec3::new(2.0, 1.0, -1.0);
        let d = v.distance(p);
        let mut best = f64::INFINITY;
        let n = 800;
        for i in 0..=n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * j as f64 / n as f64;
                let u = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                let local = u * DVec3::new(1.5, 0.7, 0.3);
                let rows = [rot.x_axis, rot.y_axis, rot.z_axis];
                let w = v.center + rows[0] * local.x + rows[1] * local.y + rows[2] * local.z;
                best = best.min((w - p).length());
            }
        }
        assert!(d <= best + 1e-12 && best - d < 2e-3, "{d} vs {best}");
    }

    #[test]
    fn obb_inside_test_and_distance_follow_the_schema() {
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let c = DVec3::new(1.0, 2.0, 3.0);
        let half = DVec3::new(1.0, 0.5, 0.25);
        let v = Vol::new(&obb(c, half, rot)).unwrap();
        // Rows of the file are the frame's axes: the corner along +u, +v, +w.
        let corner = c + rot.x_axis * half.x + rot.y_axis * half.y + rot.z_axis * half.z;
        assert!(v.contains(corner));
        assert!(!v.contains(c + (corner - c) * (1.0 + 1e-6)));
        let out = c + rot.x_axis * (half.x + 0.5);
        assert!((v.distance(out) - 0.5).abs() < 1e-12);
        // The box around it holds it.
        assert!(corner.cmpge(v.lo).all() && corner.cmple(v.hi).all());
    }

    #[test]
    fn pruned_distances_bound_the_exact_ones_and_keep_the_nearest() {
        let mut rng = SplitMix::new(3);
        let mut r = || rng.signed();
        let vols: Vec<Vol> = (0..36)
            .map(|i| {
                let axes = DMat3::from_euler(glam::EulerRot::XYZ, r() * 3.0, r() * 3.0, r() * 3.0);
                let center = DVec3::new(r(), r(), r()) * 5.0;
                let radii = DVec3::new(r().abs(), r().abs(), r().abs()) * 2.0 + 0.01;
                Vol::new(&match i % 6 {
                    0 => obb(center, radii, axes),
                    1 => ellipsoid(center, axes, radii),
                    2 => sphere(center, radii.x),
                    3 => capsule(center, axes.x_axis, radii.y, radii.x),
                    4 => cylinder(center, axes.y_axis, radii.y, radii.z),
                    _ => hull_volume(
                        &(0..6)
                            .map(|_| center + DVec3::new(r(), r(), r()) * radii)
                            .collect::<Vec<_>>(),
                    ),
                })
                .unwrap()
            })
            .collect();
        for _ in 0..500 {
            let p = DVec3::new(r(), r(), r()) * 8.0;
            let fast = distances(p, &vols);
            let exact: Vec<f64> = vols.iter().map(|v| v.distance(p)).collect();
            let min_exact = exact.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let min_fast = fast.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            assert_eq!(min_fast, min_exact);
            for (f, e) in fast.iter().zip(&exact) {
                assert!(f >= e);
            }
        }
    }

    /// Brute-force distance from `p` to the segment `a`..`b`, by sampling it finely.
    fn segment_distance_sampled(p: DVec3, a: DVec3, b: DVec3) -> f64 {
        let n = 20_000;
        (0..=n)
            .map(|i| (a + (b - a) * (i as f64 / n as f64) - p).length())
            .fold(f64::INFINITY, f64::min)
    }

    /// Every plane through three of the points with all of them on one side (within
    /// rounding): the hull's facets, found the slow way.
    fn brute_facets(pts: &[DVec3]) -> Vec<(DVec3, f64)> {
        let mut out = Vec::new();
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                for k in j + 1..pts.len() {
                    let n = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
                    if n.length() < 1e-9 {
                        continue;
                    }
                    let n = n.normalize();
                    let off: Vec<f64> = pts.iter().map(|q| n.dot(*q - pts[i])).collect();
                    if off.iter().all(|&o| o <= 1e-12) {
                        out.push((n, n.dot(pts[i])));
                    } else if off.iter().all(|&o| o >= -1e-12) {
                        out.push((-n, -n.dot(pts[i])));
                    }
                }
            }
        }
        out
    }

    fn random_hull(rng: &mut SplitMix, n: usize, c: DVec3) -> Vec<DVec3> {
        (0..n)
            .map(|_| c + DVec3::new(rng.signed(), 0.5 * rng.signed(), 0.8 * rng.signed()))
            .collect()
    }

    #[test]
    fn new_shapes_inside_tests_match_their_definitions() {
        let mut rng = SplitMix::new(21);
        let c = DVec3::new(0.3, -0.2, 1.1);
        let w = DVec3::new(0.2, -0.5, 0.8).normalize();
        let (h, rad) = (0.7, 0.4);
        let caps = Vol::new(&capsule(c, w, h, rad)).unwrap();
        let cyl = Vol::new(&cylinder(c, w, h, rad)).unwrap();
        let ball = Vol::new(&sphere(c, rad)).unwrap();
        let pts = random_hull(&mut rng, 12, c);
        let hull = Vol::new(&hull_volume(&pts)).unwrap();
        let facets = brute_facets(&pts);
        assert!(facets.len() >= 4);
        let (mut inside, mut total) = ([0; 4], 0);
        for _ in 0..4000 {
            let p = c + DVec3::new(rng.signed(), rng.signed(), rng.signed()) * 0.9;
            // Points within 1e-6 of a boundary could go either way in the sampled distance.
            let ds = segment_distance_sampled(p, c - w * h, c + w * h);
            if (ds - rad).abs() > 1e-6 {
                assert_eq!(caps.contains(p), ds <= rad, "capsule {p}");
                inside[0] += caps.contains(p) as usize;
            }
            let z = w.dot(p - c);
            let radial = (p - c - w * z).length();
            if (z.abs() - h).abs() > 1e-9 && (radial - rad).abs() > 1e-9 {
                assert_eq!(
                    cyl.contains(p),
                    z.abs() <= h && radial <= rad,
                    "cylinder {p}"
                );
                inside[1] += cyl.contains(p) as usize;
            }
            if ((p - c).length() - rad).abs() > 1e-9 {
                assert_eq!(ball.contains(p), (p - c).length() <= rad, "sphere {p}");
                inside[2] += ball.contains(p) as usize;
            }
            let off = facets
                .iter()
                .map(|&(n, d)| n.dot(p) - d)
                .fold(f64::NEG_INFINITY, f64::max);
            if off.abs() > 1e-9 {
                assert_eq!(hull.contains(p), off < 0.0, "hull {p}");
                inside[3] += hull.contains(p) as usize;
            }
            total += 1;
        }
        // Both answers seen often for every shape.
        assert!(
            inside.iter().all(|&k| k > 100 && k < total - 100),
            "{inside:?}"
        );
        // The slack: 1e-9 on distance over radius, on the axial ratio, on plane offsets
        // over the hull's size.
        let u = complete_frame(w).0;
        for (v, on, normal, scale) in [
            (&caps, c + w * h + u * rad, u, rad),
            (&caps, c + w * (h + rad), w, rad),
            (&caps, c - w * 0.3 - u * rad, -u, rad),
            (&cyl, c + w * h + u * 0.1, w, h),
            (&cyl, c - w * 0.2 + u * rad, u, rad),
            (&ball, c + u * rad, u, rad),
        ] {
            let at = |e: f64| on + normal * (e * scale);
            assert!(v.contains(at(0.0)) && v.contains(at(0.5e-9)), "{on}");
            assert!(!v.contains(at(2e-9)), "{on}");
            assert!(!v.strictly_inside(at(0.0)) && v.strictly_inside(at(-1e-6)));
        }
        let cube = Vol::new(&hull_volume(
            &(0..8)
                .map(|i| {
                    DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64) * 2.0
                        - DVec3::ONE
                        + c
                })
                .collect::<Vec<_>>(),
        ))
        .unwrap();
        // Size 1: the largest coordinate difference of a corner from the centre.
        for (e, want) in [(0.0, true), (0.5e-9, true), (2e-9, false)] {
            assert_eq!(
                cube.contains(c + DVec3::new(1.0 + e, 0.3, -0.2)),
                want,
                "{e}"
            );
        }
        assert!(cube.strictly_inside(c) && !cube.strictly_inside(c + DVec3::X));
    }

    #[test]
    fn new_shapes_distances_match_a_dense_search() {
        let mut rng = SplitMix::new(5);
        let c = DVec3::new(-0.4, 0.9, 0.2);
        let w = DVec3::new(-0.3, 0.4, 0.6).normalize();
        let pts = random_hull(&mut rng, 20, c);
        let shapes = [
            sphere(c, 0.6),
            capsule(c, w, 0.8, 0.3),
            capsule(c, w, 0.0, 0.3),
            cylinder(c, w, 0.5, 0.7),
            hull_volume(&pts),
        ];
        for shape in &shapes {
            let v = Vol::new(shape).unwrap();
            // A dense set of boundary points (also a check that they are on the boundary).
            let n = 64;
            let mut surface = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let r = [i, j, k].map(|x| (x as f64 + 0.5) / n as f64);
                        let q = v.boundary_point(r);
                        assert!(v.contains(q) && !v.strictly_inside(q), "{shape:?}: {q}");
                        surface.push(q);
                    }
                }
            }
            for _ in 0..30 {
                let p = c + DVec3::new(rng.signed(), rng.signed(), rng.signed()) * 2.5;
                let d = v.distance(p);
                if v.contains(p) {
                    assert_eq!(d, 0.0);
                    continue;
                }
                let best = surface
                    .iter()
                    .map(|q| (*q - p).length())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    d <= best + 1e-12 && best - d < 0.03,
                    "{shape:?}: {d} vs {best}"
                );
            }
        }
    }

    #[test]
    fn new_shapes_boxes_areas_volumes_and_sampling() {
        use std::f64::consts::PI;
        let c = DVec3::new(1.0, -2.0, 0.5);
        let w = DVec3::new(1.0, 2.0, 2.0) / 3.0;
        let (h, r) = (0.75, 0.5);
        let mut rng = SplitMix::new(9);
        for (shape, area, volume) in [
            (sphere(c, r), 4.0 * PI * r * r, 4.0 / 3.0 * PI * r.powi(3)),
            (
                capsule(c, w, h, r),
                4.0 * PI * r * h + 4.0 * PI * r * r,
                2.0 * PI * r * r * h + 4.0 / 3.0 * PI * r.powi(3),
            ),
            (
                cylinder(c, w, h, r),
                4.0 * PI * r * h + 2.0 * PI * r * r,
                2.0 * PI * r * r * h,
            ),
        ] {
            let v = Vol::new(&shape).unwrap();
            assert!((v.area() - area).abs() < 1e-12 && (v.volume() - volume).abs() < 1e-12);
            // The box holds the solid, and is tight: boundary points reach each side.
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let mut on_side = 0usize;
            let n = 40_000;
            for _ in 0..n {
                let q = v.boundary_point([rng.next_f64(), rng.next_f64(), rng.next_f64()]);
                assert!(q.cmpge(v.lo).all() && q.cmple(v.hi).all());
                lo = lo.min(q);
                hi = hi.max(q);
                let z = w.dot(q - c);
                on_side +=
                    (z.abs() < h - 1e-9 && ((q - c - w * z).length() - r).abs() < 1e-9) as usize;
            }
            assert!(((lo - v.lo).max_element()).abs() < 0.02, "{shape:?}");
            assert!(((hi - v.hi).min_element()).abs() < 0.02, "{shape:?}");
            // Sampled by area: the side's share (capsule, cylinder; a ball's equator band
            // is no side).
            if !matches!(shape, Volume::Sphere { .. }) {
                let want = 4.0 * PI * r * h / area;
                let got = on_side as f64 / n as f64;
                assert!((got - want).abs() < 0.01, "{shape:?}: {got} vs {want}");
            }
        }
        // A hull: the unit cube's corners and points inside it.
        let mut pts: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        pts.extend((0..20).map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())));
        let v = Vol::new(&hull_volume(&pts)).unwrap();
        assert!((v.area() - 6.0).abs() < 1e-12 && (v.volume() - 1.0).abs() < 1e-12);
        assert!((v.center - DVec3::splat(0.5)).length() < 1e-15);
        assert!(v.lo.cmple(DVec3::ZERO).all() && v.hi.cmpge(DVec3::ONE).all());
        assert!((v.hi - DVec3::ONE).max_element() < 1e-5);
        let Shape::Hull(h) = &v.shape else {
            unreachable!()
        };
        assert_eq!(h.planes.len(), 6, "coplanar triangles share a plane");
        // Uniform by area over the facets: each face gets a sixth.
        let mut faces = [0usize; 6];
        let n = 60_000;
        for _ in 0..n {
            let q = v.boundary_point([rng.next_f64(), rng.next_f64(), rng.next_f64()]);
            let d = (0..3)
                .find(|&d| q[d].abs() < 1e-12 || (q[d] - 1.0).abs() < 1e-12)
                .map(|d| 2 * d + (q[d] > 0.5) as usize);
            faces[d.unwrap_or_else(|| panic!("{q} on no face"))] += 1;
        }
        for f in faces {
            assert!((f as f64 / n as f64 - 1.0 / 6.0).abs() < 0.01, "{faces:?}");
        }
        // A flat hull is refused.
        let flat: Vec<DVec3> = pts.iter().map(|p| DVec3::new(p.x, p.y, 0.0)).collect();
        assert!(Vol::new(&hull_volume(&flat)).is_err());
    }
}
