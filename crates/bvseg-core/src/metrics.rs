//! Stage 8: outside volumes, counted on the sampling lattice (paper section 5).
//!
//! A lattice cell is inside the solid iff it is a sample; every other cell of the
//! (unbounded) lattice is outside. For each bounding volume, the cells whose centres it
//! contains are enumerated column by column (each column meets a convex volume in one
//! interval, found in closed form), so the cost is the number of cells covered.
//!
//! - `TOV = #(cells outside S in the union) / #samples`
//! - `OV_i = #(cells outside S in volume i) / #samples of part i`, `MOV = max_i OV_i`
use glam::DVec3;

use crate::sampling::{Grid, NONE};
use crate::volume::{BoundingVolume, Shape};

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

/// The range of `t` with `|a + t b| <= 1` for the ellipsoid (`|.|` Euclidean) or box (`|.|`
/// max norm), or `None`.
#[inline]
fn interval(shape: Shape, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
    match shape {
        Shape::Ellipsoid => {
            let bb = b.length_squared();
            let ab = a.dot(b);
            let disc = ab * ab - bb * (a.length_squared() - 1.0);
            if disc < 0.0 || bb <= 0.0 {
                return None;
            }
            let r = disc.sqrt();
            Some(((-ab - r) / bb, (-ab + r) / bb))
        }
        Shape::Obb => {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for j in 0..3 {
                if b[j].abs() < 1e-300 {
                    if a[j].abs() > 1.0 {
                        return None;
                    }
                } else {
                    let t0 = (-1.0 - a[j]) / b[j];
                    let t1 = (1.0 - a[j]) / b[j];
                    lo = lo.max(t0.min(t1));
                    hi = hi.min(t0.max(t1));
                }
            }
            (lo <= hi).then_some((lo, hi))
        }
    }
}

/// Call `f(i, j, k)` for every lattice cell whose centre lies in `v`.
pub fn for_each_cell(grid: &Grid, v: &BoundingVolume, mut f: impl FnMut(i64, i64, i64)) {
    let (lo, hi) = v.aabb();
    let h = grid.h;
    let to_l = |p: DVec3| (p - grid.origin) / h;
    let (l0, l1) = (to_l(lo), to_l(hi));
    let (i0, i1) = (l0.x.ceil() as i64, l1.x.floor() as i64);
    let (j0, j1) = (l0.y.ceil() as i64, l1.y.floor() as i64);
    // Local coordinates of a cell centre are affine in (i, j, k): t = base + i di + j dj + k dk.
    let inv_r = 1.0 / v.radii;
    let at = v.axes.transpose();
    let base = (at * (grid.origin - v.center)) * inv_r;
    let di = (at * DVec3::X) * h * inv_r;
    let dj = (at * DVec3::Y) * h * inv_r;
    let dk = (at * DVec3::Z) * h * inv_r;
    for j in j0..=j1 {
        for i in i0..=i1 {
            let a = base + di * i as f64 + dj * j as f64;
            if let Some((t0, t1)) = interval(v.shape, a, dk) {
                // A hair of slack so that cells exactly on the boundary count as inside,
                // matching `BoundingVolume::contains`.
                let k0 = (t0 - 1e-9).ceil() as i64;
                let k1 = (t1 + 1e-9).floor() as i64;
                for k in k0..=k1 {
                    f(i, j, k);
                }
            }
        }
    }
}

/// Lattice cells outside the solid whose centres `v` contains.
pub fn outside_cells(grid: &Grid, v: &BoundingVolume) -> Vec<[i64; 3]> {
    let mut out = Vec::new();
    for_each_cell(grid, v, |i, j, k| {
        if grid.sample_at(i, j, k) == NONE {
            out.push([i, j, k]);
        }
    });
    out
}

/// TOV, OV and MOV of `volumes`, where volume `i` bounds a part of `counts[i]` samples.
pub fn outside_volumes(grid: &Grid, volumes: &[BoundingVolume], counts: &[f64]) -> Outside {
    let per: Vec<Vec<[i64; 3]>> = crate::parallel::map(volumes, |v| outside_cells(grid, v));
    outside_from_cells(
        &per.iter().map(|c| c.as_slice()).collect::<Vec<_>>(),
        counts,
    )
}

/// TOV, OV and MOV from each volume's outside cells (see [`outside_cells`]).
pub fn outside_from_cells(per: &[&[[i64; 3]]], counts: &[f64]) -> Outside {
    let total: f64 = counts.iter().sum();
    let ov: Vec<f64> = per
        .iter()
        .zip(counts)
        .map(|(c, &n)| c.len() as f64 / n.max(1.0))
        .collect();
    let mov = ov.iter().copied().fold(0.0, f64::max);
    // The union: mark cells in a bitmap over the box of all outside cells.
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for c in per.iter().copied().flatten() {
        for d in 0..3 {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
    }
    let mut union = 0usize;
    if lo[0] <= hi[0] {
        let n = [
            (hi[0] - lo[0] + 1) as usize,
            (hi[1] - lo[1] + 1) as usize,
            (hi[2] - lo[2] + 1) as usize,
        ];
        let mut bits = vec![0u64; (n[0] * n[1] * n[2]).div_ceil(64)];
        for c in per.iter().copied().flatten() {
            let idx = (c[0] - lo[0]) as usize
                + n[0] * ((c[1] - lo[1]) as usize + n[1] * (c[2] - lo[2]) as usize);
            let (w, b) = (idx / 64, idx % 64);
            if bits[w] & (1 << b) == 0 {
                bits[w] |= 1 << b;
                union += 1;
            }
        }
    }
    Outside {
        tov: union as f64 / total.max(1.0),
        ov,
        mov,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

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
        };
        let o = outside_volumes(&g, &[v], &[g.len() as f64]);
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
        };
        // 11^3 cell centres in the box, one of them the sample.
        let o = outside_volumes(&g, &[v, v], &[1.0, 1.0]);
        assert_eq!(o.ov, vec![1330.0, 1330.0]);
        assert_eq!(o.tov, 665.0);
    }
}
