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
