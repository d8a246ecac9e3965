//! # bvseg
//!
//! Tight unions of ellipsoids, boxes, spheres, capsules, cylinders and convex hulls around
//! 3D meshes. This facade re-exports the core ([`bvseg_core`], pure computation) and the I/O
//! crate ([`bvseg_io`]); with the `parry` feature, `bvseg::parry` turns a result into parry3d
//! shapes (rapier, Avian).
pub use bvseg_core::*;
pub use bvseg_io as io;

#[cfg(feature = "parry")]
pub mod parry;

// The README's and the library manual's Rust examples are compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/library.md")]
pub struct LibraryManualDoctests;
