//! The optimisation of the paper's §4 and Appendix B: weighted total variation under
//! the barycentric constraints, by over-relaxed ADMM.

use std::time::{Duration, Instant};

use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

use crate::compact::Coordinates;
use crate::domain::Domain;
use crate::error::LbcError;
use crate::fem::{Elements, Pattern, RowFactor};
use crate::geodesic::geodesics;
use crate::projection::project_row;
use crate::report::{Progress, Report};

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
    /// The residuals are measured every 5 iterations, so a solve stops on a multiple
    /// of 5 (or at the cap).
    pub max_iterations: usize,
    /// Over-relaxation `α` (the paper: 1.5–1.8).
    pub relaxation: f64,
    /// Penalty `μ` to start with (in the solver's frame: cage centred, farthest cage
    /// vertex at distance 1); `None` chooses `‖φ√A‖ / ‖G W₀‖`, the ratio of the
    /// weights to the gradients of the starting coordinates.
    pub initial_penalty: Option<f64>,
    /// Residual balancing (Boyd et al. 2011, §3.4.1): when the relative primal and
    /// dual residuals differ by more than a factor of 1.5, multiply `μ` by the square
    /// root of their ratio (at most 10×), first after 10 iterations, then waiting
    /// twice as long after each change. The Y-update matrix does not depend on `μ`,
    /// so this costs no refactorisation.
    pub adaptive_penalty: bool,
    /// Run the iterations' passes compiled for AVX2 where the CPU has it (the same
    /// numbers, about twice as fast on a large mesh); `false` runs them as compiled
    /// for the baseline x86-64.
    pub wide_vectors: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            tau: Tau::Square,
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: 20_000,
            relaxation: 1.65,
            initial_penalty: None,
            adaptive_penalty: true,
            wide_vectors: true,
        }
    }
}

/// The default relative stopping threshold (see the crate docs for why).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;

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
    in_local_order(domain, |domain, _| {
        let start = Instant::now();
        let mut problem = Problem::new(domain);
        // The ADMM's factorisation needs the geodesics' elimination order alone: it
        // runs beside their own two factorisations.
        let (distances, factor) = geodesics(domain, |order| {
            problem.needs_admm().then(|| {
                let t = Instant::now();
                problem.factorise(Some(order)).map(|f| (f, t.elapsed()))
            })
        })?;
        let time = start.elapsed();
        problem.weigh(&distances, settings.tau);
        let mut c = solve_problem(domain, problem, factor.transpose()?, settings, progress)?;
        c.report.geodesics = time;
        Ok(c)
    })
}

/// Like [`solve`], with the normalised distances `D_i` given (`distances[i][v]`, as
/// [`geodesic_distances`](crate::geodesic_distances) returns them).
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
    in_local_order(domain, |domain, old_of| match old_of {
        Some(old_of) => {
            let distances: Vec<Vec<f64>> = distances
                .iter()
                .map(|d| old_of.iter().map(|&old| d[old as usize]).collect())
                .collect();
            solve_ordered(domain, &distances, settings, progress)
        }
        None => solve_ordered(domain, distances, settings, progress),
    })
}

/// Runs `solve` on `domain` numbered for locality and returns its rows in the
/// caller's numbering. The passes read each triangle's corners' rows and each row's
/// triangles, which a mesh given as a file may number far apart; `solve` gets the mesh
/// it is to solve and, where that is a renumbered copy, the old number of each of its
/// vertices.
fn in_local_order(
    domain: &Domain,
    solve: impl FnOnce(&Domain, Option<&[u32]>) -> Result<Coordinates, LbcError>,
) -> Result<Coordinates, LbcError> {
    match domain.spatially_ordered() {
        Some((ordered, old_of)) => Ok(solve(&ordered, Some(&old_of))?.renumbered(&old_of)),
        None => solve(domain, None),
    }
}

/// [`solve_with_distances`] on a mesh numbered for locality.
fn solve_ordered(
    domain: &Domain,
    distances: &[Vec<f64>],
    settings: &Settings,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<Coordinates, LbcError> {
    let mut problem = Problem::new(domain);
    problem.weigh(distances, settings.tau);
    solve_problem(domain, problem, None, settings, progress)
}

/// The ADMM on `problem` (weighted) and the projection of its rows; `factor` its
/// Y-update's factorisation and the time it took, where done already (see
/// [`Problem::factorise`]).
fn solve_problem(
    domain: &Domain,
    problem: Problem,
    factor: Option<(RowFactor, Duration)>,
    settings: &Settings,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<Coordinates, LbcError> {
    let n = domain.cage().len();
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
        threads: 1,
    };
    let mut clamped = None;
    if problem.needs_admm() {
        let (factor, time) = match factor {
            Some(done) => done,
            None => {
                let t = Instant::now();
                (problem.factorise(None)?, t.elapsed())
            }
        };
        report.factorisation = time;
        let t = Instant::now();
        clamped = Some(problem.admm(&factor, &mut z, settings, progress, &mut report)?);
        report.admm = t.elapsed();
    }
    let t = Instant::now();
    let mut z = problem.unpadded(&z);
    let clamped = clamped.map(|c| problem.unpadded(&c));
    problem.project(&mut z, clamped.as_deref());
    report.projection = t.elapsed();
    report.objective = problem.objective(&z);
    let mut k = problem.k;
    k.truncate(n);
    Ok(Coordinates::new(n, z, report, k, problem.q))
}

/// Everything fixed during the iterations, in the solver's frame.
struct Problem {
    /// Columns of the iterations' rows: the cage vertices, and zero columns up to
    /// a multiple of four (see [`padded`]).
    n: usize,
    /// Cage vertices.
    cage_vertices: usize,
    triangles: Vec<[u32; 3]>,
    /// Mesh vertex of each unknown row.
    interior: Vec<u32>,
    /// Unknown row of each mesh vertex.
    row_of: Vec<Option<u32>>,
    /// `√A_s·∇λ_k`: `G` of the paper with the gradient integrated over `√A_s`.
    g: Vec<[DVec2; 3]>,
    /// `φ_i^s·√A_s`, triangle-major.
    coef: Vec<Stored>,
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
    /// `Gᵀ E` per unknown row and cage vertex, with `E` of eq. (17) (`G` applied to
    /// the boundary values alone): the constant part of the Y-update's right-hand
    /// side. Only the rows next to the boundary have any: unknown row `j`'s are
    /// `gte[gte_at[j] * n..]`, where `gte_at[j]` is not [`u32::MAX`].
    gte: Vec<f64>,
    gte_at: Vec<u32>,
    /// Per unknown row, its `(triangle, corner)` incidences (CSR).
    adj_ptr: Vec<u32>,
    adj: Vec<(u32, u8)>,
    /// Per unknown row, the weight `β·m_v` of its `W = W̃` split in the augmented
    /// Lagrangian (`m_v` the lumped mass), and its square root.
    split: Vec<f64>,
    root: Vec<f64>,
    /// The columns of `K` (`x`, `y`, 1), for `H`'s rows (the least-norm solution of
    /// `WK = B`), computed where they are used rather than streamed from memory.
    k_columns: [Vec<f64>; 3],
}

impl Problem {
    /// The problem on `domain`, its weights `φ` yet to be given ([`Problem::weigh`]).
    fn new(domain: &Domain) -> Self {
        let cage = domain.cage().vertices();
        let cage_vertices = cage.len();
        let n = padded(cage_vertices);
        // The frame: cage centroid at the origin, farthest cage vertex at 1.
        let centre = cage.iter().copied().sum::<DVec2>() / cage_vertices as f64;
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
        let mut interior = Vec::new();
        let mut row_of = vec![None; q.len()];
        for (v, on) in domain.on_cage().iter().enumerate() {
            if on.is_none() {
                row_of[v] = Some(interior.len() as u32);
                interior.push(v as u32);
            }
        }
        let mut k: Vec<DVec3> = cage
            .iter()
            .map(|c| ((*c - centre) / scale).extend(1.0))
            .collect();
        k.resize(n, DVec3::ZERO);
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
        let mass = elements.lumped_mass(&triangles, q.len());
        let split: Vec<f64> = interior
            .iter()
            .map(|&v| SPLIT_WEIGHT * mass[v as usize])
            .collect();
        let root = split.iter().map(|m: &f64| m.sqrt()).collect();
        let k_columns = [0, 1, 2].map(|c| k.iter().map(|k| k[c]).collect());
        let mut problem = Self {
            cage_vertices,
            split,
            root,
            n,
            triangles,
            interior,
            row_of,
            g,
            coef: Vec::new(),
            elements,
            phi: Vec::new(),
            k,
            ktk_inv,
            q,
            scale,
            gte: Vec::new(),
            gte_at: Vec::new(),
            k_columns,
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
        let mut gte = vec![0.0; problem.interior.len() * n];
        gte.par_chunks_mut(n).enumerate().for_each(|(j, out)| {
            for &(s, c) in problem.incidences(j) {
                let g = problem.g[s as usize][c as usize];
                for (o, e) in out.iter_mut().zip(&e[s as usize * n..(s as usize + 1) * n]) {
                    *o += g.dot(*e);
                }
            }
        });
        problem.gte_at = vec![u32::MAX; problem.interior.len()];
        for (j, row) in gte.chunks_exact(n).enumerate() {
            if row.iter().any(|&x| x != 0.0) {
                problem.gte_at[j] = (problem.gte.len() / n) as u32;
                problem.gte.extend_from_slice(row);
            }
        }
        problem
    }

    /// Sets the weights `φ_i^s = τ(D_i)` of eq. (11), `D_i` the normalised distance
    /// from cage vertex `i` averaged over each triangle's corners.
    fn weigh(&mut self, distances: &[Vec<f64>], tau: Tau) {
        let n = self.n;
        let mut phi = vec![0.0; self.triangles.len() * n];
        for (s, t) in self.triangles.iter().enumerate() {
            for i in 0..self.cage_vertices {
                let d = t.iter().map(|&v| distances[i][v as usize]).sum::<f64>() / 3.0;
                phi[s * n + i] = tau.apply(d);
            }
        }
        self.coef = phi
            .iter()
            .enumerate()
            .map(|(si, &p)| (p * self.elements.area[si / n].sqrt()) as Stored)
            .collect();
        self.phi = phi;
    }

    /// Whether the coordinates are left to the ADMM: rows inside, and more cage
    /// vertices than a triangle's (whose barycentric coordinates are the answer).
    fn needs_admm(&self) -> bool {
        !self.interior.is_empty() && self.cage_vertices > 3
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

    /// Factorises `GᵀG + βM` on the unknown rows. `order`, an elimination order of
    /// the mesh's vertices (the geodesics'), is followed on the unknown ones where
    /// given; a minimum-degree ordering is computed otherwise.
    fn factorise(&self, order: Option<&[u32]>) -> Result<RowFactor, LbcError> {
        let mut split = vec![0.0; self.q.len()];
        for (j, &v) in self.interior.iter().enumerate() {
            split[v as usize] = self.split[j];
        }
        let row_of = &self.row_of;
        let map = |v: u32| row_of[v as usize].map(|r| r as usize);
        let lower = self.elements.lower(&self.triangles, &map, &split);
        let order: Option<Vec<u32>> =
            order.map(|order| order.iter().filter_map(|&v| row_of[v as usize]).collect());
        let pattern = Pattern::new(self.interior.len(), &lower, order.as_deref())?;
        RowFactor::new(&pattern, &lower.values(1.0, 1.0))
    }

    /// Unknown row `j`'s `(triangle, corner)` incidences.
    fn incidences(&self, j: usize) -> &[(u32, u8)] {
        &self.adj[self.adj_ptr[j] as usize..self.adj_ptr[j + 1] as usize]
    }

    /// Length of the triangle part of a state vector (see [`Problem::admm`]).
    fn triangle_part(&self) -> usize {
        2 * self.triangles.len() * self.n
    }

    /// Unknown row `j` of `Gᵀ t₁`, for the triangle part `t1` of a state vector: a
    /// gather over the row's incident triangles (which sit near each other, the
    /// triangles being numbered by their first vertex along a Z-order curve). Adding
    /// each triangle's terms into per-thread copies of all rows instead cost 10%
    /// more an iteration at 20k vertices, in filling and summing the copies.
    #[inline(always)]
    fn gather_row(&self, t1: &[Stored], j: usize, acc: &mut [f64]) {
        let n = self.n;
        acc.fill(0.0);
        for &(s, c) in self.incidences(j) {
            let g = self.g[s as usize][c as usize];
            let (tx, ty) = t1[2 * s as usize * n..(2 * s as usize + 2) * n].split_at(n);
            for ((a, &x), &y) in acc.iter_mut().zip(tx).zip(ty) {
                *a += g.x * f64::from(x) + g.y * f64::from(y);
            }
        }
    }

    crate::wide::twice! {
    /// The Y-update towards the targets in the state vector `t`: the unknown rows
    /// of `z` become `YM + H` with
    /// `Y = (GᵀG + βM)⁻¹ [Gᵀ(t₁ − E) + βM t₂] Mᵀ`, `Gᵀt₁` gathered row by row
    /// ([`Problem::gather_row`]).
    ///
    /// `(GᵀG + βM)⁻¹` acts on rows (mesh vertices) and `MᵀM` on columns (cage
    /// vertices), so they commute: `Y M = (GᵀG + βM)⁻¹ (R MᵀM)`, and `MᵀM` is the
    /// projector onto the null space of `Kᵀ`, `I − K(KᵀK)⁻¹Kᵀ`. Projecting each row of
    /// `R` (3 dot products) costs far less than multiplying by `Mᵀ` and then by `M`
    /// (n − 3 each), for three more right-hand side columns in the solve.
    ///
    /// With `measure`, returns `‖G ΔZ‖² + β‖ΔZ‖²_M` for the change `ΔZ` of the unknown
    /// rows since the last call, the dual residual's square over `μ²`: with
    /// `L = GᵀG + βM` and `L Y = R`, it is `ΔY · ΔR`, a sum over the unknown rows
    /// rather than a pass over every triangle (zero when the last call did not
    /// `keep` its `R` and `Y`; `keep` them where the next call measures).
    fn y_update / y_update_plain / y_update_avx2 (
        &self,
        wide: bool,
        factor: &RowFactor,
        t: &[Stored],
        b: &mut YBuffers,
        z: &mut [f64],
        measure: bool,
        keep: bool,
    ) -> f64 {
        let n = self.n;
        let (t1, t2) = t.split_at(self.triangle_part());
        // `R − R_prev` goes into `b.r` where this call measures, `R` into
        // `b.r_previous` where it keeps.
        let measuring = measure && b.has_previous;
        b.rhs
            .par_chunks_mut(n * PER_TASK)
            .zip(b.r.par_chunks_mut(n * PER_TASK))
            .zip(b.r_previous.par_chunks_mut(n * PER_TASK))
            .enumerate()
            .for_each(|(task, ((rows, change), kept))| {
                for (k, acc) in rows.chunks_exact_mut(n).enumerate() {
                    let j = task * PER_TASK + k;
                    let root = self.root[j];
                    let row = j * n..(j + 1) * n;
                    // `Gᵀt₁` first, then the rest around it.
                    self.gather_row(t1, j, acc);
                    let rows = acc.iter_mut().zip(&t2[row]);
                    match self.gte_at[j] {
                        u32::MAX => {
                            for (a, &t) in rows {
                                *a += root * f64::from(t);
                            }
                        }
                        at => {
                            let e = &self.gte[at as usize * n..(at as usize + 1) * n];
                            for ((a, &t), e) in rows.zip(e) {
                                *a += root * f64::from(t) - e;
                            }
                        }
                    }
                    let kt: DVec3 = acc.iter().zip(&self.k).map(|(a, k)| *a * *k).sum();
                    let coef = self.ktk_inv * kt;
                    for (a, k) in acc.iter_mut().zip(&self.k) {
                        *a -= k.dot(coef);
                    }
                    let row = k * n..(k + 1) * n;
                    if measuring {
                        let was = &kept[row.clone()];
                        for ((c, p), a) in change[row.clone()].iter_mut().zip(was).zip(&*acc) {
                            *c = a - p;
                        }
                    }
                    if keep {
                        kept[row].copy_from_slice(acc);
                    }
                }
            });
        factor.solve_rows(wide, &mut b.rhs, n, &mut b.scratch);
        let y = &b.rhs;
        z.par_chunks_mut(n * PER_TASK)
            .enumerate()
            .for_each(|(task, rows)| {
                let [kx, ky, kz] = &self.k_columns;
                for (k, w) in rows.chunks_exact_mut(n).enumerate() {
                    let v = task * PER_TASK + k;
                    if let Some(j) = self.row_of[v] {
                        let row = j as usize * n..(j as usize + 1) * n;
                        // `H`'s row, as `least_norm` makes it.
                        let a = self.ktk_inv * self.q[v].extend(1.0);
                        for ((((w, y), kx), ky), kz) in
                            w.iter_mut().zip(&y[row]).zip(kx).zip(ky).zip(kz)
                        {
                            *w = ((kx * a.x) + (ky * a.y) + (kz * a.z)) + y;
                        }
                    }
                }
            });
        let dual = if measuring {
            b.rhs
                .par_chunks(CHUNK)
                .zip(b.y_previous.par_chunks(CHUNK))
                .zip(b.r.par_chunks(CHUNK))
                .map(|((y, yp), change)| {
                    // In four lanes, so that the loop vectorises.
                    let mut lanes = [0.0; 4];
                    let quads = y
                        .chunks_exact(4)
                        .zip(yp.chunks_exact(4))
                        .zip(change.chunks_exact(4));
                    for ((y, yp), c) in quads {
                        for l in 0..4 {
                            lanes[l] += (y[l] - yp[l]) * c[l];
                        }
                    }
                    let whole = y.len() - y.len() % 4;
                    let rest: f64 = (whole..y.len()).map(|k| (y[k] - yp[k]) * change[k]).sum();
                    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + rest
                })
                .collect::<Vec<f64>>()
                .iter()
                .sum()
        } else {
            0.0
        };
        if keep {
            std::mem::swap(&mut b.rhs, &mut b.y_previous);
        }
        b.has_previous = keep;
        dual
    }
    }

    crate::wide::twice! {
    /// One ADMM iteration as a map of its state, in place: the Y-update from `t`
    /// (into `z`), then the multipliers `u = t − (Gz, z)`, the X-update by group
    /// soft-thresholding (eq. 30) and the W-update by clamping (eq. 31), both
    /// over-relaxed, and the next state `x̃ + u` into `t`. Only when `measure`, the
    /// clamped `W` goes into `clamped` and the residuals are summed (their terms
    /// stored per triangle or row and summed by [`Residuals::of_terms`]); the Y-update
    /// keeps what the dual residual needs only when `keep` (the next iteration
    /// measures).
    fn iterate / iterate_plain / iterate_avx2 (
        &self,
        wide: bool,
        factor: &RowFactor,
        t: &mut [Stored],
        z: &mut [f64],
        clamped: &mut [f64],
        penalty: f64,
        alpha: f64,
        b: &mut YBuffers,
        measure: bool,
        keep: bool,
    ) -> Residuals {
        let n = self.n;
        let dual = self.y_update(wide, factor, t, b, z, measure, keep);
        let z = &*z;
        let (t1, t2) = t.split_at_mut(self.triangle_part());
        let inverse_penalty = 1.0 / penalty;
        // Each task's sums, then the tasks' in order (here and below): rayon's own
        // reduction groups them as the threads happen to split the work, which moves
        // the last bits, and so the stop, from run to run.
        let gradients = t1
            .par_chunks_mut(2 * n * PER_TASK)
            .enumerate()
            .map(|(task, triangles)| {
                let mut r = Residuals::default();
                let mut terms = if measure { vec![0.0; 4 * n] } else { Vec::new() };
                for (k, ts) in triangles.chunks_exact_mut(2 * n).enumerate() {
                    let s = task * PER_TASK + k;
                    if measure {
                        self.shrink_triangle::<true>(s, z, ts, inverse_penalty, alpha, &mut terms);
                        r = r.add(Residuals::of_terms(&terms, n));
                    } else {
                        self.shrink_triangle::<false>(s, z, ts, inverse_penalty, alpha, &mut terms);
                    }
                }
                r
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Residuals::default(), Residuals::add);
        // The W-update row by row.
        let values = t2
            .par_chunks_mut(n * PER_TASK)
            .zip(clamped.par_chunks_mut(n * PER_TASK))
            .enumerate()
            .map(|(task, (t2, clamped))| {
                let mut sum = Residuals::default();
                let mut terms = if measure { vec![0.0; 4 * n] } else { Vec::new() };
                let rows = t2.chunks_exact_mut(n).zip(clamped.chunks_exact_mut(n));
                for (k, (tj, wj)) in rows.enumerate() {
                    let j = task * PER_TASK + k;
                    let v = self.interior[j] as usize;
                    let zj = &z[v * n..(v + 1) * n];
                    let (root, m) = (self.root[j], self.split[j]);
                    let clamp = |t: Stored, z: f64| {
                        let u = f64::from(t) / root - z;
                        let w = (z - u).max(0.0);
                        (w, (root * (alpha * w + (1.0 - alpha) * z + u)) as Stored, u)
                    };
                    if measure {
                        let (e0, e) = terms.split_at_mut(n);
                        let (e1, e) = e.split_at_mut(n);
                        let (e2, e3) = e.split_at_mut(n);
                        for i in 0..n {
                            let (w, next, u) = clamp(tj[i], zj[i]);
                            (wj[i], tj[i]) = (w, next);
                            (e0[i], e1[i], e2[i], e3[i]) =
                                ((w - zj[i]).powi(2), w * w, zj[i] * zj[i], u * u);
                        }
                        sum = sum.add(Residuals::of_terms(&terms, n).scaled(m));
                    } else {
                        // Nor the clamped `W`, which only the last iteration's is
                        // used, and the last measures.
                        for (t, &z) in tj.iter_mut().zip(zj) {
                            (_, *t, _) = clamp(*t, z);
                        }
                    }
                }
                sum
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Residuals::default(), Residuals::add);
        let mut r = gradients.add(values);
        r.dual = dual;
        r
    }
    }

    /// The X-update of [`Problem::iterate`] on triangle `s`: the gradients `p = Gz`
    /// from its corners' rows, `u = t − p` from its part `ts` of the state, group
    /// soft-thresholding of `p − u` by `φ√A/μ`, over-relaxation, and its part of the
    /// next state `x̃ + u` into `ts`; the residual terms go into `r`.
    #[inline(always)]
    fn shrink_triangle<const MEASURE: bool>(
        &self,
        s: usize,
        z: &[f64],
        ts: &mut [Stored],
        inverse_penalty: f64,
        alpha: f64,
        terms: &mut [f64],
    ) {
        let n = self.n;
        let [a, b, c] = self.triangles[s].map(|v| v as usize * n);
        let (za, zb, zc) = (&z[a..a + n], &z[b..b + n], &z[c..c + n]);
        let [ga, gb, gc] = self.g[s];
        let coef = &self.coef[s * n..(s + 1) * n];
        let (tx, ty) = ts[..2 * n].split_at_mut(n);
        let step = |i: usize, t: DVec2| {
            let p = DVec2::new(
                ga.x * za[i] + gb.x * zb[i] + gc.x * zc[i],
                ga.y * za[i] + gb.y * zb[i] + gc.y * zc[i],
            );
            shrink(p, t, f64::from(coef[i]) * inverse_penalty, alpha)
        };
        if MEASURE {
            let (e0, e) = terms[..4 * n].split_at_mut(n);
            let (e1, e) = e.split_at_mut(n);
            let (e2, e3) = e.split_at_mut(n);
            for i in 0..n {
                let (next, x, p, u) = step(i, DVec2::new(tx[i].into(), ty[i].into()));
                (tx[i], ty[i]) = (next.x as Stored, next.y as Stored);
                (e0[i], e1[i], e2[i], e3[i]) = (
                    (x - p).length_squared(),
                    x.length_squared(),
                    p.length_squared(),
                    u.length_squared(),
                );
            }
        } else {
            for i in 0..n {
                let (next, ..) = step(i, DVec2::new(tx[i].into(), ty[i].into()));
                (tx[i], ty[i]) = (next.x as Stored, next.y as Stored);
            }
        }
    }

    /// The state `next` = `x̃ + u` that [`Problem::iterate`] made from `t` when the
    /// penalty is multiplied by `factor` (the scaled multipliers `u = λ/μ` divide by
    /// it): `next − u (1 − 1/factor)`, with `u = t − (Gz, z)` recomputed from the
    /// iteration's input `t` and its `z`.
    fn rescale(&self, t: &[Stored], z: &[f64], next: &mut [Stored], factor: f64) {
        let n = self.n;
        let keep = 1.0 - 1.0 / factor;
        let (t1, t2) = t.split_at(self.triangle_part());
        let (next1, next2) = next.split_at_mut(self.triangle_part());
        next1
            .par_chunks_mut(2 * n)
            .zip(t1.par_chunks(2 * n))
            .enumerate()
            .for_each(|(s, (out, ts))| {
                let t = self.triangles[s].map(|v| v as usize * n);
                let g = &self.g[s];
                for i in 0..n {
                    let p = g[0] * z[t[0] + i] + g[1] * z[t[1] + i] + g[2] * z[t[2] + i];
                    let shift = |o: Stored, t: Stored, p: f64| {
                        (f64::from(o) - keep * (f64::from(t) - p)) as Stored
                    };
                    out[i] = shift(out[i], ts[i], p.x);
                    out[n + i] = shift(out[n + i], ts[n + i], p.y);
                }
            });
        next2
            .par_chunks_mut(n)
            .zip(t2.par_chunks(n))
            .enumerate()
            .for_each(|(j, (out, tj))| {
                let v = self.interior[j] as usize;
                let root = self.root[j];
                for i in 0..n {
                    let u = f64::from(tj[i]) - root * z[v * n + i];
                    out[i] = (f64::from(out[i]) - keep * u) as Stored;
                }
            });
    }

    /// Appendix B's over-relaxed ADMM from the smoothest coordinates, with residual
    /// balancing of the penalty. On return `z` holds the last Y-update's rows; the
    /// result is the last clamped `W` (whose zeros the projection keeps).
    ///
    /// The iteration is written as a map of one state vector `t`, the Y-update's
    /// targets: per triangle `x̃ + u₁` (its `n` x components, then its `n` y
    /// components), then per unknown row `√(βm)·(w̃ + u₂)`. The Y-update gives `z`
    /// from `t`, the multipliers are `u = t − (Gz, z)`, and the next state follows
    /// ([`Problem::iterate`]).
    fn admm(
        &self,
        factor: &RowFactor,
        z: &mut [f64],
        settings: &Settings,
        progress: &mut dyn FnMut(&Progress) -> bool,
        report: &mut Report,
    ) -> Result<Vec<f64>, LbcError> {
        let n = self.n;
        let mi = self.interior.len();
        let len = self.triangle_part() + mi * n;
        let mut buffers = YBuffers {
            rhs: vec![0.0; mi * n],
            r: vec![0.0; mi * n],
            r_previous: vec![0.0; mi * n],
            y_previous: vec![0.0; mi * n],
            has_previous: false,
            scratch: Vec::new(),
        };
        // Start from the smoothest coordinates: the Y-update with every split
        // variable and multiplier zero (a regularised harmonic solve), and the state
        // whose multipliers are zero, `t = (Gz, √(βM) z)`, which the Y-update maps to
        // that same `z`.
        let measures =
            |it: usize| it.is_multiple_of(MEASURE_EVERY) || it == settings.max_iterations;
        let mut t: Vec<Stored> = vec![0.0; len];
        let wide = settings.wide_vectors && crate::wide::available();
        self.y_update(wide, factor, &t, &mut buffers, z, false, measures(1));
        let mut p = vec![DVec2::ZERO; self.triangles.len() * n];
        self.apply_g(z, &mut p);
        {
            let (t1, t2) = t.split_at_mut(self.triangle_part());
            for (ts, ps) in t1.chunks_exact_mut(2 * n).zip(p.chunks_exact(n)) {
                for (i, p) in ps.iter().enumerate() {
                    ts[i] = p.x as Stored;
                    ts[n + i] = p.y as Stored;
                }
            }
            for (j, &v) in self.interior.iter().enumerate() {
                let v = v as usize;
                for i in 0..n {
                    t2[j * n + i] = (self.root[j] * z[v * n + i]) as Stored;
                }
            }
        }
        // The penalty to start with: the multipliers of the gradient split are
        // bounded by the weights `φ√A` at the optimum and the split gradients are
        // near those of the start, so `μ = ‖φ√A‖ / ‖G W₀‖` balances the residuals'
        // first estimate.
        let mut mu = settings.initial_penalty.unwrap_or_else(|| {
            let gradients: f64 = p.iter().map(|p| p.length_squared()).sum();
            let weights: f64 = self.coef.iter().map(|&c| f64::from(c).powi(2)).sum();
            if gradients > 0.0 {
                (weights / gradients).sqrt()
            } else {
                1.0
            }
        });
        drop(p);
        // The state an iteration started from, kept where the penalty may change
        // after it (see `rescale`).
        let mut previous: Vec<Stored> = Vec::new();
        let mut clamped = vec![0.0; mi * n];
        let alpha = settings.relaxation;
        report.converged = false;
        let tiny = 1e-14 * (len as f64).sqrt();
        let (mut last_change, mut interval) = (0, PENALTY_INTERVAL);
        let mut state = None;
        let mut threads = ThreadChoice::new();
        for it in 1..=settings.max_iterations {
            let (measure, keep) = (measures(it), measures(it + 1));
            let may_rebalance =
                measure && settings.adaptive_penalty && it - last_change >= interval;
            if may_rebalance {
                previous.clear();
                previous.extend_from_slice(&t);
            }
            let clock = Instant::now();
            let mut iterate = || {
                self.iterate(
                    wide,
                    factor,
                    &mut t,
                    z,
                    &mut clamped,
                    mu,
                    alpha,
                    &mut buffers,
                    measure,
                    keep,
                )
            };
            // On a thread of the pool either way: called from outside one, each of
            // an iteration's passes would be handed to the pool and waited for.
            let r = match threads.single_for(it) {
                Some(pool) => pool.install(iterate),
                None => rayon::scope(|_| iterate()),
            };
            threads.took(it, clock.elapsed());
            report.iterations = it;
            report.threads = threads.count();
            if !measure {
                let mut shown = state.unwrap_or(Progress {
                    iteration: it,
                    primal_residual: f64::INFINITY,
                    dual_residual: f64::INFINITY,
                    primal_threshold: 0.0,
                    dual_threshold: 0.0,
                    penalty: mu,
                });
                shown.iteration = it;
                if !progress(&shown) {
                    return Err(LbcError::Cancelled);
                }
                continue;
            }
            let measured = Progress {
                iteration: it,
                primal_residual: r.primal.sqrt(),
                dual_residual: mu * r.dual.sqrt(),
                primal_threshold: settings.tolerance * r.split.max(r.unknown).sqrt() + tiny,
                dual_threshold: settings.tolerance * mu * r.multiplier.sqrt() + tiny,
                penalty: mu,
            };
            state = Some(measured);
            let state = measured;
            report.last = Some(state);
            if !progress(&state) {
                return Err(LbcError::Cancelled);
            }
            // The first iteration's Y-update returns the start itself (zero dual
            // residual): it cannot stop there.
            if it > 1
                && state.primal_residual <= state.primal_threshold
                && state.dual_residual <= state.dual_threshold
            {
                report.converged = true;
                break;
            }
            let ratio = (state.primal_residual / state.primal_threshold)
                / (state.dual_residual / state.dual_threshold);
            if may_rebalance && !(1.0 / PENALTY_BAND..=PENALTY_BAND).contains(&ratio) {
                // Residual balancing: the penalty moves towards equal relative
                // residuals, by at most a factor of ten, and less and less often.
                let factor = ratio.sqrt().clamp(0.1, 10.0);
                mu *= factor;
                self.rescale(&previous, z, &mut t, factor);
                last_change = it;
                interval *= 2;
            }
        }
        Ok(clamped)
    }

    /// Rows of `n` columns (the iterations') cut to a column per cage vertex.
    fn unpadded(&self, rows: &[f64]) -> Vec<f64> {
        if self.n == self.cage_vertices {
            return rows.to_vec();
        }
        rows.chunks_exact(self.n)
            .flat_map(|row| &row[..self.cage_vertices])
            .copied()
            .collect()
    }

    /// Projects every unknown row onto `{w ≥ 0, Σ w_i c_i = x, Σ w_i = 1}`, first
    /// within the face where ADMM's clamped `W` is zero (so its zeros stay exact
    /// zeros), and over the whole set if that face has no solution.
    /// `z` and `clamped` have a column per cage vertex (see [`Problem::unpadded`]).
    fn project(&self, z: &mut [f64], clamped: Option<&[f64]>) {
        let n = self.cage_vertices;
        let k = &self.k[..n];
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
                    if let Ok(row) = project_row(z0, k, b, Some(&support)) {
                        return (v, row);
                    }
                }
                match project_row(z0, k, b, None) {
                    Ok(row) | Err(Some(row)) => (v, row),
                    Err(None) => (v, z0.to_vec()),
                }
            })
            .collect();
        for (v, row) in rows {
            z[v * n..(v + 1) * n].copy_from_slice(&row);
        }
    }

    /// Eq. (14) of `z` (a column per cage vertex), in the caller's units.
    fn objective(&self, z: &[f64]) -> f64 {
        let (n, padded) = (self.cage_vertices, self.n);
        let total: f64 = (0..self.triangles.len())
            .into_par_iter()
            .map(|s| {
                let t = self.triangles[s];
                let g = &self.elements.grad[s];
                (0..n)
                    .map(|i| {
                        let grad: DVec2 = (0..3).map(|k| g[k] * z[t[k] as usize * n + i]).sum();
                        self.phi[s * padded + i] * self.elements.area[s] * grad.length()
                    })
                    .sum::<f64>()
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        total * self.scale
    }
}

/// The Y-update's right-hand side and solution, and the last ones, for the dual
/// residual.
struct YBuffers {
    /// `R`, solved in place into `Y`.
    rhs: Vec<f64>,
    /// `R − R_prev`, where the dual residual is measured…
    r: Vec<f64>,
    /// …from the `R` kept by the call before.
    r_previous: Vec<f64>,
    y_previous: Vec<f64>,
    has_previous: bool,
    /// The factor's working rows.
    scratch: Vec<Vec<f64>>,
}

/// Whether the iterations run on all of rayon's threads or on one, whichever a few
/// timed iterations each way find faster (see the crate docs for why one can win).
/// The iterates are the same either way; only the order of the residuals' sums may
/// differ.
struct ThreadChoice {
    /// A pool of one thread, when rayon has more.
    single: Option<rayon::ThreadPool>,
    /// Time of the trial iterations on all threads and on one.
    all: Duration,
    one: Duration,
    /// The choice, once the trials are done.
    chosen_single: Option<bool>,
}

/// Iterations timed on all threads, then on one (each five long, with one that
/// measures the residuals, so that both do the same work).
const TRIAL_ALL: std::ops::RangeInclusive<usize> = 6..=10;
const TRIAL_ONE: std::ops::RangeInclusive<usize> = 11..=15;

impl ThreadChoice {
    fn new() -> Self {
        let single = (rayon::current_num_threads() > 1)
            .then(|| rayon::ThreadPoolBuilder::new().num_threads(1).build().ok())
            .flatten();
        Self {
            single,
            all: Duration::ZERO,
            one: Duration::ZERO,
            chosen_single: None,
        }
    }

    /// The one-thread pool if iteration `it` runs on it.
    fn single_for(&self, it: usize) -> Option<&rayon::ThreadPool> {
        let on_one = self
            .chosen_single
            .unwrap_or_else(|| TRIAL_ONE.contains(&it));
        self.single.as_ref().filter(|_| on_one)
    }

    /// Iteration `it` took `time`.
    fn took(&mut self, it: usize, time: Duration) {
        if self.single.is_none() || self.chosen_single.is_some() {
            return;
        }
        if TRIAL_ALL.contains(&it) {
            self.all += time;
        } else if TRIAL_ONE.contains(&it) {
            self.one += time;
            if it == *TRIAL_ONE.end() {
                self.chosen_single = Some(self.one < self.all);
            }
        }
    }

    /// Threads the iterations run on now.
    fn count(&self) -> usize {
        match self.chosen_single {
            Some(true) => 1,
            _ if self.single.is_none() => 1,
            _ => rayon::current_num_threads(),
        }
    }
}

/// The columns the iterations' rows have for `n` cage vertices: a multiple of four
/// from 8 on, so that every loop over a row runs in whole vectors of four (the extra
/// columns have no cage vertex: zero weights `φ`, zero rows of `K`, and their values
/// stay zero throughout). An entry costs 9% less with 28 columns than with 27.
fn padded(n: usize) -> usize {
    if n >= 8 { n.next_multiple_of(4) } else { n }
}

/// How the iterations keep their state and the weights `φ√A`, which they stream
/// through once an iteration: single precision halves that traffic, the largest part
/// of an iteration on a large mesh, and every sum and update is done in double
/// precision. (Rounding the state to 6·10⁻⁸ relative is far below the relative stop
/// at 10⁻³; the coordinates themselves are solved in double precision.)
type Stored = f32;

/// Rows (or triangles) one task of a pass takes: each task is one call of the
/// pass's closure, whose loop over them is then compiled as one (and, in the AVX2
/// copy, for AVX2, which a closure called per row could not be).
const PER_TASK: usize = 256;

/// Chunk length of the parallel sums over the unknown rows.
const CHUNK: usize = 1 << 14;

/// Squared norms one iteration adds up, for the residuals and their thresholds.
#[derive(Clone, Copy, Debug, Default)]
struct Residuals {
    /// `‖X − GZ‖² + ‖W − Z‖²_βM`.
    primal: f64,
    /// `‖G(Z − Z_prev)‖² + ‖Z − Z_prev‖²_βM`.
    dual: f64,
    /// `‖X‖² + ‖W‖²_βM`.
    split: f64,
    /// `‖GZ‖² + ‖Z‖²_βM`.
    unknown: f64,
    /// `‖u‖²`, scaled multipliers.
    multiplier: f64,
}

impl Residuals {
    /// The sums of `n` entries' primal, split, unknown and multiplier terms, given
    /// as four runs of `n` in `terms`. Adding each entry's terms as a loop computes
    /// them keeps that loop from being vectorised (floating-point sums are kept in
    /// order); the terms are stored instead and summed here in four lanes.
    #[inline(always)]
    fn of_terms(terms: &[f64], n: usize) -> Self {
        let sum = |run: &[f64]| {
            let mut lanes = [0.0; 4];
            let quads = run.chunks_exact(4);
            let rest: f64 = quads.remainder().iter().sum();
            for quad in quads {
                for (lane, x) in lanes.iter_mut().zip(quad) {
                    *lane += x;
                }
            }
            (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + rest
        };
        let mut runs = terms[..4 * n].chunks_exact(n.max(1)).map(sum);
        let mut next = || runs.next().unwrap_or(0.0);
        Self {
            primal: next(),
            split: next(),
            unknown: next(),
            multiplier: next(),
            dual: 0.0,
        }
    }

    fn scaled(self, m: f64) -> Self {
        Self {
            primal: m * self.primal,
            dual: m * self.dual,
            split: m * self.split,
            unknown: m * self.unknown,
            multiplier: m * self.multiplier,
        }
    }

    fn add(self, o: Self) -> Self {
        Self {
            primal: self.primal + o.primal,
            dual: self.dual + o.dual,
            split: self.split + o.split,
            unknown: self.unknown + o.unknown,
            multiplier: self.multiplier + o.multiplier,
        }
    }
}

/// One entry of the X-update: from the gradient `p` and the state `t`, the
/// multiplier `u = t − p`, `x` = `p − u` group soft-thresholded by `threshold`, and
/// the next state `αx + (1 − α)p + u`. Returns `(next, x, p, u)`.
#[inline(always)]
fn shrink(p: DVec2, t: DVec2, threshold: f64, alpha: f64) -> (DVec2, DVec2, DVec2, DVec2) {
    let u = t - p;
    let a = p - u;
    let keep = (1.0 - threshold / a.length().max(f64::MIN_POSITIVE)).max(0.0);
    let x = keep * a;
    (alpha * x + (1.0 - alpha) * p + u, x, p, u)
}

/// `β`: the `W = W̃` split enters the augmented Lagrangian as `β‖W − W̃‖²_M`, the
/// squared L² norm of the difference (lumped mass `M`), so that the Y-update matrix
/// `GᵀG + βM` discretises `−Δ + β` at any mesh resolution.
const SPLIT_WEIGHT: f64 = 1.0;

/// The residuals are measured (and the stopping test and residual balancing run)
/// every this many iterations.
const MEASURE_EVERY: usize = 5;

/// Residual balancing waits this many iterations before its first change of the
/// penalty, and twice as long after each change (changes that never stop can keep
/// ADMM from converging)…
const PENALTY_INTERVAL: usize = 10;
/// …and moves the penalty when their relative sizes differ by more than this factor.
/// The stop waits for the larger of the two, so the nearer they are kept, the sooner
/// both fall below it: 1.5 instead of 2 took 10–28% fewer iterations on the benchmark
/// cages, the lizard's and the authors' (a few unchanged), with the objective within
/// 0.06% of a run 100× tighter on all of them (0.11% with 2).
const PENALTY_BAND: f64 = 1.5;
