//! Whether an equilibrium is stable, and what grows when it is not: a typed verdict from
//! a stage's modes and its float block, with every growing mode's growth rate and dominant
//! coordinates, floats that have no stable position, and bodies that hang upside down.
//!
//! The equilibrium is stable when the stiffness over the variables *and* the floats is
//! positive definite. By the inertia additivity of the Schur complement (Haynsworth), the
//! negative eigenvalues of that matrix are those of the float block Q (with the variables
//! held) plus those of K_eff = K − C Q⁻¹ Cᵀ (with the floats following), so both are checked:
//! a float whose block is indefinite is massless and sits on a maximum of the potential, it
//! runs away at once (an infinite growth rate), whatever K_eff says. A mode or a float
//! stiffness is counted as negative only when it lies below minus its estimated error
//! (rounding of the terms' Hessians and of the eigensolver); within it, it is neutral.
//!
//! [`TermRounding`] is that estimate for the assembled stage: each entry of each term's
//! Hessian is known to a few ulps of itself, and each term's geometric stiffness (tension
//! on minus tension off) to a few ulps of its *stiffness* part: a wire's geometric
//! stiffness T/l is k (l − l₀)/l with l − l₀ a small difference of lengths, so it carries
//! about ε k of error, not ε T/l (the inverse strain, 1e3–1e4 for steel wires and silica
//! fibres, times more). The floats' share of a mode comes from the float-elimination map
//! z_q = −Q⁻¹ C_qx v.

use std::fmt;

use nalgebra::DMatrix;
use pendkit_assembly::{Assembled, OffHessian};
use pendkit_system::{Damping, System};

use crate::DynamicsError;
use crate::modes::{Modes, ROUNDING, StiffnessRounding};
use crate::pattern::Pattern;
use crate::stage::StageModel;

/// The stability of an equilibrium.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Every mode has ω² above its error and every float is held: a minimum of the
    /// potential.
    Stable,
    /// Nothing grows, but some mode has ω² within its error of zero (a free coordinate, or
    /// a stiffness too small to tell from rounding).
    Neutral,
    /// Some mode grows (ω² below minus its error) or some float has no stable position.
    Unstable,
    /// Nothing grows, but a body with mass hangs upside down (its z axis below the
    /// horizontal): a minimum other than the hanging equilibrium, reached from a bad start.
    /// Not reported as stable: it is not the suspension asked about.
    Inverted,
}

/// A mode that grows exponentially: e^{2π rate t}.
#[derive(Clone, Debug, PartialEq)]
pub struct GrowingMode {
    /// 1-based number of the mode in ascending order of ω² among the stage's modes.
    pub index: usize,
    /// Growth rate sqrt(−ω²)/2π (Hz).
    pub rate_hz: f64,
    /// Estimated relative error of the growth rate.
    pub accuracy: f64,
    /// The coordinates with the largest kinetic-energy fractions (name, fraction 0–1).
    pub dominant: Vec<(String, f64)>,
}

/// A direction of the float block with negative stiffness: with the variables held, the
/// massless floats have no stable position along it.
#[derive(Clone, Debug, PartialEq)]
pub struct RunawayFloat {
    /// Stiffness along the direction (N/m, N m/rad for angles; a unit vector over the
    /// floats): negative, or within `error` of zero.
    pub stiffness: f64,
    /// Estimated error of `stiffness` (same units). A stiffness within it of zero is a
    /// runaway direction only when the floats along it are coupled to the variables so
    /// strongly that, whichever its sign within the error, the potential goes downhill:
    /// negative, the floats run away; positive, following the variables they turn the
    /// variables' stiffness negative (see [`runaway_floats`]).
    pub error: f64,
    /// The floats with the largest shares of the direction (name, share 0–1).
    pub floats: Vec<(String, f64)>,
}

/// The float block's directions that decide the verdict: those with no stable position,
/// and those whose stiffness is zero within its error (sign not determined) but whose
/// coupling to the variables is too weak to make either sign unstable.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FloatDirections {
    /// Directions where the massless floats have no stable position.
    pub runaway: Vec<RunawayFloat>,
    /// Directions with stiffness zero within its error: nothing shown to grow, but a
    /// stable verdict would rest on a sign rounding cannot tell.
    pub neutral: Vec<RunawayFloat>,
}

/// A body whose frame's z axis points below the horizontal at equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct InvertedBody {
    /// Body name.
    pub body: String,
    /// Angle between its z axis and the lab's (degrees, above 90).
    pub tilt_deg: f64,
}

/// The stability report of an equilibrium: the verdict and the evidence.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    /// Stable, neutral or unstable.
    pub verdict: Verdict,
    /// The growing modes, fastest first.
    pub growing: Vec<GrowingMode>,
    /// Float directions with negative stiffness.
    pub runaway_floats: Vec<RunawayFloat>,
    /// Float directions with zero stiffness within its error, weakly coupled: neutral.
    pub neutral_floats: Vec<RunawayFloat>,
    /// Number of neutral modes (ω² = 0 within its error).
    pub neutral: usize,
    /// Number of directions the potential was examined in: modes plus floats.
    pub directions: usize,
    /// Bodies hanging upside down (tilted past 90°), often the sign of an equilibrium
    /// reached from a bad start.
    pub inverted: Vec<InvertedBody>,
}

impl Stability {
    /// The verdict from modes alone (no floats, no bodies): for [`Modes::check_stable`].
    pub fn of_modes(modes: &Modes) -> Stability {
        Stability::assess(modes, FloatDirections::default(), 0, Vec::new())
    }

    /// The verdict from a stage's modes (which must include every mode with ω² < 0: all of
    /// them, or those below a positive frequency), the runaway and neutral directions of
    /// its float block among `floats` floats ([`float_directions`]), and the bodies found
    /// upside down.
    pub fn assess(
        modes: &Modes,
        float_directions: FloatDirections,
        floats: usize,
        inverted: Vec<InvertedBody>,
    ) -> Stability {
        let FloatDirections {
            runaway: runaway_floats,
            neutral: neutral_floats,
        } = float_directions;
        let mut growing: Vec<GrowingMode> = modes
            .modes
            .iter()
            .enumerate()
            .filter(|(_, m)| m.omega_squared < 0.0)
            .map(|(i, m)| GrowingMode {
                index: i + 1,
                rate_hz: -m.hz,
                accuracy: m.accuracy(),
                dominant: m.dominant(&modes.coordinates, 3),
            })
            .collect();
        growing.sort_by(|a, b| b.rate_hz.total_cmp(&a.rate_hz));
        let neutral = modes
            .modes
            .iter()
            .filter(|m| m.omega_squared == 0.0)
            .count();
        let verdict = if !growing.is_empty() || !runaway_floats.is_empty() {
            Verdict::Unstable
        } else if !inverted.is_empty() {
            Verdict::Inverted
        } else if neutral > 0 || !neutral_floats.is_empty() {
            Verdict::Neutral
        } else {
            Verdict::Stable
        };
        Stability {
            verdict,
            growing,
            runaway_floats,
            neutral_floats,
            neutral,
            // any count of floats is a count, never an overflow
            directions: modes.coordinates.len().saturating_add(floats),
            inverted,
        }
    }

    /// `Err(DynamicsError::Unstable)` (one line naming what grows, or which bodies hang
    /// upside down) unless the equilibrium is stable or neutral.
    pub fn check(&self) -> Result<(), DynamicsError> {
        match self.verdict {
            Verdict::Unstable | Verdict::Inverted => {
                Err(DynamicsError::Unstable(Box::new(self.clone())))
            }
            Verdict::Stable | Verdict::Neutral => Ok(()),
        }
    }

    /// Whether the equilibrium is the hanging one and nothing grows (stable or neutral).
    pub fn is_stable(&self) -> bool {
        matches!(self.verdict, Verdict::Stable | Verdict::Neutral)
    }
}

/// "pitch3 68 %, pitch2 29 %".
fn shares(list: &[(String, f64)]) -> String {
    list.iter()
        .map(|(name, f)| format!("{name} {:.0} %", 100.0 * f))
        .collect::<Vec<_>>()
        .join(", ")
}

impl fmt::Display for Stability {
    /// One line: what grows, fastest first, and what kind of stationary point this is.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.verdict {
            Verdict::Stable => return write!(f, "stable equilibrium (a minimum of the potential)"),
            Verdict::Neutral => {
                write!(f, "neutral equilibrium: ")?;
                if self.neutral > 0 {
                    write!(
                        f,
                        "{} mode(s) with zero stiffness within rounding, ",
                        self.neutral
                    )?;
                }
                for r in &self.neutral_floats {
                    let names: Vec<&str> = r.floats.iter().map(|(n, _)| n.as_str()).collect();
                    write!(
                        f,
                        "float(s) {} with stiffness {:.1e} ± {:.1e} N/m or N m/rad (variables held), zero within rounding: its sign, and whether they run away, cannot be told, ",
                        names.join(", "),
                        r.stiffness,
                        r.error
                    )?;
                }
                return write!(f, "nothing is shown to grow");
            }
            Verdict::Inverted => {
                let bodies: Vec<String> = self
                    .inverted
                    .iter()
                    .map(|b| format!("'{}' ({:.0}°)", b.body, b.tilt_deg))
                    .collect();
                return write!(
                    f,
                    "inverted equilibrium: nothing grows, but {} hang(s) upside down (tilted past 90°): a minimum other than the hanging one, reached from a bad start",
                    bodies.join(", ")
                );
            }
            Verdict::Unstable => {}
        }
        write!(f, "unstable equilibrium: ")?;
        let mut parts = Vec::new();
        for r in &self.runaway_floats {
            let names: Vec<&str> = r.floats.iter().map(|(n, _)| n.as_str()).collect();
            let what = if names.len() == 1 {
                format!("float '{}' has", names[0])
            } else {
                format!("floats {} have", names.join(", "))
            };
            if r.stiffness < -r.error {
                parts.push(format!(
                    "{what} no stable position (stiffness {:.4e} N/m or N m/rad with the variables held: a massless coordinate on a maximum of the potential moves without limit)",
                    r.stiffness
                ));
            } else {
                parts.push(format!(
                    "{what} no stable position within rounding (stiffness {:.1e} ± {:.1e} N/m or N m/rad with the variables held, zero within its error, and coupled to the variables so strongly that either sign goes downhill: negative, the massless coordinate runs away; positive, following the variables it makes their stiffness negative)",
                    r.stiffness, r.error
                ));
            }
        }
        if let Some(g) = self.growing.first() {
            let more = if self.growing.len() > 1 {
                format!(" ({} growing modes, this the fastest)", self.growing.len())
            } else {
                String::new()
            };
            parts.push(format!(
                "mode {} grows at {:.6} Hz (e-folding time {:.3e} s){more}, mostly {}",
                g.index,
                g.rate_hz,
                1.0 / (2.0 * std::f64::consts::PI * g.rate_hz),
                shares(&g.dominant)
            ));
        }
        let downhill = self.growing.len() + self.runaway_floats.len();
        let kind = if downhill >= self.directions && self.directions > 0 {
            "a maximum of the potential".to_string()
        } else {
            format!(
                "a saddle of the potential: {downhill} of {} directions go downhill",
                self.directions.max(downhill)
            )
        };
        parts.push(kind);
        if !self.inverted.is_empty() {
            let bodies: Vec<String> = self
                .inverted
                .iter()
                .map(|b| format!("'{}' ({:.0}°)", b.body, b.tilt_deg))
                .collect();
            parts.push(format!(
                "upside down (tilted past 90°, started from a bad position?): {}",
                bodies.join(", ")
            ));
        }
        write!(f, "{}", parts.join("; "))
    }
}

/// The float-elimination map at f = 0: the floats' displacement −Q⁻¹ C_qx v that follows
/// a displacement v of the variables (m or rad), from the stage's real stiffness. Kept per
/// group of floats that Q couples (each fibre's bead joints, each blade's tip): the map is
/// zero between a group and the variables it does not touch.
#[derive(Clone, Debug)]
pub struct FloatMap {
    nx: usize,
    nq: usize,
    /// Per group: its floats (0-based among the floats), the variables it couples to, and
    /// −Q_g⁻¹ C_g over them; empty when there are no floats or Q is singular.
    groups: Vec<(Vec<usize>, Vec<usize>, DMatrix<f64>)>,
}

/// The float block Q (nq × nq) and the float–variable coupling C (nq × nx) of `model` at
/// f = 0 with `damping`'s ε'(0), and the real stiffness's values they were taken from (on
/// the stage's pattern).
fn float_blocks(model: &StageModel, damping: &Damping) -> (DMatrix<f64>, DMatrix<f64>, Vec<f64>) {
    let (nx, nq, _) = model.sizes;
    let (re, _) = model.master_values(damping, 0.0);
    let mut q = DMatrix::zeros(nq, nq);
    let mut c = DMatrix::zeros(nq, nx);
    for (s, &v) in re.iter().enumerate() {
        let (r, col) = model.pattern.position(s);
        if (nx..nx + nq).contains(&r) {
            if (nx..nx + nq).contains(&col) {
                q[(r - nx, col - nx)] = v;
            } else if col < nx {
                c[(r - nx, col)] = v;
            }
        }
    }
    (q, c, re)
}

impl FloatMap {
    /// The map of `model` with `damping`'s ε'(0).
    pub fn new(model: &StageModel, damping: &Damping) -> Self {
        let (nx, nq, _) = model.sizes;
        let (q, c, _) = float_blocks(model, damping);
        let mut groups = Vec::new();
        for group in crate::schur::components(nq, |i, j| q[(i, j)] != 0.0) {
            let variables: Vec<usize> = (0..nx)
                .filter(|&j| group.iter().any(|&f| c[(f, j)] != 0.0))
                .collect();
            let qg = DMatrix::from_fn(group.len(), group.len(), |i, j| q[(group[i], group[j])]);
            let cg = DMatrix::from_fn(group.len(), variables.len(), |i, j| {
                c[(group[i], variables[j])]
            });
            match qg.full_piv_lu().solve(&cg) {
                Some(x) if x.iter().all(|v| v.is_finite()) => groups.push((group, variables, -x)),
                // Q singular: no map (the elimination itself reports the float)
                _ => {
                    groups.clear();
                    break;
                }
            }
        }
        FloatMap { nx, nq, groups }
    }

    /// [v; −Q⁻¹ C_qx v] over the variables and the floats.
    pub fn extend(&self, v: &[f64]) -> Vec<f64> {
        let mut z: Vec<f64> = v.iter().copied().take(self.nx).collect();
        z.resize(self.nx + self.nq, 0.0);
        let (variables, floats) = z.split_at_mut(self.nx);
        for (group, coupled, map) in &self.groups {
            // by columns of the map (its storage order), skipping the variables a mode
            // leaves still
            for (column, &j) in map.column_iter().zip(coupled) {
                let x = variables[j];
                if x != 0.0 {
                    for (&f, m) in group.iter().zip(column.iter()) {
                        floats[f] += m * x;
                    }
                }
            }
        }
        z
    }

    /// Whether the float block Q is singular: then there is no map (it is empty, and
    /// [`FloatMap::matrix`] is zero).
    pub fn is_singular(&self) -> bool {
        self.nq > 0 && self.groups.is_empty()
    }

    /// The map −Q⁻¹ C_qx itself (floats × variables).
    pub fn matrix(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.nq, self.nx);
        for (group, coupled, map) in &self.groups {
            for (a, &f) in group.iter().enumerate() {
                for (b, &j) in coupled.iter().enumerate() {
                    m[(f, j)] = map[(a, b)];
                }
            }
        }
        m
    }
}

/// One term's geometric stiffness for the term-by-term estimate: the part whose rounding
/// is amplified (see [`TermRounding`]), over the term's coordinates that are unknowns.
struct GeometricPart {
    /// Master positions (variables and floats) of the term's unknown coordinates.
    positions: Vec<usize>,
    /// H_on − H_off over those positions, row-major (positions.len()²).
    values: Vec<f64>,
    /// a_t = max|H_off| / max|H_on − H_off|, at least 1: the geometric stiffness is a force
    /// times a curvature, and the force (k times a small difference of lengths) carries the
    /// rounding of the stiffness times the lengths, not of itself.
    amplification: f64,
}

impl GeometricPart {
    /// |zᵀ (H_on − H_off) z| over this term's positions.
    fn form(&self, z: &[f64]) -> f64 {
        // the term's few coordinates gathered on the stack (a term couples at most a few
        // bodies' coordinates; larger ones take the heap)
        const ON_STACK: usize = 32;
        let n = self.positions.len();
        let mut stack = [0.0; ON_STACK];
        let mut heap = Vec::new();
        let local: &mut [f64] = if n <= ON_STACK {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap
        };
        for (x, &p) in local.iter_mut().zip(&self.positions) {
            *x = z.get(p).copied().unwrap_or(0.0);
        }
        if local.iter().all(|&x| x == 0.0) {
            return 0.0;
        }
        let mut sum = 0.0;
        for (a, row) in self.values.chunks_exact(n.max(1)).enumerate() {
            if local[a] != 0.0 {
                let row_dot: f64 = row.iter().zip(local.iter()).map(|(g, zb)| g * zb).sum();
                sum += local[a] * row_dot;
            }
        }
        sum.abs()
    }
}

/// The rounding of an assembled stage's stiffness, term by term (see the module
/// documentation), for a mode shape z over the variables and floats:
/// ROUNDING ε Σ_t [ |z|ᵀ (|H_on| + |H_off|) |z| + a_t |zᵀ (H_on − H_off) z| ], the first
/// sum the rounding of the entries as stored, the second that of each term's geometric
/// stiffness, amplified by a_t = max|H_off| / max|H_on − H_off| (for a wire, k l / T: the
/// inverse strain).
///
/// The first sum is linear in the terms, so it is added up once on the stage's pattern and
/// costs one sparse quadratic form per mode. The second is not (the absolute value is per
/// term), so [`TermRounding::error_unknowns`] evaluates it term by term; replacing each
/// |zᵀ G_t z| by its upper bound |z|ᵀ |G_t| |z| makes it linear too, and
/// [`TermRounding::bound_unknowns`] is that bound, one sparse form per mode. The modes use
/// the bound where it already shows a mode resolved far better than anything reported
/// (see `modes::REFINE_ABOVE`), and the term-by-term estimate elsewhere.
pub struct TermRounding {
    /// The entries part and the bound on the stage's pattern.
    stored: AbsWeights,
    /// The same at positions the pattern does not store (the terms there sum to an exact
    /// zero, each term's own entries need not be zero).
    unstored: AbsWeights,
    /// `unstored` without the positions that join two of the pattern's exactly decoupled
    /// blocks: a vector within one block (a mode with its floats) meets only these, the
    /// others multiply its exact zeros.
    unstored_within: AbsWeights,
    /// The block of each unknown (the pattern's connected components).
    block_of: Vec<usize>,
    /// The terms with a geometric part.
    geometric: Vec<GeometricPart>,
    /// `geometric_terms[geometric_start[p]..geometric_start[p + 1]]`: the geometric terms at
    /// unknown p, ascending (a mode's refined estimate visits the terms at its block only).
    geometric_start: Vec<usize>,
    geometric_terms: Vec<usize>,
    floats: FloatMap,
    unknowns: usize,
}

/// A term's tension-off Hessian (row-major, as `on`); `zeros` (at least as long as `on`)
/// stands for an exact zero one, or one of the wrong size.
fn off_values<'a>(off: &'a OffHessian, on: &'a [f64], zeros: &'a [f64]) -> &'a [f64] {
    match off {
        OffHessian::Same => on,
        OffHessian::Matrix(m) if m.len() == on.len() => m,
        _ => &zeros[..on.len().min(zeros.len())],
    }
}

/// Two sets of non-negative weights on one sparsity pattern (compressed rows), for the forms
/// Σ w_rc |z_r| |z_c|: the rounding of the stored entries, Σ_t (|H_off s + G| + |H_off s|)
/// (s: the tag's storage multiplier ε'(0) if above 1; G = H_on − H_off), and the bound,
/// that plus Σ_t a_t |G|.
struct AbsWeights {
    row_start: Vec<usize>,
    cols: Vec<usize>,
    entries: Vec<f64>,
    bound: Vec<f64>,
}

impl AbsWeights {
    fn on(pattern: &Pattern) -> Self {
        let rows = pattern.dim();
        AbsWeights {
            row_start: (0..rows)
                .map(|r| pattern.row_slots(r).start)
                .chain([pattern.len()])
                .collect(),
            cols: (0..pattern.len()).map(|s| pattern.position(s).1).collect(),
            entries: vec![0.0; pattern.len()],
            bound: vec![0.0; pattern.len()],
        }
    }

    /// Σ w_rc |z_r| |z_c| over rows and columns below `unknowns` (`bound`: the bound's
    /// weights, else the entries').
    fn form(&self, bound: bool, unknowns: usize, z: &[f64]) -> f64 {
        let weights = if bound { &self.bound } else { &self.entries };
        let mut sum = 0.0;
        for (r, &zr) in z.iter().enumerate().take(unknowns) {
            let Some(range) = self.row_range(r) else {
                break;
            };
            if zr != 0.0 {
                sum += zr.abs() * self.row_form(weights, range, unknowns, z);
            }
        }
        sum
    }

    /// Where row `r`'s entries are stored, if it is stored.
    fn row_range(&self, r: usize) -> Option<std::ops::Range<usize>> {
        Some(*self.row_start.get(r)?..*self.row_start.get(r + 1)?)
    }

    /// Σ_c w_rc |z_c| over the stored `range` of one row, columns below `unknowns`.
    fn row_form(
        &self,
        weights: &[f64],
        range: std::ops::Range<usize>,
        unknowns: usize,
        z: &[f64],
    ) -> f64 {
        let mut row = 0.0;
        for (&c, w) in self.cols[range.clone()].iter().zip(&weights[range]) {
            if c < unknowns
                && let Some(zc) = z.get(c)
            {
                row += w * zc.abs();
            }
        }
        row
    }
}

impl AbsWeights {
    /// [`AbsWeights::form`] over the listed `rows` only (ascending), for a `z` that is zero
    /// on every other row: the same sum in the same order.
    fn form_rows(&self, bound: bool, unknowns: usize, z: &[f64], rows: &[usize]) -> f64 {
        let weights = if bound { &self.bound } else { &self.entries };
        let mut sum = 0.0;
        for &r in rows.iter().take_while(|&&r| r < unknowns) {
            let (Some(&zr), Some(range)) = (z.get(r), self.row_range(r)) else {
                break;
            };
            if zr != 0.0 {
                sum += zr.abs() * self.row_form(weights, range, unknowns, z);
            }
        }
        sum
    }
}

impl TermRounding {
    /// The rounding of `assembled`'s terms on `model` (the stage built from it).
    #[expect(
        clippy::too_many_lines,
        reason = "one linear-time pass over the terms and then their rows: the flat per-term arrays \
                  (scales, locals, first_local) built first are the index the row-by-row sums read, \
                  and each slot must receive its terms in term order"
    )]
    pub fn new(model: &StageModel, assembled: &Assembled, damping: &Damping) -> Self {
        let unknowns = model.unknowns();
        let mut stored = AbsWeights::on(&model.pattern);
        let mut geometric = Vec::new();
        let mut storages: Vec<(&str, f64)> = Vec::new();
        // per term: its storage multiplier, amplification, and (local index, master
        // position) of its coordinates that are unknowns, flat
        let mut scales: Vec<(f64, f64)> = Vec::with_capacity(assembled.terms.len());
        let mut first_local = Vec::with_capacity(assembled.terms.len() + 1);
        first_local.push(0);
        let mut locals: Vec<(usize, usize)> = Vec::new();
        let zeros = vec![
            0.0;
            assembled
                .terms
                .iter()
                .map(|t| t.on.len())
                .max()
                .unwrap_or(0)
        ];
        for t in &assembled.terms {
            let size = t.coords.len();
            let start = locals.len();
            if t.on.len() == size * size {
                locals.extend(t.coords.iter().enumerate().filter_map(|(a, &g)| {
                    let p = *assembled.layout.position.get(g)?;
                    (p < unknowns).then_some((a, p))
                }));
            }
            first_local.push(locals.len());
            let positions = &locals[start..];
            if positions.is_empty() {
                scales.push((1.0, 1.0));
                continue;
            }
            let off = off_values(&t.off, &t.on, &zeros);
            let (mut off_max, mut g_max) = (0.0f64, 0.0f64);
            for (&on, &off) in t.on.iter().zip(off) {
                off_max = off_max.max(off.abs());
                g_max = g_max.max((on - off).abs());
            }
            let amplification = if g_max > 0.0 {
                (off_max / g_max).clamp(1.0, 1.0 / f64::EPSILON)
            } else {
                1.0
            };
            // the tag's ε'(0), evaluated once per tag (a model has a few tags, many terms)
            let storage = match storages.iter().find(|(tag, _)| *tag == t.tag.as_str()) {
                Some(&(_, storage)) => storage,
                None => {
                    let storage = damping.at(&t.tag, 0.0).0.abs();
                    let storage = if storage.is_finite() {
                        storage.max(1.0)
                    } else {
                        1.0
                    };
                    storages.push((t.tag.as_str(), storage));
                    storage
                }
            };
            scales.push((storage, amplification));
            if g_max > 0.0 {
                let mut values = Vec::with_capacity(positions.len() * positions.len());
                for &(a, _) in positions {
                    for &(b, _) in positions {
                        let k = a * size + b;
                        values.push(t.on[k] - off[k]);
                    }
                }
                geometric.push(GeometricPart {
                    positions: positions.iter().map(|&(_, p)| p).collect(),
                    values,
                    amplification,
                });
            }
        }
        // the terms' rows by unknown, in term order: (term, index among its unknowns)
        let mut row_start = vec![0usize; unknowns + 1];
        for &(_, p) in &locals {
            row_start[p + 1] += 1;
        }
        for p in 0..unknowns {
            row_start[p + 1] += row_start[p];
        }
        let mut next = row_start.clone();
        let mut row_terms = vec![(0usize, 0usize); locals.len()];
        for (t, w) in first_local.windows(2).enumerate() {
            for (i, &(_, p)) in locals[w[0]..w[1]].iter().enumerate() {
                row_terms[next[p]] = (t, i);
                next[p] += 1;
            }
        }
        // row by row: the stored slot of each column (tagged by the row it was set for,
        // so nothing is reset), and the positions the pattern lacks (the terms there sum
        // to an exact zero, each term's own entries need not be zero) gathered per row.
        // Each slot receives the terms in term order, as a pass over the terms would add
        // them.
        const NONE: usize = usize::MAX;
        let mut slot_of_column = vec![(NONE, 0usize); unknowns];
        let mut unstored_at = vec![(NONE, 0usize); unknowns];
        let empty = || AbsWeights {
            row_start: vec![0],
            cols: Vec::new(),
            entries: Vec::new(),
            bound: Vec::new(),
        };
        let (mut unstored, mut unstored_within) = (empty(), empty());
        let block_of: Vec<usize> = (0..unknowns)
            .map(|p| model.blocks.get(p).copied().unwrap_or(p))
            .collect();
        let mut row_unstored: Vec<(usize, f64, f64)> = Vec::new();
        for pa in 0..unknowns {
            let (start, end) = (stored.row_start[pa], stored.row_start[pa + 1]);
            for (s, &c) in (start..end).zip(&stored.cols[start..end]) {
                if c < unknowns {
                    slot_of_column[c] = (pa, s);
                }
            }
            row_unstored.clear();
            for &(t, i) in &row_terms[row_start[pa]..row_start[pa + 1]] {
                let term = &assembled.terms[t];
                let size = term.coords.len();
                let (storage, amplification) = scales[t];
                let positions = &locals[first_local[t]..first_local[t + 1]];
                let a = positions[i].0;
                let on = &term.on[a * size..(a + 1) * size];
                let off = &off_values(&term.off, &term.on, &zeros)[a * size..(a + 1) * size];
                for &(b, pb) in positions {
                    let (on, off) = (on[b], off[b]);
                    // most of a term's local entries are exact zeros (a vertical wire does
                    // not couple x to y): their weights are +0, which leave every sum
                    // below as it is (the sums start at +0 and add only non-negative
                    // numbers), so they are skipped
                    if on == 0.0 && off == 0.0 {
                        continue;
                    }
                    let g = on - off;
                    let entries = (off * storage + g).abs() + (off * storage).abs();
                    let bound = entries + amplification * g.abs();
                    match slot_of_column[pb] {
                        (row, s) if row == pa => {
                            stored.entries[s] += entries;
                            stored.bound[s] += bound;
                        }
                        _ if bound != 0.0 => match unstored_at[pb] {
                            (row, u) if row == pa => {
                                row_unstored[u].1 += entries;
                                row_unstored[u].2 += bound;
                            }
                            _ => {
                                unstored_at[pb] = (pa, row_unstored.len());
                                row_unstored.push((pb, entries, bound));
                            }
                        },
                        _ => {}
                    }
                }
            }
            row_unstored.sort_unstable_by_key(|&(c, _, _)| c);
            for &(c, entries, bound) in &row_unstored {
                unstored.cols.push(c);
                unstored.entries.push(entries);
                unstored.bound.push(bound);
                if block_of[c] == block_of[pa] {
                    unstored_within.cols.push(c);
                    unstored_within.entries.push(entries);
                    unstored_within.bound.push(bound);
                }
            }
            unstored.row_start.push(unstored.cols.len());
            unstored_within.row_start.push(unstored_within.cols.len());
        }
        // for each unknown, the geometric terms at it (ascending), in compressed rows
        let mut geometric_start = vec![0usize; unknowns + 1];
        for part in &geometric {
            for &p in &part.positions {
                geometric_start[p + 1] += 1;
            }
        }
        for p in 0..unknowns {
            geometric_start[p + 1] += geometric_start[p];
        }
        let mut next = geometric_start.clone();
        let mut geometric_terms = vec![0usize; geometric_start[unknowns]];
        for (t, part) in geometric.iter().enumerate() {
            for &p in &part.positions {
                geometric_terms[next[p]] = t;
                next[p] += 1;
            }
        }
        TermRounding {
            stored,
            unstored,
            unstored_within,
            block_of,
            geometric,
            geometric_start,
            geometric_terms,
            floats: FloatMap::new(model, damping),
            unknowns,
        }
    }

    /// The forms over the listed `rows` (ascending, every row where `z` is non-zero among
    /// them): [`TermRounding::bound_unknowns`] (`bound`) or
    /// [`TermRounding::error_unknowns`], the same values at the cost of the rows' entries
    /// and terms.
    fn on_rows(&self, bound: bool, z: &[f64], rows: &[usize]) -> f64 {
        // rows within one block meet only the unstored positions within it (the others
        // add exact zeros, so the sum is the same)
        let first_block = rows.first().and_then(|&r| self.block_of.get(r));
        let one_block = rows.iter().all(|&r| self.block_of.get(r) == first_block);
        let unstored = if one_block {
            &self.unstored_within
        } else {
            &self.unstored
        };
        let forms = self.stored.form_rows(bound, self.unknowns, z, rows)
            + unstored.form_rows(bound, self.unknowns, z, rows);
        if bound {
            return ROUNDING * f64::EPSILON * forms;
        }
        // the geometric terms at the rows, each once, in ascending order (as the sum over
        // all terms adds them; the others add exact zeros)
        let mut terms: Vec<usize> = rows
            .iter()
            .filter_map(|&r| Some(*self.geometric_start.get(r)?..*self.geometric_start.get(r + 1)?))
            .flat_map(|range| self.geometric_terms[range].iter().copied())
            .collect();
        terms.sort_unstable();
        terms.dedup();
        let geometric: f64 = terms
            .iter()
            .map(|&t| self.geometric[t].amplification * self.geometric[t].form(z))
            .sum();
        ROUNDING * f64::EPSILON * (forms + geometric)
    }

    /// Σ over both patterns' weights (`bound` or entries).
    fn abs_form(&self, bound: bool, z: &[f64]) -> f64 {
        self.stored.form(bound, self.unknowns, z) + self.unstored.form(bound, self.unknowns, z)
    }

    /// Estimated |δ(zᵀ K z)| for `z` over the variables and floats (master order).
    pub fn error_unknowns(&self, z: &[f64]) -> f64 {
        let geometric: f64 = self
            .geometric
            .iter()
            .map(|t| t.amplification * t.form(z))
            .sum();
        ROUNDING * f64::EPSILON * (self.abs_form(false, z) + geometric)
    }

    /// An upper bound of [`TermRounding::error_unknowns`] at the cost of sparse forms:
    /// each term's |zᵀ G_t z| replaced by |z|ᵀ |G_t| |z|.
    pub fn bound_unknowns(&self, z: &[f64]) -> f64 {
        ROUNDING * f64::EPSILON * self.abs_form(true, z)
    }

    /// The float-elimination map used for the floats' share of a mode.
    pub fn float_map(&self) -> &FloatMap {
        &self.floats
    }

    /// Number of unknowns (variables and floats) the terms are over.
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }
}

impl StiffnessRounding for TermRounding {
    fn error(&self, v: &[f64]) -> f64 {
        self.error_unknowns(&self.floats.extend(v))
    }

    fn bound(&self, v: &[f64]) -> f64 {
        self.bound_unknowns(&self.floats.extend(v))
    }

    fn estimate(&self, v: &[f64], keep_bound: &dyn Fn(f64) -> bool) -> f64 {
        // the floats' motion once for both figures
        let z = self.floats.extend(v);
        let bound = self.bound_unknowns(&z);
        if keep_bound(bound) {
            bound
        } else {
            self.error_unknowns(&z)
        }
    }

    fn estimate_on(&self, v: &[f64], support: &[usize], keep_bound: &dyn Fn(f64) -> bool) -> f64 {
        let z = self.floats.extend(v);
        // the rows where z can be non-zero: the support, then the floats that move
        let nx = self.floats.nx;
        let rows: Vec<usize> = support
            .iter()
            .copied()
            .filter(|&i| i < nx)
            .chain((nx..z.len()).filter(|&f| z[f] != 0.0))
            .collect();
        let bound = self.on_rows(true, &z, &rows);
        if keep_bound(bound) {
            bound
        } else {
            self.on_rows(false, &z, &rows)
        }
    }
}

/// The directions of the float block Q (real stiffness at f = 0, variables held) with
/// stiffness below minus its rounding (`rounding`, or a few ulps of Q's entries without
/// it): those where the massless floats have no stable position ([`float_directions`]'s
/// runaway ones).
pub fn runaway_floats(
    model: &StageModel,
    damping: &Damping,
    rounding: Option<&TermRounding>,
) -> Result<Vec<RunawayFloat>, DynamicsError> {
    Ok(float_directions(model, damping, rounding)?.runaway)
}

/// The float block Q's directions (real stiffness at f = 0, variables held) that decide
/// the verdict, each stiffness κ against its rounding δ (`rounding`, or a few ulps of Q's
/// entries without it): runaway when κ < −δ, or when |κ| ≤ δ and the direction is so
/// strongly coupled to the variables that either sign goes downhill
/// (`undetermined_runaways`); neutral when |κ| ≤ δ otherwise.
pub fn float_directions(
    model: &StageModel,
    damping: &Damping,
    rounding: Option<&TermRounding>,
) -> Result<FloatDirections, DynamicsError> {
    let (nx, nq, _) = model.sizes;
    if nq == 0 {
        return Ok(FloatDirections::default());
    }
    let (q, c, re) = float_blocks(model, damping);
    if let Some(bad) = q.iter().position(|x| !x.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: "float stiffness block",
            row: bad % nq,
            column: bad / nq,
        });
    }
    let mut runaway = Vec::new();
    let mut undetermined = Vec::new();
    // Q is block diagonal over the groups its exact zeros separate: its eigenpairs are the
    // groups' own
    for group in crate::schur::components(nq, |i, j| q[(i, j)] != 0.0) {
        let qg = DMatrix::from_fn(group.len(), group.len(), |i, j| q[(group[i], group[j])]);
        let eigen = qg.clone().symmetric_eigen();
        // the group's rows among the unknowns (where its directions are non-zero)
        let rows: Vec<usize> = group.iter().map(|&f| nx + f).collect();
        for (k, &kappa) in eigen.eigenvalues.iter().enumerate() {
            let w = eigen.eigenvectors.column(k);
            let error = match rounding {
                Some(r) => {
                    let mut z = vec![0.0; nx + nq];
                    for (&f, x) in group.iter().zip(w.iter()) {
                        z[nx + f] = *x;
                    }
                    // a positive stiffness above the cheap bound of its rounding is held
                    if kappa >= 0.0 && kappa > r.on_rows(true, &z, &rows) {
                        continue;
                    }
                    r.on_rows(false, &z, &rows)
                }
                None => {
                    let mut sum = 0.0;
                    for i in 0..group.len() {
                        for j in 0..group.len() {
                            sum += w[i].abs() * qg[(i, j)].abs() * w[j].abs();
                        }
                    }
                    let error = ROUNDING * f64::EPSILON * sum;
                    if kappa > error {
                        continue;
                    }
                    error
                }
            };
            if kappa < -error {
                runaway.push(RunawayFloat {
                    stiffness: kappa,
                    error,
                    floats: float_shares(model, &group, w.iter().copied()),
                });
            } else if kappa <= error {
                undetermined.push((kappa, error, group.clone(), w.iter().copied().collect()));
            }
        }
    }
    let (coupled, neutral) = undetermined_runaways(model, &re, &c, nx, undetermined);
    runaway.extend(coupled);
    runaway.sort_by(|a, b| a.stiffness.total_cmp(&b.stiffness));
    Ok(FloatDirections { runaway, neutral })
}

/// The floats with the largest shares (at least 1 %) of a direction `w` over the floats
/// `group` (0-based among the floats): at most three, largest first.
fn float_shares(
    model: &StageModel,
    group: &[usize],
    w: impl Iterator<Item = f64>,
) -> Vec<(String, f64)> {
    let mut floats: Vec<(String, f64)> = w
        .zip(group)
        .map(|(x, &f)| (model.floats.get(f).cloned().unwrap_or_default(), x * x))
        .filter(|(_, share)| *share >= 0.01)
        .collect();
    floats.sort_by(|a, b| b.1.total_cmp(&a.1));
    floats.truncate(3);
    floats
}

/// A float direction w (unit, over the floats) whose stiffness κ is zero within its error
/// δ: unknown in sign. With b = C w the variables' coupling to it (N/m) and a = uᵀ K u the
/// variables' own stiffness along u = b/|b|, the stiffness restricted to the plane of u
/// and w is [[a, |b|], [|b|, κ]], indefinite for every κ ≤ κ + δ when a (κ + δ) < |b|²; by
/// Cauchy interlacing the whole stiffness then has a negative eigenvalue whatever the
/// rounding: the direction is reported as runaway. (The margin of 2 covers the rounding
/// of a and b themselves, a few ulps.) Directions weakly coupled are returned second:
/// neutral.
fn undetermined_runaways(
    model: &StageModel,
    re: &[f64],
    c: &DMatrix<f64>,
    nx: usize,
    undetermined: Vec<(f64, f64, Vec<usize>, Vec<f64>)>,
) -> (Vec<RunawayFloat>, Vec<RunawayFloat>) {
    let (mut runaway, mut neutral) = (Vec::new(), Vec::new());
    for (kappa, error, group, w) in undetermined {
        // b = Cᵀ w over the variables
        let mut b = vec![0.0; nx];
        for (&f, &wf) in group.iter().zip(&w) {
            for (j, bj) in b.iter_mut().enumerate() {
                *bj += wf * c[(f, j)];
            }
        }
        let b2: f64 = b.iter().map(|x| x * x).sum();
        let direction = RunawayFloat {
            stiffness: kappa,
            error,
            floats: float_shares(model, &group, w.iter().copied()),
        };
        if b2 == 0.0 || !b2.is_finite() {
            neutral.push(direction);
            continue;
        }
        // a = uᵀ K_xx u from the pattern's variable entries
        let mut a = 0.0;
        for (slot, &v) in re.iter().enumerate() {
            let (r, col) = model.pattern.position(slot);
            if r < nx && col < nx {
                a += b[r] * v * b[col];
            }
        }
        let a = a / b2;
        if 2.0 * a * (kappa + error) < b2 {
            runaway.push(direction);
        } else {
            neutral.push(direction);
        }
    }
    (runaway, neutral)
}

/// Bodies with mass whose z axis points below the horizontal at coordinates `x` (a full
/// coordinate vector of `system`).
pub fn inverted_bodies(system: &System, x: &[f64]) -> Vec<InvertedBody> {
    system
        .bodies
        .iter()
        .filter(|b| b.mass > 0.0)
        .filter(|b| b.frame.var_list().iter().all(|&g| g < x.len()))
        .filter_map(|b| {
            let zz = b.frame.eval(x).rotation[(2, 2)];
            (zz < 0.0).then(|| InvertedBody {
                body: b.name.clone(),
                tilt_deg: zz.clamp(-1.0, 1.0).acos().to_degrees(),
            })
        })
        .collect()
}
