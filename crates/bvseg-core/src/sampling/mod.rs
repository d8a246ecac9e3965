//! Stage 1: uniform grid samples inside the solid.
//!
//! The solid is sampled by the centres of the cells of a regular grid that lie inside the
//! mesh (see [`inside`] for the inside test). Each sample stands for one cube cell of side
//! `h`, so it carries weight `h^3` and the per-cell covariance `h^2/12 I`. Cells outside the
//! mesh are implicit: any lattice cell that is not a sample is outside the solid, which is
//! how the metrics measure outside volume.
//!
//! The grid also classifies the centres of a second lattice, offset by half a cell along
//! every axis (the corners of the first one's cells). The output volumes are fitted to
//! points on the first lattice (samples and the centres of shared cell faces), so their
//! surfaces pass through its cell centres far more often than chance: counted there alone,
//! the outside volume of boxes around thin slabs came out up to 20 % below an independent
//! measurement. The metrics count both lattices (see [`crate::metrics`]).
pub mod distance;
pub mod inside;
mod runs;
mod shells;

pub use runs::InsideRuns;

use crate::math;
use glam::DVec3;

use crate::{Error, Mesh, NoVolume};

/// Marker for "no sample" in index arrays.
pub const NONE: u32 = u32::MAX;

/// The sampling lattice and its interior samples.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Centre of cell `(0, 0, 0)`.
    pub origin: DVec3,
    /// Cell size.
    pub h: f64,
    /// Number of cells along x, y, z.
    pub dims: [usize; 3],
    /// For each cell (`i + nx * (j + ny * k)`), its sample index or [`NONE`] when outside.
    pub sample_of_cell: Vec<u32>,
    /// For each sample, its cell coordinates.
    pub coords: Vec<[u32; 3]>,
    /// For each sample, its position (the cell centre).
    pub points: Vec<DVec3>,
    /// For each sample, its face neighbours (-x, +x, -y, +y, -z, +z) that are samples, or [`NONE`].
    pub neighbors: Vec<[u32; 6]>,
    /// The inside cells of the sampling lattice and of the offset one, as runs per column
    /// (for counting and listing a volume's outside cells column by column). Cell `(i, j, k)`
    /// of the offset lattice (`0 <= i <= nx` and so on) has its centre at
    /// `origin + h (i + 1/2, j + 1/2, k + 1/2)`; the runs are all that is kept of it.
    pub inside_runs: [InsideRuns; 2],
}

impl Grid {
    /// Sample the solid bounded by `mesh` with about `target` interior samples.
    ///
    /// The cell size starts from the mesh's enclosed volume (`h = (V / n)^(1/3)`) and is
    /// corrected once from the count actually found, so open or oddly oriented meshes, whose
    /// signed volume says little, still get close to `target`.
    ///
    /// # Errors
    ///
    /// [`Error::NoVolume`] when no cell lies inside, [`Error::TooComplex`] when the inside
    /// test would exceed its work bound.
    pub fn from_mesh(mesh: &Mesh, target: usize) -> Result<Self, Error> {
        let (lo, hi) = mesh.bbox();
        let ext = hi - lo;
        if ext.min_element() <= 0.0 || !ext.is_finite() {
            return Err(Error::NoVolume(NoVolume::FlatBox {
                extent: ext.to_array(),
            }));
        }
        let box_vol = ext.x * ext.y * ext.z;
        let mut vol = mesh.signed_volume().abs();
        if vol.is_nan() || vol <= box_vol * 1e-9 || vol > box_vol {
            vol = box_vol * 0.25;
        }
        let target = target.max(1) as f64;
        let mut h = math::cbrt(vol / target);
        // Keep the lattice bounded whatever the shape: at most ~64x the target in cells.
        let max_cells = 64.0 * target + 1e6;
        // One bound on the inside tests' work for the lattices tried, renewed for a coarser
        // retry: a coarser lattice has fewer columns, so it costs less than the last one did,
        // and too many samples cost more downstream than the retry does.
        let full = inside::column_budget(max_cells);
        let mut budget = full;
        let mut grid = Self::from_mesh_with_h(mesh, h, max_cells, &mut budget)?;
        for _ in 0..3 {
            let n = grid.points.len() as f64;
            let ratio = n / target;
            if (0.85..=1.15).contains(&ratio) {
                break;
            }
            if ratio > 1.0 {
                budget = full;
            }
            // A thin solid can hide between cell centres: shrink h until it shows up.
            h *= if n == 0.0 { 0.25 } else { math::cbrt(ratio) };
            match Self::from_mesh_with_h(mesh, h, max_cells, &mut budget) {
                Ok(g) => grid = g,
                // A finer lattice would cost too much: keep the samples found so far.
                Err(Error::TooComplex(_)) if n > 0.0 => break,
                Err(e) => return Err(e),
            }
        }
        if grid.points.is_empty() {
            return Err(Error::NoVolume(NoVolume::NoCellInside));
        }
        Ok(grid)
    }

    fn from_mesh_with_h(
        mesh: &Mesh,
        h: f64,
        max_cells: f64,
        budget: &mut u64,
    ) -> Result<Self, Error> {
        let (lo, hi) = mesh.bbox();
        let (origin, dims, h) = lattice_for_box(lo, hi, h, max_cells);
        let mut inside = inside::inside_cells_within(mesh, origin, h, dims, budget)?;
        shells::mark_sub_cell_shells(mesh, origin, h, dims, &mut inside);
        let offset_origin = origin + DVec3::splat(0.5 * h);
        let offset =
            inside::inside_cells_within(mesh, offset_origin, h, offset_dims(dims), budget)?;
        Ok(Self::from_masks(origin, h, dims, &inside, offset))
    }

    /// Sample an implicit solid `inside(p)` over the box `[lo, hi]` with cell size `h`
    /// (for tests and analytic shapes).
    pub fn from_inside_fn(lo: DVec3, hi: DVec3, h: f64, inside: impl Fn(DVec3) -> bool) -> Self {
        let (origin, dims, h) = lattice_for_box(lo, hi, h, f64::INFINITY);
        let mask_of = |origin: DVec3, dims: [usize; 3]| {
            let mut mask = vec![false; dims[0] * dims[1] * dims[2]];
            for k in 0..dims[2] {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        let p = origin + h * DVec3::new(i as f64, j as f64, k as f64);
                        mask[i + dims[0] * (j + dims[1] * k)] = inside(p);
                    }
                }
            }
            mask
        };
        let mask = mask_of(origin, dims);
        let offset = mask_of(origin + DVec3::splat(0.5 * h), offset_dims(dims));
        Self::from_masks(origin, h, dims, &mask, offset)
    }

    /// Build the sample arrays from a per-cell inside mask of the lattice and one of the
    /// offset lattice (dimensions [`offset_dims`]).
    fn from_masks(
        origin: DVec3,
        h: f64,
        dims: [usize; 3],
        mask: &[bool],
        offset_inside: Vec<bool>,
    ) -> Self {
        let [nx, ny, nz] = dims;
        let mut sample_of_cell = vec![NONE; nx * ny * nz];
        let mut coords = Vec::new();
        let mut points = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = i + nx * (j + ny * k);
                    if mask[c] {
                        sample_of_cell[c] = points.len() as u32;
                        coords.push([i as u32, j as u32, k as u32]);
                        points.push(origin + h * DVec3::new(i as f64, j as f64, k as f64));
                    }
                }
            }
        }
        let mut grid = Self {
            origin,
            h,
            dims,
            sample_of_cell,
            coords,
            points,
            neighbors: Vec::new(),
            inside_runs: Default::default(),
        };
        grid.inside_runs = [
            InsideRuns::new(dims, |c| grid.sample_of_cell[c] != NONE),
            InsideRuns::new(offset_dims(dims), |c| offset_inside[c]),
        ];
        // Freed before the neighbour lists, the largest array, are built.
        drop(offset_inside);
        grid.neighbors = (0..grid.points.len())
            .map(|s| {
                let [i, j, k] = grid.coords[s];
                let (i, j, k) = (i as i64, j as i64, k as i64);
                [
                    grid.sample_at(i - 1, j, k),
                    grid.sample_at(i + 1, j, k),
                    grid.sample_at(i, j - 1, k),
                    grid.sample_at(i, j + 1, k),
                    grid.sample_at(i, j, k - 1),
                    grid.sample_at(i, j, k + 1),
                ]
            })
            .collect();
        grid
    }

    /// The lattice of twice the cell size over the same box, each of its cells a sample when
    /// any of the eight cells it covers is one (so every sample lies in one of its samples:
    /// see [`Grid::coarse_cell`]). Only the optimisation of F runs on it, never the outside
    /// volume, so its offset lattice is left empty.
    pub fn coarser(&self) -> Grid {
        let [nx, ny, nz] = self.dims;
        let dims = [nx.div_ceil(2), ny.div_ceil(2), nz.div_ceil(2)];
        let mut mask = vec![false; dims[0] * dims[1] * dims[2]];
        for c in &self.coords {
            let [i, j, k] = c.map(|x| x as usize / 2);
            mask[i + dims[0] * (j + dims[1] * k)] = true;
        }
        let od = offset_dims(dims);
        Self::from_masks(
            self.origin + DVec3::splat(0.5 * self.h),
            2.0 * self.h,
            dims,
            &mask,
            vec![false; od[0] * od[1] * od[2]],
        )
    }

    /// The cell of [`Grid::coarser`] that sample `s` lies in, as its cell coordinates.
    #[inline]
    pub fn coarse_cell(&self, s: usize) -> [i64; 3] {
        self.coords[s].map(|x| i64::from(x / 2))
    }

    /// The sample at lattice cell `(i, j, k)`, or [`NONE`] when that cell is outside the solid
    /// (including every cell beyond the grid's extent).
    #[inline]
    pub fn sample_at(&self, i: i64, j: i64, k: i64) -> u32 {
        let [nx, ny, nz] = self.dims;
        if i < 0 || j < 0 || k < 0 || i >= nx as i64 || j >= ny as i64 || k >= nz as i64 {
            return NONE;
        }
        self.sample_of_cell[i as usize + nx * (j as usize + ny * k as usize)]
    }

    /// Number of interior samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the grid has no interior sample.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Volume one sample stands for.
    pub fn cell_volume(&self) -> f64 {
        self.h * self.h * self.h
    }

    /// Lattice coordinate (possibly outside the grid) of the cell containing `p`.
    #[inline]
    pub fn cell_of(&self, p: DVec3) -> [i64; 3] {
        let t = ((p - self.origin) / self.h).round();
        [t.x as i64, t.y as i64, t.z as i64]
    }

    /// Centre of lattice cell `(i, j, k)` (which may lie beyond the grid).
    #[inline]
    pub fn cell_center(&self, i: i64, j: i64, k: i64) -> DVec3 {
        self.origin + self.h * DVec3::new(i as f64, j as f64, k as f64)
    }
}

/// Dimensions of the offset lattice of a grid with dimensions `dims`: one more cell along each
/// axis, so that its cells' centres straddle the grid's.
pub fn offset_dims(dims: [usize; 3]) -> [usize; 3] {
    [dims[0] + 1, dims[1] + 1, dims[2] + 1]
}

/// A lattice covering `[lo, hi]` with one empty cell of margin on every side. The cell size is
/// enlarged if the lattice would exceed `max_cells`.
fn lattice_for_box(lo: DVec3, hi: DVec3, h: f64, max_cells: f64) -> (DVec3, [usize; 3], f64) {
    let ext = hi - lo;
    let mut h = h;
    let cells = |h: f64| {
        let n = (ext / h).ceil() + 3.0;
        n.x * n.y * n.z
    };
    while cells(h) > max_cells {
        h *= 1.1;
    }
    let n = (ext / h).ceil() + 3.0;
    let dims = [n.x as usize, n.y as usize, n.z as usize];
    // Centre the lattice on the box so the margin is symmetric.
    let span = DVec3::new(
        dims[0] as f64 - 1.0,
        dims[1] as f64 - 1.0,
        dims[2] as f64 - 1.0,
    ) * h;
    let origin = 0.5 * (lo + hi) - 0.5 * span;
    (origin, dims, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implicit_ball_has_expected_count_and_neighbours() {
        let h = 0.1;
        let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), h, |p| {
            p.length() <= 1.0
        });
        let expected = 4.0 / 3.0 * std::f64::consts::PI / (h * h * h);
        let n = g.len() as f64;
        assert!((n - expected).abs() / expected < 0.02, "{n} vs {expected}");
        // Neighbour relation is symmetric.
        for (s, nb) in g.neighbors.iter().enumerate() {
            for (d, &t) in nb.iter().enumerate() {
                if t != NONE {
                    assert_eq!(g.neighbors[t as usize][d ^ 1], s as u32);
                }
            }
        }
    }
}
