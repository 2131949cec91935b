//! Planar geometry shared by C2Warp's numeric crates: each predicate is written once
//! here, so that meshing, weights, ARAP and cages judge the same configuration alike.
//!
//! The crate knows points and segments in `f64` ([`glam::DVec2`]) and, for exact work
//! on pixel corners, in integers ([`lattice`]). It knows nothing of images, meshes or
//! handles.
//!
//! # Conventions
//! * **Units.** Whatever the caller's coordinates are (pixels throughout C2Warp);
//!   distances come in those units, areas in their square.
//! * **Orientation.** [`orient`]`(a, b, c)` is positive when `a → b → c` turns
//!   counter-clockwise in a y-up frame, which is clockwise as seen on screen in image
//!   coordinates (y down). [`signed_area`] follows the same sign, and a
//!   [`Similarity`]'s positive rotation turns `+x` towards `+y`.
//! * **Rings.** A ring is a closed polygon given by its vertices in order, the last
//!   one joined back to the first (the first vertex is not repeated).
//! * **Degenerate input.** A zero-length segment is its end point; what each function
//!   does with fewer points than it needs, or with non-finite coordinates, is said on
//!   the function. Nothing here panics on finite input.
//! * **Rounding.** Each formula is fixed: the callers' results (meshes, weights,
//!   goldens) depend on its exact rounding, so a rewrite that is equal only
//!   mathematically is a change of behaviour.
//!
//! # Example
//! ```
//! use geometry::{orient, point_segment_distance, segments_cross, signed_area};
//! use glam::DVec2;
//!
//! let square = [
//!     DVec2::new(0.0, 0.0),
//!     DVec2::new(2.0, 0.0),
//!     DVec2::new(2.0, 2.0),
//!     DVec2::new(0.0, 2.0),
//! ];
//! assert!(orient(square[0], square[1], square[2]) > 0.0);
//! assert_eq!(signed_area(&square), 4.0);
//! assert_eq!(point_segment_distance(DVec2::new(1.0, 3.0), square[2], square[3]), 1.0);
//! assert!(segments_cross(square[0], square[2], square[1], square[3]));
//! ```

mod area;
mod distance;
mod intersect;
pub mod lattice;
mod order;
mod similarity;
mod simplify;

pub use area::{orient, signed_area};
pub use distance::{
    closest_point_on_segment, point_segment_distance, point_segment_distance_squared,
    polyline_distance_squared, segment_distance,
};
pub use intersect::{segments_cross, segments_touch};
pub use order::z_order;
pub use similarity::Similarity;
pub use simplify::{douglas_peucker, farthest_from_chord};
