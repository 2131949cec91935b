//! Errors: input the method cannot work with.

/// Input that [`Mls::new`](crate::Mls::new), [`Mls::deform`](crate::Mls::deform) or
/// [`deform_point`](crate::deform_point) refuses. Every variant is a caller's mistake.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MlsError {
    /// The weight exponent α is NaN, infinite, zero or negative.
    #[error("alpha must be finite and positive, got {alpha}")]
    InvalidAlpha {
        /// The value given.
        alpha: f64,
    },
    /// A rest vertex (or the point given to `deform_point`) is NaN or infinite.
    #[error("vertex {vertex} is not finite")]
    NonFiniteVertex {
        /// Index of the vertex (0 for `deform_point`).
        vertex: usize,
    },
    /// A rest control has a NaN or infinite coordinate.
    #[error("rest control {control} is not finite")]
    NonFiniteControl {
        /// Index of the control.
        control: usize,
    },
    /// A posed control has a NaN or infinite coordinate.
    #[error("posed control {control} is not finite")]
    NonFinitePosed {
        /// Index of the control.
        control: usize,
    },
    /// A rest bar whose two ends coincide (within the on-control tolerance,
    /// `1e-12 · (1 + largest absolute coordinate of its ends)` pixels). Under
    /// arc-length weighting such a bar would carry no weight at all.
    #[error("rest bar {control} has zero length")]
    ZeroLengthBar {
        /// Index of the control.
        control: usize,
    },
    /// The pose lists a different number of controls than the rest state.
    #[error("{posed} posed controls given for {rest} rest controls")]
    PoseLength {
        /// Number of posed controls given.
        posed: usize,
        /// Number of rest controls.
        rest: usize,
    },
    /// A posed control is a point where the rest control is a bar, or the reverse.
    #[error("posed control {control} is not of the same kind (point or bar) as at rest")]
    PoseKind {
        /// Index of the control.
        control: usize,
    },
    /// The output slice does not have one slot per vertex.
    #[error("the output has {got} slots for {vertices} vertices")]
    OutputLength {
        /// Length of the slice given.
        got: usize,
        /// Number of vertices.
        vertices: usize,
    },
}
