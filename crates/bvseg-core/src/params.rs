//! The parameters of a run.
use crate::error::ParamError;
use crate::kinds::Kinds;

/// Parameters of [`crate::segment`]. `Params::default()`: 20,000 samples, every primitive
/// kind ([`Kinds::PRIMITIVES`]), and
/// tolerance mode with TOV below 0.3 (the paper's sigma_G) and the protrusion below
/// [`DEFAULT_MAX_PROTRUSION`] of the box diagonal, at most 96 parts.
/// [`Params::validate`] checks every range below; [`crate::segment`] calls it first.
///
/// ```
/// use bvseg_core::{Kinds, Params};
/// // Eight oriented boxes, whatever the tolerances.
/// let p = Params { k: Some(8), kinds: Kinds::OBB, ..Params::default() };
/// assert!(p.validate().is_ok());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Target number of interior samples (lattice cells inside the solid). More samples
    /// resolve thinner features and give tighter volumes, at a cost roughly linear in them.
    /// Default 20,000; range 100 to [`MAX_SAMPLES`]; a count (the lattice gets within a few
    /// per cent of it).
    pub samples: usize,
    /// Seed of the initialisation: equal seeds give bit-identical results, on any thread
    /// count and platform. It matters only with a fixed [`Params::k`]: the tolerance mode
    /// starts from one part per piece of the solid, which needs no random choice, and splits
    /// deterministically. Default 0; any value.
    pub seed: u64,
    /// The kinds of bounding volume a part may get: each part gets, of these, the volume
    /// that adds the least outside volume. Default [`Kinds::PRIMITIVES`] (ellipsoid, box,
    /// sphere, capsule, cylinder: the tightest primitive set on the shared meshes);
    /// [`Kinds::ELLIPSOID`] is the paper's; [`crate::Target::kinds`] gives an engine's
    /// native set. Not empty.
    pub kinds: Kinds,
    /// Most vertices of a hull volume ([`crate::Shape::Hull`]): the hull of a part with more
    /// is replaced by an enclosing polyhedron with at most this many (engines cap convex
    /// meshes: PhysX at 255, Unity at 255, many pipelines at 32 or 64). Default 32; range
    /// 4 to [`MAX_HULL_VERTICES`]. Fewer vertices are looser and cheaper to collide.
    pub max_hull_vertices: usize,
    /// Fixed number of parts: skip the tolerance loop and return exactly this many parts
    /// (fewer only when the solid has fewer samples). Default `None` (tolerance mode); range
    /// 1 to `samples / 8`.
    pub k: Option<usize>,
    /// Tolerance on the total outside volume TOV, the volume of the union outside the solid
    /// relative to the solid's (sigma_G in the paper). Tolerance mode splits parts until TOV
    /// is below it. Default 0.3; finite, at least 0; a ratio. Lower values need more parts.
    pub tov: f64,
    /// The paper's local tolerance, on the largest per-part outside volume MOV relative to
    /// the part's volume (sigma_L): `None` (the default) leaves MOV unchecked. With the whole
    /// surface enclosed, a part at a flat end has OV >= 0.5 and one at a pointed tip more,
    /// whatever k (see the method's docs), so the paper's 0.5 cannot be met on most models;
    /// the protrusion is the local tolerance instead. When set: finite, at least 0, a ratio;
    /// refinement then also stops when more parts no longer lower MOV.
    pub mov: Option<f64>,
    /// The local tolerance: the largest distance from the union's boundary to the surface
    /// (the one-way Hausdorff distance, "protrusion"), as a fraction of the mesh's
    /// bounding-box diagonal. Tolerance mode splits the part that protrudes most until it is
    /// below this (once TOV is met). Default [`DEFAULT_MAX_PROTRUSION`]; finite, above 0.
    /// Smaller values need more parts.
    pub max_protrusion: f64,
    /// The same tolerance in mesh units; when set, it replaces [`Params::max_protrusion`]
    /// (for users who think in millimetres). Default `None`; finite, above 0.
    pub max_protrusion_abs: Option<f64>,
    /// Upper bound on the number of parts in tolerance mode. Default 96 (the thin-limbed shared
    /// human_2 needs 82 to meet the default tolerances; most models stop far below); range 1
    /// to [`MAX_K`].
    pub max_k: usize,
    /// Merge parts at the end of the tolerance loop while that lowers TOV (and keeps met
    /// tolerances met). Default `true`.
    pub merge: bool,
    /// Beyond the paper, lower the outside volume of the union of the bounding volumes, which
    /// F only stands in for: move boundary layers between neighbouring parts while that
    /// lowers it (at checkpoints of the tolerance loop when splits stall near the TOV
    /// tolerance, and before the final step, where tolerance mode also moves layers at the
    /// part with the largest OV while that lowers an unmet MOV), then reshape the output
    /// volumes (and switch their kinds among the run's) to stick out of the solid less.
    /// Tighter (TOV typically 10-20 % lower) for about a third more time. Does not turn off
    /// the boundary sample moves that lower F in every optimisation. Default `true`.
    pub tighten: bool,
    /// Upper bound on Lloyd sweeps per optimisation. Default 100; at least 1. The loop
    /// usually converges in far fewer.
    pub max_sweeps: usize,
    /// Grow every output volume (and every node of the hierarchy) outward by this distance,
    /// in mesh units (see [`crate::BoundingVolume::grown`]). The volumes enclose the mesh as
    /// given, in f64; an engine that stores them, or the mesh, in f32 moves each by up to an
    /// ulp or so of its coordinates, and a margin of that size (for example `1e-6` times the
    /// mesh's largest coordinate) keeps the enclosure. Default 0; finite and at least 0. The
    /// reported figures (TOV, MOV) are those of the grown volumes.
    pub margin: f64,
    /// Build the bounding-volume hierarchy over the parts (paper section 5.3) into
    /// [`crate::Segmentation::hierarchy`]. It costs about a sixth of a default run (every
    /// candidate parent gets a volume of each kind); without it the hierarchy is left empty.
    /// Default `true`; the CLI turns it off when no output it writes carries the hierarchy
    /// (only the JSON document does).
    pub hierarchy: bool,
    /// Where the start's seeds come from (the paper's section 6.1): [`SkeletonMode::Rig`]
    /// (the default) seeds one part per link of the mesh's [`crate::Skeleton`] when it has
    /// one, and binds every part to a bone; [`SkeletonMode::Auto`] computes an approximate
    /// curve skeleton of the solid first; [`SkeletonMode::None`] ignores any skeleton.
    pub skeleton: SkeletonMode,
    /// How the solid's interior is sampled (the paper's section 6.2): [`Sampling::Regular`]
    /// (the default), one sample per cell of a regular lattice; [`Sampling::Adaptive`], a
    /// finer lattice whose thick inside is gathered into weighted blocks, so that thin
    /// features get more samples at the same [`Params::samples`].
    pub sampling: Sampling,
    /// How the mesh is bounded: [`Route::Auto`] (the default) samples the interior of a solid
    /// on a lattice and partitions it (the paper's method) and bounds clusters of triangles
    /// from the surface where the lattice cannot see an interior: meshes with open or thin
    /// pieces, meshes of several pieces that one volume each holds, skinned characters, in
    /// tolerance mode (a fixed [`Params::k`] always takes the lattice).
    pub route: Route,
    /// Most volumes per bone of a skinned mesh on the surface route: 1 gives one volume per
    /// bone that moves triangles (a ragdoll). Default `None`: 3. At least 1; a count.
    pub per_bone: Option<usize>,
}

/// How a run bounds the mesh (see [`Params::route`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Route {
    /// The surface route for meshes whose interior the lattice cannot sample (open or thin
    /// pieces, several pieces of one volume each, skinned characters), the lattice otherwise.
    #[default]
    Auto,
    /// Sample the solid's interior and partition it (the paper's method): needs a closed
    /// solid the lattice can see.
    Lattice,
    /// Cluster the triangles and fit each cluster's corners: encloses every triangle of any
    /// mesh, measures no interior (TOV and MOV are not measured).
    Surface,
}

impl std::str::FromStr for Route {
    type Err = String;

    /// `"auto"`, `"lattice"` or `"surface"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Self::Auto),
            "lattice" => Ok(Self::Lattice),
            "surface" => Ok(Self::Surface),
            _ => Err(format!(
                "{s:?} is not a route: use auto, lattice or surface"
            )),
        }
    }
}

impl std::fmt::Display for Route {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Auto => "auto",
            Self::Lattice => "lattice",
            Self::Surface => "surface",
        })
    }
}

/// How the solid's interior is sampled (see [`Params::sampling`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Sampling {
    /// One sample per cell of a regular lattice: every sample stands for the same volume.
    #[default]
    Regular,
    /// A finer lattice, whose cells at least 2 cells from the boundary are gathered into
    /// blocks of 2x2x2, and at least 4 into blocks of 4x4x4: each block is one sample that
    /// weighs as its cells. On the boundary and in thin features every cell is a sample.
    Adaptive,
}

/// Where the initial partition's seeds come from (see [`Params::skeleton`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum SkeletonMode {
    /// The mesh's own skeleton ([`crate::Mesh::rig`]) when it has one with a link; otherwise
    /// as [`SkeletonMode::None`].
    #[default]
    Rig,
    /// An approximate curve skeleton computed from the solid's interior samples.
    Auto,
    /// No skeleton: the tolerance mode grows parts from one per piece of the solid, a fixed
    /// k starts from a CVT.
    None,
}

impl std::str::FromStr for Sampling {
    type Err = String;

    /// `"regular"` or `"adaptive"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "regular" => Ok(Self::Regular),
            "adaptive" => Ok(Self::Adaptive),
            _ => Err(format!("{s:?} is not a sampling: use regular or adaptive")),
        }
    }
}

impl std::fmt::Display for Sampling {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Regular => "regular",
            Self::Adaptive => "adaptive",
        })
    }
}

impl std::str::FromStr for SkeletonMode {
    type Err = String;

    /// `"rig"` (the mesh's own skeleton: [`SkeletonMode::Rig`]; `"skin"`, its former name,
    /// is read as the same), `"auto"` or `"none"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "rig" | "skin" => Ok(Self::Rig),
            "auto" => Ok(Self::Auto),
            "none" => Ok(Self::None),
            _ => Err(format!(
                "{s:?} is not a skeleton mode: use rig, auto or none"
            )),
        }
    }
}

impl std::fmt::Display for SkeletonMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Rig => "rig",
            Self::Auto => "auto",
            Self::None => "none",
        })
    }
}

impl Default for Params {
    fn default() -> Self {
        Self {
            samples: 20_000,
            seed: 0,
            kinds: Kinds::PRIMITIVES,
            max_hull_vertices: 32,
            k: None,
            tov: 0.3,
            mov: None,
            max_protrusion: DEFAULT_MAX_PROTRUSION,
            max_protrusion_abs: None,
            max_k: 96,
            merge: true,
            tighten: true,
            max_sweeps: 100,
            margin: 0.0,
            hierarchy: true,
            skeleton: SkeletonMode::Rig,
            sampling: Sampling::Regular,
            route: Route::Auto,
            per_bone: None,
        }
    }
}

/// Largest [`Params::samples`]: beyond it the lattice would not fit comfortably in memory.
pub const MAX_SAMPLES: usize = 50_000_000;

/// Default [`Params::max_protrusion`]: a fraction of the box diagonal.
pub const DEFAULT_MAX_PROTRUSION: f64 = 0.05;

/// Largest [`Params::max_hull_vertices`] (PhysX's limit on a convex mesh).
pub const MAX_HULL_VERTICES: usize = 255;

/// Largest [`Params::max_k`].
pub const MAX_K: usize = 4096;

/// Smallest [`Params::samples`].
const MIN_SAMPLES: usize = 100;

impl Params {
    /// The protrusion tolerance in mesh units, for a mesh whose bounding box has diagonal
    /// `diagonal`: [`Params::max_protrusion_abs`], or [`Params::max_protrusion`] times the
    /// diagonal.
    #[must_use]
    pub fn protrusion_tolerance(&self, diagonal: f64) -> f64 {
        self.max_protrusion_abs
            .unwrap_or(self.max_protrusion * diagonal)
    }

    /// The same tolerance as a fraction of the diagonal.
    #[must_use]
    pub fn protrusion_tolerance_rel(&self, diagonal: f64) -> f64 {
        self.max_protrusion_abs
            .map_or(self.max_protrusion, |a| a / diagonal)
    }

    /// Check every parameter against its range.
    ///
    /// # Errors
    ///
    /// The first rule broken, as a [`ParamError`].
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.samples < MIN_SAMPLES || self.samples > MAX_SAMPLES {
            return Err(ParamError::Samples {
                value: self.samples,
                min: MIN_SAMPLES,
                max: MAX_SAMPLES,
            });
        }
        match self.k {
            Some(0) => return Err(ParamError::KZero),
            Some(k) if k > self.samples / 8 => {
                return Err(ParamError::KTooLarge {
                    value: k,
                    samples: self.samples,
                })
            }
            _ => {}
        }
        for (field, value) in [("tov", Some(self.tov)), ("mov", self.mov)] {
            if let Some(value) = value.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(ParamError::Tolerance { field, value });
            }
        }
        for (field, value) in [
            ("max_protrusion", Some(self.max_protrusion)),
            ("max_protrusion_abs", self.max_protrusion_abs),
        ] {
            if let Some(value) = value.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(ParamError::Protrusion { field, value });
            }
        }
        if self.max_k == 0 || self.max_k > MAX_K {
            return Err(ParamError::MaxK {
                value: self.max_k,
                max: MAX_K,
            });
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err(ParamError::Margin { value: self.margin });
        }
        if self.max_sweeps == 0 {
            return Err(ParamError::MaxSweeps);
        }
        if self.per_bone == Some(0) {
            return Err(ParamError::PerBoneZero);
        }
        if self.kinds.is_empty() {
            return Err(ParamError::NoKinds);
        }
        if !(4..=MAX_HULL_VERTICES).contains(&self.max_hull_vertices) {
            return Err(ParamError::MaxHullVertices {
                value: self.max_hull_vertices,
                min: 4,
                max: MAX_HULL_VERTICES,
            });
        }
        Ok(())
    }
}
