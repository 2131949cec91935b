//! Piecewise-linear finite elements on the domain: per-triangle areas and gradients
//! of the hat functions, the stiffness and lumped mass matrices, and sparse Cholesky
//! factorisations with faer.

use faer::Side;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use geometry::orient;
use glam::DVec2;

use rayon::prelude::*;

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

    /// The lower triangle (row ≥ column) of the stiffness matrix `K = ∫∇φ_a·∇φ_b`
    /// and of a diagonal `mass`, over the vertices `map[v] = Some(row)`: one
    /// assembly for every `scale_k · K + scale_m · M` of that pattern
    /// ([`Lower::values`]).
    pub fn lower(
        &self,
        triangles: &[[u32; 3]],
        map: &dyn Fn(u32) -> Option<usize>,
        mass: &[f64],
    ) -> Lower {
        let capacity = triangles.len() * 6 + mass.len();
        let mut lower = Lower {
            index: Vec::with_capacity(capacity),
            stiffness: Vec::with_capacity(capacity),
            mass: Vec::with_capacity(capacity),
        };
        for (s, t) in triangles.iter().enumerate() {
            let g = &self.grad[s];
            for a in 0..3 {
                let Some(ra) = map(t[a]) else { continue };
                for b in 0..3 {
                    let Some(rb) = map(t[b]) else { continue };
                    if ra >= rb {
                        lower.push(ra, rb, self.area[s] * g[a].dot(g[b]), 0.0);
                    }
                }
            }
        }
        for (v, &m) in mass.iter().enumerate() {
            if let Some(r) = map(v as u32) {
                lower.push(r, r, 0.0, m);
            }
        }
        lower
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

/// Entries of the lower triangles of a stiffness and a mass matrix on one pattern
/// (duplicates to be summed), from [`Elements::lower`].
pub(crate) struct Lower {
    index: Vec<Pair<usize, usize>>,
    stiffness: Vec<f64>,
    mass: Vec<f64>,
}

impl Lower {
    fn push(&mut self, row: usize, col: usize, stiffness: f64, mass: f64) {
        self.index.push(Pair::new(row, col));
        self.stiffness.push(stiffness);
        self.mass.push(mass);
    }

    /// The entries of `scale_k · K + scale_m · M`, in the order of the pattern's.
    pub fn values(&self, scale_k: f64, scale_m: f64) -> Vec<f64> {
        self.stiffness
            .iter()
            .zip(&self.mass)
            .map(|(k, m)| scale_k * k + scale_m * m)
            .collect()
    }
}

/// The structure of a symmetric positive definite `n × n` matrix given by the
/// entries of its lower triangle, and of its Cholesky factor (simplicial, in a
/// fill-reducing order): worked out once for every matrix of that pattern. The
/// geodesics' two matrices share one, and the ADMM's, on the inner vertices only,
/// takes the order of theirs ([`Pattern::order`]) rather than ordering afresh:
/// the minimum-degree ordering is most of the cost of a factorisation.
pub(crate) struct Pattern {
    matrix: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    cholesky: SymbolicCholesky<usize>,
}

impl Pattern {
    /// The pattern of the entries of `lower` (row ≥ column) of an `n × n` matrix,
    /// eliminated in approximate minimum degree order, or in `order` where given
    /// (`order[i]` the unknown eliminated `i`-th).
    pub fn new(n: usize, lower: &Lower, order: Option<&[u32]>) -> Result<Self, LbcError> {
        let (matrix, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &lower.index)
            .map_err(|e| failed(&e))?;
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let cholesky = match order {
            None => factorize_symbolic_cholesky(
                matrix.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                params,
            ),
            Some(order) => {
                if order.len() != n {
                    return Err(LbcError::Factorization(
                        "an order of the wrong length".into(),
                    ));
                }
                let forward: Vec<usize> = order.iter().map(|&i| i as usize).collect();
                let mut inverse = vec![0; n];
                for (i, &p) in forward.iter().enumerate() {
                    inverse[p] = i;
                }
                let perm = PermRef::new_checked(&forward, &inverse, n);
                factorize_symbolic_cholesky(
                    matrix.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Custom(perm),
                    params,
                )
            }
        }
        .map_err(|e| failed(&e))?;
        Ok(Self {
            matrix,
            argsort,
            cholesky,
        })
    }

    /// The elimination order: `order()[i]` is the unknown eliminated `i`-th.
    pub fn order(&self) -> Vec<u32> {
        match self.cholesky.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| i as u32).collect(),
            None => (0..self.matrix.nrows() as u32).collect(),
        }
    }
}

fn failed(e: &dyn std::fmt::Debug) -> LbcError {
    LbcError::Factorization(format!("{e:?}"))
}

/// A sparse Cholesky factor `P A Pᵀ = L Lᵀ` (faer's fill-reducing ordering `P`,
/// simplicial) kept as plain arrays, for solving many right-hand sides stored row
/// by row: ADMM's Y-update solves one column per cage vertex, and its right-hand
/// sides are rows of `n` weights per mesh vertex. Each step of the substitution is
/// then a short contiguous `axpy` on a row, and the permutation a copy of whole rows.
pub(crate) struct RowFactor {
    /// Row `i` of the factor is unknown `perm[i]`…
    perm: Vec<u32>,
    /// …and unknown `p` is row `position[p]`.
    position: Vec<u32>,
    /// `L` by columns, the diagonal first in each.
    col_ptr: Vec<usize>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
}

impl RowFactor {
    /// Factorises the matrix of `pattern` whose entries are `values` (in the order of
    /// the pattern's, duplicates summed).
    pub fn new(pattern: &Pattern, values: &[f64]) -> Result<Self, LbcError> {
        let a = SparseColMat::new_from_argsort(pattern.matrix.clone(), &pattern.argsort, values)
            .map_err(|e| failed(&e))?;
        let symbolic = &pattern.cholesky;
        let mut values = vec![0.0; symbolic.len_val()];
        let par = faer::Par::Seq;
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|e| failed(&e))?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| failed(&e))?;
        let SymbolicCholeskyRaw::Simplicial(s) = symbolic.raw() else {
            return Err(LbcError::Factorization(
                "expected a simplicial factor".into(),
            ));
        };
        let n = pattern.matrix.nrows();
        let col_ptr: Vec<usize> = s.col_ptr().to_vec();
        let row_idx: Vec<u32> = s.row_idx().iter().map(|&r| r as u32).collect();
        if (0..n).any(|j| col_ptr[j] == col_ptr[j + 1] || row_idx[col_ptr[j]] as usize != j) {
            return Err(LbcError::Factorization(
                "a column of the factor does not start at its diagonal".into(),
            ));
        }
        let perm = pattern.order();
        let mut position = vec![0; perm.len()];
        for (i, &p) in perm.iter().enumerate() {
            position[p as usize] = i as u32;
        }
        Ok(Self {
            perm,
            position,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// Solves `A X = B` for the `W` columns of `b` (row-major, `width` values a row)
    /// from `first` on (those past `width` taken as zero), into `x` (in the factor's
    /// order: row `i` is unknown `perm[i]`).
    #[inline(always)]
    fn solve_block<const W: usize>(&self, b: &[f64], width: usize, first: usize, x: &mut [f64]) {
        let take = (width - first).min(W);
        let n = self.perm.len();
        let (x, _) = x[..n * W].as_chunks_mut::<W>();
        for (row, &p) in x.iter_mut().zip(&self.perm) {
            let p = p as usize * width + first;
            if take == W {
                // A copy of known length, inlined (a call to `memmove` per row
                // otherwise).
                *row = b[p..p + W].try_into().expect("W values");
            } else {
                *row = [0.0; W];
                row[..take].copy_from_slice(&b[p..p + take]);
            }
        }
        // L y = b.
        for j in 0..n {
            let (start, end) = (self.col_ptr[j], self.col_ptr[j + 1]);
            let d = 1.0 / self.values[start];
            let xj = x[j].map(|v| v * d);
            x[j] = xj;
            for (&i, &l) in self.row_idx[start + 1..end]
                .iter()
                .zip(&self.values[start + 1..end])
            {
                let xi = &mut x[i as usize];
                for c in 0..W {
                    xi[c] -= l * xj[c];
                }
            }
        }
        // Lᵀ x = y.
        for j in (0..n).rev() {
            let (start, end) = (self.col_ptr[j], self.col_ptr[j + 1]);
            let d = 1.0 / self.values[start];
            let mut xj = x[j];
            for (&i, &l) in self.row_idx[start + 1..end]
                .iter()
                .zip(&self.values[start + 1..end])
            {
                let xi = &x[i as usize];
                for c in 0..W {
                    xj[c] -= l * xi[c];
                }
            }
            x[j] = xj.map(|v| v * d);
        }
    }

    crate::wide::twice! {
    /// Solves `A X = B` in place for every column of `b` (row-major, `width` values
    /// a row), in blocks of columns of an even width as near equal as can be, at most
    /// 32, as few as can be (each is a pass over the factor) but a multiple of the
    /// threads (two at most), so that the threads share the blocks evenly: 26 columns
    /// in two blocks of 14 on two threads and one of 26 on one; 34 in two of 18 (three
    /// of 12 kept one thread waiting for the third: 7% off an iteration).
    /// `scratch` holds their working rows; with `_wide`, compiled for AVX2.
    pub fn solve_rows / solve_rows_plain / solve_rows_avx2
        (&self, _wide: bool, b: &mut [f64], width: usize, scratch: &mut Vec<Vec<f64>>) {
        let n = self.perm.len();
        let threads = rayon::current_num_threads().clamp(1, 2);
        let blocks = width.div_ceil(32).div_ceil(threads) * threads;
        let w = (width.div_ceil(blocks).div_ceil(2) * 2).clamp(2, 32);
        let blocks = width.div_ceil(w);
        scratch.resize_with(blocks, Vec::new);
        {
            let b = &*b;
            scratch.par_iter_mut().enumerate().for_each(|(k, x)| {
                x.resize(n * w, 0.0);
                let first = k * w;
                match w {
                    2 => self.solve_block::<2>(b, width, first, x),
                    4 => self.solve_block::<4>(b, width, first, x),
                    6 => self.solve_block::<6>(b, width, first, x),
                    8 => self.solve_block::<8>(b, width, first, x),
                    10 => self.solve_block::<10>(b, width, first, x),
                    12 => self.solve_block::<12>(b, width, first, x),
                    14 => self.solve_block::<14>(b, width, first, x),
                    16 => self.solve_block::<16>(b, width, first, x),
                    18 => self.solve_block::<18>(b, width, first, x),
                    20 => self.solve_block::<20>(b, width, first, x),
                    22 => self.solve_block::<22>(b, width, first, x),
                    24 => self.solve_block::<24>(b, width, first, x),
                    26 => self.solve_block::<26>(b, width, first, x),
                    28 => self.solve_block::<28>(b, width, first, x),
                    30 => self.solve_block::<30>(b, width, first, x),
                    _ => self.solve_block::<32>(b, width, first, x),
                }
            });
        }
        let scratch = &*scratch;
        const PER_TASK: usize = 256;
        b.par_chunks_mut(width * PER_TASK)
            .enumerate()
            .for_each(|(task, rows)| {
                for (q, row) in rows.chunks_exact_mut(width).enumerate() {
                    let i = self.position[task * PER_TASK + q] as usize;
                    for (k, chunk) in row.chunks_mut(w).enumerate() {
                        let from = &scratch[k][i * w..i * w + chunk.len()];
                        // Element by element: `copy_from_slice` calls `memmove`
                        // for each of these short runs.
                        for (c, f) in chunk.iter_mut().zip(from) {
                            *c = *f;
                        }
                    }
                }
            });
    }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// `A = L + I` for the 5-point Laplacian `L` of a `k × k` grid, lower triangle.
    fn grid(k: usize) -> (usize, Vec<Triplet<usize, usize, f64>>) {
        let n = k * k;
        let mut lower = Vec::new();
        for y in 0..k {
            for x in 0..k {
                let i = y * k + x;
                let mut degree = 0.0;
                for (dx, dy) in [(1, 0), (0, 1)] {
                    if x + dx < k && y + dy < k {
                        let j = (y + dy) * k + x + dx;
                        lower.push(Triplet::new(j, i, -1.0));
                    }
                }
                for (nx, ny) in [
                    (x.wrapping_sub(1), y),
                    (x + 1, y),
                    (x, y.wrapping_sub(1)),
                    (x, y + 1),
                ] {
                    if nx < k && ny < k {
                        degree += 1.0;
                    }
                }
                lower.push(Triplet::new(i, i, degree + 1.0));
            }
        }
        (n, lower)
    }

    /// `lower` as the entries of a stiffness matrix (no mass).
    fn entries_of(lower: &[Triplet<usize, usize, f64>]) -> Lower {
        let mut entries = Lower {
            index: Vec::new(),
            stiffness: Vec::new(),
            mass: Vec::new(),
        };
        for t in lower {
            entries.push(t.row, t.col, t.val, 0.0);
        }
        entries
    }

    #[test]
    fn row_factor_solves_every_column_of_any_width() {
        let (n, lower) = grid(23);
        let entries = entries_of(&lower);
        let pattern = Pattern::new(n, &entries, None).expect("a pattern");
        let factor =
            RowFactor::new(&pattern, &entries.values(1.0, 0.0)).expect("positive definite");
        let mut scratch = Vec::new();
        // Blocks for two threads and for one; the plain and (where the CPU has it) the
        // AVX2 copy, which give the same numbers.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool");
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool");
        let mut plain: Vec<Vec<f64>> = Vec::new();
        for (width, pool, wide) in [1, 2, 5, 16, 17, 26, 33, 37, 66]
            .into_iter()
            .flat_map(|w| [(w, &one), (w, &two)])
            .flat_map(|(w, p)| [(w, p, false), (w, p, crate::wide::available())])
        {
            let b: Vec<f64> = (0..n * width)
                .map(|k| ((k * 7919) % 101) as f64 / 50.0 - 1.0)
                .collect();
            let mut x = b.clone();
            pool.install(|| factor.solve_rows(wide, &mut x, width, &mut scratch));
            // A x, from the lower triangle.
            let mut ax = vec![0.0; n * width];
            for t in &lower {
                let (i, j, v) = (t.row, t.col, t.val);
                for c in 0..width {
                    ax[i * width + c] += v * x[j * width + c];
                    if i != j {
                        ax[j * width + c] += v * x[i * width + c];
                    }
                }
            }
            let worst = ax
                .iter()
                .zip(&b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-12, "width {width}: residual {worst}");
            if wide {
                assert_eq!(plain.last(), Some(&x), "width {width}: AVX2 as plain");
            } else {
                plain.push(x);
            }
        }
    }

    /// A factor in a given elimination order solves as well as one in the
    /// minimum-degree order, and keeps that order; a pattern's order can be reused.
    #[test]
    fn row_factor_follows_a_given_order() {
        let (n, lower) = grid(17);
        let entries = entries_of(&lower);
        let amd = Pattern::new(n, &entries, None).expect("a pattern");
        // Every other unknown first, then the rest backwards: far from the
        // minimum-degree order.
        let given: Vec<u32> = (0..n as u32)
            .step_by(2)
            .chain((1..n as u32).step_by(2).rev())
            .collect();
        for (order, pattern) in [
            (amd.order(), Pattern::new(n, &entries, Some(&amd.order()))),
            (given.clone(), Pattern::new(n, &entries, Some(&given))),
        ] {
            let pattern = pattern.expect("a pattern");
            assert_eq!(pattern.order(), order);
            let factor =
                RowFactor::new(&pattern, &entries.values(1.0, 0.0)).expect("positive definite");
            let b: Vec<f64> = (0..n).map(|k| ((k * 31) % 13) as f64 - 6.0).collect();
            let mut x = b.clone();
            factor.solve_rows(false, &mut x, 1, &mut Vec::new());
            let mut ax = vec![0.0; n];
            for t in &lower {
                ax[t.row] += t.val * x[t.col];
                if t.row != t.col {
                    ax[t.col] += t.val * x[t.row];
                }
            }
            let worst = ax
                .iter()
                .zip(&b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-12, "residual {worst}");
        }
        assert!(Pattern::new(n, &entries, Some(&given[1..])).is_err());
    }
}
