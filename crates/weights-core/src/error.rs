//! Errors: what a caller gave that cannot be used.

/// A domain that cannot be built from the given samples and triangles.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum DomainError {
    /// No triangles were given.
    #[error("the domain has no triangles")]
    Empty,
    /// A sample position is NaN or infinite.
    #[error("sample {vertex} has a non-finite position")]
    NonFinite {
        /// Index of the sample.
        vertex: usize,
    },
    /// A triangle refers to a sample that does not exist.
    #[error("triangle {triangle} refers to a vertex beyond the {vertices} samples")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// Number of samples.
        vertices: usize,
    },
    /// A triangle repeats a vertex.
    #[error("triangle {triangle} repeats a vertex")]
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
    },
}

/// A rig that cannot be built or edited as asked.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum RigError {
    /// A handle coordinate or transform component is NaN or infinite.
    #[error("handle {handle} has a non-finite coordinate or transform")]
    NonFinite {
        /// Index of the handle.
        handle: usize,
    },
    /// A handle lies outside the domain (off the shape).
    #[error("handle {handle} at ({x:.2}, {y:.2}) lies outside the shape")]
    OutsideDomain {
        /// Index of the handle.
        handle: usize,
        /// Rest x in pixels.
        x: f64,
        /// Rest y in pixels.
        y: f64,
    },
    /// Two handles closer than [`COINCIDENT`](crate::COINCIDENT): the same place.
    #[error(
        "handles {a} and {b} coincide (closer than {} px); move one of them",
        crate::COINCIDENT
    )]
    Coincident {
        /// The first handle.
        a: usize,
        /// The second handle.
        b: usize,
    },
    /// Two handles that take the same sample of the mesh (a mesh given as it is, too
    /// coarse where they are; a picture's mesh is refined around close handles).
    #[error(
        "handles {a} and {b} fall on the same sample of the mesh; refine the mesh there \
         or move them apart"
    )]
    SameSample {
        /// The first handle.
        a: usize,
        /// The second handle.
        b: usize,
    },
    /// A bar handle whose two ends coincide.
    #[error("bar handle {handle} has zero length")]
    ZeroLengthBar {
        /// Index of the handle.
        handle: usize,
    },
    /// A scale that is not positive.
    #[error("handle {handle} has a non-positive scale")]
    BadScale {
        /// Index of the handle.
        handle: usize,
    },
    /// A pose beyond [`MAX_POSE`](crate::MAX_POSE) pixels (or radians), or a scale
    /// outside [`MIN_SCALE`](crate::MIN_SCALE)..=[`MAX_SCALE`](crate::MAX_SCALE): the
    /// deformation would overflow.
    #[error(
        "handle {handle} has a pose beyond ±{max_pose:e} or a scale outside \
         [{min_scale:e}, {max_scale:e}]",
        max_pose = crate::MAX_POSE,
        min_scale = crate::MIN_SCALE,
        max_scale = crate::MAX_SCALE
    )]
    PoseOutOfRange {
        /// Index of the handle.
        handle: usize,
    },
    /// An index that names no handle.
    #[error("there is no handle {handle}")]
    NoSuchHandle {
        /// The index given.
        handle: usize,
    },
    /// A handle pose of the wrong kind (a bar pose for a point handle or vice versa).
    #[error("handle {handle} is a {expected} handle")]
    WrongKind {
        /// Index of the handle.
        handle: usize,
        /// What the handle is.
        expected: &'static str,
    },
    /// Options out of range.
    #[error("invalid options: {0}")]
    Options(String),
    /// A virtual handle given to rebuild a rig names no sample.
    #[error("virtual handle sample {0} does not exist")]
    BadVirtual(u32),
    /// A virtual handle given to rebuild a rig was placed for a handle that does not
    /// exist.
    #[error("virtual handle {index} was placed for handle {handle}, which does not exist")]
    BadPlacedFor {
        /// Index of the virtual handle in the list given.
        index: usize,
        /// The handle it names.
        handle: usize,
    },
    /// More handles than [`crate::MAX_HANDLES`].
    #[error("{count} handles; the weights are built for up to {max} handles")]
    TooManyHandles {
        /// Handles given.
        count: usize,
        /// The most a rig takes.
        max: usize,
    },
    /// More virtual handles than the domain has samples (each takes a sample of its
    /// own).
    #[error("{count} virtual handles on {samples} samples: there can be at most one a sample")]
    TooManyVirtual {
        /// Virtual handles given.
        count: usize,
        /// Samples of the domain.
        samples: usize,
    },
}
