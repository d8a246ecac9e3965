//! The state every stage works on: the sampled solid and a labelling of its samples.
//!
//! Positions are kept in lattice units, relative to the grid's centre cell: every sample
//! coordinate is an integer, so the moment sums below are exact in f64 (for any grid that
//! fits in memory) and therefore independent of summation order. That is what makes the
//! result bit-identical whatever the thread count. F and e are affine invariant, so nothing
//! is lost by working in these units.
use glam::DVec3;

use crate::flooding::solid_components;
use crate::moments::Moments;
use crate::sampling::Grid;

/// Covariance of a unit cube cell (lattice units): `h^2 / 12` with `h = 1`.
pub const CELL_VAR: f64 = 1.0 / 12.0;

/// The sampled solid in lattice units, with its connected pieces: every stage that keeps
/// parts connected needs them, so they travel with the samples.
#[derive(Debug, Clone)]
pub struct Solid {
    /// The sampling grid.
    pub grid: Grid,
    /// Sample positions in lattice units relative to `offset` (a block's centre: half
    /// integers for blocks of even side).
    pub q: Vec<DVec3>,
    /// Lattice coordinate that `q = 0` stands for.
    pub offset: [i64; 3],
    /// For each sample, the connected piece of the solid it lies in (face-adjacent samples).
    pub components: Vec<u32>,
    /// Number of connected pieces.
    pub pieces: usize,
}

impl Solid {
    /// Wrap a grid, finding its connected pieces.
    pub fn new(grid: Grid) -> Self {
        let offset = [
            (grid.dims[0] / 2) as i64,
            (grid.dims[1] / 2) as i64,
            (grid.dims[2] / 2) as i64,
        ];
        let q = grid
            .coords
            .iter()
            .enumerate()
            .map(|(s, c)| {
                let mid = 0.5 * f64::from(grid.side(s) - 1);
                DVec3::new(
                    (c[0] as i64 - offset[0]) as f64,
                    (c[1] as i64 - offset[1]) as f64,
                    (c[2] as i64 - offset[2]) as f64,
                ) + mid
            })
            .collect();
        let (components, pieces) = solid_components(&grid);
        Self {
            grid,
            q,
            offset,
            components,
            pieces,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// Number of lattice cells inside the solid (the samples' weights summed): the solid's
    /// volume in cells, what TOV is relative to.
    pub fn cells(&self) -> f64 {
        self.grid.cells() as f64
    }

    /// Add sample `s` to moments `m`: its one cell, or every cell of its block.
    #[inline]
    pub fn add(&self, m: &mut Moments, s: usize) {
        match self.grid.side(s) {
            1 => m.add(self.q[s]),
            b => m.add_block(self.q[s], b),
        }
    }

    /// Remove sample `s` (added before) from moments `m`.
    #[inline]
    pub fn remove(&self, m: &mut Moments, s: usize) {
        match self.grid.side(s) {
            1 => m.remove(self.q[s]),
            b => m.remove_block(self.q[s], b),
        }
    }

    /// Whether there is no sample.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// World position of a point given in lattice units.
    #[inline]
    pub fn to_world(&self, q: DVec3) -> DVec3 {
        self.grid.origin
            + self.grid.h
                * (q + DVec3::new(
                    self.offset[0] as f64,
                    self.offset[1] as f64,
                    self.offset[2] as f64,
                ))
    }
}

/// A partition of the samples into `k` labelled parts, with each part's moments.
#[derive(Debug, Clone, PartialEq)]
pub struct Partition {
    /// Part of each sample.
    pub labels: Vec<u32>,
    /// Moments of each part.
    pub parts: Vec<Moments>,
}

impl Partition {
    /// Build from labels (each in `0..k`).
    pub fn from_labels(solid: &Solid, labels: Vec<u32>, k: usize) -> Self {
        let mut parts = vec![Moments::default(); k];
        for (s, &l) in labels.iter().enumerate() {
            solid.add(&mut parts[l as usize], s);
        }
        Self { labels, parts }
    }

    /// Number of parts.
    pub fn k(&self) -> usize {
        self.parts.len()
    }

    /// F(P) = sum_i vol(S_i)/vol(S) e(S_i).
    pub fn f(&self) -> f64 {
        let n: f64 = self.parts.iter().map(|m| m.n).sum();
        self.parts
            .iter()
            .map(|m| m.f_term(CELL_VAR, 1.0))
            .sum::<f64>()
            / n
    }

    /// e-tightness of part `i`.
    pub fn e(&self, i: usize) -> f64 {
        self.parts[i].e(CELL_VAR, 1.0)
    }

    /// Move sample `s` to part `to`.
    #[inline]
    pub fn move_sample(&mut self, solid: &Solid, s: usize, to: u32) {
        let from = self.labels[s];
        solid.remove(&mut self.parts[from as usize], s);
        solid.add(&mut self.parts[to as usize], s);
        self.labels[s] = to;
    }

    /// Each part's number of cells (of samples, when each is one cell).
    pub fn counts(&self) -> Vec<f64> {
        self.parts.iter().map(|m| m.n).collect()
    }

    /// This partition with part `b` merged into part `a`; labels above `b` shift down.
    pub fn merged(&self, a: usize, b: usize) -> Self {
        let mut part = self.clone();
        for l in part.labels.iter_mut() {
            if *l as usize == b {
                *l = a as u32;
            }
        }
        let mb = part.parts[b];
        part.parts[a] = part.parts[a].merged(&mb);
        part.parts[b] = Moments::default();
        part.remove_empty_part(b);
        part
    }

    /// Whether some part has no sample.
    pub fn has_empty_part(&self) -> bool {
        self.parts.iter().any(|m| m.n < 1.0)
    }

    /// The samples of each part.
    pub fn members(&self) -> Vec<Vec<u32>> {
        let mut m = vec![Vec::new(); self.k()];
        for (s, &l) in self.labels.iter().enumerate() {
            m[l as usize].push(s as u32);
        }
        m
    }

    /// Pairs of parts that touch (share a grid face), sorted, each once as `(a, b)`, `a < b`.
    pub fn adjacency(&self, grid: &Grid) -> Vec<(u32, u32)> {
        let mut pairs = Vec::new();
        for s in 0..self.labels.len() {
            let a = self.labels[s];
            // Looking only at the neighbours after a sample sees each touching pair once.
            for &t in grid.neighbors(s) {
                if t != crate::sampling::NONE && t as usize > s {
                    let b = self.labels[t as usize];
                    if a != b {
                        pairs.push((a.min(b), a.max(b)));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs
    }

    /// Remove part `i` after its samples have been relabelled; labels above `i` shift down.
    pub fn remove_empty_part(&mut self, i: usize) {
        self.parts.remove(i);
        for l in &mut self.labels {
            if *l as usize > i {
                *l -= 1;
            }
        }
    }
}
