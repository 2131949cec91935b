//! Manipulation (§4.3, step 3): one back-substitution for step one, the per-triangle
//! fit, and one back-substitution (x and y together) for step two.

use glam::DVec2;

use crate::compile::{Compiled, PassTriangle, StepOne};
use crate::error::ArapError;
use crate::solver::Entry;
use crate::triangle::{fitted_rotation, rotate};

/// The result of one pose: vertex positions, indexed like the rest positions.
///
/// Keep one around and pass it to [`Compiled::update_into`] to reuse its buffers
/// across drag frames.
#[derive(Default)]
pub struct Deformation {
    /// Step one's intermediate result (§4.1): the scale-free fit, which lets triangles
    /// grow and shrink.
    pub step_one: Vec<DVec2>,
    /// The final result (§4.2): step two's scale-adjusted positions.
    pub positions: Vec<DVec2>,
    pub(crate) scratch: Scratch,
}

impl Clone for Deformation {
    fn clone(&self) -> Self {
        Self {
            step_one: self.step_one.clone(),
            positions: self.positions.clone(),
            scratch: Scratch::default(),
        }
    }
}

impl std::fmt::Debug for Deformation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Deformation")
            .field("step_one", &self.step_one)
            .field("positions", &self.positions)
            .finish_non_exhaustive()
    }
}

/// Buffers reused between updates.
#[derive(Default)]
pub(crate) struct Scratch {
    step_one: Vec<DVec2>,
    pub(crate) step_two: Vec<DVec2>,
    pub(crate) linear: Vec<DVec2>,
    pub(crate) work: Vec<DVec2>,
}

impl Compiled {
    /// Poses the mesh: `targets[i]` is where constrained vertex
    /// [`constrained()[i]`](Compiled::constrained) goes. Returns step one's result and
    /// the final one; constrained vertices sit exactly on their targets in both.
    ///
    /// ```
    /// use arap::Registration;
    /// use glam::DVec2;
    ///
    /// // A 3 × 2 strip of unit squares, each split along a diagonal.
    /// let rest: Vec<DVec2> = (0..3)
    ///     .flat_map(|y| (0..4).map(move |x| DVec2::new(x as f64, y as f64)))
    ///     .collect();
    /// let mut triangles = Vec::new();
    /// for y in 0..2u32 {
    ///     for x in 0..3u32 {
    ///         let v = y * 4 + x;
    ///         triangles.push([v, v + 1, v + 5]);
    ///         triangles.push([v, v + 5, v + 4]);
    ///     }
    /// }
    /// let registration = Registration::new(&rest, &triangles)?;
    /// // Pin the two ends of the middle row; drag the right one up.
    /// let compiled = registration.compile(&[4, 7], None)?;
    /// let pose = compiled.update(&[DVec2::new(0.0, 1.0), DVec2::new(3.0, 2.5)])?;
    /// assert_eq!(pose.positions[7], DVec2::new(3.0, 2.5));
    /// assert!(pose.positions.iter().all(|p| p.is_finite()));
    /// # Ok::<(), arap::ArapError>(())
    /// ```
    ///
    /// # Errors
    /// [`ArapError::TargetCount`] if `targets` is not as long as the constraint list,
    /// [`ArapError::NonFiniteTarget`] for a NaN or infinite target.
    pub fn update(&self, targets: &[DVec2]) -> Result<Deformation, ArapError> {
        let mut out = Deformation::default();
        self.update_into(targets, &mut out)?;
        Ok(out)
    }

    /// [`Compiled::update`] into `out`, reusing its buffers: a drag frame allocates
    /// nothing after the first.
    ///
    /// # Errors
    /// As [`Compiled::update`]; `out` is left unchanged on error.
    pub fn update_into(&self, targets: &[DVec2], out: &mut Deformation) -> Result<(), ArapError> {
        self.update_split_into(targets, targets, out)
    }

    /// [`Compiled::update_into`] with the constrained vertices at `targets` in step
    /// two (the final result) but at `step_one` in step one: for a constraint added
    /// where a solve already put its vertices — pinned at their step-one and final
    /// positions, it leaves both steps' answers as they were (each step's minimiser
    /// over fewer free vertices is the one it had).
    ///
    /// # Errors
    /// Refuses a list of constrained positions of the wrong length or with a
    /// non-finite entry.
    pub(crate) fn check_targets(&self, targets: &[DVec2]) -> Result<(), ArapError> {
        if targets.len() != self.constrained.len() {
            return Err(ArapError::TargetCount {
                got: targets.len(),
                expected: self.constrained.len(),
            });
        }
        if let Some(constraint) = targets.iter().position(|t| !t.is_finite()) {
            return Err(ArapError::NonFiniteTarget { constraint });
        }
        Ok(())
    }

    /// As [`Compiled::update`], for either list; `out` is left unchanged on error.
    pub fn update_split_into(
        &self,
        step_one: &[DVec2],
        targets: &[DVec2],
        out: &mut Deformation,
    ) -> Result<(), ArapError> {
        self.check_targets(step_one)?;
        self.check_targets(targets)?;
        let mesh = &*self.mesh;
        out.step_one.clear();
        out.step_one.extend_from_slice(&mesh.rest);
        for (&v, &t) in self.constrained.iter().zip(step_one) {
            out.step_one[v as usize] = t;
        }
        let (Some(one), Some(two)) = (&self.step_one, &self.step_two) else {
            out.positions.clone_from(&out.step_one);
            for (&v, &t) in self.constrained.iter().zip(targets) {
                out.positions[v as usize] = t;
            }
            return Ok(());
        };
        let scratch = &mut out.scratch;

        // Step one (eq. 8): G'u = −Bq (+ the rest pull on loose pieces).
        match one {
            StepOne::Substitution(factor) => {
                let r1 = &mut scratch.step_one;
                r1.clone_from(&self.step_one_rhs);
                for c in &self.couplings {
                    r1[c.free as usize] -= c.g.mul(step_one[c.constraint as usize]);
                }
                factor.solve_in_place(r1, &mut scratch.work);
                for (&v, &p) in self.free.iter().zip(r1.iter()) {
                    out.step_one[v as usize] = p;
                }
            }
            StepOne::Product { base, columns } => {
                let k = step_one.len();
                for ((&v, &u0), row) in self.free.iter().zip(base).zip(columns.chunks_exact(k)) {
                    let mut u = u0;
                    for (c, &q) in row.iter().zip(step_one) {
                        u += c.mul(q);
                    }
                    out.step_one[v as usize] = u;
                }
            }
        }

        // Step two: fit each rest triangle to its step-one triangle (eqs. 9–11),
        // keep the rotation (the fit scaled back to rest size), and solve for the
        // positions whose edges are nearest the rotated rest edges (eqs. 12–16).
        out.positions.clone_from(&out.step_one);
        for (&v, &t) in self.constrained.iter().zip(targets) {
            out.positions[v as usize] = t;
        }
        self.fit_and_solve(two, &out.step_one, targets, &mut out.positions, scratch);
        Ok(())
    }

    /// The ARAP energy of `positions` over the triangles with a constraint in their
    /// piece: Σ w·Σ‖d − R·e‖² over each triangle's three edges, e at rest, d posed, R
    /// the rotation fitted to the triangle (the paper's fit), w its rigidity weight.
    pub fn energy(&self, positions: &[DVec2]) -> f64 {
        self.fit(positions, &mut Vec::new())
    }

    /// Step two's fit and solve: rotations fitted to the triangles of `shape`, the
    /// rotated rest edges added to the linear term f at each corner (corner c ends
    /// edge c−1 → c and starts edge c → c+1), and H'u = f_u − Dq solved (eq. 16, x and
    /// y together) into the free vertices of `out`. Returns the energy of `shape`
    /// ([`Compiled::energy`]), which the fit computes on the way.
    pub(crate) fn fit_and_solve(
        &self,
        two: &crate::solver::Cholesky<f64>,
        shape: &[DVec2],
        targets: &[DVec2],
        out: &mut [DVec2],
        scratch: &mut Scratch,
    ) -> f64 {
        let energy = self.fit(shape, &mut scratch.linear);
        self.solve_fitted(two, targets, out, scratch);
        energy
    }

    /// The global step after [`Compiled::fit`] has filled `scratch.linear`: H'u =
    /// f_u − Dq solved into the free vertices of `out`.
    pub(crate) fn solve_fitted(
        &self,
        two: &crate::solver::Cholesky<f64>,
        targets: &[DVec2],
        out: &mut [DVec2],
        scratch: &mut Scratch,
    ) {
        let r2 = &mut scratch.step_two;
        r2.clear();
        r2.extend(self.free.iter().map(|&v| scratch.linear[v as usize]));
        for c in &self.couplings {
            r2[c.free as usize] -= c.h * targets[c.constraint as usize];
        }
        two.solve_in_place(r2, &mut scratch.work);
        for (&v, &p) in self.free.iter().zip(r2.iter()) {
            out[v as usize] = p;
        }
    }

    /// The local step: fits every triangle's rotation to `shape` and writes the
    /// rotated rest edges' contributions to the global step's linear term into `b`
    /// (one per vertex). Returns the energy of `shape` with those rotations, which
    /// is [`Compiled::energy`] of it.
    pub(crate) fn fit(&self, shape: &[DVec2], b: &mut Vec<DVec2>) -> f64 {
        let n = self.mesh.rest.len();
        b.clear();
        b.resize(n, DVec2::ZERO);
        fit_triangles(&self.triangles, shape, b)
    }
}

/// [`Compiled::fit`] over some of its triangles, adding into `b`.
fn fit_triangles(triangles: &[PassTriangle], shape: &[DVec2], b: &mut [DVec2]) -> f64 {
    let mut energy = 0.0;
    for t in triangles {
        let [i, j, k] = t.vertices.map(|v| v as usize);
        let rotation = fitted_rotation(&t.fit, [shape[i], shape[j], shape[k]]);
        let e01 = rotate(rotation, t.edges[0]);
        let e12 = rotate(rotation, t.edges[1]);
        let e20 = -(e01 + e12);
        b[i] += e20 - e01;
        b[j] += e01 - e12;
        b[k] += e12 - e20;
        // The edges carry the weight w: w·‖d − R·e‖² = ‖w·d − R·(w·e)‖² / w.
        let w = t.weight;
        let d = [
            shape[j] - shape[i],
            shape[k] - shape[j],
            shape[i] - shape[k],
        ];
        energy += ((d[0] * w - e01).length_squared()
            + (d[1] * w - e12).length_squared()
            + (d[2] * w - e20).length_squared())
            * t.inverse_weight;
    }
    energy
}
