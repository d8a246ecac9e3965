//! Which part to split, and whether the split stays (paper section 5.2).
//!
//! The figure out of tolerance decides ([`Aim`]): while TOV is, the part that adds the most
//! outside volume is split (the paper's largest OV favours small parts, whose split barely
//! moves TOV); once TOV is met and the protrusion is not, the part that protrudes most; with
//! the optional MOV tolerance, the part with the largest OV, as in the paper. A split that does
//! not improve that figure is undone and the next part tried, up to [`SPLIT_TRIES`]; if every
//! try fails, [`keeps_first_anyway`] decides whether refinement goes on from the first.
use super::{Aim, Figures, Tolerances};
use crate::initialization::split;
use crate::math;
use crate::optimization::optimize;
use crate::parallel::{join, threads};
use crate::partition::{Partition, Solid};
use crate::pipeline::{Context, State};
use crate::{Step, StepKind};

/// How many parts a refinement step tries to split before keeping the first split anyway.
/// More tries rarely found a better split on the shared meshes, and each costs a local
/// re-optimisation.
pub const SPLIT_TRIES: usize = 2;

/// Lloyd sweeps of the two halves after a split, at most. A boundary between halves often
/// drifts by one layer per sweep for a hundred sweeps, each gaining little; the boundary
/// sample moves that follow makes those moves at a fraction of the cost.
pub const LOCAL_SWEEPS: usize = 10;

/// The parts to try splitting for `aim`, best first (at most [`SPLIT_TRIES`]): by outside
/// volume (`ov[i]` times the part's samples `sizes[i]`) for TOV, by protrusion `pr[i]` for the
/// protrusion, by OV for MOV; ties go to the lower index.
pub fn candidates(aim: Aim, ov: &[f64], sizes: &[f64], pr: &[f64]) -> Vec<usize> {
    let weight = |i: usize| match aim {
        Aim::Tov => ov[i] * sizes[i],
        Aim::Protrusion => pr[i],
        Aim::Mov => ov[i],
    };
    let mut order: Vec<usize> = (0..ov.len()).collect();
    order.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)).then(a.cmp(&b)));
    order.truncate(SPLIT_TRIES);
    order
}

/// Whether a split for `aim` that gave `cand` from `cur` stays: it must improve the figure
/// out of tolerance (for the protrusion: the sum over the parts beyond the tolerance, the
/// largest not rising) and, past TOV, keep TOV in tolerance.
pub fn keeps(aim: Aim, cur: Figures, cand: Figures, tol: Tolerances) -> bool {
    match aim {
        Aim::Tov => cand.tov < cur.tov,
        Aim::Protrusion => {
            cand.tov < tol.tov && cand.protrusion <= cur.protrusion && cand.over < cur.over
        }
        Aim::Mov => {
            cand.mov < cur.mov
                && cand.tov < tol.tov
                && cand.protrusion <= math::max(cur.protrusion, tol.protrusion)
        }
    }
}

/// When every try failed: whether to keep the first anyway. For TOV always (the paper's
/// choice, so that refinement progresses); for the protrusion when it keeps TOV in tolerance
/// and the protrusion no higher (a later split may then fix it); for MOV never.
pub fn keeps_first_anyway(aim: Aim, cur: Figures, first: Figures, tol: Tolerances) -> bool {
    match aim {
        Aim::Tov => true,
        Aim::Protrusion => first.tov < tol.tov && first.protrusion <= cur.protrusion,
        Aim::Mov => false,
    }
}

/// One split step in progress: what it aims at, the parts left to try (the next last), the
/// first try's result, and the next try, when it was prepared alongside the current one.
#[derive(Debug, Default)]
pub struct SplitStep {
    aim: Option<Aim>,
    tries: Vec<usize>,
    first: Option<State>,
    pending: Option<(usize, Partition)>,
}

/// What a call of [`SplitStep::next`] came to.
#[derive(Debug)]
pub enum Split {
    /// A split to keep (it helped, or it is the first try, kept anyway).
    Kept(State),
    /// A try did not help and was recorded as a backtrack; more tries are left.
    Backtracked(Step),
    /// No try helped and none is worth keeping: refinement is over.
    Ended,
    /// No part could be split at all.
    Impossible,
}

impl SplitStep {
    /// Whether a step has tries left or is deciding on its first try.
    pub fn in_progress(&self) -> bool {
        !self.tries.is_empty() || self.first.is_some()
    }

    /// A new step on `cur`, for `aim`.
    pub fn begin(&mut self, aim: Aim, cur: &State) {
        self.aim = Some(aim);
        self.tries = candidates(aim, &cur.ov, &cur.part.counts(), &cur.pr);
        self.tries.reverse();
        self.first = None;
    }

    /// The try prepared ahead was split from a state that is no longer current.
    pub fn forget_pending(&mut self) {
        self.pending = None;
    }

    /// Try the next candidate split of `cur`, and say what came of it; a rejected try is
    /// recorded in `history` as a backtrack.
    pub fn next(
        &mut self,
        ctx: &mut Context,
        cur: &State,
        tol: Tolerances,
        history: &mut Vec<Step>,
    ) -> Split {
        let aim = self.aim.unwrap_or(Aim::Tov);
        while let Some(i) = self.tries.pop() {
            let part = match self.pending.take() {
                Some((j, p)) if j == i => Some(p),
                _ => {
                    // With a second thread, the next try is re-optimised alongside this one:
                    // the optimisation is serial, and the first try is often undone.
                    let next = self.tries.last().copied().filter(|_| threads() > 1);
                    let (solid, sweeps) = (&ctx.solid, ctx.params.max_sweeps);
                    let (this, ahead) = join(
                        || try_split(solid, &cur.part, i, sweeps),
                        || {
                            next.and_then(|j| {
                                try_split(solid, &cur.part, j, sweeps).map(|p| (j, p))
                            })
                        },
                    );
                    self.pending = ahead;
                    this
                }
            };
            let Some(part) = part else {
                continue;
            };
            let cand = State::evaluate(ctx, part);
            if keeps(aim, cur.figures(&tol), cand.figures(&tol), tol) {
                self.tries.clear();
                self.first = None;
                return Split::Kept(cand);
            }
            let step = cand.step(StepKind::Backtrack);
            history.push(step);
            if self.first.is_none() {
                self.first = Some(cand);
            }
            if !self.tries.is_empty() {
                return Split::Backtracked(step);
            }
        }
        match self.first.take() {
            Some(f) if keeps_first_anyway(aim, cur.figures(&tol), f.figures(&tol), tol) => {
                Split::Kept(f)
            }
            Some(_) => Split::Ended,
            None => Split::Impossible,
        }
    }
}

/// Part `i` of `part` split in two, and the halves re-optimised: Lloyd sweeps on the two
/// halves (at most `max_sweeps`, and [`LOCAL_SWEEPS`]), boundary moves with their neighbours
/// too. `None` if `i` cannot be split.
pub fn try_split(
    solid: &Solid,
    part: &Partition,
    i: usize,
    max_sweeps: usize,
) -> Option<Partition> {
    let k = part.k();
    let mut new = split(solid, part, i)?;
    let mut active: Vec<u32> = part
        .adjacency(&solid.grid)
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
        solid,
        &mut new,
        Some(&[i as u32, k as u32]),
        Some(&active),
        max_sweeps.min(LOCAL_SWEEPS),
    );
    Some(new)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::initialization::cvt;
    use crate::sampling::Grid;
    use glam::DVec3;

    #[test]
    fn candidates_by_outside_volume_protrusion_or_ov() {
        // Part 0: small with a large OV; part 2: large with a moderate one; part 1 protrudes.
        let ov = [2.0, 0.1, 0.5, 0.5];
        let sizes = [10.0, 100.0, 100.0, 100.0];
        let pr = [0.1, 0.4, 0.2, 0.2];
        assert_eq!(candidates(Aim::Tov, &ov, &sizes, &pr), vec![2, 3]);
        assert_eq!(candidates(Aim::Protrusion, &ov, &sizes, &pr), vec![1, 2]);
        assert_eq!(candidates(Aim::Mov, &ov, &sizes, &pr), vec![0, 2]);
        assert_eq!(candidates(Aim::Tov, &[1.0], &[5.0], &[0.0]), vec![0]);
    }

    #[test]
    fn keeps_what_improves_the_figure_out_of_tolerance() {
        let tol = Tolerances {
            tov: 0.3,
            mov: Some(0.5),
            protrusion: 0.1,
        };
        let f = |tov, mov, protrusion, over| Figures {
            tov,
            mov,
            protrusion,
            over,
        };
        // TOV out of tolerance: only TOV counts.
        assert!(keeps(
            Aim::Tov,
            f(0.4, 0.9, 1.0, 1.0),
            f(0.39, 2.0, 2.0, 2.0),
            tol
        ));
        assert!(!keeps(
            Aim::Tov,
            f(0.4, 0.9, 0.0, 0.0),
            f(0.4, 0.1, 0.0, 0.0),
            tol
        ));
        // The protrusion: less beyond the tolerance in all, the largest not higher, TOV kept.
        let cur = f(0.2, 0.9, 0.3, 0.35);
        assert!(keeps(Aim::Protrusion, cur, f(0.25, 0.9, 0.3, 0.2), tol));
        assert!(!keeps(Aim::Protrusion, cur, f(0.31, 0.9, 0.1, 0.0), tol));
        assert!(!keeps(Aim::Protrusion, cur, f(0.2, 0.9, 0.31, 0.21), tol));
        assert!(!keeps(Aim::Protrusion, cur, f(0.2, 0.9, 0.3, 0.35), tol));
        // Only MOV out: MOV must drop and TOV stay in tolerance.
        assert!(keeps(
            Aim::Mov,
            f(0.2, 0.9, 0.0, 0.0),
            f(0.25, 0.8, 0.05, 0.0),
            tol
        ));
        assert!(!keeps(
            Aim::Mov,
            f(0.2, 0.9, 0.0, 0.0),
            f(0.31, 0.6, 0.0, 0.0),
            tol
        ));
        assert!(!keeps(
            Aim::Mov,
            f(0.2, 0.9, 0.0, 0.0),
            f(0.1, 0.9, 0.0, 0.0),
            tol
        ));
        // After failed tries.
        assert!(keeps_first_anyway(
            Aim::Tov,
            cur,
            f(0.5, 9.0, 9.0, 9.0),
            tol
        ));
        assert!(keeps_first_anyway(
            Aim::Protrusion,
            cur,
            f(0.2, 0.9, 0.3, 0.4),
            tol
        ));
        assert!(!keeps_first_anyway(
            Aim::Protrusion,
            cur,
            f(0.2, 0.9, 0.31, 0.3),
            tol
        ));
        assert!(!keeps_first_anyway(Aim::Mov, cur, cur, tol));
    }

    #[test]
    fn a_split_adds_one_part_and_keeps_the_others_in_place() {
        // Two cubes joined by a bar: split the single part.
        let g = Grid::from_inside_fn(DVec3::ZERO, DVec3::new(12.0, 4.0, 4.0), 1.0, |p| {
            p.x < 4.0 || p.x > 8.0 || (p.y - 2.0).abs() < 1.0 && (p.z - 2.0).abs() < 1.0
        });
        let solid = Solid::new(g);
        let part = cvt(&solid, 1, 0);
        let new = try_split(&solid, &part, 0, 100).expect("a solid of many samples splits");
        assert_eq!(new.k(), 2);
        assert!(new.parts.iter().all(|m| m.n >= 1.0));
        assert_eq!(new.counts().iter().sum::<f64>(), solid.len() as f64);
        assert!(crate::flooding::is_connected(
            &solid.grid,
            &new.labels,
            &solid.components
        ));
        assert!(
            new.f() < part.f(),
            "two parts fit a dumbbell better than one"
        );
    }
}
