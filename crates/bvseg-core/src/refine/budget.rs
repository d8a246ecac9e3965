//! The run's bound on optional work.
//!
//! A solid of many specks scattered across a large box, whose parts must each span several of
//! them, makes every fit count a large share of the lattice, and would take minutes. So the
//! run's optional work (refinement, merging, the tightening) has a bound, counted in the outside
//! cells its fits visit. Once it is spent, those stop where they are: the result is the
//! partition reached, with its volumes (still enclosing everything), measured.
use crate::partition::Solid;

/// Outside cells per sample the run may count: with [`WORK_PER_CELL`], the 24 bundled and
/// shared meshes use at most 27 % of the bound (chair_1, `--max-k 128`), most under 15 %.
pub const WORK_PER_SAMPLE: u64 = 1000;

/// Outside cells per lattice cell the run may count, on top of [`WORK_PER_SAMPLE`].
pub const WORK_PER_CELL: u64 = 8;

/// The bound on optional work for `solid`; the fits and the reshaping have one each.
pub fn work_budget(solid: &Solid) -> u64 {
    let g = &solid.grid;
    WORK_PER_SAMPLE * g.len() as u64 + WORK_PER_CELL * (g.dims[0] * g.dims[1] * g.dims[2]) as u64
}

/// Nodes and triangles of the surface's tree one volume's protrusion may visit: on ordinary
/// meshes a volume needs a few tens of thousands; a hostile mesh of huge overlapping triangles
/// would make each of its ~200 queries visit them all.
pub const DISTANCE_PER_FIT: u64 = 4_000_000;

/// The run's bound on the protrusions' searches, per sample. Beyond it they are taken as the
/// distance to the nearest point of the part instead: an upper bound (see
/// [`crate::metrics::protrusion_capped`]), so no tolerance is ever met by mistake.
pub const DISTANCE_PER_SAMPLE: u64 = 2_500;

/// The bound on the protrusions' searches for `solid`.
pub fn distance_budget(solid: &Solid) -> u64 {
    DISTANCE_PER_SAMPLE * solid.len() as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Grid;
    use glam::DVec3;

    #[test]
    fn bound_grows_with_samples_and_lattice() {
        let ball = |r: f64| {
            Solid::new(Grid::from_inside_fn(
                DVec3::splat(-r),
                DVec3::splat(r),
                1.0,
                |p| p.length() <= r,
            ))
        };
        let (small, large) = (ball(3.0), ball(6.0));
        let expect = |s: &Solid| {
            let d = s.grid.dims;
            WORK_PER_SAMPLE * s.len() as u64 + WORK_PER_CELL * (d[0] * d[1] * d[2]) as u64
        };
        assert_eq!(work_budget(&small), expect(&small));
        assert!(work_budget(&large) > 4 * work_budget(&small));
    }
}
