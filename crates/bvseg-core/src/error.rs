//! What can go wrong, in layers: the mesh ([`MeshError`]), the parameters ([`ParamError`]),
//! and the run ([`Error`], which wraps both).
use thiserror::Error;

/// Everything that can go wrong in [`crate::segment`]: a problem with the mesh, with the
/// parameters, or with what the mesh encloses; a cancelled run; or a bug ([`Error::Internal`]).
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// The mesh is malformed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParams(#[from] ParamError),
    /// The mesh is flat or encloses no volume that the sampling grid can see.
    #[error("the mesh encloses no volume (flat, open or degenerate): {0}")]
    NoVolume(NoVolume),
    /// The surface is far more complex than the sampling lattice can resolve in bounded
    /// time (typically a hostile file: many huge overlapping triangles).
    #[error("the mesh is too complex to sample: {0}")]
    TooComplex(TooComplex),
    /// A broken invariant inside bvseg (a bug): please report it with the input. Returned
    /// instead of a result with non-finite figures or volumes.
    #[error("internal error (please report it with the input): {0}")]
    Internal(String),
    /// The run was stopped through its [`crate::Cancel`] flag.
    #[error("the run was cancelled")]
    Cancelled,
    /// The mesh's rig (skeleton or skin) is malformed.
    #[error(transparent)]
    Rig(#[from] RigError),
}

/// Why the sampling lattice sees no volume in a mesh ([`Error::NoVolume`]), and what would
/// help.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum NoVolume {
    /// The mesh's bounding box has no extent (or an infinite one) along some axis.
    #[error(
        "the bounding box is flat ({:.3e} x {:.3e} x {:.3e}); a solid needs extent along all \
         three axes",
        .extent[0],
        .extent[1],
        .extent[2]
    )]
    FlatBox {
        /// The box's extent along x, y and z, in mesh units.
        extent: [f64; 3],
    },
    /// No cell centre of the lattice lies inside the mesh, even on the finer lattices tried.
    #[error(
        "no grid cell centre lies inside the mesh; close its holes, or raise `samples` if the \
         solid is thinner than a cell"
    )]
    NoCellInside,
    /// Too few cells lie inside the mesh to segment it.
    #[error(
        "only {inside} grid cells lie inside the mesh (at least {needed} are needed); raise \
         `samples`"
    )]
    FewCells {
        /// The cells inside.
        inside: usize,
        /// The fewest a run takes.
        needed: usize,
    },
}

/// Why a surface is beyond what the sampling can do in bounded time or memory
/// ([`Error::TooComplex`]), and what would help.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum TooComplex {
    /// The inside test would scan the lattice's columns more than `per_cell` times per cell
    /// (see docs/method.md): stacked copies of faces, or fans of huge slivers.
    #[error(
        "sampling it would scan its lattice's columns more than {per_cell} times per cell: far \
         more overlapping surface than a model has; remove the repeated or overlapping faces"
    )]
    LatticeScans {
        /// The bound on the scans per lattice cell.
        per_cell: u32,
    },
    /// An allocation failed (noted by the web viewer's allocator, before its worker aborts).
    #[error(
        "the core ran out of memory (an allocation of {:.1} MB failed); try fewer samples",
        *.bytes as f64 / 1e6
    )]
    OutOfMemory {
        /// The size of the allocation that failed, in bytes.
        bytes: usize,
    },
}

/// A rig that [`crate::Rig::validate`] (and so [`crate::Mesh::with_rig`]) rejects.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum RigError {
    /// A joint's parent is not a joint.
    #[error("joint {joint}'s parent {parent} is not a joint (the skeleton has {count})")]
    Parent {
        /// The joint.
        joint: usize,
        /// Its parent index.
        parent: usize,
        /// Number of joints.
        count: usize,
    },
    /// The parents form a cycle.
    #[error("the skeleton's parents form a cycle through joint `{joint}`; each joint needs one root above it")]
    Cycle {
        /// A joint on the cycle.
        joint: String,
    },
    /// A joint's rest matrix is not finite or not invertible.
    #[error("joint {joint}'s rest matrix is not finite or not invertible")]
    BadJoint {
        /// The joint.
        joint: usize,
    },
    /// The skin does not fit the mesh or the skeleton.
    #[error("the skin is malformed: {message}")]
    Skin {
        /// What is wrong.
        message: String,
    },
}

/// A mesh that [`crate::Mesh::new`] rejects.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// A vertex coordinate is NaN or infinite, or too large to be handled in f64 arithmetic
    /// (beyond [`crate::MAX_COORDINATE`]).
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
}

/// A parameter out of its range: one variant per rule of [`crate::Params::validate`], each
/// with the value given and the range allowed.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ParamError {
    /// [`crate::Params::samples`] is outside `min..=max`.
    #[error("samples must be between {min} and {max}, got {value}")]
    Samples {
        /// The value given.
        value: usize,
        /// Smallest allowed.
        min: usize,
        /// Largest allowed ([`crate::MAX_SAMPLES`]).
        max: usize,
    },
    /// [`crate::Params::per_bone`] is 0.
    #[error("per_bone must be at least 1")]
    PerBoneZero,
    /// [`crate::Params::k`] is 0.
    #[error("k must be at least 1")]
    KZero,
    /// [`crate::Params::k`] is above `samples / 8` (each part needs samples to be fitted).
    #[error("k = {value} is too large for {samples} samples (at most samples / 8)")]
    KTooLarge {
        /// The value given.
        value: usize,
        /// The sample count it was given with.
        samples: usize,
    },
    /// [`crate::Params::tov`] or [`crate::Params::mov`] is negative or not finite.
    #[error("tolerances must be finite and non-negative ({field} = {value})")]
    Tolerance {
        /// `"tov"` or `"mov"`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// [`crate::Params::max_protrusion`] or [`crate::Params::max_protrusion_abs`] is not
    /// finite or not above 0.
    #[error("{field} must be finite and above 0, got {value}")]
    Protrusion {
        /// `"max_protrusion"` or `"max_protrusion_abs"`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// [`crate::Params::max_k`] is outside `1..=max`.
    #[error("max_k must be between 1 and {max}, got {value}")]
    MaxK {
        /// The value given.
        value: usize,
        /// Largest allowed ([`crate::MAX_K`]).
        max: usize,
    },
    /// [`crate::Params::margin`] is negative or not finite.
    #[error("margin must be finite and at least 0, got {value}")]
    Margin {
        /// The value given.
        value: f64,
    },
    /// [`crate::Params::max_sweeps`] is 0.
    #[error("max_sweeps must be at least 1")]
    MaxSweeps,
    /// [`crate::Params::kinds`] is empty.
    #[error("the set of volume kinds is empty")]
    NoKinds,
    /// [`crate::Params::max_hull_vertices`] is outside `min..=max`.
    #[error("max_hull_vertices must be between {min} and {max}, got {value}")]
    MaxHullVertices {
        /// The value given.
        value: usize,
        /// Smallest allowed (a tetrahedron).
        min: usize,
        /// Largest allowed ([`crate::MAX_HULL_VERTICES`], PhysX's limit).
        max: usize,
    },
}
