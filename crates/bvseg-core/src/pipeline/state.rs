//! A partition with the output volumes of its parts and its figures: what each step of the
//! run produces and the next one judges.
use crate::math;
use std::sync::Arc;

use super::Context;
use crate::fitting::Fit;
use crate::metrics::{outside_from_cells, Cells, Outside};
use crate::partition::Partition;
use crate::refine::{Figures, Tolerances};
use crate::{BoundingVolume, Step, StepKind};

/// A partition with its volumes and figures.
#[derive(Debug, Clone)]
pub(crate) struct State {
    pub part: Partition,
    pub fits: Vec<Arc<Fit>>,
    pub volumes: Vec<BoundingVolume>,
    pub f: f64,
    pub tov: f64,
    pub mov: f64,
    pub ov: Vec<f64>,
    /// Each part's own protrusion (see [`crate::metrics::protrusion`]); their largest is the
    /// union's.
    pub pr: Vec<f64>,
    pub protrusion: f64,
}

impl State {
    /// Fit (or fetch from the cache) every part's output volume, and measure.
    pub fn evaluate(ctx: &mut Context, part: Partition) -> Self {
        let fits = ctx.fit_all(&part);
        let pr = ctx.fitter.protrusions(&ctx.solid, &fits);
        Self::measure(part, fits, pr)
    }

    /// `part` with the volumes `fits` of protrusions `pr`, measured.
    pub fn measure(part: Partition, fits: Vec<Arc<Fit>>, pr: Vec<f64>) -> Self {
        let counts = part.counts();
        let volumes: Vec<BoundingVolume> = fits.iter().map(|f| f.volume.clone()).collect();
        let cells: Vec<&Cells> = fits.iter().map(|f| &f.outside).collect();
        let o = outside_from_cells(&cells, &counts);
        State {
            f: part.f(),
            part,
            fits,
            volumes,
            tov: o.tov,
            mov: o.mov,
            ov: o.ov,
            protrusion: pr.iter().copied().fold(0.0, math::max),
            pr,
        }
    }

    /// The same partition with other volumes, measured as `o`.
    pub fn with_volumes(self, volumes: Vec<BoundingVolume>, o: Outside) -> Self {
        State {
            volumes,
            tov: o.tov,
            mov: o.mov,
            ov: o.ov,
            ..self
        }
    }

    /// The figures the tolerances `tol` judge.
    pub fn figures(&self, tol: &Tolerances) -> Figures {
        Figures {
            tov: self.tov,
            mov: self.mov,
            protrusion: self.protrusion,
            over: tol.over(&self.pr),
        }
    }

    /// The step of kind `kind` that led here.
    pub fn step(&self, kind: StepKind) -> Step {
        Step {
            kind,
            k: self.part.k(),
            f: self.f,
            tov: self.tov,
            mov: self.mov,
            protrusion: self.protrusion,
        }
    }
}
