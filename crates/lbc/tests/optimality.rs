//! An independent check that the solver finds the optimum: on a small concave cage, a
//! second solver written here from the problem statement alone (Chambolle and Pock's
//! primal-dual method, with none of the crate's machinery: no `W = YM + H`, no ADMM,
//! no factorisation) produces dual variables, and those certify a lower bound on the
//! optimal objective. The crate's coordinates must come within half a percent of it.
//!
//! The certificate: for any `y_si` with `‖y_si‖ ≤ φ_i^s A_s`, Cauchy–Schwarz gives
//! `Σ φ A ‖∇w_i‖ ≥ Σ ⟨y, ∇w_i⟩` for every `W`, so the optimum is at least
//! `min over feasible W of Σ ⟨y, ∇W⟩`, which splits into one small linear program per
//! mesh vertex (minimise `⟨g_v, w⟩` over `w ≥ 0`, `Σ w_i = 1`, `Σ w_i c_i = x_v`),
//! solved exactly by trying every basis of three cage vertices. A poor `y` gives a
//! poor bound and fails the test; it cannot pass it wrongly.

use glam::{DMat3, DVec2, DVec3};
use lbc::{Cage, Domain, Settings, geodesic_distances, solve};

/// Everything the problem statement defines, computed here on its own.
struct Problem {
    n: usize,
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    /// Per triangle, the gradients of its three hat functions.
    grad: Vec<[DVec2; 3]>,
    /// `φ_i^s A_s`, triangle-major.
    weight: Vec<f64>,
    /// Boundary rows (fixed), `None` inside.
    fixed: Vec<Option<Vec<f64>>>,
    cage: Vec<DVec2>,
}

impl Problem {
    fn new(domain: &Domain, boundary: impl Fn(usize) -> Vec<f64>) -> Self {
        let n = domain.cage().len();
        let positions = domain.positions().to_vec();
        let triangles = domain.triangles().to_vec();
        let distances = geodesic_distances(domain).expect("geodesics");
        let mut grad = Vec::new();
        let mut weight = Vec::new();
        for t in &triangles {
            let p = t.map(|v| positions[v as usize]);
            let twice = (p[1] - p[0]).perp_dot(p[2] - p[0]);
            grad.push(std::array::from_fn(|k| {
                (p[(k + 2) % 3] - p[(k + 1) % 3]).perp() / twice
            }));
            for d in &distances {
                let mean = t.iter().map(|&v| d[v as usize]).sum::<f64>() / 3.0;
                // τ(x) = x², the default.
                weight.push(mean * mean * 0.5 * twice.abs());
            }
        }
        let fixed = domain
            .on_cage()
            .iter()
            .enumerate()
            .map(|(v, on)| on.map(|_| boundary(v)))
            .collect();
        Self {
            n,
            positions,
            triangles,
            grad,
            weight,
            fixed,
            cage: domain.cage().vertices().to_vec(),
        }
    }

    /// `∇_s w_i` for every triangle and cage vertex.
    fn gradient(&self, w: &[f64]) -> Vec<DVec2> {
        let n = self.n;
        let mut out = vec![DVec2::ZERO; self.triangles.len() * n];
        for (s, t) in self.triangles.iter().enumerate() {
            for i in 0..n {
                out[s * n + i] = (0..3)
                    .map(|k| self.grad[s][k] * w[t[k] as usize * n + i])
                    .sum();
            }
        }
        out
    }

    /// `∇ᵀ y`, per mesh vertex and cage vertex.
    fn divergence(&self, y: &[DVec2]) -> Vec<f64> {
        let n = self.n;
        let mut out = vec![0.0; self.positions.len() * n];
        for (s, t) in self.triangles.iter().enumerate() {
            for i in 0..n {
                for k in 0..3 {
                    out[t[k] as usize * n + i] += self.grad[s][k].dot(y[s * n + i]);
                }
            }
        }
        out
    }

    /// `Σ φ A ‖∇w‖`.
    fn objective(&self, w: &[f64]) -> f64 {
        self.gradient(w)
            .iter()
            .zip(&self.weight)
            .map(|(g, a)| a * g.length())
            .sum()
    }

    /// `min over feasible W of ⟨y, ∇W⟩`: one exact linear program per vertex.
    fn lower_bound(&self, y: &[DVec2]) -> f64 {
        let n = self.n;
        let g = self.divergence(y);
        let mut total = 0.0;
        for (v, fixed) in self.fixed.iter().enumerate() {
            let gv = &g[v * n..(v + 1) * n];
            total += match fixed {
                Some(row) => row.iter().zip(gv).map(|(a, b)| a * b).sum::<f64>(),
                None => self.vertex_lp(self.positions[v], gv),
            };
        }
        total
    }

    /// `min ⟨g, w⟩` over `w ≥ 0`, `Σ w_i (c_i, 1) = (x, 1)`: the optimum lies at a
    /// vertex of the polytope, a basic solution on three cage vertices.
    fn vertex_lp(&self, x: DVec2, g: &[f64]) -> f64 {
        let n = self.n;
        let mut best = f64::INFINITY;
        for a in 0..n {
            for b in a + 1..n {
                for c in b + 1..n {
                    let m = DMat3::from_cols(
                        self.cage[a].extend(1.0),
                        self.cage[b].extend(1.0),
                        self.cage[c].extend(1.0),
                    );
                    if m.determinant().abs() < 1e-12 {
                        continue;
                    }
                    let w = m.inverse() * x.extend(1.0);
                    if w.min_element() >= -1e-12 {
                        best = best.min(w.x * g[a] + w.y * g[b] + w.z * g[c]);
                    }
                }
            }
        }
        assert!(best.is_finite(), "no basic solution at {x}");
        best
    }

    /// Chambolle–Pock on `min Σ φA‖∇W‖ + ι(W ≥ 0)` subject to the per-vertex
    /// equalities `Σ w_i (c_i, 1) = (x, 1)` (dualised) and the fixed boundary rows.
    /// Returns the dual `y` of the gradient term.
    fn chambolle_pock(&self, iterations: usize) -> Vec<DVec2> {
        let n = self.n;
        let nv = self.positions.len();
        let nt = self.triangles.len();
        let mut w = vec![0.0; nv * n];
        for (v, fixed) in self.fixed.iter().enumerate() {
            match fixed {
                Some(row) => w[v * n..(v + 1) * n].copy_from_slice(row),
                None => w[v * n..(v + 1) * n].fill(1.0 / n as f64),
            }
        }
        // ‖K‖² ≤ ‖∇‖² + ‖E‖², each by power iteration.
        let grad_norm = {
            let mut x: Vec<f64> = (0..nv * n)
                .map(|k| ((k * 7919) % 13) as f64 - 6.0)
                .collect();
            let mut lambda = 0.0;
            for _ in 0..100 {
                let y = self.divergence(&self.gradient(&x));
                lambda = y.iter().map(|a| a * a).sum::<f64>().sqrt()
                    / x.iter().map(|a| a * a).sum::<f64>().sqrt();
                x = y.iter().map(|a| a / lambda).collect();
            }
            lambda
        };
        let ete = self.cage.iter().fold(DMat3::ZERO, |acc, c| {
            let k = c.extend(1.0);
            acc + DMat3::from_cols(k * k.x, k * k.y, k * k.z)
        });
        let e_norm = {
            let mut x = DVec3::ONE;
            for _ in 0..100 {
                x = (ete * x).normalize();
            }
            (ete * x).length()
        };
        let step = 0.99 / (grad_norm + e_norm).sqrt();
        let mut y = vec![DVec2::ZERO; nt * n];
        let mut lambda = vec![DVec3::ZERO; nv];
        let mut bar = w.clone();
        for _ in 0..iterations {
            let gb = self.gradient(&bar);
            for (k, yk) in y.iter_mut().enumerate() {
                let t = *yk + step * gb[k];
                let bound = self.weight[k];
                *yk = if t.length() > bound {
                    t * (bound / t.length())
                } else {
                    t
                };
            }
            for (v, l) in lambda.iter_mut().enumerate() {
                if self.fixed[v].is_some() {
                    continue;
                }
                let ew: DVec3 = (0..n)
                    .map(|i| bar[v * n + i] * self.cage[i].extend(1.0))
                    .sum();
                *l += step * (ew - self.positions[v].extend(1.0));
            }
            let div = self.divergence(&y);
            let old = w.clone();
            for (v, l) in lambda.iter().enumerate() {
                if self.fixed[v].is_some() {
                    continue;
                }
                for (i, c) in self.cage.iter().enumerate() {
                    let k = v * n + i;
                    let descent = div[k] + l.dot(c.extend(1.0));
                    w[k] = (w[k] - step * descent).max(0.0);
                }
            }
            for k in 0..w.len() {
                bar[k] = 2.0 * w[k] - old[k];
            }
        }
        y
    }
}

#[test]
fn the_objective_is_certified_optimal_by_an_independent_solver() {
    // An L: concave, six vertices.
    certify(&[
        (0.0, 0.0),
        (6.0, 0.0),
        (6.0, 2.0),
        (2.0, 2.0),
        (2.0, 6.0),
        (0.0, 6.0),
    ]);
}

/// Nine cage vertices: the solver's rows get three columns of no cage vertex (its
/// rows are padded to a multiple of four), which must change nothing.
#[test]
fn the_objective_is_certified_optimal_with_padded_rows() {
    certify(&[
        (0.0, 0.0),
        (3.0, -0.5),
        (6.0, 0.0),
        (6.5, 1.0),
        (6.0, 2.0),
        (2.0, 2.0),
        (2.0, 6.0),
        (1.0, 6.5),
        (0.0, 6.0),
    ]);
}

/// Solves inside the cage through `points` with the crate and checks its objective
/// within 0.5% of a lower bound from an independent first-order solver.
fn certify(points: &[(f64, f64)]) {
    let cage = Cage::new(points.iter().map(|&(x, y)| DVec2::new(x, y)).collect())
        .expect("a simple polygon");
    let domain = Domain::triangulate(&cage, 120).expect("meshed");
    let ours = solve(&domain, &Settings::default(), &mut |_| true).expect("solved");
    let problem = Problem::new(&domain, |v| ours.row(v).to_vec());
    let mut weights = Vec::new();
    for v in 0..domain.positions().len() {
        weights.extend_from_slice(ours.row(v));
    }
    let objective = problem.objective(&weights);
    // The crate reports the same objective (computed its own way).
    assert!(
        (objective - ours.report.objective).abs() <= 1e-9 * objective,
        "{objective} vs {}",
        ours.report.objective
    );
    let y = problem.chambolle_pock(20_000);
    let bound = problem.lower_bound(&y);
    assert!(bound <= objective * (1.0 + 1e-9), "{bound} > {objective}");
    let gap = (objective - bound) / bound;
    eprintln!(
        "objective {objective}, certified lower bound {bound}, gap {:.4}%",
        100.0 * gap
    );
    assert!(
        gap <= 0.005,
        "objective {objective} is {:.3}% above the certified lower bound {bound}",
        100.0 * gap
    );
}
