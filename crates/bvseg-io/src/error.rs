//! The one error type of this crate.
use std::io;

/// Everything that can go wrong while reading a mesh or writing a result. Every message is a
/// single line that starts with the file it concerns, so a front end can print it as it is.
/// More variants may be added: a `match` on it needs a `_` arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system refused an operation on a file (open, read, write, rename, ...).
    #[error("{name}: cannot {action}: {source}")]
    Io {
        /// The file, as the caller named it.
        name: String,
        /// What was being done, e.g. `open` or `write`.
        action: &'static str,
        /// The underlying error.
        source: io::Error,
    },
    /// The input is larger than [`crate::MAX_INPUT_BYTES`].
    #[error("{name}: the file is larger than {limit} bytes; refusing to load it")]
    TooLarge {
        /// The file, as the caller named it.
        name: String,
        /// The limit, in bytes.
        limit: u64,
    },
    /// The file is not a well-formed mesh file.
    #[error("{name}: {}{message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Parse {
        /// The file, as the caller named it.
        name: String,
        /// The 1-based line of the problem, when it is known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// An output option is out of range (e.g. USD's meters per unit).
    #[error("{name}: {message}")]
    BadOption {
        /// The output, as the caller named it.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// The path cannot be used as asked (a directory where a file is needed, no file name).
    #[error("{name}: {message}")]
    BadPath {
        /// The path, as the caller named it.
        name: String,
        /// What is wrong with it.
        message: String,
    },
    /// The file parsed, but holds no usable triangle.
    #[error("{name}: no triangles{}", if *.degenerate > 0 { format!(" ({} degenerate dropped)", .degenerate) } else { String::new() })]
    NoTriangles {
        /// The file, as the caller named it.
        name: String,
        /// How many triangles were dropped as degenerate after welding.
        degenerate: usize,
    },
    /// The mesh was rejected by [`bvseg_core::Mesh::new`].
    #[error("{name}: {source}")]
    Mesh {
        /// The file, as the caller named it.
        name: String,
        /// Why the core rejected it.
        source: bvseg_core::MeshError,
    },
    /// The file's extension names a format this crate cannot read or write.
    #[error("{name}: unsupported {what} format{} (supported: {supported})", ext.as_ref().map(|e| format!(" '.{e}'")).unwrap_or_else(|| " (no file extension)".into()))]
    UnsupportedFormat {
        /// The file, as the caller named it.
        name: String,
        /// `mesh` or `output`.
        what: &'static str,
        /// The extension, without the dot; `None` when the name has none.
        ext: Option<String>,
        /// The extensions that are supported, for the message.
        supported: &'static str,
    },
    /// A robot file (URDF, MJCF) that is not well-formed XML or not a robot.
    #[error("{name}: {message}")]
    Robot {
        /// The robot file, as the caller named it.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// Two links (URDF) or bodies (MJCF) of a robot share a name.
    #[error("{name}: the link name {link:?} is used twice")]
    DuplicateLink {
        /// The robot file.
        name: String,
        /// The repeated name.
        link: String,
    },
    /// A joint names a parent or child that is not a link of the robot.
    #[error("{name}: joint {joint:?}: its {role} {link:?} is not a link of the robot")]
    UnknownLink {
        /// The robot file.
        name: String,
        /// The joint.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The name the joint gives.
        link: String,
    },
    /// An MJCF `<include>` that includes itself, directly or not.
    #[error("{name}: include cycle: {chain}")]
    IncludeCycle {
        /// The robot file, where the chain starts.
        name: String,
        /// The files of the cycle, joined by ` -> `.
        chain: String,
    },
    /// A link's mesh file does not exist (under any of the places it may be read from).
    #[error("{name}: link {link:?}: mesh file {file:?} not found (looked for {tried})")]
    MissingMesh {
        /// The robot file.
        name: String,
        /// The link.
        link: String,
        /// The file name, as the robot file gives it.
        file: String,
        /// The paths tried, joined by `, `.
        tried: String,
    },
    /// A link's mesh could not be loaded; the source names the file.
    #[error("{name}: link {link:?}: {source}")]
    Link {
        /// The robot file.
        name: String,
        /// The link.
        link: String,
        /// Why its mesh could not be loaded.
        source: Box<IoError>,
    },
}

impl IoError {
    pub(crate) fn io(name: &str, action: &'static str, source: io::Error) -> Self {
        IoError::Io {
            name: name.to_owned(),
            action,
            source,
        }
    }
}
