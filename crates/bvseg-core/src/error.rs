use thiserror::Error;

/// Everything that can go wrong in [`crate::segment`]. Each variant is a problem with the
/// input or the parameters; the core never fails on its own account.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// A vertex coordinate is NaN or infinite, or too large to be handled in f64 arithmetic.
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
    /// The mesh is flat or encloses no volume that the sampling grid can see.
    #[error("the mesh encloses no volume (flat, open or degenerate): {0}")]
    NoVolume(String),
    /// The surface is far more complex than the sampling lattice can resolve in bounded
    /// time (typically a hostile file: many huge overlapping triangles).
    #[error("the mesh is too complex to sample: {0}")]
    TooComplex(String),
    /// A broken invariant inside bvseg (a bug): please report it with the input.
    #[error("internal error (please report it with the input): {0}")]
    Internal(String),
    /// The run was stopped through its [`crate::Cancel`] flag.
    #[error("the run was cancelled")]
    Cancelled,
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
}
