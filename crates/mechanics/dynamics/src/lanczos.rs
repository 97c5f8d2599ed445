//! The modes below a frequency, for models too large for the dense n³ eigensolver (violin
//! beads, long chains): block Lanczos with full reorthogonalisation on the shift-invert
//! operator (K − σM)⁻¹M over the sparse factorisation of the joint variables-and-floats
//! matrix, whose float rows eliminate the floats exactly (the Schur complement, without
//! forming it). How many modes lie below the bound is known beforehand from Sylvester's law
//! of inertia (the negative pivots of an LDLᵀ factorisation of K − λ_max M, the classic
//! Sturm-sequence check), and the iteration stops only when that many Ritz pairs below the
//! bound have converged, or when the Krylov basis spans every variable (then the
//! Rayleigh–Ritz step is the full eigenproblem). The same counts cut the spectrum below the
//! bound into slices of at most [`SLICE_MODES`] modes (spectrum slicing), each searched
//! with a shift inside it, so that modes far up (violin harmonics above the suspension
//! modes) are found at the cost of their own slice and not of every bead mode below them.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Mat, Par, Side};
use pendkit_system::Damping;

use crate::DynamicsError;
use crate::modes::{Modes, ROUNDING, RawMode, SparseColumns, StiffnessRounding, finish};
use crate::sparse_lu::SparseLu;
use crate::stage::{StageModel, TWO_PI};

/// Vectors added to the Krylov basis per step: at least the multiplicity of the
/// degenerate modes of symmetric suspensions (four identical fibres), so that each copy
/// of a repeated eigenvalue is found in exact arithmetic too.
const BLOCK: usize = 4;

/// A Ritz pair has converged when ‖(K − σM)⁻¹M u − θ u‖_M ≤ TOLERANCE |θ|: its eigenvalue
/// is then accurate to about TOLERANCE² relative to the gap to its neighbours, and to
/// TOLERANCE at worst.
const TOLERANCE: f64 = 1e-11;

/// Absolute error of the Rayleigh–Ritz values θ of a basis of `dim` vectors whose largest
/// |θ| is `theta_max`: a few ulps per step of the dense eigen-solve, as for the dense modes.
fn ritz_noise(dim: usize, theta_max: f64) -> f64 {
    ROUNDING * (dim as f64).sqrt().max(1.0) * f64::EPSILON * theta_max
}

/// A symmetric matrix over the unknowns (variables, then floats) in compressed columns,
/// with each stored entry's slot in the stage's pattern.
struct Unknowns {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    slots: Vec<usize>,
}

impl Unknowns {
    /// The pattern's entries among the nodes `nodes`, renumbered from 0.
    fn new(model: &StageModel, nodes: std::ops::Range<usize>) -> Self {
        let mut col_ptr = vec![0];
        let (mut row_idx, mut slots) = (Vec::new(), Vec::new());
        for c in nodes.clone() {
            for s in model.pattern.row_slots(c) {
                let (_, r) = model.pattern.position(s);
                if nodes.contains(&r) {
                    row_idx.push(r - nodes.start);
                    slots.push(s);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Unknowns {
            n: nodes.len(),
            col_ptr,
            row_idx,
            slots,
        }
    }

    fn structure(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }

    /// Values of K − shift M on the structure.
    fn values(&self, k: &[f64], m: &[f64], shift: f64) -> Vec<f64> {
        self.slots.iter().map(|&s| k[s] - shift * m[s]).collect()
    }
}

/// Counts negative eigenvalues of symmetric matrices of one pattern by LDLᵀ (fill-reducing
/// ordering, no pivoting): by Sylvester's law of inertia, the number of negative pivots.
struct Inertia<'a> {
    matrix: &'a Unknowns,
    symbolic: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    scratch: MemBuffer,
}

impl<'a> Inertia<'a> {
    fn new(matrix: &'a Unknowns) -> Result<Self, DynamicsError> {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            matrix.structure(),
            Side::Upper,
            SymmetricOrdering::Amd,
            params,
        )
        .map_err(|e| DynamicsError::Solver(format!("LDLᵀ analysis: {e:?}")))?;
        let scratch = MemBuffer::new(
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        );
        Ok(Inertia {
            factor: vec![0.0; symbolic.len_val()],
            matrix,
            symbolic,
            scratch,
        })
    }

    /// Negative pivots of the matrix with `values`; None if a pivot is exactly zero.
    fn negatives(&mut self, values: &[f64]) -> Option<usize> {
        if self.matrix.n == 0 {
            return Some(0);
        }
        let a = SparseColMatRef::new(self.matrix.structure(), values);
        self.symbolic
            .factorize_numeric_ldlt(
                &mut self.factor,
                a,
                Side::Upper,
                LdltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .ok()?;
        // simplicial storage: each column of L starts with its diagonal, which holds D
        let SymbolicCholeskyRaw::Simplicial(s) = self.symbolic.raw() else {
            return None;
        };
        let col_ptr = s.col_ptr();
        Some(
            (0..self.matrix.n)
                .filter(|&k| self.factor[col_ptr[k]] < 0.0)
                .count(),
        )
    }
}

/// How many eigenvalues of K_eff − λM (the floats eliminated) lie below λ: the negative
/// pivots of the joint matrix less those of the float block.
struct ModeCounter<'a> {
    joint: Inertia<'a>,
    float_negatives: Option<usize>,
    k: &'a [f64],
    m: &'a [f64],
}

impl ModeCounter<'_> {
    /// Eigenvalues below `lambda` (rad²/s²); None where a pivot is exactly zero.
    fn below(&mut self, lambda: f64) -> Option<usize> {
        let values = self.joint.matrix.values(self.k, self.m, lambda);
        self.joint
            .negatives(&values)?
            .checked_sub(self.float_negatives?)
    }

    /// A boundary near `lambda` with no eigenvalue within [`BOUNDARY_GAP`] of it (so that
    /// a Ritz value, accurate to far better, cannot fall on the wrong side), and the count
    /// below it: `lambda` itself or a point moved up by up to a few per mille.
    fn clear_boundary(&mut self, lambda: f64) -> Option<(f64, usize)> {
        (0..4).find_map(|attempt| {
            let at = lambda * (1.0 + 1e-3 * attempt as f64);
            let below = self.below(at * (1.0 - BOUNDARY_GAP))?;
            (self.below(at * (1.0 + BOUNDARY_GAP))? == below).then_some((at, below))
        })
    }
}

/// Relative distance (in λ) a slice boundary keeps from every eigenvalue.
const BOUNDARY_GAP: f64 = 1e-7;

/// Most modes one shift-invert run looks for: a slice of the spectrum with more is cut in
/// two. With one shift near zero, modes far up the spectrum (violin harmonics at 500 and
/// 1000 Hz above suspension modes at 1 Hz) are tiny Ritz values among the many of the beads'
/// higher modes, and the Krylov basis grew to nearly every variable before they converged
/// (18 s for 40 beads per fibre); a shift inside each slice makes its modes the dominant
/// ones.
const SLICE_MODES: usize = 16;

/// Most slices one bound is cut into: each costs a factorisation and a Krylov basis.
const MAX_SLICES: usize = 64;

/// A part of the spectrum searched with one shift: the eigenvalues λ (rad²/s²) in
/// [`low`, `high`), `count` of them (None when the inertia could not count them: then the
/// search runs until its basis spans every variable).
struct Slice {
    low: f64,
    high: f64,
    count: Option<usize>,
}

impl Slice {
    /// The shift: just below zero for the lowest slice (its modes are the largest Ritz
    /// values, well separated, and a neutral mode does not make the operator singular),
    /// else the middle of the slice in frequency.
    fn shift(&self, lambda_max: f64) -> f64 {
        if self.low == f64::NEG_INFINITY {
            -1e-6 * lambda_max
        } else {
            (0.5 * (self.low.sqrt() + self.high.sqrt())).powi(2)
        }
    }
}

/// The slices of [−∞, `lambda_max`) holding the `wanted` eigenvalues below it, at most
/// [`SLICE_MODES`] each where the spectrum allows: the fullest slice is cut at its middle
/// frequency (moved to a clear boundary) until none holds more, or a cut would not split it.
fn plan_slices(counter: &mut ModeCounter<'_>, lambda_max: f64, wanted: usize) -> Vec<Slice> {
    // boundaries in λ with the count below each; the first stands for −∞
    let mut bounds: Vec<(f64, usize)> = vec![(0.0, 0), (lambda_max, wanted)];
    let mut uncuttable: Vec<f64> = Vec::new();
    while bounds.len() <= MAX_SLICES {
        let fullest = bounds
            .windows(2)
            .enumerate()
            .filter(|(_, w)| !uncuttable.contains(&w[0].0))
            .map(|(i, w)| (i, w[1].1.saturating_sub(w[0].1)))
            .filter(|&(_, count)| count > SLICE_MODES)
            .max_by_key(|&(_, count)| count);
        let Some((i, _)) = fullest else {
            break;
        };
        let (low, high) = (bounds[i], bounds[i + 1]);
        let middle = (0.5 * (low.0.sqrt() + high.0.sqrt())).powi(2);
        match counter.clear_boundary(middle) {
            // a cut strictly inside, with counts in order, that splits the slice
            Some((at, below)) if at > low.0 && at < high.0 && below > low.1 && below < high.1 => {
                bounds.insert(i + 1, (at, below));
            }
            _ => uncuttable.push(low.0),
        }
    }
    bounds
        .windows(2)
        .enumerate()
        .map(|(i, w)| Slice {
            low: if i == 0 { f64::NEG_INFINITY } else { w[0].0 },
            high: w[1].0,
            count: Some(w[1].1 - w[0].1),
        })
        .filter(|slice| slice.count != Some(0))
        .collect()
}

/// [`crate::EntryRounding`] for the variables' block of a matrix on the stage's pattern.
struct PatternEntries<'a> {
    model: &'a StageModel,
    values: Vec<f64>,
}

impl StiffnessRounding for PatternEntries<'_> {
    fn error(&self, v: &[f64]) -> f64 {
        let sum: f64 = self
            .values
            .iter()
            .enumerate()
            .map(|(s, k)| {
                let (i, j) = self.model.pattern.position(s);
                match (v.get(i), v.get(j)) {
                    (Some(a), Some(b)) if i < self.model.sizes.0 && j < self.model.sizes.0 => {
                        a.abs() * k.abs() * b.abs()
                    }
                    _ => 0.0,
                }
            })
            .sum();
        ROUNDING * f64::EPSILON * sum
    }
}

/// Deterministic pseudo-random start vectors (xorshift), uniform in (−1, 1).
fn start_block(n: usize, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..count)
        .map(|_| (0..n).map(|_| next()).collect())
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl StageModel {
    /// The normal modes below `hz` (Hz) at f = 0 stiffness (each tag's ε'(0)), ascending,
    /// found by shift-invert block Lanczos on the sparse factorisation instead of the dense
    /// eigensolver: for large models, at a cost set by the number of modes asked for. The
    /// modes are those [`crate::normal_modes`] gives below `hz` (mass-normalised vectors,
    /// kinetic-energy fractions, labels; unstable modes with minus their growth rate).
    pub fn modes_below(&self, damping: &Damping, hz: f64) -> Result<Modes, DynamicsError> {
        let rounding = PatternEntries {
            model: self,
            values: self.master_values(damping, 0.0).0,
        };
        self.modes_below_with_rounding(damping, hz, &rounding)
    }

    /// [`StageModel::modes_below`] with the rounding of the stiffness given by `rounding`
    /// (each mode's estimated error, and which modes are neutral).
    pub fn modes_below_with_rounding(
        &self,
        damping: &Damping,
        hz: f64,
        rounding: &dyn StiffnessRounding,
    ) -> Result<Modes, DynamicsError> {
        if !(hz > 0.0 && hz.is_finite()) {
            return Err(DynamicsError::BelowFrequency(hz));
        }
        let (nx, nq, _) = self.sizes;
        let n = nx + nq;
        let lambda_max = (TWO_PI * hz).powi(2);
        let k = self.master_values(damping, 0.0).0;
        let m = &self.mass_on_pattern;
        let mass = SparseColumns::from_mass(&self.mass);
        if (0..nx).any(|i| self.mass[(i, i)] <= 0.0) {
            let weakest = (0..nx)
                .min_by(|&i, &j| self.mass[(i, i)].total_cmp(&self.mass[(j, j)]))
                .unwrap_or(0);
            return Err(DynamicsError::SingularMass {
                variable: self.variables.get(weakest).cloned().unwrap_or_default(),
            });
        }

        // how many eigenvalues lie below λ_max: inertia of the joint matrix minus that of
        // the float block (inertia(joint) = inertia(Q) + inertia(K_eff − λ M))
        let joint = Unknowns::new(self, 0..n);
        let floats = Unknowns::new(self, nx..n);
        let mut counter = ModeCounter {
            float_negatives: Inertia::new(&floats)?.negatives(&floats.values(&k, m, 0.0)),
            joint: Inertia::new(&joint)?,
            k: &k,
            m,
        };
        let wanted = (0..4).find_map(|attempt| {
            // a pivot exactly zero (an eigenvalue exactly at the bound): nudge the bound
            counter.below(lambda_max * (1.0 + 1e-12 * attempt as f64))
        });
        // how many lie below zero, the same way: the growing modes, which must all be
        // among those found (a pivot of rounding size may count a neutral mode either way)
        let growing = counter.below(0.0);
        if wanted == Some(0) {
            return Ok(Modes {
                coordinates: self.variables.clone(),
                modes: Vec::new(),
            });
        }
        let slices = match wanted {
            Some(wanted) => plan_slices(&mut counter, lambda_max, wanted),
            None => vec![Slice {
                low: f64::NEG_INFINITY,
                high: lambda_max,
                count: None,
            }],
        };
        // one symbolic analysis of the joint pattern; each slice factorises its own shift
        let mut lu = SparseLu::<f64>::new(joint.col_ptr.clone(), joint.row_idx.clone())?;
        let mut raw = Vec::new();
        for slice in &slices {
            raw.extend(self.slice_modes(&joint, &mut lu, &k, &mass, slice, lambda_max)?);
        }
        let modes = finish(raw, &[(0..nx).collect()], &mass, &self.variables, rounding);
        // every growing mode the inertia counts is among the modes found (growing, or
        // neutral within its error); one beyond the shift's resolution is not reported
        // as a verdict from an incomplete list
        let found_growing = modes.iter().filter(|m| m.omega_squared <= 0.0).count();
        if let Some(growing) = growing
            && found_growing < growing
        {
            return Err(DynamicsError::Solver(format!(
                "shift-invert resolved {found_growing} of the {growing} growing modes the inertia counts"
            )));
        }
        Ok(Modes {
            coordinates: self.variables.clone(),
            modes,
        })
    }
}

impl StageModel {
    /// The modes in one `slice` of the spectrum: block Lanczos with full
    /// reorthogonalisation on (K − σM)⁻¹M, σ the slice's shift, until as many Ritz pairs
    /// in the slice as it holds have converged (or the basis spans every variable). `lu`
    /// holds the joint pattern's symbolic analysis, shared by the slices; it is factorised
    /// here at the slice's shift.
    #[expect(
        clippy::too_many_lines,
        reason = "one shift-invert block Lanczos run: the factorised operator and the basis Q, W, \
                  MQ are the shared state of the loop that grows the basis and runs Rayleigh–Ritz, \
                  read in the order the algorithm takes its steps"
    )]
    fn slice_modes(
        &self,
        joint: &Unknowns,
        lu: &mut SparseLu<f64>,
        k: &[f64],
        mass: &SparseColumns,
        slice: &Slice,
        lambda_max: f64,
    ) -> Result<Vec<RawMode>, DynamicsError> {
        let (nx, nq, _) = self.sizes;
        let n = nx + nq;
        let m = &self.mass_on_pattern;
        // a shift exactly on an eigenvalue leaves K − σM singular: nudged
        let shift = slice.shift(lambda_max);
        let sigma = (0..4)
            .map(|attempt| shift * (1.0 + 1e-9 * attempt as f64))
            .find(|&sigma| lu.factor(&joint.values(k, m, sigma)))
            .ok_or_else(|| {
                DynamicsError::Solver(
                    "K − σM could not be factorised for the shift-invert modes".into(),
                )
            })?;
        let mut rhs = vec![0.0; n];
        let mut op = |v: &[f64]| -> Result<Vec<f64>, DynamicsError> {
            rhs[..nx].copy_from_slice(&mass.times(v));
            rhs[nx..].fill(0.0);
            if !lu.solve(&mut rhs) || rhs.iter().any(|x| !x.is_finite()) {
                return Err(DynamicsError::Solver(
                    "shift-invert solve is not finite (K − σM singular)".into(),
                ));
            }
            Ok(rhs[..nx].to_vec())
        };

        // M-orthonormal basis Q, its images W = Op Q and M Q
        let mut q: Vec<Vec<f64>> = Vec::new();
        let mut w: Vec<Vec<f64>> = Vec::new();
        let mut mq: Vec<Vec<f64>> = Vec::new();
        let mut block = start_block(nx, BLOCK.min(nx), 1);
        let mut seed = 1;
        let mut found: Vec<(f64, Vec<f64>, f64)> = Vec::new();
        let mut projected: Vec<Vec<f64>> = Vec::new();
        loop {
            let mut added = 0;
            for mut v in block.drain(..) {
                let original = dot(&v, &mass.times(&v)).sqrt();
                for _ in 0..2 {
                    for (qj, mqj) in q.iter().zip(&mq) {
                        let c = dot(mqj, &v);
                        v.iter_mut().zip(qj).for_each(|(x, y)| *x -= c * y);
                    }
                }
                let mv = mass.times(&v);
                let norm = dot(&v, &mv).sqrt();
                // (a NaN norm counts as dependent too)
                if norm.is_nan() || norm <= 1e-10 * original {
                    continue;
                }
                v.iter_mut().for_each(|x| *x /= norm);
                let image = op(&v)?;
                mq.push(mv.iter().map(|x| x / norm).collect());
                q.push(v);
                w.push(image);
                added += 1;
            }
            let dim = q.len();
            let complete = dim >= nx;
            if added == 0 && !complete {
                // the Krylov space closed without the wanted modes: restart from new vectors
                seed += 1;
                block = start_block(nx, BLOCK.min(nx), seed);
                continue;
            }
            // Rayleigh–Ritz every few blocks once enough vectors are in
            let due = complete
                || (dim >= slice.count.unwrap_or(0) + BLOCK && (dim / BLOCK).is_multiple_of(3));
            if due {
                // the projected operator's lower triangle, extended by the new basis
                // vectors' rows only (the earlier entries do not change as the basis grows)
                for i in projected.len()..dim {
                    projected.push(
                        (0..=i)
                            .map(|j| 0.5 * (dot(&mq[i], &w[j]) + dot(&mq[j], &w[i])))
                            .collect(),
                    );
                }
                let t = Mat::from_fn(dim, dim, |i, j| {
                    if j <= i {
                        projected[i][j]
                    } else {
                        projected[j][i]
                    }
                });
                let (theta, y) = crate::modes::symmetric_eigen(&t)?;
                found.clear();
                let mut all_converged = true;
                // the Rayleigh–Ritz values carry an absolute error of a few ulps of the
                // largest |θ| (the eigen-solve of T and the rounding of the operator's
                // images): a |θ| at that level is not resolved, and λ = σ + 1/θ from it
                // would be a spurious mode far above or below (a tiny negative θ from
                // rounding reads as a huge growth rate)
                let theta_max = (0..dim).map(|j| theta[j].abs()).fold(0.0, f64::max);
                let unresolved = ritz_noise(dim, theta_max);
                for j in 0..dim {
                    let th = theta[j];
                    if th.abs() <= unresolved {
                        continue;
                    }
                    let lambda = sigma + 1.0 / th;
                    if lambda < slice.low || lambda >= slice.high {
                        continue;
                    }
                    let mut u = vec![0.0; nx];
                    let mut r = vec![0.0; nx];
                    for i in 0..dim {
                        let c = y[(i, j)];
                        u.iter_mut().zip(&q[i]).for_each(|(a, b)| *a += c * b);
                        r.iter_mut().zip(&w[i]).for_each(|(a, b)| *a += c * b);
                    }
                    r.iter_mut().zip(&u).for_each(|(a, b)| *a -= th * b);
                    let residual = dot(&r, &mass.times(&r)).sqrt();
                    if residual <= TOLERANCE * th.abs() || complete {
                        // δλ = δθ/θ² for the Ritz value's own rounding
                        found.push((lambda, u, unresolved / (th * th)));
                    } else {
                        all_converged = false;
                    }
                }
                let enough = slice.count.is_some_and(|c| found.len() >= c);
                if complete || (enough && all_converged) {
                    break;
                }
            }
            block = w[dim - added..].to_vec();
        }
        // a converged Ritz value θ is within TOLERANCE |θ| of an eigenvalue of the operator,
        // so λ = σ + 1/θ within TOLERANCE |λ − σ|
        Ok(found
            .into_iter()
            .map(|(lambda, u, rounding)| RawMode {
                omega_squared: lambda,
                error: TOLERANCE * (lambda - sigma).abs() + rounding,
                vector: u,
                block: 0,
            })
            .collect())
    }
}
