//! Responses frequency by frequency on the stage's fixed pattern (docs/physics.md §3): the
//! dynamic stiffness E(f) = P(f) − ω² diag(M, 0) over the unknowns (variables and floats)
//! is assembled from parts prepared once per sweep, then factorised and solved.
//!
//! - Assembly: every tag whose multiplier does not depend on f (its compiled expressions
//!   are constants) is folded, with the lossless part, into one complex array of values;
//!   the tags that do depend on f keep their values on the fixed pattern and are added with
//!   their multiplier at each frequency. Nothing is allocated per frequency.
//! - Restriction ([`Solver::Restricted`]): z = E⁻¹ rhs is non-zero only in the connected
//!   components of the pattern that the right-hand side touches, and the output reads only
//!   the components its vector touches; the others are exactly decoupled (zero entries, not
//!   small ones), so only the unknowns of components touched by both are solved, with no
//!   approximation (the quad's x3 with input x00: the 8 unknowns of the x–pitch block).
//! - Solvers by size: up to [`DENSE_LIMIT`] unknowns a dense complex LU in the sweep's own
//!   storage; above, E(f) (complex symmetric) is factorised as L D Lᵀ by a schedule worked
//!   out once per sweep in an approximate-minimum-degree order, which keeps the fill within
//!   each fibre's chain of beads: O(n) per point for chain-like suspensions (beads, chains
//!   of stages), with no search or allocation per point. Where partial pivoting would have
//!   exchanged rows (for beads, at every frequency: massless joint angles next to beads
//!   whose −ω²m outweighs them) the solution is checked by its residual against E(f) and
//!   refined to a componentwise backward error of a few ε, or solved by faer's pivoting
//!   sparse LU when that fails (about one point in ten with 50 beads per fibre).
//! - [`Solver::DenseReference`] is the straightforward path kept to check the others:
//!   P(f) summed densely over the whole master matrix and one dense LU over all unknowns,
//!   with one step of iterative refinement.

use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use pendkit_expr::Compiled;
use pendkit_system::Damping;

use crate::DynamicsError;
use crate::lu::{self, Pivots};
use crate::sparse_lu::SymmetricSparse;
use crate::stage::{Input, Output, Projection, StageModel, TWO_PI, block_len};

/// Largest number of unknowns solved by the dense LU; above it the sparse LU is used.
/// The dense factorisation costs n³/3 complex operations, the sparse one a per-column
/// overhead that pays once the blocks are a few dozen unknowns: measured on the quad with
/// one bead per fibre (42 unknowns, all coupled) 13.5 µs per point dense against 12.4 µs
/// sparse, and with two (54) 23 µs against 19 µs; the 8-unknown x–pitch block of the quad
/// factorises densely in well under a microsecond. (Those sparse figures are faer's LU,
/// measured before the scheduled L D Lᵀ replaced it; the limit was not measured again.)
pub const DENSE_LIMIT: usize = 40;

/// How a response is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solver {
    /// Only the unknowns in the blocks that couple to both the input and the output (exact:
    /// the other blocks are decoupled by exact zeros). The default.
    #[default]
    Restricted,
    /// Every variable and float, by the same fast assembly and solvers.
    Full,
    /// The reference: P(f) summed densely over the master matrix and one dense LU over all
    /// unknowns, per frequency (the straightforward algorithm; slow, for checking).
    DenseReference,
}

/// One of ε', ε'' of a tag: a constant, or an expression of f to evaluate per frequency.
#[derive(Clone, Debug)]
enum Coefficient {
    Constant(f64),
    OfFrequency(Compiled),
}

impl Coefficient {
    fn of(expression: &Compiled) -> Self {
        match expression.as_const() {
            Some(x) => Coefficient::Constant(x),
            None => Coefficient::OfFrequency(expression.clone()),
        }
    }

    fn at(&self, f_hz: f64) -> f64 {
        match self {
            Coefficient::Constant(x) => *x,
            // an expression of f alone (`TagDamping`); NaN otherwise, refused by the
            // damping check every sweep makes first
            Coefficient::OfFrequency(e) => e.eval(&[f_hz]).unwrap_or(f64::NAN),
        }
    }

    /// The values at every frequency of `freqs` (Hz) into `out`, in one pass.
    fn over(&self, freqs: &[f64], out: &mut [f64]) {
        match self {
            Coefficient::Constant(x) => out.fill(*x),
            Coefficient::OfFrequency(e) => {
                if e.eval_points(&[freqs], out).is_err() {
                    out.fill(f64::NAN);
                }
            }
        }
    }
}

/// The complex multiplier ε' + i ε'' of one tag over a sweep.
#[derive(Clone, Debug)]
enum Multiplier {
    /// Does not depend on frequency.
    Constant(c64),
    /// Evaluated at each frequency (only the parts that read f).
    Varying(Coefficient, Coefficient),
}

impl Multiplier {
    fn of(damping: &Damping, tag: &str) -> Self {
        match damping.get(tag) {
            None => Multiplier::Constant(c64::new(1.0, 0.0)),
            Some(d) => match (d.real.as_const(), d.imag.as_const()) {
                (Some(re), Some(im)) => Multiplier::Constant(c64::new(re, im)),
                _ => Multiplier::Varying(Coefficient::of(&d.real), Coefficient::of(&d.imag)),
            },
        }
    }
}

/// A complex array that is linear in the varying tags' multipliers:
/// constant + Σ_varying m_t(f) part_t, with each part a sparse list of real entries.
#[derive(Clone, Debug)]
struct Linear {
    constant: Vec<c64>,
    parts: Vec<Vec<(usize, f64)>>,
}

impl Linear {
    fn new(len: usize, varying: usize) -> Self {
        Linear {
            constant: vec![c64::new(0.0, 0.0); len],
            parts: vec![Vec::new(); varying],
        }
    }

    /// Adds `value` × the multiplier of the part `which` (None: constant `m`) at `index`.
    fn add(&mut self, index: usize, value: f64, which: Part) {
        match which {
            Part::Constant(m) => self.constant[index] += m * value,
            Part::Varying(k) => self.parts[k].push((index, value)),
        }
    }

    /// out = constant + Σ m_t part_t.
    fn evaluate(&self, varying: &[c64], out: &mut [c64]) {
        out.copy_from_slice(&self.constant);
        for (part, &m) in self.parts.iter().zip(varying) {
            for &(i, v) in part {
                out[i] += c64::new(m.re * v, m.im * v);
            }
        }
    }
}

/// Where a part's values go: folded with a constant multiplier, or kept as varying part k.
#[derive(Clone, Copy)]
enum Part {
    Constant(c64),
    Varying(usize),
}

/// The mass entries and the frequency terms' additions to E, by stored slot.
type MassAndExtra<'a> = (&'a [(usize, f64)], &'a [(usize, c64)]);

/// Where one entry of a frequency term's local matrix goes (the cases of a stored slot in
/// [`Fast::new`]): E over the solved unknowns, the right-hand side (times the weight), the
/// output's weight on the response, or the direct term.
#[derive(Clone, Copy)]
enum Dest {
    Matrix(usize),
    Rhs(usize, f64),
    Out(usize, f64),
    Direct(f64),
}

/// A frequency term's state in a sweep: its tags' indices among the model's, and its
/// multipliers, blocks and their projection at the current frequency.
struct TermState {
    tags: Vec<Option<usize>>,
    multipliers: Vec<c64>,
    projection: Projection,
    /// The term's blocks ([`FrequencyTerm::parts`]) and Σ_g J_gᵀ V_g J_g over its rows.
    values: Vec<c64>,
    sum: Vec<c64>,
    /// Scratch of one value per coordinate, and (taken and put back by the `&self`
    /// dissipation, so no point allocates) per coordinate and per own displacement.
    scratch: Vec<c64>,
    response: std::cell::Cell<(Vec<c64>, Vec<c64>)>,
}

/// The factorisation of E(f) over the solved unknowns: L D Lᵀ by a schedule worked out once
/// per sweep while no row exchange is needed (E is complex symmetric), a pivoting LU
/// otherwise.
enum Factor {
    /// Dense column-major n × n (the values array is the matrix), eliminated in the natural
    /// order; the fallback is the dense pivoting LU, used straight away while the last
    /// solve needed a row exchange (neighbouring frequencies usually pivot alike, and a
    /// refused schedule is work lost). Both make the same numbers where no row is exchanged.
    Dense {
        schedule: lu::Schedule,
        pivots: Vec<usize>,
        /// The pivoting LU's scratch.
        rows: Vec<usize>,
        exchanged: bool,
    },
    /// The lower triangle of the matrix permuted to a fill-reducing order, with its fill;
    /// the fallback is faer's sparse LU.
    Sparse(Box<SymmetricSparse>),
}

const NONE: usize = usize::MAX;

/// Which factorisation the last solve left in [`Fast`]'s values, for [`Sweep::solve_again`].
#[derive(Clone, Copy, PartialEq)]
enum Factored {
    /// None usable (no solve yet, or the last one failed).
    Nothing,
    /// Dense, by the schedule (no row exchange).
    Schedule,
    /// Dense, by the pivoting LU.
    Pivoted,
    /// Sparse, by the schedule or faer's pivoting LU (the factor knows which).
    Sparse,
    /// Sparse, by the schedule where partial pivoting would have exchanged rows: each
    /// solve is checked against E itself and refined.
    Refined,
}

/// A frequency term's entries into E, as (entry, slot of E).
type MatrixEntries = Vec<(usize, usize)>;

/// A frequency term's destinations split into its entries into E and the others.
fn split_matrix(dest: Vec<(usize, Dest)>) -> (MatrixEntries, Vec<(usize, Dest)>) {
    let (mut matrix, mut other) = (Vec::new(), Vec::new());
    for (e, d) in dest {
        match d {
            Dest::Matrix(k) => matrix.push((e, k)),
            _ => other.push((e, d)),
        }
    }
    (matrix, other)
}

/// The fixed-pattern engine: parts prepared once, assembled and solved per frequency.
struct Fast {
    matrix: Linear,
    mass: Vec<(usize, f64)>,
    rhs: Linear,
    out: Linear,
    direct: Linear,
    factor: Factor,
    /// E(f) on the pattern, factorised in place.
    values: Vec<c64>,
    /// E(f) unfactorised, for checking a solve without row exchanges.
    original: Vec<c64>,
    scalar: Vec<c64>,
    /// What the last solve left factorised, and its ω² (rad²/s²).
    factored: Factored,
    w2: f64,
    /// Per frequency term: (entry, slot of E) of its entries that go into E, and where
    /// each of the others goes (none for a force input and a displacement output).
    term_matrix: Vec<MatrixEntries>,
    term_dest: Vec<Vec<(usize, Dest)>>,
    /// The frequency terms at the current frequency: additions to E, to the right-hand
    /// side and to the output's weights, and to the direct term.
    extra: Vec<(usize, c64)>,
    extra_rhs: Vec<(usize, c64)>,
    extra_out: Vec<(usize, c64)>,
    extra_direct: c64,
}

/// The reference engine: today's dense algorithm.
struct Reference {
    input: Input,
    output: Output,
}

enum Engine {
    Fast(Box<Fast>),
    Reference(Box<Reference>),
}

/// One input and one output of a stage, prepared for solving at many frequencies: the
/// response z = E(f)⁻¹ rhs(f) over the solved unknowns and the output value oᵀ z (+ the
/// direct term of a support-force output) at each frequency given to [`Sweep::at`].
pub struct Sweep<'m> {
    model: &'m StageModel,
    damping: &'m Damping,
    unknowns: Vec<usize>,
    local: Vec<usize>,
    multipliers: Vec<Multiplier>,
    varying: Vec<usize>,
    now: Vec<c64>,
    now_varying: Vec<c64>,
    engine: Engine,
    z: Vec<c64>,
    /// The last frequency solved at (Hz).
    last_f: Option<f64>,
    /// The model's frequency terms ([`StageModel::frequency_terms`]).
    terms: Vec<TermState>,
}

impl<'m> Sweep<'m> {
    /// Prepares `input` → `output` of `model` with `damping`, solving as `solver` says.
    pub fn new(
        model: &'m StageModel,
        damping: &'m Damping,
        input: &Input,
        output: &Output,
        solver: Solver,
    ) -> Result<Self, DynamicsError> {
        model.check(input, output)?;
        let n_all = model.unknowns();
        let unknowns: Vec<usize> = match solver {
            Solver::Restricted => coupled_unknowns_checked(model, input, output),
            Solver::Full | Solver::DenseReference => (0..n_all).collect(),
        };
        let mut local = vec![NONE; n_all];
        for (l, &u) in unknowns.iter().enumerate() {
            local[u] = l;
        }
        let multipliers: Vec<Multiplier> = model
            .by_tag
            .iter()
            .map(|(tag, _)| Multiplier::of(damping, tag))
            .collect();
        let varying: Vec<usize> = (0..multipliers.len())
            .filter(|&t| matches!(multipliers[t], Multiplier::Varying(..)))
            .collect();
        let now: Vec<c64> = multipliers
            .iter()
            .map(|m| match m {
                Multiplier::Constant(c) => *c,
                Multiplier::Varying(..) => c64::new(f64::NAN, f64::NAN),
            })
            .collect();
        for (t, m) in multipliers.iter().enumerate() {
            if let (Multiplier::Constant(c), Some((tag, _))) = (m, model.by_tag.get(t)) {
                crate::validate::check_multiplier(tag, 0.0, c.re, c.im)?;
            }
        }
        let engine = match solver {
            Solver::DenseReference => Engine::Reference(Box::new(Reference {
                input: input.clone(),
                output: output.clone(),
            })),
            _ => Engine::Fast(Box::new(Fast::new(
                model,
                &unknowns,
                &local,
                &multipliers,
                &varying,
                input,
                output,
            )?)),
        };
        Ok(Sweep {
            model,
            damping,
            z: vec![c64::new(0.0, 0.0); unknowns.len()],
            unknowns,
            local,
            now,
            now_varying: vec![c64::new(0.0, 0.0); varying.len()],
            multipliers,
            varying,
            engine,
            last_f: None,
            terms: model
                .frequency_terms
                .iter()
                .map(|t| {
                    let projection = Projection::new(t.as_ref());
                    let (n, m) = (projection.coordinates(), projection.own());
                    let tags = t.tags();
                    let zero = c64::new(0.0, 0.0);
                    TermState {
                        tags: tags
                            .iter()
                            .map(|tag| model.by_tag.iter().position(|(name, _)| name == tag))
                            .collect(),
                        multipliers: vec![c64::new(1.0, 0.0); tags.len()],
                        projection,
                        values: vec![zero; block_len(t.groups())],
                        sum: vec![zero; n * n],
                        scratch: vec![zero; n],
                        response: std::cell::Cell::new((vec![zero; n], vec![zero; m])),
                    }
                })
                .collect(),
        })
    }

    /// Per tag of the model (`by_tag` order), the dissipation ȳᴴ Im(part) y of the
    /// frequency terms' parts of that tag at the last frequency solved, y = J z the term's
    /// own displacements from the response over the solved unknowns (the parameters do not
    /// move) (N m per unit response²), added to `out`. A term's tag the model lacks is left
    /// out: the model's tags include every wire's, since its static terms are lossy.
    pub fn add_frequency_dissipation(&self, out: &mut [f64]) {
        for (term, state) in self.model.frequency_terms.iter().zip(&self.terms) {
            let (mut z, mut y) = state.response.take();
            for (zc, &r) in z.iter_mut().zip(term.positions()) {
                *zc = self.local(r).map_or(c64::new(0.0, 0.0), |l| self.z[l]);
            }
            state
                .projection
                .dissipation(&state.values, &z, &state.tags, &mut y, out);
            state.response.set((z, y));
        }
    }

    /// The frequency terms' blocks and projections at `f_hz` with the current multipliers.
    fn update_terms(&mut self, f_hz: f64) {
        for (term, state) in self.model.frequency_terms.iter().zip(&mut self.terms) {
            for (m, (tag, t)) in state
                .multipliers
                .iter_mut()
                .zip(state.tags.iter().zip(term.tags()))
            {
                *m = match tag {
                    Some(k) => self.now[*k],
                    None => {
                        let (re, im) = self.damping.at(t, f_hz);
                        c64::new(re, im)
                    }
                };
            }
            term.parts(f_hz, &state.multipliers, &mut state.values);
            state
                .projection
                .project(&state.values, &mut state.sum, &mut state.scratch);
        }
    }

    /// Master indices (variables, then floats) of the unknowns solved for, ascending.
    pub fn unknowns(&self) -> &[usize] {
        &self.unknowns
    }

    /// Position of master unknown `u` among the solved ones.
    pub fn local(&self, u: usize) -> Option<usize> {
        self.local.get(u).copied().filter(|&l| l != NONE)
    }

    /// The response z over the solved unknowns at the last frequency given to
    /// [`Sweep::at`] (every other unknown's response is exactly zero).
    pub fn response(&self) -> &[c64] {
        &self.z
    }

    /// The multiplier ε' + i ε'' of tag `t` (index into the model's `by_tag`) at the last
    /// frequency given to [`Sweep::at`]; `None` for an index past the model's tags.
    pub fn multiplier(&self, t: usize) -> Option<c64> {
        self.now.get(t).copied()
    }

    /// Solves at `f_hz` (Hz) and returns the output per unit input.
    pub fn at(&mut self, f_hz: f64) -> Result<c64, DynamicsError> {
        crate::validate::check_frequency("frequency", f_hz)?;
        for (k, &t) in self.varying.iter().enumerate() {
            if let Multiplier::Varying(re, im) = &self.multipliers[t] {
                let (r, i) = (re.at(f_hz), im.at(f_hz));
                let tag = self.model.by_tag.get(t).map_or("", |(tag, _)| tag.as_str());
                crate::validate::check_multiplier(tag, f_hz, r, i)?;
                self.now[t] = c64::new(r, i);
                self.now_varying[k] = self.now[t];
            }
        }
        self.solve(f_hz)
    }

    /// Solves at every frequency of `freqs` (Hz) in turn, calling `visit(k, output, sweep)`
    /// after the k-th (the sweep gives [`Sweep::response`] and [`Sweep::multiplier`] there).
    /// The same numbers as [`Sweep::at`] point by point, but the multipliers of the
    /// frequency-dependent tags are evaluated for a block of frequencies at a time, one walk
    /// of each expression per block instead of one per point. Stops at the first frequency
    /// where the dynamic stiffness is singular and says which.
    pub fn for_each(
        &mut self,
        freqs: &[f64],
        mut visit: impl FnMut(usize, c64, &Sweep<'m>),
    ) -> Result<(), DynamicsError> {
        const BLOCK: usize = 256;
        let nv = self.varying.len();
        // ε' then ε'' of each varying tag over the block: 2 nv rows of BLOCK values
        let mut table = vec![0.0; 2 * nv * BLOCK];
        for (b, block) in freqs.chunks(BLOCK).enumerate() {
            let n = block.len();
            for (k, &t) in self.varying.iter().enumerate() {
                if let Multiplier::Varying(re, im) = &self.multipliers[t] {
                    let (rows_re, rows_im) = table.split_at_mut(nv * BLOCK);
                    re.over(block, &mut rows_re[k * BLOCK..k * BLOCK + n]);
                    im.over(block, &mut rows_im[k * BLOCK..k * BLOCK + n]);
                }
            }
            for (i, &f_hz) in block.iter().enumerate() {
                for (k, &t) in self.varying.iter().enumerate() {
                    let m = c64::new(table[k * BLOCK + i], table[(nv + k) * BLOCK + i]);
                    // as in `at`: a multiplier that is not finite or has a negative loss
                    // here (a temperature of 1e300 K makes a thermoelastic loss infinite)
                    // is named, not left to show up as a singular solve
                    let tag = self.model.by_tag.get(t).map_or("", |(tag, _)| tag.as_str());
                    crate::validate::check_multiplier(tag, f_hz, m.re, m.im)?;
                    self.now[t] = m;
                    self.now_varying[k] = m;
                }
                let y = self.solve(f_hz)?;
                visit(b * BLOCK + i, y, self);
            }
        }
        Ok(())
    }

    /// Solves E(f) x = rhs in place for another right-hand side `rhs` over the solved
    /// unknowns ([`Sweep::unknowns`] order), E at the last frequency given to [`Sweep::at`]
    /// or [`Sweep::for_each`], reusing its factorisation: the adjoint responses of a
    /// derivative, or further inputs at one frequency. An error before any solve, for a
    /// `rhs` of another length, or where E is singular.
    pub fn solve_again(&mut self, rhs: &mut [c64]) -> Result<(), DynamicsError> {
        if rhs.len() != self.unknowns.len() {
            return Err(DynamicsError::Length {
                what: "solve_again: right-hand side",
                expected: self.unknowns.len(),
                got: rhs.len(),
            });
        }
        let Some(f_hz) = self.last_f else {
            return Err(DynamicsError::Solver(
                "solve_again before any frequency was solved".into(),
            ));
        };
        let solved = match &mut self.engine {
            Engine::Fast(fast) => fast.solve_again(&self.now_varying, rhs),
            Engine::Reference(_) => {
                Reference::solve_dense(self.model, self.damping, f_hz, rhs);
                true
            }
        };
        if solved && rhs.iter().all(|x| x.re.is_finite() && x.im.is_finite()) {
            Ok(())
        } else {
            Err(DynamicsError::Singular { f_hz })
        }
    }

    /// Solves at `f_hz` with the multipliers already set for it.
    fn solve(&mut self, f_hz: f64) -> Result<c64, DynamicsError> {
        self.last_f = Some(f_hz);
        let w2 = (TWO_PI * f_hz).powi(2);
        if !self.terms.is_empty() {
            self.update_terms(f_hz);
        }
        let solved = match &mut self.engine {
            Engine::Fast(fast) => {
                fast.set_terms(&self.terms);
                fast.solve(&self.now_varying, w2, &mut self.z)
            }
            Engine::Reference(r) => r.solve(self.model, self.damping, f_hz, &mut self.z),
        };
        match solved {
            Some(y) if y.re.is_finite() && y.im.is_finite() => Ok(y),
            _ => Err(DynamicsError::Singular { f_hz }),
        }
    }
}

impl Fast {
    #[expect(
        clippy::too_many_lines,
        reason = "lowers the stage's parts into the fast engine once per sweep: the factor's index map \
                  and the four cases of a stored slot (unknowns, input force, support force, input to \
                  output) sit in one match, so each slot visibly lands in exactly one of matrix, rhs, \
                  out or direct"
    )]
    fn new(
        model: &StageModel,
        unknowns: &[usize],
        local: &[usize],
        multipliers: &[Multiplier],
        varying: &[usize],
        input: &Input,
        output: &Output,
    ) -> Result<Self, DynamicsError> {
        let n = unknowns.len();
        let (nx, nq, _) = model.sizes;
        let n_all = nx + nq;
        let mut factor = if n <= DENSE_LIMIT {
            // the schedule is made below, once the stored entries are known
            Factor::Dense {
                schedule: lu::Schedule::new(0, &[]),
                pivots: vec![0; n],
                rows: Vec::with_capacity(n),
                exchanged: false,
            }
        } else {
            let (col_ptr, row_idx) = model.pattern.restricted_columns(unknowns, local);
            Factor::Sparse(Box::new(SymmetricSparse::new(col_ptr, row_idx)?))
        };
        let len = match &factor {
            Factor::Dense { .. } => n * n,
            Factor::Sparse(s) => s.len(),
        };
        let index = |i: usize, j: usize| match &factor {
            Factor::Dense { .. } => Some(i + j * n),
            Factor::Sparse(s) => s.index(i, j),
        };
        let nv = varying.len();
        let mut matrix = Linear::new(len, nv);
        let mut rhs = Linear::new(n, nv);
        let mut out = Linear::new(n, nv);
        let mut direct = Linear::new(1, nv);
        let loc = |u: usize| local.get(u).copied().filter(|&l| l != NONE);
        // forces and output weights over the unknowns they have entries for (variables,
        // or variables and floats)
        match input {
            Input::Force(force) => {
                for (l, &u) in unknowns.iter().enumerate() {
                    if let Some(&f) = force.as_slice().get(u) {
                        rhs.constant[l] = c64::new(f, 0.0);
                    }
                }
            }
            Input::Displacement(_) => {}
        }
        match output {
            Output::Displacement(o) => {
                for (l, &u) in unknowns.iter().enumerate() {
                    if let Some(&w) = o.as_slice().get(u) {
                        out.constant[l] = c64::new(w, 0.0);
                    }
                }
                // an output reading the parameters too: the input's displacement directly
                if let Input::Displacement(s) = input {
                    let through: f64 = (0..s.len())
                        .filter_map(|k| Some(o.as_slice().get(n_all + k)? * s[k]))
                        .sum();
                    direct.constant[0] += c64::new(through, 0.0);
                }
            }
            Output::SupportForce(_) => {}
        }
        let parts = std::iter::once((&model.lossless, Part::Constant(c64::new(1.0, 0.0)))).chain(
            model.by_tag.iter().enumerate().map(|(t, (_, values))| {
                let part = match &multipliers[t] {
                    Multiplier::Constant(m) => Part::Constant(*m),
                    Multiplier::Varying(..) => {
                        Part::Varying(varying.iter().position(|&v| v == t).unwrap_or(0))
                    }
                };
                (values, part)
            }),
        );
        for (values, part) in parts {
            for (slot, &v) in values.iter().enumerate() {
                if v == 0.0 {
                    continue;
                }
                let (r, c) = model.pattern.position(slot);
                match (r < n_all, c < n_all) {
                    (true, true) => {
                        if let Some(k) = loc(r).zip(loc(c)).and_then(|(i, j)| index(i, j)) {
                            matrix.add(k, v, part);
                        }
                    }
                    // the input's force on the unknowns: −P_us s
                    (true, false) => {
                        if let (Some(i), Input::Displacement(s)) = (loc(r), input) {
                            let s_c = s[c - n_all];
                            if s_c != 0.0 {
                                rhs.add(i, -v * s_c, part);
                            }
                        }
                    }
                    // the support force read from the response: −o_s P_su z
                    (false, true) => {
                        if let (Some(j), Output::SupportForce(o)) = (loc(c), output) {
                            let o_r = o[r - n_all];
                            if o_r != 0.0 {
                                out.add(j, -v * o_r, part);
                            }
                        }
                    }
                    // and straight from the input: −o_s P_ss s
                    (false, false) => {
                        if let (Input::Displacement(s), Output::SupportForce(o)) = (input, output) {
                            let w = o[r - n_all] * s[c - n_all];
                            if w != 0.0 {
                                direct.add(0, -v * w, part);
                            }
                        }
                    }
                }
            }
        }
        let term_dest = Self::term_destinations(model, &loc, &index, input, output);
        let mut mass = Vec::new();
        for (slot, &m) in model.mass_on_pattern.iter().enumerate() {
            if m == 0.0 {
                continue;
            }
            let (r, c) = model.pattern.position(slot);
            if let Some(k) = loc(r).zip(loc(c)).and_then(|(i, j)| index(i, j)) {
                mass.push((k, m));
            }
        }
        if let Factor::Dense { schedule, .. } = &mut factor {
            // every entry the assembly can make non-zero
            let mut stored: Vec<bool> = matrix
                .constant
                .iter()
                .map(|x| *x != c64::new(0.0, 0.0))
                .collect();
            for &(k, _) in matrix.parts.iter().flatten().chain(&mass) {
                stored[k] = true;
            }
            for &(_, d) in term_dest.iter().flatten() {
                if let Dest::Matrix(k) = d {
                    stored[k] = true;
                }
            }
            *schedule = lu::Schedule::new(n, &stored);
        }
        // the entries into E apart: a point copies them in one pass, without a match each
        let (term_matrix, term_dest) = term_dest.into_iter().map(split_matrix).unzip();
        Ok(Fast {
            values: vec![c64::new(0.0, 0.0); len],
            original: vec![c64::new(0.0, 0.0); len],
            scalar: vec![c64::new(0.0, 0.0); 1],
            factored: Factored::Nothing,
            w2: 0.0,
            matrix,
            mass,
            rhs,
            out,
            direct,
            factor,
            term_matrix,
            term_dest,
            extra: Vec::new(),
            extra_rhs: Vec::new(),
            extra_out: Vec::new(),
            extra_direct: c64::new(0.0, 0.0),
        })
    }

    /// Where each entry of each of `model`'s frequency terms goes, as the static parts'
    /// slots do in [`Fast::new`] (entries outside the solved unknowns' stored slots are left
    /// out: the static model has them at zero).
    fn term_destinations(
        model: &StageModel,
        loc: &dyn Fn(usize) -> Option<usize>,
        index: &dyn Fn(usize, usize) -> Option<usize>,
        input: &Input,
        output: &Output,
    ) -> Vec<Vec<(usize, Dest)>> {
        let (nx, nq, _) = model.sizes;
        let n_all = nx + nq;
        model
            .frequency_terms
            .iter()
            .map(|t| {
                let p = t.positions();
                let n = p.len();
                let mut dest = Vec::new();
                for e in 0..n * n {
                    let (r, c) = (p[e / n], p[e % n]);
                    let d = match (r < n_all, c < n_all, input, output) {
                        (true, true, ..) => loc(r)
                            .zip(loc(c))
                            .and_then(|(i, j)| index(i, j))
                            .map(Dest::Matrix),
                        (true, false, Input::Displacement(s), _) => {
                            loc(r).map(|i| Dest::Rhs(i, -s[c - n_all]))
                        }
                        (false, true, _, Output::SupportForce(o)) => {
                            loc(c).map(|j| Dest::Out(j, -o[r - n_all]))
                        }
                        (false, false, Input::Displacement(s), Output::SupportForce(o)) => {
                            Some(Dest::Direct(-o[r - n_all] * s[c - n_all]))
                        }
                        _ => None,
                    };
                    if let Some(d) = d {
                        dest.push((e, d));
                    }
                }
                dest
            })
            .collect()
    }

    /// The frequency terms' additions at the current frequency, from their summed local
    /// matrices.
    fn set_terms(&mut self, terms: &[TermState]) {
        self.extra.clear();
        self.extra_rhs.clear();
        self.extra_out.clear();
        self.extra_direct = c64::new(0.0, 0.0);
        for ((matrix, dest), state) in self.term_matrix.iter().zip(&self.term_dest).zip(terms) {
            self.extra
                .extend(matrix.iter().map(|&(e, k)| (k, state.sum[e])));
            for &(e, d) in dest {
                let v = state.sum[e];
                match d {
                    // in `term_matrix` (`split_matrix`)
                    Dest::Matrix(_) => {}
                    Dest::Rhs(i, w) => self.extra_rhs.push((i, v * w)),
                    Dest::Out(j, w) => self.extra_out.push((j, v * w)),
                    Dest::Direct(w) => self.extra_direct += v * w,
                }
            }
        }
    }

    /// Solves E x = b in place by the factorisation the last [`Fast::solve`] left (its
    /// multipliers `varying`): false where there is none, or where a refined solve is
    /// refused and faer's pivoting LU fails too (that LU is then the factorisation kept).
    fn solve_again(&mut self, varying: &[c64], b: &mut [c64]) -> bool {
        let Fast {
            matrix,
            mass,
            extra,
            values,
            original,
            factor,
            factored,
            w2,
            ..
        } = self;
        match (factor, *factored) {
            (Factor::Dense { schedule, .. }, Factored::Schedule) => {
                schedule.solve(values, b);
                true
            }
            (
                Factor::Dense {
                    schedule, pivots, ..
                },
                Factored::Pivoted,
            ) => {
                lu::solve(values, schedule.len(), pivots, b);
                true
            }
            (Factor::Sparse(s), Factored::Sparse) => s.solve(values, b),
            (Factor::Sparse(s), Factored::Refined) => {
                let rhs = b.to_vec();
                if s.solve_refined(values, original, b) {
                    return true;
                }
                // as in `solve`: faer's pivoting LU on the matrix afresh, kept from now on
                b.copy_from_slice(&rhs);
                Self::assemble(matrix, (mass, extra), varying, *w2, values);
                let ok = s.factor_pivoting(values) && s.solve(values, b);
                *factored = if ok {
                    Factored::Sparse
                } else {
                    Factored::Nothing
                };
                ok
            }
            _ => false,
        }
    }

    /// E(f) = P(f) − ω² M (+ the frequency terms' `extra`) into `values`.
    fn assemble(
        matrix: &Linear,
        (mass, extra): MassAndExtra<'_>,
        varying: &[c64],
        w2: f64,
        values: &mut [c64],
    ) {
        matrix.evaluate(varying, values);
        for &(k, m) in mass {
            values[k].re -= w2 * m;
        }
        for &(k, v) in extra {
            values[k] += v;
        }
    }

    /// The right-hand side at the current frequency into `z`.
    fn right_hand_side(rhs: &Linear, extra_rhs: &[(usize, c64)], varying: &[c64], z: &mut [c64]) {
        rhs.evaluate(varying, z);
        for &(i, v) in extra_rhs {
            z[i] += v;
        }
    }

    /// Assembles E(f), factorises, solves into `z` and returns the output value.
    fn solve(&mut self, varying: &[c64], w2: f64, z: &mut [c64]) -> Option<c64> {
        self.w2 = w2;
        let Fast {
            matrix,
            mass,
            extra,
            extra_rhs,
            values,
            original,
            factor,
            rhs,
            factored,
            ..
        } = self;
        Self::assemble(matrix, (mass, extra), varying, w2, values);
        Self::right_hand_side(rhs, extra_rhs, varying, z);
        *factored = match factor {
            Factor::Dense {
                schedule,
                pivots,
                rows,
                exchanged,
            } => {
                if !*exchanged && schedule.factor(values) {
                    schedule.solve(values, z);
                    Factored::Schedule
                } else {
                    // a row exchange is needed (or was at the last frequency): the general
                    // LU, on the matrix afresh if the schedule spoilt it
                    if !*exchanged {
                        Self::assemble(matrix, (mass, extra), varying, w2, values);
                    }
                    let n = schedule.len();
                    if lu::factor(values, n, pivots, rows) {
                        lu::solve(values, n, pivots, z);
                        *exchanged = pivots.iter().enumerate().any(|(k, &p)| k != p);
                        Factored::Pivoted
                    } else {
                        Factored::Nothing
                    }
                }
            }
            Factor::Sparse(s) => {
                let solved = match s.factor(values) {
                    Pivots::Kept => s.solve(values, z).then_some(Factored::Sparse),
                    Pivots::Failed => None,
                    Pivots::Exceeded => {
                        // checked against E itself, refined, or refused
                        Self::assemble(matrix, (mass, extra), varying, w2, original);
                        s.solve_refined(values, original, z)
                            .then_some(Factored::Refined)
                    }
                };
                solved.unwrap_or_else(|| {
                    // faer's pivoting LU on the matrix afresh
                    Self::right_hand_side(rhs, extra_rhs, varying, z);
                    Self::assemble(matrix, (mass, extra), varying, w2, values);
                    if s.factor_pivoting(values) && s.solve(values, z) {
                        Factored::Sparse
                    } else {
                        Factored::Nothing
                    }
                })
            }
        };
        if *factored == Factored::Nothing {
            return None;
        }
        self.direct.evaluate(varying, &mut self.scalar);
        let mut y = self.scalar[0] + self.extra_direct;
        for &(j, v) in &self.extra_out {
            y += v * z[j];
        }
        // out·z with the output's parts: constant + Σ varying
        for (&o, &zi) in self.out.constant.iter().zip(z.iter()) {
            y += o * zi;
        }
        for (part, &m) in self.out.parts.iter().zip(varying) {
            for &(i, v) in part {
                y += c64::new(m.re * v, m.im * v) * z[i];
            }
        }
        Some(y)
    }
}

impl Reference {
    /// Solves E(f) x = b in place over every unknown: dense P(f) and A(f) =
    /// P_{xq,xq} − ω² diag(M, 0), faer's pivoting LU and one step of iterative refinement in
    /// working precision (Higham, Accuracy and Stability of Numerical Algorithms, §12.2):
    /// the solution becomes componentwise backward stable, so the reference's rounding is
    /// that of its backward error and not of the pivoting LU's growth (which reached 1e-12
    /// of the noise of a point on quad-v5's test mass, whose own per-term sum agreed with
    /// the refined value).
    fn solve_dense(model: &StageModel, damping: &Damping, f_hz: f64, b: &mut [c64]) {
        let (nx, nq, _) = model.sizes;
        let n = nx + nq;
        let (re, im) = model.master(damping, f_hz);
        let w2 = (TWO_PI * f_hz).powi(2);
        let a = Mat::<c64>::from_fn(n, n, |i, j| {
            let m = if i < nx && j < nx {
                model.mass[(i, j)]
            } else {
                0.0
            };
            c64::new(re[(i, j)], im[(i, j)]) - c64::new(w2 * m, 0.0)
        });
        let rhs = Mat::<c64>::from_fn(n, 1, |i, _| b[i]);
        let lu = a.partial_piv_lu();
        let mut x = lu.solve(&rhs);
        let residual = &rhs - &a * &x;
        x += lu.solve(&residual);
        for (i, bi) in b.iter_mut().enumerate() {
            *bi = x[(i, 0)];
        }
    }

    /// Today's algorithm: dense P(f), dense A(f) = P_{xq,xq} − ω² diag(M, 0), faer's LU.
    fn solve(
        &self,
        model: &StageModel,
        damping: &Damping,
        f_hz: f64,
        z: &mut [c64],
    ) -> Option<c64> {
        let (nx, nq, ns) = model.sizes;
        let n = nx + nq;
        let (re, im) = model.master(damping, f_hz);
        let pc = |i: usize, j: usize| c64::new(re[(i, j)], im[(i, j)]);
        for (i, zi) in z.iter_mut().enumerate() {
            *zi = match &self.input {
                Input::Force(force) => {
                    c64::new(force.as_slice().get(i).copied().unwrap_or(0.0), 0.0)
                }
                Input::Displacement(s) => -(0..ns).map(|k| pc(i, n + k) * s[k]).sum::<c64>(),
            };
        }
        Self::solve_dense(model, damping, f_hz, z);
        Some(match &self.output {
            Output::Displacement(o) => {
                let from_z: c64 = (0..n.min(o.len())).map(|i| z[i] * o[i]).sum();
                let from_s: f64 = match &self.input {
                    Input::Displacement(s) => (0..ns)
                        .filter_map(|k| Some(o.as_slice().get(n + k)? * s[k]))
                        .sum(),
                    Input::Force(_) => 0.0,
                };
                from_z + c64::new(from_s, 0.0)
            }
            Output::SupportForce(o) => (0..ns)
                .map(|k| {
                    let row = n + k;
                    let from_z: c64 = (0..n).map(|j| pc(row, j) * z[j]).sum();
                    let from_s: c64 = match &self.input {
                        Input::Displacement(s) => (0..ns).map(|j| pc(row, n + j) * s[j]).sum(),
                        Input::Force(_) => c64::new(0.0, 0.0),
                    };
                    -(from_z + from_s) * o[k]
                })
                .sum(),
        })
    }
}

/// The unknowns (master indices, ascending) in the blocks of the pattern that both the
/// input's right-hand side and the output's vector touch.
pub fn coupled_unknowns(
    model: &StageModel,
    input: &Input,
    output: &Output,
) -> Result<Vec<usize>, DynamicsError> {
    model.check(input, output)?;
    Ok(coupled_unknowns_checked(model, input, output))
}

/// [`coupled_unknowns`] of an input and output [`StageModel::check`] accepted.
fn coupled_unknowns_checked(model: &StageModel, input: &Input, output: &Output) -> Vec<usize> {
    let n_all = model.unknowns();
    let n_blocks = model.blocks.iter().map(|&b| b + 1).max().unwrap_or(0);
    let mark = |touched: &mut Vec<bool>, u: usize| {
        if let Some(&b) = model.blocks.get(u) {
            touched[b] = true;
        }
    };
    // the unknowns a parameter row or column reaches through the pattern
    let through_parameters = |touched: &mut Vec<bool>, weights: &[f64]| {
        for (k, &w) in weights.iter().enumerate() {
            if w != 0.0 {
                for &u in model.pattern.row(n_all + k) {
                    if u < n_all {
                        mark(touched, u);
                    }
                }
            }
        }
    };
    let direct = |touched: &mut Vec<bool>, weights: &[f64]| {
        for (u, &w) in weights.iter().enumerate().take(n_all) {
            if w != 0.0 {
                mark(touched, u);
            }
        }
    };
    let mut by_input = vec![false; n_blocks];
    match input {
        Input::Force(f) => direct(&mut by_input, f.as_slice()),
        Input::Displacement(s) => through_parameters(&mut by_input, s.as_slice()),
    }
    let mut by_output = vec![false; n_blocks];
    match output {
        Output::Displacement(o) => direct(&mut by_output, o.as_slice()),
        Output::SupportForce(o) => through_parameters(&mut by_output, o.as_slice()),
    }
    (0..n_all)
        .filter(|&u| {
            let b = model.blocks[u];
            by_input[b] && by_output[b]
        })
        .collect()
}
