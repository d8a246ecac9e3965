//! The first partition for large n, optimised on coarser lattices first (paper section 6.2).
//!
//! The Lloyd sweeps of the start cost time in proportion to the samples, and most of them
//! only move boundaries across distances much larger than a cell. Above
//! [`MULTIGRID_MIN`] samples the start runs on the lattice of twice the cell size (an eighth
//! of the samples; again and again while that is still large), each sample takes the part of
//! the coarse cell it lies in, and the optimisation goes on from there on the fine lattice,
//! where it only has to settle the boundaries.
use crate::assignment::{PartMetric, Rule};
use crate::flooding::make_connected;
use crate::initialization::{cvt, drop_empty_parts};
use crate::optimization::optimize;
use crate::partition::{Partition, Solid};

/// Samples from which the start begins on a coarser lattice. Below it the start runs as the
/// paper's, and so do all default runs (20,000 samples).
pub const MULTIGRID_MIN: usize = 400_000;

/// Lloyd sweeps on a lattice whose start was carried from a coarser one, where the
/// boundaries only have to settle. Half as many left TOV measurably above the direct start's;
/// more cost time for no gain (measured at a million samples when chosen: the commit that set
/// it has the figures; BENCHMARKS.md times such runs today).
const FINE_SWEEPS: usize = 16;

/// The CVT start of `k` parts (seeded by `seed`) optimised with up to `max_sweeps` Lloyd
/// sweeps and the boundary moves, on coarser lattices first when `solid` is large.
pub fn initial_partition(solid: &Solid, k: usize, seed: u64, max_sweeps: usize) -> Partition {
    let k = k.min(solid.len());
    if solid.len() < MULTIGRID_MIN {
        let mut part = cvt(solid, k, seed);
        optimize(solid, &mut part, None, None, max_sweeps);
        return part;
    }
    let coarse = Solid::new(solid.grid.coarser());
    let rough = initial_partition(&coarse, k, seed, max_sweeps);
    let mut part = carried(solid, &coarse, &rough);
    optimize(solid, &mut part, None, None, max_sweeps.min(FINE_SWEEPS));
    part
}

/// The partition of `solid` that gives each sample the part of its coarse cell in `rough`
/// (a partition of `coarse`, [`crate::sampling::Grid::coarser`] of `solid`'s grid), kept
/// connected.
fn carried(solid: &Solid, coarse: &Solid, rough: &Partition) -> Partition {
    let g = &solid.grid;
    let mut labels: Vec<u32> = (0..solid.len())
        .map(|s| {
            let [i, j, k] = g.coarse_cell(s);
            // Every sample's coarse cell is a coarse sample; 0 only guards the impossible.
            let c = coarse.grid.sample_at(i, j, k);
            rough.labels.get(c as usize).copied().unwrap_or(0)
        })
        .collect();
    // Pieces the coarse lattice joined may be apart here, and a part with them.
    let first = Partition::from_labels(solid, labels.clone(), rough.k());
    let metrics: Vec<PartMetric> = first.parts.iter().map(PartMetric::new).collect();
    make_connected(g, &mut labels, &solid.components, None, |s, j| {
        metrics[j as usize].cost_of(solid, s, Rule::Euclidean)
    });
    let mut part = Partition::from_labels(solid, labels, rough.k());
    drop_empty_parts(&mut part);
    part
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flooding::is_connected;
    use crate::sampling::Grid;
    use glam::DVec3;

    #[test]
    fn a_start_carried_from_a_coarser_lattice_is_connected_and_as_good() {
        // A bent tube of about 350,000 samples, its start carried from the coarser lattice.
        let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.0135, |p| {
            let r = (p.x * p.x + p.y * p.y).sqrt();
            (r - 0.7).abs() < 0.25 && p.z.abs() < 0.25 && p.y > -0.5
        });
        let solid = Solid::new(g);
        let n = solid.len();
        assert!(n > 300_000, "{n}");
        let direct = {
            let mut p = cvt(&solid, 6, 1);
            optimize(&solid, &mut p, None, None, 40);
            p
        };
        let coarse = Solid::new(solid.grid.coarser());
        assert!(
            coarse.len() < n / 4 && coarse.len() > n / 16,
            "{}",
            coarse.len()
        );
        let rough = initial_partition(&coarse, 6, 1, 40);
        let mut carried = carried(&solid, &coarse, &rough);
        assert_eq!(carried.k(), 6);
        optimize(&solid, &mut carried, None, None, FINE_SWEEPS);
        assert!(is_connected(
            &solid.grid,
            &carried.labels,
            &solid.components
        ));
        assert!(!carried.has_empty_part());
        // As good a minimum of F as the direct start's, within a few per cent.
        assert!(
            carried.f() <= direct.f() * 1.03,
            "{} vs {}",
            carried.f(),
            direct.f()
        );
    }
}
