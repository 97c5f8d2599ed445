//! faer's sparse LU for the sizes where a dense factorisation no longer pays (violin beads,
//! long chains): the symbolic analysis (fill-reducing column ordering, elimination tree) is
//! done once per pattern, the numeric factorisation per matrix, in storage kept between
//! calls so that a frequency sweep does not allocate per point.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par};

use crate::DynamicsError;

/// A square sparse pattern in compressed columns (rows ascending in each column) with its
/// symbolic LU analysis, and the numeric factors of the last matrix factorised.
pub(crate) struct SparseLu<T> {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, T>,
    factored: bool,
    scratch: MemBuffer,
}

impl<T: ComplexField> SparseLu<T> {
    /// Analyses the pattern given by `col_ptr` (n + 1 entries) and `row_idx`.
    pub(crate) fn new(col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Result<Self, DynamicsError> {
        let n = col_ptr.len().saturating_sub(1);
        let structure = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let symbolic = factorize_symbolic_lu(structure, Default::default())
            .map_err(|e| DynamicsError::Solver(format!("LU analysis: {e:?}")))?;
        let scratch = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<T>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<T>(1, Par::Seq),
        ]));
        Ok(SparseLu {
            n,
            col_ptr,
            row_idx,
            symbolic,
            numeric: NumericLu::new(),
            factored: false,
            scratch,
        })
    }

    /// Number of stored entries (the length of a values array).
    pub(crate) fn len(&self) -> usize {
        self.row_idx.len()
    }

    /// Index of (i, j) in the values array, if stored.
    pub(crate) fn index(&self, i: usize, j: usize) -> Option<usize> {
        let range = self.col_ptr[j]..self.col_ptr[j + 1];
        self.row_idx[range.clone()]
            .binary_search(&i)
            .ok()
            .map(|k| range.start + k)
    }

    /// Factorises the matrix with `values` (in the order of the pattern); false if the
    /// factorisation fails.
    pub(crate) fn factor(&mut self, values: &[T]) -> bool {
        let structure = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(structure, values);
        self.factored = self
            .symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .is_ok();
        self.factored
    }

    /// Solves A x = b in place with the last factorisation; false (b untouched) if there is
    /// none.
    pub(crate) fn solve(&mut self, b: &mut [T]) -> bool {
        if !self.factored {
            return false;
        }
        let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(&self.symbolic, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, self.n, 1),
            Par::Seq,
            MemStack::new(&mut self.scratch),
        );
        true
    }
}
