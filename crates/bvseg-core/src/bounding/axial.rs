//! Near-minimum-volume capsules and cylinders.
//!
//! For a given axis direction the best cylinder and capsule are exact: the points projected
//! on the plane across the axis have a minimum enclosing circle (the cylinder's radius and
//! axis line), and their extent along the axis gives the cylinder's height. A capsule around
//! that line with radius `r >= R` needs the segment `[max_i (z_i - sqrt(r^2 - rho_i^2)),
//! min_i ...]` read from each point's height `z_i` and distance `rho_i` from the line, and
//! its radius is found by a one-dimensional search. The direction is searched: seeds are the
//! principal axes of the points, the direction of their widest pair of extreme points and
//! the 13 axes of a 26-DOP; the best few are refined by a pattern search on the sphere of
//! directions with shrinking steps. The search judges a capsule by the one of radius `R`
//! (one pass over the points instead of a radius search); the best directions then get
//! their best radius. The pattern search skips a direction without its circle when a lower
//! bound (see [`Circles::quick_bound`]) shows that it cannot beat the current one.
use std::cell::{Cell, RefCell};
use std::collections::HashMap;

use glam::{DMat3, DVec2, DVec3};

use super::ball::{circle3_radius_below, finite_shuffled, min_circle_hinted, min_circle_in_order};
use super::extreme_points;
use crate::linalg::sym_eigen;
use crate::math;
use crate::volume::BoundingVolume;
#[cfg(test)]
use crate::volume::Shape;

/// Seeds refined by the pattern search.
const REFINED: usize = 2;
/// First step of the pattern search, in radians.
const FIRST_STEP: f64 = 0.25;
/// Halvings of the pattern search's step.
const HALVINGS: usize = 6;
/// Radii tried, from the circle's to the enclosing ball's, before the golden-section search.
const RADII: usize = 12;
/// Relative margin of [`Circles::quick_bound`] over its round-off (a few units of 1e-16), so
/// that skipping a direction by it never changes the search.
const BOUND_SLACK: f64 = 1e-9;

/// Which of the two axial shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axial {
    /// A capsule.
    Capsule,
    /// A cylinder.
    Cylinder,
}

/// A near-minimum-volume capsule or cylinder holding `points` (finite ones), radius and
/// half-length at least `min_r` (a capsule's half-length may be 0).
pub fn min_axial(points: &[DVec3], kind: Axial, min_r: f64) -> BoundingVolume {
    let p: Vec<DVec3> = finite_shuffled(points);
    search(&Circles::new(&p), kind, min_r)
}

/// The capsule and the cylinder of [`min_axial`], in that order: the two searches share the
/// circles of the directions both try (every seed, and the first steps from a shared one).
pub fn min_capsule_and_cylinder(points: &[DVec3], min_r: f64) -> [BoundingVolume; 2] {
    let p: Vec<DVec3> = finite_shuffled(points);
    let circles = Circles::new(&p);
    [Axial::Capsule, Axial::Cylinder].map(|kind| search(&circles, kind, min_r))
}

/// The points (shuffled once for all the projections' circles) and what is known across each
/// direction tried so far, by the direction's bits.
struct Circles<'a> {
    p: &'a [DVec3],
    known: RefCell<HashMap<[u64; 3], Across>>,
    /// [`fit_with`]'s buffers: the points across and along a direction.
    scratch: RefCell<(Vec<DVec2>, Vec<f64>)>,
    /// The points the last circle computed rests on: the search tries directions close to
    /// each other in turn, whose circles mostly rest on the same points.
    last: Cell<Option<[usize; 3]>>,
}

/// The points seen along and across a direction.
#[derive(Clone, Copy)]
struct Across {
    /// The minimum circle of the points projected across it: centre and radius.
    centre: DVec2,
    radius: f64,
    /// The points that circle rests on (indices, repeated when fewer than three).
    support: [usize; 3],
    /// The points lowest and highest along it.
    ends: [usize; 2],
}

impl<'a> Circles<'a> {
    fn new(p: &'a [DVec3]) -> Self {
        Self {
            p,
            known: RefCell::default(),
            scratch: RefCell::default(),
            last: Cell::new(None),
        }
    }

    /// The minimum circle (centre, radius) of the points projected on `(u, w)`, the basis
    /// [`fit_with`] takes for `a`; `ends` are the points lowest and highest along `a`.
    fn of(&self, a: DVec3, flat: &mut [DVec2], ends: [usize; 2]) -> (DVec2, f64) {
        let key = a.to_array().map(f64::to_bits);
        if let Some(c) = self.known.borrow().get(&key) {
            return (c.centre, c.radius);
        }

        let (centre, radius, support) = match self.last.get() {
            Some(hint) => min_circle_hinted(flat, hint),
            None => min_circle_in_order(flat),
        };
        self.last.set(Some(support));
        let across = Across {
            centre,
            radius,
            support,
            ends,
        };
        self.known.borrow_mut().insert(key, across);
        (centre, radius)
    }

    /// What is known across `a`, if its circle was computed.
    fn get(&self, a: DVec3) -> Option<Across> {
        let key = a.to_array().map(f64::to_bits);
        self.known.borrow().get(&key).copied()
    }

    /// Whether the quick volume along `cand`, whose circle is not known yet, is shown not to
    /// be below `limit` by [`Circles::quick_bound`] from `near`.
    fn cannot_beat(&self, cand: DVec3, near: DVec3, kind: Axial, min_r: f64, limit: f64) -> bool {
        self.get(cand).is_none()
            && self
                .quick_bound(cand, near, kind, min_r)
                .is_some_and(|b| b * (1.0 - BOUND_SLACK) >= limit)
    }

    /// A lower bound on the volume of `fit_with(self, a, kind, min_r, false)`, from the few
    /// points that made the circle and the extent across and along `near`, a direction close
    /// to `a` whose circle is known: across `a`, the circle of those points is no larger than
    /// all the points' circle, and the spread of the two ends no larger than the extent; both
    /// volumes grow with either. A handful of dot products instead of passes over the points.
    fn quick_bound(&self, a: DVec3, near: DVec3, kind: Axial, min_r: f64) -> Option<f64> {
        let known = self.get(near)?;
        let u = a.any_orthonormal_vector();
        let w = a.cross(u);
        let flat = known.support.map(|i| {
            let q = self.p[i];
            DVec2::new(q.dot(u), q.dot(w))
        });
        let r = math::max(circle3_radius_below(flat), min_r);
        // The same products as `fit_with`'s, so never more than its extent.
        let height = self.p[known.ends[1]].dot(a) - self.p[known.ends[0]].dot(a);
        let pi = std::f64::consts::PI;
        Some(match kind {
            Axial::Cylinder => 2.0 * pi * r * r * math::max(0.5 * height, min_r),
            // The capsule's segment and caps span the extent: the segment is at least
            // `height - 2 r`, and the bound grows with r (its derivative is
            // `2 pi r (height - r)` below `r = height / 2`, then the ball's).
            Axial::Capsule => pi * r * r * (math::max(height - 2.0 * r, 0.0) + 4.0 / 3.0 * r),
        })
    }
}

/// The search of [`min_axial`] over directions, on `circles`' points.
fn search(circles: &Circles, kind: Axial, min_r: f64) -> BoundingVolume {
    let p = circles.p;
    if p.is_empty() {
        let unit = match kind {
            Axial::Capsule => BoundingVolume::capsule(DVec3::ZERO, DVec3::Z, 0.0, min_r),
            Axial::Cylinder => BoundingVolume::cylinder(DVec3::ZERO, DVec3::Z, min_r, min_r),
        };
        return unit;
    }
    let seeds = seeds(p);
    let quick = |a: DVec3| fit_with(circles, a, kind, min_r, false).volume();
    let mut scored: Vec<(f64, DVec3)> = seeds.into_iter().map(|a| (quick(a), a)).collect();
    scored.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut best: Option<BoundingVolume> = None;
    // A direction whose circle is not known yet is skipped when a bound shows it cannot
    // beat the incumbent: the search takes the same steps, with fewer circles.
    let cannot_beat =
        |cand: DVec3, near: DVec3, limit: f64| circles.cannot_beat(cand, near, kind, min_r, limit);
    for &(v0, a0) in scored.iter().take(REFINED) {
        let (_, a) = refine(a0, v0, quick, cannot_beat);
        let v = fit_with(circles, a, kind, min_r, true);
        if best.as_ref().is_none_or(|b| v.volume() < b.volume()) {
            best = Some(v);
        }
    }
    best.unwrap_or_else(|| fit_with(circles, DVec3::Z, kind, min_r, true))
        .scaled_to_contain(p.iter().copied())
}

/// Pattern search over directions from `a` (volume `v`) for the least `volume`;
/// `cannot_beat(cand, a, limit)` may tell, without the volume, that `cand`'s is not below
/// `limit`.
fn refine(
    mut a: DVec3,
    mut v: f64,
    volume: impl Fn(DVec3) -> f64,
    cannot_beat: impl Fn(DVec3, DVec3, f64) -> bool,
) -> (f64, DVec3) {
    let mut step = FIRST_STEP;
    for _ in 0..HALVINGS {
        let mut moved = true;
        let mut rounds = 0;
        while moved && rounds < 8 {
            moved = false;
            rounds += 1;
            let e1 = a.any_orthonormal_vector();
            let e2 = a.cross(e1);
            let (s, c) = crate::math::sin_cos(step);
            for d in [e1, -e1, e2, -e2] {
                let cand = (a * c + d * s).normalize();
                let limit = v * (1.0 - 1e-12);
                if cannot_beat(cand, a, limit) {
                    continue;
                }
                let vc = volume(cand);
                if vc < limit {
                    (a, v, moved) = (cand, vc, true);
                    break;
                }
            }
        }
        step *= 0.5;
    }
    (v, a)
}

/// The seed directions (unit, sign irrelevant).
fn seeds(p: &[DVec3]) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(20);
    let n = p.len() as f64;
    let mean = p.iter().copied().sum::<DVec3>() / n;
    let mut cov = DMat3::ZERO;
    for &q in p {
        let d = q - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let (_, vecs) = sym_eigen(cov * (1.0 / n));
    out.extend([vecs.x_axis, vecs.y_axis, vecs.z_axis]);
    let dop: [DVec3; 13] = [
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(0.0, 1.0, -1.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, -1.0),
        DVec3::new(1.0, -1.0, 1.0),
        DVec3::new(-1.0, 1.0, 1.0),
    ];
    // The widest pair among the extreme points along the 26-DOP's axes.
    let mut ext = Vec::with_capacity(26);
    for d in dop {
        ext.extend(extreme_points(p, d));
    }
    let mut wide = (0.0, DVec3::Z);
    for i in 0..ext.len() {
        for j in i + 1..ext.len() {
            let d = (ext[j] - ext[i]).length_squared();
            if d > wide.0 {
                wide = (d, ext[j] - ext[i]);
            }
        }
    }
    out.push(wide.1);
    out.extend(dop);
    out.into_iter().filter_map(DVec3::try_normalize).collect()
}

/// The best capsule or cylinder along the unit direction `a`.
#[cfg(test)]
fn fit_along(p: &[DVec3], a: DVec3, kind: Axial, min_r: f64) -> BoundingVolume {
    fit_with(&Circles::new(p), a, kind, min_r, true)
}

/// [`fit_along`] on `circles`' points, with a capsule's radius searched (`search_radius`)
/// or the axis circle's.
fn fit_with(
    circles: &Circles,
    a: DVec3,
    kind: Axial,
    min_r: f64,
    search_radius: bool,
) -> BoundingVolume {
    let p = circles.p;
    let u = a.any_orthonormal_vector();
    let w = a.cross(u);
    let mut scratch = circles.scratch.borrow_mut();
    let (flat, z) = &mut *scratch;
    z.clear();
    z.extend(p.iter().map(|&q| q.dot(a)));
    let (mut zlo, mut zhi, mut ends) = (f64::INFINITY, f64::NEG_INFINITY, [0; 2]);
    for (i, &x) in z.iter().enumerate() {
        if x < zlo {
            ends[0] = i;
        }
        if x > zhi {
            ends[1] = i;
        }
        (zlo, zhi) = (math::min(zlo, x), math::max(zhi, x));
    }
    // A cylinder along a direction tried before needs only the points' extent along it.
    let known = circles.get(a).filter(|_| kind == Axial::Cylinder);
    let (c2, circle) = match known {
        Some(k) => (k.centre, k.radius),
        None => {
            flat.clear();
            flat.extend(p.iter().map(|&q| DVec2::new(q.dot(u), q.dot(w))));
            circles.of(a, flat, ends)
        }
    };
    let big_r = math::max(circle, min_r);
    let line = u * c2.x + w * c2.y;
    match kind {
        Axial::Cylinder => {
            let half = math::max(0.5 * (zhi - zlo), min_r);
            BoundingVolume::cylinder(line + a * (0.5 * (zlo + zhi)), a, half, big_r)
        }
        Axial::Capsule if !search_radius => {
            let (mut z0, mut z1) = (f64::INFINITY, f64::NEG_INFINITY);
            for (q, &zi) in flat.iter().zip(z.iter()) {
                let s = math::max(big_r * big_r - (*q - c2).length_squared(), 0.0).sqrt();
                z0 = math::min(z0, zi + s);
                z1 = math::max(z1, zi - s);
            }
            let half = math::max(0.5 * (z1 - z0), 0.0);
            BoundingVolume::capsule(line + a * (0.5 * (z0 + z1)), a, half, big_r)
        }
        Axial::Capsule => {
            let rho2: Vec<f64> = flat.iter().map(|&q| (q - c2).length_squared()).collect();
            // The segment [z0, z1] of a capsule of radius r around the line.
            let segment = |r: f64| {
                let (mut z0, mut z1) = (f64::INFINITY, f64::NEG_INFINITY);
                for (&zi, &ri) in z.iter().zip(&rho2) {
                    let s = math::max(r * r - ri, 0.0).sqrt();
                    z0 = math::min(z0, zi + s);
                    z1 = math::max(z1, zi - s);
                }
                (z0, z1)
            };
            let volume = |r: f64| {
                let (z0, z1) = segment(r);
                std::f64::consts::PI * r * r * (math::max(z1 - z0, 0.0) + 4.0 / 3.0 * r)
            };
            // Past the ball around the middle that holds every point, the segment is empty
            // and the volume only grows.
            let half = 0.5 * (zhi - zlo);
            let r_max = math::max((big_r * big_r + half * half).sqrt(), big_r);
            let at = |i: usize| {
                let f = i as f64 / (RADII - 1) as f64;
                big_r + (r_max - big_r) * f * f
            };
            let mut bi = 0;
            let mut bv = f64::INFINITY;
            for i in 0..RADII {
                let v = volume(at(i));
                if v < bv {
                    (bi, bv) = (i, v);
                }
            }
            // Golden-section search between the neighbours of the best sample.
            let (mut lo, mut hi) = (at(bi.saturating_sub(1)), at((bi + 1).min(RADII - 1)));
            let g = 0.5 * (5f64.sqrt() - 1.0);
            for _ in 0..30 {
                let m1 = hi - g * (hi - lo);
                let m2 = lo + g * (hi - lo);
                if volume(m1) <= volume(m2) {
                    hi = m2;
                } else {
                    lo = m1;
                }
            }
            let r = if volume(0.5 * (lo + hi)) < bv {
                0.5 * (lo + hi)
            } else {
                at(bi)
            };
            let (z0, z1) = segment(r);
            let (mid, half) = if z1 >= z0 {
                (0.5 * (z0 + z1), 0.5 * (z1 - z0))
            } else {
                (0.5 * (z0 + z1), 0.0)
            };
            BoundingVolume::capsule(line + a * mid, a, half, r)
        }
    }
}

/// The exact volume a capsule or cylinder of `shape` needs along `a` (for tests).
#[cfg(test)]
fn volume_along(p: &[DVec3], a: DVec3, shape: Shape) -> f64 {
    let kind = if shape == Shape::Capsule {
        Axial::Capsule
    } else {
        Axial::Cylinder
    };
    fit_along(p, a, kind, 1e-12).volume()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn limb(seed: u64) -> Vec<DVec3> {
        let mut r = Rng::new(seed);
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3 * seed as f64, 0.7, -0.2);
        (0..150)
            .map(|_| {
                let z = (r.next_f64() - 0.5) * 4.0;
                let ang = r.next_f64() * std::f64::consts::TAU;
                let rad = r.next_f64().sqrt() * (0.5 + 0.2 * z.abs());
                rot * DVec3::new(rad * ang.cos(), rad * ang.sin() * 0.8, z)
            })
            .collect()
    }

    /// Unit directions near `a`, as the pattern search tries them.
    fn around(a: DVec3, r: &mut Rng) -> Vec<DVec3> {
        (0..40)
            .filter_map(|i| {
                let step = 0.25 * 0.5f64.powi(i % 7);
                let d = DVec3::new(r.next_f64() - 0.5, r.next_f64() - 0.5, r.next_f64() - 0.5);
                (a + step * d.reject_from(a).normalize_or_zero()).try_normalize()
            })
            .collect()
    }

    #[test]
    fn the_quick_bound_is_below_the_quick_volume() {
        let mut r = Rng::new(11);
        let mut tight = 0;
        let mut tried = 0;
        for seed in 0..6 {
            let p = finite_shuffled(&limb(seed));
            let circles = Circles::new(&p);
            for near in seeds(&p) {
                for kind in [Axial::Capsule, Axial::Cylinder] {
                    let _ = fit_with(&circles, near, kind, 1e-6, false);
                    for cand in around(near, &mut r) {
                        let bound = circles
                            .quick_bound(cand, near, kind, 1e-6)
                            .expect("the circle across `near` is known");
                        let v = fit_with(&Circles::new(&p), cand, kind, 1e-6, false).volume();
                        assert!(bound * (1.0 - BOUND_SLACK) <= v, "{kind:?}: {bound} > {v}");
                        tried += 1;
                        tight += usize::from(bound > 0.9 * v);
                    }
                }
            }
        }
        // A bound far below the volume would be useless: near half are within 10 % (the
        // directions here reach 0.25 rad away, where other points make the circle and ends).
        assert!(tight * 3 > tried, "{tight} of {tried} within 10 %");
    }

    #[test]
    fn skipping_by_the_bound_leaves_the_search_as_it_was() {
        for seed in 0..6 {
            let p = finite_shuffled(&limb(seed));
            for kind in [Axial::Capsule, Axial::Cylinder] {
                let (skipping, plain) = (Circles::new(&p), Circles::new(&p));
                let quick = |c: &Circles, a: DVec3| fit_with(c, a, kind, 1e-6, false).volume();
                for a0 in seeds(&p) {
                    let v0 = quick(&plain, a0);
                    let _ = quick(&skipping, a0);
                    let cannot_beat = |cand: DVec3, near: DVec3, limit: f64| {
                        skipping.cannot_beat(cand, near, kind, 1e-6, limit)
                    };
                    let with = refine(a0, v0, |a| quick(&skipping, a), cannot_beat);
                    let without = refine(a0, v0, |a| quick(&plain, a), |_, _, _| false);
                    assert_eq!(
                        with.0.to_bits(),
                        without.0.to_bits(),
                        "{kind:?} seed {seed}"
                    );
                    assert_eq!(with.1, without.1);
                }
                assert!(skipping.known.borrow().len() < plain.known.borrow().len());
            }
        }
    }

    #[test]
    fn within_two_per_cent_of_a_brute_force_sweep_and_enclosing() {
        for seed in 0..4 {
            let p = limb(seed);
            for (kind, shape) in [
                (Axial::Capsule, Shape::Capsule),
                (Axial::Cylinder, Shape::Cylinder),
            ] {
                let v = min_axial(&p, kind, 1e-9);
                assert_eq!(v.shape, shape);
                assert!(p.iter().all(|&q| v.contains(q)), "{shape:?} misses a point");
                // Brute force: 4,000 directions of a Fibonacci hemisphere.
                let n = 4000;
                let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
                let best = (0..n)
                    .map(|i| {
                        let z = 1.0 - (i as f64 + 0.5) / n as f64;
                        let r = (1.0 - z * z).sqrt();
                        let t = golden * i as f64;
                        volume_along(&p, DVec3::new(r * t.cos(), r * t.sin(), z), shape)
                    })
                    .fold(f64::INFINITY, math::min);
                assert!(
                    v.volume() <= best * 1.02,
                    "seed {seed} {shape:?}: {} vs brute force {best}",
                    v.volume()
                );
            }
        }
    }

    #[test]
    fn a_capsule_around_a_capsule_is_that_capsule() {
        // Points on a capsule's surface: radius 0.5, segment half-length 1 along (1, 1, 0).
        let a = DVec3::new(1.0, 1.0, 0.0).normalize();
        let u = a.any_orthonormal_vector();
        let w = a.cross(u);
        let mut p = Vec::new();
        for i in 0..24 {
            let t = std::f64::consts::TAU * i as f64 / 24.0;
            let rim = (u * t.cos() + w * t.sin()) * 0.5;
            for z in [-1.0, 0.0, 1.0] {
                p.push(a * z + rim);
            }
            for j in 1..6 {
                let th = std::f64::consts::FRAC_PI_2 * j as f64 / 6.0;
                p.push(a * (1.0 + 0.5 * th.sin()) + rim * th.cos());
                p.push(a * (-1.0 - 0.5 * th.sin()) + rim * th.cos());
            }
        }
        let v = min_axial(&p, Axial::Capsule, 1e-9);
        assert!((v.radius() - 0.5).abs() < 1e-3, "{}", v.radius());
        assert!((v.half_length() - 1.0).abs() < 1e-2, "{}", v.half_length());
        assert!(v.axis().dot(a).abs() > 0.9999);
    }
}
