//! Which parts to merge (paper section 5.3, and beyond it while refining).
//!
//! After refinement, the pair whose merge lowers TOV most is merged, while one does and the
//! tolerances stay met ([`best`]). While refining with only MOV out of tolerance, merging the
//! worst part into a neighbour often fixes it where splitting cannot (a small part's outside
//! volume is large relative to its own volume): [`relieving`]. Pairs are those that touch, and
//! those whose volumes' boxes overlap (separate pieces of the solid, such as a teddy's eyes,
//! touch nothing); a merge must leave the part connected within each piece of the solid.
use glam::DVec3;

use super::{Figures, Tolerances};
use crate::flooding::connected_merges;
use crate::metrics::{relative, Coverage};
use crate::moments::Moments;
use crate::pipeline::{Context, State};

/// Candidate merges fitted at a time: each fit holds its outside cells until it is judged.
const MERGE_CHUNK: usize = 16;

/// The figures after merging parts `a < b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MergeOption {
    /// TOV and MOV of the partition with the two parts merged.
    pub after: Figures,
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
    let total = ctx.solid.len() as f64;
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
                .fold(ov, f64::max);
            out.push(MergeOption {
                after: Figures { tov, mov },
                a,
                b,
            });
        }
    }
    (out, false)
}

/// The merge that lowers TOV most below `cur`'s, keeping the tolerances if `cur` meets them;
/// ties go to the first pair.
pub fn best(options: &[MergeOption], cur: Figures, tol: Tolerances) -> Option<(usize, usize)> {
    let met = tol.met(cur);
    options
        .iter()
        .filter(|o| o.after.tov < cur.tov && (!met || tol.met(o.after)))
        .min_by(|x, y| {
            x.after
                .tov
                .total_cmp(&y.after.tov)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        })
        .map(|o| (o.a, o.b))
}

/// Of the merges of part `worst` with a neighbour, the one that lowers MOV most below
/// `cur_mov` and keeps TOV in tolerance; ties go to the first pair.
pub fn relieving(options: &[MergeOption], cur_mov: f64, tol: Tolerances) -> Option<(usize, usize)> {
    options
        .iter()
        .filter(|o| o.after.tov < tol.tov && o.after.mov < cur_mov)
        .min_by(|x, y| {
            x.after
                .mov
                .total_cmp(&y.after.mov)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        })
        .map(|o| (o.a, o.b))
}

/// The part with the largest OV (the last on ties), if any.
pub fn worst(ov: &[f64]) -> Option<usize> {
    (0..ov.len()).max_by(|&a, &b| ov[a].total_cmp(&ov[b]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opt(tov: f64, mov: f64, a: usize, b: usize) -> MergeOption {
        MergeOption {
            after: Figures { tov, mov },
            a,
            b,
        }
    }

    const TOL: Tolerances = Tolerances { tov: 0.3, mov: 0.5 };

    #[test]
    fn best_lowers_tov_most_and_keeps_met_tolerances() {
        let cur_unmet = Figures {
            tov: 0.35,
            mov: 0.9,
        };
        let options = [
            opt(0.34, 0.9, 0, 1),
            opt(0.33, 0.95, 2, 3),
            opt(0.36, 0.1, 1, 2),
        ];
        assert_eq!(best(&options, cur_unmet, TOL), Some((2, 3)));
        // Met before: a merge must keep both tolerances.
        let cur_met = Figures {
            tov: 0.25,
            mov: 0.4,
        };
        let options = [
            opt(0.2, 0.6, 0, 1),
            opt(0.24, 0.45, 1, 2),
            opt(0.26, 0.1, 0, 2),
        ];
        assert_eq!(best(&options, cur_met, TOL), Some((1, 2)));
        // Nothing lowers TOV: no merge.
        assert_eq!(best(&[opt(0.25, 0.1, 0, 1)], cur_met, TOL), None);
        // Ties go to the first pair.
        let options = [opt(0.3, 0.9, 2, 3), opt(0.3, 0.9, 0, 4)];
        assert_eq!(best(&options, cur_unmet, TOL), Some((0, 4)));
    }

    #[test]
    fn relieving_lowers_mov_within_the_tov_tolerance() {
        let options = [
            opt(0.29, 0.7, 0, 3),
            opt(0.31, 0.2, 1, 3),
            opt(0.2, 0.6, 3, 4),
        ];
        assert_eq!(relieving(&options, 0.9, TOL), Some((3, 4)));
        assert_eq!(relieving(&options, 0.6, TOL), None);
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
