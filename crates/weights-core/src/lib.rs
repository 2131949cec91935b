//! Closed-form C² weights for handle-driven image warping, after Xian, Jin and Wang,
//! "Efficient C²-Weighting for Image Warping", with their virtual-handle insertion.
//!
//! The crate knows samples, triangles and handles; it knows nothing of images, pixels
//! or screens. Build a [`Domain`] from sample positions and triangles, put
//! [`Handle`]s on it, and a [`Rig`] gives every sample sparse weights over the handle
//! nodes that
//! - sum to one and are non-negative,
//! - are one at a node's own sample and zero at every other node,
//! - are zero beyond each node's support radius (1 − α)·r_d + α·r_h,
//! - are C² in the distance (basis [`Basis`]).
//!
//! Distances are Euclidean on convex domains and shortest paths on the sample graph
//! otherwise ([`Metric`]). Virtual handles are inserted until every node's cell fits in
//! its support (Algorithm 1); their transforms blend the real handles' by harmonic
//! coordinates on the dual graph. Inserting or removing a handle updates only what it
//! changes and gives the same weights as a rebuild with the same nodes.
//!
//! A rig takes up to [`MAX_HANDLES`] handles; [`Rig::with_progress`] tells a caller how
//! far a long build has come, and [`Rig::placed_virtual_handles`] with
//! [`Rig::with_placed_virtual_handles`] save and restore the virtual handles together
//! with the handle each was placed for.

mod basis;
mod domain;
mod error;
mod harmonic;
mod ldl;
mod nearest;
mod overlay;
mod queue;
mod rig;
mod virtual_handles;
mod voronoi;
mod weights;

pub use basis::{Basis, MAX_DEGREE, MIN_DEGREE, MiddleControls};
pub use domain::{Domain, Metric};
pub use error::{DomainError, RigError};
pub use geometry::Similarity;
pub use overlay::similarity_fit;
pub use rig::{
    BuildTimings, COINCIDENT, Handle, MAX_BAR_PIECES, MAX_HANDLES, MAX_POSE, MAX_SCALE, MIN_SCALE,
    Node, NodeKind, NodeRadii, Phase, Progress, Rig, RigOptions, RigStats, UpdateTimings,
    VirtualHandle, bar_samples, bar_spacing, bar_spacing_overlaid, check_handles_on,
};
pub use virtual_handles::Placement;
pub use voronoi::nearest_source;
