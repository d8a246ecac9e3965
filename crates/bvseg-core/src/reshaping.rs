//! Beyond the paper: output ellipsoids shaped to stick out of the solid less, not to be small.
//!
//! The minimum-volume ellipsoid of a part is the smallest that holds it, not the one that
//! sticks out least. Space inside the solid costs nothing, and neither does space outside it
//! that another volume already covers: what counts is the outside volume of the union. The
//! ideal case shows the gap. The minimum-volume ellipsoid of a piece of a long cylinder
//! bulges out by OV = 1/3 whatever the piece's length, so a chain of them leaves TOV = 1/3
//! along a limb however finely it is cut. An ellipsoid that holds the same piece but reaches
//! further along the cylinder, into its neighbours' parts, bulges much less: OV =
//! (2/3) u^2 / (1 - u^2) when the piece spans the middle `2u` of the ellipsoid's length.
//!
//! So after the tightening, each output ellipsoid in turn is reshaped to add as few lattice
//! cells outside the solid to the union of all the other volumes as it can, while it still
//! holds every enclosure point of its part (so the union still bounds the object) and its
//! part's OV stays at most the larger of its own and MOV (so neither TOV nor MOV can rise; a
//! part's OV can, up to MOV, when its volume reaches into space other volumes already cover). The search is a compass search over the centre, the log semi-axes and the
//! orientation, each trial scaled about its centre to hold the points exactly; it starts from
//! the minimum-volume ellipsoid and accepts only strict improvements. Volumes are visited in
//! index order, so the result does not depend on the thread count.
//!
//! The same rule picks each part's kind among the run's kinds: the tightening gives a part the
//! kind with the fewest outside cells of its own, and here a part may switch to a kind that
//! covers more of its own but less that no other volume covers.
//!
//! Real parts are rarely pieces of straight cylinders: on the shared meshes the gain is a few
//! per cent of TOV at k = 32, most on furniture's bars and slabs.
use glam::{DMat3, DQuat, DVec3};

use std::sync::atomic::{AtomicU64, Ordering};

use crate::math;

use crate::metrics::{outside_cells, outside_cells_while, relative, Cells, Coverage, LATTICES};
use crate::partition::Solid;
use crate::volume::{BoundingVolume, Shape};

/// Number of halvings of the step sizes before the search of one volume stops.
const LEVELS: usize = 5;

/// Largest number of trial ellipsoids per volume (the search usually stops at about 100).
const MAX_TRIALS: usize = 600;

/// Smallest semi-axis, in cells, of an ellipsoid that is reshaped or tried. A thinner one
/// can slip between layers of cell centres: on a plate one cell thick, reshaping lowered the
/// lattice's count of outside cells while the true outside volume rose by 6 %.
const MIN_SEMI_AXIS_CELLS: f64 = 1.5;

/// Reshape the volumes: each in turn becomes the candidate that adds the fewest outside
/// cells to the union of the others. The candidates are the volume itself,
/// `fits(points[i], shape)` (the fits of every other kind the run allows: a part whose own
/// best kind leaves outside space that no neighbour covers can switch to one that overlaps
/// its neighbours), and the reshaped ellipsoid searched from the best ellipsoid among them.
/// `points[i]` are the points volume `i` must hold (its part's enclosure or convex-hull
/// points), `cells[i]` its outside cells (see [`outside_cells`]), `counts[i]` the number of
/// samples in its part; `min_r` is the smallest semi-axis allowed. The trials may visit
/// `budget` outside cells in all: the search stops, keeping the best volume so far, at the
/// end of the round that spent it (a volume spanning a lattice of mostly empty cells would
/// otherwise take seconds per round). Returns the new volumes and their outside cells, in the
/// same order.
pub fn reshape(
    solid: &Solid,
    points: &[&[DVec3]],
    volumes: &[BoundingVolume],
    mut cells: Vec<Cells>,
    counts: &[f64],
    (min_r, budget): (f64, u64),
    fits: &(dyn Fn(&[DVec3], Shape) -> Vec<BoundingVolume> + Sync),
) -> (Vec<BoundingVolume>, Vec<Cells>) {
    let grid = &solid.grid;
    // Cells the trials visited. Each trial's count is fixed by its volume and the round's
    // best, so the total after a round does not depend on the thread count.
    let visited = AtomicU64::new(0);
    let spent = || visited.load(Ordering::Relaxed) > budget;
    let mov = cells
        .iter()
        .zip(counts)
        .map(|(c, &n)| relative(c.len(), n))
        .fold(0.0, math::max);
    let mut cov = Coverage::new(solid);
    for c in &cells {
        cov.add(c);
    }
    // A trial thinner than this can slip between layers of cell centres (a hull's radii are
    // one scale, not its extent: its fit already holds the points it is judged on).
    let thin = |v: &BoundingVolume| {
        v.shape != Shape::Hull && v.radii.min_element() < MIN_SEMI_AXIS_CELLS * grid.h
    };
    let mut out = volumes.to_vec();
    for i in 0..volumes.len() {
        if spent() {
            break;
        }
        if points[i].is_empty() {
            continue;
        }
        cov.remove(&cells[i]);
        // A part's OV may rise, but not past the largest OV (so MOV cannot rise either).
        let own_limit = cells[i]
            .len()
            .max((mov * LATTICES * counts[i]).floor() as usize);
        let cov_ref = &cov;
        // (outside cells no other volume covers, own outside cells), or None when the trial
        // covers more outside cells of its own than `own_limit`, or more than `bound` that no
        // other volume covers (it cannot win then: stop counting early).
        let score = |v: &BoundingVolume, bound: usize| {
            if thin(v) {
                return None;
            }
            let (mut marginal, mut own) = (0usize, 0usize);
            let complete = outside_cells_while(grid, v, |c| {
                own += 1;
                if !cov_ref.covered(&c) {
                    marginal += 1;
                }
                own <= own_limit && marginal <= bound
            });
            visited.fetch_add(own as u64, Ordering::Relaxed);
            complete.then_some((marginal, own))
        };
        let current = &volumes[i];
        let marginal = cells[i].iter().filter(|c| !cov.covered(c)).count();
        let mut best = (
            current.clone(),
            (marginal, cells[i].len()),
            current.volume(),
        );
        let mut start = (current.shape == Shape::Ellipsoid && !thin(current)).then(|| best.clone());
        let better = |a: &(BoundingVolume, (usize, usize), f64), s: (usize, usize), vol: f64| {
            s < a.1 || (s == a.1 && vol < a.2 * (1.0 - 1e-9))
        };
        for v in fits(points[i], current.shape) {
            let Some(s) = score(&v, best.1 .0) else {
                continue;
            };
            let vol = v.volume();
            if v.shape == Shape::Ellipsoid && start.is_none() {
                start = Some((v.clone(), s, vol));
            }
            if better(&best, s, vol) {
                best = (v, s, vol);
            }
        }
        if let Some((from, _, _)) = start {
            let (v, s) = search(points[i], &from, min_r, score, &spent);
            let vol = v.volume();
            if better(&best, s, vol) {
                best = (v, s, vol);
            }
        }
        out[i] = best.0;
        if out[i] != volumes[i] {
            cells[i] = outside_cells(grid, &out[i]);
        }
        cov.add(&cells[i]);
    }
    (out, cells)
}

/// The ellipsoid with centre `c`, frame `axes` and semi-axes proportional to `radii`, scaled
/// about `c` so that the farthest of `points` lies on its surface (and no semi-axis is below
/// `min_r`).
fn hold(points: &[DVec3], c: DVec3, axes: DMat3, radii: DVec3, min_r: f64) -> BoundingVolume {
    let mut v = BoundingVolume {
        shape: Shape::Ellipsoid,
        center: c,
        axes,
        radii,
        polytope: None,
    };
    let g = points.iter().map(|&p| v.gauge(p)).fold(0.0, math::max);
    if g > 0.0 && g.is_finite() {
        v.radii *= g;
    }
    v.radii = v.radii.max(DVec3::splat(min_r));
    v
}

/// Compass search from `start` (which holds `points`) for the ellipsoid holding `points`
/// with the lowest `score`, compared lexicographically and then by volume (which must drop by
/// a relative 1e-9 to count). A trial scored `None` is rejected; `score` is told the best
/// first entry so far, and may give up (`None`) on a trial that exceeds it. Each round scores the 18
/// moves from the current best in parallel and takes the best of them (the first in move
/// order on ties), so the result does not depend on the thread count. Returns the best
/// volume and its score (`start`'s, `(usize::MAX, 0)`, when `start` itself is rejected).
fn search(
    points: &[DVec3],
    start: &BoundingVolume,
    min_r: f64,
    score: impl Fn(&BoundingVolume, usize) -> Option<(usize, usize)> + Sync + Send,
    spent: &dyn Fn() -> bool,
) -> (BoundingVolume, (usize, usize)) {
    let Some(mut best_s) = score(start, usize::MAX) else {
        return (start.clone(), (usize::MAX, 0));
    };
    let mut best = start.clone();
    let mut best_vol = best.volume();
    let mean_r = math::cbrt(start.radii.x * start.radii.y * start.radii.z);
    // Step sizes: centre (world units), log semi-axes, rotation angle (radians).
    let (mut dc, mut dr, mut da) = (0.25 * mean_r, 0.3f64, 0.2f64);
    let mut trials = 0usize;
    let mut level = 0;
    let moves: Vec<(usize, f64)> = (0..9).flat_map(|d| [(d, 1.0), (d, -1.0)]).collect();
    while level < LEVELS && trials < MAX_TRIALS && best_s.0 > 0 && !spent() {
        let from = best.clone();
        let trial = |&(dim, sign): &(usize, f64)| {
            let (mut c, mut axes, mut radii) = (from.center, from.axes, from.radii);
            match dim {
                0..=2 => c += from.axes.col(dim) * (sign * dc),
                3..=5 => radii[dim - 3] *= math::exp(sign * dr),
                _ => {
                    // `DQuat::from_axis_angle`, with the platform-independent sine.
                    let (s, c) = math::sin_cos(sign * da * 0.5);
                    let v = from.axes.col(dim - 6) * s;
                    let q = DQuat::from_xyzw(v.x, v.y, v.z, c);
                    axes = DMat3::from_quat(q) * axes;
                }
            }
            let v = hold(points, c, axes, radii, min_r);
            score(&v, best_s.0).map(|s| (s, v.volume(), v))
        };
        let scored = crate::parallel::map(&moves, trial);
        trials += moves.len();
        let mut improved = false;
        for (s, vol, v) in scored.into_iter().flatten() {
            if s < best_s || (s == best_s && vol < best_vol * (1.0 - 1e-9)) {
                (best, best_s, best_vol) = (v, s, vol);
                improved = true;
            }
        }
        if !improved {
            level += 1;
            dc *= 0.5;
            dr *= 0.5;
            da *= 0.5;
        }
    }
    (best, best_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::outside_volumes;
    use crate::sampling::Grid;

    /// A long cylinder along x, of radius `r`, sampled with cell size 1.
    fn cylinder(r: f64, half_len: f64) -> Solid {
        let lo = DVec3::new(-half_len, -r, -r);
        Solid::new(Grid::from_inside_fn(lo, -lo, 1.0, |p| {
            p.y * p.y + p.z * p.z <= r * r && p.x.abs() <= half_len
        }))
    }

    #[test]
    fn piece_of_a_cylinder_reaches_along_it_and_bulges_less() {
        let solid = cylinder(4.0, 40.0);
        let g = &solid.grid;
        // The middle piece |x| <= 6: its samples, and the surface circles at its ends.
        let mut pts: Vec<DVec3> = g
            .points
            .iter()
            .copied()
            .filter(|p| p.x.abs() <= 6.0)
            .collect();
        for i in 0..64 {
            let a = i as f64 * std::f64::consts::TAU / 64.0;
            for x in [-6.0, 6.0] {
                pts.push(DVec3::new(x, 4.0 * a.cos(), 4.0 * a.sin()));
            }
        }
        let n = pts.len() as f64 - 128.0;
        let hull = crate::bounding::hull::hull_points(&pts);
        let mvee = crate::bounding::mvee::mvee_of_hull(&hull, 1e-4, 0.5);
        let before = outside_volumes(g, std::slice::from_ref(&mvee), &[n]).ov[0];
        let cells = vec![outside_cells(g, &mvee)];
        let after_v = reshape(
            &solid,
            &[&hull],
            std::slice::from_ref(&mvee),
            cells,
            &[n],
            (0.5, u64::MAX),
            &|_, _| Vec::new(),
        )
        .0[0]
            .clone();
        let after = outside_volumes(g, std::slice::from_ref(&after_v), &[n]).ov[0];
        // The minimum-volume ellipsoid bulges by about 1/3 (more on the lattice); the reshaped
        // one reaches along the cylinder and bulges far less.
        assert!(before > 0.25, "MVEE OV {before}");
        assert!(after < 0.5 * before, "OV {before} -> {after}");
        assert!(after_v.radii.max_element() > mvee.radii.max_element());
        for &p in &pts {
            assert!(after_v.gauge(p) <= 1.0 + 1e-9, "point {p} escapes");
        }
    }

    #[test]
    fn never_raises_tov_or_mov() {
        // Two overlapping pieces of a bent solid: an L of two bars.
        let solid = Solid::new(Grid::from_inside_fn(
            DVec3::splat(-1.0),
            DVec3::new(20.0, 20.0, 4.0),
            1.0,
            |p| {
                let bar1 = p.x >= 0.0 && p.x <= 20.0 && p.y >= 0.0 && p.y <= 4.0;
                let bar2 = p.x >= 0.0 && p.x <= 4.0 && p.y >= 0.0 && p.y <= 20.0;
                (bar1 || bar2) && p.z >= 0.0 && p.z <= 4.0
            },
        ));
        let g = &solid.grid;
        let part = |f: &dyn Fn(DVec3) -> bool| -> Vec<DVec3> {
            g.points.iter().copied().filter(|&p| f(p)).collect()
        };
        let a = part(&|p| p.y <= 4.0 && p.x > 4.0);
        let b = part(&|p| p.x <= 4.0);
        let ha = crate::bounding::hull::hull_points(&a);
        let hb = crate::bounding::hull::hull_points(&b);
        let va = crate::bounding::mvee::mvee_of_hull(&ha, 1e-4, 0.5);
        let vb = crate::bounding::mvee::mvee_of_hull(&hb, 1e-4, 0.5);
        let counts = [a.len() as f64, b.len() as f64];
        let before = outside_volumes(g, &[va.clone(), vb.clone()], &counts);
        let cells = vec![outside_cells(g, &va), outside_cells(g, &vb)];
        let (new, _) = reshape(
            &solid,
            &[&ha, &hb],
            &[va, vb],
            cells,
            &counts,
            (0.5, u64::MAX),
            &|_, _| Vec::new(),
        );
        let after = outside_volumes(g, &new, &counts);
        // The bars' volumes can reach along them into each other's space (measured: TOV
        // 0.736 -> 0.707).
        assert!(after.tov < before.tov, "{} -> {}", before.tov, after.tov);
        for i in 0..2 {
            assert!(
                after.ov[i] <= before.ov[i],
                "{i}: {:?} -> {:?}",
                before.ov,
                after.ov
            );
        }
        for (v, pts) in new.iter().zip([&a, &b]) {
            assert!(pts.iter().all(|&p| v.gauge(p) <= 1.0 + 1e-9));
        }
    }

    #[test]
    fn a_part_takes_the_kind_that_adds_least_to_the_union() {
        // A bar; a large ball (another part's volume, held fixed) covers most of the space
        // around it, and the end part's box sticks out beyond the ball where a smaller ball,
        // inside the large one, would not.
        let solid = Solid::new(Grid::from_inside_fn(
            DVec3::splat(-1.0),
            DVec3::new(21.0, 5.0, 5.0),
            1.0,
            |p| p.x >= 0.0 && p.x <= 20.0 && p.y >= 0.0 && p.y <= 4.0 && p.z >= 0.0 && p.z <= 4.0,
        ));
        let g = &solid.grid;
        let end: Vec<DVec3> = g.points.iter().copied().filter(|p| p.x >= 18.0).collect();
        let big = BoundingVolume::sphere(DVec3::new(10.0, 2.0, 2.0), 12.5);
        let boxed = BoundingVolume::frame(
            Shape::Obb,
            DVec3::new(20.0, 2.0, 2.0),
            DMat3::IDENTITY,
            DVec3::splat(3.0),
        );
        let ball = BoundingVolume::sphere(DVec3::new(18.5, 2.0, 2.0), 3.3);
        assert!(end.iter().all(|&p| boxed.contains(p) && ball.contains(p)));
        let counts = [(g.points.len() - end.len()) as f64, end.len() as f64];
        let volumes = [big, boxed];
        let before = outside_volumes(g, &volumes, &counts);
        let cells = volumes.iter().map(|v| outside_cells(g, v)).collect();
        let offered = ball.clone();
        let (new, _) = reshape(
            &solid,
            &[&[], &end],
            &volumes,
            cells,
            &counts,
            (0.5, u64::MAX),
            &|_, except| {
                assert_eq!(except, Shape::Obb);
                vec![offered.clone()]
            },
        );
        assert_eq!(new[0], volumes[0], "a part without points stays as it is");
        assert_eq!(new[1], ball, "the ball adds nothing outside the union");
        let after = outside_volumes(g, &new, &counts);
        assert!(after.tov < before.tov, "{} -> {}", before.tov, after.tov);
    }
}
