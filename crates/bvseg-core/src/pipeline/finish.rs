//! The final step: tighten the partition (move boundary layers, relieve the worst part,
//! reshape the volumes), grow by the margin, and assemble the result with its hierarchy.
use crate::math;
use glam::DVec3;

use super::{Context, State};
use crate::metrics::{outside_from_cells, outside_volumes, Cells};
use crate::posing::posed_volumes;
use crate::refine::budget::work_budget;
use crate::reshaping::reshape;
use crate::tightening::{relieve_worst, tighten, Passes};
use crate::{hierarchy, BoundingVolume, HierarchyNode, Metrics, Part, Segmentation, Step};

/// Passes of the final tightening, of which 3 judge every move (the others only those that
/// gained).
pub const TIGHTEN_PASSES: Passes = Passes {
    total: 40,
    full: 3,
    keep_kinds: false,
};

/// Moves of [`relieve_worst`] after the tightening, in tolerance mode.
pub const RELIEVE_STEPS: usize = 40;

/// The final state from `cur`: tightened and reshaped, when [`crate::Params::tighten`] asks for
/// it and the work bound allows (or fitted to follow its bones' poses), grown by the margin,
/// and its protrusion measured on the union; the flag says whether the work bound cut the
/// tightening short.
pub fn final_state(ctx: &mut Context, cur: State) -> (State, bool) {
    let mut cut = false;
    let mut out_of_work = |ctx: &Context| {
        let out = ctx.out_of_work();
        cut |= out && !ctx.cancel.is_cancelled();
        out
    };
    // The tightening is optional work: skipped once the work bound is spent.
    let tightening = ctx.params.tighten && !out_of_work(ctx);
    // Volumes that follow an animation are fitted anew over its poses: tightening the
    // partition for the volumes at rest first costs a fifth of such a run and changes the
    // posed volumes' TOV by about a percent either way (CesiumMan, Fox, BrainStem).
    let cur = if tightening && !follows_animation(ctx) {
        let mut part = cur.part;
        tighten(ctx, &mut part, TIGHTEN_PASSES);
        if ctx.params.k.is_none() {
            relieve_worst(ctx, &mut part, RELIEVE_STEPS);
        }
        State::evaluate(ctx, part)
    } else {
        cur
    };
    // Nor is reshaping them at rest worth it.
    let cur = if let Some(cur) = posed(ctx, &cur) {
        cur
    } else if tightening && !out_of_work(ctx) {
        reshaped(ctx, cur)
    } else {
        cur
    };
    let mut cur = with_margin(ctx, cur);
    // The figure of the result: each part's share of the union's boundary, exactly.
    cur.pr = union_protrusions(ctx, &cur);
    cur.protrusion = cur.pr.iter().copied().fold(0.0, math::max);
    (cur, cut)
}

/// For each volume of `cur`, the largest distance to the surface of its points on the
/// union's boundary (see [`crate::metrics::protrusion`]).
fn union_protrusions(ctx: &Context, cur: &State) -> Vec<f64> {
    let volumes = &cur.volumes;
    let others: Vec<Vec<BoundingVolume>> = (0..volumes.len())
        .map(|i| {
            let (lo, hi) = volumes[i].aabb();
            // Only the volumes that can hold a point of this one's boundary.
            (0..volumes.len())
                .filter(|&j| j != i)
                .map(|j| volumes[j].clone())
                .filter(|o| {
                    let (l, h) = o.aabb();
                    l.cmple(hi).all() && lo.cmple(h).all()
                })
                .collect()
        })
        .collect();
    let list = (0..volumes.len())
        .map(|i| (&volumes[i], cur.fits[i].hull.as_slice(), None))
        .collect();
    ctx.fitter.protrusions_of(&ctx.solid, list, &others)
}

/// `cur` with its volumes reshaped, or of another kind, to stick out less (see
/// [`crate::reshaping`]), and measured again.
fn reshaped(ctx: &Context, cur: State) -> State {
    let points: Vec<&[DVec3]> = cur.fits.iter().map(|f| f.hull.as_slice()).collect();
    let min_r = 0.5 * ctx.solid.grid.h;
    let counts = cur.part.counts();
    let cells = cur.fits.iter().map(|f| f.outside.clone()).collect();
    let (mut volumes, mut cells) = reshape(
        &ctx.solid,
        &points,
        &cur.volumes,
        cells,
        &counts,
        (min_r, work_budget(&ctx.solid)),
        &|points, except| ctx.fitter.fits_of_other_kinds(&ctx.solid, points, except),
    );
    // A reshaped volume may not reach farther from the surface than the larger of the
    // fitted one's reach and the tolerance: where it would, the fitted one stays.
    let bound = ctx.tolerances().protrusion;
    let changed: Vec<usize> = (0..volumes.len())
        .filter(|&i| volumes[i] != cur.volumes[i])
        .collect();
    let list = changed
        .iter()
        .map(|&i| (&volumes[i], cur.fits[i].hull.as_slice(), None))
        .collect();
    let reach = ctx.fitter.protrusions_of(&ctx.solid, list, &[]);
    for (&i, r) in changed.iter().zip(reach) {
        if r > math::max(cur.pr[i], bound) {
            volumes[i] = cur.volumes[i].clone();
            cells[i] = cur.fits[i].outside.clone();
        }
    }
    let cells: Vec<&Cells> = cells.iter().collect();
    let o = outside_from_cells(&cells, &counts);
    cur.with_volumes(volumes, o)
}

/// For a mesh whose rig has poses, `cur` with each volume fitted to follow its bone (see
/// [`crate::posing`]), measured again at rest; `None` for any other mesh.
fn posed(ctx: &Context, cur: &State) -> Option<State> {
    let rig = ctx.mesh.rig()?;
    let skin = rig.skin.as_ref().filter(|s| !s.poses.is_empty())?;
    let bones = ctx.bones(&cur.part);
    let volumes = posed_volumes(ctx, cur, &bones, &rig.skeleton, skin);
    let o = outside_volumes(&ctx.solid.grid, &volumes, &cur.part.counts());
    Some(cur.clone().with_volumes(volumes, o))
}

/// Whether the volumes of a run on this mesh follow an animation, each with its own bone:
/// a hierarchy of them would bound nothing in any other pose than the rest.
fn follows_animation(ctx: &Context) -> bool {
    ctx.mesh
        .rig()
        .and_then(|r| r.skin.as_ref())
        .is_some_and(|s| !s.poses.is_empty())
}

/// `cur` with every volume grown by the margin ([`crate::Params::margin`]), measured again.
fn with_margin(ctx: &Context, cur: State) -> State {
    let margin = ctx.params.margin;
    if margin <= 0.0 {
        return cur;
    }
    let volumes: Vec<BoundingVolume> = cur
        .volumes
        .iter()
        .map(|v| v.clone().grown(margin))
        .collect();
    let o = outside_volumes(&ctx.solid.grid, &volumes, &cur.part.counts());
    cur.with_volumes(volumes, o)
}

/// The result for the final state `cur` after `history`: parts, figures, the hierarchy, and
/// each triangle's and sample's part.
pub fn assemble(ctx: &Context, cur: &State, history: Vec<Step>) -> Segmentation {
    let k = cur.part.k();
    let n = ctx.solid.cells();
    let mut samples = vec![0usize; k];
    for &l in &cur.part.labels {
        samples[l as usize] += 1;
    }
    let bones = ctx.bones(&cur.part);
    let parts: Vec<Part> = (0..k)
        .map(|i| Part {
            volume: cur.volumes[i].clone(),
            fraction: cur.part.parts[i].n / n,
            samples: samples[i],
            ov: cur.ov[i],
            e: cur.part.e(i),
            protrusion: cur.pr[i],
            bone: bones[i],
        })
        .collect();
    let hierarchy = if ctx.params.hierarchy && !follows_animation(ctx) {
        hierarchy_of(ctx, cur)
    } else {
        Vec::new()
    };
    Segmentation {
        kinds: ctx.params.kinds,
        parts,
        metrics: Metrics {
            k,
            f: cur.f,
            tov: cur.tov,
            mov: cur.mov,
            protrusion: cur.protrusion,
            protrusion_rel: cur.protrusion / math::max(ctx.diagonal, f64::MIN_POSITIVE),
            diagonal: ctx.diagonal,
            samples: ctx.solid.len(),
        },
        history,
        hierarchy,
        triangle_parts: ctx.fitter.enclosure().triangle_parts(&cur.part.labels),
        sample_parts: cur.part.labels.clone(),
        cell_size: ctx.solid.grid.h,
        budget_exhausted: false,
        skeleton: ctx
            .votes
            .as_ref()
            .and(ctx.mesh.rig())
            .map(|r| r.skeleton.clone()),
        route: crate::Route::Lattice,
    }
}

/// The bounding-volume hierarchy over the parts of `cur` (see [`crate::hierarchy`]), grown
/// by the margin.
pub fn hierarchy_of(ctx: &Context, cur: &State) -> Vec<HierarchyNode> {
    let adjacency = cur.part.adjacency(&ctx.solid.grid);
    let hulls: Vec<Vec<DVec3>> = cur.fits.iter().map(|f| f.hull.clone()).collect();
    let margin = ctx.params.margin;
    hierarchy::build(hulls, &cur.volumes, &adjacency, |p| {
        ctx.fitter.fit_points(&ctx.solid, p).grown(margin)
    })
}
