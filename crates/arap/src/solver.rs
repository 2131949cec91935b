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

use faer::c64;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Par, Side};
use glam::DVec2;

use crate::error::ArapError;

/// A symmetric (Hermitian) matrix given by its lower triangle in compressed columns,
/// rows sorted within each column.
pub(crate) struct LowerCsc<T> {
    pub n: usize,
    pub col_ptr: Vec<u32>,
    pub row_idx: Vec<u32>,
    pub values: Vec<T>,
}

impl<T> LowerCsc<T> {
    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, u32> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// A fill-reducing ordering: `forward[new] = old`, `inverse[old] = new`.
pub(crate) struct Ordering {
    pub forward: Vec<u32>,
    pub inverse: Vec<u32>,
}

impl Ordering {
    /// Approximate minimum degree on the pattern of `a`.
    pub fn amd<T>(a: &LowerCsc<T>) -> Result<Self, ArapError> {
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
        .map_err(|e| ArapError::Factorization(format!("{e:?}")))?;
        Ok(Self { forward, inverse })
    }
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
/// `pattern[rows..rows + rows_len]` below their diagonal block; their values are a
/// column-major `(size + rows_len) × size` block at `values`.
#[derive(Clone, Copy, Debug)]
struct Supernode {
    start: u32,
    size: u32,
    rows: u32,
    rows_len: u32,
    values: usize,
}

/// `A = P·L·Lᴴ·Pᵀ` for a symmetric (Hermitian) positive definite `A`.
pub(crate) struct Cholesky<T> {
    forward: Vec<u32>,
    inverse: Vec<u32>,
    supernodes: Vec<Supernode>,
    pattern: Vec<u32>,
    values: Vec<T>,
}

impl<T: Entry> Cholesky<T> {
    /// Factorises `a` under `ordering`.
    ///
    /// # Errors
    /// [`ArapError::Factorization`] if `a` is not numerically positive definite or
    /// memory runs out.
    pub fn new(a: &LowerCsc<T::Faer>, ordering: &Ordering) -> Result<Self, ArapError> {
        let failed = |e: &dyn std::fmt::Debug| ArapError::Factorization(format!("{e:?}"));
        let perm = PermRef::new_checked(&ordering.forward, &ordering.inverse, a.n);
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| failed(&e))?;
        let mut values: Vec<T::Faer> = Vec::new();
        values
            .try_reserve_exact(symbolic.len_val())
            .map_err(|e| failed(&e))?;
        values.resize(symbolic.len_val(), T::Faer::zero_impl());
        let par = if a.n >= 20_000 {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<T::Faer>(par, Default::default()),
        )
        .map_err(|e| failed(&e))?;
        symbolic
            .factorize_numeric_llt::<T::Faer>(
                &mut values,
                SparseColMatRef::new(a.symbolic(), &a.values),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| failed(&e))?;

        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return Err(ArapError::Factorization(
                "expected a supernodal factor".into(),
            ));
        };
        let (forward, inverse) = match symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (f.to_vec(), i.to_vec())
            }
            None => ((0..a.n as u32).collect(), (0..a.n as u32).collect()),
        };
        let mut supernodes = Vec::with_capacity(sn.n_supernodes());
        let mut pattern = Vec::new();
        for s in 0..sn.n_supernodes() {
            let node = sn.supernode(s);
            let start = sn.supernode_begin()[s] as usize;
            let end = sn.supernode_end()[s] as usize;
            supernodes.push(Supernode {
                start: start as u32,
                size: (end - start) as u32,
                rows: pattern.len() as u32,
                rows_len: node.pattern().len() as u32,
                values: sn.col_ptr_for_val()[s] as usize,
            });
            pattern.extend_from_slice(node.pattern());
        }
        Ok(Self {
            forward,
            inverse,
            supernodes,
            pattern,
            values: values.into_iter().map(T::from_faer).collect(),
        })
    }

    /// Dimension of the matrix.
    pub fn n(&self) -> usize {
        self.forward.len()
    }

    /// Solves `A·x = b`: `b` in, `x` out; `work` is scratch of any content.
    pub fn solve_in_place(&self, b: &mut [DVec2], work: &mut Vec<DVec2>) {
        let n = self.n();
        work.clear();
        work.extend(self.forward.iter().map(|&old| b[old as usize]));
        let x = &mut work[..];
        let values = &self.values[..];
        // L·y = Pᵀ·b, column by column.
        for s in &self.supernodes {
            let (start, size, rows_len) = (s.start as usize, s.size as usize, s.rows_len as usize);
            let ld = size + rows_len;
            let rows = &self.pattern[s.rows as usize..s.rows as usize + rows_len];
            for c in 0..size {
                let col = &values[s.values + c * ld..s.values + (c + 1) * ld];
                let xc = T::div_diagonal(x[start + c], col[c]);
                x[start + c] = xc;
                for (r, &l) in col[c + 1..size].iter().enumerate() {
                    x[start + c + 1 + r] -= l.mul(xc);
                }
                for (&i, &l) in rows.iter().zip(&col[size..]) {
                    x[i as usize] -= l.mul(xc);
                }
            }
        }
        // Lᴴ·z = y, backwards.
        for s in self.supernodes.iter().rev() {
            let (start, size, rows_len) = (s.start as usize, s.size as usize, s.rows_len as usize);
            let ld = size + rows_len;
            let rows = &self.pattern[s.rows as usize..s.rows as usize + rows_len];
            for c in (0..size).rev() {
                let col = &values[s.values + c * ld..s.values + (c + 1) * ld];
                let mut acc = x[start + c];
                for (&i, &l) in rows.iter().zip(&col[size..]) {
                    acc -= l.conj_mul(x[i as usize]);
                }
                for (r, &l) in col[c + 1..size].iter().enumerate() {
                    acc -= l.conj_mul(x[start + c + 1 + r]);
                }
                x[start + c] = T::div_diagonal(acc, col[c]);
            }
        }
        for (old, out) in b[..n].iter_mut().enumerate() {
            *out = x[self.inverse[old] as usize];
        }
    }
}
