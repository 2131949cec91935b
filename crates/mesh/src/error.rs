//! The crate's error type.

/// Everything that can go wrong while building, reading or editing a mesh.
///
/// Variants up to [`MeshError::Io`] describe bad input (an empty image, a handle off the
/// shape, a malformed file); [`MeshError::Triangulation`] reports an internal failure of
/// the triangulator and is a bug worth reporting.
#[derive(thiserror::Error, Debug)]
#[non_exhaustive]
pub enum MeshError {
    /// The domain has no area: the image has no pixels, or none with alpha above the
    /// threshold, or a hand-made [`Domain`](crate::Domain) has no polygon of positive area.
    #[error("the domain is empty: the image has no visible pixels")]
    EmptyDomain,

    /// A coordinate is NaN or infinite.
    #[error("non-finite coordinate in {what}")]
    NonFinite {
        /// Which input holds the bad coordinate, e.g. `"constraint point 3"`.
        what: String,
    },

    /// A coordinate is too large (above 1e50 in magnitude) or too close to zero (below
    /// 1e-40, zero itself is fine) for the triangulator's exact predicates.
    #[error("coordinate out of range in {what}: magnitudes must be 0 or within [1e-40, 1e50]")]
    CoordinateOutOfRange {
        /// Which input holds the bad coordinate, e.g. `"constraint point 3"`.
        what: String,
    },

    /// A constraint point lies outside the domain.
    #[error("constraint point {index} at ({x}, {y}) lies outside the shape")]
    PointOutsideDomain {
        /// Index into [`Constraints::points`](crate::Constraints::points).
        index: usize,
        /// Pixel x of the point.
        x: f64,
        /// Pixel y of the point.
        y: f64,
    },

    /// A point of a constraint polyline lies outside the domain.
    #[error("point {index} of polyline {polyline} at ({x}, {y}) lies outside the shape")]
    PolylinePointOutsideDomain {
        /// Index into [`Constraints::polylines`](crate::Constraints::polylines).
        polyline: usize,
        /// Index of the point within that polyline.
        index: usize,
        /// Pixel x of the point.
        x: f64,
        /// Pixel y of the point.
        y: f64,
    },

    /// A segment of a constraint polyline leaves the domain between two points that are
    /// inside it (it crosses a hole or a gap in the shape).
    #[error("segment {segment} of polyline {polyline} leaves the shape")]
    PolylineOutsideDomain {
        /// Index into [`Constraints::polylines`](crate::Constraints::polylines).
        polyline: usize,
        /// Index of the segment: it joins points `segment` and `segment + 1`.
        segment: usize,
    },

    /// [`Mesh::insert_point`](crate::Mesh::insert_point) was given a point that no
    /// triangle contains.
    #[error("point ({x}, {y}) lies outside the mesh")]
    PointOutsideMesh {
        /// Pixel x of the point.
        x: f64,
        /// Pixel y of the point.
        y: f64,
    },

    /// An option out of its range (the message says which and why).
    #[error("{0}")]
    InvalidOption(String),

    /// A hand-made [`Domain`](crate::Domain) is unusable (too few ring vertices,
    /// intersecting rings, ...).
    #[error("invalid domain: {0}")]
    InvalidDomain(String),

    /// A mesh breaks an invariant checked by [`Mesh::sanity_check`](crate::Mesh::sanity_check).
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),

    /// A Wavefront OBJ file could not be parsed or describes an invalid mesh.
    #[error("OBJ line {line}: {message}")]
    Obj {
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong with that line.
        message: String,
    },

    /// Reading or writing failed.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),

    /// The triangulator failed on input that passed validation (an internal error).
    #[error("triangulation failed (internal error): {0}")]
    Triangulation(String),
}
