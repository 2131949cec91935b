//! As-rigid-as-possible shape manipulation on a 2-D triangle mesh, as Igarashi,
//! Moscovich and Hughes give it ("As-Rigid-As-Possible Shape Manipulation",
//! SIGGRAPH 2005): the two-step closed-form algorithm of their §4 with the rigidity
//! weights of §5.2.
//!
//! The crate knows vertices, triangles and constrained vertices; it knows nothing of
//! images, pixels, files or screens. The work is split as the paper splits it:
//!
//! 1. **Registration** ([`Registration::new`], once per rest mesh): each triangle's
//!    share of step one's error matrix, from its local coordinates (every corner
//!    predicted from the other two), step two's per-triangle fitting matrices,
//!    inverted, and a fill-reducing order of the vertices.
//! 2. **Compilation** ([`Registration::compile`], when the constrained vertices or
//!    the rigidity weights change): split free and constrained unknowns, assemble
//!    step one's system (`2m` unknowns, x and y interleaved) and step two's (`m`
//!    unknowns, the same matrix for x and y), and factorise both with faer's sparse
//!    Cholesky.
//! 3. **Update** ([`Compiled::update`], every drag): step one by one
//!    back-substitution (or, with few handles, by the product with `G'⁻¹B` formed at
//!    compilation, as the paper does), a per-triangle pass fitting each rest triangle
//!    to its step-one triangle by rotation (scale removed), and one back-substitution
//!    with two right-hand sides (x and y) for step two. Nothing is factorised.
//!
//! The error terms are the paper's, without area normalisation: step one sums, over
//! every triangle, the squared distance of each of its three corners from where the
//! other two (by a similarity of the rest triangle) put it; step two sums, over every
//! triangle, the squared differences of its three edge vectors from the fitted
//! triangle's (an interior edge counts once from each side). A rigidity weight
//! multiplies a triangle's terms in both.
//!
//! Degenerate input has a defined answer (see [`Registration::compile`]): no
//! constraint gives the rest shape, one constrained vertex translates its component,
//! a component without constraints stays at rest, zero-area rest triangles are left
//! out, and nothing is ever NaN for finite input.
//!
//! # Reading the paper
//!
//! Where the text leaves a choice, this crate takes these:
//! - `R90` is the matrix the paper prints, `[[0, 1], [−1, 0]]` (a quarter turn
//!   clockwise in a y-up frame, counter-clockwise on screen in image coordinates). The
//!   results do not depend on it: local coordinates are read and used with the same
//!   matrix.
//! - Step one's error of a triangle is the sum over all three corners (eq. 4), each
//!   predicted from the other two in either order (the similarity through two points
//!   is unique); no area weighting.
//! - Step two fits by the paper's 4×4 system `F` (eqs. 9–11), inverted at
//!   registration; the fitted triangle is then a similarity image of the rest one,
//!   and "scaling it back" leaves its rotation. The final solve (eq. 12) sees only
//!   the fitted edges, so the centre of that scaling does not matter. A step-one
//!   triangle collapsed to a point has no rotation to read; it keeps the rest
//!   orientation.
//! - Step one's `2m × 2m` matrix has 2×2 blocks `p·I + q·R90` only, so it is the real
//!   form of an `m × m` Hermitian matrix and so is its Cholesky factor: it is
//!   factorised and stored in that form, the same numbers in half the memory.
//! - The paper forms `G'⁻¹B` at compilation (§4.3, 2-1), so that step one costs a
//!   product per pose; that is done when the constrained vertices are few next to
//!   the mesh, and a back-substitution otherwise (same result up to rounding).
//! - Rigidity weights multiply both of a triangle's terms: its step-one error and its
//!   three edges in step two's final solve (not the fitting, which is per triangle).
//!
//! ```
//! use arap::Registration;
//! use glam::DVec2;
//!
//! // A 4 × 1 bar of unit squares.
//! let rest: Vec<DVec2> = (0..2)
//!     .flat_map(|y| (0..5).map(move |x| DVec2::new(x as f64, y as f64)))
//!     .collect();
//! let triangles: Vec<[u32; 3]> = (0..4u32)
//!     .flat_map(|x| [[x, x + 1, x + 6], [x, x + 6, x + 5]])
//!     .collect();
//! let registration = Registration::new(&rest, &triangles)?;
//! // Handles on the two bottom corners; stretch the bar to twice its length.
//! let compiled = registration.compile(&[0, 4], None)?;
//! let pose = compiled.update(&[DVec2::new(0.0, 0.0), DVec2::new(8.0, 0.0)])?;
//! // Step one scales the bar up uniformly (its top edge moves to y = 2); step two
//! // keeps the triangles closer to their rest size.
//! assert!((pose.step_one[9] - DVec2::new(8.0, 2.0)).length() < 1e-9);
//! assert!(pose.positions[9].y < 1.5);
//! # Ok::<(), arap::ArapError>(())
//! ```

mod compile;
mod error;
mod minimise;
mod registration;
mod ring;
mod solver;
mod topology;
mod triangle;
mod update;

pub use compile::Compiled;
pub use error::ArapError;
pub use geometry::Similarity;
pub use minimise::{Convergence, Minimise};
pub use registration::Registration;
pub use ring::{ring_constraints, similarity_constraints};
pub use update::Deformation;
