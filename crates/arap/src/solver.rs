//! The sparse Cholesky factorisation both steps use (faer's supernodal or simplicial
//! `LLᵀ`), with a fill-reducing ordering chosen once per compilation.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::error::ArapError;

/// A symmetric matrix given by its lower triangle in compressed columns, rows sorted
/// within each column.
pub(crate) struct LowerCsc {
    pub n: usize,
    pub col_ptr: Vec<u32>,
    pub row_idx: Vec<u32>,
    pub values: Vec<f64>,
}

impl LowerCsc {
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
    pub fn amd(a: &LowerCsc) -> Result<Self, ArapError> {
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

    /// The same ordering applied to `(x, y)` pairs: unknown `2·i + c` follows
    /// vertex `i`.
    pub fn interleaved(&self) -> Self {
        let spread = |p: &[u32]| p.iter().flat_map(|&i| [2 * i, 2 * i + 1]).collect();
        Self {
            forward: spread(&self.forward),
            inverse: spread(&self.inverse),
        }
    }
}

/// `A = L·Lᵀ` for a symmetric positive definite `A`.
pub(crate) struct Cholesky {
    symbolic: SymbolicCholesky<u32>,
    values: Vec<f64>,
}

impl Cholesky {
    /// Factorises `a` under `ordering`.
    ///
    /// # Errors
    /// [`ArapError::Factorization`] if `a` is not numerically positive definite or
    /// memory runs out.
    pub fn new(a: &LowerCsc, ordering: &Ordering) -> Result<Self, ArapError> {
        let failed = |e: &dyn std::fmt::Debug| ArapError::Factorization(format!("{e:?}"));
        let perm = PermRef::new_checked(&ordering.forward, &ordering.inverse, a.n);
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            Default::default(),
        )
        .map_err(|e| failed(&e))?;
        let mut values = Vec::new();
        values
            .try_reserve_exact(symbolic.len_val())
            .map_err(|e| failed(&e))?;
        values.resize(symbolic.len_val(), 0.0);
        let par = parallelism(a.n);
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|e| failed(&e))?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                SparseColMatRef::new(a.symbolic(), &a.values),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| failed(&e))?;
        Ok(Self { symbolic, values })
    }

    /// Dimension of the matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Workspace for [`Cholesky::solve_in_place`] with `columns` right-hand sides.
    pub fn scratch(&self, columns: usize) -> StackReq {
        self.symbolic
            .solve_in_place_scratch::<f64>(columns, Par::Seq)
    }

    /// Overwrites the column-major `n × columns` block `rhs` with `A⁻¹·rhs`.
    pub fn solve_in_place(&self, rhs: &mut [f64], columns: usize, stack: &mut MemStack) {
        let n = self.n();
        LltRef::<'_, u32, f64>::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, columns),
            Par::Seq,
            stack,
        );
    }
}

/// Threads for a numeric factorisation: all of them for large systems.
fn parallelism(n: usize) -> Par {
    if n >= 20_000 { Par::rayon(0) } else { Par::Seq }
}
