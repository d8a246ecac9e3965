//! The refinement's decisions (paper section 5), one file each: which part to split and
//! whether the split stays ([`split`]), which parts to merge ([`merge`]), when to tighten
//! during refinement ([`checkpoint`]), when more parts stop helping ([`patience`]), and how
//! much optional work a run may do ([`budget`]). The pipeline ([`crate::pipeline`]) asks;
//! these files decide.
//!
//! Beyond the paper, which judges steps with scaled Legendre ellipsoids, every step is judged
//! with the output volumes themselves, fitted to the points the output must enclose (see
//! [`crate::enclosure`]): the tolerances then hold for what the user gets, not for a proxy.
pub(crate) mod budget;
pub(crate) mod checkpoint;
pub(crate) mod merge;
pub(crate) mod patience;
pub(crate) mod split;

use crate::math;
use crate::Params;

/// The figures the tolerances judge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// Total outside volume relative to the solid's.
    pub tov: f64,
    /// Largest outside volume of a part relative to the part's.
    pub mov: f64,
    /// Largest distance from the union's boundary to the surface, in mesh units.
    pub protrusion: f64,
    /// How far the parts protrude beyond the protrusion tolerance, summed over the parts: it
    /// drops when a split fixes one of several parts that protrude too far.
    pub over: f64,
}

/// What refinement works on: the first figure out of tolerance, in this order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aim {
    /// TOV.
    Tov,
    /// The protrusion.
    Protrusion,
    /// MOV (only when the user asked for a MOV tolerance).
    Mov,
}

/// The tolerances of tolerance mode: sigma_G on TOV, a distance on the protrusion, and, if the
/// user asks for it, the paper's sigma_L on MOV.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// sigma_G ([`Params::tov`]).
    pub tov: f64,
    /// sigma_L ([`Params::mov`]), if checked.
    pub mov: Option<f64>,
    /// The protrusion allowed, in mesh units ([`Params::max_protrusion_abs`], or
    /// [`Params::max_protrusion`] times the box diagonal).
    pub protrusion: f64,
}

impl Tolerances {
    /// The tolerances `params` asks for, for a mesh whose bounding box has diagonal
    /// `diagonal`.
    pub fn of(params: &Params, diagonal: f64) -> Self {
        Self {
            tov: params.tov,
            mov: params.mov,
            protrusion: params.protrusion_tolerance(diagonal),
        }
    }

    /// Whether `x` meets every tolerance: the one rule for "tolerances met".
    pub fn met(&self, x: Figures) -> bool {
        !self.tov_bad(x) && !self.protrusion_bad(x) && !self.mov_bad(x)
    }

    /// The figure refinement should improve next, or `None` when `x` meets every tolerance.
    pub fn aim(&self, x: Figures) -> Option<Aim> {
        if self.tov_bad(x) {
            Some(Aim::Tov)
        } else if self.protrusion_bad(x) {
            Some(Aim::Protrusion)
        } else if self.mov_bad(x) {
            Some(Aim::Mov)
        } else {
            None
        }
    }

    /// How far parts of protrusions `pr` reach beyond the tolerance, summed.
    pub fn over(&self, pr: &[f64]) -> f64 {
        pr.iter()
            .map(|&p| math::max(p - self.protrusion, 0.0))
            .sum()
    }

    /// Whether TOV is out of tolerance (the first thing refinement fixes).
    pub fn tov_bad(&self, x: Figures) -> bool {
        x.tov >= self.tov
    }

    /// Whether the protrusion is out of tolerance.
    pub fn protrusion_bad(&self, x: Figures) -> bool {
        x.protrusion >= self.protrusion
    }

    /// Whether MOV is checked and out of tolerance.
    pub fn mov_bad(&self, x: Figures) -> bool {
        self.mov.is_some_and(|m| x.mov >= m)
    }

    /// The bound a move may not push a part's OV past (infinite when MOV is not checked).
    pub fn mov_bound(&self) -> f64 {
        self.mov.unwrap_or(f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn met_needs_both_strictly_below() {
        let t = Tolerances {
            tov: 0.3,
            mov: Some(0.5),
            protrusion: 0.1,
        };
        let f = |tov, mov, protrusion| Figures {
            tov,
            mov,
            protrusion,
            over: 0.0,
        };
        assert!(t.met(f(0.29, 0.49, 0.09)));
        assert!(!t.met(f(0.3, 0.1, 0.0)));
        assert!(!t.met(f(0.1, 0.5, 0.0)));
        assert!(!t.met(f(0.1, 0.1, 0.1)));
        assert!(t.tov_bad(f(0.3, 0.1, 0.0)) && !t.tov_bad(f(0.29, 9.0, 9.0)));
        // Without a MOV tolerance, MOV is not judged.
        let t = Tolerances { mov: None, ..t };
        assert!(t.met(f(0.29, 50.0, 0.09)) && t.mov_bound().is_infinite());
        assert_eq!(t.aim(f(0.3, 0.0, 0.2)), Some(Aim::Tov));
        assert_eq!(t.aim(f(0.2, 0.0, 0.2)), Some(Aim::Protrusion));
        assert_eq!(t.aim(f(0.2, 0.0, 0.05)), None);
        assert!((t.over(&[0.05, 0.15, 0.3]) - 0.25).abs() < 1e-15);
    }

    #[test]
    fn the_distance_is_relative_to_the_diagonal_unless_given_in_mesh_units() {
        let p = Params::default();
        let t = Tolerances::of(&p, 10.0);
        assert_eq!(t.protrusion, crate::DEFAULT_MAX_PROTRUSION * 10.0);
        assert_eq!(t.mov, None);
        let p = Params {
            max_protrusion_abs: Some(0.25),
            ..p
        };
        assert_eq!(Tolerances::of(&p, 10.0).protrusion, 0.25);
    }
}
