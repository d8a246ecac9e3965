//! Tight oriented bounding box.
//!
//! The minimum-volume box has a face flush with a face of the convex hull, or two adjacent
//! faces flush with hull edges (O'Rourke). The exact search over edge pairs is cubic, so this
//! takes the cheap, usually sufficient part of it and lets a local search do the rest:
//!
//! - candidate frames: the principal axes (of the hull vertices and of all the points), the
//!   axes themselves, DiTO-14's frames (edges of a large triangle of extreme points and of the
//!   two tetrahedra over it), and for the largest distinct hull face normals the box flush
//!   with that face whose other axes come from the minimum-area rectangle of the hull's
//!   projection on the face plane (rotating calipers);
//! - the best few candidates are refined by coordinate descent over small rotations about
//!   their own axes, with shrinking steps, evaluated on the few hull vertices that can still
//!   become extreme within the remaining rotation.
//!
//! Everything is evaluated on the hull vertices; the final extents are taken over all points.
use crate::math;
use glam::{DMat3, DVec2, DVec3};

use super::hull::convex_hull;
use super::{extreme_points, extremes};
use crate::linalg::{orthonormalize, sym_eigen};
use crate::volume::{BoundingVolume, Shape};

/// How many distinct hull face normals get a flush-box candidate (the largest faces first).
const MAX_FACE_NORMALS: usize = 40;
/// Normals closer than this (as `|cos|`) count as one direction.
const SAME_NORMAL: f64 = 0.99995;
/// How many of the best candidates are refined (the best one before refinement is not always
/// the best one after; 6 rather than 3 fixed a 0.8% miss in the brute-force test).
const REFINED: usize = 6;

/// A tight oriented bounding box of `points` holding all of them; half-extents at least
/// `min_radius`.
///
/// Deterministic, never panics; non-finite points are ignored (with none left the result is
/// a cube of half-extent `min_radius` at the origin). A non-positive or non-finite
/// `min_radius` counts as `1e-12`.
pub fn min_obb(points: &[DVec3], min_radius: f64) -> BoundingVolume {
    let min_r = if min_radius.is_finite() && min_radius > 0.0 {
        min_radius
    } else {
        1e-12
    };
    let finite: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let hull = convex_hull(&finite);
    let v = &hull.vertices;
    let axes = if v.len() < 2 {
        DMat3::IDENTITY
    } else if hull.dim == 1 {
        frame_from_axis(v[v.len() - 1] - v[0])
    } else {
        best_frame(&hull, &finite, min_r)
    };
    box_in_frame(axes, &finite, min_r)
}

/// The box with axes `axes` tightly holding `points` (half-extents at least `min_r`).
pub fn box_in_frame(axes: DMat3, points: &[DVec3], min_r: f64) -> BoundingVolume {
    let (lo, hi) = extents(axes, points);
    let (mid, half) = if lo.x <= hi.x {
        (0.5 * (lo + hi), 0.5 * (hi - lo))
    } else {
        (DVec3::ZERO, DVec3::ZERO)
    };
    BoundingVolume {
        shape: Shape::Obb,
        center: axes * mid,
        axes,
        radii: half.max(DVec3::splat(min_r)),
        polytope: None,
    }
    .scaled_to_contain(points.iter().copied())
}

/// Minimum and maximum of the points' coordinates along the columns of `axes`.
fn extents(axes: DMat3, points: &[DVec3]) -> (DVec3, DVec3) {
    // The hot loop of the whole search: plain scalar selects (one `minsd`/`maxsd` each, where
    // `f64::min` adds NaN handling; the points are finite) and no matrix type in between.
    let (a, b, c) = (axes.x_axis, axes.y_axis, axes.z_axis);
    let (mut l0, mut l1, mut l2) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let (mut h0, mut h1, mut h2) = (f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        let y0 = a.x * p.x + a.y * p.y + a.z * p.z;
        let y1 = b.x * p.x + b.y * p.y + b.z * p.z;
        let y2 = c.x * p.x + c.y * p.y + c.z * p.z;
        l0 = if y0 < l0 { y0 } else { l0 };
        l1 = if y1 < l1 { y1 } else { l1 };
        l2 = if y2 < l2 { y2 } else { l2 };
        h0 = if y0 > h0 { y0 } else { h0 };
        h1 = if y1 > h1 { y1 } else { h1 };
        h2 = if y2 > h2 { y2 } else { h2 };
    }
    (DVec3::new(l0, l1, l2), DVec3::new(h0, h1, h2))
}

/// Volume measure of the box of `points` in frame `axes`, with the `min_r` padding.
fn padded_volume(axes: DMat3, points: &[DVec3], min_r: f64) -> f64 {
    let (lo, hi) = extents(axes, points);
    (0.5 * (hi - lo)).max(DVec3::splat(min_r)).element_product()
}

/// A right-handed orthonormal frame whose first axis is along `a` (any, if `a` is zero).
fn frame_from_axis(a: DVec3) -> DMat3 {
    let x = a.try_normalize().unwrap_or(DVec3::X);
    let y = x.any_orthonormal_vector();
    DMat3::from_cols(x, y, x.cross(y))
}

/// A right-handed frame with third axis `n` and first axis along `e` projected off `n`.
fn frame_from_normal(n: DVec3, e: DVec3) -> Option<DMat3> {
    let n = n.try_normalize()?;
    let x = (e - n * n.dot(e)).try_normalize()?;
    Some(DMat3::from_cols(x, n.cross(x), n))
}

/// The principal axes of `points` as a right-handed frame.
fn pca_frame(points: &[DVec3]) -> Option<DMat3> {
    if points.is_empty() {
        return None;
    }
    let m = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let mut cov = DMat3::ZERO;
    for &p in points {
        let d = p - m;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let (_, r) = sym_eigen(cov);
    r.is_finite().then_some(r)
}

/// The frame of the smallest box found for a hull of dimension 2 or 3 (see the module docs).
fn best_frame(hull: &super::hull::Hull, all: &[DVec3], min_r: f64) -> DMat3 {
    let v = &hull.vertices;
    let mut cands: Vec<DMat3> = vec![DMat3::IDENTITY];
    cands.extend(pca_frame(v));
    cands.extend(pca_frame(all));
    cands.extend(dito_frames(v));
    cands.extend(face_frames(hull));
    let mut scored: Vec<(f64, DMat3)> = cands
        .into_iter()
        .filter(|r| r.is_finite())
        .map(|r| (padded_volume(r, v, min_r), r))
        .collect();
    // Stable, so equal volumes keep the candidates' (deterministic) order.
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Refine the best few that are not the same frame up to axis permutations and signs.
    let mut picked: Vec<(f64, DMat3)> = Vec::new();
    for &(vol, r) in &scored {
        if picked.len() == REFINED {
            break;
        }
        let same = picked.iter().any(|(_, p)| {
            (0..3).all(|k| (0..3).any(|j| p.col(j).dot(r.col(k)).abs() > SAME_NORMAL))
        });
        if !same {
            picked.push((vol, r));
        }
    }
    let mut best = scored
        .first()
        .copied()
        .unwrap_or((f64::INFINITY, DMat3::IDENTITY));
    for (vol, r) in picked {
        let (rv, rr) = refine(r, vol, v, min_r);
        if rv < best.0 {
            best = (rv, rr);
        }
    }
    best.1
}

/// DiTO-14 candidate frames: from the extremes along 7 directions, a large triangle (the
/// farthest pair and the point farthest from their line) and the two tetrahedra over it
/// (apexes at the extremes along its normal); each triangle gives a frame per edge.
fn dito_frames(v: &[DVec3]) -> Vec<DMat3> {
    const DIRS: [[f64; 3]; 7] = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, 1.0, -1.0],
        [1.0, -1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    let mut ext: Vec<DVec3> = Vec::with_capacity(14);
    for d in DIRS.map(DVec3::from_array) {
        ext.extend(extreme_points(v, d));
    }
    let mut best = (0.0, DVec3::ZERO, DVec3::ZERO);
    for (i, &a) in ext.iter().enumerate() {
        for &b in &ext[i + 1..] {
            let d = a.distance_squared(b);
            if d > best.0 {
                best = (d, a, b);
            }
        }
    }
    let (_, p0, p1) = best;
    let e0 = p1 - p0;
    let Some(p2) = ext.iter().copied().max_by(|a, b| {
        e0.cross(*a - p0)
            .length_squared()
            .total_cmp(&e0.cross(*b - p0).length_squared())
    }) else {
        return Vec::new();
    };
    let mut tris = vec![[p0, p1, p2]];
    let n = e0.cross(p2 - p0);
    if n.length_squared() > 0.0 {
        for q in extreme_points(v, n) {
            tris.extend([[p0, p1, q], [p1, p2, q], [p2, p0, q]]);
        }
    }
    let mut out = Vec::new();
    for [a, b, c] in tris {
        let n = (b - a).cross(c - a);
        for e in [b - a, c - b, a - c] {
            out.extend(frame_from_normal(n, e));
        }
    }
    out
}

/// For the largest distinct face normals: the box flush with that face, with the minimum-area
/// rectangle of the hull's projection in the face plane.
fn face_frames(hull: &super::hull::Hull) -> Vec<DMat3> {
    let nf = hull.faces.len();
    let fn_: Vec<(DVec3, f64)> = (0..nf).map(|f| hull.face_normal_area(f)).collect();
    // Largest first, index on ties, so the order is deterministic.
    let mut order: Vec<usize> = (0..nf).filter(|&f| fn_[f].1 > 0.0).collect();
    order.sort_unstable_by(|&a, &b| fn_[b].1.total_cmp(&fn_[a].1).then(a.cmp(&b)));
    let mut normals: Vec<DVec3> = Vec::new();
    for f in order {
        if normals.len() == MAX_FACE_NORMALS {
            break;
        }
        let n = fn_[f].0;
        if normals.iter().all(|m| m.dot(n).abs() < SAME_NORMAL) {
            normals.push(n);
        }
    }
    // The projection of a convex polytope along n is the projection of its silhouette: the
    // edges between faces facing n and faces not facing it. Only their ends need the 2D hull.
    // All the normals at once: bit j of a face's mask says whether it faces normal j, so an
    // edge is on normal j's rim where its two faces' masks differ in bit j.
    const _: () = assert!(MAX_FACE_NORMALS <= 64);
    let facing: Vec<u64> = fn_
        .iter()
        .map(|(m, _)| {
            normals.iter().enumerate().fold(0u64, |bits, (j, n)| {
                bits | (u64::from(m.dot(*n) > 0.0) << j)
            })
        })
        .collect();
    let mut rims = vec![0u64; hull.vertices.len()];
    // Each edge once, as the two faces on either side of it.
    let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * nf);
    for (f, t) in hull.faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            edges.push(((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), f as u32));
        }
    }
    edges.sort_unstable();
    for w in edges.windows(2).filter(|w| w[0].0 == w[1].0) {
        let rim = facing[w[0].1 as usize] ^ facing[w[1].1 as usize];
        rims[(w[0].0 >> 32) as usize] |= rim;
        rims[w[0].0 as u32 as usize] |= rim;
    }
    let mut out = Vec::with_capacity(normals.len());
    let mut pts: Vec<DVec2> = Vec::new();
    for (j, n) in normals.into_iter().enumerate() {
        let basis = frame_from_axis(n);
        let (u, w) = (basis.y_axis, basis.z_axis);
        let project = |p: &DVec3| DVec2::new(u.dot(*p), w.dot(*p));
        pts.clear();
        pts.extend(
            hull.vertices
                .iter()
                .zip(&rims)
                .filter(|(_, &r)| r >> j & 1 == 1)
                .map(|(p, _)| project(p)),
        );
        if pts.len() < 3 {
            // Not a closed surface after all: every vertex.
            pts.clear();
            pts.extend(hull.vertices.iter().map(project));
        }
        let poly = convex_polygon(&mut pts);
        if let Some(dir) = min_area_rect_dir(&poly) {
            out.extend(frame_from_normal(n, u * dir.x + w * dir.y));
        }
    }
    out
}

/// Counter-clockwise convex hull of 2D points (monotone chain; collinear points dropped).
/// Sorts `pts` in place.
pub fn convex_polygon(pts: &mut [DVec2]) -> Vec<DVec2> {
    pts.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::with_capacity(pts.len() + 1);
    for &p in pts.iter() {
        while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    let lower = h.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while h.len() >= lower && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    h.pop();
    h
}

/// Direction of one side of the minimum-area rectangle around a convex polygon
/// (counter-clockwise), by rotating calipers: the optimal rectangle has a side on a polygon
/// edge, and as the edge advances the extreme vertices in the edge's frame only move forward.
pub fn min_area_rect_dir(poly: &[DVec2]) -> Option<DVec2> {
    let m = poly.len();
    match m {
        0 => return None,
        1 => return Some(DVec2::X),
        2 => return (poly[1] - poly[0]).try_normalize(),
        _ => {}
    }
    // Indices stay below `m`: a wrapped successor rather than `% m`, an integer division at
    // every step.
    let next = |i: usize| if i + 1 == m { 0 } else { i + 1 };
    let (mut right, mut far, mut left) = (0usize, 0usize, 0usize);
    let mut best: Option<(f64, DVec2)> = None;
    for i in 0..m {
        let a = poly[i];
        let Some(e) = (poly[next(i)] - a).try_normalize() else {
            continue;
        };
        let nrm = e.perp();
        if i == 0 {
            // Initial pointers by a full scan; later they only advance.
            let last_max = |x: Option<[usize; 2]>| x.map_or(0, |[_, hi]| hi);
            right = last_max(extremes(poly, |p| e.dot(p)));
            far = last_max(extremes(poly, |p| nrm.dot(p)));
            left = last_max(extremes(poly, |p| -e.dot(p)));
        } else {
            // Bounded advances guard against rounding on nearly collinear vertices.
            for _ in 0..m {
                if e.dot(poly[next(right)]) >= e.dot(poly[right]) {
                    right = next(right);
                } else {
                    break;
                }
            }
            for _ in 0..m {
                if nrm.dot(poly[next(far)]) >= nrm.dot(poly[far]) {
                    far = next(far);
                } else {
                    break;
                }
            }
            for _ in 0..m {
                if e.dot(poly[next(left)]) <= e.dot(poly[left]) {
                    left = next(left);
                } else {
                    break;
                }
            }
        }
        let width = e.dot(poly[right]) - e.dot(poly[left]);
        let height = nrm.dot(poly[far] - a);
        let area = width * height;
        match best {
            Some((b, _)) if area >= b => {}
            _ => best = Some((area, e)),
        }
    }
    best.map(|(_, e)| e)
}

/// Coordinate descent on small rotations of `r` about its own axes, with steps shrinking from
/// about 3 degrees to 1e-5 rad. Returns the refined volume measure and frame.
fn refine(mut r: DMat3, mut vol: f64, v: &[DVec3], min_r: f64) -> (f64, DMat3) {
    const PASSES: usize = 4;
    // Moves of the current step size allowed before the support set is rebuilt.
    const BUDGET: f64 = 6.0;
    let centre = v.iter().copied().sum::<DVec3>() / v.len().max(1) as f64;
    let reach = v.iter().map(|p| p.distance(centre)).fold(0.0f64, math::max);
    let mut support: Vec<DVec3> = Vec::with_capacity(v.len());
    // Rotation since the support set was built, and how much it allows.
    let (mut turned, mut allowed) = (0.0, -1.0);
    let mut step = 0.05;
    while step > 1e-5 {
        // The rotations by +-step, computed once per step size rather than per trial.
        let turns = [1.0, -1.0].map(|sign: f64| math::sin_cos(sign * step));
        for _ in 0..PASSES {
            let mut improved = false;
            for axis in 0..3 {
                for &(s, c) in &turns {
                    // Rebuilt when spent, or when much looser than the current step needs.
                    if turned + step > allowed || allowed > 4.0 * BUDGET * step {
                        // A frame turned by at most `allowed` changes the difference of two
                        // projections by at most `2 reach allowed`: only points that close
                        // to an extreme now can be one then.
                        allowed = BUDGET * step;
                        turned = 0.0;
                        let slack = 2.0 * reach * allowed;
                        let (lo, hi) = extents(r, v);
                        let t = r.transpose();
                        support.clear();
                        support.extend(v.iter().copied().filter(|&p| {
                            let y = t * p;
                            (y - lo).min_element() <= slack || (hi - y).min_element() <= slack
                        }));
                    }
                    let mut rot = DMat3::IDENTITY;
                    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
                    rot.col_mut(i)[i] = c;
                    rot.col_mut(i)[j] = s;
                    rot.col_mut(j)[i] = -s;
                    rot.col_mut(j)[j] = c;
                    let cand = orthonormalize(r * rot);
                    let cv = padded_volume(cand, &support, min_r);
                    if cv < vol * (1.0 - 1e-12) {
                        (vol, r) = (cv, cand);
                        turned += step;
                        improved = true;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        step *= 0.5;
    }
    // The support sets were conservative, but measure once more on every vertex.
    (padded_volume(r, v, min_r), r)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::{DQuat, EulerRot};

    fn gaussian(rng: &mut Rng) -> f64 {
        let (a, b) = (math::max(rng.next_f64(), 1e-300), rng.next_f64());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }

    fn random_rotation(rng: &mut Rng) -> DMat3 {
        let q = DQuat::from_xyzw(gaussian(rng), gaussian(rng), gaussian(rng), gaussian(rng));
        DMat3::from_quat(q.normalize())
    }

    fn assert_contains(b: &BoundingVolume, pts: &[DVec3], min_r: f64) {
        assert!(b.radii.is_finite() && b.center.is_finite() && b.axes.is_finite());
        assert!(b.radii.min_element() >= min_r);
        assert!((b.axes.determinant() - 1.0).abs() < 1e-9);
        for &p in pts.iter().filter(|p| p.is_finite()) {
            assert!(b.contains(p), "gauge {} at {p}", b.gauge(p));
        }
    }

    /// Random point sets of different characters (seeded).
    fn point_set(kind: usize, seed: u64, n: usize) -> Vec<DVec3> {
        let mut rng = Rng::new(seed);
        let rot = random_rotation(&mut rng);
        let scale = DVec3::new(3.0, 1.5, 0.7);
        (0..n)
            .map(|_| {
                let p = match kind {
                    // Uniform in a box.
                    0 => DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5,
                    // Gaussian blob.
                    1 => DVec3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng)),
                    // Uniform in a ball.
                    _ => loop {
                        let p =
                            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
                        if p.length_squared() <= 1.0 {
                            break p;
                        }
                    },
                };
                rot * (p * scale) + DVec3::new(2.0, -1.0, 4.0)
            })
            .collect()
    }

    #[test]
    fn rotated_box_lattice_gives_that_box() {
        let rot = DMat3::from_euler(EulerRot::ZXY, 0.7, -0.4, 1.3);
        let t = DVec3::new(10.0, -3.0, 0.5);
        let mut pts = Vec::new();
        for i in 0..=10 {
            for j in 0..=6 {
                for k in 0..=3 {
                    pts.push(rot * DVec3::new(i as f64 * 0.3, j as f64 * 0.25, k as f64 * 0.2) + t);
                }
            }
        }
        let b = min_obb(&pts, 1e-6);
        assert_contains(&b, &pts, 1e-6);
        let exact = 3.0 * 1.5 * 0.6;
        assert!(
            (b.volume() / exact - 1.0).abs() < 1e-6,
            "{}",
            b.volume() / exact
        );
        // Its axes are the box's, up to order and sign.
        for k in 0..3 {
            assert!((0..3).any(|j| b.axes.col(j).dot(rot.col(k)).abs() > 1.0 - 1e-9));
        }
    }

    #[test]
    fn beats_the_pca_box_and_holds_every_point() {
        for kind in 0..3 {
            for seed in 0..4 {
                let pts = point_set(kind, 100 + seed, 400);
                let b = min_obb(&pts, 1e-9);
                assert_contains(&b, &pts, 1e-9);
                let pca = box_in_frame(pca_frame(&pts).unwrap_or(DMat3::IDENTITY), &pts, 1e-9);
                assert!(b.volume() <= pca.volume() * (1.0 + 1e-9), "kind {kind}");
            }
        }
    }

    /// A dense search over rotations: the best of many random frames, each of the best few
    /// then improved by random small rotations of shrinking size.
    fn brute_force(pts: &[DVec3], rng: &mut Rng) -> f64 {
        let v = convex_hull(pts).vertices;
        let vol = |r: DMat3| padded_volume(r, &v, 1e-12);
        let mut frames: Vec<(f64, DMat3)> = (0..6000)
            .map(|_| {
                let r = random_rotation(rng);
                (vol(r), r)
            })
            .collect();
        frames.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best = f64::INFINITY;
        for &(mut fv, mut r) in frames.iter().take(8) {
            for scale in [0.1, 0.03, 0.01, 0.003, 1e-3, 3e-4, 1e-4] {
                for _ in 0..150 {
                    let axis = DVec3::new(gaussian(rng), gaussian(rng), gaussian(rng));
                    let turn = DMat3::from_axis_angle(axis.normalize(), scale * gaussian(rng));
                    let c = orthonormalize(turn * r);
                    let cv = vol(c);
                    if cv < fv {
                        (fv, r) = (cv, c);
                    }
                }
            }
            best = math::min(best, fv);
        }
        8.0 * best
    }

    /// Measured: min_obb / brute force = 1.00015, 1.00002, 1.00126, 1.00000 on these four
    /// sets (the brute force is itself only near-optimal, so the ratio could even dip below 1).
    /// Over 32 further sets of 300 and 1000 points against a denser search (20,000 random
    /// frames, the best 20 refined): at most 1.0009, mean 1.00005.
    #[test]
    fn close_to_a_brute_force_minimum() {
        let mut rng = Rng::new(77);
        let mut worst = 0.0f64;
        for (kind, seed) in [(0, 1), (1, 2), (2, 3), (1, 4)] {
            let pts = point_set(kind, seed, 300);
            let b = min_obb(&pts, 1e-12);
            let ratio = b.volume() / brute_force(&pts, &mut rng);
            eprintln!("kind {kind} seed {seed}: min_obb / brute force = {ratio:.5}");
            worst = math::max(worst, ratio);
        }
        assert!(worst < 1.01, "{worst}");
    }

    #[test]
    fn degenerate_inputs() {
        let min_r = 0.01;
        let check = |pts: &[DVec3]| {
            let b = min_obb(pts, min_r);
            assert_contains(&b, pts, min_r);
            b
        };
        let b = min_obb(&[], min_r);
        assert_eq!((b.center, b.radii), (DVec3::ZERO, DVec3::splat(min_r)));
        let p = DVec3::new(1.0, 2.0, -3.0);
        let b = check(&[p, p, DVec3::NAN]);
        assert_eq!(b.radii, DVec3::splat(min_r));
        // A segment: its half-length along it, min_radius across.
        let line: Vec<DVec3> = (0..7)
            .map(|i| p + DVec3::new(1.0, 2.0, 2.0) * i as f64)
            .collect();
        let b = check(&line);
        assert!((b.volume() / (8.0 * 9.0 * min_r * min_r) - 1.0).abs() < 1e-9);
        // A tilted rectangle lattice: the rectangle, min_radius thick.
        let rot = DMat3::from_euler(EulerRot::XYZ, 0.3, -0.8, 0.5);
        let rect: Vec<DVec3> = (0..40)
            .map(|i| rot * DVec3::new((i % 8) as f64 * 0.5, (i / 8) as f64 * 0.25, 0.0) + p)
            .collect();
        let b = check(&rect);
        // Tilting the box a little out of the plane can trade in-plane area for the padded
        // thickness, so the flush box is an upper bound.
        let flush = 8.0 * 1.75 * 0.5 * min_r;
        let ratio = b.volume() / flush;
        assert!((0.99..1.0 + 1e-9).contains(&ratio), "{ratio}");
    }

    #[test]
    fn fuzz_degenerate_sets() {
        let mut rng = Rng::new(2024);
        for case in 0..300 {
            let pts = awkward_set(&mut rng, case);
            let min_r = if case % 2 == 0 { 1e-3 } else { 1e-12 };
            let b = min_obb(&pts, min_r);
            assert_contains(&b, &pts, min_r);
        }
    }

    /// Small awkward point sets: few points, duplicates, nearly collinear or coplanar sets,
    /// lattices, tiny or huge coordinates, the odd non-finite point.
    pub(crate) fn awkward_set(rng: &mut Rng, case: usize) -> Vec<DVec3> {
        let n = 1 + rng.below(40);
        let scale = [1e-6, 1.0, 1e4][case % 3];
        let offset = DVec3::splat([0.0, 1e3, -1e6][(case / 3) % 3]);
        let rot = random_rotation(rng);
        let mut pts: Vec<DVec3> = (0..n)
            .map(|i| {
                let mut p = match case % 5 {
                    0 => DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()),
                    1 => DVec3::new(rng.next_f64(), 0.0, 0.0),
                    2 => DVec3::new(rng.next_f64(), rng.next_f64(), 0.0),
                    3 => DVec3::new((i % 3) as f64, ((i / 3) % 3) as f64, (i / 9) as f64),
                    _ => DVec3::new(rng.next_f64(), rng.next_f64(), 1e-9 * rng.next_f64()),
                };
                if rng.below(4) == 0 {
                    p += DVec3::splat(1e-13 * rng.next_f64());
                }
                rot * p * scale + offset
            })
            .collect();
        if rng.below(3) == 0 {
            let dup = pts[rng.below(pts.len())];
            pts.extend([dup; 3]);
        }
        if rng.below(10) == 0 {
            pts.push(DVec3::new(f64::NAN, 0.0, f64::INFINITY));
        }
        pts
    }

    /// The box's exact bits, recorded once: the same on every platform (its rotations' sines
    /// come from libm) and thread. See the MVEE's test of the same name.
    #[test]
    fn same_bits_on_every_platform_and_thread() {
        const GOLDEN: u64 = 0x7733_9282_9388_d09b;
        let pts = crate::bounding::mvee::tests::portable_blob(9, 2000);
        let here =
            crate::bounding::mvee::tests::same_on_threads(|| min_obb(&pts, 1e-6).bits_digest());
        assert_eq!(here, GOLDEN, "OBB digest {here:#x}");
    }

    #[test]
    fn min_area_rectangle_of_a_rotated_rectangle() {
        let (s, c) = 0.3f64.sin_cos();
        let mut pts: Vec<DVec2> = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0), (1.0, 0.5)]
            .iter()
            .map(|&(x, y)| DVec2::new(c * x - s * y, s * x + c * y))
            .collect();
        let poly = convex_polygon(&mut pts);
        assert_eq!(poly.len(), 4);
        let dir = min_area_rect_dir(&poly).unwrap_or(DVec2::ZERO);
        assert!(
            dir.dot(DVec2::new(c, s)).abs() > 1.0 - 1e-12
                || dir.dot(DVec2::new(-s, c)).abs() > 1.0 - 1e-12
        );
    }
}
