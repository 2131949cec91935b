//! The ARAP energy's minimum for the constrained vertices' targets: local/global
//! iterations (Sorkine and Alexa 2007) on step two's system, sped up by Anderson
//! acceleration (as Peng, Deng, Zhang and Liu apply it to local/global solvers in
//! "Anderson Acceleration for Geometry Optimization and Physics Simulation", 2018).
//!
//! One local/global iteration is a map `G`: fit every triangle's rotation to the
//! current shape, then solve for the positions whose edges best match the rotated
//! rest edges. Neither half raises the energy, so plain iteration of `G` goes down to
//! a stationary point, but slowly: on a few thousand vertices hundreds of iterations
//! to settle to a hundredth of a pixel. Anderson acceleration extrapolates from the
//! last few iterates: it takes the combination of the last `G` outputs whose
//! residuals `G(x) − x` combine to the smallest, which converges like a quasi-Newton
//! method. An extrapolated shape whose energy is higher than the last accepted one is
//! dropped for the plain `G` output, whose energy cannot be higher, so the accepted
//! energies never rise.

use glam::DVec2;

use crate::compile::Compiled;
use crate::error::ArapError;
use crate::update::Deformation;

/// When [`Compiled::minimise_into`] stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Minimise {
    /// The most local/global iterations.
    pub iterations: usize,
    /// Stop once one more iteration would move no vertex farther than this (the
    /// mesh's units; pixels in the editor).
    pub tolerance: f64,
    /// How many earlier iterates the acceleration combines; 0 is plain local/global.
    pub history: usize,
}

impl Default for Minimise {
    /// 500 iterations at most, a hundredth of a unit, five earlier iterates.
    fn default() -> Self {
        Self {
            iterations: 500,
            tolerance: 0.01,
            history: 5,
        }
    }
}

/// How a minimisation went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Convergence {
    /// Local/global iterations run (each one fit and one back-substitution; a dropped
    /// extrapolation costs one more fit).
    pub iterations: usize,
    /// [`Compiled::energy`] of the result's last fitted shape (the result itself has
    /// at most this energy).
    pub energy: f64,
    /// How far the last iteration moved a vertex.
    pub moved: f64,
}

impl Compiled {
    /// Moves `out.positions` (any shape with the constrained vertices anywhere; the
    /// two-step result, or the previous frame's) to the minimum of the ARAP energy
    /// [`Compiled::energy`] with the constrained vertices at `targets`, by
    /// accelerated local/global iterations (see the module docs). Stops when an
    /// iteration would move no vertex farther than `settings.tolerance`, or after
    /// `settings.iterations`. `out.step_one` is left as it is.
    ///
    /// # Errors
    /// As [`Compiled::update`]; `out` is left unchanged on error.
    pub fn minimise_into(
        &self,
        targets: &[DVec2],
        out: &mut Deformation,
        settings: &Minimise,
    ) -> Result<Convergence, ArapError> {
        self.check_targets(targets)?;
        let rest = &self.mesh.rest;
        if out.positions.len() != rest.len() {
            out.positions.clone_from(rest);
        }
        for (&v, &t) in self.constrained.iter().zip(targets) {
            out.positions[v as usize] = t;
        }
        let Some(two) = &self.step_two else {
            return Ok(Convergence {
                iterations: 0,
                energy: self.energy(&out.positions),
                moved: 0.0,
            });
        };
        let free = &self.free;
        let mut shape = std::mem::take(&mut out.positions);
        let mut acceleration = Anderson::new(settings.history);
        // The last plain output of G, in the free vertices' order, and its shape's
        // energy bound.
        let mut plain: Vec<DVec2> = Vec::with_capacity(free.len());
        let mut accepted = f64::INFINITY;
        let mut report = Convergence {
            iterations: 0,
            energy: f64::INFINITY,
            moved: f64::INFINITY,
        };
        let mut next = shape.clone();
        let mut current: Vec<DVec2> = free.iter().map(|&v| shape[v as usize]).collect();
        for iteration in 0..settings.iterations {
            let scratch = &mut out.scratch;
            let mut energy = self.fit(&shape, &mut scratch.linear);
            if energy > accepted && !plain.is_empty() {
                // The extrapolation went uphill: take the plain step instead (its
                // energy is at most the last accepted one).
                for (&v, &p) in free.iter().zip(&plain) {
                    shape[v as usize] = p;
                }
                current.clone_from(&plain);
                energy = self.fit(&shape, &mut scratch.linear);
            }
            self.solve_fitted(two, targets, &mut next, scratch);
            accepted = energy;
            plain.clear();
            plain.extend(free.iter().map(|&v| next[v as usize]));
            let moved = current
                .iter()
                .zip(&plain)
                .map(|(a, b)| a.distance_squared(*b))
                .fold(0.0, f64::max)
                .sqrt();
            report = Convergence {
                iterations: iteration + 1,
                energy,
                moved,
            };
            if moved <= settings.tolerance || !moved.is_finite() {
                break;
            }
            acceleration.step(&plain, &mut current);
            for (&v, &p) in free.iter().zip(&current) {
                shape[v as usize] = p;
            }
        }
        // The last plain output: its energy is at most the last accepted one.
        for (&v, &p) in free.iter().zip(&plain) {
            shape[v as usize] = p;
        }
        out.positions = shape;
        Ok(report)
    }
}

/// Anderson acceleration's memory: the differences between successive outputs of
/// `G` and between successive residuals `G(x) − x`, in a ring of `depth`.
struct Anderson {
    depth: usize,
    outputs: Vec<Vec<DVec2>>,
    residuals: Vec<Vec<DVec2>>,
    /// The previous output and residual, once there is one.
    last: Option<(Vec<DVec2>, Vec<DVec2>)>,
    /// Where the next difference goes.
    slot: usize,
    residual: Vec<DVec2>,
    /// The residual differences' dot products, `gram[i][j]` of the ring's `i` and `j`:
    /// only a new difference's are worked out (the same numbers as afresh, each dot
    /// product summed in the same order).
    gram: Vec<Vec<f64>>,
}

impl Anderson {
    fn new(depth: usize) -> Self {
        Self {
            depth,
            outputs: Vec::new(),
            residuals: Vec::new(),
            last: None,
            slot: 0,
            residual: Vec::new(),
            gram: vec![vec![0.0; depth]; depth],
        }
    }

    /// From iterate `x` and its image `g = G(x)`, the next iterate into `x`: `g`
    /// less the combination of earlier output differences whose residual
    /// differences best cancel the current residual.
    fn step(&mut self, g: &[DVec2], x: &mut [DVec2]) {
        if self.depth == 0 {
            x.clone_from_slice(g);
            return;
        }
        self.residual.clear();
        self.residual
            .extend(g.iter().zip(x.iter()).map(|(g, x)| *g - *x));
        if let Some((last_g, last_r)) = &mut self.last {
            // The new differences go into the ring (reusing the oldest's buffers);
            // the last output and residual become the current ones.
            if self.outputs.len() < self.depth {
                self.outputs.push(Vec::new());
                self.residuals.push(Vec::new());
            }
            let (dg, dr) = (&mut self.outputs[self.slot], &mut self.residuals[self.slot]);
            dg.clear();
            dg.extend(g.iter().zip(last_g.iter()).map(|(a, b)| *a - *b));
            dr.clear();
            dr.extend(
                self.residual
                    .iter()
                    .zip(last_r.iter())
                    .map(|(a, b)| *a - *b),
            );
            for (j, other) in self.residuals.iter().enumerate() {
                let d = dot(&self.residuals[self.slot], other);
                self.gram[self.slot][j] = d;
                self.gram[j][self.slot] = d;
            }
            self.slot = (self.slot + 1) % self.depth;
            last_g.clone_from_slice(g);
            last_r.clone_from_slice(&self.residual);
        } else {
            self.last = Some((g.to_vec(), self.residual.clone()));
        }
        x.clone_from_slice(g);
        if let Some(theta) = least_squares(&self.gram, &self.residuals, &self.residual) {
            for (t, dg) in theta.iter().zip(&self.outputs) {
                for (n, d) in x.iter_mut().zip(dg) {
                    *n -= *t * *d;
                }
            }
        }
    }
}

/// `Σ aᵢ·bᵢ`, in order.
fn dot(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum::<f64>()
}

/// The coefficients θ minimising ‖r − Σ θⱼ·columnsⱼ‖ (normal equations, a touch of
/// regularisation), or `None` with no columns or a singular system. `gram` holds the
/// columns' dot products with each other.
fn least_squares(gram: &[Vec<f64>], columns: &[Vec<DVec2>], r: &[DVec2]) -> Option<Vec<f64>> {
    let m = columns.len();
    if m == 0 {
        return None;
    }
    let mut matrix = vec![vec![0.0; m + 1]; m];
    for i in 0..m {
        matrix[i][..m].copy_from_slice(&gram[i][..m]);
        matrix[i][m] = dot(&columns[i], r);
    }
    let trace: f64 = (0..m).map(|i| matrix[i][i]).sum();
    if trace <= 0.0 || !trace.is_finite() {
        return None;
    }
    for (i, row) in matrix.iter_mut().enumerate() {
        row[i] += 1e-10 * trace;
    }
    // Gaussian elimination with partial pivoting on the augmented matrix.
    for c in 0..m {
        let pivot = (c..m).max_by(|&a, &b| matrix[a][c].abs().total_cmp(&matrix[b][c].abs()))?;
        matrix.swap(c, pivot);
        let p = matrix[c][c];
        if p.abs() <= 1e-300 {
            return None;
        }
        let (above, below) = matrix.split_at_mut(c + 1);
        let pivot_row = &above[c];
        for row in below {
            let f = row[c] / p;
            for (x, &y) in row[c..].iter_mut().zip(&pivot_row[c..]) {
                *x -= f * y;
            }
        }
    }
    let mut theta = vec![0.0; m];
    for i in (0..m).rev() {
        let s: f64 = (i + 1..m).map(|k| matrix[i][k] * theta[k]).sum();
        theta[i] = (matrix[i][m] - s) / matrix[i][i];
    }
    theta.iter().all(|t| t.is_finite()).then_some(theta)
}
