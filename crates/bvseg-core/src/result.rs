//! What [`crate::segment`] returns.
use crate::{BoundingVolume, Kinds};

/// One part of the segmentation and its bounding volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// The part's bounding volume.
    pub volume: BoundingVolume,
    /// Share of the solid's volume in this part (the fractions sum to 1).
    pub fraction: f64,
    /// Number of interior samples in the part.
    pub samples: usize,
    /// Outside volume of this part's bounding volume relative to the part's volume, OV_i,
    /// measured on the sampling lattice.
    pub ov: f64,
    /// e-tightness of the part (1 for an ellipsoid, about 1.127 for a box).
    pub e: f64,
    /// The largest distance to the mesh surface of the points of this part's volume on the
    /// union's boundary, in mesh units (0 when the other volumes cover all of it).
    pub protrusion: f64,
    /// The joint of the mesh's [`crate::Skeleton`] the volume moves with (an index into
    /// [`crate::Skeleton::joints`]), `None` without a skeleton. At a pose where that joint's
    /// world matrix is `G(t)`, the volume is `G(t) * rest⁻¹` applied to [`Part::volume`].
    pub bone: Option<usize>,
}

/// Summary figures of a segmentation, measured on the sampling lattice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// Number of parts.
    pub k: usize,
    /// The paper's functional F(P) >= 1 (1 when every part is an ellipsoid).
    pub f: f64,
    /// Total outside volume: vol(union of volumes minus solid) / vol(solid).
    pub tov: f64,
    /// Largest per-part outside volume.
    pub mov: f64,
    /// The protrusion: the one-way Hausdorff distance from the boundary of the union of the
    /// volumes to the mesh surface, in mesh units (the largest of the parts').
    pub protrusion: f64,
    /// [`Metrics::protrusion`] as a fraction of [`Metrics::diagonal`].
    pub protrusion_rel: f64,
    /// The diagonal of the mesh's bounding box, in mesh units.
    pub diagonal: f64,
    /// Number of interior samples.
    pub samples: usize,
}

/// What a refinement step did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepKind {
    /// The first optimised partition (k parts from the initialisation).
    Initial,
    /// A part was split and the partition re-optimised.
    Split,
    /// A split made TOV worse and was undone; another part is tried next.
    Backtrack,
    /// Two adjacent parts were merged.
    Merge,
    /// Boundary layers moved between parts to lower the outside volume (a checkpoint of
    /// the tightening during refinement).
    Tighten,
    /// The final bounding volumes (minimum-volume ellipsoids / boxes) were fitted.
    Final,
}

impl StepKind {
    /// Lower-case name, as written to JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            StepKind::Initial => "initial",
            StepKind::Split => "split",
            StepKind::Backtrack => "backtrack",
            StepKind::Merge => "merge",
            StepKind::Tighten => "tighten",
            StepKind::Final => "final",
        }
    }
}

/// One entry of the refinement history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// What happened.
    pub kind: StepKind,
    /// Number of parts after the step.
    pub k: usize,
    /// F(P) after the step.
    pub f: f64,
    /// TOV after the step (with the refinement's bounding volumes; the final step uses the
    /// output volumes).
    pub tov: f64,
    /// MOV after the step.
    pub mov: f64,
    /// The protrusion after the step, in mesh units.
    pub protrusion: f64,
}

/// A node of the bounding-volume hierarchy. Leaves are parts; inner nodes bound their two
/// children's parts.
#[derive(Debug, Clone, PartialEq)]
pub struct HierarchyNode {
    /// The node's bounding volume (of the kind requested; for `mixed`, the smaller).
    pub volume: BoundingVolume,
    /// For a leaf, the part index.
    pub part: Option<usize>,
    /// For an inner node, the indices of its two children in [`Segmentation::hierarchy`].
    pub children: Option<[usize; 2]>,
}

/// The result of [`crate::segment`].
#[derive(Debug, Clone, PartialEq)]
#[must_use]
pub struct Segmentation {
    /// The kinds of volume the run could choose from.
    pub kinds: Kinds,
    /// The parts, each with its bounding volume.
    pub parts: Vec<Part>,
    /// Summary figures.
    pub metrics: Metrics,
    /// Every refinement step, in order.
    pub history: Vec<Step>,
    /// Binary hierarchy over the parts: nodes `0..k` are the parts' leaves, the root is the
    /// last node (with one part, that single leaf). Empty when [`crate::Params::hierarchy`]
    /// is off.
    pub hierarchy: Vec<HierarchyNode>,
    /// For each input triangle, the part whose volume encloses it.
    pub triangle_parts: Vec<u32>,
    /// For each interior sample, its part.
    pub sample_parts: Vec<u32>,
    /// The lattice cell size that was used.
    pub cell_size: f64,
    /// Whether the run's bound on work cut refinement, merging or the tightening short (see
    /// the crate's docs on awkward inputs): the volumes still enclose the mesh, but more
    /// work would have made them tighter. Happens on solids of many specks scattered over a
    /// large box, not on ordinary models. [`BUDGET_WARNING`] says it in words.
    pub budget_exhausted: bool,
    /// The skeleton the parts' [`Part::bone`]s index (the mesh's rig's), `None` when the
    /// mesh has no rig.
    pub skeleton: Option<crate::Skeleton>,
    /// The route the run took ([`crate::Route::Lattice`] or [`crate::Route::Surface`]). On
    /// the surface route no interior is sampled: [`Metrics::tov`], [`Metrics::mov`] and
    /// [`Metrics::f`] are 0 and not measured, the parts have no samples, and
    /// [`Segmentation::unmet`] checks the protrusion only.
    pub route: crate::Route,
}

/// What the front ends (the CLI, the Python package) warn when
/// [`Segmentation::budget_exhausted`] is set.
pub const BUDGET_WARNING: &str = "refinement stopped early: the volumes cover far more empty \
    space than their parts (many pieces scattered over a large box?); they still enclose the mesh";

/// One of the tolerances a tolerance-mode run is asked to meet (see [`crate::Params`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Tolerance {
    /// The total outside volume, [`Metrics::tov`], against `params.tov` (a fraction).
    Tov,
    /// The protrusion, [`Metrics::protrusion`], against `params.max_protrusion_abs` or
    /// `params.max_protrusion` times the diagonal (both in mesh units).
    Protrusion,
    /// The maximum outside volume, [`Metrics::mov`], against `params.mov` (a fraction).
    Mov,
}

impl Tolerance {
    /// The tolerance's short name, as the Python package and the JSON reports spell it:
    /// `"tov"`, `"protrusion"` or `"mov"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Tov => "tov",
            Self::Protrusion => "protrusion",
            Self::Mov => "mov",
        }
    }
}

impl std::fmt::Display for Tolerance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A tolerance a tolerance-mode run left unmet: which, the figure reached and the limit it
/// should have stayed below, in the units of the figure (a fraction for TOV and MOV, mesh
/// units for the protrusion).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Unmet {
    /// Which tolerance.
    pub tolerance: Tolerance,
    /// The figure the run reached.
    pub value: f64,
    /// The tolerance it was asked to stay below.
    pub limit: f64,
}

impl Segmentation {
    /// Whether a tolerance-mode run (`params.k == None`) met its tolerances: TOV below
    /// `params.tov`, the protrusion below its tolerance, and MOV below `params.mov` if set.
    /// `None` for a run with a fixed k, which has no tolerances to meet. The one rule the CLI,
    /// the summary and the viewer share.
    #[must_use]
    pub fn tolerances_met(&self, params: &crate::Params) -> Option<bool> {
        params.k.is_none().then(|| self.unmet(params).is_empty())
    }

    /// Which tolerances a tolerance-mode run left unmet, each with its value and its limit
    /// (see [`Unmet`]), in the order TOV, protrusion, MOV. Empty when every tolerance is met
    /// or the run had a fixed k.
    #[must_use]
    pub fn unmet(&self, params: &crate::Params) -> Vec<Unmet> {
        if params.k.is_some() {
            return Vec::new();
        }
        let m = &self.metrics;
        let tol = crate::refine::Tolerances::of(params, m.diagonal);
        let x = crate::refine::Figures {
            tov: m.tov,
            mov: m.mov,
            protrusion: m.protrusion,
            over: 0.0,
        };
        let mut out = Vec::new();
        let lattice = self.route != crate::Route::Surface;
        if lattice && tol.tov_bad(x) {
            out.push(Unmet {
                tolerance: Tolerance::Tov,
                value: m.tov,
                limit: tol.tov,
            });
        }
        if tol.protrusion_bad(x) {
            out.push(Unmet {
                tolerance: Tolerance::Protrusion,
                value: m.protrusion,
                limit: tol.protrusion,
            });
        }
        if let Some(t) = tol.mov.filter(|_| lattice && tol.mov_bad(x)) {
            out.push(Unmet {
                tolerance: Tolerance::Mov,
                value: m.mov,
                limit: t,
            });
        }
        out
    }

    /// The invariants every result keeps, checked before it is returned: one volume per part,
    /// finite figures and volumes, parts and labels in range. A broken one is a bug, reported
    /// as [`crate::Error::Internal`] instead of a result with NaNs in it.
    pub(crate) fn check(&self) -> Result<(), crate::Error> {
        let bad = |what: &str| Err(crate::Error::Internal(what.to_owned()));
        let k = self.parts.len();
        if k == 0 || self.metrics.k != k {
            return bad("the part count is inconsistent");
        }
        let m = &self.metrics;
        if ![m.f, m.tov, m.mov, m.protrusion]
            .iter()
            .all(|x| x.is_finite())
        {
            return bad("a figure of the result is not finite");
        }
        let finite = |v: &BoundingVolume| {
            v.center.is_finite()
                && v.radii.is_finite()
                && v.axes.is_finite()
                && v.radii.min_element() >= 0.0
        };
        if !self
            .parts
            .iter()
            .all(|p| finite(&p.volume) && p.ov.is_finite() && p.protrusion.is_finite())
        {
            return bad("a volume of the result is not finite");
        }
        if !self.hierarchy.iter().all(|n| finite(&n.volume)) {
            return bad("a volume of the hierarchy is not finite");
        }
        let in_range = |l: &u32| (*l as usize) < k;
        if !self.triangle_parts.iter().all(in_range) || !self.sample_parts.iter().all(in_range) {
            return bad("a label of the result is out of range");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::{segment, shapes, Error, Params};
    use glam::DVec3;

    #[test]
    fn a_result_with_a_nan_is_an_internal_error() {
        let mesh = shapes::ellipsoid(
            DVec3::ZERO,
            DVec3::new(2.0, 1.0, 1.0),
            glam::DMat3::IDENTITY,
            12,
        );
        let params = Params {
            samples: 1000,
            k: Some(2),
            ..Params::default()
        };
        let seg = segment(&mesh, &params).unwrap();
        assert_eq!(seg.check(), Ok(()));
        let mut broken = seg.clone();
        broken.parts[0].volume.radii.x = f64::NAN;
        assert!(matches!(broken.check(), Err(Error::Internal(_))));
        let mut broken = seg.clone();
        broken.metrics.tov = f64::NAN;
        assert!(matches!(broken.check(), Err(Error::Internal(_))));
        let mut broken = seg;
        broken.sample_parts[0] = 7;
        assert!(matches!(broken.check(), Err(Error::Internal(_))));
    }
}
