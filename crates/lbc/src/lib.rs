//! Local barycentric coordinates inside a 2-D cage, as Zhang, Deng, Liu, Patanè,
//! Bouaziz, Hormann and Liu give them ("Local Barycentric Coordinates", SIGGRAPH
//! Asia 2014): the weighted total-variation formulation of their §3–4 and the ADMM
//! solver of Appendix B.
//!
//! The crate knows a polygon, a triangle mesh and numbers; it knows nothing of
//! images, pixels, files or screens. The pipeline:
//!
//! 1. **Cage** ([`Cage::new`]): a simple polygon, either orientation; fewer than three
//!    vertices, non-finite or repeated vertices, zero area and self-intersection are
//!    refused.
//! 2. **Domain** ([`Domain::triangulate`] or [`Domain::from_mesh`]): a triangulation
//!    of the interior, every cage vertex a mesh vertex, cage edges chains of boundary
//!    edges. Mesh vertices on the cage carry the Lagrange/linear boundary values.
//! 3. **Geodesics** ([`geodesic_distances`]): the heat method of Crane et al. 2013,
//!    as the paper uses (one factorisation of `M + h²K`, one solve per cage vertex,
//!    one Poisson solve with a second factorisation); each distance divided by its
//!    own maximum (eq. 12). `φ_i = τ(D_i)` ([`Tau`], `x²` by default).
//! 4. **Optimisation** ([`solve`]): one piecewise-linear function `w_i` per cage
//!    vertex minimising `Σ_i Σ_s φ_i^s A_s ‖∇_s w_i‖` under reproduction, partition of
//!    unity, non-negativity and the boundary values. The unknown rows are written
//!    `W = YM + H` (the rows of `M` an orthonormal basis of the null space of `Kᵀ`,
//!    `H` the least-norm solution of `WK = B`), and Appendix B's ADMM runs: group
//!    soft-thresholding for the gradients, clamping for non-negativity, one sparse
//!    Cholesky factorisation of `GᵀG + βM` (faer) reused by every Y-update,
//!    over-relaxation 1.65. Per-triangle and per-vertex steps run in parallel
//!    (rayon). A final per-vertex projection onto the constraint set makes the
//!    returned coordinates satisfy partition of unity, reproduction and
//!    non-negativity to rounding; boundary rows are the exact boundary values.
//! 5. **Storage** ([`Coordinates::compact`]): weights below `10⁻³/n` dropped and
//!    each row renormalised, as the paper's Table 1; [`CompactWeights::deform`].
//! 6. **Locality statistics** ([`locality`]): the paper's `P(t)` and `Q(k)`
//!    (eqs. 19–21), `P` exact for the piecewise-linear functions, `Q` counted at the
//!    vertices.
//!
//! # Converged, not just stopped
//!
//! Appendix B taken literally (model scaled to bounding-box diameter 1, `μ = 10`,
//! absolute thresholds `ε_p = N_p·10⁻⁶`, `ε_d = N_d·10⁻⁵`) stops far from the optimum.
//! This crate instead:
//! - works in a frame with the cage centred and its farthest vertex at distance 1;
//! - splits the gradient as `x = √A_s·∇_s w` (so `GᵀG` is the cotangent stiffness
//!   matrix, independent of the frame's scale, and the objective term is
//!   `φ √A_s ‖x‖`), where the paper's printed `G` has `x = ∇_s w` and the authors'
//!   released code `x = A_s ∇_s w`; all three have the same minimiser;
//! - weights the `W = W̃` split by the lumped mass, `β‖W − W̃‖²_M` with `β = 1`, so
//!   that both splits measure functions in the L² norm and the Y-update matrix
//!   `GᵀG + βM` discretises `−Δ + β` whatever the mesh resolution (the printed
//!   `GᵀG + I` weights every vertex alike, so the finer the mesh, the more the
//!   clamping split dominates: it took about twice the iterations);
//! - starts the penalty at `μ = ‖φ√A‖ / ‖G W₀‖` (the multipliers of the gradient
//!   split are bounded by `φ√A`; `W₀` is the starting point) and adapts it by
//!   residual balancing towards equal relative residuals, first after 10 iterations
//!   and then half as often after each change (changes that never stop can keep
//!   ADMM from converging); `μ` multiplies the whole Y-update, so no
//!   refactorisation is needed;
//! - stops on relative residuals (Boyd et al. 2011, §3.3.1) at
//!   [`DEFAULT_TOLERANCE`], measured every 5 iterations. The test
//!   `converged_objective_is_stable` checks the objective is within 0.5% of a run
//!   with a 10× tighter threshold, and `tests/optimality.rs` certifies it within
//!   0.5% of the optimum with a lower bound from an independent solver.
//!
//! Anderson acceleration of the iteration (Zhang, Peng, Ouyang and Deng 2019) was
//! measured: with a memory of 5 it saved 25–75% of the iterations, but its history
//! pass costs more than the iteration it replaces, so it is not used.
//!
//! An iteration is one sparse solve with `n` right-hand sides (the columns split
//! between two threads), one pass over the triangles (the X-update, in place) and
//! one over the unknown rows (the W-update, with the next Y-update's `Gᵀ(x̃ + u)`
//! gathered from each row's triangles); the dual residual is `ΔY·ΔR` from the
//! Y-update's own right-hand sides rather than another pass. The iterations keep
//! their state (and the weights `φ√A`) in single precision, computing in double:
//! half the memory they stream through, the same iterates to the objective's
//! seventh digit. Their rows are padded to a multiple of four columns (from 8 cage
//! vertices on; the extra columns have no cage vertex and stay zero) so that every
//! loop over a row runs in whole vectors, and the iterations that measure the
//! residuals store their terms and sum them in four lanes, so that their loops
//! vectorise too. A mesh given as it is ([`Domain::from_mesh`]) is solved numbered
//! along a Z-order curve, as [`Domain::triangulate`] numbers its own, and the rows
//! come back in the caller's numbering: the passes read each triangle's corners' rows
//! and each row's triangles, which a file's numbering may scatter.
//!
//! The passes of an iteration are compiled twice, for the baseline x86-64 and for
//! AVX2, and the AVX2 copy runs where the CPU has it ([`Settings::wide_vectors`]):
//! the same numbers (nothing is fused or reordered), an iteration 15–20% cheaper at
//! 5,000–20,000 vertices and half as dear at 92,000.
//!
//! Iterations 6–10 run on all of rayon's threads and 11–15 on one; the faster way
//! runs the rest ([`Report::threads`] says which). Where the mesh's working set
//! outgrows the caches, one thread can beat two that share a core's caches: on a
//! machine with two hardware threads, the baseline passes took 76 ms an iteration on
//! one against 104 ms on both at 92,000 vertices, while at 19,000 two took 6.1 ms and
//! one 11 ms (with AVX2, two win at both sizes there).
//!
//! # Reading the paper
//!
//! Where the text leaves a choice, this crate takes these:
//! - `φ_i^s` is `τ` of the mean of `D_i` at the triangle's corners (the value of the
//!   piecewise-linear `D_i` at the centroid; the paper says "at the centroid").
//! - `D_i` is divided by its own maximum over the mesh vertices (eq. 12), not a
//!   global maximum.
//! - The heat method's time step is `t = h²` with `h` the mean edge length; the
//!   Laplacian has natural (Neumann) boundary conditions; the heat is a unit impulse
//!   at the cage vertex; the Poisson problem is made definite with a mass term
//!   `10⁻⁸·M/|Ω|` and its solution shifted to zero at the source.
//! - The boundary values on cage edges (property 5, "linear on cage edges") are the
//!   linear interpolation between the edge's two Lagrange values; mesh vertices lie
//!   on the cage when within `10⁻⁹` of the cage's bounding-box diagonal.
//! - The W-split constraint enters the augmented Lagrangian weighted by the lumped
//!   mass (above), so the Y-update matrix is `GᵀG + βM`. `YM` is never formed
//!   through `M` itself: `(GᵀG + βM)⁻¹` acts on rows and `MᵀM` on columns, so the
//!   update is `(GᵀG + βM)⁻¹ R (I − K(KᵀK)⁻¹Kᵀ)` — the same `W` up to rounding,
//!   with a 3-column projection per row in place of two products with the
//!   `(n − 3) × n` basis (12% off an iteration with 26 cage vertices).
//! - The dual residual is eq. (27) (with `G` applied, not the `Mᵀ`-projected form,
//!   and the mass-weighted split), and eq. (26)'s primal residual uses the
//!   un-relaxed `X`, `W`.
//! - The ADMM starts from the Y-update with every split variable and multiplier zero
//!   (smooth, harmonic-like coordinates), the multipliers from zero.
//! - Compact rows keep weights `≥ 10⁻³/n` (the paper: "greater than").
//! - The returned rows are not ADMM's iterate but its projection onto the
//!   constraint set (the paper returns the iterate). The projection is first sought
//!   within the face where ADMM's clamped `W` is zero, so that the zeros that make
//!   the coordinates local stay exact zeros; only if that face holds no solution is
//!   the row projected onto the whole set.
//!
//! ```
//! use glam::DVec2;
//! use lbc::{Cage, Domain, Settings, solve};
//!
//! let cage = Cage::new(vec![
//!     DVec2::new(0.0, 0.0),
//!     DVec2::new(2.0, 0.0),
//!     DVec2::new(2.0, 1.0),
//!     DVec2::new(0.0, 1.0),
//! ])?;
//! let domain = Domain::triangulate(&cage, 150)?;
//! let coordinates = solve(&domain, &Settings::default(), &mut |_| true)?;
//! // Linear precision: moving the cage affinely moves the inside the same way.
//! let pose: Vec<DVec2> = cage.vertices().iter().map(|c| 2.0 * *c + DVec2::X).collect();
//! let moved = coordinates.deform(&pose)?;
//! for (p, q) in domain.positions().iter().zip(&moved) {
//!     assert!((2.0 * *p + DVec2::X - *q).length() < 1e-6);
//! }
//! # Ok::<(), lbc::LbcError>(())
//! ```

mod cage;
mod compact;
mod domain;
mod error;
mod fem;
mod geodesic;
mod projection;
mod report;
mod solve;
mod stats;
mod wide;

pub use cage::{Cage, THIN};
pub use compact::{CompactWeights, Coordinates};
pub use domain::{Domain, OnCage};
pub use error::LbcError;
pub use geodesic::geodesic_distances;
pub use report::{Progress, Report};
pub use solve::{DEFAULT_TOLERANCE, Settings, Tau, solve, solve_with_distances};
pub use stats::{Locality, locality};
