//! The equilibrium's Hessian on the terms' sparsity pattern, for models too large for a
//! dense n × n matrix (a 10 000-stage chain has 60 000 free coordinates: 28.8 GB dense).
//!
//! Each term couples only its own coordinates, so the Hessian's pattern is the union of
//! the terms' coordinate pairs: a chain's or a tree's has a bounded number of entries per
//! row, and its Cholesky factor, in a fill-reducing order, stays near-linear in size. The
//! pattern and the factor's symbolic analysis are made once per Newton search (the terms
//! do not change during it); each step sums the values and factorises them.

use faer::Side;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{MatMut, linalg::solvers::SolveCore};
use nalgebra::{DMatrix, DVector};

use crate::evaluate::Evaluator;

/// Largest number of free coordinates whose Newton step uses a dense Hessian and a dense
/// Cholesky factorisation; larger searches sum the Hessian on the terms' sparsity pattern
/// and factorise it sparse. Every bundled model at its defaults (84 coordinates at most)
/// stays dense, with its figures as they were; at 200 coordinates a dense Cholesky is a few
/// million operations, under a millisecond.
pub const DENSE_EQUILIBRIUM_LIMIT: usize = 200;

/// The lower triangle of a symmetric matrix over the free coordinates, in compressed
/// columns (rows ascending), with the symbolic analysis of its Cholesky factor.
pub(crate) struct SparseHessian {
    structure: SymbolicSparseColMat<usize>,
    /// Values in the order of `structure`.
    pub(crate) values: Vec<f64>,
    /// Position of each diagonal entry in `values`.
    diagonal: Vec<usize>,
    llt: Option<SymbolicLlt<usize>>,
}

impl SparseHessian {
    /// The pattern of the evaluator's terms over the free coordinates (`slot` maps a
    /// global coordinate to its free index), every diagonal entry included.
    pub(crate) fn new(ev: &Evaluator, slot: &[Option<usize>], n: usize) -> Self {
        // rows of each column, from every term's pairs (lower triangle: row ≥ column)
        let mut rows: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for term in ev.terms() {
            for &ga in &term.coords {
                let Some(i) = slot[ga] else { continue };
                for &gb in &term.coords {
                    if let Some(j) = slot[gb]
                        && i > j
                    {
                        rows[j].push(i);
                    }
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut diagonal = Vec::with_capacity(n);
        col_ptr.push(0);
        for (j, mut column) in rows.into_iter().enumerate() {
            column.sort_unstable();
            column.dedup();
            // the column's first row is its diagonal (every other row is below it)
            diagonal.push(row_idx.len());
            debug_assert_eq!(column.first(), Some(&j));
            row_idx.extend(column);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        // the pattern is sorted and in bounds by construction
        let structure = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let llt = SymbolicLlt::try_new(structure.as_ref(), Side::Lower).ok();
        SparseHessian {
            structure,
            values: vec![0.0; nnz],
            diagonal,
            llt,
        }
    }

    /// Position of entry (i, j), i ≥ j, in `values`.
    fn position(&self, i: usize, j: usize) -> Option<usize> {
        let start = self.structure.col_ptr()[j];
        let column = &self.structure.row_idx()[start..self.structure.col_ptr()[j + 1]];
        column.binary_search(&i).ok().map(|k| start + k)
    }

    /// Sums the per-term tension-on Hessians of `ev` over the free coordinates (the lower
    /// triangle only: the upper is its mirror).
    pub(crate) fn sum(&mut self, ev: &Evaluator, slot: &[Option<usize>]) {
        self.values.fill(0.0);
        for (t, term) in ev.terms().iter().enumerate() {
            let (h, m) = (ev.on(t), term.coords.len());
            for (a, &ga) in term.coords.iter().enumerate() {
                let Some(i) = slot[ga] else { continue };
                for (b, &gb) in term.coords.iter().enumerate() {
                    if let Some(j) = slot[gb]
                        && i >= j
                        && let Some(p) = self.position(i, j)
                    {
                        self.values[p] += h[a * m + b];
                    }
                }
            }
        }
    }

    /// Entry (i, i).
    pub(crate) fn diagonal(&self, i: usize) -> f64 {
        self.values[self.diagonal[i]]
    }

    /// Solves (H + diag(shift)) x = rhs by a sparse Cholesky factorisation; None if the
    /// shifted matrix is not positive definite (or the analysis failed).
    pub(crate) fn solve_shifted(&self, shift: &[f64], rhs: &DVector<f64>) -> Option<DVector<f64>> {
        let symbolic = self.llt.clone()?;
        let mut values = self.values.clone();
        for (&p, &s) in self.diagonal.iter().zip(shift) {
            values[p] += s;
        }
        let matrix = SparseColMatRef::new(self.structure.as_ref(), &values);
        let llt = Llt::try_new_with_symbolic(symbolic, matrix, Side::Lower).ok()?;
        let mut x = rhs.clone();
        let n = x.len();
        llt.solve_in_place_with_conj(
            faer::Conj::No,
            MatMut::from_column_major_slice_mut(x.as_mut_slice(), n, 1),
        );
        Some(x)
    }
}

/// A symmetric matrix stored by its entries, row by row (columns ascending in each row,
/// both triangles): the mass matrix, whose entries couple only the coordinates of one body.
/// Its size grows with the number of bodies, where a dense n × n matrix grows with its
/// square (28.8 GB for a 10 000-stage chain). [`MassMatrix::to_dense`] gives the dense
/// matrix for the dense solvers of small models; indexing reads one entry (0 off the
/// pattern).
#[derive(Clone, Debug, PartialEq)]
pub struct MassMatrix {
    n: usize,
    row_start: Vec<usize>,
    cols: Vec<usize>,
    values: Vec<f64>,
}

/// What indexing off the pattern reads.
static ZERO: f64 = 0.0;

impl MassMatrix {
    /// The `n` × `n` matrix with the sum of the `entries` (row, column, value) at each
    /// position, summed in the order given (the order of a dense scatter, so the numbers
    /// are those a dense sum gives). Entries out of range are left out.
    pub fn from_entries(n: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut order: Vec<usize> = (0..entries.len())
            .filter(|&k| entries[k].0 < n && entries[k].1 < n)
            .collect();
        // stable: equal positions keep the order given
        order.sort_by_key(|&k| (entries[k].0, entries[k].1));
        let mut row_start = vec![0; n + 1];
        let (mut cols, mut values) = (Vec::new(), Vec::<f64>::new());
        let mut last = None;
        for k in order {
            let (i, j, v) = entries[k];
            if last == Some((i, j)) {
                if let Some(sum) = values.last_mut() {
                    *sum += v;
                }
            } else {
                cols.push(j);
                values.push(0.0 + v);
                row_start[i + 1] += 1;
                last = Some((i, j));
            }
        }
        for i in 0..n {
            row_start[i + 1] += row_start[i];
        }
        MassMatrix {
            n,
            row_start,
            cols,
            values,
        }
    }

    /// The non-zero entries of a dense square matrix (a non-square one: its square part).
    pub fn from_dense(m: &DMatrix<f64>) -> Self {
        let n = m.nrows().min(m.ncols());
        let entries: Vec<(usize, usize, f64)> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j, m[(i, j)])))
            .filter(|e| e.2 != 0.0)
            .collect();
        Self::from_entries(n, &entries)
    }

    /// The dense matrix (for the dense solvers of small models).
    pub fn to_dense(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.n, self.n);
        for (i, j, v) in self.entries() {
            m[(i, j)] = v;
        }
        m
    }

    /// Number of rows (= columns).
    pub fn nrows(&self) -> usize {
        self.n
    }

    /// Number of columns (= rows).
    pub fn ncols(&self) -> usize {
        self.n
    }

    /// (rows, columns).
    pub fn shape(&self) -> (usize, usize) {
        (self.n, self.n)
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row `i`: its columns (ascending) and values; empty past the last row.
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        if i >= self.n {
            return (&[], &[]);
        }
        let range = self.row_start[i]..self.row_start[i + 1];
        (&self.cols[range.clone()], &self.values[range])
    }

    /// Entry (i, j): 0 off the pattern or out of range.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (cols, values) = self.row(i);
        cols.binary_search(&j).map_or(0.0, |k| values[k])
    }

    /// Every stored entry as (row, column, value), row by row.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.n).flat_map(move |i| {
            let (cols, values) = self.row(i);
            cols.iter().zip(values).map(move |(&j, &v)| (i, j, v))
        })
    }
}

impl std::ops::Index<(usize, usize)> for MassMatrix {
    type Output = f64;

    /// Entry (i, j), 0 off the pattern or out of range (as [`MassMatrix::get`]).
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        let (cols, values) = self.row(i);
        cols.binary_search(&j).map_or(&ZERO, |k| &values[k])
    }
}
