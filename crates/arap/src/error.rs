//! Errors: what a caller gave that cannot be used.

/// Input that the method cannot work with. Every variant is a caller's mistake except
/// [`ArapError::Factorization`], which would be a bug (the systems are built so that
/// they are always positive definite).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ArapError {
    /// A rest position is NaN or infinite.
    #[error("vertex {vertex} has a non-finite rest position")]
    NonFiniteRest {
        /// Index of the vertex.
        vertex: usize,
    },
    /// More vertices than a `u32` index can name.
    #[error("the mesh has {vertices} vertices; at most 4294967295 are supported")]
    TooManyVertices {
        /// Number of vertices given.
        vertices: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, beyond the {vertices} vertices")]
    TriangleVertexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The vertex index it names.
        vertex: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A constraint, or a helper's argument, names a vertex that does not exist.
    #[error("vertex {vertex} does not exist (the mesh has {vertices} vertices)")]
    VertexOutOfRange {
        /// The vertex index given.
        vertex: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// The same vertex appears twice in a constraint list.
    #[error("vertex {vertex} is constrained twice (constraints {first} and {second})")]
    DuplicateConstraint {
        /// The vertex.
        vertex: u32,
        /// Position of its first appearance in the list.
        first: usize,
        /// Position of its second appearance.
        second: usize,
    },
    /// A rigidity list whose length is not the number of triangles.
    #[error("{got} rigidity weights given for {triangles} triangles")]
    RigidityLength {
        /// Number of weights given.
        got: usize,
        /// Number of triangles of the mesh.
        triangles: usize,
    },
    /// A rigidity weight that is not finite and positive.
    #[error("the rigidity weight of triangle {triangle} is {weight}; it must be finite and > 0")]
    BadRigidity {
        /// Index of the triangle.
        triangle: usize,
        /// The weight given.
        weight: f64,
    },
    /// The number of targets differs from the number of constrained vertices.
    #[error("{got} targets given for {expected} constrained vertices")]
    TargetCount {
        /// Number of targets given.
        got: usize,
        /// Number of constrained vertices the system was compiled for.
        expected: usize,
    },
    /// A target position is NaN or infinite.
    #[error("the target of constraint {constraint} is not finite")]
    NonFiniteTarget {
        /// Position of the target in the list.
        constraint: usize,
    },
    /// A similarity transform with a NaN or infinite component.
    #[error("the similarity transform has a non-finite component")]
    NonFiniteSimilarity,
    /// The sparse Cholesky factorisation failed. The systems are positive definite
    /// by construction, so this is a bug (or memory ran out); please report it.
    #[error("the sparse factorisation failed: {0}")]
    Factorization(String),
}
