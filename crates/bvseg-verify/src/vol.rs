//! The volumes' own inside tests and distances, by the schema's formulas.
use glam::DVec3;

use crate::Volume;

/// A volume with what the tests need precomputed: the frame as rows, the box around it.
pub(crate) struct Vol {
    obb: bool,
    pub(crate) center: DVec3,
    pub(crate) rows: [DVec3; 3],
    radii: [f64; 3],
    /// Radius of a sphere about the centre holding the volume (with room for the slack).
    rmax: f64,
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
}

/// Slack of the inside test on the normalised coordinates, as in the schema.
const SLACK: f64 = 1e-9;

impl Vol {
    pub(crate) fn new(v: &Volume) -> Self {
        let (center, axes, radii) = v.frame();
        let center = DVec3::from_array(center);
        let rows = axes.map(DVec3::from_array);
        let obb = v.is_obb();
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
            obb,
            center,
            rows,
            radii,
            rmax: if obb { r.length() } else { r.max_element() } * 1.000_001,
            lo: center - half,
            hi: center + half,
        }
    }

    /// Coordinates in the volume's frame (not normalised).
    #[inline]
    fn frame(&self, p: DVec3) -> [f64; 3] {
        let d = p - self.center;
        [
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        ]
    }

    #[inline]
    pub(crate) fn contains(&self, p: DVec3) -> bool {
        let y = self.frame(p);
        let t = [
            y[0] / self.radii[0],
            y[1] / self.radii[1],
            y[2] / self.radii[2],
        ];
        if self.obb {
            t.iter().all(|x| x.abs() <= 1.0 + SLACK)
        } else {
            t[0] * t[0] + t[1] * t[1] + t[2] * t[2] <= 1.0 + SLACK
        }
    }

    /// Whether `p` is inside the volume by more than rounding (`gauge < 1 - 1e-7`): such a
    /// point of another volume's boundary is not on the union's boundary.
    pub(crate) fn strictly_inside(&self, p: DVec3) -> bool {
        let y = self.frame(p);
        let t = [0, 1, 2].map(|j| y[j] / self.radii[j]);
        let g = if self.obb {
            t.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        } else {
            (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()
        };
        g < 1.0 - 1e-7
    }

    /// The boundary's area (Knud Thomsen's formula for the ellipsoid, within 1.1 %).
    pub(crate) fn area(&self) -> f64 {
        let [a, b, c] = self.radii;
        if self.obb {
            8.0 * (a * b + b * c + a * c)
        } else {
            let p = 1.6075;
            4.0 * std::f64::consts::PI
                * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0).powf(1.0 / p)
        }
    }

    /// A point of the boundary from three numbers in `[0, 1)`: on a box, a face chosen by
    /// area and a uniform point of it; on an ellipsoid, the image of a uniform point of the
    /// unit sphere.
    pub(crate) fn boundary_point(&self, r: [f64; 3]) -> DVec3 {
        let [a, b, c] = self.radii;
        let local = if self.obb {
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
            let z = 2.0 * r[0] - 1.0;
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * r[1];
            [rho * phi.cos() * a, rho * phi.sin() * b, z * c]
        };
        // Back to the world: the rows are the axes.
        self.center + self.rows[0] * local[0] + self.rows[1] * local[1] + self.rows[2] * local[2]
    }

    /// Euclidean distance from `p` to the volume (0 inside, with the slack).
    pub(crate) fn distance(&self, p: DVec3) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        let y = self.frame(p);
        let r = self.radii;
        if self.obb {
            let e = DVec3::new(
                (y[0].abs() - r[0]).max(0.0),
                (y[1].abs() - r[1]).max(0.0),
                (y[2].abs() - r[2]).max(0.0),
            );
            return e.length();
        }
        // Closest point x_j = r_j² y_j / (r_j² + λ), where λ > 0 solves
        // Σ (r_j y_j / (r_j² + λ))² = 1; the left side falls with λ, so bisect.
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
    use crate::test_support::{obb, SplitMix};
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
        let v = Vol::new(&ellipsoid(
            DVec3::new(0.2, -0.1, 0.3),
            DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
            DVec3::new(1.5, 0.7, 0.3),
        ));
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
                let rows = v.rows;
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
        let v = Vol::new(&obb(c, half, rot));
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
        let vols: Vec<Vol> = (0..30)
            .map(|i| {
                let axes = DMat3::from_euler(glam::EulerRot::XYZ, r() * 3.0, r() * 3.0, r() * 3.0);
                let center = DVec3::new(r(), r(), r()) * 5.0;
                let radii = DVec3::new(r().abs(), r().abs(), r().abs()) * 2.0 + 0.01;
                Vol::new(&if i % 2 == 0 {
                    obb(center, radii, axes)
                } else {
                    ellipsoid(center, axes, radii)
                })
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
}
