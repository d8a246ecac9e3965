//! What every stage of a run reads, in one place.
use std::sync::Arc;

use crate::fitting::{Fit, Fitter};
use crate::partition::{Partition, Solid};
use crate::refine::budget::{distance_budget, work_budget};
use crate::refine::Tolerances;
use crate::skeleton::auto::curve_skeleton;
use crate::skeleton::bones::Votes;
use crate::skeleton::{links, Link};
use crate::{Cancel, Mesh, Params, SkeletonMode};

/// The mesh, its sampled solid (with its connected pieces), the parameters and the run's
/// cancel flag, read by every stage; and the one thing the stages share mutably, the fitter
/// with its cache of fits and its account of the run's work.
pub(crate) struct Context {
    pub mesh: Mesh,
    pub solid: Solid,
    pub params: Params,
    pub fitter: Fitter,
    pub cancel: Cancel,
    /// The diagonal of the mesh's bounding box: the protrusion tolerance is relative to it.
    pub diagonal: f64,
    /// The links that seed the start (see [`crate::skeleton::seeds`]); empty for the
    /// unseeded start.
    pub seeds: Vec<Link>,
    /// The samples' votes for the bones of the mesh's rig, when it has a skeleton: every part
    /// is then bound to a bone (see [`crate::skeleton::bones`]).
    pub votes: Option<Votes>,
    /// Each sample's bone by its skin, for the seeds (see [`crate::skeleton::seeds`]); empty
    /// unless the skin's skeleton seeds the start.
    pub seed_bones: Vec<Option<usize>>,
}

impl Context {
    /// A run's context: the fitter gets the run's bound on optional work (see
    /// [`crate::refine::budget`]).
    pub fn new(mesh: &Mesh, solid: Solid, params: &Params, cancel: Cancel) -> Self {
        let budget = [work_budget(&solid), distance_budget(&solid)];
        let fitter = Fitter::with_budget(
            mesh,
            &solid,
            (params.kinds, params.max_hull_vertices),
            budget,
            cancel.clone(),
        );
        let (lo, hi) = mesh.bbox();
        let rig = mesh.rig().filter(|r| !r.skeleton.joints.is_empty());
        let seeds = match params.skeleton {
            SkeletonMode::Rig => rig.map(|r| links(&r.skeleton, &solid)).unwrap_or_default(),
            SkeletonMode::Auto => links(&curve_skeleton(&solid), &solid),
            SkeletonMode::None => Vec::new(),
        };
        let votes = rig.map(|r| {
            let own = links(&r.skeleton, &solid);
            Votes::new(
                mesh,
                &solid,
                fitter.enclosure(),
                &own,
                r.skin.as_ref(),
                r.skeleton.joints.len(),
            )
        });
        let skinned = rig.is_some_and(|r| r.skin.is_some());
        let seed_bones = match (&votes, params.skeleton) {
            (Some(v), SkeletonMode::Rig) if skinned => v.skin_bones(),
            _ => Vec::new(),
        };
        Self {
            seed_bones,
            diagonal: (hi - lo).length(),
            mesh: mesh.clone(),
            solid,
            params: params.clone(),
            fitter,
            cancel,
            seeds,
            votes,
        }
    }

    /// The bone of each part of `part` (all `None` without a rig).
    pub fn bones(&self, part: &Partition) -> Vec<Option<usize>> {
        match &self.votes {
            Some(v) => v.bones(&part.labels, part.k()),
            None => vec![None; part.k()],
        }
    }

    /// Every part's fit, from the cache where it has one.
    pub fn fit_all(&mut self, part: &Partition) -> Vec<Arc<Fit>> {
        self.fitter
            .fit_all(&self.mesh, &self.solid, &part.labels, &part.parts)
    }

    /// The tolerances the parameters ask for, on this mesh.
    pub fn tolerances(&self) -> Tolerances {
        Tolerances::of(&self.params, self.diagonal)
    }

    /// Whether the run's optional work should stop: its bound is spent, or it was cancelled.
    pub fn out_of_work(&self) -> bool {
        self.fitter.exhausted()
    }
}
