//! Minimum-volume enclosing ellipsoid (MVEE).
//!
//! The ellipsoid is fitted to the convex hull's vertices (the only points that can touch it),
//! in Khachiyan's lifted form: the points `(z, 1)` in one more dimension, whose smallest
//! centred ellipsoid cuts the MVEE out of the hyperplane of the last coordinate 1. Its dual
//! is a weighting `u` of the points, and the weights certify the accuracy: once every point
//! has `omega_i = q_i^T M(u)^-1 q_i <= (d + 1)(1 + eps)`, the volume is within
//! `(1 + eps)^((d+1)/2)` of the minimum.
//!
//! Two solvers share the work. Todd–Yildirim (Khachiyan's coordinate ascent on `u` with away
//! and drop steps, from the Kumar–Yildirim core set) is robust and certifies, but it
//! equalises many similar weights slowly, which is the usual case here: a blob's hull
//! vertices all lie near the optimal ellipsoid. So a primal log-barrier method (Newton steps
//! on the `(d + 1)(d + 2) / 2` entries of the ellipsoid's matrix, whatever the number of
//! points) first brings the duality gap near the target, and Todd–Yildirim steps then finish
//! and certify from its dual weights, over all the points. Between two centrings the barrier
//! drops the points that provably cannot support the optimum (Harman and Pronzato's bound),
//! usually most of them, so that only the first centring works on every point. Points are
//! first put in their principal frame and scaled to a unit box, which makes both blind to
//! position, scale and anisotropy (the MVEE is affine-equivariant).
//!
//! Flat sets (all coplanar or collinear points, one point) are fitted in their own subspace
//! and padded to `min_radius` across it; sets that are merely thinner than `min_radius` are
//! fitted both ways and the smaller result is kept.
//!
//! Here the frame and the subspace fits; Todd–Yildirim in `todd_yildirim.rs`, the barrier
//! in `barrier.rs`, the small dense algebra both use in `dense.rs`.
// Small dense matrix code (N <= 4, K <= 10) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

mod barrier;
mod todd_yildirim;

use crate::math;
use glam::{DMat3, DVec3};

use super::hull::convex_hull;
use crate::linalg::sym_eigen;
use crate::volume::{BoundingVolume, Shape};
use todd_yildirim::WaTy;

/// Minimum-volume enclosing ellipsoid of `points`, then scaled so every point is inside.
/// Radii are at least `min_radius` (for flat or tiny sets).
///
/// `tol` is the relative accuracy of the volume: the result is at most `1 + tol` times the
/// minimum (before the `min_radius` padding; `tol` is clamped to `[1e-12, 1]`). Non-finite
/// points are ignored; with none left the result is a sphere of radius `min_radius` at the
/// origin. Never panics; the radii are at least `min_radius` (a non-positive or non-finite
/// `min_radius` counts as `1e-12`) and finite for any input whose extent is.
pub fn mvee(points: &[DVec3], tol: f64, min_radius: f64) -> BoundingVolume {
    let hull = convex_hull(points);
    fit(&hull.vertices, points, tol, min_radius)
}

/// [`mvee`] of points already known to be in convex position, typically the vertices of a
/// convex hull (from [`super::hull::hull_points`]): the same fit without computing their hull
/// again. Points inside the hull of the others are allowed (they only cost time), so any
/// point set gives a correct, if slower, result; non-finite points are ignored.
pub fn mvee_of_hull(hull_vertices: &[DVec3], tol: f64, min_radius: f64) -> BoundingVolume {
    if hull_vertices.iter().all(|p| p.is_finite()) {
        fit(hull_vertices, hull_vertices, tol, min_radius)
    } else {
        let v: Vec<DVec3> = hull_vertices
            .iter()
            .copied()
            .filter(|p| p.is_finite())
            .collect();
        fit(&v, &v, tol, min_radius)
    }
}

/// The fit of [`mvee`] to the finite points `v` (hull vertices), scaled to hold every finite
/// point of `points` too.
fn fit(v: &[DVec3], points: &[DVec3], tol: f64, min_radius: f64) -> BoundingVolume {
    let min_r = if min_radius.is_finite() && min_radius > 0.0 {
        min_radius
    } else {
        1e-12
    };
    let tol = if tol.is_finite() && tol > 0.0 {
        tol.clamp(1e-12, 1.0)
    } else {
        1e-3
    };
    let finite = || points.iter().copied().filter(|p| p.is_finite());
    let sphere = |c: DVec3| BoundingVolume {
        shape: Shape::Ellipsoid,
        center: c,
        axes: DMat3::IDENTITY,
        radii: DVec3::splat(min_r),
        polytope: None,
    };
    if v.is_empty() {
        return sphere(DVec3::ZERO);
    }
    let frame = Frame::new(v);
    if frame.half.max_element() <= 0.0 {
        return sphere(v[0]).scaled_to_contain(finite());
    }

    // Directions too flat to fit in (relative to the largest extent), and directions thinner
    // than `min_radius`, where padding may beat fitting.
    let hmax = frame.half.max_element();
    let flat = |k: usize| frame.half[k] <= 1e-9 * hmax;
    let thin = |k: usize| flat(k) || frame.half[k] < min_r;
    let mut cands: Vec<BoundingVolume> = Vec::new();
    if !(0..3).any(flat) {
        if let Some(e) = fit_subspace(&frame, v, &[0, 1, 2], tol) {
            cands.push(e.to_volume(&frame, &[], min_r));
        }
    }
    let keep: Vec<usize> = (0..3).filter(|&k| !thin(k)).collect();
    if keep.len() < 3 || cands.is_empty() {
        let keep = if keep.len() == 3 {
            // Only reached if the full fit failed numerically: fall back to padding the
            // thinnest direction.
            let kmin = (0..3)
                .min_by(|&a, &b| frame.half[a].total_cmp(&frame.half[b]))
                .unwrap_or(2);
            (0..3).filter(|&k| k != kmin).collect()
        } else {
            keep
        };
        let e = fit_subspace(&frame, v, &keep, tol).unwrap_or_else(|| SubFit::bounding(&keep));
        let dropped: Vec<usize> = (0..3).filter(|k| !keep.contains(k)).collect();
        // Pads across the subspace: the worst case (a boundary point at the largest offset)
        // is best served by sqrt(2) times the offset, but usually less is needed.
        for f in [0.0, 1.0, std::f64::consts::SQRT_2, 2.0, 4.0] {
            let pads: Vec<(usize, f64)> = dropped
                .iter()
                .map(|&k| (k, math::max(f * frame.half[k], min_r)))
                .collect();
            cands.push(e.to_volume(&frame, &pads, min_r));
        }
    }
    let best = cands
        .into_iter()
        .map(|c| c.scaled_to_contain(v.iter().copied()))
        .min_by(|a, b| a.volume().total_cmp(&b.volume()))
        .unwrap_or_else(|| sphere(frame.origin));
    best.scaled_to_contain(finite())
}

/// The principal frame of the hull vertices and their extent in it: `y = R^T (x - origin)`,
/// with `y` in `mid ± half`.
struct Frame {
    origin: DVec3,
    rot: DMat3,
    mid: DVec3,
    half: DVec3,
}

impl Frame {
    fn new(v: &[DVec3]) -> Self {
        let origin = v.iter().copied().sum::<DVec3>() / v.len() as f64;
        let mut cov = DMat3::ZERO;
        for &p in v {
            let d = p - origin;
            cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (_, rot) = sym_eigen(cov);
        let rot = if rot.is_finite() {
            rot
        } else {
            DMat3::IDENTITY
        };
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for &p in v {
            let y = rot.transpose() * (p - origin);
            lo = lo.min(y);
            hi = hi.max(y);
        }
        Self {
            origin,
            rot,
            mid: 0.5 * (lo + hi),
            half: 0.5 * (hi - lo),
        }
    }

    /// Coordinates of `p` in the unit box of the frame, for the axes `keep`.
    fn unit(&self, p: DVec3, keep: &[usize]) -> [f64; 3] {
        let y = self.rot.transpose() * (p - self.origin);
        let mut z = [0.0; 3];
        for (i, &k) in keep.iter().enumerate() {
            z[i] = (y[k] - self.mid[k]) / self.half[k];
        }
        z
    }
}

/// An ellipsoid fitted in the unit-box coordinates of some axes of a [`Frame`]:
/// `(z - c)^T S^-1 (z - c) <= 1`, only the leading `keep.len()` entries used.
struct SubFit {
    keep: Vec<usize>,
    c: [f64; 3],
    s: [[f64; 3]; 3],
}

impl SubFit {
    /// The ellipsoid through the corners of the unit box: a valid, if loose, enclosure.
    fn bounding(keep: &[usize]) -> Self {
        let d = keep.len() as f64;
        let mut s = [[0.0; 3]; 3];
        for (i, row) in s.iter_mut().enumerate().take(keep.len()) {
            row[i] = d;
        }
        Self {
            keep: keep.to_vec(),
            c: [0.0; 3],
            s,
        }
    }

    /// Maps the fit back to world space, with radius `pad` along each dropped frame axis.
    fn to_volume(&self, f: &Frame, pads: &[(usize, f64)], min_r: f64) -> BoundingVolume {
        // Shape matrix (the inverse of the quadratic form, so no inversion) in frame
        // coordinates: H S H on the kept axes, pad^2 on the dropped ones.
        let mut sy = DMat3::ZERO;
        let mut cy = f.mid;
        for (i, &ki) in self.keep.iter().enumerate() {
            cy[ki] += f.half[ki] * self.c[i];
            for (j, &kj) in self.keep.iter().enumerate() {
                sy.col_mut(kj)[ki] = f.half[ki] * self.s[i][j] * f.half[kj];
            }
        }
        for &(k, r) in pads {
            sy.col_mut(k)[k] = r * r;
        }
        let (vals, vecs) = sym_eigen(sy);
        let radii = vals
            .max(DVec3::ZERO)
            .map(f64::sqrt)
            .max(DVec3::splat(min_r));
        let axes = f.rot * vecs;
        let ok = radii.is_finite() && axes.is_finite();
        BoundingVolume {
            shape: Shape::Ellipsoid,
            center: f.origin + f.rot * cy,
            axes: if ok { axes } else { f.rot },
            radii: if ok { radii } else { DVec3::splat(min_r) },
            polytope: None,
        }
    }
}

/// MVEE of the points `v` in the unit box of the frame axes `keep` (1 to 3 of them).
fn fit_subspace(f: &Frame, v: &[DVec3], keep: &[usize], tol: f64) -> Option<SubFit> {
    let z: Vec<[f64; 3]> = v.iter().map(|&p| f.unit(p, keep)).collect();
    let d = keep.len();
    // Once every lifted point has `omega <= (d + 1)(1 + eps)`, the duality gap of the lifted
    // problem bounds the volume of the ellipsoid grown to hold them by (1 + eps)^((d+1)/2)
    // times the minimum; the final rescaling only shrinks that ellipsoid.
    let eps = math::powf(1.0 + tol, 2.0 / (d + 1) as f64) - 1.0;
    let (c, s) = match d {
        // A segment: the unit box's extremes are attained, so the MVEE is [-1, 1].
        1 => ([0.0; 3], {
            let mut s = [[0.0; 3]; 3];
            s[0][0] = 1.0;
            s
        }),
        2 => solve::<3, 6>(&z, eps)?,
        3 => solve::<4, 10>(&z, eps)?,
        _ => return None,
    };
    Some(SubFit {
        keep: keep.to_vec(),
        c,
        s,
    })
}

/// Todd–Yildirim on the lifted points `(z, 1)` in `N = d + 1` dimensions; returns the centre
/// and shape matrix `S = d * (sum u z z^T - c c^T)` of the fitted ellipsoid.
fn solve<const N: usize, const K: usize>(
    z: &[[f64; 3]],
    eps: f64,
) -> Option<([f64; 3], [[f64; 3]; 3])> {
    let d = N - 1;
    let q: Vec<[f64; N]> = z
        .iter()
        .map(|p| {
            let mut x = [1.0; N];
            x[..d].copy_from_slice(&p[..d]);
            x
        })
        .collect();
    let u = WaTy::<N>::run::<K>(&q, eps)?;
    let mut c = [0.0; 3];
    let mut s = [[0.0; 3]; 3];
    for (ui, qi) in u.iter().zip(&q) {
        if *ui == 0.0 {
            continue;
        }
        for a in 0..d {
            c[a] += ui * qi[a];
            for b in 0..d {
                s[a][b] += ui * qi[a] * qi[b];
            }
        }
    }
    for a in 0..d {
        for b in 0..d {
            s[a][b] = d as f64 * (s[a][b] - c[a] * c[b]);
        }
    }
    Some((c, s))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::EulerRot;

    fn gaussian(rng: &mut Rng) -> DVec3 {
        // Box–Muller, three coordinates.
        let mut g = || {
            let (a, b) = (math::max(rng.next_f64(), 1e-300), rng.next_f64());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        DVec3::new(g(), g(), g())
    }

    fn blob(rng: &mut Rng, n: usize) -> Vec<DVec3> {
        let r = DMat3::from_euler(EulerRot::ZYX, 0.7, -0.3, 1.9);
        (0..n)
            .map(|_| r * (gaussian(rng) * DVec3::new(3.0, 1.0, 0.4)) + DVec3::new(5.0, -2.0, 1.0))
            .collect()
    }

    fn assert_contains(e: &BoundingVolume, pts: &[DVec3]) {
        assert!(e.radii.is_finite() && e.center.is_finite() && e.axes.is_finite());
        for &p in pts.iter().filter(|p| p.is_finite()) {
            assert!(e.contains(p), "gauge {} at {p}", e.gauge(p));
        }
    }

    /// The covariance ellipsoid of the points, scaled to hold them.
    fn cov_ellipsoid(pts: &[DVec3]) -> BoundingVolume {
        let m = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        let mut c = DMat3::ZERO;
        for &p in pts {
            let d = p - m;
            c += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (vals, axes) = sym_eigen(c / pts.len() as f64);
        BoundingVolume {
            shape: Shape::Ellipsoid,
            center: m,
            axes,
            radii: vals.map(f64::sqrt),
            polytope: None,
        }
        .scaled_to_contain(pts.iter().copied())
    }

    #[test]
    fn cube_corners_give_circumscribed_sphere() {
        let pts: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let e = mvee(&pts, 1e-3, 1e-6);
        assert_contains(&e, &pts);
        let r = 3f64.sqrt() / 2.0;
        assert!(
            (e.radii / r - 1.0).abs().max_element() < 1e-3,
            "{:?}",
            e.radii
        );
        assert!((e.center - DVec3::splat(0.5)).length() < 1e-3);
    }

    #[test]
    fn recovers_an_ellipsoid_from_surface_points() {
        let mut rng = Rng::new(5);
        let rot = DMat3::from_euler(EulerRot::XYZ, 0.4, -1.2, 2.5);
        let (radii, centre) = (DVec3::new(3.0, 2.0, 0.5), DVec3::new(-4.0, 10.0, 7.5));
        let pts: Vec<DVec3> = (0..600)
            .map(|_| rot * (gaussian(&mut rng).normalize() * radii) + centre)
            .collect();
        let e = mvee(&pts, 1e-7, 1e-6);
        assert_contains(&e, &pts);
        assert!(
            (e.radii - radii).abs().max_element() < 1e-3 * 3.0,
            "{:?}",
            e.radii
        );
        assert!((e.center - centre).length() < 1e-3);
        for k in 0..3 {
            assert!(e.axes.col(k).dot(rot.col(k)).abs() > 1.0 - 1e-6);
        }
    }

    #[test]
    fn contains_all_points_and_is_near_optimal() {
        let mut rng = Rng::new(9);
        for n in [4, 10, 100, 3000] {
            let pts = blob(&mut rng, n);
            let e = mvee(&pts, 1e-3, 1e-9);
            assert_contains(&e, &pts);
            let opt = mvee(&pts, 1e-9, 1e-9);
            assert_contains(&opt, &pts);
            let ratio = e.volume() / opt.volume();
            eprintln!(
                "n={n}: ratio {ratio} vs cov {}",
                e.volume() / cov_ellipsoid(&pts).volume()
            );
            assert!(
                (1.0 - 1e-9..=1.0 + 1e-3).contains(&ratio),
                "n={n}: ratio {ratio}"
            );
            let cov = cov_ellipsoid(&pts);
            assert!(e.volume() <= cov.volume() * (1.0 + 1e-9));
        }
    }

    #[test]
    fn lattice_points_with_ties() {
        // Grid-cell centres inside a rotated box: many coplanar and cospherical ties.
        let rot = DMat3::from_euler(EulerRot::YXZ, 0.3, 0.2, -0.9);
        let mut pts = Vec::new();
        for i in 0..12 {
            for j in 0..7 {
                for k in 0..4 {
                    pts.push(rot * DVec3::new(i as f64, j as f64, k as f64) * 0.1);
                }
            }
        }
        let e = mvee(&pts, 1e-3, 1e-6);
        assert_contains(&e, &pts);
        // The MVEE of a box is the box's circumscribed ellipsoid scaled by sqrt(3) per axis.
        let half = DVec3::new(1.1, 0.6, 0.3) / 2.0;
        let expect = 4.0 / 3.0 * std::f64::consts::PI * (half * 3f64.sqrt()).element_product();
        assert!(
            (e.volume() / expect - 1.0).abs() < 2e-3,
            "{}",
            e.volume() / expect
        );
    }

    #[test]
    fn scale_and_position_invariant() {
        let mut rng = Rng::new(21);
        let pts = blob(&mut rng, 500);
        let a = mvee(&pts, 1e-6, 1e-12);
        for (s, t) in [(1e-7, 1e3), (1e6, -1e7)] {
            let moved: Vec<DVec3> = pts.iter().map(|&p| p * s + DVec3::splat(t)).collect();
            let b = mvee(&moved, 1e-6, 1e-30);
            assert_contains(&b, &moved);
            assert!((b.radii / (a.radii * s) - 1.0).abs().max_element() < 1e-4);
        }
    }

    #[test]
    fn degenerate_inputs() {
        let min_r = 0.01;
        let check = |pts: &[DVec3]| {
            let e = mvee(pts, 1e-3, min_r);
            assert_contains(&e, pts);
            assert!(e.radii.min_element() >= min_r);
            e
        };
        // Empty: a sphere of min_radius at the origin.
        let e = mvee(&[], 1e-3, min_r);
        assert_eq!((e.center, e.radii), (DVec3::ZERO, DVec3::splat(min_r)));
        // A single point, duplicates and a NaN.
        let p = DVec3::new(1.0, -2.0, 3.0);
        let e = check(&[p]);
        assert_eq!((e.center, e.radii), (p, DVec3::splat(min_r)));
        check(&[p, p, p, DVec3::NAN]);
        // Collinear: a segment of half-length 2 along (1, 1, 0)/sqrt(2).
        let line: Vec<DVec3> = (0..9)
            .map(|i| p + DVec3::new(1.0, 1.0, 0.0) * (i as f64 / 8.0 * 8f64.sqrt()))
            .collect();
        let e = check(&line);
        assert!((e.radii.x - 2.0).abs() < 1e-3, "{:?}", e.radii);
        assert!((e.radii.z / min_r - 1.0).abs() < 1e-9, "{:?}", e.radii);
        // A tilted square: its circle, flat across.
        let rot = DMat3::from_euler(EulerRot::XYZ, 0.5, 0.1, 0.3);
        let sq: Vec<DVec3> = (0..4)
            .map(|i| rot * DVec3::new((i & 1) as f64, (i >> 1) as f64, 0.0) + p)
            .collect();
        let e = check(&sq);
        let r = 0.5f64.sqrt();
        assert!((e.radii.x - r).abs() < 1e-3 && (e.radii.y - r).abs() < 1e-3);
        assert!((e.radii.z / min_r - 1.0).abs() < 1e-9, "{:?}", e.radii);
        // Slightly thicker than flat, but thinner than min_radius: still padded, not fitted.
        let mut slab = sq.clone();
        slab.extend(sq.iter().map(|&q| q + rot.z_axis * 1e-4));
        let e = check(&slab);
        assert!(e.radii.z < 2.0 * min_r && e.radii.x < r * 1.01);
    }

    #[test]
    fn fuzz_degenerate_sets() {
        let mut rng = Rng::new(99);
        for case in 0..300 {
            let pts = crate::bounding::obb::tests::awkward_set(&mut rng, case);
            let min_r = if case % 2 == 0 { 1e-3 } else { 1e-12 };
            let e = mvee(&pts, 1e-3, min_r);
            assert_contains(&e, &pts);
            assert!(e.radii.min_element() >= min_r);
        }
    }

    #[test]
    fn of_hull_matches_the_general_fit() {
        let mut rng = Rng::new(13);
        let rot = DMat3::from_euler(EulerRot::XYZ, 0.3, 1.1, -0.6);
        // A blob's points plus grid-cell centres: lattice ties, as in the pipeline.
        let mut pts = blob(&mut rng, 1500);
        for i in 0..8 {
            for j in 0..5 {
                for k in 0..3 {
                    pts.push(rot * DVec3::new(i as f64, j as f64, k as f64) * 0.5);
                }
            }
        }
        let hull = crate::bounding::hull::hull_points(&pts);
        for tol in [1e-3, 1e-4] {
            let e = mvee_of_hull(&hull, tol, 1e-6);
            assert_contains(&e, &pts);
            let opt = mvee(&pts, 1e-9, 1e-6);
            let ratio = e.volume() / opt.volume();
            assert!((1.0 - 1e-9..=1.0 + tol).contains(&ratio), "{tol}: {ratio}");
            assert_eq!(e, mvee_of_hull(&hull, tol, 1e-6));
        }
        // Non-finite points are ignored, as by `mvee`.
        let mut with_nan = hull.clone();
        with_nan.push(DVec3::NAN);
        assert_eq!(
            mvee_of_hull(&with_nan, 1e-4, 1e-6),
            mvee_of_hull(&hull, 1e-4, 1e-6)
        );
        let e = mvee_of_hull(&[], 1e-4, 0.5);
        assert_eq!((e.center, e.radii), (DVec3::ZERO, DVec3::splat(0.5)));
    }

    /// Points from arithmetic alone (no transcendental), so the input is the same everywhere.
    pub(crate) fn portable_blob(seed: u64, n: usize) -> Vec<DVec3> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| {
                let [x, y, z] = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
                DVec3::new(3.0 * x + y, y - 0.5 * z, 0.4 * z * (1.0 + x)) + DVec3::splat(7.0)
            })
            .collect()
    }

    /// `digest()`, after checking that four threads running it at once get the same (on
    /// targets with threads).
    pub(crate) fn same_on_threads(digest: impl Fn() -> u64 + Sync) -> u64 {
        let here = digest();
        #[cfg(not(target_family = "wasm"))]
        std::thread::scope(|s| {
            let runs: Vec<_> = (0..4).map(|_| s.spawn(&digest)).collect();
            for r in runs {
                assert_eq!(r.join().ok(), Some(here));
            }
        });
        here
    }

    /// The fit's exact bits, recorded once: the same on every platform (the MVEE's `ln` and
    /// `powf` come from libm, see `crate::math`) and on every thread. `.ci/run` also runs
    /// this test compiled for wasm32 (`scripts/wasm_tests.sh`). A change here means either
    /// the platform's maths leaks into the result, or an intended change of the fit (then
    /// record the new digest, and say so).
    #[test]
    fn same_bits_on_every_platform_and_thread() {
        const GOLDEN: u64 = 0xde3f_abd7_8742_a04e;
        let pts = portable_blob(2, 2000);
        let here = same_on_threads(|| mvee(&pts, 1e-4, 1e-6).bits_digest());
        assert_eq!(here, GOLDEN, "MVEE digest {here:#x}");
    }
}
