//! A small dense complex LU with partial pivoting that works in caller-owned storage, for
//! the exactly decoupled blocks of a suspension (8 unknowns for the quad's x–pitch block):
//! at these sizes a general library call costs more in setup than the arithmetic, and a
//! frequency sweep must not allocate per point.

use faer::c64;

/// Factorises the n × n matrix stored column-major in `a` in place (L below the diagonal
/// with unit diagonal, U on and above it), recording in `pivots[k]` the row swapped with
/// row k. Returns false if a pivot is exactly zero (the matrix is singular).
pub(crate) fn factor(a: &mut [c64], n: usize, pivots: &mut [usize]) -> bool {
    debug_assert!(a.len() >= n * n && pivots.len() >= n);
    for k in 0..n {
        // pivot: the largest |a_ik| in column k at or below the diagonal
        let column = &a[k * n..(k + 1) * n];
        let mut p = k;
        let mut best = column[k].norm_sqr();
        for (i, x) in column.iter().enumerate().skip(k + 1) {
            let size = x.norm_sqr();
            if size > best {
                best = size;
                p = i;
            }
        }
        pivots[k] = p;
        if best == 0.0 || !best.is_finite() {
            return false;
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        // the multipliers l_ik end at the column's last non-zero: a suspension's blocks are
        // banded (each stage couples to its neighbours), and skipping exact zeros changes
        // no value, only the work (about n b² instead of n³/3 for bandwidth b)
        let below = &a[k * n + k + 1..(k + 1) * n];
        let rows = below
            .iter()
            .rposition(|x| *x != c64::new(0.0, 0.0))
            .map_or(0, |last| last + 1);
        let inv = a[k * n + k].inv();
        for x in &mut a[k * n + k + 1..k * n + k + 1 + rows] {
            *x *= inv;
        }
        // trailing update, column by column: a_ij −= l_ik u_kj
        let (left, right) = a.split_at_mut((k + 1) * n);
        let l = &left[k * n + k + 1..k * n + k + 1 + rows];
        for column in right.chunks_exact_mut(n) {
            let u_kj = column[k];
            if u_kj == c64::new(0.0, 0.0) {
                continue;
            }
            for (x, &l_ik) in column[k + 1..].iter_mut().zip(l) {
                *x -= l_ik * u_kj;
            }
        }
    }
    true
}

/// Solves A x = b in place with the factors from [`factor`].
pub(crate) fn solve(a: &[c64], n: usize, pivots: &[usize], b: &mut [c64]) {
    for (k, &p) in pivots.iter().enumerate().take(n) {
        b.swap(k, p);
    }
    // L y = P b (unit lower triangular), column-oriented
    for k in 0..n {
        let y = b[k];
        if y == c64::new(0.0, 0.0) {
            continue;
        }
        for (x, &l) in b[k + 1..n].iter_mut().zip(&a[k * n + k + 1..(k + 1) * n]) {
            *x -= l * y;
        }
    }
    // U x = y, column-oriented from the last column
    for k in (0..n).rev() {
        b[k] /= a[k * n + k];
        let x_k = b[k];
        if x_k == c64::new(0.0, 0.0) {
            continue;
        }
        for (x, &u) in b[..k].iter_mut().zip(&a[k * n..k * n + k]) {
            *x -= u * x_k;
        }
    }
}

/// The elimination of one fixed sparsity pattern without row exchanges, worked out once:
/// for each step k the stored entries below the diagonal (the multipliers l_ik), the
/// trailing updates a_ij −= l_ik u_kj that are not exactly zero by structure (the fill
/// included), and for the back substitution the entries above the diagonal. A sweep solves
/// the same pattern at every frequency, so the per-point factorisation only walks these
/// lists instead of testing every entry of the dense block for zero.
///
/// [`Schedule::factor`] performs exactly the operations of [`factor`], in the same order per
/// entry, whenever partial pivoting would keep every diagonal pivot (it checks that, on the
/// stored entries: the others are exact zeros and cannot be larger), so the factors are
/// the same numbers; when a row exchange would be needed it reports so and leaves `a`
/// partly eliminated, and the caller refactorises a fresh copy with [`factor`].
#[derive(Clone, Debug)]
pub(crate) struct Schedule {
    n: usize,
    /// Per step k: its range in `below` and in `updates`.
    steps: Vec<(std::ops::Range<usize>, std::ops::Range<usize>)>,
    /// (row i, index of l_ik) of the stored entries below the diagonal, step by step.
    below: Vec<(usize, usize)>,
    /// (index of a_ij, index of l_ik, index of u_kj), step by step.
    updates: Vec<(usize, usize, usize)>,
    /// Per column k: (row i, index of u_ik) of the stored entries above the diagonal.
    above: Vec<Vec<(usize, usize)>>,
}

impl Schedule {
    /// The schedule of an n × n column-major matrix whose entry at index `i + j n` may be
    /// non-zero where `stored[i + j n]` (the diagonal always counts as stored).
    pub(crate) fn new(n: usize, stored: &[bool]) -> Self {
        let mut s: Vec<bool> = (0..n * n)
            .map(|idx| stored.get(idx).copied().unwrap_or(false) || idx % n == idx / n)
            .collect();
        let (mut steps, mut below, mut updates) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            let rows: Vec<usize> = (k + 1..n).filter(|&i| s[i + k * n]).collect();
            let cols: Vec<usize> = (k + 1..n).filter(|&j| s[k + j * n]).collect();
            let (b0, u0) = (below.len(), updates.len());
            below.extend(rows.iter().map(|&i| (i, i + k * n)));
            for &j in &cols {
                for &i in &rows {
                    s[i + j * n] = true;
                    updates.push((i + j * n, i + k * n, k + j * n));
                }
            }
            steps.push((b0..below.len(), u0..updates.len()));
        }
        let above = (0..n)
            .map(|k| {
                (0..k)
                    .filter(|&i| s[i + k * n])
                    .map(|i| (i, i + k * n))
                    .collect()
            })
            .collect();
        Schedule {
            n,
            steps,
            below,
            updates,
            above,
        }
    }

    /// Number of unknowns.
    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// Factorises `a` in place as [`factor`] does when it exchanges no rows. False when a
    /// row exchange is needed or a pivot is zero (then `a` is spoilt: factorise a fresh copy
    /// with [`factor`], which also reports a singular matrix).
    pub(crate) fn factor(&self, a: &mut [c64]) -> bool {
        let n = self.n;
        for (k, (below, updates)) in self.steps.iter().enumerate() {
            let pivot = a[k * n + k];
            let size = pivot.norm_sqr();
            if size == 0.0 || !size.is_finite() {
                return false;
            }
            let below = &self.below[below.clone()];
            if below.iter().any(|&(_, idx)| a[idx].norm_sqr() > size) {
                return false;
            }
            let inv = pivot.inv();
            for &(_, idx) in below {
                a[idx] *= inv;
            }
            for &(target, l, u) in &self.updates[updates.clone()] {
                let update = a[l] * a[u];
                a[target] -= update;
            }
        }
        true
    }

    /// Solves A x = b in place with the factors from [`Schedule::factor`] (no row exchanges),
    /// the operations of [`solve`] in the same order per entry.
    pub(crate) fn solve(&self, a: &[c64], b: &mut [c64]) {
        let n = self.n;
        for (k, (below, _)) in self.steps.iter().enumerate() {
            let y = b[k];
            if y == c64::new(0.0, 0.0) {
                continue;
            }
            for &(i, idx) in &self.below[below.clone()] {
                b[i] -= a[idx] * y;
            }
        }
        for k in (0..n).rev() {
            b[k] /= a[k * n + k];
            let x_k = b[k];
            if x_k == c64::new(0.0, 0.0) {
                continue;
            }
            for &(i, idx) in &self.above[k] {
                b[i] -= a[idx] * x_k;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_complex_system() {
        // A x = b with a zero leading entry (needs a row swap) and a known solution x
        let n = 3;
        let rows = [
            [c64::new(0.0, 0.0), c64::new(2.0, 1.0), c64::new(1.0, 0.0)],
            [c64::new(4.0, -1.0), c64::new(1.0, 0.0), c64::new(0.0, 2.0)],
            [c64::new(1.0, 0.0), c64::new(-3.0, 0.5), c64::new(5.0, 0.0)],
        ];
        let x = [c64::new(1.0, 2.0), c64::new(-0.5, 0.0), c64::new(0.0, -3.0)];
        let mut b: Vec<c64> = rows
            .iter()
            .map(|r| r.iter().zip(&x).map(|(a, x)| a * x).sum())
            .collect();
        let mut a: Vec<c64> = (0..n * n).map(|k| rows[k % n][k / n]).collect();
        let mut pivots = [0; 3];
        assert!(factor(&mut a, n, &mut pivots));
        solve(&a, n, &pivots, &mut b);
        for (got, want) in b.iter().zip(&x) {
            assert!((got - want).norm() < 1e-14, "{got} vs {want}");
        }
    }

    /// A banded complex n × n matrix (bandwidth 2, column-major) with a dominant diagonal
    /// unless `swap_first` makes row 1 dominate column 0.
    fn banded(n: usize, swap_first: bool) -> (Vec<c64>, Vec<bool>) {
        let mut a = vec![c64::new(0.0, 0.0); n * n];
        for j in 0..n {
            for i in j.saturating_sub(2)..(j + 3).min(n) {
                let d = i.abs_diff(j) as f64;
                a[i + j * n] = if i == j {
                    c64::new(10.0 + i as f64, 0.3)
                } else {
                    c64::new(-1.0 / (1.0 + d + 0.1 * (i + j) as f64), 0.01 * d)
                };
            }
        }
        if swap_first {
            a[1] = c64::new(50.0, 1.0);
        }
        let stored = a.iter().map(|x| *x != c64::new(0.0, 0.0)).collect();
        (a, stored)
    }

    #[test]
    fn the_schedule_gives_the_same_numbers_as_the_pivoting_lu() {
        // without row exchanges the scheduled elimination performs the same operations on
        // every entry, so factors and solution are equal bit for bit (tolerance zero)
        let n = 9;
        let (a, stored) = banded(n, false);
        let schedule = Schedule::new(n, &stored);
        let (mut dense, mut scheduled) = (a.clone(), a.clone());
        let mut pivots = vec![0; n];
        assert!(factor(&mut dense, n, &mut pivots));
        assert!(pivots.iter().enumerate().all(|(k, &p)| k == p));
        assert!(schedule.factor(&mut scheduled));
        assert_eq!(dense, scheduled);
        let rhs: Vec<c64> = (0..n).map(|i| c64::new(i as f64 - 3.0, 1.0)).collect();
        let (mut x, mut y) = (rhs.clone(), rhs);
        solve(&dense, n, &pivots, &mut x);
        schedule.solve(&scheduled, &mut y);
        assert_eq!(x, y);
    }

    #[test]
    fn the_schedule_refuses_when_a_row_exchange_is_needed() {
        // row 1 outweighs the first pivot: partial pivoting exchanges rows, the schedule
        // says it cannot, and the pivoting LU still solves the system
        let n = 6;
        let (a, stored) = banded(n, true);
        let schedule = Schedule::new(n, &stored);
        assert!(!schedule.factor(&mut a.clone()));
        let mut pivots = vec![0; n];
        let mut f = a.clone();
        assert!(factor(&mut f, n, &mut pivots));
        assert_eq!(pivots[0], 1);
    }

    #[test]
    fn a_singular_matrix_is_refused() {
        let mut a = vec![
            c64::new(1.0, 0.0),
            c64::new(2.0, 0.0),
            c64::new(2.0, 0.0),
            c64::new(4.0, 0.0),
        ];
        assert!(!factor(&mut a, 2, &mut [0; 2]));
    }
}
