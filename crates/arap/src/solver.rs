//! The sparse Cholesky factorisations of both steps: a fill-reducing ordering, faer's
//! supernodal `LLᴴ`, and tight forward and backward substitutions over the factor.
//!
//! Right-hand sides are 2-vectors per unknown (`DVec2`). Step two's matrix is real and
//! the two components are its x and y columns, solved in one sweep over the factor.
//! Step one's is the paper's `2m × 2m` matrix with x and y interleaved; each of its
//! 2×2 blocks is `p·I + q·R90`, the real form of the complex number `p − i·q`, so it
//! is the real form of an `m × m` Hermitian matrix, and so is its Cholesky factor
//! (under an ordering that keeps each vertex's x and y together). That factor is
//! stored as complex numbers (`DVec2` as `re + i·im`): the same factor and the same
//! substitutions in half the memory.

use std::sync::Arc;

use faer::c64;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Par, Side};
use glam::DVec2;

use crate::error::ArapError;

/// The pattern of a symmetric (Hermitian) matrix's lower triangle in compressed
/// columns, rows sorted within each column; values come beside it in that order.
pub(crate) struct LowerPattern {
    pub n: usize,
    pub col_ptr: Vec<u32>,
    pub row_idx: Vec<u32>,
}

impl LowerPattern {
    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, u32> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// Supernodes merge with their neighbours only where that stores few explicit
/// zeros: every pose's substitutions read every stored entry, while the
/// factorisation, done once, gains little from larger blocks on meshes.
const RELAX: &[(usize, f64)] = &[(4, 0.3), (16, 0.1), (usize::MAX, 0.02)];

/// A fill-reducing order (approximate minimum degree) of the unknowns of a matrix
/// with the pattern `a`: `order[new] = old`.
pub(crate) fn amd_order(a: &LowerPattern) -> Result<Vec<u32>, ArapError> {
    let n = a.n;
    let mut forward = vec![0u32; n];
    let mut inverse = vec![0u32; n];
    let nnz = a.row_idx.len();
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<u32>(n, nnz))
        .map_err(|_| ArapError::Factorization("out of memory".into()))?;
    amd::order_maybe_unsorted(
        &mut forward,
        &mut inverse,
        a.symbolic(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| failed(&e))?;
    Ok(forward)
}

/// An entry of a Cholesky factor acting on a `DVec2` unknown: a real number scaling
/// both components (step two), or a complex number (step one).
pub(crate) trait Entry: Copy + Send + Sync {
    /// The matching faer scalar.
    type Faer: ComplexField + Copy;
    /// `self · x`.
    fn mul(self, x: DVec2) -> DVec2;
    /// `conj(self) · x`.
    fn conj_mul(self, x: DVec2) -> DVec2;
    /// `x / self` for a diagonal entry (real and positive).
    fn div_diagonal(x: DVec2, d: Self) -> DVec2;
    fn from_faer(v: Self::Faer) -> Self;
}

impl Entry for f64 {
    type Faer = f64;
    #[inline(always)]
    fn mul(self, x: DVec2) -> DVec2 {
        self * x
    }
    #[inline(always)]
    fn conj_mul(self, x: DVec2) -> DVec2 {
        self * x
    }
    #[inline(always)]
    fn div_diagonal(x: DVec2, d: Self) -> DVec2 {
        x / d
    }
    fn from_faer(v: f64) -> Self {
        v
    }
}

/// A complex number `re + i·im`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Complex(pub DVec2);

impl Entry for Complex {
    type Faer = c64;
    #[inline(always)]
    fn mul(self, x: DVec2) -> DVec2 {
        let a = self.0;
        DVec2::new(a.x * x.x - a.y * x.y, a.x * x.y + a.y * x.x)
    }
    #[inline(always)]
    fn conj_mul(self, x: DVec2) -> DVec2 {
        let a = self.0;
        DVec2::new(a.x * x.x + a.y * x.y, a.x * x.y - a.y * x.x)
    }
    #[inline(always)]
    fn div_diagonal(x: DVec2, d: Self) -> DVec2 {
        x / d.0.x
    }
    fn from_faer(v: c64) -> Self {
        Self(DVec2::new(v.re, v.im))
    }
}

/// One supernode of the factor: columns `start..start + size` share the row pattern
/// `pattern[rows..rows + rows_len]` below their diagonal block. faer stores their
/// values as a column-major `(size + rows_len) × size` block at `faer_values`, the
/// diagonal block's upper triangle included; [`Cholesky`] keeps them packed at
/// `values`, each column from its diagonal entry down (column `c` holds
/// `size + rows_len − c` entries), so that the substitutions read nothing unused.
#[derive(Clone, Copy, Debug)]
struct Supernode {
    start: u32,
    size: u32,
    rows: u32,
    rows_len: u32,
    faer_values: usize,
    values: usize,
}

impl Supernode {
    /// Number of packed entries.
    fn packed_len(&self) -> usize {
        let (size, ld) = (self.size as usize, (self.size + self.rows_len) as usize);
        size * ld - size * (size - 1) / 2
    }
}

/// What both steps' factors share: they have one pattern and one ordering, so one
/// symbolic analysis serves both.
pub(crate) struct Structure {
    symbolic: SymbolicCholesky<u32>,
    layout: Arc<Layout>,
}

/// The factor's layout: its supernodes.
struct Layout {
    n: usize,
    supernodes: Vec<Supernode>,
    pattern: Vec<u32>,
    /// The most rows below any supernode's diagonal block.
    widest: usize,
    /// Number of packed entries of a factor.
    len: usize,
}

fn failed(e: &dyn std::fmt::Debug) -> ArapError {
    ArapError::Factorization(format!("{e:?}"))
}

impl Structure {
    /// The symbolic factorisation of `pattern` (supernodal), unknowns in the order
    /// given: they come numbered by a fill-reducing order already.
    pub fn new(pattern: &LowerPattern) -> Result<Self, ArapError> {
        // The identity as a custom ordering: with `SymmetricOrdering::Identity` and
        // a lower triangle, faer 0.24's numeric factorisation panicked on an index;
        // a custom ordering goes through its usual path.
        let identity: Vec<u32> = (0..pattern.n as u32).collect();
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&identity, &identity, pattern.n)),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                supernodal_params: SymbolicSupernodalParams { relax: Some(RELAX) },
                ..Default::default()
            },
        )
        .map_err(|e| failed(&e))?;
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return Err(ArapError::Factorization(
                "expected a supernodal factor".into(),
            ));
        };
        let mut supernodes = Vec::with_capacity(sn.n_supernodes());
        let mut rows = Vec::new();
        let mut len = 0;
        for s in 0..sn.n_supernodes() {
            let node = sn.supernode(s);
            let start = sn.supernode_begin()[s] as usize;
            let end = sn.supernode_end()[s] as usize;
            let supernode = Supernode {
                start: start as u32,
                size: (end - start) as u32,
                rows: rows.len() as u32,
                rows_len: node.pattern().len() as u32,
                faer_values: sn.col_ptr_for_val()[s] as usize,
                values: len,
            };
            len += supernode.packed_len();
            supernodes.push(supernode);
            rows.extend_from_slice(node.pattern());
        }
        let widest = supernodes
            .iter()
            .map(|s| s.rows_len as usize)
            .max()
            .unwrap_or(0);
        Ok(Self {
            symbolic,
            layout: Arc::new(Layout {
                n: pattern.n,
                supernodes,
                pattern: rows,
                widest,
                len,
            }),
        })
    }
}

/// `A = L·Lᴴ` for a symmetric (Hermitian) positive definite `A` whose unknowns come
/// in a fill-reducing order.
pub(crate) struct Cholesky<T> {
    layout: Arc<Layout>,
    values: Vec<T>,
}

impl<T: Entry> Cholesky<T> {
    /// Factorises the matrix with `structure`'s pattern and lower-triangle `values`.
    ///
    /// # Errors
    /// [`ArapError::Factorization`] if it is not numerically positive definite or
    /// memory runs out.
    pub fn new(
        structure: &Structure,
        pattern: &LowerPattern,
        values: &[T::Faer],
    ) -> Result<Self, ArapError> {
        let symbolic = &structure.symbolic;
        let mut factor: Vec<T::Faer> = Vec::new();
        factor
            .try_reserve_exact(symbolic.len_val())
            .map_err(|e| failed(&e))?;
        factor.resize(symbolic.len_val(), T::Faer::zero_impl());
        let par = Par::Seq;
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<T::Faer>(par, Default::default()),
        )
        .map_err(|e| failed(&e))?;
        symbolic
            .factorize_numeric_llt::<T::Faer>(
                &mut factor,
                SparseColMatRef::new(pattern.symbolic(), values),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| failed(&e))?;
        let layout = &structure.layout;
        let mut values = Vec::new();
        values
            .try_reserve_exact(layout.len)
            .map_err(|e| failed(&e))?;
        for s in &layout.supernodes {
            let (size, ld) = (s.size as usize, (s.size + s.rows_len) as usize);
            for c in 0..size {
                let column = s.faer_values + c * ld;
                values.extend(
                    factor[column + c..column + ld]
                        .iter()
                        .map(|&v| T::from_faer(v)),
                );
            }
        }
        Ok(Self {
            layout: Arc::clone(layout),
            values,
        })
    }

    /// Number of stored entries of the factor.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Dimension of the matrix.
    pub fn n(&self) -> usize {
        self.layout.n
    }

    /// Solves `L·Lᴴ·x = b`: `b` in, `x` out; `work` is scratch of any content.
    pub fn solve_in_place(&self, x: &mut [DVec2], work: &mut Vec<DVec2>) {
        let layout = &*self.layout;
        debug_assert_eq!(x.len(), self.n());
        // Room for one supernode's rows below its diagonal block.
        work.resize(layout.widest, DVec2::ZERO);
        let tmp = &mut work[..];
        let values = &self.values[..];
        // L·y = Pᵀ·b: per supernode, its diagonal block, then one update of the rows
        // below it.
        for s in &layout.supernodes {
            let (start, size, rows_len) = (s.start as usize, s.size as usize, s.rows_len as usize);
            let ld = size + rows_len;
            let mut block = &values[s.values..s.values + s.packed_len()];
            let rows = &layout.pattern[s.rows as usize..s.rows as usize + rows_len];
            let tmp = &mut tmp[..rows_len];
            tmp.fill(DVec2::ZERO);
            let xs = &mut x[start..start + size];
            for c in 0..size {
                // Column c from its diagonal entry: the diagonal block, then below.
                let (col, next) = block.split_at(ld - c);
                block = next;
                let (inside, below) = col.split_at(size - c);
                let xc = T::div_diagonal(xs[c], inside[0]);
                xs[c] = xc;
                for (xr, &l) in xs[c + 1..].iter_mut().zip(&inside[1..]) {
                    *xr -= l.mul(xc);
                }
                for (t, &l) in tmp.iter_mut().zip(below) {
                    *t += l.mul(xc);
                }
            }
            for (&i, &t) in rows.iter().zip(tmp.iter()) {
                x[i as usize] -= t;
            }
        }
        // Lᴴ·z = y, backwards: the rows below each supernode gathered once.
        for s in layout.supernodes.iter().rev() {
            let (start, size, rows_len) = (s.start as usize, s.size as usize, s.rows_len as usize);
            let ld = size + rows_len;
            let mut block = &values[s.values..s.values + s.packed_len()];
            let rows = &layout.pattern[s.rows as usize..s.rows as usize + rows_len];
            let tmp = &mut tmp[..rows_len];
            for (t, &i) in tmp.iter_mut().zip(rows) {
                *t = x[i as usize];
            }
            let xs = &mut x[start..start + size];
            for c in (0..size).rev() {
                // Column c is the last ld − c entries of what is left.
                let (rest, col) = block.split_at(block.len() - (ld - c));
                block = rest;
                let (inside, below) = col.split_at(size - c);
                let mut acc = xs[c];
                for (&l, &t) in below.iter().zip(tmp.iter()) {
                    acc -= l.conj_mul(t);
                }
                for (&l, &xr) in inside[1..].iter().zip(&xs[c + 1..]) {
                    acc -= l.conj_mul(xr);
                }
                xs[c] = T::div_diagonal(acc, inside[0]);
            }
        }
    }
}
