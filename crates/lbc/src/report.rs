//! What a solve reports: its progress while it runs, and how it went.

use std::time::Duration;

/// One ADMM iteration's state, for a progress display. The residuals are those of
/// the last iteration that measured them (every fifth; infinite before the first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Iterations done.
    pub iteration: usize,
    /// `‖r_p‖_F` (eq. 26) in the solver's frame.
    pub primal_residual: f64,
    /// `‖r_d‖_F` (eq. 27).
    pub dual_residual: f64,
    /// What `primal_residual` must fall below.
    pub primal_threshold: f64,
    /// What `dual_residual` must fall below.
    pub dual_threshold: f64,
    /// The current penalty `μ`.
    pub penalty: f64,
}

/// How a solve went.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// ADMM iterations.
    pub iterations: usize,
    /// Whether both residuals fell below their thresholds.
    pub converged: bool,
    /// The last iteration's residuals and thresholds.
    pub last: Option<Progress>,
    /// The objective (eq. 14) of the returned coordinates, in the caller's units.
    pub objective: f64,
    /// Mesh vertices inside the cage (the unknown rows).
    pub interior_vertices: usize,
    /// Time for the geodesic distances (zero if they were given). [`solve`] factorises
    /// the Y-update's matrix beside them, on another thread: this is the time of both.
    ///
    /// [`solve`]: crate::solve
    pub geodesics: Duration,
    /// Time to assemble and factorise the Y-update's matrix `GᵀG + βM` (within
    /// `geodesics` where it ran beside them).
    pub factorisation: Duration,
    /// Time in ADMM iterations.
    pub admm: Duration,
    /// Time for the final projection.
    pub projection: Duration,
    /// Threads the iterations ran on, after the first few timed them on all of
    /// rayon's threads and on one (see the crate docs).
    pub threads: usize,
}
