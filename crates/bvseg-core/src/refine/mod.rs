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

use crate::Params;

/// The figures the tolerances judge: total and largest per-part outside volume, relative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// Total outside volume relative to the solid's.
    pub tov: f64,
    /// Largest outside volume of a part relative to the part's.
    pub mov: f64,
}

/// The tolerances of tolerance mode: sigma_G on TOV, sigma_L on MOV.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// sigma_G ([`Params::tov`]).
    pub tov: f64,
    /// sigma_L ([`Params::mov`]).
    pub mov: f64,
}

impl Tolerances {
    /// The tolerances `params` asks for.
    pub fn of(params: &Params) -> Self {
        Self {
            tov: params.tov,
            mov: params.mov,
        }
    }

    /// Whether `x` meets both tolerances: the one rule for "tolerances met".
    pub fn met(&self, x: Figures) -> bool {
        x.tov < self.tov && x.mov < self.mov
    }

    /// Whether TOV is the figure out of tolerance (else, if any, only MOV is).
    pub fn tov_bad(&self, x: Figures) -> bool {
        x.tov >= self.tov
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn met_needs_both_strictly_below() {
        let t = Tolerances { tov: 0.3, mov: 0.5 };
        let f = |tov, mov| Figures { tov, mov };
        assert!(t.met(f(0.29, 0.49)));
        assert!(!t.met(f(0.3, 0.1)));
        assert!(!t.met(f(0.1, 0.5)));
        assert!(t.tov_bad(f(0.3, 0.1)) && !t.tov_bad(f(0.29, 9.0)));
    }
}
