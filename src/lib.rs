//! # bvseg
//!
//! Tight unions of ellipsoids and oriented boxes around 3D meshes. This facade re-exports
//! the core ([`bvseg_core`], pure computation) and the I/O crate ([`bvseg_io`]).
pub use bvseg_core::*;
pub use bvseg_io as io;

// The README's and the library manual's Rust examples are compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

#[cfg(doctest)]
#[doc = include_str!("../docs/library.md")]
pub struct LibraryManualDoctests;
