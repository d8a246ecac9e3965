//! Which parts to merge (paper section 5.3, and beyond it while refining).
//!
//! After refinement, the pair whose merge lowers TOV most is merged, while one does and the
//! tolerances stay met ([`best`]). While refining with only MOV out of tolerance, merging the
//! worst part into a neighbour often fixes it where splitting cannot (a small part's outside
//! volume is large relative to its own volume): [`relieving`]. Pairs are those that touch, and
//! those whose volumes' boxes overlap (separate pieces of the solid, such as a teddy's eyes,
//! touch nothing); a merge must leave the part connected within each piece of the solid, and
//! with a rig, both parts must be bound to the same bone.
use crate::math;
use glam::DVec3;

use super::{Figures, Tolerances};
use crate::flooding::connected_merges;
use crate::metrics::{relative, Coverage};
use crate::moments::Moments;
use crate::pipeline::{Context, State};

/// Candidate merges fitted at a time: each fit holds its outside cells until it is judged.
const MERGE_CHUNK: usize = 16;

/// TOV and MOV after merging parts `a < b` (the protrusion is measured only for the options
/// that could win, see [`best`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MergeOption {
    /// TOV of the partition with the two parts merged.
    pub tov: f64,
    /// MOV of the partition with the two parts merged.
    pub mov: f64,
    /// The parts.
    pub a: usize,
    /// See `a`.
    pub b: usize,
}

/// Pairs of parts of `s` that may merge (see the module's docs), sorted.
pub fn pairs(ctx: &Context, s: &State) -> Vec<(u32, u32)> {
    let mut pairs = s.part.adjacency(&ctx.solid.grid);
    let boxes: Vec<(DVec3, DVec3)> = s.volumes.iter().map(|v| v.aabb()).collect();
    pairs.extend(overlapping(&boxes));
    pairs.sort_unstable();
    pairs.dedup();
    if ctx.votes.is_some() {
        // Parts bound to different bones move apart when the rig moves: merged, one of
        // them would have to be bounded over the other's whole motion.
        let bones = ctx.bones(&s.part);
        pairs.retain(|&(a, b)| bones[a as usize] == bones[b as usize]);
    }
    connected_merges(
        &ctx.solid.grid,
        &s.part.labels,
        &ctx.solid.components,
        &pairs,
    )
}

/// Pairs `(a, b)`, `a < b`, of boxes `(lo, hi)` that overlap (touching counts).
fn overlapping(boxes: &[(DVec3, DVec3)]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for a in 0..boxes.len() {
        for b in a + 1..boxes.len() {
            let (la, ha) = boxes[a];
            let (lb, hb) = boxes[b];
            if la.cmple(hb).all() && lb.cmple(ha).all() {
                out.push((a as u32, b as u32));
            }
        }
    }
    out
}

/// TOV and MOV after merging each pair of `pairs`, judged incrementally on the coverage of the
/// union's outside cells. Stops early when the run's work bound is spent; the flag says so.
pub fn options(ctx: &mut Context, cur: &State, pairs: &[(u32, u32)]) -> (Vec<MergeOption>, bool) {
    let total = ctx.solid.cells();
    let mut cov = Coverage::new(&ctx.solid);
    for f in &cur.fits {
        cov.add(&f.outside);
    }
    let mut out = Vec::new();
    // A few at a time, so that the fits' outside cells need not all be held at once.
    for chunk in pairs.chunks(MERGE_CHUNK) {
        if ctx.out_of_work() {
            return (out, true);
        }
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
        ctx.fitter.fit_candidates(&ctx.solid, todo);
        for &(a, b) in chunk {
            let (a, b) = (a as usize, b as usize);
            let m = cur.part.parts[a].merged(&cur.part.parts[b]);
            let Some(fit) = ctx.fitter.get(&m) else {
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
                .fold(ov, math::max);
            out.push(MergeOption { tov, mov, a, b });
        }
    }
    (out, false)
}

/// The merge that lowers TOV most below `cur`'s, keeping the tolerances if `cur` meets them
/// and never raising the protrusion past the larger of `cur`'s and its tolerance; ties go to
/// the first pair. `protrusion(a, b)` measures the protrusion after a merge: it is asked only
/// for the options in the order they would win, until one passes.
pub fn best(
    options: &[MergeOption],
    cur: Figures,
    tol: Tolerances,
    protrusion: impl FnMut(usize, usize) -> f64,
) -> Option<(usize, usize)> {
    let met = tol.met(cur);
    let mut order: Vec<&MergeOption> = options
        .iter()
        .filter(|o| o.tov < cur.tov && (!met || (o.tov < tol.tov && o.mov < tol.mov_bound())))
        .collect();
    order.sort_by(|x, y| x.tov.total_cmp(&y.tov).then((x.a, x.b).cmp(&(y.a, y.b))));
    first_within(&order, cur, tol, protrusion)
}

/// Of the merges of part `worst` with a neighbour, the one that lowers MOV most below
/// `cur_mov` and keeps TOV in tolerance (and the protrusion as in [`best`]); ties go to the
/// first pair.
pub fn relieving(
    options: &[MergeOption],
    cur: Figures,
    tol: Tolerances,
    protrusion: impl FnMut(usize, usize) -> f64,
) -> Option<(usize, usize)> {
    let mut order: Vec<&MergeOption> = options
        .iter()
        .filter(|o| o.tov < tol.tov && o.mov < cur.mov)
        .collect();
    order.sort_by(|x, y| x.mov.total_cmp(&y.mov).then((x.a, x.b).cmp(&(y.a, y.b))));
    first_within(&order, cur, tol, protrusion)
}

/// The first of `order` whose protrusion stays within the larger of `cur`'s and its tolerance.
fn first_within(
    order: &[&MergeOption],
    cur: Figures,
    tol: Tolerances,
    mut protrusion: impl FnMut(usize, usize) -> f64,
) -> Option<(usize, usize)> {
    let bound = math::max(cur.protrusion, tol.protrusion);
    order
        .iter()
        .find(|o| protrusion(o.a, o.b) <= bound)
        .map(|o| (o.a, o.b))
}

/// The merge phase's merge for `cur` (see [`best`]), measured; the flag says whether the
/// run's work bound cut the candidates short.
pub fn best_merge(ctx: &mut Context, cur: &State, tol: Tolerances) -> (Option<State>, bool) {
    let pairs = pairs(ctx, cur);
    let (options, cut) = options(ctx, cur, &pairs);
    let choice = best(&options, cur.figures(&tol), tol, protrusion_after(ctx, cur));
    (choice.map(|(a, b)| merged(ctx, cur, a, b)), cut)
}

/// The merge of `cur`'s worst part (the largest OV) with a neighbour that [`relieving`]
/// picks, measured; the flag as in [`best_merge`].
pub fn relieving_merge(ctx: &mut Context, cur: &State, tol: Tolerances) -> (Option<State>, bool) {
    let Some(w) = worst(&cur.ov) else {
        return (None, false);
    };
    let w = w as u32;
    let pairs: Vec<(u32, u32)> = pairs(ctx, cur)
        .into_iter()
        .filter(|&(a, b)| a == w || b == w)
        .collect();
    let (options, cut) = options(ctx, cur, &pairs);
    let choice = relieving(&options, cur.figures(&tol), tol, protrusion_after(ctx, cur));
    (choice.map(|(a, b)| merged(ctx, cur, a, b)), cut)
}

/// The protrusion of `cur` with parts `a` and `b` merged: the merged part's fit (fitted by
/// [`options`]) and the other parts'.
fn protrusion_after<'a>(ctx: &'a Context, cur: &'a State) -> impl FnMut(usize, usize) -> f64 + 'a {
    move |a, b| {
        let m = cur.part.parts[a].merged(&cur.part.parts[b]);
        let Some(fit) = ctx.fitter.get(&m) else {
            return f64::INFINITY;
        };
        let merged = ctx.fitter.protrusions(&ctx.solid, &[fit])[0];
        (0..cur.pr.len())
            .filter(|&i| i != a && i != b)
            .map(|i| cur.pr[i])
            .fold(merged, math::max)
    }
}

/// `cur` with parts `a` and `b` merged, measured.
fn merged(ctx: &mut Context, cur: &State, a: usize, b: usize) -> State {
    State::evaluate(ctx, cur.part.merged(a, b))
}

/// The part with the largest OV (the last on ties), if any.
pub fn worst(ov: &[f64]) -> Option<usize> {
    (0..ov.len()).max_by(|&a, &b| ov[a].total_cmp(&ov[b]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opt(tov: f64, mov: f64, a: usize, b: usize) -> MergeOption {
        MergeOption { tov, mov, a, b }
    }

    fn fig(tov: f64, mov: f64, protrusion: f64) -> Figures {
        Figures {
            tov,
            mov,
            protrusion,
            over: 0.0,
        }
    }

    const TOL: Tolerances = Tolerances {
        tov: 0.3,
        mov: Some(0.5),
        protrusion: 0.1,
    };

    #[test]
    fn best_lowers_tov_most_and_keeps_met_tolerances() {
        let none = |_, _| 0.0;
        let cur_unmet = fig(0.35, 0.9, 0.05);
        let options = [
            opt(0.34, 0.9, 0, 1),
            opt(0.33, 0.95, 2, 3),
            opt(0.36, 0.1, 1, 2),
        ];
        assert_eq!(best(&options, cur_unmet, TOL, none), Some((2, 3)));
        // Met before: a merge must keep every tolerance.
        let cur_met = fig(0.25, 0.4, 0.05);
        let options = [
            opt(0.2, 0.6, 0, 1),
            opt(0.24, 0.45, 1, 2),
            opt(0.26, 0.1, 0, 2),
        ];
        assert_eq!(best(&options, cur_met, TOL, none), Some((1, 2)));
        // Nothing lowers TOV: no merge.
        assert_eq!(best(&[opt(0.25, 0.1, 0, 1)], cur_met, TOL, none), None);
        // Ties go to the first pair.
        let options = [opt(0.3, 0.9, 2, 3), opt(0.3, 0.9, 0, 4)];
        assert_eq!(best(&options, cur_unmet, TOL, none), Some((0, 4)));
    }

    #[test]
    fn best_asks_for_the_protrusion_in_winning_order_until_one_passes() {
        let options = [
            opt(0.2, 0.1, 0, 1),
            opt(0.22, 0.1, 1, 2),
            opt(0.21, 0.1, 2, 3),
        ];
        let cur = fig(0.25, 0.4, 0.05);
        let mut asked = Vec::new();
        let got = best(&options, cur, TOL, |a, b| {
            asked.push((a, b));
            if a == 0 {
                0.2 // beyond the tolerance: this merge would not keep it
            } else {
                0.08
            }
        });
        assert_eq!(got, Some((2, 3)));
        assert_eq!(asked, vec![(0, 1), (2, 3)]);
    }

    #[test]
    fn relieving_lowers_mov_within_the_tov_tolerance() {
        let none = |_, _| 0.0;
        let options = [
            opt(0.29, 0.7, 0, 3),
            opt(0.31, 0.2, 1, 3),
            opt(0.2, 0.6, 3, 4),
        ];
        assert_eq!(
            relieving(&options, fig(0.2, 0.9, 0.0), TOL, none),
            Some((3, 4))
        );
        assert_eq!(relieving(&options, fig(0.2, 0.6, 0.0), TOL, none), None);
    }

    #[test]
    fn worst_is_the_last_largest() {
        assert_eq!(worst(&[0.1, 0.7, 0.7, 0.2]), Some(2));
        assert_eq!(worst(&[]), None);
    }

    #[test]
    fn boxes_overlap_when_they_touch() {
        let b = |lo: f64, hi: f64| (DVec3::splat(lo), DVec3::splat(hi));
        assert_eq!(
            overlapping(&[b(0.0, 1.0), b(1.0, 2.0), b(2.5, 3.0), b(0.5, 0.6)]),
            vec![(0, 1), (0, 3)]
        );
    }
}
