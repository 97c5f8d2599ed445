//! Normal modes: the generalised symmetric eigenproblem K_eff v = ω² M v, solved block by
//! block over the exactly decoupled blocks of K_eff and M (their exact zeros: the quad's
//! x–pitch, y–z–roll and yaw blocks, or the identical stages of a chain), with labels, the
//! kinetic-energy fractions, and a lab-frame table of body motions.

use faer::{Mat, Side};
use nalgebra::{DMatrix, Vector3};
use pendkit_assembly::Layout;
use pendkit_rotations::lab_yaw_pitch_roll;
use pendkit_system::{CoordKind, Damping, System};

use crate::pattern::dense_components;
use crate::{DynamicsError, StageModel};

/// One normal mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// Eigenvalue ω² (rad²/s²); negative for an unstable mode, exactly zero for a neutral
    /// one (|ω²| within its estimated error, [`Mode::omega_squared_error`]).
    pub omega_squared: f64,
    /// Frequency (Hz); for an unstable mode, minus the growth rate sqrt(-ω²)/2π.
    pub hz: f64,
    /// Dominant coordinate by kinetic-energy fraction.
    pub label: String,
    /// Mass-normalised eigenvector over the variables (vᵀ M v = 1).
    pub vector: Vec<f64>,
    /// Kinetic-energy fraction per variable, v_i (M v)_i (sums to 1).
    pub energy_fractions: Vec<f64>,
    /// Estimated error of `omega_squared` (rad²/s², absolute): the eigensolver's own
    /// resolution of this mode (set by the ratio of this mode's ω² to the ones its method
    /// resolves best) plus the first-order effect of rounding the stiffness and mass
    /// matrices' entries (set by the stiffness and mass ratios of the parts this mode moves).
    /// See [`Mode::accuracy`].
    pub omega_squared_error: f64,
    /// Estimated error of the mode shape (radians of rotation in the mass metric, at most
    /// 1): `omega_squared_error` over the gap to the nearest other mode of the same block
    /// (modes closer than their errors mix, and only their span is determined).
    pub vector_error: f64,
}

/// What a stiffness matrix's entries are known to: the first-order change of vᵀ K v
/// (rad²/s² for a mass-normalised v) that rounding them can cause. The modes use it for
/// each mode's estimated accuracy and to tell a neutral mode from a growing one.
pub trait StiffnessRounding {
    /// Upper estimate of |δ(vᵀ K v)| for the vector `v` over the variables (vᵀ M v = 1).
    fn error(&self, v: &[f64]) -> f64;

    /// A cheaper estimate, never below [`StiffnessRounding::error`]. A mode whose error by
    /// this bound is already far below anything reported or decided on keeps the bound as
    /// its error (see [`REFINE_ABOVE`]); the others get [`StiffnessRounding::error`].
    fn bound(&self, v: &[f64]) -> f64 {
        self.error(v)
    }

    /// [`StiffnessRounding::bound`] if `keep_bound` accepts it, else
    /// [`StiffnessRounding::error`] (implementations may share work between the two).
    fn estimate(&self, v: &[f64], keep_bound: &dyn Fn(f64) -> bool) -> f64 {
        let bound = self.bound(v);
        if keep_bound(bound) {
            bound
        } else {
            self.error(v)
        }
    }

    /// [`StiffnessRounding::estimate`] for a `v` that is exactly zero outside `support`
    /// (ascending variable indices: a mode's block). The same value; implementations use
    /// the support to cost the block's entries instead of all n variables.
    fn estimate_on(&self, v: &[f64], support: &[usize], keep_bound: &dyn Fn(f64) -> bool) -> f64 {
        let _ = support;
        self.estimate(v, keep_bound)
    }
}

/// Rounding of a matrix given entry by entry: each entry known to a few ulps of itself,
/// ε Σ |v_i| |K_ij| |v_j| (for matrices built by the caller; the stage runs use the
/// rounding of every term that makes up the entries instead). The non-zeros are kept by
/// column, so the form costs K's non-zeros per mode; the bound ε ‖|K|‖₂ ‖v‖², with
/// ‖|K|‖₂ ≤ √(‖K‖₁ ‖K‖∞), costs n.
pub struct EntryRounding {
    columns: SparseColumns,
    norm: f64,
}

impl EntryRounding {
    /// The rounding of `k`'s entries.
    pub fn new(k: &DMatrix<f64>) -> Self {
        let n = k.nrows().min(k.ncols());
        let columns = SparseColumns::new(n, |i, j| k[(i, j)]);
        let one = (0..n)
            .map(|j| (0..n).map(|i| k[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let infinity = (0..n)
            .map(|i| (0..n).map(|j| k[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        EntryRounding {
            columns,
            norm: (one * infinity).sqrt(),
        }
    }
}

impl StiffnessRounding for EntryRounding {
    fn error(&self, v: &[f64]) -> f64 {
        ROUNDING * f64::EPSILON * self.columns.abs_form(v)
    }

    fn bound(&self, v: &[f64]) -> f64 {
        // |v|ᵀ |K| |v| ≤ ‖|K|‖₂ ‖v‖² (and the 1-norm/∞-norm product bounds the 2-norm)
        ROUNDING * f64::EPSILON * self.norm * v.iter().map(|x| x * x).sum::<f64>()
    }

    fn estimate_on(&self, v: &[f64], support: &[usize], keep_bound: &dyn Fn(f64) -> bool) -> f64 {
        // the sums over the support alone, in the same order (the zeros add nothing)
        let squares: f64 = support
            .iter()
            .filter_map(|&i| v.get(i))
            .map(|x| x * x)
            .sum();
        let bound = ROUNDING * f64::EPSILON * self.norm * squares;
        if keep_bound(bound) {
            bound
        } else {
            ROUNDING * f64::EPSILON * self.columns.abs_form_on(v, support)
        }
    }
}

/// A mode's error is taken from [`StiffnessRounding::bound`] when that bound puts its
/// relative accuracy (half the relative error of ω²) below this, and from
/// [`StiffnessRounding::error`] otherwise. Well under the 1e-6 above which the command
/// line prints a mode's accuracy, and under the neutral test (|ω²| within its error), so
/// every accuracy that is printed or decides a verdict is the finer estimate.
pub const REFINE_ABOVE: f64 = 1e-7;

/// Ulps of an entry (or of a term's largest entry) its rounding is estimated at: each
/// entry is a sum of a few terms and a product of a few roundings.
pub(crate) const ROUNDING: f64 = 4.0;

impl Mode {
    /// Whether ω² ≥ 0 (zero-frequency neutral modes count as stable).
    pub fn is_stable(&self) -> bool {
        self.omega_squared >= 0.0
    }

    /// Estimated relative error of `hz` (a frequency or growth rate): half that of ω².
    /// Infinite for a neutral mode (ω² = 0, known only to ± `omega_squared_error`).
    pub fn accuracy(&self) -> f64 {
        if self.omega_squared == 0.0 {
            f64::INFINITY
        } else {
            (0.5 * self.omega_squared_error / self.omega_squared.abs()).min(1.0)
        }
    }

    /// A mode from its eigenvalue ω² (rad²/s²) and an eigenvector `u` (any scale) given at
    /// the `support` variables (ascending; zero at the other of the `n` variables):
    /// normalised to uᵀ M u = 1 with `mass_times` = M u at the support, labelled by the
    /// largest kinetic-energy fraction. Its errors are set to zero; [`finish`] estimates
    /// them.
    pub(crate) fn from_vector(
        omega_squared: f64,
        u: &[f64],
        mass_times: &[f64],
        support: &[usize],
        names: &[String],
    ) -> Mode {
        let n = names.len();
        let norm2: f64 = u.iter().zip(mass_times).map(|(a, b)| a * b).sum();
        let scale = 1.0 / norm2.sqrt();
        let mut vector = vec![0.0; n];
        let mut energy_fractions = vec![0.0; n];
        for ((&g, &a), &b) in support.iter().zip(u).zip(mass_times) {
            if let (Some(v), Some(e)) = (vector.get_mut(g), energy_fractions.get_mut(g)) {
                *v = a * scale;
                *e = a * b / norm2;
            }
        }
        // the fractions sum to 1, so the largest is at the support (ties: the last, as a
        // scan over all variables would find)
        let dominant = support
            .iter()
            .copied()
            .filter(|&i| i < n)
            .max_by(|&i, &j| energy_fractions[i].total_cmp(&energy_fractions[j]))
            .unwrap_or(0);
        let mut mode = Mode {
            omega_squared,
            hz: 0.0,
            label: names.get(dominant).cloned().unwrap_or_default(),
            vector,
            energy_fractions,
            omega_squared_error: 0.0,
            vector_error: 0.0,
        };
        mode.set_omega_squared(omega_squared);
        mode
    }

    fn set_omega_squared(&mut self, omega_squared: f64) {
        self.omega_squared = omega_squared;
        self.hz =
            omega_squared.signum() * omega_squared.abs().sqrt() / (2.0 * std::f64::consts::PI);
        if omega_squared == 0.0 {
            self.hz = 0.0;
        }
    }

    /// The `count` coordinates with the largest kinetic-energy fractions (at least 1 %),
    /// largest first: (name, fraction).
    pub fn dominant(&self, names: &[String], count: usize) -> Vec<(String, f64)> {
        let mut shares: Vec<(usize, f64)> =
            self.energy_fractions.iter().copied().enumerate().collect();
        shares.sort_by(|a, b| b.1.total_cmp(&a.1));
        shares
            .into_iter()
            .take(count)
            .filter(|&(_, f)| f >= 0.01)
            .filter_map(|(k, f)| Some((names.get(k)?.clone(), f)))
            .collect()
    }
}

/// All normal modes of a stage (or those asked for), ascending in frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// Variable names, the order of every mode vector.
    pub coordinates: Vec<String>,
    /// The modes, ascending in ω².
    pub modes: Vec<Mode>,
}

impl Modes {
    /// An error describing the growing modes, if any (the variables only: the stage run's
    /// [`crate::Stability`] also checks the floats).
    pub fn check_stable(&self) -> Result<(), DynamicsError> {
        crate::Stability::of_modes(self).check()
    }
}

/// The non-zero entries of a matrix by column, to multiply it into many vectors at the
/// cost of its non-zeros (mass matrices are block diagonal: one 6 × 6 block per body).
pub(crate) struct SparseColumns {
    entries: Vec<Vec<(usize, f64)>>,
}

impl SparseColumns {
    pub(crate) fn new(n: usize, entry: impl Fn(usize, usize) -> f64) -> Self {
        SparseColumns {
            entries: (0..n)
                .map(|j| {
                    (0..n)
                        .filter_map(|i| {
                            let v = entry(i, j);
                            (v != 0.0).then_some((i, v))
                        })
                        .collect()
                })
                .collect(),
        }
    }

    /// The columns of a mass matrix from its stored entries: the same columns
    /// [`SparseColumns::new`] reads from its dense form (rows ascending, zeros left out), in
    /// time linear in its entries.
    pub(crate) fn from_mass(mass: &pendkit_assembly::MassMatrix) -> Self {
        let mut entries = vec![Vec::new(); mass.nrows()];
        for (i, j, v) in mass.entries() {
            if v != 0.0 {
                entries[j].push((i, v));
            }
        }
        SparseColumns { entries }
    }

    /// A x.
    pub(crate) fn times(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.entries.len()];
        for (column, &xj) in self.entries.iter().zip(x) {
            if xj != 0.0 {
                for &(i, v) in column {
                    y[i] += v * xj;
                }
            }
        }
        y
    }

    /// A x at the `support` columns (ascending) for an `x` given there (zero elsewhere),
    /// returned at the support's rows: the entries of A that couple the support only to
    /// itself (a block of exactly decoupled variables). Sums in the order of
    /// [`SparseColumns::times`].
    /// `scratch` is n zeros, and is left so.
    pub(crate) fn times_on(&self, support: &[usize], x: &[f64], scratch: &mut [f64]) -> Vec<f64> {
        for (&j, &xj) in support.iter().zip(x) {
            if xj != 0.0
                && let Some(column) = self.entries.get(j)
            {
                for &(i, v) in column {
                    scratch[i] += v * xj;
                }
            }
        }
        let y = support
            .iter()
            .map(|&i| scratch.get(i).copied().unwrap_or(0.0))
            .collect();
        for (&j, &xj) in support.iter().zip(x) {
            if xj != 0.0
                && let Some(column) = self.entries.get(j)
            {
                for &(i, _) in column {
                    scratch[i] = 0.0;
                }
            }
        }
        y
    }

    /// [`SparseColumns::abs_form`] of an `x` (over all n) that is zero outside `support`
    /// (ascending): the same sum over the support's columns.
    pub(crate) fn abs_form_on(&self, x: &[f64], support: &[usize]) -> f64 {
        let mut sum = 0.0;
        for &j in support {
            let (Some(column), Some(&xj)) = (self.entries.get(j), x.get(j)) else {
                continue;
            };
            if xj != 0.0 {
                for &(i, v) in column {
                    sum += x.get(i).map_or(0.0, |xi| xi.abs()) * v.abs() * xj.abs();
                }
            }
        }
        sum
    }

    /// Σ |x_i| |A_ij| |x_j|.
    pub(crate) fn abs_form(&self, x: &[f64]) -> f64 {
        let mut sum = 0.0;
        for (column, &xj) in self.entries.iter().zip(x) {
            if xj != 0.0 {
                for &(i, v) in column {
                    sum += x.get(i).map_or(0.0, |xi| xi.abs()) * v.abs() * xj.abs();
                }
            }
        }
        sum
    }
}

/// A lower-triangular Cholesky factor L stored by columns down to each column's last
/// non-zero (its envelope). The factor of a banded matrix is banded (a chain's blocks
/// couple each stage to its neighbours only), and triangular solves that stop each column
/// at its last non-zero skip only exact zeros: the same values up to the order of the sums,
/// at about n² b instead of n³ operations for n right-hand sides and bandwidth b.
struct Envelope {
    /// Column k of L from the diagonal down to its last non-zero.
    columns: Vec<Vec<f64>>,
}

impl Envelope {
    fn new(l: faer::MatRef<'_, f64>) -> Self {
        let n = l.nrows();
        let columns = (0..n)
            .map(|k| {
                let end = (k + 1..n)
                    .rev()
                    .find(|&i| l[(i, k)] != 0.0)
                    .map_or(k + 1, |i| i + 1);
                (k..end).map(|i| l[(i, k)]).collect()
            })
            .collect();
        Envelope { columns }
    }

    /// Whether the envelope holds so few entries that the skyline solves beat the blocked
    /// dense ones (an eighth of the lower triangle: dense blocks keep faer's kernels).
    fn is_narrow(&self) -> bool {
        let n = self.columns.len();
        let stored: usize = self.columns.iter().map(Vec::len).sum();
        8 * stored < n * n
    }

    /// x ← L⁻¹ x for every column of x, column-oriented (zeros of x skipped).
    fn solve_lower(&self, x: &mut Mat<f64>) {
        for c in 0..x.ncols() {
            let x = x.col_as_slice_mut(c);
            for (k, column) in self.columns.iter().enumerate() {
                if x[k] == 0.0 {
                    continue;
                }
                let xk = x[k] / column[0];
                x[k] = xk;
                for (xi, &lik) in x[k + 1..].iter_mut().zip(&column[1..]) {
                    *xi -= lik * xk;
                }
            }
        }
    }

    /// x ← L⁻ᵀ x for every column of x (back substitution by dot products over the columns
    /// of L).
    fn solve_upper_transposed(&self, x: &mut Mat<f64>) {
        for c in 0..x.ncols() {
            let x = x.col_as_slice_mut(c);
            for (k, column) in self.columns.iter().enumerate().rev() {
                let below: f64 = x[k + 1..]
                    .iter()
                    .zip(&column[1..])
                    .map(|(xi, lik)| lik * xi)
                    .sum();
                x[k] = (x[k] - below) / column[0];
            }
        }
    }
}

/// Eigenpairs of the pencil (A, B) by Cholesky reduction of B: C = L⁻¹ A L⁻ᵀ, eigenvalues
/// ascending, vectors L⁻ᵀ u (B-orthonormal). The triangular solves follow L's envelope
/// when it is narrow (banded blocks), faer's blocked kernels otherwise.
fn reduced_eigen(
    a: &Mat<f64>,
    b_llt: &faer::linalg::solvers::Llt<f64>,
) -> Result<(Vec<f64>, Mat<f64>), DynamicsError> {
    let n = a.nrows();
    let l = b_llt.L();
    let envelope = Envelope::new(l);
    let narrow = envelope.is_narrow();
    let solve_lower = |x: &mut Mat<f64>| {
        if narrow {
            envelope.solve_lower(x);
        } else {
            l.solve_lower_triangular_in_place(x.as_mut());
        }
    };
    let mut x = a.clone();
    solve_lower(&mut x);
    let mut c = x.transpose().to_owned();
    solve_lower(&mut c);
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    if c.col_iter().any(|col| col.iter().any(|x| !x.is_finite())) {
        return Err(DynamicsError::Eigen(
            "the reduced matrix is not finite (stiffness or mass out of range)".into(),
        ));
    }
    let (values, mut v) = symmetric_eigen(&c)?;
    if narrow {
        envelope.solve_upper_transposed(&mut v);
    } else {
        l.transpose().solve_upper_triangular_in_place(v.as_mut());
    }
    Ok((values, v))
}

/// Eigenvalues (ascending) and orthonormal eigenvectors of the symmetric `c`, by faer's
/// divide and conquer on `c` scaled by a power of two to a largest entry in [1, 2).
///
/// Why the scaling: faer merges two eigenvalues of a divide-and-conquer step into one when
/// they differ by less than 8ε max(max |d|, max |z|), and the rank-one vector z is a unit
/// vector whatever the matrix's size: for a matrix whose entries are far below 1 (the
/// reduced matrices of the modes, μ = 1/ω² ~ 1e-7 s² at the violin modes) that is an
/// absolute tolerance far above ε‖C‖, and nearly degenerate eigenvalues come back exactly
/// equal (quad-aligo's violin pairs, 5e-9 apart, were). LAPACK scales the matrix to unit
/// norm first for the same reason. A power of two keeps the scaling and its undoing exact.
pub(crate) fn symmetric_eigen(c: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>), DynamicsError> {
    let n = c.nrows();
    let largest = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .map(|(i, j)| c[(i, j)].abs())
        .fold(0.0, f64::max);
    let exponent = if largest > 0.0 && largest.is_finite() {
        // largest = m 2^e with m in [1, 2): multiply by 2^−e
        // (within ±1000, where both 2^e and 2^−e are normal numbers)
        (largest.log2().floor() as i32).clamp(-1000, 1000)
    } else {
        0
    };
    let scale = 2f64.powi(-exponent);
    let unscale = 2f64.powi(exponent);
    let scaled = Mat::from_fn(n, n, |i, j| c[(i, j)] * scale);
    let evd = scaled
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| DynamicsError::Eigen(format!("{e:?}")))?;
    let values = (0..n)
        .map(|i| evd.S().column_vector()[i] * unscale)
        .collect();
    Ok((values, evd.U().to_owned()))
}

/// Backward error of the symmetric eigensolver on an n × n reduced matrix, in units of ε
/// times its largest eigenvalue: a few ulps per step of a reduction of depth ~√n.
fn solver_ulps(n: usize) -> f64 {
    ROUNDING * (n as f64).sqrt().max(1.0)
}

/// Eigenvalues (ω², ascending) and eigenvectors (columns, any scale) of one block, with
/// each eigenvalue's error from the method that found it (rad²/s²).
struct BlockModes {
    omega_squared: Vec<f64>,
    vectors: Mat<f64>,
    errors: Vec<f64>,
}

/// Whether A is numerically positive definite: its Cholesky factorisation succeeds.
fn positive_definite(a: &Mat<f64>) -> bool {
    a.llt(Side::Lower).is_ok()
}

/// The block's modes from the Cholesky factor of K + σM (positive definite, σ ≥ 0),
/// solving M u = μ (K + σM) u: μ = 1/(ω² + σ), the largest μ (lowest ω², and the growing
/// modes when σ > 0) resolved to ε relative, each ω² + σ to ε (ω² + σ)/(ω²_min + σ).
///
/// One solve resolves only the modes near the lowest: a mode 10⁴ times stiffer carries
/// 10⁴ times the relative error, and one beyond 1/(100 ε) is not resolved at all. A
/// (near-)neutral mode is the extreme case: with ω²_min ≈ 0 every other mode of the block
/// would be lost. So the modes this solve resolves to [`RESOLVED`] are kept, and the rest
/// are solved again in the part of the block M-orthogonal to them (`complement_modes`),
/// where the lowest of the rest is the lowest, and so on until every mode is resolved.
/// The pencil's eigenvectors are M-orthogonal, so the rest lie exactly in that part: the
/// modes above a neutral one are its true neighbours, continuous as its stiffness goes to
/// zero. `None` when K + σM is not numerically positive definite.
fn shifted_modes(
    k: &Mat<f64>,
    m: &Mat<f64>,
    sigma: f64,
) -> Result<Option<BlockModes>, DynamicsError> {
    let n = m.nrows();
    let shifted = Mat::from_fn(n, n, |i, j| k[(i, j)] + sigma * m[(i, j)]);
    let Ok(llt) = shifted.llt(Side::Lower) else {
        return Ok(None);
    };
    let (mus, u) = reduced_eigen(m, &llt)?;
    let mu_max = mus.last().copied().unwrap_or(0.0);
    let ulps = solver_ulps(n);
    // δμ = ulps ε μ_max for every μ, so μ ≥ `resolved` is known to RESOLVED relative
    let resolved = ulps * f64::EPSILON * mu_max / RESOLVED;
    // descending μ: ascending ω²
    let order: Vec<usize> = (0..n).rev().collect();
    let kept = order.iter().take_while(|&&j| mus[j] >= resolved).count();
    if kept > 0 && kept < n {
        let basis = Mat::from_fn(n, kept, |i, c| u[(i, order[c])]);
        if let Some(rest) = complement_modes(k, m, sigma, &basis)? {
            let mut modes: Vec<FoundMode> = order[..kept]
                .iter()
                .map(|&j| {
                    let mu = mus[j];
                    FoundMode {
                        omega_squared: 1.0 / mu - sigma,
                        error: ulps * f64::EPSILON * mu_max / (mu * mu),
                        vector: u.col(j).iter().copied().collect(),
                    }
                })
                .chain(rest)
                .collect();
            // the rest lie above the kept ones up to their errors: ascending as a whole
            modes.sort_by(|a, b| a.omega_squared.total_cmp(&b.omega_squared));
            return Ok(Some(BlockModes {
                omega_squared: modes.iter().map(|mode| mode.omega_squared).collect(),
                errors: modes.iter().map(|mode| mode.error).collect(),
                vectors: Mat::from_fn(n, n, |i, c| modes[c].vector[i]),
            }));
        }
    }
    // every mode resolved, or (rounding having made the rest's K + σM indefinite) no
    // second solve: modes beyond double precision (μ below rounding of the largest) are
    // then reported at that bound, with an error of half their ω²
    let floor = 100.0 * f64::EPSILON * mu_max;
    let mut omega_squared = Vec::with_capacity(n);
    let mut errors = Vec::with_capacity(n);
    for &j in &order {
        let mu = mus[j];
        if mu > floor {
            let w2 = 1.0 / mu - sigma;
            omega_squared.push(w2);
            // δμ = ulps ε μ_max, so δ(1/μ) = ulps ε μ_max / μ²
            errors.push(ulps * f64::EPSILON * mu_max / (mu * mu));
        } else {
            // known only to lie above the bound: an error of its own order
            let bound = 1.0 / floor - sigma;
            omega_squared.push(bound);
            errors.push(0.5 * bound.abs());
        }
    }
    Ok(Some(BlockModes {
        omega_squared,
        vectors: Mat::from_fn(n, n, |i, c| u[(i, order[c])]),
        errors,
    }))
}

/// A mode found by one solve of `shifted_modes`: ω², its error, its vector over the block.
struct FoundMode {
    omega_squared: f64,
    error: f64,
    vector: Vec<f64>,
}

/// Relative accuracy of ω² + σ to which one solve of `shifted_modes` must resolve a mode
/// for it to be kept; the others are solved again without the kept ones. Far above the
/// solver's few ulps (so each solve keeps modes over about four decades of ω² and a
/// block needs few), far below anything reported (the command line prints accuracies
/// above 1e-6) or decided on.
const RESOLVED: f64 = 1e-10;

/// The modes of the pencil (K + σM, M) M-orthogonal to the columns of `kept` (modes
/// already found): with Q an orthonormal basis of the vectors x with keptᵀ M x = 0 (the
/// last columns of the Householder QR of M·kept), the block's other modes are Q y for
/// the modes y of (Qᵀ K Q, Qᵀ M Q), solved by `shifted_modes` (so again from their own
/// lowest). Each comes back with its vector over the whole block, its error including the
/// rounding of forming Qᵀ K Q and Qᵀ M Q, γ (|Q| |y|)ᵀ (|K| + |ω²| |M|) (|Q| |y|) for y
/// normalised to yᵀ Qᵀ M Q y = 1. `None` when rounding has left Qᵀ (K + σM) Q indefinite.
fn complement_modes(
    k: &Mat<f64>,
    m: &Mat<f64>,
    sigma: f64,
    kept: &Mat<f64>,
) -> Result<Option<Vec<FoundMode>>, DynamicsError> {
    let n = m.nrows();
    let kept_count = kept.ncols();
    let full = (m * kept).qr().compute_Q();
    let q = full.subcols(kept_count, n - kept_count).to_owned();
    let symmetric =
        |a: Mat<f64>| Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let k_rest = symmetric(q.transpose() * k * &q);
    let m_rest = symmetric(q.transpose() * m * &q);
    let Some(rest) = shifted_modes(&k_rest, &m_rest, sigma)? else {
        return Ok(None);
    };
    let abs_q = Mat::from_fn(n, q.ncols(), |i, j| q[(i, j)].abs());
    let abs_form = |a: &Mat<f64>, z: &[f64]| -> f64 {
        (0..n)
            .map(|i| z[i] * (0..n).map(|j| a[(i, j)].abs() * z[j]).sum::<f64>())
            .sum()
    };
    let gamma = solver_ulps(n) * f64::EPSILON;
    Ok(Some(
        (0..rest.omega_squared.len())
            .map(|c| {
                let y = rest.vectors.col(c);
                let norm2 = (y.transpose() * &m_rest * y).abs();
                let scale = if norm2 > 0.0 { 1.0 / norm2.sqrt() } else { 0.0 };
                let z: Vec<f64> = (0..n)
                    .map(|i| {
                        scale
                            * (0..y.nrows())
                                .map(|j| abs_q[(i, j)] * y[j].abs())
                                .sum::<f64>()
                    })
                    .collect();
                let w2 = rest.omega_squared[c];
                let forming = gamma * (abs_form(k, &z) + w2.abs() * abs_form(m, &z));
                let vector = (&q * y).iter().copied().collect();
                FoundMode {
                    omega_squared: w2,
                    error: rest.errors[c] + forming,
                    vector,
                }
            })
            .collect(),
    ))
}

/// Solves one block: with K's Cholesky factor and for 1/ω² when K is positive definite
/// there, so low modes keep full relative accuracy next to stiff, light parts. Otherwise
/// with M's factor (every ω² to about ε ω²_max), and, unless K + σM is positive definite
/// already for σ at the rounding of that solve, also with the factor of K + σM for a
/// shift σ that makes it positive definite: by bisection on σ, the smallest such shift is
/// bracketed within a factor 2 (σ_ok), and the solve uses σ = 2 σ_ok, so that
/// ω²_min + σ ≥ σ_ok ≥ |ω²_min|/2 (when ω²_min < 0): the growing modes, the largest
/// 1/(ω² + σ), are resolved relative to their own size, however stiff the rest of the
/// block. Each ω² is taken from whichever of the two solves resolves it better.
fn block_modes(
    k: &Mat<f64>,
    m: &Mat<f64>,
    weakest: impl Fn() -> String,
) -> Result<BlockModes, DynamicsError> {
    let m_llt = m
        .llt(Side::Lower)
        .map_err(|_| DynamicsError::SingularMass {
            variable: weakest(),
        })?;
    // K positive definite: M u = μ K u with μ = 1/ω², the shifted solve without a shift
    if let Some(modes) = shifted_modes(k, m, 0.0)? {
        return Ok(modes);
    }
    let n = m.nrows();
    let (lambdas, v) = reduced_eigen(k, &m_llt)?;
    let top = lambdas.iter().fold(0.0f64, |a, l| a.max(l.abs()));
    let by_mass_error = solver_ulps(n) * f64::EPSILON * top;
    let by_mass = BlockModes {
        errors: vec![by_mass_error; n],
        omega_squared: lambdas,
        vectors: v,
    };
    let shift_pd =
        |sigma: f64| positive_definite(&Mat::from_fn(n, n, |i, j| k[(i, j)] + sigma * m[(i, j)]));
    // K + σM positive definite already for a shift at the level of rounding of M's own
    // solve: nothing lies measurably below zero, and M's factor has every ω² as well as
    // any method (ω² near zero are then neutral)
    let floor = f64::EPSILON * by_mass_error;
    if by_mass_error == 0.0 || shift_pd(floor) {
        return Ok(by_mass);
    }
    // a shift that makes K + σM positive definite: above −ω²_min, which M's factor knows
    // to within its error
    let lowest = by_mass.omega_squared.first().copied().unwrap_or(0.0);
    let mut high = 2.0 * (lowest.abs() + by_mass_error);
    let mut tries = 0;
    while !shift_pd(high) {
        high *= 4.0;
        tries += 1;
        if tries > 60 || !high.is_finite() {
            return Ok(by_mass);
        }
    }
    // a geometric bisection needs a positive start: with stiffnesses near the bottom of
    // the f64 range the floor underflows to 0, and from 0 the midpoint stays 0 for ever
    let mut low = floor.max(f64::MIN_POSITIVE);
    while high > 2.0 * low {
        // the geometric mean without forming low·high, which underflows to 0 there
        let mid = low.sqrt() * high.sqrt();
        if shift_pd(mid) {
            high = mid;
        } else {
            low = mid;
        }
    }
    // σ = 2 high: ω²_min + σ ≥ high, so the growing modes are the best-resolved ones
    let Some(shifted) = shifted_modes(k, m, 2.0 * high)? else {
        return Ok(by_mass);
    };
    // both lists ascending, each ω² within its error of the exact j-th eigenvalue: take
    // each from the solve that resolves it better
    let take_shifted: Vec<bool> = (0..n)
        .map(|j| shifted.errors[j] < by_mass.errors[j])
        .collect();
    Ok(BlockModes {
        omega_squared: (0..n)
            .map(|j| {
                if take_shifted[j] {
                    shifted.omega_squared[j]
                } else {
                    by_mass.omega_squared[j]
                }
            })
            .collect(),
        vectors: Mat::from_fn(n, n, |i, j| {
            if take_shifted[j] {
                shifted.vectors[(i, j)]
            } else {
                by_mass.vectors[(i, j)]
            }
        }),
        errors: (0..n)
            .map(|j| shifted.errors[j].min(by_mass.errors[j]))
            .collect(),
    })
}

/// A mode as an eigensolver found it: ω², the method's error, and a vector (any scale)
/// over the variables of its block (exactly zero at every other variable).
pub(crate) struct RawMode {
    pub(crate) omega_squared: f64,
    pub(crate) error: f64,
    /// The vector at the block's variables, in their (ascending) order.
    pub(crate) vector: Vec<f64>,
    /// Index of the block in `finish`'s `blocks`.
    pub(crate) block: usize,
}

/// Turns solver output into modes: normalised vectors, energy fractions and labels; each
/// mode's ω² error (the method's plus the first-order effect of rounding K's entries,
/// `rounding`, and M's, ε |ω²| Σ |v_i| |M_ij| |v_j|); ω² within that error of zero set to
/// exactly zero (neutral: its sign is not determined); the vector error from the gap to the
/// nearest mode of the same block; sorted ascending. `blocks` lists each block's variables
/// (ascending); a mode's products and forms run over its block only (the matrices couple
/// nothing outside it), so each mode costs its block's entries, not all n².
pub(crate) fn finish(
    raw: Vec<RawMode>,
    blocks: &[Vec<usize>],
    mass: &SparseColumns,
    names: &[String],
    rounding: &dyn StiffnessRounding,
) -> Vec<Mode> {
    let mut scratch = vec![0.0; mass.entries.len()];
    let mut modes: Vec<(Mode, usize)> = raw
        .into_iter()
        .map(|r| {
            let support: &[usize] = blocks.get(r.block).map_or(&[], Vec::as_slice);
            let mu = mass.times_on(support, &r.vector, &mut scratch);
            let mut mode = Mode::from_vector(r.omega_squared, &r.vector, &mu, support, names);
            let w2 = mode.omega_squared;
            let mass_part =
                ROUNDING * f64::EPSILON * w2.abs() * mass.abs_form_on(&mode.vector, support);
            let others = r.error + mass_part;
            let keep_bound = |bound: f64| {
                let coarse = others + bound;
                coarse.is_finite() && coarse <= 2.0 * REFINE_ABOVE * w2.abs()
            };
            let error = others + rounding.estimate_on(&mode.vector, support, &keep_bound);
            mode.omega_squared_error = if error.is_finite() { error } else { f64::MAX };
            if w2.abs() <= mode.omega_squared_error {
                mode.set_omega_squared(0.0);
            }
            (mode, r.block)
        })
        .collect();
    modes.sort_by(|a, b| a.0.omega_squared.total_cmp(&b.0.omega_squared));
    // the nearest mode of the same block is a neighbour in that block's ascending list
    let mut gaps = vec![f64::INFINITY; modes.len()];
    let mut last_of_block: Vec<Option<usize>> = vec![None; blocks.len()];
    for i in 0..modes.len() {
        let Some(last) = last_of_block.get_mut(modes[i].1) else {
            continue;
        };
        if let Some(j) = *last {
            let gap = (modes[j].0.omega_squared - modes[i].0.omega_squared).abs();
            gaps[i] = gaps[i].min(gap);
            gaps[j] = gaps[j].min(gap);
        }
        *last = Some(i);
    }
    modes
        .into_iter()
        .zip(gaps)
        .map(|((mut mode, _), gap)| {
            mode.vector_error = if gap > 0.0 {
                (mode.omega_squared_error / gap).min(1.0)
            } else {
                1.0
            };
            mode
        })
        .collect()
}

/// Solves K_eff v = ω² M v. The variables are split into the blocks that K_eff and M couple
/// (their exact zeros; found from the matrices, never assumed), and each block is solved on
/// its own: with K_eff's Cholesky factor and for 1/ω² when K_eff is positive definite on the
/// block (the low modes, the ones suspensions are about, then keep full relative accuracy
/// even when very stiff, very light parts put other modes many decades higher); otherwise
/// with M's factor, and when the block has growing modes beyond M's resolution, with the
/// factor of the shifted K_eff + σM as well (see `block_modes`), so that growth rates are
/// resolved relative to themselves. Each mode carries its estimated error
/// ([`Mode::omega_squared_error`]); ω² within it of zero is reported as exactly zero:
/// neutral. The modes one factorisation resolves to 1e-10 (those within about four decades
/// of the lowest in ω²) are kept and the rest solved again without them, so a (near-)neutral
/// mode or very stiff, light parts leave every other mode of the block resolved relative to
/// itself (see `shifted_modes`). The entries of `k_eff` and `mass` are taken as exact to a few
/// ulps ([`EntryRounding`]); [`normal_modes_with_rounding`] takes their rounding from how
/// they were made. `names` are the variable names.
pub fn normal_modes(
    k_eff: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    names: &[String],
) -> Result<Modes, DynamicsError> {
    normal_modes_with_rounding(k_eff, mass, names, &EntryRounding::new(k_eff))
}

/// [`normal_modes`] with the rounding of K_eff's entries given by `rounding` (the stage
/// runs use the rounding of the terms that make up each entry).
pub fn normal_modes_with_rounding(
    k_eff: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    names: &[String],
    rounding: &dyn StiffnessRounding,
) -> Result<Modes, DynamicsError> {
    let n = mass.nrows();
    for (what, matrix) in [("stiffness matrix", k_eff), ("mass matrix", mass)] {
        if matrix.nrows() != n || matrix.ncols() != n {
            return Err(DynamicsError::Length {
                what: if what == "mass matrix" {
                    "mass matrix (square) for the modes"
                } else {
                    "stiffness matrix for the modes"
                },
                expected: n,
                got: if matrix.nrows() != n {
                    matrix.nrows()
                } else {
                    matrix.ncols()
                },
            });
        }
        if let Some(bad) = matrix.iter().position(|x| !x.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what,
                row: bad % n.max(1),
                column: bad / n.max(1),
            });
        }
    }
    if names.len() != n {
        return Err(DynamicsError::Length {
            what: "variable names for the modes",
            expected: n,
            got: names.len(),
        });
    }
    let (label, count) = dense_components(n, &[k_eff.as_slice(), mass.as_slice()]);
    let mass_columns = SparseColumns::new(n, |i, j| mass[(i, j)]);
    modes_of_blocks(
        &label,
        count,
        |i, j| k_eff[(i, j)],
        |i, j| mass[(i, j)],
        &mass_columns,
        names,
        rounding,
    )
}

/// The modes of each exactly decoupled block (`label`: each variable's block, `count`
/// blocks), K_eff and M read entry by entry: from dense matrices, or from a stage model's
/// pattern for models too large for dense n × n storage ([`StageModel::modes_by_blocks`]).
pub(crate) fn modes_of_blocks(
    label: &[usize],
    count: usize,
    k_eff: impl Fn(usize, usize) -> f64,
    mass: impl Fn(usize, usize) -> f64,
    mass_columns: &SparseColumns,
    names: &[String],
    rounding: &dyn StiffnessRounding,
) -> Result<Modes, DynamicsError> {
    let mut blocks: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (i, &b) in label.iter().enumerate() {
        blocks[b].push(i);
    }
    let mut raw: Vec<RawMode> = Vec::with_capacity(label.len());
    for (b, idx) in blocks.iter().enumerate() {
        let kb = Mat::from_fn(idx.len(), idx.len(), |i, j| k_eff(idx[i], idx[j]));
        let mb = Mat::from_fn(idx.len(), idx.len(), |i, j| mass(idx[i], idx[j]));
        let weakest = || {
            let w = idx
                .iter()
                .copied()
                .min_by(|&i, &j| mass(i, i).total_cmp(&mass(j, j)))
                .unwrap_or(0);
            names.get(w).cloned().unwrap_or_default()
        };
        let block = block_modes(&kb, &mb, weakest)?;
        for (k, (&w2, &error)) in block.omega_squared.iter().zip(&block.errors).enumerate() {
            raw.push(RawMode {
                omega_squared: w2,
                error,
                vector: block.vectors.col(k).iter().copied().collect(),
                block: b,
            });
        }
    }
    Ok(Modes {
        coordinates: names.to_vec(),
        modes: finish(raw, &blocks, mass_columns, names, rounding),
    })
}

impl StageModel {
    /// Every mode at f = 0 stiffness (each tag's ε'(0)), block by block as
    /// [`normal_modes_with_rounding`] solves them, with each block's matrices read from the
    /// pattern: no dense n × n matrix, so memory and time grow with the blocks' sizes, not
    /// the square of the model's (10 000 bodies on their own springs are 10 000 blocks of
    /// one variable). For models without floats (whose elimination needs the dense Schur
    /// complement); `None` for a model with floats.
    pub fn modes_by_blocks(
        &self,
        damping: &Damping,
        rounding: &dyn StiffnessRounding,
    ) -> Option<Result<Modes, DynamicsError>> {
        let (nx, nq, _) = self.sizes;
        if nq > 0 {
            return None;
        }
        let k = self.master_values(damping, 0.0).0;
        if let Some(s) = k.iter().position(|v| !v.is_finite()) {
            let (row, column) = self.pattern.position(s);
            return Some(Err(DynamicsError::NotFinite {
                what: "stiffness matrix",
                row,
                column,
            }));
        }
        if let Some((row, column, _)) = self.mass.entries().find(|e| !e.2.is_finite()) {
            return Some(Err(DynamicsError::NotFinite {
                what: "mass matrix",
                row,
                column,
            }));
        }
        let label = &self.blocks[..nx.min(self.blocks.len())];
        let count = label.iter().max().map_or(0, |&b| b + 1);
        let entry = |i: usize, j: usize| self.pattern.slot(i, j).map_or(0.0, |s| k[s]);
        Some(modes_of_blocks(
            label,
            count,
            entry,
            |i, j| self.mass.get(i, j),
            &SparseColumns::from_mass(&self.mass),
            &self.variables,
            rounding,
        ))
    }
}

/// Motion of one body in a mode, in lab axes.
#[derive(Clone, Debug)]
pub struct BodyMotion {
    /// Body name.
    pub body: String,
    /// Displacement of the centre of mass (m per unit modal amplitude).
    pub translation: [f64; 3],
    /// Small rotation about lab z, y, x: lab yaw, pitch, roll (rad per unit modal amplitude).
    pub rotation: [f64; 3],
}

/// The lab-frame table of a mode (the source's `e2ni`): each massive body's centre-of-mass
/// displacement and small rotation, through the linearised geometry at `x_eq`. Float
/// motion is not included (it follows from the variables).
pub fn lab_motion(
    system: &System,
    layout: &Layout,
    x_eq: &[f64],
    mode: &Mode,
) -> Result<Vec<BodyMotion>, DynamicsError> {
    for (what, expected, got) in [
        (
            "coordinates of the equilibrium for the lab motion",
            system.coords.len(),
            x_eq.len(),
        ),
        (
            "mode vector for the lab motion (one entry per variable)",
            layout.variables.len(),
            mode.vector.len(),
        ),
    ] {
        if expected != got {
            return Err(DynamicsError::Length {
                what,
                expected,
                got,
            });
        }
    }
    if let Some(&g) = layout.variables.iter().find(|&&g| g >= system.coords.len()) {
        return Err(DynamicsError::Length {
            what: "coordinates of the system (a layout variable lies beyond them)",
            expected: system.coords.len(),
            got: g + 1,
        });
    }
    Ok(system
        .bodies
        .iter()
        .filter(|b| b.mass > 0.0)
        .map(|body| {
            let jac = body.frame.jacobian(x_eq, &body.centre_of_mass);
            let mut translation = Vector3::zeros();
            let mut omega = Vector3::zeros();
            for (&g, &v) in layout.variables.iter().zip(&mode.vector) {
                debug_assert_eq!(system.coords[g].kind, CoordKind::Variable);
                translation += jac.position.column(g) * v;
                omega += jac.omega_space.column(g) * v;
            }
            BodyMotion {
                body: body.name.clone(),
                translation: [translation[0], translation[1], translation[2]],
                rotation: lab_yaw_pitch_roll(&omega),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rounding whose fine estimate and bound are given constants (rad²/s²).
    struct Given {
        fine: f64,
        bound: f64,
    }

    impl StiffnessRounding for Given {
        fn error(&self, _: &[f64]) -> f64 {
            self.fine
        }
        fn bound(&self, _: &[f64]) -> f64 {
            self.bound
        }
    }

    #[test]
    fn the_bound_is_kept_only_far_below_reporting_and_the_fine_estimate_used_otherwise() {
        // two uncoupled unit masses on springs of 1 and 4 N/m: ω² = 1 and 4, each resolved
        // by the solver to a few ulps, so a mode's error is the rounding given here plus
        // ~1e-15
        let k = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1.0, 4.0]));
        let m = DMatrix::identity(2, 2);
        let names = vec!["a".to_string(), "b".to_string()];
        let errors = |fine: f64, bound: f64| {
            let modes = normal_modes_with_rounding(&k, &m, &names, &Given { fine, bound }).unwrap();
            modes
                .modes
                .iter()
                .map(|m| m.omega_squared_error)
                .collect::<Vec<_>>()
        };
        // a bound at 1e-12 of ω² (accuracy 5e-13 < REFINE_ABOVE) is kept
        for e in errors(1e-20, 1e-12) {
            assert!((1e-12..1.1e-12).contains(&e), "{e:e}");
        }
        // a bound at 1e-3 of ω² would state accuracy 5e-4: the fine estimate is used
        for e in errors(1e-14, 1e-3) {
            assert!((1e-14..1e-13).contains(&e), "{e:e}");
        }
    }

    #[test]
    fn a_near_zero_mode_leaves_the_others_of_its_block_exact() {
        // K = Rᵀ diag(δ, 1, 4) R with R a rotation mixing all three variables, M = I: one
        // factorisation of K gives ω² = 1 and 4 only to about √n ε/δ relative, and before
        // the deflation clamped both to one wrong value for δ ≲ 1e-13; now they are exact
        // to rounding for every δ, down to a K that is singular to rounding
        let (c, s) = (0.6f64, 0.8f64);
        let r = DMatrix::from_row_slice(3, 3, &[c, -s, 0.0, s * c, c * c, -s, s * s, s * c, c]);
        let names: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        for delta in [1e-3, 1e-9, 1e-13, 1e-15, 1e-17] {
            let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![delta, 1.0, 4.0]));
            let k = r.transpose() * d * &r;
            let k = (&k + k.transpose()) * 0.5;
            let modes = normal_modes(&k, &DMatrix::identity(3, 3), &names).unwrap();
            let w2: Vec<f64> = modes.modes.iter().map(|m| m.omega_squared).collect();
            assert!(w2[0].abs() <= delta + 1e-14, "{delta:e}: {w2:?}");
            for (got, want) in w2[1..].iter().zip([1.0, 4.0]) {
                assert!((got - want).abs() <= 1e-14 * want, "{delta:e}: {w2:?}");
            }
            for m in &modes.modes[1..] {
                assert!(
                    m.accuracy() < 1e-10,
                    "{delta:e}: accuracy {:e}",
                    m.accuracy()
                );
            }
        }
    }

    #[test]
    fn envelope_solves_equal_the_dense_triangular_solves() {
        // a banded symmetric positive definite matrix (bandwidth 3, diagonally dominant)
        // and a dense right-hand side with leading zeros: the envelope solves skip exact
        // zeros only, so they agree with faer's dense solves to rounding
        let n = 40;
        let a = Mat::from_fn(n, n, |i, j| {
            let d = i.abs_diff(j);
            match d {
                0 => 10.0 + (i % 7) as f64,
                1..=3 => 1.0 / (1.0 + (i + j) as f64 * 0.1 + d as f64),
                _ => 0.0,
            }
        });
        let llt = a.llt(Side::Lower).unwrap();
        let envelope = Envelope::new(llt.L());
        assert!(envelope.is_narrow());
        let b = Mat::from_fn(n, 5, |i, j| {
            if i < 3 * j {
                0.0
            } else {
                ((i * 7 + j * 3) % 11) as f64 - 5.0
            }
        });
        let (mut x, mut y) = (b.clone(), b.clone());
        envelope.solve_lower(&mut x);
        llt.L().solve_lower_triangular_in_place(y.as_mut());
        let (mut u, mut v) = (b.clone(), b.clone());
        envelope.solve_upper_transposed(&mut u);
        llt.L()
            .transpose()
            .solve_upper_triangular_in_place(v.as_mut());
        for j in 0..5 {
            for i in 0..n {
                assert!((x[(i, j)] - y[(i, j)]).abs() <= 1e-13 * (1.0 + y[(i, j)].abs()));
                assert!((u[(i, j)] - v[(i, j)]).abs() <= 1e-13 * (1.0 + v[(i, j)].abs()));
            }
        }
    }
}
