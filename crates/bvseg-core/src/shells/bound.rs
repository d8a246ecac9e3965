//! A cluster's volume: of the run's kinds, the smallest that holds its triangles (in every
//! pose, for a skinned mesh), and how far it reaches past the surface.
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

use crate::refine::budget::DISTANCE_PER_SAMPLE;

/// Nodes and triangles of the surface's tree one protrusion may visit. A cluster of a
/// low-poly asset needs a few thousand; a fan of huge overlapping triangles makes every query
/// visit them all. (A tenth of the lattice route's: its fits are far fewer.)
pub const DISTANCE_PER_FIT: u64 = crate::refine::budget::DISTANCE_PER_FIT / 10;

use crate::bounding::{self, hull::hull_points};
use crate::math;
use crate::mesh::Mesh;
use crate::metrics::{surface_protrusion, surface_protrusion_exceeds, SurfaceDistance};
use crate::params::Params;
use crate::rig::{Skeleton, Skin};
use crate::volume::BoundingVolume;

/// Smallest radius of a fitted volume, relative to the diagonal: a flat cluster (a quad, a
/// leaf card) gets a box this thick rather than a degenerate one.
pub const MIN_R_REL: f64 = 1e-4;

/// A corner in a pose that lies this close (relative to the diagonal) to the last sample of
/// it kept is left out of the fit, and the volume grown by that much instead: most corners
/// come back to their rest position with their bone, and leaving them out keeps fits fast.
const KEEP_REL: f64 = 5e-4;

/// A cluster's fitted volume.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The volume.
    pub volume: BoundingVolume,
    /// The hull points it was fitted to (rest pose; poses carried back by the bone).
    pub hull: Vec<DVec3>,
    /// What the volume was grown by for the motion between sampled poses.
    pub margin: f64,
    /// How far its boundary reaches from the surface (mesh units), alone: measured when first
    /// asked (most candidate fits of the split and the merge are decided by size alone).
    protrusion: std::sync::OnceLock<f64>,
}

impl Fit {
    /// Whether the volume keeps within the tolerance (cheaper than its protrusion when it
    /// does not).
    pub fn within(&self, b: &Bounder) -> bool {
        self.within_capped(b, b.cap(), true)
    }

    /// [`Fit::within`] for a search that runs in parallel with others: with a fit's cap, not
    /// counted against the budget (see [`Bounder::counted`]).
    pub fn within_in_parallel(&self, b: &Bounder) -> bool {
        self.within_capped(b, DISTANCE_PER_FIT, false)
    }

    fn within_capped(&self, b: &Bounder, cap: u64, count: bool) -> bool {
        match self.protrusion.get() {
            Some(&p) => p <= b.tol,
            None => {
                let (over, spent) =
                    surface_protrusion_exceeds(&self.volume, &b.surface, b.tol, &self.hull, cap);
                if count {
                    b.spend(spent);
                }
                !over
            }
        }
    }

    /// How far the volume's boundary reaches from the surface (mesh units), alone.
    pub fn protrusion(&self, b: &Bounder) -> f64 {
        *self.protrusion.get_or_init(|| {
            let (p, spent) = surface_protrusion(&self.volume, &b.surface, &[], &self.hull, b.cap());
            b.spend(spent);
            p
        })
    }
}

/// Fits volumes to sets of triangles.
pub struct Bounder<'a> {
    pub mesh: &'a Mesh,
    pub params: &'a Params,
    pub surface: SurfaceDistance,
    /// The protrusion tolerance, mesh units.
    pub tol: f64,
    pub diagonal: f64,
    /// The skin and skeleton, when the volumes follow bones.
    pub skin: Option<(&'a Skeleton, &'a Skin)>,
    /// The run's bound on the protrusions' searches (as the lattice route's, per sample the
    /// run would have had), and what they spent. Beyond it a protrusion is the distance to
    /// the nearest of the fit's points, an upper bound: no tolerance is met by mistake.
    budget: u64,
    spent: AtomicU64,
    /// Whether the searches count against the budget: only where they run in a fixed order
    /// (the split and the merge), so that results do not depend on the thread count; the
    /// searches run in parallel have only each fit's own cap.
    counted: bool,
}

impl<'a> Bounder<'a> {
    pub fn new(mesh: &'a Mesh, params: &'a Params, skin: Option<(&'a Skeleton, &'a Skin)>) -> Self {
        let (lo, hi) = mesh.bbox();
        let diagonal = (hi - lo).length();
        Self {
            mesh,
            params,
            surface: SurfaceDistance::new(mesh),
            tol: params.protrusion_tolerance(diagonal),
            diagonal,
            skin,
            budget: DISTANCE_PER_SAMPLE * params.samples as u64,
            spent: AtomicU64::new(0),
            counted: false,
        }
    }

    /// This bounder with its searches counted against the budget (see [`Bounder::counted`]).
    pub fn counting(mut self) -> Self {
        self.counted = true;
        self
    }

    /// The cap on the next search: a fit's, while the budget lasts.
    fn cap(&self) -> u64 {
        if self.counted && self.spent.load(Ordering::Relaxed) > self.budget {
            0
        } else {
            DISTANCE_PER_FIT
        }
    }

    /// The protrusion of `v` on the union's boundary (its points inside `others` do not
    /// count), counted against the budget.
    pub fn union_protrusion(
        &self,
        v: &BoundingVolume,
        others: &[BoundingVolume],
        points: &[DVec3],
    ) -> f64 {
        let (p, spent) = surface_protrusion(v, &self.surface, others, points, self.cap());
        self.spend(spent);
        p
    }

    fn spend(&self, n: u64) {
        if self.counted {
            self.spent.fetch_add(n, Ordering::Relaxed);
        }
    }

    /// The volume of `tris`, moving with `bone` when there is a skin.
    pub fn fit(&self, tris: &[u32], bone: Option<usize>) -> Fit {
        let (points, margin) = self.points(tris, bone);
        self.fit_points(&points, margin)
    }

    /// The volume of two fits' points together: the hull of their hulls, and the larger
    /// margin (each corner's own margin is at most its fit's).
    pub fn fit_both(&self, a: &Fit, b: &Fit) -> Fit {
        let mut points = a.hull.clone();
        points.extend_from_slice(&b.hull);
        self.fit_points(&points, math::max(a.margin, b.margin))
    }

    fn fit_points(&self, points: &[DVec3], margin: f64) -> Fit {
        let hull = hull_points(points);
        let hull = if hull.is_empty() {
            points.to_vec()
        } else {
            hull
        };
        let volume = smallest(self.params, &hull, MIN_R_REL * self.diagonal).grown(margin);
        Fit {
            volume,
            hull,
            margin,
            protrusion: std::sync::OnceLock::new(),
        }
    }

    /// The points a volume of `tris` must hold, and the margin to grow it by: the corners at
    /// rest and, with a skin, their positions in every pose carried back into the rest pose by
    /// `bone` (a volume `V` at rest is `G(t) G(rest)⁻¹ V` in a pose, so it holds `x(t)` there
    /// exactly when `V` holds `G(rest) G(t)⁻¹ x(t)`). Between two sampled poses a corner
    /// strays from the chord by about what the chord of three consecutive poses misses, which
    /// the margin adds (as the lattice route does: see `crate::posing`).
    fn points(&self, tris: &[u32], bone: Option<usize>) -> (Vec<DVec3>, f64) {
        let mesh = self.mesh;
        let mut rest: Vec<u32> = tris
            .iter()
            .flat_map(|&t| mesh.triangles()[t as usize])
            .collect();
        rest.sort_unstable();
        rest.dedup();
        let mut points: Vec<DVec3> = rest.iter().map(|&v| mesh.vertices()[v as usize]).collect();
        let (Some(b), Some((skeleton, skin))) = (bone, self.skin) else {
            return (points, 0.0);
        };
        if skin.poses.is_empty() {
            return (points, 0.0);
        }
        let (moved, margin) =
            crate::posing::carried_back(mesh, skeleton, skin, b, tris, KEEP_REL * self.diagonal);
        points.extend(moved);
        (points, margin)
    }
}

/// Of `params`' kinds, the smallest volume that holds `points` (no radius below `min_r`).
pub fn smallest(params: &Params, points: &[DVec3], min_r: f64) -> BoundingVolume {
    let fit = |s| {
        bounding::fit(s, points, min_r, params.max_hull_vertices)
            .scaled_to_contain(points.iter().copied())
    };
    params
        .kinds
        .shapes()
        .map(fit)
        .filter(|v| v.volume().is_finite())
        .min_by(|a, b| a.volume().total_cmp(&b.volume()))
        // Params::validate refuses an empty set of kinds; a box whatever happens.
        .unwrap_or_else(|| fit(crate::volume::Shape::Obb))
}
