//! # bvseg-io
//!
//! File formats for bvseg: meshes in ([`load_mesh`], Wavefront OBJ for now) and results out
//! (the `bvseg.volumes/1` JSON document, [`write_json`]). Every error is an [`IoError`] whose
//! message is one line naming the file; nothing here panics on bad input.
#![warn(missing_docs)]

mod atomic;
mod error;
mod json;
mod obj;
mod volumes_read;

use std::path::Path;

pub use volumes_read::{
    parse_volumes, read_volumes, ReportedMetrics, VolumesFile, MAX_VOLUMES, MAX_VOLUMES_BYTES,
};

pub use atomic::write_atomic;
pub use error::IoError;
pub use json::{to_json_string, write_json, GENERATOR, SCHEMA};
pub use obj::{
    load_obj, load_obj_detailed, load_obj_from_bytes, load_obj_from_bytes_detailed,
    load_obj_from_reader, LoadStats, LoadedMesh, MAX_INPUT_BYTES,
};

use bvseg_core::Mesh;

/// The mesh formats [`load_mesh`] reads, as file extensions (compared case-insensitively).
pub const MESH_EXTENSIONS: &[&str] = &["obj"];

/// Loads a mesh, choosing the reader by the file's extension; see [`load_mesh_detailed`].
pub fn load_mesh(path: impl AsRef<Path>) -> Result<Mesh, IoError> {
    load_mesh_detailed(path).map(|l| l.mesh)
}

/// Loads a mesh, choosing the reader by the file's extension (only `.obj` for now), and
/// reports what loading changed (welded vertices, dropped degenerate triangles).
pub fn load_mesh_detailed(path: impl AsRef<Path>) -> Result<LoadedMesh, IoError> {
    let path = path.as_ref();
    match extension(path).as_deref() {
        Some("obj") => load_obj_detailed(path),
        ext => Err(IoError::UnsupportedFormat {
            name: path.display().to_string(),
            what: "mesh",
            ext: ext.map(str::to_owned),
            supported: ".obj",
        }),
    }
}

/// The extension of `path` in lower case, without the dot.
pub fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}
