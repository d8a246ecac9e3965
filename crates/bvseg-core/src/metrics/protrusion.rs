//! The protrusion: how far the union of the volumes reaches beyond the surface, as the
//! one-way Hausdorff distance from the union's boundary to the mesh surface (paper section
//! 5.4 names the Hausdorff distance as an application's error measure; the collider
//! literature compares this one). Unlike the relative outside volume it goes to zero as parts
//! get smaller, at pointed tips too, so a tolerance on it can always be met.
//!
//! The distance to the surface has no local maximum outside the solid (moving away from the
//! nearest surface point increases it), so over a volume it peaks on the volume's boundary,
//! and the largest distance of the union's boundary is the largest, over the volumes, of the
//! distance of each volume's boundary outside the solid: a volume's own figure can be cached
//! with its fit. The boundary is sampled (a Fibonacci lattice on the ellipsoid, a grid on the
//! box's faces, corners included) and the best samples refined by a pattern search, so the
//! peak is found to a small fraction of the sample spacing.
use crate::math;
use glam::DVec3;

use super::surface::SurfaceDistance;
use crate::sampling::{Grid, NONE};
use crate::volume::{BoundingVolume, Shape};

/// Points of the Fibonacci lattice on an ellipsoid.
const ELLIPSOID_SAMPLES: usize = 160;

/// Grid points per face edge on a box (corners and edges included).
const BOX_GRID: usize = 6;

/// Points around a cylinder's or capsule's rings.
const AXIAL_AROUND: usize = 24;

/// Face-grid points of a hull's boundary, about.
const HULL_SAMPLES: usize = 200;

/// Best samples refined by the pattern search.
const REFINED: usize = 3;

/// Halvings of the pattern search's step.
const HALVINGS: usize = 10;

/// A point of a volume's boundary, in its local coordinates (`|t| = 1` for an ellipsoid,
/// `max |t_j| = 1` for a box).
type Local = DVec3;

/// The largest distance to the surface of the points of `v`'s boundary outside the solid
/// (and, when `others` is not empty, outside every volume of `others`: the part of the
/// union's boundary that `v` makes); 0 when there is none. (The run uses
/// [`protrusion_capped`], which bounds the search's work.)
#[cfg(test)]
pub fn protrusion(
    v: &BoundingVolume,
    surface: &SurfaceDistance,
    grid: &Grid,
    others: &[BoundingVolume],
) -> f64 {
    protrusion_by(v, outside(grid), others, |p, _| Some(surface.distance(p))).unwrap_or(0.0)
}

/// Whether [`surface_protrusion`] of `v` (alone) exceeds `tol`: most volumes that do show it
/// at a boundary sample, found without measuring the rest.
pub fn surface_protrusion_exceeds(
    v: &BoundingVolume,
    surface: &SurfaceDistance,
    tol: f64,
    points: &[DVec3],
    cap: u64,
) -> (bool, u64) {
    let near = std::cell::Cell::new(super::surface::NO_TRIANGLE);
    let spent = std::cell::Cell::new(0u64);
    let (samples, _) = boundary_samples(v);
    let mut over = false;
    for &t in &samples {
        match surface.distance_within(v.world(t), (f64::INFINITY, tol), &near, &spent, cap) {
            Some(d) if d > tol => {
                over = true;
                break;
            }
            Some(_) => {}
            None => break,
        }
    }
    crate::work::add(spent.get() as usize);
    if over {
        return (true, spent.get());
    }
    let (p, more) = surface_protrusion(v, surface, &[], points, cap);
    (p > tol, spent.get() + more)
}

/// Whether a point is outside the sampled solid (in a lattice cell without a sample).
fn outside(grid: &Grid) -> impl Fn(DVec3) -> bool + '_ {
    move |p| {
        let [i, j, k] = grid.cell_of(p);
        grid.sample_at(i, j, k) == NONE
    }
}

/// The protrusion of `v` over a surface with no inside (the surface route of
/// `crate::shells`): the largest distance to the surface of the points of `v`'s boundary
/// outside every volume of `others`, wherever they are, as the judges measure it. Within the
/// bound `cap` on the search (the lattice route has one too: (a fan of huge overlapping
/// triangles makes every query visit them all); beyond it, an upper bound: the distance to
/// the nearest of `points`, which lie on the surface. Returns the figure and the work done.
pub fn surface_protrusion(
    v: &BoundingVolume,
    surface: &SurfaceDistance,
    others: &[BoundingVolume],
    points: &[DVec3],
    cap: u64,
) -> (f64, u64) {
    let near = std::cell::Cell::new(super::surface::NO_TRIANGLE);
    let spent = std::cell::Cell::new(0u64);
    let last = std::cell::Cell::new(None::<(DVec3, f64)>);
    let exact = protrusion_by(
        v,
        |_| true,
        others,
        |p, floor| {
            let bound = last
                .get()
                .map_or(f64::INFINITY, |(q, d)| d + (p - q).length());
            let d = surface.distance_within(p, (bound, floor), &near, &spent, cap)?;
            last.set(Some((p, d)));
            Some(d)
        },
    );
    crate::work::add(spent.get() as usize);
    let value = exact.unwrap_or_else(|| {
        protrusion_by(v, |_| true, others, |p, _| Some(nearest(points, p))).unwrap_or(0.0)
    });
    (value, spent.get())
}

/// [`protrusion`] within a bound on the search's work: each fit may visit `cap` nodes and
/// triangles of the surface's tree (a hostile mesh of huge overlapping triangles makes every
/// query visit them all). Beyond it, an upper bound instead: the distance to the nearest of
/// `points`, which lie in the solid (a segment from a point outside to a point inside meets
/// the surface). Returns the figure and the work done.
pub fn protrusion_capped(
    v: &BoundingVolume,
    surface: &SurfaceDistance,
    grid: &Grid,
    others: &[BoundingVolume],
    points: &[DVec3],
    cap: u64,
) -> (f64, u64) {
    let spent = std::cell::Cell::new(0u64);
    // The distance is 1-Lipschitz: the last point's distance plus the step to this one bounds
    // it, and lets the search skip most of the tree (the samples and the pattern search move
    // in small steps).
    // For the same reason, the last point's nearest triangle is tried first.
    let last = std::cell::Cell::new(None::<(DVec3, f64)>);
    let near = std::cell::Cell::new(super::surface::NO_TRIANGLE);
    let exact = protrusion_by(v, outside(grid), others, |p, floor| {
        let bound = last
            .get()
            .map_or(f64::INFINITY, |(q, d)| d + (p - q).length());
        let d = surface.distance_within(p, (bound, floor), &near, &spent, cap)?;
        last.set(Some((p, d)));
        Some(d)
    });
    let value = exact.unwrap_or_else(|| protrusion_bound(v, grid, others, points));
    crate::work::add(spent.get() as usize);
    (value, spent.get())
}

/// An upper bound of [`protrusion`]: the distance to the nearest of `points` (points of the
/// solid) in place of the distance to the surface.
pub fn protrusion_bound(
    v: &BoundingVolume,
    grid: &Grid,
    others: &[BoundingVolume],
    points: &[DVec3],
) -> f64 {
    protrusion_by(v, outside(grid), others, |p, _| Some(nearest(points, p))).unwrap_or(0.0)
}

/// The distance from `p` to the nearest of `points` (points of the surface or the solid: an
/// upper bound of the distance to the surface from outside).
fn nearest(points: &[DVec3], p: DVec3) -> f64 {
    points
        .iter()
        .map(|&q| (q - p).length_squared())
        .fold(f64::INFINITY, math::min)
        .sqrt()
}

/// [`protrusion`] with the distance `dist`; `None` as soon as `dist` gives up. `dist(p,
/// floor)` may return any value up to `floor` when the distance is at most `floor`: only
/// the distances above it decide anything (see `distance_within`).
fn protrusion_by(
    v: &BoundingVolume,
    outside: impl Fn(DVec3) -> bool,
    others: &[BoundingVolume],
    dist: impl Fn(DVec3, f64) -> Option<f64>,
) -> Option<f64> {
    let world = |t: Local| v.world(t);
    // Only points that count: on the union's boundary and outside the solid.
    let counts = |t: Local| {
        let p = world(t);
        outside(p) && others.iter().all(|o| o.gauge(p) >= 1.0 - 1e-7)
    };
    let gave_up = std::cell::Cell::new(false);
    let value = |t: Local, floor: f64| {
        if !counts(t) || gave_up.get() {
            return f64::NEG_INFINITY;
        }
        dist(world(t), floor).unwrap_or_else(|| {
            gave_up.set(true);
            f64::NEG_INFINITY
        })
    };
    let (samples, step) = boundary_samples(v);
    // Only the largest few samples are refined: a sample no larger than the smallest of
    // those so far needs no exact value (it loses a tie, coming later).
    let mut top = [f64::NEG_INFINITY; REFINED];
    let mut scored: Vec<(f64, usize)> = Vec::with_capacity(samples.len());
    for (i, &t) in samples.iter().enumerate() {
        let d = value(t, top[REFINED - 1]);
        if !d.is_finite() {
            continue;
        }
        scored.push((d, i));
        if let Some(at) = top.iter().position(|&x| d > x) {
            top.copy_within(at..REFINED - 1, at + 1);
            top[at] = d;
        }
    }
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut best = scored.first().map_or(0.0, |s| s.0);
    for &(d, i) in scored.iter().take(REFINED) {
        best = math::max(best, refine(v, samples[i], d, step, &value));
    }
    (!gave_up.get()).then_some(best)
}

/// The sample points of a boundary of `shape` in local coordinates, and their spacing there.
fn boundary_samples(v: &BoundingVolume) -> (Vec<Local>, f64) {
    match v.shape {
        Shape::Ellipsoid | Shape::Sphere => {
            let n = ELLIPSOID_SAMPLES;
            let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
            let pts = (0..n)
                .map(|i| {
                    let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                    let r = math::max(1.0 - z * z, 0.0).sqrt();
                    let (s, c) = crate::math::sin_cos(golden * i as f64);
                    DVec3::new(r * c, r * s, z)
                })
                .collect();
            (pts, (4.0 * std::f64::consts::PI / n as f64).sqrt())
        }
        Shape::Obb => {
            let m = BOX_GRID;
            let at = |i: usize| -1.0 + 2.0 * i as f64 / (m - 1) as f64;
            let mut pts = Vec::with_capacity(6 * m * m);
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    for a in 0..m {
                        for b in 0..m {
                            let mut t = [0.0; 3];
                            t[axis] = sign;
                            t[(axis + 1) % 3] = at(a);
                            t[(axis + 2) % 3] = at(b);
                            pts.push(DVec3::from_array(t));
                        }
                    }
                }
            }
            (pts, 2.0 / (m - 1) as f64)
        }
        Shape::Cylinder | Shape::Capsule => axial_samples(v),
        Shape::Hull => hull_samples(v),
    }
}

/// Samples of a cylinder's or capsule's boundary in local coordinates: rings around the side
/// (corners included) and, at the ends, flat discs or the end balls' hemispheres.
fn axial_samples(v: &BoundingVolume) -> (Vec<Local>, f64) {
    let around = AXIAL_AROUND;
    let l = v.radii.z / v.radii.x;
    // Side rings spaced about as the points around are, in units of the radius.
    let along = ((l * around as f64 / std::f64::consts::PI).ceil() as usize).clamp(2, 4 * around);
    let mut pts = Vec::new();
    let ring = |rho: f64, z: f64, pts: &mut Vec<Local>| {
        for s in 0..around {
            let (sn, c) = crate::math::sin_cos(std::f64::consts::TAU * s as f64 / around as f64);
            pts.push(DVec3::new(rho * c, rho * sn, z));
        }
    };
    for i in 0..along {
        ring(1.0, -1.0 + 2.0 * i as f64 / (along - 1) as f64, &mut pts);
    }
    let caps = AXIAL_AROUND / 4;
    for sign in [-1.0, 1.0] {
        for i in 0..caps {
            let f = i as f64 / caps as f64;
            match v.shape {
                // Flat discs, rings from the rim in.
                Shape::Cylinder => ring(1.0 - f, sign, &mut pts),
                // Hemispheres: latitude rings out to the pole (1 / l per radius along z).
                _ => {
                    let th = std::f64::consts::FRAC_PI_2 * (i + 1) as f64 / caps as f64;
                    let (sn, c) = crate::math::sin_cos(th);
                    ring(c, sign * (1.0 + sn / l), &mut pts);
                }
            }
        }
        pts.push(match v.shape {
            Shape::Cylinder => DVec3::new(0.0, 0.0, sign),
            _ => DVec3::new(0.0, 0.0, sign * (1.0 + 1.0 / l)),
        });
    }
    (pts, std::f64::consts::TAU / around as f64)
}

/// Samples of a hull's boundary in local coordinates: its vertices and a grid on every face.
fn hull_samples(v: &BoundingVolume) -> (Vec<Local>, f64) {
    let Some(p) = v.polytope() else {
        return (Vec::new(), 1.0);
    };
    let mut pts: Vec<Local> = p.vertices().to_vec();
    let total: f64 = p
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p.vertices()[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let spacing = math::max((total / HULL_SAMPLES as f64).sqrt(), 1e-9);
    for t in p.triangles() {
        let [a, b, c] = t.map(|i| p.vertices()[i as usize]);
        let longest = math::max(
            math::max((b - a).length(), (c - a).length()),
            (c - b).length(),
        );
        let m = ((longest / spacing).ceil() as usize).clamp(1, 64);
        for i in 0..=m {
            for j in 0..=m - i {
                let (u, w) = (i as f64 / m as f64, j as f64 / m as f64);
                pts.push(a + (b - a) * u + (c - a) * w);
            }
        }
    }
    (pts, spacing)
}

/// Pattern search on the boundary from `t` (value `d`) with initial step `step`: moves along
/// the two tangent directions while they increase `value`, halving the step otherwise.
fn refine(
    v: &BoundingVolume,
    mut t: Local,
    mut d: f64,
    mut step: f64,
    value: &impl Fn(Local, f64) -> f64,
) -> f64 {
    for _ in 0..HALVINGS {
        let mut moved = true;
        while moved {
            moved = false;
            let (e1, e2) = tangents(v.shape, t);
            for dir in [e1, -e1, e2, -e2] {
                let cand = project(v, t + dir * step);
                let dc = value(cand, d);
                if dc > d {
                    (t, d, moved) = (cand, dc, true);
                    break;
                }
            }
        }
        step *= 0.5;
    }
    d
}

/// Two directions along the boundary at `t`.
fn tangents(shape: Shape, t: Local) -> (DVec3, DVec3) {
    match shape {
        // Around the direction from the centre: on the curved kinds and the hull's faces a
        // step across it followed by the projection stays near the boundary.
        Shape::Ellipsoid | Shape::Sphere | Shape::Cylinder | Shape::Capsule | Shape::Hull => {
            let a = if t.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
            let e1 = t.cross(a).normalize_or_zero();
            (e1, t.cross(e1).normalize_or_zero())
        }
        Shape::Obb => {
            // The face's two free axes.
            let a = t.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            let unit =
                |i: usize| DVec3::from_array(std::array::from_fn(|j| f64::from(u8::from(i == j))));
            (unit((axis + 1) % 3), unit((axis + 2) % 3))
        }
    }
}

/// `t` moved back onto the boundary.
fn project(v: &BoundingVolume, t: Local) -> Local {
    match v.shape {
        Shape::Ellipsoid | Shape::Sphere => t.normalize_or_zero(),
        Shape::Cylinder | Shape::Capsule | Shape::Hull => {
            let g = v.gauge_local(t);
            if g > 0.0 && g.is_finite() {
                t / g
            } else {
                DVec3::Z
            }
        }
        Shape::Obb => {
            let c = t.clamp(DVec3::splat(-1.0), DVec3::splat(1.0));
            let m = c.abs().max_element();
            if m <= 0.0 {
                return DVec3::X;
            }
            // Push the largest coordinate back onto its face.
            let a = c.abs();
            let mut out = c;
            if a.x >= a.y && a.x >= a.z {
                out.x = c.x.signum();
            } else if a.y >= a.z {
                out.y = c.y.signum();
            } else {
                out.z = c.z.signum();
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DMat3;

    fn cube_grid() -> Grid {
        Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.1, |p| {
            p.abs().max_element() <= 1.0
        })
    }

    #[test]
    fn cube_in_its_circumscribed_ball_and_in_a_larger_box() {
        let mesh = shapes::cuboid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY);
        let surface = SurfaceDistance::new(&mesh);
        let grid = cube_grid();
        // The ball of radius sqrt 3 touches the corners; its farthest points lie over the
        // face centres, sqrt 3 - 1 from the surface.
        let ball = BoundingVolume {
            shape: Shape::Ellipsoid,
            center: DVec3::ZERO,
            axes: DMat3::IDENTITY,
            radii: DVec3::splat(3f64.sqrt()),
            polytope: None,
        };
        let p = protrusion(&ball, &surface, &grid, &[]);
        assert!((p - (3f64.sqrt() - 1.0)).abs() < 1e-3, "{p}");
        // A box 1.2 times the cube: its corners are 0.2 sqrt 3 from the cube's corners.
        let b = BoundingVolume {
            shape: Shape::Obb,
            radii: DVec3::splat(1.2),
            polytope: None,
            ..ball
        };
        let p = protrusion(&b, &surface, &grid, &[]);
        assert!((p - 0.2 * 3f64.sqrt()).abs() < 1e-9, "{p}");
        // Covered by the larger box, the ball adds nothing to the union's boundary.
        let big = BoundingVolume {
            radii: DVec3::splat(2.0),
            polytope: None,
            ..b
        };
        assert_eq!(protrusion(&ball, &surface, &grid, &[big]), 0.0);
    }

    #[test]
    fn an_elongated_ellipsoid_peaks_at_its_tips() {
        // A sphere of radius 1 in an ellipsoid of semi-axes (3, 1.2, 1.2): the tips are 2 out.
        let mesh = shapes::ellipsoid(DVec3::ZERO, DVec3::ONE, DMat3::IDENTITY, 48);
        let surface = SurfaceDistance::new(&mesh);
        let grid = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.1, |p| {
            p.length() <= 1.0
        });
        let v = BoundingVolume {
            shape: Shape::Ellipsoid,
            center: DVec3::ZERO,
            axes: DMat3::from_rotation_z(0.3),
            radii: DVec3::new(3.0, 1.2, 1.2),
            polytope: None,
        };
        let p = protrusion(&v, &surface, &grid, &[]);
        assert!((p - 2.0).abs() < 2e-3, "{p}");
    }

    /// The run's measure, which skips proving most distances below the few largest (see
    /// `protrusion_by`), finds what measuring every distance finds, for volumes of every
    /// kind placed at random over a mesh.
    #[test]
    fn skipping_small_distances_finds_the_same_protrusion() {
        let mesh = shapes::union(&[
            shapes::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.6, 0.4), DMat3::IDENTITY, 32),
            shapes::cuboid(
                DVec3::new(0.8, 0.0, 0.0),
                DVec3::splat(0.3),
                DMat3::IDENTITY,
            ),
        ]);
        let surface = SurfaceDistance::new(&mesh);
        let grid = Grid::from_inside_fn(DVec3::splat(-1.2), DVec3::splat(1.2), 0.05, |p| {
            (p / DVec3::new(1.0, 0.6, 0.4)).length() <= 1.0
                || (p - DVec3::new(0.8, 0.0, 0.0)).abs().max_element() <= 0.3
        });
        let mut rng = crate::rng::Rng::new(5);
        let mut r = || rng.next_f64();
        let mut positive = 0;
        for round in 0..60 {
            let shape = [
                Shape::Ellipsoid,
                Shape::Obb,
                Shape::Capsule,
                Shape::Cylinder,
            ][round % 4];
            let v = BoundingVolume {
                shape,
                center: DVec3::new(r() - 0.5, r() - 0.5, r() - 0.5),
                axes: DMat3::from_euler(glam::EulerRot::ZXY, 3.0 * r(), 3.0 * r(), 3.0 * r()),
                radii: DVec3::new(0.3 + r(), 0.3 + r(), 0.3 + r()),
                polytope: None,
            };
            let all = protrusion(&v, &surface, &grid, &[]);
            let (run, _) = protrusion_capped(&v, &surface, &grid, &[], &[], u64::MAX);
            assert!(
                (run - all).abs() <= 1e-12 * math::max(all, 1.0),
                "{shape:?}: {run} vs {all}"
            );
            positive += usize::from(all > 0.0);
        }
        assert!(positive > 40, "{positive}");
    }
}
