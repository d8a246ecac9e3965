//! # bvseg-io
//!
//! File formats for bvseg: meshes in ([`load`], [`load_bytes`]: Wavefront OBJ, glTF 2.0 /
//! GLB, STL) and results out (the `bvseg.volumes/1` JSON document, [`write_json`];
//! engine-ready proxies in [`export`]; the summary of a run, [`RunSummary`]). Every error is
//! an [`IoError`] whose message is one line naming the file; nothing here panics on bad
//! input, and no allocation is sized by an unchecked count read from a file.
#![warn(missing_docs)]

mod atomic;
mod character;
mod error;
pub mod export;
mod finish;
mod gltf_in;
mod json;
mod obj;
mod report;
pub mod robot;
mod skeleton_file;
mod stl;
mod summary;
mod volumes_read;
mod xml;

use std::path::Path;

pub use volumes_read::{
    parse_volumes, read_volumes, ReportedMetrics, VolumesFile, MAX_VOLUMES, MAX_VOLUMES_BYTES,
};

pub use atomic::write_atomic;
pub use character::{CharacterInfo, Skinning};
pub use error::IoError;
pub use finish::{load_arrays, LoadStats, LoadedMesh, MAX_TRIANGLES};
pub use json::{schema_and_kind, to_json_string, write_json, GENERATOR, SCHEMA, SCHEMA_V2};
pub use obj::MAX_INPUT_BYTES;
pub use report::MeshReport;
pub use skeleton_file::{parse_skeleton, read_skeleton, SKELETON_SCHEMA};
pub use summary::{CliSummary, RunSummary, Tolerances};

/// The mesh formats [`load`] and [`load_bytes`] read, as file extensions (compared
/// case-insensitively).
pub const MESH_EXTENSIONS: &[&str] = &["obj", "gltf", "glb", "stl"];

pub(crate) const SUPPORTED: &str = ".obj, .gltf, .glb, .stl";

/// What [`load`] and [`load_bytes`] read of a file: `LoadOptions::default()` loads all of
/// it, and each field set narrows it down. Write it as a struct literal ending in
/// `..LoadOptions::default()`, so that the code keeps compiling when fields are added.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// OBJ: only the object or group with this name (default: all merged).
    pub object: Option<String>,
    /// glTF: only the scene nodes whose mesh has this name (default: every mesh of the
    /// default scene).
    pub mesh: Option<String>,
}

/// Loads a mesh file, choosing the reader by the file's extension (one of
/// [`MESH_EXTENSIONS`], compared case-insensitively), and reports what loading changed
/// (welded vertices, dropped degenerate triangles) and what the mesh is like. Every reader
/// merges what `options` selects into one mesh, welds exactly coincident positions, drops
/// degenerate triangles (and lists them), and turns an inward-facing surface outward. A
/// glTF file may refer to buffer files next to it; no other file is opened (OBJ `.mtl`
/// files are ignored).
///
/// # Errors
///
/// An [`IoError`], whose message is one line naming the file: it cannot be opened or read
/// ([`IoError::Io`]), is a directory ([`IoError::BadPath`]), is larger than
/// [`MAX_INPUT_BYTES`] ([`IoError::TooLarge`]), has an unsupported extension
/// ([`IoError::UnsupportedFormat`]), is malformed or lacks the object or mesh `options`
/// names ([`IoError::Parse`]), holds no usable triangle ([`IoError::NoTriangles`]) or is
/// refused by [`bvseg_core::Mesh::new`] ([`IoError::Mesh`]); an option that does not apply
/// to the format ([`LoadOptions::object`] on a non-OBJ file, [`LoadOptions::mesh`] on a
/// non-glTF one) is an [`IoError::BadPath`].
pub fn load(path: impl AsRef<Path>, options: &LoadOptions) -> Result<LoadedMesh, IoError> {
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

/// Loads a mesh held in memory, as [`load`] loads a file: the format is chosen by the
/// extension of `name`, which error messages also use. glTF documents with external buffer
/// files cannot be read this way (there is no directory to read them from); GLB and
/// embedded (data URI) buffers work.
///
/// # Errors
///
/// As for [`load`], less the operating system's: more than [`MAX_INPUT_BYTES`]
/// ([`IoError::TooLarge`]), an unsupported extension of `name`
/// ([`IoError::UnsupportedFormat`]), malformed content, a glTF buffer in an external file or
/// a missing object or mesh ([`IoError::Parse`]), no usable triangle
/// ([`IoError::NoTriangles`]), a mesh [`bvseg_core::Mesh::new`] refuses ([`IoError::Mesh`])
/// or an option that does not apply to the format ([`IoError::BadPath`]).
pub fn load_bytes(bytes: &[u8], name: &str, options: &LoadOptions) -> Result<LoadedMesh, IoError> {
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

// The crate page's example (README.md, also shown on crates.io) is compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
