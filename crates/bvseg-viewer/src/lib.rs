//! # bvseg-viewer
//!
//! An interactive viewer for bvseg, one eframe app for the desktop and the browser. It runs
//! the real core ([`bvseg_core::Segmenter`]) a bounded amount per frame, or in the background
//! in the page's threaded build (feature `threads`), so the view follows the refinement live
//! and the UI never freezes, even in a page without threads.
//!
//! - [`app`]: the [`ViewerApp`] (panels, controls, input and output).
//! - [`session`]: one segmentation run, stepped under a time budget or run in the background,
//!   with its history; [`budget`] sizes each frame's share of the work.
//! - [`meshes`]: the bundled sample meshes and the one function that turns file bytes into a mesh.
//! - [`scene`], [`camera`], [`render`]: the 3D view (CPU geometry, orbit camera, glow renderer).
//! - [`animation`]: a character's animation played in the view, its volumes moving with
//!   their bones.
//! - [`kinds`]: the volume kinds a run may use (the controls' presets, names, part sizes).
//! - [`plot`]: TOV and MOV against k.
//! - [`platform`]: what differs between native and web (reporting, files).
#![warn(missing_docs)]

pub mod animation;
pub mod app;
pub mod budget;
pub mod camera;
pub mod kinds;
pub mod meshes;
pub mod platform;
pub mod plot;
pub mod render;
pub mod scene;
pub mod session;
#[cfg(target_arch = "wasm32")]
mod web;

pub use app::{Export, Settings, StartMesh, StartOptions, Status, ViewerApp};
pub use meshes::{load_mesh_bytes, BundledMesh, LoadedFile, BUNDLED};
pub use session::{Session, Snapshot};
