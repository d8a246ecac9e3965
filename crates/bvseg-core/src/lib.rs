//! # bvseg-core
//!
//! Wraps a solid, given as a closed triangle mesh, in the union of a few simple volumes
//! (ellipsoids, oriented boxes, spheres, capsules, cylinders, convex hulls: [`Shape`], chosen
//! per part among [`Params::kinds`]) by segmenting its volume variationally (Lu, Choi, Wang,
//! Kim: *Variational 3D Shape Segmentation for Bounding Volume Computation*, Eurographics
//! 2007).
//!
//! ```
//! use bvseg_core::{segment, Mesh, Params};
//! use glam::DVec3;
//! // A unit cube.
//! let v: Vec<DVec3> = (0..8)
//!     .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
//!     .collect();
//! let t = vec![
//!     [0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
//!     [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5],
//! ];
//! let mesh = Mesh::new(v, t).unwrap();
//! let params = Params { samples: 2000, k: Some(1), ..Params::default() };
//! let seg = segment(&mesh, &params).unwrap();
//! assert_eq!(seg.parts.len(), 1);
//! ```
//!
//! ## The house
//!
//! The data flows one way: [`Mesh`] -> samples (`sampling`) -> partition (`initialization`,
//! `optimization`) -> volumes (`fitting`, `bounding`, `enclosure`) -> report ([`Segmentation`]).
//! `pipeline` runs the paper's loop step by step ([`Segmenter`]); `refine` holds its
//! decisions (split, merge, checkpoint, patience, budget), one file each; the stages it calls
//! are one module each: `sampling` (the inside test and the lattice), `moments`, `assignment`
//! and `flooding` (connectivity), `initialization`, `optimization`, `fitting` with
//! `enclosure` and `bounding`, `metrics` (outside volumes, on two lattices), `tightening`,
//! `reshaping`, `hierarchy`. All of them are private: the API is this page. [`shapes`] builds
//! test solids.
#![warn(missing_docs)]
// Index loops over 3x3 matrices and parallel arrays read more clearly than iterator chains.
#![allow(clippy::needless_range_loop)]

mod assignment;
mod bounding;
mod cancel;
mod enclosure;
mod error;
mod fitting;
mod flooding;
mod geometry;
mod hierarchy;
mod initialization;
mod kinds;
mod linalg;
mod math;
mod mesh;
mod metrics;
mod moments;
mod multigrid;
mod optimization;
mod parallel;
mod params;
mod partition;
mod pipeline;
mod posing;
mod refine;
mod reshaping;
mod result;
mod rig;
mod rng;
mod sampling;
pub mod shapes;
mod shells;
mod skeleton;
mod tightening;
mod volume;

pub use cancel::Cancel;
pub use error::{Error, MeshError, NoVolume, ParamError, RigError, TooComplex};
pub use kinds::{Kinds, Target, UnknownKind};
pub use mesh::{weld, Mesh, MAX_COORDINATE};
pub use params::{
    Params, Route, Sampling, SkeletonMode, DEFAULT_MAX_PROTRUSION, MAX_HULL_VERTICES, MAX_K,
    MAX_SAMPLES,
};
pub use pipeline::Segmenter;
pub use result::{
    HierarchyNode, Metrics, Part, Segmentation, Step, StepKind, Tolerance, Unmet, BUDGET_WARNING,
};
pub use rig::{Joint, Pose, Rig, Skeleton, Skin};
pub use volume::{BoundingVolume, Polytope, Shape, ShapeView, BALL_COVER_VERTICES};

/// The stages' own entry points, for the benchmarks, the fuzz targets and the tests that
/// check one stage at a time. Not part of the API: anything here may change in any release.
#[doc(hidden)]
pub mod internals {
    pub use crate::assignment::{assign, PartMetric, Rule};
    pub use crate::bounding::axial::{min_axial, min_capsule_and_cylinder, Axial};
    pub use crate::bounding::hull::{convex_hull, hull_points};
    pub use crate::bounding::mvee::{mvee, mvee_of_hull};
    pub use crate::bounding::obb::min_obb;
    pub use crate::enclosure::Enclosure;
    pub use crate::fitting::{Fitter, MVEE_TOL};
    pub use crate::flooding::{is_connected, solid_components};
    pub use crate::initialization::cvt;
    pub use crate::linalg::dense::{cholesky_solve, invert, log_det};
    pub use crate::linalg::sym_eigen;
    pub use crate::optimization::{lloyd, move_boundary_samples, optimize};
    pub use crate::partition::{Partition, Solid};
    pub use crate::rng::Rng;
    pub use crate::sampling::{inside::inside_cells, Grid, NONE};
    /// The count of work done on the calling thread (see `tests/linear_cost.rs`).
    pub mod work {
        pub use crate::work::{add, total};
    }
}
mod work;

/// Segment `mesh` and bound each part, with the parameters `params`.
///
/// # Errors
///
/// [`Error::InvalidParams`] for parameters out of range, [`Error::NoVolume`] when the mesh
/// encloses nothing the lattice can see, [`Error::TooComplex`] for surfaces beyond the inside
/// test's work bound, [`Error::Internal`] for a bug.
pub fn segment(mesh: &Mesh, params: &Params) -> Result<Segmentation, Error> {
    segment_with(mesh, params, |_| {})
}

/// Like [`segment`], calling `on_step` after every refinement step (for progress display).
///
/// # Errors
///
/// As [`segment`].
pub fn segment_with(
    mesh: &Mesh,
    params: &Params,
    mut on_step: impl FnMut(&Step),
) -> Result<Segmentation, Error> {
    let mut seg = Segmenter::new(mesh, params)?;
    while let Some(step) = seg.step() {
        on_step(&step);
    }
    seg.finish()
}

// The crate page's example (README.md, also shown on crates.io) is compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
