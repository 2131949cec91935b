//! The optimisation of the paper's §4 and Appendix B: weighted total variation under
//! the barycentric constraints, by over-relaxed ADMM.

use std::time::{Duration, Instant};

use faer::Mat;
use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

use crate::compact::Coordinates;
use crate::domain::Domain;
use crate::error::LbcError;
use crate::fem::{Elements, Factor};
use crate::geodesic::geodesic_distances;

/// The locality weighting `τ` of eq. (11): `φ_i = τ(D_i)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tau {
    /// `τ(x) = x²`, the paper's choice for all its results.
    #[default]
    Square,
    /// `τ(x) = x`.
    Linear,
    /// `τ ≡ 1`: unweighted total variation.
    Constant,
    /// `τ(x) = √x`.
    Sqrt,
}

impl Tau {
    /// `τ(x)`.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Tau::Square => x * x,
            Tau::Linear => x,
            Tau::Constant => 1.0,
            Tau::Sqrt => x.max(0.0).sqrt(),
        }
    }
}

/// Solver settings. The defaults are the ones the crate documents and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Locality weighting.
    pub tau: Tau,
    /// Relative stopping threshold: stop when the primal residual is below
    /// `tolerance` times the larger of the norms of the split variables and of their
    /// values from `Y`, and the dual residual below `tolerance` times the norm of the
    /// multipliers (Boyd et al. 2011, §3.3.1, without the absolute term).
    pub tolerance: f64,
    /// Iteration cap; the result is returned (projected, `converged: false`) when hit.
    pub max_iterations: usize,
    /// Over-relaxation `α` (the paper: 1.5–1.8).
    pub relaxation: f64,
    /// Penalty `μ` to start with (in the solver's frame: cage centred, farthest cage
    /// vertex at distance 1).
    pub initial_penalty: f64,
    /// Residual balancing (Boyd et al. 2011, §3.4.1): every 25 iterations, double `μ`
    /// if the relative primal residual is ten times the dual one, halve it in the
    /// opposite case. The Y-update matrix does not depend on `μ`, so this costs no
    /// refactorisation.
    pub adaptive_penalty: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tau: Tau::Square,
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: 20_000,
            relaxation: 1.65,
            initial_penalty: 10.0,
            adaptive_penalty: true,
        }
    }
}

/// The default relative stopping threshold (see the crate docs for why).
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

/// One ADMM iteration's state, for a progress display.
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
    /// Time for the geodesic distances (zero if they were given).
    pub geodesics: Duration,
    /// Time to assemble and factorise `GᵀG + I`.
    pub factorisation: Duration,
    /// Time in ADMM iterations.
    pub admm: Duration,
    /// Time for the final projection.
    pub projection: Duration,
}

/// Computes the local barycentric coordinates of every mesh vertex: geodesic
/// distances (heat method), then [`solve_with_distances`].
///
/// `progress` is called after every iteration; returning `false` cancels.
///
/// # Errors
/// [`LbcError::Cancelled`] if `progress` asked to stop; [`LbcError::Factorization`]
/// only on a bug.
pub fn solve(
    domain: &Domain,
    settings: &Settings,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<Coordinates, LbcError> {
    let start = Instant::now();
    let distances = geodesic_distances(domain)?;
    let geodesics = start.elapsed();
    let mut c = solve_with_distances(domain, &distances, settings, progress)?;
    c.report.geodesics = geodesics;
    Ok(c)
}

/// Like [`solve`], with the normalised distances `D_i` given (`distances[i][v]`, as
/// [`geodesic_distances`] returns them).
///
/// # Errors
/// As [`solve`]; [`LbcError::InvalidMesh`] if `distances` has the wrong shape.
pub fn solve_with_distances(
    domain: &Domain,
    distances: &[Vec<f64>],
    settings: &Settings,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<Coordinates, LbcError> {
    let n = domain.cage().len();
    let nv = domain.positions().len();
    if distances.len() != n || distances.iter().any(|d| d.len() != nv) {
        return Err(LbcError::InvalidMesh(
            "distances: one row per cage vertex, one value per mesh vertex".into(),
        ));
    }
    let problem = Problem::new(domain, distances, settings.tau);
    let mut z = problem.initial_rows(domain);
    let mut report = Report {
        iterations: 0,
        converged: true,
        last: None,
        objective: 0.0,
        interior_vertices: problem.interior.len(),
        geodesics: Duration::ZERO,
        factorisation: Duration::ZERO,
        admm: Duration::ZERO,
        projection: Duration::ZERO,
    };
    let mut clamped = None;
    if !problem.interior.is_empty() && n > 3 {
        let t = Instant::now();
        let factor = problem.factorise(domain)?;
        report.factorisation = t.elapsed();
        let t = Instant::now();
        clamped = Some(problem.admm(&factor, &mut z, settings, progress, &mut report)?);
        report.admm = t.elapsed();
    }
    let t = Instant::now();
    problem.project(&mut z, clamped.as_deref());
    report.projection = t.elapsed();
    report.objective = problem.objective(&z);
    Ok(Coordinates::new(n, z, report))
}

/// Everything fixed during the iterations, in the solver's frame.
struct Problem {
    n: usize,
    triangles: Vec<[u32; 3]>,
    /// Mesh vertex of each unknown row.
    interior: Vec<u32>,
    /// Unknown row of each mesh vertex.
    row_of: Vec<Option<u32>>,
    /// `√A_s·∇λ_k`: `G` of the paper with the gradient integrated over `√A_s`.
    g: Vec<[DVec2; 3]>,
    /// `φ_i^s·√A_s`, triangle-major.
    coef: Vec<f64>,
    /// `φ_i^s·A_s` and the plain gradients, for the objective.
    elements: Elements,
    phi: Vec<f64>,
    /// `(x, y, 1)` of each cage vertex: the rows of `K`.
    k: Vec<DVec3>,
    /// `(KᵀK)⁻¹`.
    ktk_inv: DMat3,
    /// Solver-frame positions.
    q: Vec<DVec2>,
    /// The caller's length per solver-frame length.
    scale: f64,
    /// `Σ_{k on the cage} √A_s ∇λ_k w_i(v_k)`: `E` of eq. (17).
    e: Vec<DVec2>,
    /// Per unknown row, its `(triangle, corner)` incidences (CSR).
    adj_ptr: Vec<u32>,
    adj: Vec<(u32, u8)>,
}

impl Problem {
    fn new(domain: &Domain, distances: &[Vec<f64>], tau: Tau) -> Self {
        let cage = domain.cage().vertices();
        let n = cage.len();
        // The frame: cage centroid at the origin, farthest cage vertex at 1.
        let centre = cage.iter().copied().sum::<DVec2>() / n as f64;
        let scale = cage.iter().map(|c| c.distance(centre)).fold(0.0, f64::max);
        let q: Vec<DVec2> = domain
            .positions()
            .iter()
            .map(|p| (*p - centre) / scale)
            .collect();
        let triangles = domain.triangles().to_vec();
        let elements = Elements::new(&q, &triangles);
        let g: Vec<[DVec2; 3]> = elements
            .grad
            .iter()
            .zip(&elements.area)
            .map(|(gr, &a)| gr.map(|x| a.sqrt() * x))
            .collect();
        let mut phi = vec![0.0; triangles.len() * n];
        for (s, t) in triangles.iter().enumerate() {
            for i in 0..n {
                let d = t.iter().map(|&v| distances[i][v as usize]).sum::<f64>() / 3.0;
                phi[s * n + i] = tau.apply(d);
            }
        }
        let coef = phi
            .iter()
            .enumerate()
            .map(|(si, &p)| p * elements.area[si / n].sqrt())
            .collect();
        let mut interior = Vec::new();
        let mut row_of = vec![None; q.len()];
        for (v, on) in domain.on_cage().iter().enumerate() {
            if on.is_none() {
                row_of[v] = Some(interior.len() as u32);
                interior.push(v as u32);
            }
        }
        let k: Vec<DVec3> = cage
            .iter()
            .map(|c| ((*c - centre) / scale).extend(1.0))
            .collect();
        let ktk = k.iter().fold(DMat3::ZERO, |acc, r| {
            acc + DMat3::from_cols(*r * r.x, *r * r.y, *r * r.z)
        });
        let ktk_inv = ktk.inverse();

        let mut count = vec![0u32; interior.len() + 1];
        for t in &triangles {
            for &v in t {
                if let Some(r) = row_of[v as usize] {
                    count[r as usize + 1] += 1;
                }
            }
        }
        for j in 0..interior.len() {
            count[j + 1] += count[j];
        }
        let adj_ptr = count.clone();
        let mut fill = count;
        let mut adj = vec![(0u32, 0u8); adj_ptr[interior.len()] as usize];
        for (s, t) in triangles.iter().enumerate() {
            for (c, &v) in t.iter().enumerate() {
                if let Some(r) = row_of[v as usize] {
                    adj[fill[r as usize] as usize] = (s as u32, c as u8);
                    fill[r as usize] += 1;
                }
            }
        }
        let mut problem = Self {
            n,
            triangles,
            interior,
            row_of,
            g,
            coef,
            elements,
            phi,
            k,
            ktk_inv,
            q,
            scale,
            e: Vec::new(),
            adj_ptr,
            adj,
        };
        // E: G applied to the boundary values alone.
        let mut boundary_only = problem.initial_rows(domain);
        for &v in &problem.interior {
            let v = v as usize;
            boundary_only[v * n..(v + 1) * n].fill(0.0);
        }
        let mut e = vec![DVec2::ZERO; problem.triangles.len() * n];
        problem.apply_g(&boundary_only, &mut e);
        problem.e = e;
        problem
    }

    /// Rows of all mesh vertices: boundary values on the cage, the least-norm
    /// solution `H` of `WK = B` inside.
    fn initial_rows(&self, domain: &Domain) -> Vec<f64> {
        let n = self.n;
        let mut z = vec![0.0; self.q.len() * n];
        for (v, on) in domain.on_cage().iter().enumerate() {
            let row = &mut z[v * n..(v + 1) * n];
            match on {
                Some(at) => {
                    for (i, w) in domain.boundary_weights(*at) {
                        row[i] += w;
                    }
                }
                None => self.least_norm(self.q[v], row),
            }
        }
        z
    }

    /// `H`'s row at `p`: `K (KᵀK)⁻¹ (p, 1)`.
    fn least_norm(&self, p: DVec2, row: &mut [f64]) {
        let a = self.ktk_inv * p.extend(1.0);
        for (w, k) in row.iter_mut().zip(&self.k) {
            *w = k.dot(a);
        }
    }

    /// `out = G·z` over all triangles (boundary rows included, so this is `GW + E`).
    fn apply_g(&self, z: &[f64], out: &mut [DVec2]) {
        let n = self.n;
        out.par_chunks_mut(n).enumerate().for_each(|(s, o)| {
            let t = self.triangles[s];
            let g = &self.g[s];
            let r = t.map(|v| &z[v as usize * n..(v as usize + 1) * n]);
            for i in 0..n {
                o[i] = g[0] * r[0][i] + g[1] * r[1][i] + g[2] * r[2][i];
            }
        });
    }

    fn factorise(&self, domain: &Domain) -> Result<Factor, LbcError> {
        let ones = vec![1.0; self.q.len()];
        let row_of = &self.row_of;
        let map = |v: u32| row_of[v as usize].map(|r| r as usize);
        let elements = Elements::new(&self.q, domain.triangles());
        Factor::new(
            self.interior.len(),
            &elements.lower_triplets(&self.triangles, &map, 1.0, &ones, 1.0),
        )
    }

    /// The Y-update: `Y = (GᵀG + I)⁻¹ [Gᵀ(x + u1 − E) + w + u2] Mᵀ`, then the unknown
    /// rows of `z` become `YM + H`. `x`, `u1` are per triangle, `w`, `u2` per unknown
    /// row; the sums are formed here rather than in buffers of their own (a pass over
    /// each less per iteration).
    fn y_update(&self, factor: &Factor, targets: Targets<'_>, z: &mut [f64]) {
        let n = self.n;
        let mi = self.interior.len();
        let Targets { x, u1, w, u2 } = targets;
        // `(GᵀG + I)⁻¹` acts on rows (mesh vertices) and `MᵀM` on columns (cage
        // vertices), so they commute: `Y M = (GᵀG + I)⁻¹ (R MᵀM)`, and `MᵀM` is the
        // projector onto the null space of `Kᵀ`, `I − K(KᵀK)⁻¹Kᵀ`. Projecting each
        // row of `R` (3 dot products) costs far less than multiplying by `Mᵀ` and then
        // by `M` (n − 3 each), for three more right-hand side columns in the solve.
        let mut y = Mat::<f64>::zeros(mi, n);
        let mut rhs = vec![0.0; mi * n];
        rhs.par_chunks_mut(n).enumerate().for_each_init(
            || vec![0.0; n],
            |acc, (j, out)| {
                for i in 0..n {
                    acc[i] = w[j * n + i] + u2.map_or(0.0, |u| u[j * n + i]);
                }
                for &(s, c) in &self.adj[self.adj_ptr[j] as usize..self.adj_ptr[j + 1] as usize] {
                    let g = self.g[s as usize][c as usize];
                    let base = s as usize * n;
                    for i in 0..n {
                        let target = u1.map_or(x[base + i], |u| x[base + i] + u[base + i]);
                        acc[i] += g.dot(target - self.e[base + i]);
                    }
                }
                let kt: DVec3 = acc.iter().zip(&self.k).map(|(a, k)| *a * *k).sum();
                let coef = self.ktk_inv * kt;
                for ((o, a), k) in out.iter_mut().zip(acc.iter()).zip(&self.k) {
                    *o = a - k.dot(coef);
                }
            },
        );
        for c in 0..n {
            for j in 0..mi {
                y[(j, c)] = rhs[j * n + c];
            }
        }
        factor.solve_in_place(y.as_mut());
        let mut rows = vec![0.0; mi * n];
        rows.par_chunks_mut(n).enumerate().for_each(|(j, row)| {
            let v = self.interior[j] as usize;
            self.least_norm(self.q[v], row);
            for (i, value) in row.iter_mut().enumerate() {
                *value += y[(j, i)];
            }
        });
        for (j, row) in rows.chunks_exact(n).enumerate() {
            let v = self.interior[j] as usize;
            z[v * n..(v + 1) * n].copy_from_slice(row);
        }
    }

    #[allow(clippy::too_many_lines)]
    fn admm(
        &self,
        factor: &Factor,
        z: &mut [f64],
        settings: &Settings,
        progress: &mut dyn FnMut(&Progress) -> bool,
        report: &mut Report,
    ) -> Result<Vec<f64>, LbcError> {
        let n = self.n;
        let nt = self.triangles.len();
        let mi = self.interior.len();
        let alpha = settings.relaxation;
        // Start from the smoothest coordinates: the Y-update with every split
        // variable and multiplier zero (a regularised harmonic solve).
        let zero_x = vec![DVec2::ZERO; nt * n];
        let zero_w = vec![0.0; mi * n];
        let start = Targets {
            x: &zero_x,
            u1: None,
            w: &zero_w,
            u2: None,
        };
        self.y_update(factor, start, z);
        drop(zero_x);
        drop(zero_w);
        let mut p = vec![DVec2::ZERO; nt * n];
        self.apply_g(z, &mut p);
        let mut p_old = p.clone();
        let mut zi_old = vec![0.0; mi * n];
        // Scaled multipliers u = λ/μ.
        let mut u1 = vec![DVec2::ZERO; nt * n];
        let mut u2 = vec![0.0; mi * n];
        let mut x = vec![DVec2::ZERO; nt * n];
        let mut xt = vec![DVec2::ZERO; nt * n];
        let mut w = vec![0.0; mi * n];
        let mut wt = vec![0.0; mi * n];
        let mut mu = settings.initial_penalty;
        report.converged = false;
        let tiny = 1e-14 * (((nt * 2 + mi) * n) as f64).sqrt();
        for it in 1..=settings.max_iterations {
            // Step 1: X by group soft-thresholding (eq. 30), W by clamping (eq. 31),
            // both over-relaxed.
            x.par_chunks_mut(n)
                .zip(xt.par_chunks_mut(n))
                .enumerate()
                .for_each(|(s, (xs, xts))| {
                    let base = s * n;
                    for i in 0..n {
                        let a = p[base + i] - u1[base + i];
                        let thr = self.coef[base + i] / mu;
                        let len = a.length();
                        let v = if len <= thr {
                            DVec2::ZERO
                        } else {
                            (1.0 - thr / len) * a
                        };
                        xs[i] = v;
                        xts[i] = alpha * v + (1.0 - alpha) * p[base + i];
                    }
                });
            w.par_chunks_mut(n)
                .zip(wt.par_chunks_mut(n))
                .enumerate()
                .for_each(|(j, (wj, wtj))| {
                    let v = self.interior[j] as usize;
                    for i in 0..n {
                        let zi = z[v * n + i];
                        let val = (zi - u2[j * n + i]).max(0.0);
                        wj[i] = val;
                        wtj[i] = alpha * val + (1.0 - alpha) * zi;
                    }
                });
            for j in 0..mi {
                let v = self.interior[j] as usize;
                zi_old[j * n..(j + 1) * n].copy_from_slice(&z[v * n..(v + 1) * n]);
            }
            std::mem::swap(&mut p, &mut p_old);
            // Step 2: Y with x̃ + u1 and w̃ + u2 as targets.
            let targets = Targets {
                x: &xt,
                u1: Some(&u1),
                w: &wt,
                u2: Some(&u2),
            };
            self.y_update(factor, targets, z);
            self.apply_g(z, &mut p);
            // Step 3: multipliers; residuals (eqs. 26–27).
            let (mut rp, mut rd, mut nx, mut nz, mut nu) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for k in 0..nt * n {
                u1[k] += xt[k] - p[k];
                rp += (x[k] - p[k]).length_squared();
                rd += (p[k] - p_old[k]).length_squared();
                nx += x[k].length_squared();
                nz += p[k].length_squared();
                nu += u1[k].length_squared();
            }
            for j in 0..mi {
                let v = self.interior[j] as usize;
                for i in 0..n {
                    let k = j * n + i;
                    let zn = z[v * n + i];
                    u2[k] += wt[k] - zn;
                    rp += (w[k] - zn).powi(2);
                    rd += (zn - zi_old[k]).powi(2);
                    nx += w[k] * w[k];
                    nz += zn * zn;
                    nu += u2[k] * u2[k];
                }
            }
            let state = Progress {
                iteration: it,
                primal_residual: rp.sqrt(),
                dual_residual: mu * rd.sqrt(),
                primal_threshold: settings.tolerance * nx.sqrt().max(nz.sqrt()) + tiny,
                dual_threshold: settings.tolerance * mu * nu.sqrt() + tiny,
                penalty: mu,
            };
            report.iterations = it;
            report.last = Some(state);
            if !progress(&state) {
                return Err(LbcError::Cancelled);
            }
            if state.primal_residual <= state.primal_threshold
                && state.dual_residual <= state.dual_threshold
            {
                report.converged = true;
                break;
            }
            if settings.adaptive_penalty && it % 25 == 0 {
                let rel_p = state.primal_residual / state.primal_threshold;
                let rel_d = state.dual_residual / state.dual_threshold;
                let factor = if rel_p > 10.0 * rel_d {
                    2.0
                } else if rel_d > 10.0 * rel_p {
                    0.5
                } else {
                    1.0
                };
                if factor != 1.0 {
                    mu *= factor;
                    u1.par_iter_mut().for_each(|u| *u /= factor);
                    u2.par_iter_mut().for_each(|u| *u /= factor);
                }
            }
        }
        Ok(w)
    }

    /// Projects every unknown row onto `{w ≥ 0, Σ w_i c_i = x, Σ w_i = 1}`, first
    /// within the face where ADMM's clamped `W` is zero (so its zeros stay exact
    /// zeros), and over the whole set if that face has no solution.
    fn project(&self, z: &mut [f64], clamped: Option<&[f64]>) {
        let n = self.n;
        let rows: Vec<(usize, Vec<f64>)> = self
            .interior
            .par_iter()
            .enumerate()
            .map(|(j, &v)| {
                let v = v as usize;
                let b = self.q[v].extend(1.0);
                let z0 = &z[v * n..(v + 1) * n];
                if let Some(w) = clamped {
                    let support: Vec<bool> =
                        w[j * n..(j + 1) * n].iter().map(|&x| x > 0.0).collect();
                    if let Ok(row) = project_row(z0, &self.k, b, Some(&support)) {
                        return (v, row);
                    }
                }
                match project_row(z0, &self.k, b, None) {
                    Ok(row) | Err(Some(row)) => (v, row),
                    Err(None) => (v, z0.to_vec()),
                }
            })
            .collect();
        for (v, row) in rows {
            z[v * n..(v + 1) * n].copy_from_slice(&row);
        }
    }

    /// Eq. (14) of `z`, in the caller's units.
    fn objective(&self, z: &[f64]) -> f64 {
        let n = self.n;
        let total: f64 = (0..self.triangles.len())
            .into_par_iter()
            .map(|s| {
                let t = self.triangles[s];
                let g = &self.elements.grad[s];
                (0..n)
                    .map(|i| {
                        let grad: DVec2 = (0..3).map(|k| g[k] * z[t[k] as usize * n + i]).sum();
                        self.phi[s * n + i] * self.elements.area[s] * grad.length()
                    })
                    .sum::<f64>()
            })
            .sum();
        total * self.scale
    }
}

/// What the Y-update pulls towards: `x + u1` per triangle and `w + u2` per unknown row
/// (no multipliers: `x` and `w` alone).
#[derive(Clone, Copy)]
struct Targets<'a> {
    x: &'a [DVec2],
    u1: Option<&'a [DVec2]>,
    w: &'a [f64],
    u2: Option<&'a [f64]>,
}

/// The Euclidean projection of `w0` onto `{w ≥ 0, Kᵀw = b}`: `w = max(0, w0 + Kν)`
/// with `ν` minimising the (convex, piecewise quadratic) dual
/// `½‖max(0, w0 + Kν)‖² − b·ν`, by Newton's method with backtracking. Partition of
/// unity is then made exact by dividing by the sum (a change of the order of
/// rounding).
///
/// With `support`, entries outside it are held at zero; the result is `None` (or,
/// without `support`, `Err` with the best row found) when the constraints cannot be
/// met to `10⁻¹²`.
pub(crate) fn project_row(
    w0: &[f64],
    k: &[DVec3],
    b: DVec3,
    support: Option<&[bool]>,
) -> ProjectResult {
    let free = |i: usize| support.is_none_or(|s| s[i]);
    let eval = |nu: DVec3| -> (f64, DVec3, DMat3) {
        let mut q = -b.dot(nu);
        let mut grad = -b;
        let mut hess = DMat3::from_diagonal(DVec3::splat(1e-12));
        for (i, (w, ki)) in w0.iter().zip(k).enumerate() {
            if !free(i) {
                continue;
            }
            let v = w + ki.dot(nu);
            if v > 0.0 {
                q += 0.5 * v * v;
                grad += v * *ki;
                hess += DMat3::from_cols(*ki * ki.x, *ki * ki.y, *ki * ki.z);
            }
        }
        (q, grad, hess)
    };
    let mut nu = DVec3::ZERO;
    let (mut q, mut grad, mut hess) = eval(nu);
    for _ in 0..200 {
        if grad.length() <= 1e-15 {
            break;
        }
        let step = -(hess.inverse() * grad);
        let slope = grad.dot(step);
        let mut t = 1.0;
        let mut moved = false;
        while t > 1e-12 {
            let candidate = nu + t * step;
            let (qc, gc, hc) = eval(candidate);
            if qc <= q + 1e-4 * t * slope {
                nu = candidate;
                (q, grad, hess) = (qc, gc, hc);
                moved = true;
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    let mut w: Vec<f64> = w0
        .iter()
        .zip(k)
        .enumerate()
        .map(|(i, (w, ki))| {
            if free(i) {
                (w + ki.dot(nu)).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    // Polish: on the support found, the projection is the equality-constrained one,
    // in closed form. It meets the constraints to rounding even where Newton's line
    // search stalled short of its tolerance (a kink of the piecewise-quadratic dual).
    let polished = polish(w0, k, b, &w);
    let polished_ok = polished.is_some();
    if let Some(p) = polished {
        w = p;
    }
    let sum: f64 = w.iter().sum();
    if sum > 0.0 && !polished_ok {
        w.iter_mut().for_each(|x| *x /= sum);
    }
    let met = (polished_ok || grad.length() <= 1e-12) && sum > 0.0;
    match (met, support) {
        (true, _) => Ok(w),
        (false, Some(_)) => Err(None),
        (false, None) => Err(Some(w)),
    }
}

/// The projection of `w0` onto `{w : Σ w_i k_i = b}` with `w_i = 0` off a support
/// `S`, starting from the positive entries of `w`: `w0_S + K_S λ` with
/// `(K_Sᵀ K_S) λ = b − K_Sᵀ w0_S`. `None` if no support reached that way carries the
/// constraints with non-negative weights.
fn polish(w0: &[f64], k: &[DVec3], b: DVec3, w: &[f64]) -> Option<Vec<f64>> {
    let mut support: Vec<usize> = (0..w.len()).filter(|&i| w[i] > 0.0).collect();
    // An entry that comes out negative leaves the support, and the rest is solved
    // again (a few rounds of an active-set method, from Newton's nearly right guess).
    for _ in 0..w.len() {
        if support.len() < 3 {
            return None;
        }
        let mut gram = DMat3::ZERO;
        let mut residual = b;
        for &i in &support {
            let ki = k[i];
            gram += DMat3::from_cols(ki * ki.x, ki * ki.y, ki * ki.z);
            residual -= w0[i] * ki;
        }
        if gram.determinant().abs() < 1e-14 {
            return None;
        }
        let lambda = gram.inverse() * residual;
        let values: Vec<(usize, f64)> = support
            .iter()
            .map(|&i| (i, w0[i] + k[i].dot(lambda)))
            .collect();
        if values.iter().all(|&(_, v)| v >= 0.0) {
            let mut out = vec![0.0; w.len()];
            for (i, v) in values {
                out[i] = v;
            }
            return Some(out);
        }
        support = values
            .iter()
            .filter(|&&(_, v)| v > 0.0)
            .map(|&(i, _)| i)
            .collect();
    }
    None
}

/// A projected row, or (failing) the best row found without a support restriction.
pub(crate) type ProjectResult = Result<Vec<f64>, Option<Vec<f64>>>;
