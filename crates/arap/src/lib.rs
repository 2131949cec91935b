//! As-rigid-as-possible shape manipulation on a 2-D triangle mesh, as Igarashi,
//! Moscovich and Hughes give it ("As-Rigid-As-Possible Shape Manipulation",
//! SIGGRAPH 2005): the two-step closed-form algorithm of their §4 with the rigidity
//! weights of §5.2.
//!
//! The crate knows vertices, triangles and constrained vertices; it knows nothing of
//! images, pixels, files or screens. The work is split as the paper splits it:
//!
//! 1. **Registration** ([`Registration::new`], once per rest mesh): each triangle's
//!    local coordinates — step one's error of every corner predicted from the other
//!    two — and step two's per-triangle fitting matrices, inverted.
//! 2. **Compilation** ([`Registration::compile`], when the constrained vertices or
//!    the rigidity weights change): split free and constrained unknowns, assemble
//!    step one's system (`2m` unknowns, x and y interleaved) and step two's (`m`
//!    unknowns, the same matrix for x and y), and factorise both with faer's sparse
//!    Cholesky under one fill-reducing ordering.
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
mod registration;
mod ring;
mod solver;
mod topology;
mod triangle;
mod update;

pub use compile::Compiled;
pub use error::ArapError;
pub use registration::Registration;
pub use ring::{Similarity, ring_constraints, similarity_constraints};
pub use update::Deformation;
