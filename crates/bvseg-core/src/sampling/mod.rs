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
//!
//! **Adaptive sampling** (the paper's section 6.2, [`crate::Sampling::Adaptive`]): the
//! lattice is finer, and where the solid is thick its cells are gathered into blocks of
//! 2x2x2 or 4x4x4 cells, each one sample standing for all of its cells (its weight). Thin
//! features and the layers along the boundary keep one sample per cell, so they are sampled
//! densely, the thick inside sparsely. A block is still a set of lattice cells: its moments
//! are the exact sums over its cells, the outside volume is still counted on the lattice
//! cells, and the enclosure still meets on cell faces. A sample's [`Grid::side`] says how
//! many cells along each axis it stands for; regular sampling has every side 1.
pub mod distance;
pub mod inside;
mod runs;
mod shells;

pub use runs::InsideRuns;

use std::sync::OnceLock;

use crate::math;
use glam::DVec3;

use crate::{Error, Mesh, NoVolume, Sampling};

/// How much finer than a regular lattice of the same sample count an adaptive one starts:
/// the first guess of the size loop in [`Grid::sampled`].
const ADAPTIVE_START: f64 = 0.6;

/// A block of side `b` cells is gathered into one sample only where every one of its cells
/// lies at least `BLOCK_DEPTH * b` cells from the nearest cell outside the solid: the
/// boundary and thin features keep single cells.
const BLOCK_DEPTH: usize = 1;

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
    /// For each sample, the coordinates of its cell (of a block's first cell: every
    /// coordinate a multiple of its side).
    pub coords: Vec<[u32; 3]>,
    /// For each sample, its position (the centre of its cell or block).
    pub points: Vec<DVec3>,
    /// The side of each sample's block of cells (1, 2 or 4), when the sampling is adaptive;
    /// empty when every sample is one cell.
    sides: Vec<u8>,
    /// The face neighbours of every sample, see [`Grid::neighbors`]: six per sample
    /// (-x, +x, -y, +y, -z, +z) when `neighbor_start` is empty, else CSR lists.
    neighbor_list: Vec<u32>,
    neighbor_start: Vec<u32>,
    /// Number of inside cells (the samples' weights summed).
    cells: usize,
    /// Each sample's distance to the boundary, computed when first asked for (see
    /// [`Grid::boundary_distance`]).
    depth: OnceLock<Vec<f64>>,
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
        Self::sampled(mesh, target, Sampling::Regular)
    }

    /// Sample the solid bounded by `mesh` with about `target` samples, regularly or
    /// adaptively (see the module's docs). An adaptive grid's lattice is finer, so that its
    /// samples, most of them single cells near the boundary, still number about `target`.
    ///
    /// # Errors
    ///
    /// As [`Grid::from_mesh`].
    pub fn sampled(mesh: &Mesh, target: usize, sampling: Sampling) -> Result<Self, Error> {
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
        let adaptive = sampling == Sampling::Adaptive;
        if adaptive {
            // The blocks gather most of a thick solid's cells: start finer.
            h *= ADAPTIVE_START;
        }
        let build = |h: f64, budget: &mut u64| {
            let g = Self::from_mesh_with_h(mesh, h, max_cells, budget)?;
            Ok::<_, Error>(if adaptive { g.into_blocks() } else { g })
        };
        let mut grid = build(h, &mut budget)?;
        for _ in 0..3 {
            let n = grid.points.len() as f64;
            let ratio = n / target;
            if (0.85..=1.15).contains(&ratio) {
                break;
            }
            if ratio > 1.0 {
                budget = full;
            }
            // A thin solid can hide between cell centres: shrink h until it shows up. Blocked
            // samples grow slower than the cells as h shrinks (the blocks' cells not at all).
            h *= if n == 0.0 {
                0.25
            } else if adaptive {
                ratio.powf(0.4)
            } else {
                math::cbrt(ratio)
            };
            match build(h, &mut budget) {
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
            cells: coords.len(),
            depth: OnceLock::new(),
            coords,
            points,
            sides: Vec::new(),
            neighbor_list: Vec::new(),
            neighbor_start: Vec::new(),
            inside_runs: Default::default(),
        };
        grid.inside_runs = [
            InsideRuns::new(dims, |c| grid.sample_of_cell[c] != NONE),
            InsideRuns::new(offset_dims(dims), |c| offset_inside[c]),
        ];
        // Freed before the neighbour lists, the largest array, are built.
        drop(offset_inside);
        let mut list = Vec::with_capacity(6 * grid.points.len());
        for s in 0..grid.points.len() {
            let [i, j, k] = grid.coords[s].map(i64::from);
            list.extend(grid.face_neighbours(i, j, k));
        }
        grid.neighbor_list = list;
        grid
    }

    /// This regular grid with its thick inside gathered into blocks, as adaptive sampling
    /// does (see the module's docs): a block of side `b` (4, then 2), aligned to multiples
    /// of `b`, becomes one sample when all its cells are inside and none lies nearer the
    /// boundary than [`BLOCK_DEPTH`] times `b` cells. Samples are numbered in the order of
    /// their first cell along the lattice (x fastest), as the regular grid's are.
    #[must_use]
    pub fn into_blocks(self) -> Self {
        let depth = distance::cell_depths(&self);
        let [nx, ny, nz] = self.dims;
        let cell = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        // The side of the block each inside cell joins (0: outside), and the block's first
        // cell.
        let mut side = vec![0u8; nx * ny * nz];
        let mut first = vec![u32::MAX; nx * ny * nz];
        for c in &self.coords {
            let [i, j, k] = c.map(|x| x as usize);
            side[cell(i, j, k)] = 1;
        }
        for b in [4usize, 2] {
            // Squared depths are compared exactly, in cells squared.
            let need = ((BLOCK_DEPTH * b) * (BLOCK_DEPTH * b)) as u32;
            for k0 in (0..nz.saturating_sub(b - 1)).step_by(b) {
                for j0 in (0..ny.saturating_sub(b - 1)).step_by(b) {
                    for i0 in (0..nx.saturating_sub(b - 1)).step_by(b) {
                        let block = || {
                            (k0..k0 + b).flat_map(move |k| {
                                (j0..j0 + b).flat_map(move |j| (i0..i0 + b).map(move |i| (i, j, k)))
                            })
                        };
                        let deep = block().all(|(i, j, k)| {
                            let c = cell(i, j, k);
                            side[c] == 1 && depth[c] >= need
                        });
                        if deep {
                            for (i, j, k) in block() {
                                side[cell(i, j, k)] = b as u8;
                                first[cell(i, j, k)] = cell(i0, j0, k0) as u32;
                            }
                        }
                    }
                }
            }
        }
        drop(depth);
        let mut sample_of_cell = vec![NONE; nx * ny * nz];
        let (mut coords, mut points, mut sides) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..nx * ny * nz {
            let b = side[c];
            if b == 0 {
                continue;
            }
            let at = if b == 1 { c } else { first[c] as usize };
            if at == c {
                let ijk = [at % nx, (at / nx) % ny, at / (nx * ny)];
                sample_of_cell[c] = points.len() as u32;
                coords.push(ijk.map(|x| x as u32));
                let mid = 0.5 * f64::from(b - 1);
                let p = DVec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64) + mid;
                points.push(self.origin + self.h * p);
                sides.push(b);
            } else {
                sample_of_cell[c] = sample_of_cell[at];
            }
        }
        drop(side);
        drop(first);
        let mut grid = Self {
            sample_of_cell,
            coords,
            points,
            sides,
            neighbor_list: Vec::new(),
            neighbor_start: Vec::new(),
            depth: OnceLock::new(),
            ..self
        };
        let mut start = Vec::with_capacity(grid.points.len() + 1);
        let mut list = Vec::new();
        for s in 0..grid.points.len() {
            start.push(list.len() as u32);
            let b = i64::from(grid.sides[s]);
            let c = grid.coords[s].map(i64::from);
            for axis in 0..3 {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for at in [c[axis] - 1, c[axis] + b] {
                    let from = list.len();
                    for du in 0..b {
                        for dv in 0..b {
                            let mut p = [0i64; 3];
                            p[axis] = at;
                            p[u] = c[u] + du;
                            p[v] = c[v] + dv;
                            let t = grid.sample_at(p[0], p[1], p[2]);
                            if !list[from..].contains(&t) {
                                list.push(t);
                            }
                        }
                    }
                }
            }
        }
        start.push(list.len() as u32);
        grid.neighbor_list = list;
        grid.neighbor_start = start;
        grid
    }

    /// The face neighbours of sample `s`: the samples of the cells across each face of its
    /// cell or block, face by face (-x, +x, -y, +y, -z, +z), each once per face, [`NONE`]
    /// for cells outside the solid. A single cell's list is its six face neighbours in that
    /// order.
    #[inline]
    pub fn neighbors(&self, s: usize) -> &[u32] {
        if self.neighbor_start.is_empty() {
            &self.neighbor_list[6 * s..6 * s + 6]
        } else {
            let (a, b) = (self.neighbor_start[s], self.neighbor_start[s + 1]);
            &self.neighbor_list[a as usize..b as usize]
        }
    }

    /// How many cells along each axis sample `s` stands for (1 but for adaptive blocks).
    #[inline]
    pub fn side(&self, s: usize) -> u32 {
        self.sides.get(s).map_or(1, |&b| u32::from(b))
    }

    /// The number of cells sample `s` stands for: its weight.
    #[inline]
    pub fn weight(&self, s: usize) -> u32 {
        self.side(s).pow(3)
    }

    /// Whether some sample stands for more than one cell.
    pub fn has_blocks(&self) -> bool {
        self.sides.iter().any(|&b| b > 1)
    }

    /// The lattice cells of sample `s`, as cell coordinates (one, or a block's, x fastest).
    pub fn cells_of(&self, s: usize) -> impl Iterator<Item = [u32; 3]> {
        let b = self.side(s);
        let [i, j, k] = self.coords[s];
        (0..b).flat_map(move |dk| {
            (0..b).flat_map(move |dj| (0..b).map(move |di| [i + di, j + dj, k + dk]))
        })
    }

    /// Number of lattice cells inside the solid: the samples' weights summed.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// Each sample's distance to the solid's boundary, in cells (see
    /// [`distance::boundary_distance`]): computed once, when first asked for, and kept with
    /// the samples.
    pub fn boundary_distance(&self) -> &[f64] {
        self.depth.get_or_init(|| distance::boundary_distance(self))
    }

    /// The lattice of twice the cell size over the same box, each of its cells a sample when
    /// any of the eight cells it covers is one (so every sample lies in one of its samples:
    /// see [`Grid::coarse_cell`]). Only the optimisation of F runs on it, never the outside
    /// volume, so its offset lattice is left empty.
    pub fn coarser(&self) -> Grid {
        let [nx, ny, nz] = self.dims;
        let dims = [nx.div_ceil(2), ny.div_ceil(2), nz.div_ceil(2)];
        let mut mask = vec![false; dims[0] * dims[1] * dims[2]];
        for s in 0..self.len() {
            for c in self.cells_of(s) {
                let [i, j, k] = c.map(|x| x as usize / 2);
                mask[i + dims[0] * (j + dims[1] * k)] = true;
            }
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

    /// The samples of the six cells that share a face with cell `(i, j, k)` (`NONE` outside),
    /// in the order -i, +i, -j, +j, -k, +k.
    pub fn face_neighbours(&self, i: i64, j: i64, k: i64) -> [u32; 6] {
        [
            self.sample_at(i - 1, j, k),
            self.sample_at(i + 1, j, k),
            self.sample_at(i, j - 1, k),
            self.sample_at(i, j + 1, k),
            self.sample_at(i, j, k - 1),
            self.sample_at(i, j, k + 1),
        ]
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
        for s in 0..g.len() {
            for (d, &t) in g.neighbors(s).iter().enumerate() {
                if t != NONE {
                    assert_eq!(g.neighbors(t as usize)[d ^ 1], s as u32);
                }
            }
        }
    }

    /// The blocks of adaptive sampling tile the same cells as the regular grid, each cell
    /// once; they lie deep inside; neighbours are symmetric and are exactly the samples of
    /// the cells across a sample's faces.
    #[test]
    fn blocks_tile_the_cells_deep_inside_with_symmetric_neighbours() {
        let inside = |p: DVec3| p.length() <= 1.0 && (p - DVec3::new(0.0, 0.0, 0.6)).length() > 0.3;
        let regular = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.05, inside);
        let g = regular.clone().into_blocks();
        assert!(g.has_blocks());
        assert!(
            g.len() < regular.len() / 2,
            "{} of {}",
            g.len(),
            regular.len()
        );
        assert_eq!(g.cells(), regular.len());
        let weights: usize = (0..g.len()).map(|s| g.weight(s) as usize).sum();
        assert_eq!(weights, regular.len());
        assert!((0..g.len()).any(|s| g.side(s) == 4) && (0..g.len()).any(|s| g.side(s) == 2));
        // Every cell of the regular grid belongs to the one sample that lists it.
        let mut owner = vec![NONE; g.sample_of_cell.len()];
        let [nx, ny, _] = g.dims;
        for s in 0..g.len() {
            for [i, j, k] in g.cells_of(s) {
                let c = i as usize + nx * (j as usize + ny * k as usize);
                assert_eq!(owner[c], NONE, "cell {c} twice");
                owner[c] = s as u32;
                assert_eq!(g.sample_of_cell[c], s as u32);
            }
        }
        for c in 0..owner.len() {
            assert_eq!(owner[c] != NONE, regular.sample_of_cell[c] != NONE);
        }
        // Blocks keep the boundary layers as single cells: their centres are deep.
        let depth = distance::boundary_distance(&g);
        for s in 0..g.len() {
            let b = f64::from(g.side(s));
            if b > 1.0 {
                let need = (BLOCK_DEPTH as f64) * b + 0.5 * (b - 1.0);
                assert!(
                    depth[s] >= need,
                    "sample {s} of side {b} at depth {}",
                    depth[s]
                );
                assert_eq!(g.coords[s].map(|x| x % g.side(s)), [0; 3]);
            }
        }
        for s in 0..g.len() {
            // The samples across the faces, cell by cell.
            let mut across: Vec<u32> = Vec::new();
            for [i, j, k] in g.cells_of(s) {
                for t in g.face_neighbours(i64::from(i), i64::from(j), i64::from(k)) {
                    if t != s as u32 {
                        across.push(t);
                    }
                }
            }
            across.sort_unstable();
            across.dedup();
            let mut listed = g.neighbors(s).to_vec();
            listed.sort_unstable();
            listed.dedup();
            assert_eq!(listed, across, "sample {s}");
            for &t in g.neighbors(s) {
                if t != NONE {
                    assert!(g.neighbors(t as usize).contains(&(s as u32)));
                }
            }
        }
    }
}
