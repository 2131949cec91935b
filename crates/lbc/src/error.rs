//! Errors: what a caller gave that cannot be used, and a cancelled solve.

/// Why a cage, a mesh or a solve was refused.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LbcError {
    /// A cage needs at least three vertices.
    #[error("a cage needs at least 3 vertices, got {vertices}")]
    TooFewVertices {
        /// Number of vertices given.
        vertices: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("cage vertex {vertex} is not finite")]
    NonFinite {
        /// Index of the cage vertex.
        vertex: usize,
    },
    /// Two cage vertices coincide.
    #[error("cage vertices {first} and {second} coincide")]
    RepeatedVertex {
        /// The first of the two.
        first: usize,
        /// The second of the two.
        second: usize,
    },
    /// The polygon encloses no area (all vertices on one line).
    #[error("the cage encloses no area")]
    ZeroArea,
    /// The polygon is a sliver: its area is a millionth of its size squared or less.
    #[error(
        "the cage is a sliver: it encloses {area:.1e} for a size of {size:.1} across (at least a \
         millionth of the size squared is needed); give it some width"
    )]
    TooThin {
        /// Its area.
        area: f64,
        /// Its bounding box's diagonal.
        size: f64,
    },
    /// Two cage edges cross or touch (edge `i` runs from vertex `i` to `i + 1`).
    #[error("cage edges {first} and {second} intersect")]
    SelfIntersection {
        /// The first edge.
        first: usize,
        /// The second edge.
        second: usize,
    },
    /// A given mesh is unusable (out-of-range index, degenerate triangle, unused or
    /// non-finite vertex).
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A given mesh reaches beyond the cage: coordinates are defined inside it only.
    #[error(
        "mesh vertex {vertex} at ({x}, {y}) lies outside the cage: local barycentric \
         coordinates are defined inside the cage only (mesh just the cage's inside, or \
         keep the outside at rest as `c2warp render` does)"
    )]
    OutsideCage {
        /// Index of the mesh vertex.
        vertex: usize,
        /// Its position.
        x: f64,
        /// Its position.
        y: f64,
    },
    /// A cage vertex is not among the given mesh's vertices.
    #[error("cage vertex {vertex} is not a vertex of the mesh")]
    CageVertexNotInMesh {
        /// Index of the cage vertex.
        vertex: usize,
    },
    /// Spade refused the cage (it should not, once the cage is validated).
    #[error("triangulation failed: {0}")]
    Triangulation(String),
    /// A sparse factorisation failed (a bug: the matrices are positive definite).
    #[error("factorisation failed: {0}")]
    Factorization(String),
    /// A pose has the wrong number of vertices or a non-finite one.
    #[error("pose has {got} vertices (expected {expected}) or a non-finite one")]
    BadPose {
        /// Number of cage vertices.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// The progress callback asked to stop.
    #[error("cancelled")]
    Cancelled,
}
