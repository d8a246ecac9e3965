//! MJCF in ([`read`]: the body tree as links and joints, the colliding mesh geoms placed as
//! MuJoCo places them; includes, defaults, frames and the compiler's settings followed) and
//! out: an MJCF input given back as it was but for its colliding mesh geoms, replaced by
//! primitive geoms in the same bodies ([`splice`]); a URDF input as a new MJCF ([`build`]).
mod build;
mod files;
mod geom;
mod orient;
mod read;
mod splice;

use std::collections::BTreeSet;
use std::ops::Range;
use std::path::PathBuf;

use glam::DAffine3;

pub(crate) use build::to_mjcf_robot;
pub(crate) use files::File;
pub(crate) use read::{included_files, parse};
pub(crate) use splice::to_mjcf_files;

/// What the MJCF writer needs of the files an MJCF robot was read from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Source {
    /// The main file, then the files it includes.
    pub(crate) files: Vec<File>,
    /// The main file's directory, canonical when it can be: what relative names are read
    /// from.
    pub(crate) dir: PathBuf,
    /// The colliding mesh geoms, in the order MuJoCo reads them.
    pub(crate) sites: Vec<Site>,
    /// By link index: where new geoms go in a link without colliding mesh geoms (read with
    /// the visual meshes as the source); `None` for the world and bodies without children.
    pub(crate) inserts: Vec<Option<Insert>>,
    /// By link index: whether MuJoCo computes the body's mass and inertia from its geoms.
    pub(crate) from_geoms: Vec<bool>,
    /// `<compiler>` attributes naming directories (`meshdir`, `texturedir`, `assetdir`).
    pub(crate) dirs: Vec<DirAttr>,
    /// Whether some `<compiler>` sets where meshes are read from (`meshdir` or `assetdir`).
    pub(crate) has_meshdir: bool,
    /// Whether some `<compiler>` sets where textures are read from.
    pub(crate) has_texturedir: bool,
    /// Every geom name of the model.
    pub(crate) names: BTreeSet<String>,
}

/// A colliding mesh geom of a link.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Site {
    /// The link (body) it is in.
    pub(crate) link: usize,
    /// The file it is written in, and where.
    pub(crate) file: usize,
    pub(crate) range: Range<usize>,
    /// The frame its `pos` and orientation are given in (its body's, or of the `<frame>`s
    /// around it), in the link's frame.
    pub(crate) parent: DAffine3,
    /// Its attributes as written, in order.
    pub(crate) attrs: Vec<(String, String)>,
    /// Where its `contype` and `conaffinity` attributes are.
    pub(crate) collision_attrs: Vec<Range<usize>>,
    /// Whether the link's new geoms stand for it: its mesh was segmented (or the visual
    /// meshes are the source), and its default class lets a primitive geom be written
    /// beside it.
    pub(crate) replace: bool,
    /// Whether it adds mass to a body whose inertia MuJoCo computes from its geoms: it then
    /// stays, no longer colliding, so that the body's mass and inertia stay as they were.
    pub(crate) carrier: bool,
}

/// Where a link without colliding mesh geoms gets its new geoms: before its body's end tag.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Insert {
    pub(crate) file: usize,
    pub(crate) at: usize,
}

/// A `<compiler>` attribute that names a directory, and where its value is.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DirAttr {
    pub(crate) file: usize,
    pub(crate) value: Range<usize>,
    pub(crate) text: String,
}
