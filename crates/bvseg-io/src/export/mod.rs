//! Engine-ready outputs: a glTF binary ([`to_glb`]), MuJoCo MJCF ([`to_mjcf`]), USD with
//! UsdPhysics colliders ([`to_usda`]), the proxies as an OBJ ([`to_obj`]) and per-triangle
//! part labels ([`to_labels`]). [`write_output`]
//! picks the format from the file's extension and writes atomically.
//!
//! Every writer is deterministic: equal segmentations give byte-identical files.
mod glb;
pub(crate) mod mjcf;
mod obj;
mod proxy;
pub(crate) mod usd;

use std::path::Path;

use bvseg_core::{Mesh, Segmentation};

use crate::{write_atomic, IoError};

pub use glb::{to_glb, to_glb_skinned};
pub use mjcf::to_mjcf;
pub use obj::to_obj;
pub use proxy::{enclosing_points, part_color, volume_rotation, y_up_rotation};
pub use usd::{to_usda, UpAxis, UsdOptions};

/// An output format, chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    /// `.json`: the `bvseg.volumes/1` document.
    Json,
    /// `.glb`: glTF 2.0 binary with one node per volume and physics colliders.
    Glb,
    /// `.xml`: MuJoCo MJCF with one geom per volume.
    Mjcf,
    /// `.obj`: the volumes as meshes, one object per part.
    Obj,
    /// `.usda`: USD text with one UsdPhysics collider prim per volume.
    Usda,
}

/// The output extensions, for messages.
pub const OUTPUT_EXTENSIONS: &str = ".json, .glb, .xml (MJCF), .obj, .usda";

impl OutputFormat {
    /// The format named by `path`'s extension.
    ///
    /// # Errors
    ///
    /// [`IoError::UnsupportedFormat`] for an extension that names no output format.
    pub fn from_path(path: &Path) -> Result<Self, IoError> {
        let ext = crate::extension(path);
        match ext.as_deref() {
            Some("json") => Ok(Self::Json),
            Some("glb") => Ok(Self::Glb),
            Some("xml") => Ok(Self::Mjcf),
            Some("obj") => Ok(Self::Obj),
            Some("usda") => Ok(Self::Usda),
            _ => Err(IoError::UnsupportedFormat {
                name: path.display().to_string(),
                what: "output",
                ext,
                supported: OUTPUT_EXTENSIONS,
            }),
        }
    }

    /// Whether this format writes [`bvseg_core::Segmentation::hierarchy`] (only the JSON
    /// document does), so that a run whose outputs do not can skip building it
    /// ([`bvseg_core::Params::hierarchy`]).
    #[must_use]
    pub fn carries_hierarchy(self) -> bool {
        self == Self::Json
    }
}

/// What the writers may add beyond the volumes.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExportOptions<'a> {
    /// GLB: also the input mesh, coloured by part (its triangles must be the ones the
    /// segmentation labelled).
    pub mesh: Option<&'a Mesh>,
    /// GLB: a skinned file's skins and animations ([`crate::LoadedMesh::skinning`]): the
    /// joints are then the file's nodes, animated as in the file, and `mesh` is written
    /// skinned ([`to_glb_skinned`]).
    pub skinning: Option<&'a crate::Skinning>,
    /// USD: the stage's up axis and units, and whether the root is a rigid body.
    pub usd: UsdOptions,
}

/// Writes `seg` to `path` in the format its extension names, atomically.
///
/// # Errors
///
/// [`IoError::UnsupportedFormat`] for an unknown extension, [`IoError::BadOption`] for a
/// `.usda` output whose [`UsdOptions::meters_per_unit`] is not finite and above 0, and the
/// errors of [`crate::write_atomic`].
pub fn write_output(
    path: impl AsRef<Path>,
    seg: &Segmentation,
    options: &ExportOptions<'_>,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let bytes = match OutputFormat::from_path(path)? {
        OutputFormat::Json => return crate::write_json(path, seg),
        OutputFormat::Glb => match options.skinning {
            Some(s) => to_glb_skinned(seg, options.mesh, s),
            None => to_glb(seg, options.mesh),
        },
        OutputFormat::Mjcf => to_mjcf(seg, &stem(path)).into_bytes(),
        OutputFormat::Obj => to_obj(seg).into_bytes(),
        OutputFormat::Usda => {
            let mpu = options.usd.meters_per_unit;
            if !(mpu.is_finite() && mpu > 0.0) {
                return Err(IoError::BadOption {
                    name: path.display().to_string(),
                    message: format!("meters per unit must be finite and above 0, got {mpu}"),
                });
            }
            to_usda(seg, &stem(path), &options.usd).into_bytes()
        }
    };
    write_atomic(path, &bytes)
}

/// The file name of `path` without its extension, `bvseg` without one: the model's name.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "bvseg".into())
}

/// One part index per triangle of the segmented mesh, one per line.
pub fn to_labels(seg: &Segmentation) -> String {
    to_labels_with_dropped(seg, &[])
}

/// One line per triangle of the file: its part index, or `-1` for a triangle that loading
/// dropped as degenerate (`dropped`: their indices among the triangles read, increasing, as
/// in [`crate::LoadedMesh::dropped`]).
pub fn to_labels_with_dropped(seg: &Segmentation, dropped: &[usize]) -> String {
    let mut s = String::with_capacity((seg.triangle_parts.len() + dropped.len()) * 3);
    let mut parts = seg.triangle_parts.iter();
    let mut dropped = dropped.iter().peekable();
    let total = seg.triangle_parts.len() + dropped.len();
    for k in 0..total {
        if dropped.next_if(|&&d| d == k).is_some() {
            s.push_str("-1\n");
        } else if let Some(p) = parts.next() {
            s.push_str(&p.to_string());
            s.push('\n');
        }
    }
    s
}

/// Writes [`to_labels_with_dropped`] to `path`, atomically.
///
/// # Errors
///
/// As [`crate::write_atomic`].
pub fn write_labels(
    path: impl AsRef<Path>,
    seg: &Segmentation,
    dropped: &[usize],
) -> Result<(), IoError> {
    write_atomic(path, to_labels_with_dropped(seg, dropped).as_bytes())
}
