//! When to tighten during refinement. Beyond the paper: the tightening of the final step
//! ([`crate::tightening`]), run while refining, so that the tolerance is judged, and the next
//! parts to split chosen, on the partition the user would get; refinement then stops at fewer
//! parts (the bunny meets the default TOV tolerance with 30 parts instead of 40).
use crate::tightening::Passes;
use crate::{Params, Step, StepKind};

/// Passes of a tightening checkpoint (one of them full).
pub const CHECKPOINT_PASSES: Passes = Passes {
    total: 4,
    full: 1,
    keep_kinds: true,
};

/// A checkpoint is due when TOV is within this factor of its tolerance (or, whatever TOV,
/// once k has reached [`CHECKPOINT_LATE`] of the part limit)...
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

/// The checkpoints of one run.
#[derive(Debug, Clone, Default)]
pub struct Checkpoints {
    /// k at the last checkpoint.
    last_k: usize,
}

impl Checkpoints {
    /// Whether to tighten now, at `k` parts and total outside volume `tov`, after `history`:
    /// while TOV is out of tolerance but within [`CHECKPOINT_NEAR`] times it (or k is past
    /// [`CHECKPOINT_LATE`] of `max_k`), and the last [`CHECKPOINT_STALL`] splits since the
    /// last checkpoint lowered it by less than [`CHECKPOINT_GAIN`] (relative).
    pub fn due(&self, history: &[Step], k: usize, tov: f64, params: &Params) -> bool {
        let tol = params.tov;
        let late = k as f64 >= CHECKPOINT_LATE * params.max_k as f64;
        if !params.tighten || tov < tol || (tov >= CHECKPOINT_NEAR * tol && !late) {
            return false;
        }
        let kept: Vec<&Step> = history
            .iter()
            .rev()
            .filter(|s| s.kind != StepKind::Backtrack)
            .take(CHECKPOINT_STALL + 1)
            .collect();
        let Some(oldest) = kept.get(CHECKPOINT_STALL) else {
            return false;
        };
        oldest.k > self.last_k
            && kept.iter().all(|s| s.kind == StepKind::Split)
            && oldest.tov - tov < CHECKPOINT_GAIN * oldest.tov
    }

    /// Record a checkpoint at `k` parts.
    pub fn mark(&mut self, k: usize) {
        self.last_k = k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(kind: StepKind, k: usize, tov: f64) -> Step {
        Step {
            kind,
            k,
            f: 0.0,
            tov,
            mov: 0.0,
            protrusion: 0.0,
        }
    }

    /// A run at TOV just above the tolerance whose last splits gained `per_split` each.
    fn splits(from_k: usize, n: usize, tov0: f64, per_split: f64) -> Vec<Step> {
        (0..n)
            .map(|i| step(StepKind::Split, from_k + i, tov0 - per_split * i as f64))
            .collect()
    }

    #[test]
    fn due_when_splits_stall_near_the_tolerance() {
        let params = Params::default(); // tov 0.3, max_k 128
        let c = Checkpoints::default();
        let h = splits(10, 5, 0.35, 0.001);
        let tov = h[4].tov;
        assert!(c.due(&h, 14, tov, &params));
        // Splits that still gain 3 % or more: not yet.
        let h = splits(10, 5, 0.36, 0.004);
        assert!(!c.due(&h, 14, h[4].tov, &params));
        // Far from the tolerance and early: splitting is still the better use of time.
        let h = splits(10, 5, 0.5, 0.001);
        assert!(!c.due(&h, 14, h[4].tov, &params));
        // Far from it but late in the part budget: due.
        let late = (CHECKPOINT_LATE * params.max_k as f64) as usize;
        let h = splits(late - 4, 5, 0.5, 0.001);
        assert!(c.due(&h, late, h[4].tov, &params));
    }

    #[test]
    fn not_due_when_met_without_tightening_too_soon_or_again() {
        let params = Params::default();
        let mut c = Checkpoints::default();
        let h = splits(10, 5, 0.35, 0.001);
        let tov = h[4].tov;
        assert!(!c.due(&h, 14, 0.29, &params), "TOV met");
        let no_tightening = Params {
            tighten: false,
            ..Params::default()
        };
        assert!(!c.due(&h, 14, tov, &no_tightening));
        assert!(
            !c.due(&h[1..], 14, tov, &params),
            "fewer than the stall count"
        );
        // Backtracks do not count as splits, but a merge between the splits does.
        let mut with_back = h.clone();
        with_back.insert(2, step(StepKind::Backtrack, 12, 0.4));
        assert!(c.due(&with_back, 14, tov, &params));
        let mut with_merge = h.clone();
        with_merge.insert(2, step(StepKind::Merge, 11, 0.35));
        assert!(!c.due(&with_merge, 14, tov, &params));
        // Once checkpointed at k = 14, the splits before it do not make another due.
        c.mark(14);
        assert!(!c.due(&h, 14, tov, &params));
    }
}
