//! # bvseg
//!
//! Tight unions of ellipsoids and oriented boxes around 3D meshes. This facade re-exports
//! the core ([`bvseg_core`], pure computation) and the I/O crate ([`bvseg_io`]).
pub use bvseg_core::*;
pub use bvseg_io as io;
