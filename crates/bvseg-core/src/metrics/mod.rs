//! Stage 8: outside volumes, counted on the sampling lattice (paper section 5).
//!
//! A lattice cell is inside the solid iff it is a sample; every other cell of the
//! (unbounded) lattice is outside. For each bounding volume, the cells whose centres it
//! contains are enumerated column by column (each column meets a convex volume in one
//! interval, found in closed form), so the cost is the number of cells covered.
//!
//! Beyond the paper, the count runs over two lattices: the sampling lattice and the one
//! offset from it by half a cell along every axis (see [`crate::sampling`]), and the outside
//! volume is the mean of the two counts. The volumes are fitted to points of the sampling
//! lattice, so on it alone their surfaces fall on cell centres more often than chance would
//! have it, and the count reads low (20 % on boxes around the shared chair's slabs); the
//! offset lattice has none of the fitted points. With `n` samples in the solid and `n_i` in
//! part `i`:
//!
//! - `TOV = #(outside cells of both lattices in the union) / (2 n)`
//! - `OV_i = #(outside cells of both lattices in volume i) / (2 n_i)`, `MOV = max_i OV_i`
//!
//! One list holds a volume's outside cells of both lattices, as runs of [`Cell`]s along the
//! columns ([`Cells`]); [`Coverage`] keeps the union's count as volumes change.
mod cell;
mod coverage;
mod protrusion;
mod surface;

pub use cell::{Cell, Cells};
pub use coverage::Coverage;
pub use protrusion::{protrusion_capped, surface_protrusion, surface_protrusion_exceeds};
pub use surface::SurfaceDistance;

use glam::DVec3;

use crate::math::{self, ceil_i64, floor_i64};
use crate::sampling::{Grid, InsideRuns};
use crate::volume::{BoundingVolume, PlanesAlong, Shape};

/// Outside-volume figures of a set of volumes.
#[derive(Debug, Clone, PartialEq)]
pub struct Outside {
    /// Total outside volume relative to the solid's volume.
    pub tov: f64,
    /// Per-volume outside volume relative to its part's volume.
    pub ov: Vec<f64>,
    /// Largest `ov`.
    pub mov: f64,
}

/// The ranges of `k` with `a + k b` (local coordinates) inside the unit shape of a volume,
/// for one direction `b` and many `a` (the columns of a lattice): what depends on `b` alone
/// is computed once.
struct Along<'a> {
    v: &'a BoundingVolume,
    b: DVec3,
    /// `sum_j w_j b_j^2` of the shape's quadratic: the ellipsoid's or the cylinder's (also
    /// the capsule's middle).
    bb: f64,
    /// A capsule's ends: their weights and `sum_j w_j b_j^2`.
    ends: (DVec3, f64),
    /// A hull's face planes prepared for `b`.
    planes: Option<PlanesAlong>,
}

/// `sum_j w_j b_j^2`.
#[inline]
fn weighted_square(b: DVec3, w: DVec3) -> f64 {
    (b * b * w).element_sum()
}

const ACROSS: DVec3 = DVec3::new(1.0, 1.0, 0.0);

impl<'a> Along<'a> {
    fn new(v: &'a BoundingVolume, b: DVec3) -> Self {
        let bb = match v.shape {
            Shape::Ellipsoid | Shape::Sphere => weighted_square(b, DVec3::ONE),
            Shape::Cylinder | Shape::Capsule => weighted_square(b, ACROSS),
            Shape::Obb | Shape::Hull => 0.0,
        };
        let ends = if v.shape == Shape::Capsule {
            // End balls of radius 1 across and 1 / l along, in the local scale.
            let l = v.radii.z / v.radii.x;
            let w = DVec3::new(1.0, 1.0, l * l);
            (w, weighted_square(b, w))
        } else {
            (DVec3::ZERO, 0.0)
        };
        let planes = v.polytope().map(|p| p.planes_along(b));
        Self {
            v,
            b,
            bb,
            ends,
            planes,
        }
    }

    /// The range of `k` with `a + k b` inside the shape, or `None`.
    #[inline]
    fn interval(&self, a: DVec3) -> Option<(f64, f64)> {
        let b = self.b;
        match self.v.shape {
            Shape::Ellipsoid | Shape::Sphere => quadratic(a, b, DVec3::ONE, self.bb),
            Shape::Obb => slabs(a, b, [true; 3]),
            Shape::Cylinder => self.cylinder(a),
            Shape::Capsule => {
                // The middle cylinder and the two end balls; the capsule is convex, so their
                // union is one interval.
                let (w, bb) = self.ends;
                let ends = [1.0, -1.0].map(|s| quadratic(a - DVec3::new(0.0, 0.0, s), b, w, bb));
                self.cylinder(a)
                    .into_iter()
                    .chain(ends.into_iter().flatten())
                    .reduce(|x, y| (math::min(x.0, y.0), math::max(x.1, y.1)))
            }
            Shape::Hull => self.planes.as_ref().and_then(|p| p.interval(a)),
        }
    }

    #[inline]
    fn cylinder(&self, a: DVec3) -> Option<(f64, f64)> {
        let (l0, h0) = quadratic(a, self.b, ACROSS, self.bb)?;
        let (l1, h1) = slabs(a, self.b, [false, false, true])?;
        let (lo, hi) = (math::max(l0, l1), math::min(h0, h1));
        (lo <= hi).then_some((lo, hi))
    }
}

/// The range of `k` with `sum_j w_j (a_j + k b_j)^2 <= 1`, or `None` (also when the line runs
/// along a direction the weights ignore and the rest is inside: the caller bounds it); `bb`
/// is [`weighted_square`]`(b, w)`.
#[inline]
fn quadratic(a: DVec3, b: DVec3, w: DVec3, bb: f64) -> Option<(f64, f64)> {
    let ab = (a * b * w).element_sum();
    let aa = (a * a * w).element_sum();
    if bb <= 0.0 {
        return (aa <= 1.0).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let disc = ab * ab - bb * (aa - 1.0);
    if disc < 0.0 {
        return None;
    }
    let r = disc.sqrt();
    Some(((-ab - r) / bb, (-ab + r) / bb))
}

/// The range of `k` with `|a_j + k b_j| <= 1` for the coordinates `j` that `which` names.
#[inline]
fn slabs(a: DVec3, b: DVec3, which: [bool; 3]) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for j in (0..3).filter(|&j| which[j]) {
        if b[j].abs() < 1e-300 {
            if a[j].abs() > 1.0 {
                return None;
            }
        } else {
            let t0 = (-1.0 - a[j]) / b[j];
            let t1 = (1.0 - a[j]) / b[j];
            lo = math::max(lo, math::min(t0, t1));
            hi = math::min(hi, math::max(t0, t1));
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Number of lattices the outside volume is counted on.
pub const LATTICES: f64 = 2.0;

/// Outside volume relative to a part of `n` samples, from its number of outside cells of
/// both lattices.
#[inline]
pub fn relative(cells: usize, n: f64) -> f64 {
    cells as f64 / (LATTICES * math::max(n, 1.0))
}

/// Call `f(i, j, k)` for every cell of the sampling lattice whose centre lies in `v`.
#[cfg(test)]
pub fn for_each_cell(grid: &Grid, v: &BoundingVolume, mut f: impl FnMut(i64, i64, i64)) {
    columns_in(grid.origin, grid.h, v, |i, j, k0, k1| {
        for k in k0..=k1 {
            f(i, j, k);
        }
        true
    });
}

/// [`outside_cells_while`] to the end.
#[cfg(test)]
pub fn for_each_outside_cell(grid: &Grid, v: &BoundingVolume, mut f: impl FnMut(Cell)) {
    outside_cells_while(grid, v, |c| {
        f(c);
        true
    });
}

/// Call `f(cell)` for every cell of either lattice outside the solid whose centre lies in
/// `v`, in the order of [`outside_cells`], stopping after the first column during which `f`
/// returned `false`. Returns whether every cell was visited.
pub fn outside_cells_while(
    grid: &Grid,
    v: &BoundingVolume,
    mut f: impl FnMut(Cell) -> bool,
) -> bool {
    let mut go = true;
    for (offset, origin, runs) in lattices(grid) {
        let done = columns_in(origin, grid.h, v, |i, j, k0, k1| {
            runs.for_each_gap([i, j], [k0, k1], |a, b| {
                (a..=b).for_each(|k| go &= f(Cell::of(offset, [i, j, k])));
            });
            go
        });
        if !done {
            return false;
        }
    }
    true
}

/// The two lattices outside volumes are counted on (see the module docs), the sampling one
/// first: whether it is the offset one, its origin, and the solid's inside runs on it.
fn lattices(grid: &Grid) -> [(bool, DVec3, &InsideRuns); 2] {
    let [sampling, offset] = &grid.inside_runs;
    [
        (false, grid.origin, sampling),
        (true, grid.origin + DVec3::splat(0.5 * grid.h), offset),
    ]
}

/// Call `f(i, j, k0, k1)` for every column `(i, j)` of the lattice `origin + h (i, j, k)` that
/// meets `v`, with the range `k0..=k1` of its points in `v`, until `f` returns `false`.
/// Returns whether every column was visited.
fn columns_in(
    origin: DVec3,
    h: f64,
    v: &BoundingVolume,
    mut f: impl FnMut(i64, i64, i64, i64) -> bool,
) -> bool {
    let (lo, hi) = v.aabb();
    let to_l = |p: DVec3| (p - origin) / h;
    let (l0, l1) = (to_l(lo), to_l(hi));
    let (i0, i1) = (ceil_i64(l0.x), floor_i64(l1.x));
    let (j0, j1) = (ceil_i64(l0.y), floor_i64(l1.y));
    // Local coordinates of a cell centre are affine in (i, j, k): t = base + i di + j dj + k dk.
    let inv_r = 1.0 / v.radii;
    let at = v.axes.transpose();
    let base = (at * (origin - v.center)) * inv_r;
    let di = (at * DVec3::X) * h * inv_r;
    let dj = (at * DVec3::Y) * h * inv_r;
    let dk = (at * DVec3::Z) * h * inv_r;
    let along = Along::new(v, dk);
    for j in j0..=j1 {
        for i in i0..=i1 {
            let a = base + di * i as f64 + dj * j as f64;
            if let Some((t0, t1)) = along.interval(a) {
                // A hair of slack so that cells exactly on the boundary count as inside,
                // matching `BoundingVolume::contains`.
                let k0 = ceil_i64(t0 - 1e-9);
                let k1 = floor_i64(t1 + 1e-9);
                if k0 <= k1 && !f(i, j, k0, k1) {
                    return false;
                }
            }
        }
    }
    true
}

/// Number of cells of both lattices outside the solid whose centres `v` contains: the
/// length of [`outside_cells`], counted per column from the solid's runs.
pub fn outside_count(grid: &Grid, v: &BoundingVolume) -> usize {
    let mut n = 0;
    for (_, origin, runs) in lattices(grid) {
        columns_in(origin, grid.h, v, |i, j, k0, k1| {
            n += (k1 - k0 + 1) as usize - runs.count([i, j], [k0, k1]);
            true
        });
    }
    n
}

/// Cells of both lattices outside the solid whose centres `v` contains, as runs up the
/// columns: the gaps between the solid's inside runs within the volume's interval of each
/// column, the sampling lattice's columns first.
pub fn outside_cells(grid: &Grid, v: &BoundingVolume) -> Cells {
    let mut out = Cells::default();
    for (offset, origin, runs) in lattices(grid) {
        columns_in(origin, grid.h, v, |i, j, k0, k1| {
            runs.for_each_gap([i, j], [k0, k1], |a, b| {
                out.push_run(offset, [i, j], [a, b])
            });
            true
        });
    }
    // The fit cache keeps these lists: no more memory than they hold (a growing vector ends
    // up to twice that).
    out.shrink_to_fit();
    out
}

/// TOV, OV and MOV of `volumes`, where volume `i` bounds a part of `counts[i]` samples.
pub fn outside_volumes(grid: &Grid, volumes: &[BoundingVolume], counts: &[f64]) -> Outside {
    let per: Vec<Cells> = crate::parallel::map(volumes, |v| outside_cells(grid, v));
    outside_from_cells(&per.iter().collect::<Vec<_>>(), counts)
}

/// TOV, OV and MOV from each volume's outside cells (see [`outside_cells`]).
pub fn outside_from_cells(per: &[&Cells], counts: &[f64]) -> Outside {
    let total: f64 = counts.iter().sum();
    let ov: Vec<f64> = per
        .iter()
        .zip(counts)
        .map(|(c, &n)| relative(c.len(), n))
        .collect();
    let mov = ov.iter().copied().fold(0.0, math::max);
    let union = distinct(per, false) + distinct(per, true);
    Outside {
        tov: relative(union, total),
        ov,
        mov,
    }
}

/// Number of distinct cells of one lattice (the offset one if `offset`) in `per`, marked in a
/// bitmap over their bounding box. The third index is the bitmap's fastest, so that a run of
/// cells up a column sets whole words at a time.
fn distinct(per: &[&Cells], offset: bool) -> usize {
    let runs = || {
        per.iter()
            .flat_map(|c| c.runs())
            .filter(move |(c, _)| c.is_offset() == offset)
            .map(|&(c, len)| (c.index(), u64::from(len)))
    };
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for (c, len) in runs() {
        for d in 0..3 {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
        hi[2] = hi[2].max(c[2] + len as i64 - 1);
    }
    if lo[0] > hi[0] {
        return 0;
    }
    let n = [
        (hi[0] - lo[0] + 1) as usize,
        (hi[1] - lo[1] + 1) as usize,
        (hi[2] - lo[2] + 1) as usize,
    ];
    let mut bits = vec![0u64; (n[0] * n[1] * n[2]).div_ceil(64)];
    for (c, len) in runs() {
        let first = (c[2] - lo[2]) as usize
            + n[2] * ((c[1] - lo[1]) as usize + n[1] * (c[0] - lo[0]) as usize);
        let (mut i, end) = (first, first + len as usize);
        while i < end {
            let (w, b) = (i / 64, i % 64);
            let take = (64 - b).min(end - i);
            bits[w] |= (u64::MAX >> (64 - take)) << b;
            i += take;
        }
    }
    bits.iter().map(|w| w.count_ones() as usize).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    /// One volume of every kind, tilted and off-centre.
    fn every_kind() -> Vec<BoundingVolume> {
        let axes = DMat3::from_euler(glam::EulerRot::XYZ, 0.4, -0.3, 0.9);
        let c = DVec3::new(0.13, -0.07, 0.21);
        let mut hull_pts = Vec::new();
        for i in 0..9 {
            let a = i as f64 * 2.4;
            hull_pts.push(c + DVec3::new(a.cos(), a.sin() * 0.6, (i as f64 / 4.0) - 1.0));
        }
        vec![
            BoundingVolume::frame(Shape::Ellipsoid, c, axes, DVec3::new(1.1, 0.6, 0.4)),
            BoundingVolume::frame(Shape::Obb, c, axes, DVec3::new(0.9, 0.5, 0.3)),
            BoundingVolume::sphere(c, 0.8),
            BoundingVolume::capsule(c, axes.x_axis, 0.7, 0.35),
            BoundingVolume::capsule(c, axes.y_axis, 0.0, 0.6),
            BoundingVolume::cylinder(c, axes.z_axis, 0.6, 0.45),
            BoundingVolume::hull(&hull_pts).unwrap(),
        ]
    }

    #[test]
    fn the_count_of_outside_cells_is_the_length_of_their_list() {
        // A holey solid, so columns hold several runs; volumes reaching past the lattice.
        let g = Grid::from_inside_fn(DVec3::splat(-0.6), DVec3::splat(0.6), 0.04, |p| {
            p.length() <= 0.6 && (p * 9.0).x.sin() * (p * 7.0).z.cos() < 0.4
        });
        for v in every_kind() {
            for s in [0.3, 0.7, 1.0, 1.6] {
                let mut w = v.clone();
                w.radii *= s;
                let cells = outside_cells(&g, &w);
                assert_eq!(outside_count(&g, &w), cells.len(), "{:?} x {s}", w.shape);
                // The runs hold the cells the walk visits, in its order.
                let mut walk = Vec::new();
                for_each_outside_cell(&g, &w, |c| walk.push(c));
                assert_eq!(
                    cells.iter().collect::<Vec<_>>(),
                    walk,
                    "{:?} x {s}",
                    w.shape
                );
            }
        }
    }

    #[test]
    fn every_kind_scans_columns_as_its_point_test_says() {
        let h = 0.05;
        let g = Grid::from_inside_fn(DVec3::splat(-0.2), DVec3::splat(0.2), h, |p| {
            p.length() <= 0.2
        });
        for v in every_kind() {
            // The column scan against the inside test at every lattice point of the box.
            let mut scanned = std::collections::HashSet::new();
            for_each_cell(&g, &v, |i, j, k| {
                scanned.insert((i, j, k));
            });
            let (lo, hi) = v.aabb();
            let (l, u) = ((lo - g.origin) / h, (hi - g.origin) / h);
            let mut brute = std::collections::HashSet::new();
            for k in (l.z.floor() as i64 - 1)..=(u.z.ceil() as i64 + 1) {
                for j in (l.y.floor() as i64 - 1)..=(u.y.ceil() as i64 + 1) {
                    for i in (l.x.floor() as i64 - 1)..=(u.x.ceil() as i64 + 1) {
                        let p = g.origin + DVec3::new(i as f64, j as f64, k as f64) * h;
                        let inside = v.contains(p);
                        assert_eq!(inside, v.gauge(p) <= 1.0 + 1e-9, "{:?} at {p}", v.shape);
                        if inside {
                            brute.insert((i, j, k));
                        }
                    }
                }
            }
            let diff = scanned.symmetric_difference(&brute).count();
            // Points within round-off of the boundary may go either way.
            assert!(
                diff <= 2,
                "{:?}: {diff} cells differ of {}",
                v.shape,
                brute.len()
            );
            // The count is the volume.
            let vol = brute.len() as f64 * h * h * h;
            assert!(
                (vol / v.volume() - 1.0).abs() < 0.03,
                "{:?}: {vol} vs {}",
                v.shape,
                v.volume()
            );
            // The box holds the boundary, and scaling divides the gauge.
            let p = v.center + DVec3::new(0.3, -0.2, 0.5);
            let mut big = v.clone();
            big.radii *= 2.0;
            assert!((big.gauge(p) * 2.0 - v.gauge(p)).abs() < 1e-9 * math::max(v.gauge(p), 1.0));
            let g2 = v.clone().grown(0.1);
            for t in [DVec3::X, DVec3::Y, DVec3::Z, -DVec3::ONE.normalize()] {
                // A point 0.1 out from the boundary along a ray from the centre is in the
                // grown volume.
                let g0 = v.gauge(v.center + t);
                let q = v.center + t / g0;
                assert!(
                    g2.contains(q + t.normalize() * 0.0999),
                    "{:?} grown",
                    v.shape
                );
            }
        }
    }

    #[test]
    fn ball_in_cube_outside_volume() {
        // A cube solid [-1, 1]^3 wrapped in its circumscribed ball: TOV = (sqrt 3)^3 pi 4/3 / 8 - 1.
        let h = 0.05;
        let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), h, |p| {
            p.abs().max_element() <= 1.0
        });
        let v = BoundingVolume {
            shape: Shape::Ellipsoid,
            center: DVec3::ZERO,
            axes: DMat3::IDENTITY,
            radii: DVec3::splat(3f64.sqrt()),
            polytope: None,
        };
        let o = outside_volumes(&g, std::slice::from_ref(&v), &[g.len() as f64]);
        let expect = 4.0 / 3.0 * std::f64::consts::PI * 3f64.powf(1.5) / 8.0 - 1.0;
        assert!((o.tov - expect).abs() < 0.02, "{} vs {expect}", o.tov);
        assert_eq!(o.tov, o.mov);
        // Cell enumeration agrees with the point test.
        let mut n = 0;
        for_each_cell(&g, &v, |i, j, k| {
            assert!(v.contains(g.cell_center(i, j, k)));
            n += 1;
        });
        let c = g.cell_of(DVec3::ZERO);
        let r = 40;
        let brute = (c[2] - r..=c[2] + r)
            .flat_map(|k| {
                (c[1] - r..=c[1] + r)
                    .flat_map(move |j| (c[0] - r..=c[0] + r).map(move |i| (i, j, k)))
            })
            .filter(|&(i, j, k)| v.contains(g.cell_center(i, j, k)))
            .count();
        assert_eq!(n, brute);
        // So does the offset lattice's: its outside cells are those of its centres that are
        // in the ball but not in the cube.
        let half = DVec3::splat(0.5 * h);
        let offset_cells: Vec<Cell> = outside_cells(&g, &v)
            .iter()
            .filter(Cell::is_offset)
            .collect();
        let brute = (c[2] - r..=c[2] + r)
            .flat_map(|k| {
                (c[1] - r..=c[1] + r)
                    .flat_map(move |j| (c[0] - r..=c[0] + r).map(move |i| (i, j, k)))
            })
            .filter(|&(i, j, k)| {
                let p = g.cell_center(i, j, k) + half;
                v.contains(p) && p.abs().max_element() > 1.0
            })
            .count();
        assert_eq!(offset_cells.len(), brute);
    }

    /// Runs of every length, across bitmap words and overlapping between lists and lattices,
    /// counted as a set of cells would count them.
    #[test]
    fn distinct_counts_each_cell_once_whatever_its_runs() {
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..50 {
            let lists: Vec<Cells> = (0..3)
                .map(|_| {
                    let mut c = Cells::default();
                    for _ in 0..rng.below(12) {
                        let (i, j) = (rng.below(4) as i64 - 2, rng.below(3) as i64);
                        let a = rng.below(150) as i64 - 40;
                        let b = a + rng.below(140) as i64 - 2;
                        c.push_run(rng.below(2) == 1, [i, j], [a, b]);
                    }
                    c
                })
                .collect();
            let per: Vec<&Cells> = lists.iter().collect();
            for offset in [false, true] {
                let brute: std::collections::HashSet<[i64; 3]> = lists
                    .iter()
                    .flat_map(Cells::iter)
                    .filter(|c| c.is_offset() == offset)
                    .map(|c| c.index())
                    .collect();
                assert_eq!(distinct(&per, offset), brute.len());
            }
        }
    }

    #[test]
    fn union_counts_overlap_once() {
        let h = 0.1;
        let g = Grid::from_inside_fn(DVec3::ZERO, DVec3::ZERO, h, |p| p.length() < 0.01);
        assert_eq!(g.len(), 1);
        let v = BoundingVolume {
            shape: Shape::Obb,
            center: DVec3::ZERO,
            axes: DMat3::IDENTITY,
            radii: DVec3::splat(0.55),
            polytope: None,
        };
        // 11^3 cell centres in the box, one of them the sample, and 12^3 of the offset
        // lattice (at odd multiples of h / 2), none inside.
        let o = outside_volumes(&g, &[v.clone(), v.clone()], &[1.0, 1.0]);
        let cells = 1330.0 + 1728.0;
        assert_eq!(o.ov, vec![cells / 2.0, cells / 2.0]);
        assert_eq!(o.tov, cells / 4.0);
    }
}
