//! Piecewise-linear finite elements on the domain: per-triangle areas and gradients
//! of the hat functions, the stiffness and lumped mass matrices, and sparse Cholesky
//! factorisations with faer.

use faer::linalg::solvers::SolveCore;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut, Side};
use geometry::orient;
use glam::DVec2;

use crate::error::LbcError;

/// Per-triangle geometry in the solver's frame.
pub(crate) struct Elements {
    /// Area of each triangle.
    pub area: Vec<f64>,
    /// Gradients of the three hat functions of each triangle.
    pub grad: Vec<[DVec2; 3]>,
}

impl Elements {
    pub fn new(positions: &[DVec2], triangles: &[[u32; 3]]) -> Self {
        let mut area = Vec::with_capacity(triangles.len());
        let mut grad = Vec::with_capacity(triangles.len());
        for t in triangles {
            let p = t.map(|v| positions[v as usize]);
            let twice = orient(p[0], p[1], p[2]);
            area.push(0.5 * twice);
            // ∇λ_k is the inward normal of the opposite edge over twice the area.
            grad.push(std::array::from_fn(|k| {
                (p[(k + 2) % 3] - p[(k + 1) % 3]).perp() / twice
            }));
        }
        Self { area, grad }
    }

    /// Lower triangle (row ≥ column) of `scale_k · K + scale_m · M` over the vertices
    /// `map[v] = Some(row)`, with `K` the stiffness matrix `∫∇φ_a·∇φ_b` and `M` the
    /// lumped mass matrix.
    pub fn lower_triplets(
        &self,
        triangles: &[[u32; 3]],
        map: &dyn Fn(u32) -> Option<usize>,
        scale_k: f64,
        mass: &[f64],
        scale_m: f64,
    ) -> Vec<Triplet<usize, usize, f64>> {
        let mut out = Vec::with_capacity(triangles.len() * 6 + mass.len());
        for (s, t) in triangles.iter().enumerate() {
            let g = &self.grad[s];
            for a in 0..3 {
                let Some(ra) = map(t[a]) else { continue };
                for b in 0..3 {
                    let Some(rb) = map(t[b]) else { continue };
                    if ra >= rb {
                        out.push(Triplet::new(
                            ra,
                            rb,
                            scale_k * self.area[s] * g[a].dot(g[b]),
                        ));
                    }
                }
            }
        }
        for (v, &m) in mass.iter().enumerate() {
            if let Some(r) = map(v as u32) {
                out.push(Triplet::new(r, r, scale_m * m));
            }
        }
        out
    }

    /// Lumped mass: a third of each incident triangle's area.
    pub fn lumped_mass(&self, triangles: &[[u32; 3]], vertices: usize) -> Vec<f64> {
        let mut m = vec![0.0; vertices];
        for (s, t) in triangles.iter().enumerate() {
            for &v in t {
                m[v as usize] += self.area[s] / 3.0;
            }
        }
        m
    }
}

/// A sparse symmetric positive definite matrix, factorised once.
pub(crate) struct Factor {
    llt: faer::sparse::linalg::solvers::Llt<usize, f64>,
}

impl Factor {
    /// Factorises the `n × n` matrix given by its lower triangle (duplicates summed),
    /// with faer's fill-reducing ordering.
    pub fn new(n: usize, lower: &[Triplet<usize, usize, f64>]) -> Result<Self, LbcError> {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, lower)
            .map_err(|e| LbcError::Factorization(format!("{e:?}")))?;
        let llt = a
            .sp_cholesky(Side::Lower)
            .map_err(|e| LbcError::Factorization(format!("{e:?}")))?;
        Ok(Self { llt })
    }

    /// Solves for every column of `rhs` in place.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.llt.solve_in_place_with_conj(Conj::No, rhs);
    }
}
