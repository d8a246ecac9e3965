//! # bvseg-io
//!
//! File formats for bvseg: meshes in ([`load_mesh`]: Wavefront OBJ, glTF 2.0 / GLB, STL) and
//! results out (the `bvseg.volumes/1` JSON document, [`write_json`]; engine-ready proxies in
//! [`export`]). Every error is an [`IoError`] whose message is one line naming the file;
//! nothing here panics on bad input, and no allocation is sized by an unchecked count read
//! from a file.
#![warn(missing_docs)]

mod atomic;
mod error;
pub mod export;
mod finish;
mod gltf_in;
mod json;
mod obj;
mod report;
mod stl;
mod volumes_read;

use std::path::Path;

pub use volumes_read::{
    parse_volumes, read_volumes, ReportedMetrics, VolumesFile, MAX_VOLUMES, MAX_VOLUMES_BYTES,
};

pub use atomic::write_atomic;
pub use error::IoError;
pub use finish::{LoadStats, LoadedMesh, MAX_TRIANGLES};
pub use json::{to_json_string, write_json, GENERATOR, SCHEMA};
pub use obj::{
    load_obj, load_obj_detailed, load_obj_from_bytes, load_obj_from_bytes_detailed,
    load_obj_from_reader, MAX_INPUT_BYTES,
};
pub use report::MeshReport;

use bvseg_core::Mesh;

/// The mesh formats [`load_mesh`] reads, as file extensions (compared case-insensitively).
pub const MESH_EXTENSIONS: &[&str] = &["obj", "gltf", "glb", "stl"];

const SUPPORTED: &str = ".obj, .gltf, .glb, .stl";

/// Which part of a file to load.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// OBJ: only the object or group with this name (default: all merged).
    pub object: Option<String>,
    /// glTF: only the scene nodes whose mesh has this name (default: every mesh of the
    /// default scene).
    pub mesh: Option<String>,
}

/// Loads a mesh, choosing the reader by the file's extension; see [`load_mesh_detailed`].
pub fn load_mesh(path: impl AsRef<Path>) -> Result<Mesh, IoError> {
    load_mesh_detailed(path).map(|l| l.mesh)
}

/// Loads a whole mesh file, choosing the reader by the file's extension, and reports what
/// loading changed (welded vertices, dropped degenerate triangles) and what the mesh is like.
pub fn load_mesh_detailed(path: impl AsRef<Path>) -> Result<LoadedMesh, IoError> {
    load_mesh_with(path, &LoadOptions::default())
}

/// Like [`load_mesh_detailed`], loading only what `options` selects.
pub fn load_mesh_with(
    path: impl AsRef<Path>,
    options: &LoadOptions,
) -> Result<LoadedMesh, IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let ext = extension(path);
    let ext = check_extension(ext, &name, options)?;
    let file = obj::open_input(path, &name)?;
    match ext {
        Format::Obj => obj::read_obj(
            std::io::BufReader::new(file),
            &name,
            options.object.as_deref(),
        ),
        Format::Stl => stl::read_stl(&gltf_in::read_limited(file, &name)?, &name),
        Format::Gltf => {
            let bytes = gltf_in::read_limited(file, &name)?;
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            gltf_in::read_gltf(
                &bytes,
                &name,
                gltf_in::Externals::Dir(dir),
                options.mesh.as_deref(),
            )
        }
    }
}

/// Loads a mesh held in memory; the format is chosen by the extension of `name` (which
/// error messages also use). glTF documents with external buffer files cannot be read this
/// way (there is no directory to read them from); GLB and embedded buffers work.
pub fn load_mesh_from_bytes(bytes: &[u8], name: &str) -> Result<LoadedMesh, IoError> {
    load_mesh_from_bytes_with(bytes, name, &LoadOptions::default())
}

/// Like [`load_mesh_from_bytes`], loading only what `options` selects.
pub fn load_mesh_from_bytes_with(
    bytes: &[u8],
    name: &str,
    options: &LoadOptions,
) -> Result<LoadedMesh, IoError> {
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(IoError::TooLarge {
            name: name.to_owned(),
            limit: MAX_INPUT_BYTES,
        });
    }
    let ext = extension(Path::new(name));
    match check_extension(ext, name, options)? {
        Format::Obj => obj::read_obj(bytes, name, options.object.as_deref()),
        Format::Stl => stl::read_stl(bytes, name),
        Format::Gltf => gltf_in::read_gltf(
            bytes,
            name,
            gltf_in::Externals::None,
            options.mesh.as_deref(),
        ),
    }
}

enum Format {
    Obj,
    Stl,
    Gltf,
}

fn check_extension(
    ext: Option<String>,
    name: &str,
    options: &LoadOptions,
) -> Result<Format, IoError> {
    let format = match ext.as_deref() {
        Some("obj") => Format::Obj,
        Some("stl") => Format::Stl,
        Some("gltf" | "glb") => Format::Gltf,
        _ => {
            return Err(IoError::UnsupportedFormat {
                name: name.to_owned(),
                what: "mesh",
                ext,
                supported: SUPPORTED,
            })
        }
    };
    let misuse = |opt: &str, fmt: &str| IoError::BadPath {
        name: name.to_owned(),
        message: format!("{opt} applies only to {fmt} files"),
    };
    if options.object.is_some() && !matches!(format, Format::Obj) {
        return Err(misuse("--object", "OBJ"));
    }
    if options.mesh.is_some() && !matches!(format, Format::Gltf) {
        return Err(misuse("--mesh", "glTF"));
    }
    Ok(format)
}

/// The extension of `path` in lower case, without the dot.
pub fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}
