//! A small dense complex LU with partial pivoting that works in caller-owned storage, for
//! the exactly decoupled blocks of a suspension (8 unknowns for the quad's x–pitch block):
//! at these sizes a general library call costs more in setup than the arithmetic, and a
//! frequency sweep must not allocate per point.

use faer::c64;

/// Factorises the n × n matrix stored column-major in `a` in place (L below the diagonal
/// with unit diagonal, U on and above it), recording in `pivots[k]` the row swapped with
/// row k; `rows` is scratch (its allocation is kept for the next call). Returns false if a
/// pivot is exactly zero (the matrix is singular).
pub(crate) fn factor(a: &mut [c64], n: usize, pivots: &mut [usize], rows: &mut Vec<usize>) -> bool {
    debug_assert!(a.len() >= n * n && pivots.len() >= n);
    let zero = c64::new(0.0, 0.0);
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
        // the multipliers l_ik, only where they are not exact zeros: a suspension's blocks
        // are sparse (each stage couples to its neighbours, the floats to a few rows), and
        // an update by a zero l_ik leaves its entry as it was, so skipping those changes no
        // value, only the work (the rows that are left stay in ascending order, so every
        // entry sees the same operations in the same order as a dense elimination)
        let inv = a[k * n + k].inv();
        rows.clear();
        for (i, x) in a[k * n..(k + 1) * n].iter_mut().enumerate().skip(k + 1) {
            if *x != zero {
                *x *= inv;
                rows.push(i);
            }
        }
        // trailing update, column by column: a_ij −= l_ik u_kj
        let (left, right) = a.split_at_mut((k + 1) * n);
        let l = &left[k * n..(k + 1) * n];
        for column in right.chunks_exact_mut(n) {
            let u_kj = column[k];
            if u_kj == zero {
                continue;
            }
            for &i in rows.iter() {
                column[i] -= l[i] * u_kj;
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
    // L y = P b (unit lower triangular), column-oriented; a zero l_ik or u_ik changes
    // nothing ([`factor`] leaves most of them zero), so it is skipped
    let zero = c64::new(0.0, 0.0);
    for k in 0..n {
        let y = b[k];
        if y == zero {
            continue;
        }
        for (x, &l) in b[k + 1..n].iter_mut().zip(&a[k * n + k + 1..(k + 1) * n]) {
            if l != zero {
                *x -= l * y;
            }
        }
    }
    // U x = y, column-oriented from the last column
    for k in (0..n).rev() {
        b[k] /= a[k * n + k];
        let x_k = b[k];
        if x_k == zero {
            continue;
        }
        for (x, &u) in b[..k].iter_mut().zip(&a[k * n..k * n + k]) {
            if u != zero {
                *x -= u * x_k;
            }
        }
    }
}

/// The elimination of one fixed sparsity pattern without row exchanges, worked out once:
/// for each step k the stored entries below the diagonal (the multipliers l_ik) and the
/// columns of the stored entries u_kj right of it, whose products are the trailing updates
/// a_ij −= l_ik u_kj that are not exactly zero by structure (the fill included), and for
/// the back substitution the entries above the diagonal. A sweep solves the same pattern
/// at every frequency, so the per-point factorisation only walks these lists instead of
/// testing every entry of the dense block for zero.
///
/// [`Schedule::factor`] performs exactly the operations of [`factor`], in the same order per
/// entry, whenever partial pivoting would keep every diagonal pivot (it checks that, on the
/// stored entries: the others are exact zeros and cannot be larger), so the factors are
/// the same numbers; when a row exchange would be needed it reports so and leaves `a`
/// partly eliminated, and the caller refactorises a fresh copy with [`factor`].
#[derive(Clone, Debug)]
pub(crate) struct Schedule {
    n: usize,
    /// Per step k: its range in `below` and in `columns`.
    steps: Vec<(std::ops::Range<usize>, std::ops::Range<usize>)>,
    /// (row i, index of l_ik) of the stored entries below the diagonal, step by step.
    below: Vec<(usize, usize)>,
    /// The columns j > k of the stored entries u_kj, step by step: step k updates
    /// a_ij −= l_ik u_kj for each of them and each row i of its `below`, in that order.
    columns: Vec<usize>,
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
        let (mut steps, mut below, mut columns) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            let rows: Vec<usize> = (k + 1..n).filter(|&i| s[i + k * n]).collect();
            let cols: Vec<usize> = (k + 1..n).filter(|&j| s[k + j * n]).collect();
            let (b0, c0) = (below.len(), columns.len());
            below.extend(rows.iter().map(|&i| (i, i + k * n)));
            // the fill: the entries this step updates are stored from now on
            for &j in &cols {
                for &i in &rows {
                    s[i + j * n] = true;
                }
            }
            columns.extend_from_slice(&cols);
            steps.push((b0..below.len(), c0..columns.len()));
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
            columns,
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
        for (k, (below, columns)) in self.steps.iter().enumerate() {
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
            // column by column (u_kj is in a row step k does not change), the rows as stored
            let (left, right) = a.split_at_mut((k + 1) * n);
            let l = &left[k * n..];
            for &j in &self.columns[columns.clone()] {
                let column = &mut right[(j - k - 1) * n..(j - k) * n];
                let u_kj = column[k];
                for &(i, _) in below {
                    column[i] -= l[i] * u_kj;
                }
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

/// The elimination of one fixed, structurally symmetric pattern of a complex symmetric
/// matrix (A = Aᵀ without conjugation, as the dynamic stiffness E(f) = P(f) − ω² M is),
/// worked out once: A = L D Lᵀ with L unit lower triangular and no row exchanges. Step k
/// lists the entries of column k of L below the diagonal (the pattern's and the fill) and
/// the indices of the lower-triangle entries it updates, a_ij −= l_ik a_jk for every i ≥ j
/// of that column. Only the lower triangle is read or written: half the arithmetic of an
/// LU. A sweep solves the same pattern at every frequency, so the factorisation per point
/// only walks these lists, in storage the caller lays out ([`SymmetricSchedule::from_filled`]).
///
/// [`SymmetricSchedule::factor`] checks at each step whether partial pivoting would keep
/// the diagonal pivot (no stored entry below it is larger in magnitude; the others are exact
/// zeros). If it would at every step, the elimination is the one a partial-pivoting LU
/// performs on the same matrix in the same order, up to rounding (U = D Lᵀ), with the same
/// backward stability ([`Pivots::Kept`]). If not, the factorisation goes on and says so
/// ([`Pivots::Exceeded`]): [`SymmetricSchedule::solve_refined`] then checks the solution by
/// its residual and refines it, and the caller uses a pivoting LU when that is refused.
///
/// The dense blocks (the quad's x–pitch block) keep the LU [`Schedule`]: it performs the
/// operations of the pivoting LU [`factor`] exactly, whereas L D Lᵀ, though as accurate,
/// rounds differently, and on a point output of the quad at 0.77 Hz (where E(f) amplifies
/// rounding by ~1e3) that moved the noise by 1.03e-12 of the reference, over the 1e-12 that
/// tests/fast_responses.rs allows.
#[derive(Clone, Debug)]
pub(crate) struct SymmetricSchedule {
    steps: Vec<Step>,
    /// (row i, index of a_ik) of the entries below the diagonal, step by step, i ascending.
    below: Vec<(usize, usize)>,
    /// The entries each step updates, step by step: for the rows r_0 < r_1 < … of the
    /// step's column, for p = 0, 1, …, the indices of (r_q, r_p) for q = p, p + 1, ….
    targets: Vec<usize>,
    /// The step's column before scaling (a_ik) and after (l_ik = a_ik / a_kk).
    column: Vec<c64>,
    scaled: Vec<c64>,
    /// The right-hand side and the residual of [`SymmetricSchedule::solve_refined`].
    rhs: Vec<c64>,
    residual: Vec<c64>,
    scale: Vec<f64>,
}

/// How a factorisation by a [`SymmetricSchedule`] went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pivots {
    /// Partial pivoting would have kept every pivot: the factors are those of a pivoting
    /// LU, up to rounding, and as backward stable.
    Kept,
    /// Some entry below a pivot was larger than it: solve with
    /// [`SymmetricSchedule::solve_refined`], which checks the result.
    Exceeded,
    /// A pivot was zero or not finite.
    Failed,
}

/// Largest componentwise backward error accepted from a factorisation without row
/// exchanges ([`SymmetricSchedule::solve_refined`]): a few units of rounding, what a backward-stable
/// solve gives.
pub(crate) const BACKWARD_ERROR: f64 = 4.0 * f64::EPSILON;

/// Most steps of iterative refinement tried before a pivoting LU is used instead.
pub(crate) const REFINEMENTS: usize = 2;

/// One step of a [`SymmetricSchedule`].
#[derive(Clone, Debug)]
struct Step {
    /// Index of the pivot a_kk.
    diag: usize,
    /// Its entries in `below`.
    below: std::ops::Range<usize>,
    /// Where its entries of `targets` start.
    targets: usize,
}

impl SymmetricSchedule {
    /// The schedule of the factor whose columns hold below the diagonal the rows `filled`
    /// (as [`fill`] gives them), with entry (i, j), i ≥ j, of the lower triangle at
    /// `index(i, j)` in the values. `index` is called once per stored entry of the factor.
    pub(crate) fn from_filled(
        filled: &[Vec<usize>],
        index: impl Fn(usize, usize) -> usize,
    ) -> Self {
        let n = filled.len();
        let mut steps = Vec::with_capacity(n);
        let mut below = Vec::new();
        let mut len = 0;
        for (k, rows) in filled.iter().enumerate() {
            let start = below.len();
            below.extend(rows.iter().map(|&i| (i, index(i, k))));
            steps.push(Step {
                diag: index(k, k),
                below: start..below.len(),
                targets: len,
            });
            len += rows.len() * (rows.len() + 1) / 2;
        }
        // column by column: the indices of column j's entries, then every step k whose
        // column holds row j writes its updates of column j (rows j and below); j comes in
        // ascending order, so it is the next row of each such column
        let mut steps_at_row: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (k, rows) in filled.iter().enumerate() {
            for &i in rows {
                steps_at_row[i].push(k);
            }
        }
        let mut targets = vec![0; len];
        let mut next = vec![0; n];
        let mut at = vec![0; n];
        for (j, steps_j) in steps_at_row.iter().enumerate() {
            at[j] = index(j, j);
            for &i in &filled[j] {
                at[i] = index(i, j);
            }
            for &k in steps_j {
                let rows = &filled[k];
                let (p, r) = (next[k], rows.len());
                next[k] += 1;
                debug_assert_eq!(rows[p], j);
                // the updates of the columns r_0 … r_(p−1) come first
                let start = steps[k].targets + p * r - p * p.saturating_sub(1) / 2;
                for (t, &i) in targets[start..].iter_mut().zip(&rows[p..]) {
                    *t = at[i];
                }
            }
        }
        let widest = filled.iter().map(Vec::len).max().unwrap_or(0);
        SymmetricSchedule {
            steps,
            below,
            targets,
            column: vec![c64::new(0.0, 0.0); widest],
            scaled: vec![c64::new(0.0, 0.0); widest],
            rhs: Vec::new(),
            residual: Vec::new(),
            scale: Vec::new(),
        }
    }

    /// Number of updates a_ij −= l_ik a_jk per factorisation (the arithmetic's measure).
    #[cfg(test)]
    pub(crate) fn updates(&self) -> usize {
        self.targets.len()
    }

    /// Factorises `a` in place as L D Lᵀ (D on the diagonal, L below it, the upper triangle
    /// untouched), and says whether partial pivoting would have kept every pivot. A zero or
    /// non-finite pivot stops it ([`Pivots::Failed`]: `a` is spoilt, factorise a fresh copy
    /// with a pivoting LU, which also reports a singular matrix).
    pub(crate) fn factor(&mut self, a: &mut [c64]) -> Pivots {
        let SymmetricSchedule {
            steps,
            below,
            targets,
            column,
            scaled,
            ..
        } = self;
        let mut pivots = Pivots::Kept;
        for step in steps.iter() {
            let pivot = a[step.diag];
            let size = pivot.norm_sqr();
            if size == 0.0 || !size.is_finite() {
                return Pivots::Failed;
            }
            let below = &below[step.below.clone()];
            let r = below.len();
            for (c, &(_, idx)) in column.iter_mut().zip(below) {
                *c = a[idx];
                if c.norm_sqr() > size {
                    pivots = Pivots::Exceeded;
                }
            }
            let inv = pivot.inv();
            for ((s, c), &(_, idx)) in scaled.iter_mut().zip(column.iter()).zip(below) {
                *s = c * inv;
                a[idx] = *s;
            }
            let mut t = step.targets;
            for p in 0..r {
                let u = column[p];
                let entries = &targets[t..t + r - p];
                t += r - p;
                if u == c64::new(0.0, 0.0) {
                    continue;
                }
                for (&target, &l) in entries.iter().zip(&scaled[p..r]) {
                    a[target] -= l * u;
                }
            }
        }
        pivots
    }

    /// Solves A x = b in place (`x` holds b on entry) by the factors `factors` of a
    /// factorisation that exchanged no rows although partial pivoting would have
    /// ([`Pivots::Exceeded`]), made as accurate as a pivoting LU's or refused: the residual
    /// r = b − A x is computed with the matrix `a` itself, and while the componentwise
    /// backward error max_i |r_i| / (|A| |x| + |b|)_i is above [`BACKWARD_ERROR`] a step of
    /// iterative refinement (x += A⁻¹ r with the same factors) follows, at most
    /// [`REFINEMENTS`] of them (Higham, Accuracy and Stability of Numerical Algorithms,
    /// §7.1 and ch. 12: one step in working precision already makes the solution
    /// componentwise backward stable unless the factors are very poor). False (x spoilt)
    /// when the error stays above: the caller solves by a pivoting LU instead.
    pub(crate) fn solve_refined(&mut self, factors: &[c64], a: &[c64], x: &mut [c64]) -> bool {
        let mut b = std::mem::take(&mut self.rhs);
        let mut r = std::mem::take(&mut self.residual);
        let mut scale = std::mem::take(&mut self.scale);
        b.clear();
        b.extend_from_slice(x);
        r.resize(x.len(), c64::new(0.0, 0.0));
        self.solve(factors, x);
        let mut accepted = false;
        for step in 0..=REFINEMENTS {
            let error = self.backward_error(a, x, &b, &mut r, &mut scale);
            if error <= BACKWARD_ERROR {
                accepted = true;
                break;
            }
            if step < REFINEMENTS {
                self.solve(factors, &mut r);
                for (x, d) in x.iter_mut().zip(&r) {
                    *x += d;
                }
            }
        }
        (self.rhs, self.residual, self.scale) = (b, r, scale);
        accepted
    }

    /// The residual r = b − A x into `r` and the componentwise backward error of x,
    /// max_i |r_i| / (|A| |x| + |b|)_i, with A given by its lower triangle in `a` (the
    /// layout of the schedule; the fill entries are zero there) and |z| = |Re z| + |Im z|.
    fn backward_error(
        &self,
        a: &[c64],
        x: &[c64],
        b: &[c64],
        r: &mut [c64],
        scale: &mut Vec<f64>,
    ) -> f64 {
        let abs = |z: c64| z.re.abs() + z.im.abs();
        scale.clear();
        scale.extend(b.iter().map(|&b| abs(b)));
        r.copy_from_slice(b);
        for (k, step) in self.steps.iter().enumerate() {
            let d = a[step.diag];
            r[k] -= d * x[k];
            scale[k] += abs(d) * abs(x[k]);
            for &(i, idx) in &self.below[step.below.clone()] {
                let v = a[idx];
                r[i] -= v * x[k];
                r[k] -= v * x[i];
                scale[i] += abs(v) * abs(x[k]);
                scale[k] += abs(v) * abs(x[i]);
            }
        }
        r.iter()
            .zip(scale.iter())
            .map(|(&r, &s)| {
                if s > 0.0 {
                    abs(r) / s
                } else if abs(r) > 0.0 {
                    f64::INFINITY
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max)
    }

    /// Solves A x = b in place with the factors from [`SymmetricSchedule::factor`].
    pub(crate) fn solve(&self, a: &[c64], b: &mut [c64]) {
        // L y = b, column by column
        for (k, step) in self.steps.iter().enumerate() {
            let y = b[k];
            if y == c64::new(0.0, 0.0) {
                continue;
            }
            for &(i, idx) in &self.below[step.below.clone()] {
                b[i] -= a[idx] * y;
            }
        }
        // Lᵀ x = D⁻¹ y, row by row from the last
        for (k, step) in self.steps.iter().enumerate().rev() {
            let mut x = b[k] / a[step.diag];
            for &(i, idx) in &self.below[step.below.clone()] {
                x -= a[idx] * b[i];
            }
            b[k] = x;
        }
    }
}

/// The rows below the diagonal of each column of L in A = L D Lᵀ, for a structurally
/// symmetric A whose column k has below the diagonal the rows `lower[k]` (ascending): its
/// own rows and the fill. Column k of L holds A's rows and those of every column c whose
/// first row below the diagonal (its parent in the elimination tree) is k, less k itself;
/// one merge per column.
pub(crate) fn fill(lower: Vec<Vec<usize>>) -> Vec<Vec<usize>> {
    let n = lower.len();
    let mut from_children: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut filled = Vec::with_capacity(n);
    for (k, own) in lower.into_iter().enumerate() {
        let column = union(&own, &std::mem::take(&mut from_children[k]));
        if let Some((&parent, rest)) = column.split_first() {
            from_children[parent] = union(&from_children[parent], rest);
        }
        filled.push(column);
    }
    filled
}

/// The union of two ascending lists, ascending and without repeats.
fn union(a: &[usize], b: &[usize]) -> Vec<usize> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x == y => {
                i += 1;
                j += 1;
                x
            }
            (Some(&x), Some(&y)) if x < y => {
                i += 1;
                x
            }
            (_, Some(&y)) => {
                j += 1;
                y
            }
            (Some(&x), None) => {
                i += 1;
                x
            }
            (None, None) => break,
        };
        out.push(next);
    }
    out
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
        assert!(factor(&mut a, n, &mut pivots, &mut Vec::new()));
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
        assert!(factor(&mut dense, n, &mut pivots, &mut Vec::new()));
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
        assert!(factor(&mut f, n, &mut pivots, &mut Vec::new()));
        assert_eq!(pivots[0], 1);
    }

    /// The textbook partial-pivoting LU, every entry updated (zeros too): the reference
    /// that [`factor`], which skips the updates by exact zeros, must equal bit for bit.
    fn textbook_lu(a: &mut [c64], n: usize) -> Vec<usize> {
        let mut pivots = vec![0; n];
        for k in 0..n {
            let p = (k..n)
                .reduce(|p, i| {
                    if a[i + k * n].norm_sqr() > a[p + k * n].norm_sqr() {
                        i
                    } else {
                        p
                    }
                })
                .unwrap();
            pivots[k] = p;
            for j in 0..n {
                a.swap(k + j * n, p + j * n);
            }
            let inv = a[k + k * n].inv();
            for i in k + 1..n {
                a[i + k * n] *= inv;
            }
            for j in k + 1..n {
                for i in k + 1..n {
                    let update = a[i + k * n] * a[k + j * n];
                    a[i + j * n] -= update;
                }
            }
        }
        pivots
    }

    #[test]
    fn skipping_exact_zeros_changes_no_number() {
        // a banded matrix with a dominant off-band row (row exchanges at the first steps)
        // and a dense last row and column (a float coupled to everything, as in the quad):
        // factors, pivots and solution equal the textbook LU's bit for bit (tolerance zero;
        // an update by an exact zero leaves its entry as it was, so only the work differs)
        let n = 12;
        let (mut a, _) = banded(n, true);
        for k in 0..n - 1 {
            let v = c64::new(0.3 + 0.1 * k as f64, -0.02 * k as f64);
            a[(n - 1) + k * n] = v;
            a[k + (n - 1) * n] = v;
        }
        a[3 + 5 * n] = c64::new(80.0, -2.0);
        let (mut skipped, mut textbook) = (a.clone(), a);
        let mut pivots = vec![0; n];
        assert!(factor(&mut skipped, n, &mut pivots, &mut Vec::new()));
        let reference = textbook_lu(&mut textbook, n);
        assert_eq!(pivots, reference);
        assert!(pivots.iter().enumerate().any(|(k, &p)| k != p));
        // == on each part: equal numbers, a zero of either sign equal to a zero
        assert_eq!(skipped, textbook);
        let rhs: Vec<c64> = (0..n).map(|i| c64::new(1.0 - i as f64, 0.5)).collect();
        let mut x = rhs.clone();
        solve(&skipped, n, &pivots, &mut x);
        // the textbook substitutions, every entry
        let mut y = rhs;
        for (k, &p) in reference.iter().enumerate() {
            y.swap(k, p);
        }
        for k in 0..n {
            for i in k + 1..n {
                let update = textbook[i + k * n] * y[k];
                y[i] -= update;
            }
        }
        for k in (0..n).rev() {
            y[k] /= textbook[k + k * n];
            for i in 0..k {
                let update = textbook[i + k * n] * y[k];
                y[i] -= update;
            }
        }
        assert_eq!(x, y);
    }

    #[test]
    fn the_fill_follows_the_elimination_tree() {
        // a ring 0–1–2–3–0 eliminated in order: removing 0 joins 1 and 3, removing 1 then
        // joins 2 and 3 (already joined); by hand, L has rows {1, 3}, {2, 3}, {3}, {}
        let lower = vec![vec![1, 3], vec![2], vec![3], vec![]];
        assert_eq!(fill(lower), vec![vec![1, 3], vec![2, 3], vec![3], vec![]]);
        // an arrow pointing at 0 (0 coupled to all) fills everything below it
        let arrow = vec![vec![1, 2, 3], vec![], vec![], vec![]];
        assert_eq!(
            fill(arrow),
            vec![vec![1, 2, 3], vec![2, 3], vec![3], vec![]]
        );
        assert_eq!(union(&[1, 4, 6], &[2, 4, 7]), vec![1, 2, 4, 6, 7]);
    }

    #[test]
    fn a_singular_matrix_is_refused() {
        let mut a = vec![
            c64::new(1.0, 0.0),
            c64::new(2.0, 0.0),
            c64::new(2.0, 0.0),
            c64::new(4.0, 0.0),
        ];
        assert!(!factor(&mut a, 2, &mut [0; 2], &mut Vec::new()));
    }
}
