//! faer's sparse LU for the sizes where a dense factorisation no longer pays (violin beads,
//! long chains): the symbolic analysis (fill-reducing column ordering, elimination tree) is
//! done once per pattern, the numeric factorisation per matrix, in storage kept between
//! calls so that a frequency sweep does not allocate per point.

use faer::c64;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par};

use crate::DynamicsError;
use crate::lu::{Pivots, SymmetricSchedule, fill};

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

/// A complex symmetric matrix on a fixed sparse pattern (the dynamic stiffness of a large
/// block: violin beads, long chains), factorised per frequency as L D Lᵀ by a [`SymmetricSchedule`]
/// worked out once, in an approximate-minimum-degree order (faer's AMD on the pattern) that
/// keeps the fill along each fibre's chain of beads. The values are the lower triangle of
/// the permuted matrix with its fill, column by column. When partial pivoting would
/// exchange rows, the same values (both triangles) go to faer's sparse LU instead.
pub(crate) struct SymmetricSparse {
    /// The position in the elimination order of each unknown.
    order: Vec<usize>,
    /// Per column of the permuted lower triangle: where its entries start in the values
    /// (the diagonal first, then the rows below it ascending); one more at the end.
    col_start: Vec<usize>,
    /// The row of each stored entry.
    rows: Vec<usize>,
    schedule: SymmetricSchedule,
    /// The pivoting fallback over the unpermuted pattern, and for each of its entries the
    /// index of that entry (or its transpose) in the values.
    pivoting: SparseLu<c64>,
    gather: Vec<usize>,
    gathered: Vec<c64>,
    /// The right-hand side in elimination order.
    permuted: Vec<c64>,
    /// Whether the last factorisation was the pivoting one.
    pivoted: bool,
}

impl SymmetricSparse {
    /// Analyses the symmetric pattern given by `col_ptr` (n + 1 entries) and `row_idx` (rows
    /// ascending in each column, both triangles).
    pub(crate) fn new(col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Result<Self, DynamicsError> {
        let n = col_ptr.len().saturating_sub(1);
        let structure = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let (mut new_to_old, mut order) = (vec![0usize; n], vec![0usize; n]);
        let mut scratch = MemBuffer::new(amd::order_scratch::<usize>(n, row_idx.len()));
        amd::order(
            &mut new_to_old,
            &mut order,
            structure,
            Default::default(),
            MemStack::new(&mut scratch),
        )
        .map_err(|e| DynamicsError::Solver(format!("ordering: {e:?}")))?;
        let lower: Vec<Vec<usize>> = new_to_old
            .iter()
            .enumerate()
            .map(|(k, &old)| {
                let mut rows: Vec<usize> = row_idx[col_ptr[old]..col_ptr[old + 1]]
                    .iter()
                    .map(|&i| order[i])
                    .filter(|&i| i > k)
                    .collect();
                rows.sort_unstable();
                rows
            })
            .collect();
        let filled = fill(lower);
        let mut col_start = Vec::with_capacity(n + 1);
        let mut rows = Vec::new();
        for (j, below) in filled.iter().enumerate() {
            col_start.push(rows.len());
            rows.push(j);
            rows.extend(below);
        }
        col_start.push(rows.len());
        let position = |i: usize, j: usize| {
            let range = col_start[j]..col_start[j + 1];
            rows[range.clone()]
                .binary_search(&i)
                .map_or(usize::MAX, |k| range.start + k)
        };
        let schedule = SymmetricSchedule::from_filled(&filled, position);
        let gather = (0..n)
            .flat_map(|c| {
                row_idx[col_ptr[c]..col_ptr[c + 1]]
                    .iter()
                    .map(move |&r| (r, c))
            })
            .map(|(r, c)| {
                let (i, j) = (order[r], order[c]);
                position(i.max(j), i.min(j))
            })
            .collect::<Vec<_>>();
        let pivoting = SparseLu::new(col_ptr, row_idx)?;
        Ok(SymmetricSparse {
            order,
            gathered: vec![c64::new(0.0, 0.0); gather.len()],
            gather,
            col_start,
            rows,
            schedule,
            pivoting,
            permuted: vec![c64::new(0.0, 0.0); n],
            pivoted: false,
        })
    }

    /// Number of stored entries (the length of a values array).
    pub(crate) fn len(&self) -> usize {
        self.rows.len()
    }

    /// Index in the values of the entry (i, j) of the unpermuted matrix, if it is the one
    /// of (i, j) and (j, i) stored (the lower one after permutation); None for the other
    /// (the same value: the matrix is symmetric) and for entries not in the pattern.
    pub(crate) fn index(&self, i: usize, j: usize) -> Option<usize> {
        let (i, j) = (*self.order.get(i)?, *self.order.get(j)?);
        if i < j {
            return None;
        }
        let range = self.col_start[j]..self.col_start[j + 1];
        self.rows[range.clone()]
            .binary_search(&i)
            .ok()
            .map(|k| range.start + k)
    }

    /// Factorises the matrix with `values` in place by the schedule (see
    /// [`SymmetricSchedule::factor`]).
    pub(crate) fn factor(&mut self, values: &mut [c64]) -> Pivots {
        self.pivoted = false;
        self.schedule.factor(values)
    }

    /// Solves A x = b in place after a factorisation by the schedule that partial pivoting
    /// would have done otherwise, checked against the matrix `a` (its values before
    /// factorisation) and refined as [`SymmetricSchedule::solve_refined`] does; false when refused.
    pub(crate) fn solve_refined(&mut self, factors: &[c64], a: &[c64], b: &mut [c64]) -> bool {
        for (&k, &x) in self.order.iter().zip(b.iter()) {
            self.permuted[k] = x;
        }
        let accepted = self.schedule.solve_refined(factors, a, &mut self.permuted);
        for (&k, x) in self.order.iter().zip(b.iter_mut()) {
            *x = self.permuted[k];
        }
        accepted
    }

    /// Factorises the matrix with `values` (not factorised) by faer's pivoting sparse LU;
    /// false if that fails.
    pub(crate) fn factor_pivoting(&mut self, values: &[c64]) -> bool {
        for (g, &k) in self.gathered.iter_mut().zip(&self.gather) {
            *g = values[k];
        }
        self.pivoted = true;
        self.pivoting.factor(&self.gathered)
    }

    /// Solves A x = b in place with the last factorisation (`values` as it left them).
    pub(crate) fn solve(&mut self, values: &[c64], b: &mut [c64]) -> bool {
        if self.pivoted {
            return self.pivoting.solve(b);
        }
        for (&k, &x) in self.order.iter().zip(b.iter()) {
            self.permuted[k] = x;
        }
        self.schedule.solve(values, &mut self.permuted);
        for (&k, x) in self.order.iter().zip(b.iter_mut()) {
            *x = self.permuted[k];
        }
        true
    }

    /// Number of updates per factorisation by the schedule.
    #[cfg(test)]
    pub(crate) fn updates(&self) -> usize {
        self.schedule.updates()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two chains of `m` nodes each joining node 0 to node 1 (a ring, as a mass hanging by
    /// two beaded fibres): a complex symmetric matrix with diagonal `diag` and off-diagonal
    /// −1 + 0.05i, as compressed columns (both triangles) and a dense column-major copy.
    fn ring(m: usize, diag: f64) -> (Vec<usize>, Vec<usize>, Vec<c64>, Vec<c64>) {
        let n = 2 + 2 * m;
        let mut edges = Vec::new();
        for chain in 0..2 {
            let node = |k: usize| 2 + chain * m + k;
            edges.push((0, node(0)));
            edges.extend((1..m).map(|k| (node(k - 1), node(k))));
            edges.push((node(m - 1), 1));
        }
        let mut dense = vec![c64::new(0.0, 0.0); n * n];
        for k in 0..n {
            dense[k + k * n] = c64::new(diag + 0.01 * k as f64, 0.2);
        }
        for &(i, j) in &edges {
            dense[i + j * n] = c64::new(-1.0, 0.05);
            dense[j + i * n] = c64::new(-1.0, 0.05);
        }
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            for i in 0..n {
                if dense[i + j * n] != c64::new(0.0, 0.0) {
                    row_idx.push(i);
                    values.push(dense[i + j * n]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx, values, dense)
    }

    /// The values of `s` from the compressed columns: each symmetric pair stored once.
    fn stored(
        s: &SymmetricSparse,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[c64],
    ) -> Vec<c64> {
        let mut out = vec![c64::new(0.0, 0.0); s.len()];
        let mut once = 0;
        for j in 0..col_ptr.len() - 1 {
            for k in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[k];
                // exactly one of (i, j) and (j, i) has a place
                assert!(s.index(i, j).is_some() != s.index(j, i).is_some() || i == j);
                if let Some(at) = s.index(i, j) {
                    out[at] = values[k];
                    once += 1;
                }
            }
        }
        assert_eq!(once, (row_idx.len() + col_ptr.len() - 1) / 2);
        out
    }

    /// Solves by `s` (its schedule, refined when it says so, and its pivoting LU) and by the
    /// dense pivoting LU, and checks every solution against the chosen x.
    fn check(m: usize, diag: f64, pivots: Pivots) {
        let (col_ptr, row_idx, values, dense) = ring(m, diag);
        let n = col_ptr.len() - 1;
        let mut s = SymmetricSparse::new(col_ptr.clone(), row_idx.clone()).unwrap();
        let x: Vec<c64> = (0..n)
            .map(|i| c64::new(1.0 + i as f64, -0.5 * i as f64))
            .collect();
        let b: Vec<c64> = (0..n)
            .map(|i| (0..n).map(|j| dense[i + j * n] * x[j]).sum())
            .collect();
        let a = stored(&s, &col_ptr, &row_idx, &values);
        let mut factors = a.clone();
        assert_eq!(s.factor(&mut factors), pivots);
        let mut scheduled = b.clone();
        match pivots {
            Pivots::Kept => assert!(s.solve(&factors, &mut scheduled)),
            _ => assert!(s.solve_refined(&factors, &a, &mut scheduled)),
        }
        assert!(s.factor_pivoting(&a));
        let mut pivoted = b.clone();
        assert!(s.solve(&a, &mut pivoted));
        let (mut lu, mut pivots, mut dense_lu) = (dense, vec![0; n], b);
        assert!(crate::lu::factor(&mut lu, n, &mut pivots, &mut Vec::new()));
        crate::lu::solve(&lu, n, &pivots, &mut dense_lu);
        for (k, x) in x.iter().enumerate() {
            for (how, got) in [
                ("schedule", &scheduled),
                ("faer", &pivoted),
                ("dense", &dense_lu),
            ] {
                assert!(
                    (got[k] - x).norm() < 1e-12 * x.norm(),
                    "{how}: {} vs {x}",
                    got[k]
                );
            }
        }
    }

    #[test]
    fn solves_a_ring_of_chains_by_the_schedule() {
        // diagonal 4 against at most three off-diagonal entries of size ~1: partial
        // pivoting keeps every pivot, the condition number is below 10, and every solver
        // recovers x to rounding; 1e-12 relative leaves room for the 42 unknowns' sums
        check(20, 4.0, Pivots::Kept);
        let (col_ptr, row_idx, ..) = ring(20, 4.0);
        let s = SymmetricSparse::new(col_ptr, row_idx).unwrap();
        // the minimum-degree order keeps the fill along the chains: a ring of n nodes
        // eliminated along it needs 3 updates per node (two neighbours) and a fixed number
        // more where the chains meet, against n³/6 for a dense block
        assert!(s.updates() < 6 * 42, "{} updates", s.updates());
    }

    #[test]
    fn a_pivot_partial_pivoting_would_exchange_is_refined_and_checked() {
        // a diagonal of 0.5 under off-diagonal entries of size 1: partial pivoting would
        // exchange the first rows, the schedule does not and says so; the residual check
        // with refinement, faer's pivoting LU and the dense LU all recover x (the condition
        // number is about 10 here: the imaginary 0.2 on the diagonal keeps it off singular)
        check(3, 0.5, Pivots::Exceeded);
    }
}
