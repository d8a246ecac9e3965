use thiserror::Error;

/// Everything that can go wrong in [`crate::verify`] and [`crate::Volumes::from_json`]: each
/// variant is a problem with the input. Messages are one line.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum VerifyError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// A vertex coordinate is NaN or infinite, or above 1e100 in magnitude.
    #[error("vertex {index} has a non-finite or out-of-range coordinate")]
    BadVertex {
        /// Index of the offending vertex.
        index: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {index} refers to vertex {vertex}, but the mesh has only {count} vertices")]
    BadIndex {
        /// Index of the offending triangle.
        index: usize,
        /// The vertex index it refers to.
        vertex: u32,
        /// Number of vertices in the mesh.
        count: usize,
    },
    /// The mesh encloses no volume at the resolution of the verification grid.
    #[error(
        "the mesh encloses no volume (flat, open or degenerate): none of the verification \
         grid's {points} points lies inside it; close its holes, or raise `points` if it is \
         thinner than the grid's spacing"
    )]
    NoVolume {
        /// The points of the grid.
        points: usize,
    },
    /// An option or a volume is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The volumes document breaks the `bvseg.volumes` schema.
    #[error("invalid volumes document: {0}")]
    Document(String),
    /// A volume of a shape that this verifier cannot check. Not returned by this version:
    /// it checks every shape of `bvseg.volumes/2`, and [`crate::Volumes::from_json`]
    /// refuses unknown shape names as [`VerifyError::Document`]. Kept so that code matching
    /// on it still compiles.
    #[error("volume {index}: shape \"{shape}\" is not supported by the verifier")]
    UnsupportedShape {
        /// Index of the volume in the document.
        index: usize,
        /// The shape's name in the document.
        shape: String,
    },
}
