//! Stage 9: the complete algorithm of the paper's section 5, as a steppable state machine.
//!
//! 1. Start: a CVT with one part per connected piece of the solid (or `k` parts in fixed-k
//!    mode), optimised.
//! 2. Refine (tolerance mode): while TOV >= sigma_G or MOV >= sigma_L and k < max_k, split a
//!    part and re-optimise it with its neighbours (at most [`LOCAL_SWEEPS`] Lloyd sweeps of
//!    the halves, then the boundary polish; with two threads the next try is re-optimised
//!    alongside, since a try is often undone). While TOV is out of tolerance the part that
//!    adds the most outside volume is split, once only MOV is, the part with the largest OV
//!    (the paper's choice). A split that does not improve the figure out of tolerance is
//!    undone and the next part tried (up to [`SPLIT_TRIES`]); if every try fails the first is
//!    kept. Beyond the paper: when only MOV is out of tolerance, merging the worst part into
//!    a neighbour is tried first, a split must keep TOV in tolerance, and refinement stops
//!    when no split helps or MOV has not improved for [`MOV_PATIENCE`] steps. When splits
//!    stall with TOV near its tolerance, a tightening checkpoint (a short
//!    [`crate::tightening`]) lowers TOV on the partition itself, so that fewer parts are
//!    needed.
//! 3. Merge: merge the pair (touching, or with overlapping volumes) whose merge lowers TOV
//!    most, while one does and the tolerances stay met.
//! 4. Final: the tightening ([`crate::tightening`]; in tolerance mode followed by
//!    [`crate::tightening::relieve_worst`]), the ellipsoids reshaped to stick out less
//!    ([`crate::reshaping`]), then the measured result and the hierarchy.
//!
//! Beyond the paper, which judges steps 2-3 with scaled Legendre ellipsoids, every step is
//! judged with the output volumes themselves, fitted to the points the output must enclose
//! (see [`crate::enclosure`]): the tolerances then hold for what the user gets, not for a
//! proxy. A part's fit depends only on its set of samples, so fits are cached by the part's
//! exact moments ([`crate::fitting`]) and only the parts a step changed are refitted.
use glam::DVec3;

use std::sync::Arc;

use crate::fitting::{Fit, Fitter};
use crate::flooding::{connected_merges, solid_components};
use crate::initialization::{cvt, split};
use crate::metrics::{outside_from_cells, outside_volumes, relative, Outside};
use crate::moments::Moments;
use crate::optimization::optimize;
use crate::parallel::{join, threads};
use crate::partition::{Partition, Solid};
use crate::reshaping::reshape;
use crate::sampling::Grid;
use crate::tightening::{relieve_worst, tighten, Coverage};
use crate::{
    hierarchy, BoundingVolume, Cancel, Error, Mesh, Metrics, Params, Part, Segmentation, Step,
    StepKind,
};

/// Passes of the outside-volume tightening (see [`crate::tightening`]).
pub const TIGHTEN_PASSES: usize = 40;

/// Of the tightening passes, how many judge every move (the others only those that gained).
pub const TIGHTEN_FULL_PASSES: usize = 3;

/// Passes of a tightening checkpoint during refinement (one of them full).
pub const CHECKPOINT_PASSES: usize = 4;

/// Moves of [`relieve_worst`] after the tightening, in tolerance mode.
pub const RELIEVE_STEPS: usize = 40;

/// Refinement steps without a better MOV (while only MOV is out of tolerance) after which
/// refinement stops.
pub const MOV_PATIENCE: usize = 6;

/// A tightening checkpoint is due when TOV is within this factor of its tolerance (or,
/// whatever TOV, once k has reached [`CHECKPOINT_LATE`] of the part limit)...
pub const CHECKPOINT_NEAR: f64 = 1.3;

/// Share of `max_k` from which checkpoints run whatever TOV: on limb-like models (human_1,
/// dinosaur_1) splits stall far from the tolerance, and a checkpoint there gains more than the
/// splits left before the limit (auto mode, ellipsoids: TOV 0.310 -> 0.292 and 0.324 ->
/// 0.313). From 60 % of the limit the gains were about the same for 10 % more time.
pub const CHECKPOINT_LATE: f64 = 0.75;

/// ... and the last this many splits ...
pub const CHECKPOINT_STALL: usize = 4;

/// ... lowered it by less than this share.
pub const CHECKPOINT_GAIN: f64 = 0.03;

/// How many parts a refinement step tries to split before keeping the first split anyway.
/// More tries rarely found a better split on the shared meshes, and each costs a local
/// re-optimisation.
pub const SPLIT_TRIES: usize = 2;

/// Lloyd sweeps of the two halves after a split, at most. A boundary between halves often
/// drifts by one layer per sweep for a hundred sweeps, each gaining little; the boundary
/// polish that follows makes those moves at a fraction of the cost.
pub const LOCAL_SWEEPS: usize = 10;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Start,
    Refine,
    Merge,
    Final,
    Done,
}

/// A partition with its volumes and figures.
#[derive(Debug, Clone)]
struct State {
    part: Partition,
    fits: Vec<Arc<Fit>>,
    volumes: Vec<BoundingVolume>,
    f: f64,
    tov: f64,
    mov: f64,
    ov: Vec<f64>,
}

impl State {
    /// The same partition with other volumes, measured as `o`.
    fn with_volumes(self, volumes: Vec<BoundingVolume>, o: Outside) -> Self {
        State {
            volumes,
            tov: o.tov,
            mov: o.mov,
            ov: o.ov,
            ..self
        }
    }
}

/// The segmentation as a sequence of steps, for progress display and interactive use: call
/// [`Segmenter::step`] until it returns `None`, then [`Segmenter::finish`]. Each step is a
/// bounded amount of work (one split or merge with its re-optimisation), so a UI can run one
/// per frame.
pub struct Segmenter {
    mesh: Mesh,
    params: Params,
    solid: Solid,
    comps: Vec<u32>,
    ncomp: usize,
    fitter: Fitter,
    phase: Phase,
    state: Option<State>,
    /// Parts left to try in the current split step, and the first try's result.
    tries: Vec<usize>,
    first_try: Option<State>,
    /// The next try's partition, when it was prepared alongside the current one.
    pending: Option<(usize, Partition)>,
    refine_steps: usize,
    /// k at the last tightening checkpoint.
    checkpoint_k: usize,
    /// Best MOV seen while only MOV was out of tolerance, and steps since it improved.
    best_mov: f64,
    stale: usize,
    history: Vec<Step>,
    result: Option<Segmentation>,
    cancel: Cancel,
    /// Whether the work bound cut the run short (see [`WORK_PER_SAMPLE`]).
    budget_hit: bool,
}

/// The run's bound on optional work, in outside cells counted by its fits: this many per
/// sample, plus [`WORK_PER_CELL`] per lattice cell. The 24 bundled and shared meshes use at
/// most 27 % of it (chair_1, `--max-k 128`), most under 15 %; a solid of many specks
/// scattered across a large box, whose parts must each span several of them, makes every fit
/// count a large share of the lattice, and would take minutes.
/// Once it is spent, refinement, merging and the polish stop where they are: the result is
/// the partition reached, with its volumes (still enclosing everything), measured.
pub const WORK_PER_SAMPLE: u64 = 1000;

/// See [`WORK_PER_SAMPLE`].
pub const WORK_PER_CELL: u64 = 8;

/// The bound on optional work for `solid` (see [`WORK_PER_SAMPLE`]); the fits and the
/// reshaping have one each.
fn work_budget(solid: &Solid) -> u64 {
    let g = &solid.grid;
    WORK_PER_SAMPLE * g.len() as u64 + WORK_PER_CELL * (g.dims[0] * g.dims[1] * g.dims[2]) as u64
}

/// Candidate merges fitted at a time: each fit holds its outside cells until it is judged.
const MERGE_CHUNK: usize = 16;

impl Segmenter {
    /// Validate the input and sample the solid. The remaining work happens in
    /// [`Segmenter::step`].
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParams`] when `params` fails [`Params::validate`], and the sampling's
    /// errors: [`Error::NoVolume`], [`Error::TooComplex`].
    pub fn new(mesh: &Mesh, params: &Params) -> Result<Self, Error> {
        Self::with_cancel(mesh, params, Cancel::new())
    }

    /// Like [`Segmenter::new`], stopping when `cancel` is set: [`Segmenter::step`] then
    /// returns `None` and [`Segmenter::finish`] [`Error::Cancelled`].
    ///
    /// # Errors
    ///
    /// As [`Segmenter::new`], and [`Error::Cancelled`] if `cancel` was set during sampling.
    pub fn with_cancel(mesh: &Mesh, params: &Params, cancel: Cancel) -> Result<Self, Error> {
        params.validate()?;
        cancel.check()?;
        let grid = Grid::from_mesh(mesh, params.samples)?;
        cancel.check()?;
        if grid.len() < 8 {
            return Err(Error::NoVolume(format!(
                "only {} grid cells lie inside the mesh",
                grid.len()
            )));
        }
        let (comps, ncomp) = solid_components(&grid);
        let solid = Solid::new(grid);
        let budget = work_budget(&solid);
        let fitter = Fitter::with_budget(mesh, &solid, params.bounding, budget, cancel.clone());
        Ok(Self {
            mesh: mesh.clone(),
            params: params.clone(),
            solid,
            comps,
            ncomp,
            fitter,
            phase: Phase::Start,
            state: None,
            tries: Vec::new(),
            first_try: None,
            pending: None,
            refine_steps: 0,
            checkpoint_k: 0,
            best_mov: f64::INFINITY,
            stale: 0,
            history: Vec::new(),
            result: None,
            cancel,
            budget_hit: false,
        })
    }

    /// The sampling grid.
    pub fn grid(&self) -> &Grid {
        &self.solid.grid
    }

    /// The refinement history so far.
    pub fn history(&self) -> &[Step] {
        &self.history
    }

    /// The current part of each sample (empty before the first step).
    pub fn labels(&self) -> &[u32] {
        self.state.as_ref().map_or(&[], |s| &s.part.labels)
    }

    /// The current refinement-time bounding volumes (empty before the first step).
    pub fn volumes(&self) -> &[BoundingVolume] {
        self.state.as_ref().map_or(&[], |s| &s.volumes)
    }

    /// Whether [`Segmenter::step`] has returned `None`.
    pub fn is_done(&self) -> bool {
        self.phase == Phase::Done
    }

    /// Fit (or fetch from the cache) every part's output volume, and measure.
    fn evaluate(&mut self, part: Partition) -> State {
        let fits = self
            .fitter
            .fit_all(&self.mesh, &self.solid, &part.labels, &part.parts);
        self.state_with(part, fits)
    }

    fn state_with(&self, part: Partition, fits: Vec<Arc<Fit>>) -> State {
        let counts: Vec<f64> = part.parts.iter().map(|m| m.n).collect();
        let volumes: Vec<BoundingVolume> = fits.iter().map(|f| f.volume).collect();
        let cells: Vec<&[[i64; 3]]> = fits.iter().map(|f| f.outside.as_slice()).collect();
        let o = outside_from_cells(&cells, &counts);
        State {
            f: part.f(),
            part,
            fits,
            volumes,
            tov: o.tov,
            mov: o.mov,
            ov: o.ov,
        }
    }

    fn record(&mut self, kind: StepKind, s: &State) -> Step {
        let step = Step {
            kind,
            k: s.part.k(),
            f: s.f,
            tov: s.tov,
            mov: s.mov,
        };
        self.history.push(step);
        step
    }

    /// Make `s` the current state, recording the step that led to it.
    fn accept(&mut self, kind: StepKind, s: State) -> Step {
        // A try prepared ahead was split from the state being replaced.
        self.pending = None;
        let step = self.record(kind, &s);
        self.state = Some(s);
        step
    }

    /// Leave the refinement for the merge phase (or straight for the final step).
    fn end_refinement(&mut self) -> Option<Step> {
        self.phase = if self.params.merge {
            Phase::Merge
        } else {
            Phase::Final
        };
        None
    }

    fn meets(&self, s: &State) -> bool {
        s.tov < self.params.tov && s.mov < self.params.mov
    }

    /// Do the next step and report it; `None` when the segmentation is complete.
    pub fn step(&mut self) -> Option<Step> {
        if self.cancel.is_cancelled() {
            self.phase = Phase::Done;
            return None;
        }
        loop {
            match self.phase {
                Phase::Start => return Some(self.start()),
                Phase::Refine => {
                    if let Some(s) = self.refine() {
                        return Some(s);
                    }
                }
                Phase::Merge => {
                    if let Some(s) = self.merge() {
                        return Some(s);
                    }
                }
                Phase::Final => return Some(self.finalize()),
                Phase::Done => return None,
            }
        }
    }

    fn start(&mut self) -> Step {
        let k = match self.params.k {
            Some(k) => k,
            None => self.ncomp.min(self.params.max_k),
        }
        .min(self.solid.len());
        let mut part = cvt(&self.solid, &self.comps, self.ncomp, k, self.params.seed);
        optimize(
            &self.solid,
            &self.comps,
            &mut part,
            None,
            None,
            self.params.max_sweeps,
        );
        let s = self.evaluate(part);
        let step = self.record(StepKind::Initial, &s);
        self.state = Some(s);
        self.phase = if self.params.k.is_some() {
            Phase::Final
        } else {
            Phase::Refine
        };
        step
    }

    /// One split attempt; `None` when refinement is over (the phase has moved on).
    fn refine(&mut self) -> Option<Step> {
        if self.out_of_work() {
            return None;
        }
        let cur = self.state.as_ref()?;
        let k = cur.part.k();
        if self.meets(cur) || k >= self.params.max_k || k >= self.solid.len() / 2 {
            return self.end_refinement();
        }
        if self.tries.is_empty() && self.first_try.is_none() {
            self.refine_steps += 1;
            if self.refine_steps > 4 * self.params.max_k {
                // A guard against splits and merges undoing each other forever.
                self.phase = Phase::Final;
                return None;
            }
            if self.checkpoint_due(cur) {
                let part = cur.part.clone();
                return Some(self.checkpoint(part));
            }
            if cur.tov < self.params.tov {
                // Only MOV is out of tolerance. Stop when it has not improved for a while:
                // more parts would not fix it (see `merge_worst`), only add cost.
                if cur.mov < self.best_mov {
                    self.best_mov = cur.mov;
                    self.stale = 0;
                } else {
                    self.stale += 1;
                    if self.stale > MOV_PATIENCE {
                        return self.end_refinement();
                    }
                }
                if let Some(step) = self.merge_worst() {
                    return Some(step);
                }
            }
            let cur = self.state.as_ref()?;
            // While TOV is too large, the part that adds the most outside volume is the one to
            // split (the paper's largest OV favours small parts, whose split barely moves TOV);
            // once only MOV is too large, the largest OV, as in the paper.
            let tov_bad = cur.tov >= self.params.tov;
            let weight = |i: usize| {
                if tov_bad {
                    cur.ov[i] * cur.part.parts[i].n
                } else {
                    cur.ov[i]
                }
            };
            let mut order: Vec<usize> = (0..k).collect();
            order.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)).then(a.cmp(&b)));
            order.truncate(SPLIT_TRIES);
            order.reverse();
            self.tries = order;
        }
        while let Some(i) = self.tries.pop() {
            let cur = self.state.as_ref()?;
            let part = match self.pending.take() {
                Some((j, p)) if j == i => Some(p),
                _ => {
                    // With a second thread, the next try is re-optimised alongside this
                    // one: the optimisation is serial, and the first try is often undone.
                    let next = self.tries.last().copied().filter(|_| threads() > 1);
                    let (this, ahead) = join(
                        || self.try_split(cur, i),
                        || next.and_then(|j| self.try_split(cur, j).map(|p| (j, p))),
                    );
                    self.pending = ahead;
                    this
                }
            };
            let Some(part) = part else {
                continue;
            };
            let cand = self.evaluate(part);
            let cur = self.state.as_ref()?;
            // A split is kept if it improves the figure that is out of tolerance (and, when
            // that is MOV, keeps TOV in tolerance).
            let better = if cur.tov >= self.params.tov {
                cand.tov < cur.tov
            } else {
                cand.mov < cur.mov && cand.tov < self.params.tov
            };
            if better {
                self.tries.clear();
                self.first_try = None;
                return Some(self.accept(StepKind::Split, cand));
            }
            let step = self.record(StepKind::Backtrack, &cand);
            if self.first_try.is_none() {
                self.first_try = Some(cand);
            }
            if !self.tries.is_empty() {
                return Some(step);
            }
        }
        // Every try made TOV worse: keep the first (the part with the largest OV), as the
        // paper does, so that refinement always progresses. When only MOV was out of
        // tolerance, no split helps it without breaking TOV: refinement is over.
        let tov_bad = self
            .state
            .as_ref()
            .is_some_and(|s| s.tov >= self.params.tov);
        match self.first_try.take() {
            Some(_) if !tov_bad => self.end_refinement(),
            Some(s) => Some(self.accept(StepKind::Split, s)),
            None => {
                // No part could be split at all.
                self.phase = Phase::Final;
                None
            }
        }
    }

    /// Part `i` of `cur` split in two, and the halves re-optimised: Lloyd sweeps on the two
    /// halves, boundary moves with their neighbours too. `None` if `i` cannot be split.
    fn try_split(&self, cur: &State, i: usize) -> Option<Partition> {
        let k = cur.part.k();
        let mut part = split(&self.solid, &self.comps, &cur.part, i)?;
        let mut active: Vec<u32> = cur
            .part
            .adjacency(&self.solid.grid)
            .iter()
            .filter_map(|&(a, b)| {
                if a as usize == i {
                    Some(b)
                } else if b as usize == i {
                    Some(a)
                } else {
                    None
                }
            })
            .collect();
        active.push(i as u32);
        active.push(k as u32);
        active.sort_unstable();
        optimize(
            &self.solid,
            &self.comps,
            &mut part,
            Some(&[i as u32, k as u32]),
            Some(&active),
            self.params.max_sweeps.min(LOCAL_SWEEPS),
        );
        Some(part)
    }

    /// Whether to tighten the partition now (see [`Segmenter::checkpoint`]): while TOV is out
    /// of tolerance but within [`CHECKPOINT_NEAR`] times it (or k is past [`CHECKPOINT_LATE`]
    /// of `max_k`), and the last [`CHECKPOINT_STALL`] splits lowered it by less than
    /// [`CHECKPOINT_GAIN`] (relative).
    fn checkpoint_due(&self, cur: &State) -> bool {
        let tol = self.params.tov;
        let late = cur.part.k() as f64 >= CHECKPOINT_LATE * self.params.max_k as f64;
        if !self.params.polish || cur.tov < tol || (cur.tov >= CHECKPOINT_NEAR * tol && !late) {
            return false;
        }
        let kept: Vec<&Step> = self
            .history
            .iter()
            .rev()
            .filter(|s| s.kind != StepKind::Backtrack)
            .take(CHECKPOINT_STALL + 1)
            .collect();
        let Some(oldest) = kept.get(CHECKPOINT_STALL) else {
            return false;
        };
        oldest.k > self.checkpoint_k
            && kept.iter().all(|s| s.kind == StepKind::Split)
            && oldest.tov - cur.tov < CHECKPOINT_GAIN * oldest.tov
    }

    /// Beyond the paper: the tightening of the final step ([`crate::tightening`]), run during
    /// the refinement. The tolerance is then judged, and the next parts to split chosen, on
    /// the partition the user would get, so refinement stops at fewer parts (the bunny meets
    /// the default TOV tolerance with 30 parts instead of 40).
    fn checkpoint(&mut self, mut part: Partition) -> Step {
        self.checkpoint_k = part.k();
        tighten(
            &self.mesh,
            &self.solid,
            &self.comps,
            &mut self.fitter,
            &mut part,
            CHECKPOINT_PASSES,
            1,
            self.params.mov,
        );
        let s = self.evaluate(part);
        self.accept(StepKind::Tighten, s)
    }

    /// Pairs of parts that may merge: those that touch, and those whose volumes' boxes
    /// overlap (separate pieces of the solid, such as a teddy's eyes, touch nothing).
    fn merge_pairs(&self, s: &State) -> Vec<(u32, u32)> {
        let mut pairs = s.part.adjacency(&self.solid.grid);
        let boxes: Vec<(DVec3, DVec3)> = s.volumes.iter().map(|v| v.aabb()).collect();
        for a in 0..boxes.len() {
            for b in a + 1..boxes.len() {
                let (la, ha) = boxes[a];
                let (lb, hb) = boxes[b];
                if la.cmple(hb).all() && lb.cmple(ha).all() {
                    pairs.push((a as u32, b as u32));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        connected_merges(&self.solid.grid, &s.part.labels, &self.comps, &pairs)
    }

    /// TOV and MOV after merging each pair, judged incrementally on the coverage of the
    /// union's outside cells: `(tov, mov, a, b)`.
    fn merge_options(&mut self, pairs: &[(u32, u32)]) -> Vec<(f64, f64, usize, usize)> {
        let Some(cur) = self.state.as_ref() else {
            return Vec::new();
        };
        let total = self.solid.len() as f64;
        let mut cov = Coverage::new(&self.solid);
        for f in &cur.fits {
            cov.add(&f.outside);
        }
        let mut out = Vec::new();
        // A few at a time, so that the fits' outside cells need not all be held at once.
        for chunk in pairs.chunks(MERGE_CHUNK) {
            if self.fitter.exhausted() {
                self.budget_hit |= !self.cancel.is_cancelled();
                break;
            }
            let Some(cur) = self.state.as_ref() else {
                break;
            };
            // The hull of the union is the hull of the two hulls.
            let todo: Vec<(Moments, Vec<DVec3>)> = chunk
                .iter()
                .map(|&(a, b)| {
                    let m = cur.part.parts[a as usize].merged(&cur.part.parts[b as usize]);
                    let mut pts = cur.fits[a as usize].hull.clone();
                    pts.extend_from_slice(&cur.fits[b as usize].hull);
                    (m, pts)
                })
                .collect();
            self.fitter.fit_candidates(&self.solid, todo);
            let Some(cur) = self.state.as_ref() else {
                break;
            };
            for &(a, b) in chunk {
                let (a, b) = (a as usize, b as usize);
                let m = cur.part.parts[a].merged(&cur.part.parts[b]);
                let Some(fit) = self.fitter.get(&m) else {
                    continue;
                };
                cov.remove(&cur.fits[a].outside);
                cov.remove(&cur.fits[b].outside);
                cov.add(&fit.outside);
                let tov = relative(cov.union, total);
                cov.remove(&fit.outside);
                cov.add(&cur.fits[a].outside);
                cov.add(&cur.fits[b].outside);
                let ov = relative(fit.outside.len(), m.n);
                let mov = (0..cur.ov.len())
                    .filter(|&i| i != a && i != b)
                    .map(|i| cur.ov[i])
                    .fold(ov, f64::max);
                out.push((tov, mov, a, b));
            }
        }
        out
    }

    /// The current partition with parts `a` and `b` merged, measured.
    fn merged_state(&mut self, a: usize, b: usize) -> Option<State> {
        let cur = self.state.as_ref()?;
        let mut part = cur.part.clone();
        for l in part.labels.iter_mut() {
            if *l as usize == b {
                *l = a as u32;
            }
        }
        let mb = part.parts[b];
        part.parts[a] = part.parts[a].merged(&mb);
        part.parts[b] = Moments::default();
        part.remove_empty_part(b);
        Some(self.evaluate(part))
    }

    /// The merge that lowers TOV most (keeping the tolerances if they are met), measured.
    fn best_merge(&mut self) -> Option<State> {
        let cur = self.state.as_ref()?;
        let met = self.meets(cur);
        let cur_tov = cur.tov;
        let pairs = self.merge_pairs(cur);
        let (tol_t, tol_m) = (self.params.tov, self.params.mov);
        let best = self
            .merge_options(&pairs)
            .into_iter()
            .filter(|&(tov, mov, _, _)| tov < cur_tov && (!met || (tov < tol_t && mov < tol_m)))
            .min_by(|x, y| x.0.total_cmp(&y.0).then((x.2, x.3).cmp(&(y.2, y.3))));
        best.and_then(|(_, _, a, b)| self.merged_state(a, b))
    }

    /// The bound on the run's optional work (see [`WORK_PER_SAMPLE`]).
    fn work_budget(&self) -> u64 {
        work_budget(&self.solid)
    }

    /// Whether the work bound is spent (see [`WORK_PER_SAMPLE`]); if so, the run moves on
    /// to its final step.
    fn out_of_work(&mut self) -> bool {
        if self.fitter.exhausted() {
            self.budget_hit |= !self.cancel.is_cancelled();
            self.phase = Phase::Final;
            return true;
        }
        false
    }

    /// One merge; `None` when no merge helps (the phase has moved on).
    fn merge(&mut self) -> Option<Step> {
        if self.out_of_work() {
            return None;
        }
        match self.best_merge() {
            Some(s) => Some(self.accept(StepKind::Merge, s)),
            None => {
                self.phase = Phase::Final;
                None
            }
        }
    }

    /// When only MOV is out of tolerance, merging the worst part into a neighbour often
    /// fixes it where splitting cannot (a small part's outside volume is large relative to
    /// its own volume). Returns the merge step if one lowers MOV and keeps TOV in tolerance.
    fn merge_worst(&mut self) -> Option<Step> {
        let cur = self.state.as_ref()?;
        let worst = (0..cur.ov.len()).max_by(|&a, &b| cur.ov[a].total_cmp(&cur.ov[b]))? as u32;
        let cur_mov = cur.mov;
        let pairs: Vec<(u32, u32)> = self
            .merge_pairs(cur)
            .into_iter()
            .filter(|&(a, b)| a == worst || b == worst)
            .collect();
        let tol_t = self.params.tov;
        let best = self
            .merge_options(&pairs)
            .into_iter()
            .filter(|&(tov, mov, _, _)| tov < tol_t && mov < cur_mov)
            .min_by(|x, y| x.1.total_cmp(&y.1).then((x.2, x.3).cmp(&(y.2, y.3))))?;
        let s = self.merged_state(best.2, best.3)?;
        Some(self.accept(StepKind::Merge, s))
    }

    /// `cur` with its ellipsoids reshaped to stick out less (see [`crate::reshaping`]), and
    /// measured again.
    fn reshaped(&self, cur: State) -> State {
        let points: Vec<&[DVec3]> = cur.fits.iter().map(|f| f.hull.as_slice()).collect();
        let min_r = 0.5 * self.solid.grid.h;
        let counts: Vec<f64> = cur.part.parts.iter().map(|m| m.n).collect();
        let cells = cur.fits.iter().map(|f| f.outside.clone()).collect();
        let (volumes, cells) = reshape(
            &self.solid,
            &points,
            &cur.volumes,
            cells,
            &counts,
            min_r,
            self.work_budget(),
        );
        let cells: Vec<&[[i64; 3]]> = cells.iter().map(Vec::as_slice).collect();
        cur.with_volumes(volumes, outside_from_cells(&cells, &counts))
    }

    /// `cur` with every volume grown by the margin ([`Params::margin`]), measured again.
    fn with_margin(&self, cur: State) -> State {
        if self.params.margin <= 0.0 {
            return cur;
        }
        let volumes: Vec<BoundingVolume> = cur
            .volumes
            .iter()
            .map(|v| v.grown(self.params.margin))
            .collect();
        let counts: Vec<f64> = cur.part.parts.iter().map(|m| m.n).collect();
        let o = outside_volumes(&self.solid.grid, &volumes, &counts);
        cur.with_volumes(volumes, o)
    }

    fn finalize(&mut self) -> Step {
        let Some(cur) = self.state.take() else {
            self.phase = Phase::Done;
            return Step {
                kind: StepKind::Final,
                k: 0,
                f: f64::NAN,
                tov: f64::NAN,
                mov: f64::NAN,
            };
        };
        // The polish is optional work: skipped once the work bound is spent.
        let polish = self.params.polish && !self.out_of_work();
        let cur = if polish {
            let mut part = cur.part;
            tighten(
                &self.mesh,
                &self.solid,
                &self.comps,
                &mut self.fitter,
                &mut part,
                TIGHTEN_PASSES,
                TIGHTEN_FULL_PASSES,
                self.params.mov,
            );
            if self.params.k.is_none() {
                relieve_worst(
                    &self.mesh,
                    &self.solid,
                    &self.comps,
                    &mut self.fitter,
                    &mut part,
                    RELIEVE_STEPS,
                    self.params.tov,
                    self.params.mov,
                );
            }
            self.evaluate(part)
        } else {
            cur
        };
        let cur = if polish && !self.out_of_work() {
            self.reshaped(cur)
        } else {
            cur
        };
        let cur = self.with_margin(cur);
        let k = cur.part.k();
        let n = self.solid.len() as f64;
        let parts: Vec<Part> = (0..k)
            .map(|i| Part {
                volume: cur.volumes[i],
                fraction: cur.part.parts[i].n / n,
                samples: cur.part.parts[i].n as usize,
                ov: cur.ov[i],
                e: cur.part.e(i),
            })
            .collect();
        let adjacency = cur.part.adjacency(&self.solid.grid);
        let hulls: Vec<Vec<DVec3>> = cur.fits.iter().map(|f| f.hull.clone()).collect();
        let margin = self.params.margin;
        let hierarchy = hierarchy::build(hulls, &cur.volumes, &adjacency, |p| {
            self.fitter.fit_points(&self.solid, p).grown(margin)
        });
        let metrics = Metrics {
            k,
            f: cur.f,
            tov: cur.tov,
            mov: cur.mov,
            samples: self.solid.len(),
        };
        let step = self.record(StepKind::Final, &cur);
        self.result = Some(Segmentation {
            kind: self.params.bounding,
            parts,
            metrics,
            history: self.history.clone(),
            hierarchy,
            triangle_parts: self.fitter.enclosure().triangle_parts(&cur.part.labels),
            sample_parts: cur.part.labels.clone(),
            cell_size: self.solid.grid.h,
            budget_exhausted: false,
        });
        self.state = Some(cur);
        self.phase = Phase::Done;
        step
    }

    /// Run any remaining steps and return the result.
    ///
    /// # Errors
    ///
    /// [`Error::Cancelled`] when the run's [`Cancel`] flag was set before it ended.
    pub fn finish(mut self) -> Result<Segmentation, Error> {
        while self.step().is_some() {}
        if self.cancel.is_cancelled() {
            return Err(Error::Cancelled);
        }
        let mut r = self
            .result
            .take()
            .ok_or_else(|| Error::Internal("the run ended without a result".into()))?;
        r.budget_exhausted = self.budget_hit;
        Ok(r)
    }
}
