//! The algorithm of the paper's section 5, as a steppable loop.
//!
//! 1. **Sample** the solid's interior ([`crate::sampling`]); done by [`Segmenter::new`].
//! 2. **Start**: a CVT with one part per connected piece of the solid (or `k` parts with a
//!    fixed k), **optimised** by the e-weighted Lloyd loop and the boundary moves
//!    ([`crate::optimization`]).
//! 3. **Refine** (tolerance mode): **judge** the output volumes; while TOV >= sigma_G, or the
//!    protrusion is at or above its tolerance, or (when asked for) MOV >= sigma_L, and
//!    k < max_k, **split** a part for the first figure out of tolerance and re-optimise it with
//!    its neighbours ([`crate::refine::split`]), or **merge** the worst part away when only MOV
//!    is out of tolerance ([`crate::refine::merge`]); **tighten** when splits stall near the
//!    TOV tolerance ([`crate::refine::checkpoint`]); stop when more parts stop helping
//!    ([`crate::refine::patience`]).
//! 4. **Merge** the pair whose merge lowers TOV most, while one does and the tolerances stay
//!    met.
//! 5. **Final**: **tighten** ([`crate::tightening`]), **reshape** ([`crate::reshaping`]),
//!    **measure**, and build the **hierarchy** ([`crate::hierarchy`]): see [`finish`].
//!
//! Every step is judged with the output volumes themselves ([`crate::fitting`]), cached by
//! the part's exact moments, so only the parts a step changed are refitted.
mod context;
mod finish;
mod segmenter;
mod state;

pub use segmenter::Segmenter;

pub(crate) use context::Context;
pub(crate) use state::State;

use crate::multigrid::initial_partition;
use crate::partition::{Partition, Solid};
use crate::refine::checkpoint::{Checkpoints, CHECKPOINT_PASSES};
use crate::refine::patience::MovPatience;
use crate::refine::split::{Split, SplitStep};
use crate::refine::{merge, Aim, Tolerances};
use crate::sampling::Grid;
use crate::skeleton::seeds::seeded_partition;
use crate::tightening::tighten;
use crate::{
    BoundingVolume, Cancel, Error, HierarchyNode, Mesh, NoVolume, Params, Segmentation, Step,
    StepKind,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Start,
    Refine,
    Merge,
    Final,
    Done,
}

/// The lattice route's run: the paper's loop (see the module's docs).
pub(crate) struct Lattice {
    ctx: Context,
    tol: Tolerances,
    phase: Phase,
    state: Option<State>,
    /// The split step in progress, if any.
    split: SplitStep,
    refine_steps: usize,
    checkpoints: Checkpoints,
    patience: MovPatience,
    history: Vec<Step>,
    result: Option<Segmentation>,
    /// Whether the work bound cut the run short (see [`crate::refine::budget`]).
    budget_hit: bool,
}

impl Lattice {
    /// Sample the solid, for [`Segmenter::with_cancel`] (which has validated `params`).
    ///
    /// # Errors
    ///
    /// As [`Segmenter::with_cancel`].
    pub fn with_cancel(mesh: &Mesh, params: &Params, cancel: Cancel) -> Result<Self, Error> {
        let grid = Grid::sampled(mesh, params.samples, params.sampling)?;
        cancel.check()?;
        if grid.len() < 8 {
            return Err(Error::NoVolume(NoVolume::FewCells {
                inside: grid.len(),
                needed: 8,
            }));
        }
        let solid = Solid::new(grid);
        let ctx = Context::new(mesh, solid, params, cancel);
        Ok(Self {
            tol: ctx.tolerances(),
            ctx,
            phase: Phase::Start,
            state: None,
            split: SplitStep::default(),
            refine_steps: 0,
            checkpoints: Checkpoints::default(),
            patience: MovPatience::default(),
            history: Vec::new(),
            result: None,
            budget_hit: false,
        })
    }

    /// Number of interior samples the solid was sampled with.
    #[must_use]
    pub fn samples(&self) -> usize {
        self.ctx.solid.len()
    }

    /// The refinement history so far.
    #[must_use]
    pub fn history(&self) -> &[Step] {
        &self.history
    }

    /// The current part of each sample (empty before the first step).
    #[must_use]
    pub fn labels(&self) -> &[u32] {
        self.state.as_ref().map_or(&[], |s| &s.part.labels)
    }

    /// The current part of each input triangle (empty before the first step), by the rule
    /// [`Segmentation::triangle_parts`] follows.
    #[must_use]
    pub fn triangle_parts(&self) -> Vec<u32> {
        self.state.as_ref().map_or_else(Vec::new, |s| {
            self.ctx.fitter.enclosure().triangle_parts(&s.part.labels)
        })
    }

    /// The current refinement-time bounding volumes (empty before the first step).
    #[must_use]
    pub fn volumes(&self) -> &[BoundingVolume] {
        self.state.as_ref().map_or(&[], |s| &s.volumes)
    }

    /// The bounding-volume hierarchy over the current parts (after the last step, those of
    /// the result), as [`Segmentation::hierarchy`] holds it when [`Params::hierarchy`] is on:
    /// for a run made without it whose user turns out to want it (the viewer builds it only
    /// for a JSON export). Empty before the first step.
    #[must_use]
    pub fn hierarchy(&self) -> Vec<HierarchyNode> {
        self.state
            .as_ref()
            .map_or_else(Vec::new, |s| finish::hierarchy_of(&self.ctx, s))
    }

    /// Whether [`Segmenter::step`] has returned `None`.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.phase == Phase::Done
    }

    /// Do the next step and report it; `None` when the segmentation is complete.
    pub fn step(&mut self) -> Option<Step> {
        if self.ctx.cancel.is_cancelled() {
            self.phase = Phase::Done;
            return None;
        }
        loop {
            let step = match self.phase {
                Phase::Start => Some(self.start()),
                Phase::Refine => self.refine(),
                Phase::Merge => self.merge(),
                Phase::Final => Some(self.finalize()),
                Phase::Done => return None,
            };
            // A phase that ends without a step has moved the run on to the next.
            if step.is_some() {
                return step;
            }
        }
    }

    /// Like [`Segmenter::finish`], keeping the segmenter, so that [`Segmenter::hierarchy`]
    /// can still build the hierarchy of a run made without it. A second call returns
    /// [`Error::Internal`].
    ///
    /// # Errors
    ///
    /// As [`Segmenter::finish`].
    pub fn take_result(&mut self) -> Result<Segmentation, Error> {
        while self.step().is_some() {}
        if self.ctx.cancel.is_cancelled() {
            return Err(Error::Cancelled);
        }
        let mut r = self
            .result
            .take()
            .ok_or_else(|| Error::Internal("the run ended without a result".into()))?;
        r.budget_exhausted = self.budget_hit;
        r.check()?;
        Ok(r)
    }

    /// Initial partition, optimised: one part per link of the skeleton when there is one (in
    /// tolerance mode), else one part per piece of the solid (or k).
    fn start(&mut self) -> Step {
        let p = &self.ctx.params;
        let seeded = match p.k {
            None => seeded_partition(
                &self.ctx.solid,
                &self.ctx.seeds,
                &self.ctx.seed_bones,
                p.max_sweeps,
            )
            .filter(|part| part.k() <= p.max_k),
            Some(_) => None,
        };
        let part = seeded.unwrap_or_else(|| {
            let k = p.k.unwrap_or(self.ctx.solid.pieces.min(p.max_k));
            initial_partition(&self.ctx.solid, k, p.seed, p.max_sweeps)
        });
        let s = State::evaluate(&mut self.ctx, part);
        self.phase = if self.ctx.params.k.is_some() {
            Phase::Final
        } else {
            Phase::Refine
        };
        self.accept(StepKind::Initial, s)
    }

    /// One refinement step: judge, then split (or merge the worst part, or tighten); `None`
    /// when refinement is over (the phase has moved on).
    fn refine(&mut self) -> Option<Step> {
        if self.out_of_work() {
            return None;
        }
        let cur = self.state.as_ref()?;
        let k = cur.part.k();
        let Some(aim) = self.tol.aim(cur.figures(&self.tol)) else {
            return self.end_refinement();
        };
        if k >= self.ctx.params.max_k || k >= self.ctx.solid.len() / 2 {
            return self.end_refinement();
        }
        if !self.split.in_progress() {
            self.refine_steps += 1;
            if self.refine_steps > 4 * self.ctx.params.max_k {
                // A guard against splits and merges undoing each other forever.
                self.phase = Phase::Final;
                return None;
            }
            if self
                .checkpoints
                .due(&self.history, k, cur.tov, &self.ctx.params)
            {
                let part = cur.part.clone();
                return Some(self.checkpoint(part));
            }
            if aim == Aim::Mov {
                if self.patience.run_out(cur.mov) {
                    return self.end_refinement();
                }
                if let Some(step) = self.merge_worst() {
                    return Some(step);
                }
            }
            let cur = self.state.as_ref()?;
            self.split.begin(aim, cur);
        }
        let cur = self.state.as_ref()?;
        match self
            .split
            .next(&mut self.ctx, cur, self.tol, &mut self.history)
        {
            Split::Kept(s) => Some(self.accept(StepKind::Split, s)),
            Split::Backtracked(step) => Some(step),
            Split::Ended => self.end_refinement(),
            Split::Impossible => {
                self.phase = Phase::Final;
                None
            }
        }
    }

    /// Tighten the current partition during refinement (see [`crate::refine::checkpoint`]).
    fn checkpoint(&mut self, mut part: Partition) -> Step {
        self.checkpoints.mark(part.k());
        tighten(&mut self.ctx, &mut part, CHECKPOINT_PASSES);
        let s = State::evaluate(&mut self.ctx, part);
        self.accept(StepKind::Tighten, s)
    }

    /// When only MOV is out of tolerance: merge the worst part into the neighbour that
    /// lowers MOV most, keeping TOV in tolerance, if one does.
    fn merge_worst(&mut self) -> Option<Step> {
        let cur = self.state.as_ref()?;
        let (merged, cut) = merge::relieving_merge(&mut self.ctx, cur, self.tol);
        self.budget_hit |= cut && !self.ctx.cancel.is_cancelled();
        Some(self.accept(StepKind::Merge, merged?))
    }

    /// One merge of the merge phase; `None` when no merge helps (the phase has moved on).
    fn merge(&mut self) -> Option<Step> {
        if self.out_of_work() {
            return None;
        }
        let merged = self.state.as_ref().and_then(|cur| {
            let (merged, cut) = merge::best_merge(&mut self.ctx, cur, self.tol);
            self.budget_hit |= cut && !self.ctx.cancel.is_cancelled();
            merged
        });
        match merged {
            Some(s) => Some(self.accept(StepKind::Merge, s)),
            None => {
                self.phase = Phase::Final;
                None
            }
        }
    }

    /// The final step (see [`finish`]).
    fn finalize(&mut self) -> Step {
        self.phase = Phase::Done;
        let Some(cur) = self.state.take() else {
            return Step {
                kind: StepKind::Final,
                k: 0,
                f: f64::NAN,
                tov: f64::NAN,
                mov: f64::NAN,
                protrusion: f64::NAN,
            };
        };
        let (cur, budget_cut) = finish::final_state(&mut self.ctx, cur);
        self.budget_hit |= budget_cut;
        let step = self.record(cur.step(StepKind::Final));
        self.result = Some(finish::assemble(&self.ctx, &cur, self.history.clone()));
        self.state = Some(cur);
        step
    }

    /// Leave the refinement for the merge phase (or straight for the final step).
    fn end_refinement(&mut self) -> Option<Step> {
        self.phase = if self.ctx.params.merge {
            Phase::Merge
        } else {
            Phase::Final
        };
        None
    }

    /// Whether the work bound is spent; if so, the run moves on to its final step.
    fn out_of_work(&mut self) -> bool {
        if self.ctx.out_of_work() {
            self.budget_hit |= !self.ctx.cancel.is_cancelled();
            self.phase = Phase::Final;
            return true;
        }
        false
    }

    fn record(&mut self, step: Step) -> Step {
        self.history.push(step);
        step
    }

    /// Make `s` the current state, recording the step that led to it.
    fn accept(&mut self, kind: StepKind, s: State) -> Step {
        // A try prepared ahead was split from the state being replaced.
        self.split.forget_pending();
        let step = self.record(s.step(kind));
        self.state = Some(s);
        step
    }
}
