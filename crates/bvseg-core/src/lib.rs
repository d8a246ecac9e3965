//! # bvseg-core
//!
//! Wraps a solid, given as a closed triangle mesh, in the union of a few ellipsoids or
//! oriented boxes by segmenting its volume variationally (Lu, Choi, Wang, Kim: *Variational
//! 3D Shape Segmentation for Bounding Volume Computation*, Eurographics 2007).
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
//! The pipeline, one module per stage: [`sampling`] -> [`moments`] -> [`initialization`] ->
//! [`assignment`] / [`flooding`] -> [`optimization`] -> [`refinement`] (judged with
//! [`fitting`]: [`bounding`] volumes of the [`enclosure`] points, measured by [`metrics`]) ->
//! [`tightening`] -> [`reshaping`] -> [`hierarchy`]. [`Segmenter`] runs it step by step;
//! [`segment`] runs it to the end.
#![warn(missing_docs)]
// Index loops over 3x3 matrices and parallel arrays read more clearly than iterator chains.
#![allow(clippy::needless_range_loop)]

pub mod assignment;
pub mod bounding;
mod cancel;
pub mod enclosure;
mod error;
pub mod fitting;
pub mod flooding;
pub mod hierarchy;
pub mod initialization;
pub mod linalg;
mod math;
mod mesh;
pub mod metrics;
pub mod moments;
pub mod optimization;
mod parallel;
mod params;
pub mod partition;
pub mod refinement;
pub mod reshaping;
mod result;
pub mod rng;
pub mod sampling;
pub mod shapes;
pub mod tightening;
pub mod verify;
mod volume;
#[doc(hidden)]
pub mod work;

pub use cancel::Cancel;
pub use error::Error;
pub use mesh::{Mesh, MAX_COORDINATE};
pub use params::{BoundingKind, Params, MAX_SAMPLES};
pub use refinement::Segmenter;
pub use result::{HierarchyNode, Metrics, Part, Segmentation, Step, StepKind};
pub use volume::{BoundingVolume, Shape};

/// Segment `mesh` and bound each part, with the parameters `params`.
pub fn segment(mesh: &Mesh, params: &Params) -> Result<Segmentation, Error> {
    segment_with(mesh, params, |_| {})
}

/// Like [`segment`], calling `on_step` after every refinement step (for progress display).
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
