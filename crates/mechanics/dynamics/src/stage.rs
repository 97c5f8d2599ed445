//! The frequency-independent matrices of one stage on one fixed sparsity pattern (docs/physics.md
//! §2–§3): P(f) = lossless + Σ_tag (ε'_tag(f) + i ε''_tag(f)) P_tag, the mass matrix, and
//! the per-term tension-off Hessians for the noise breakdown; with the dense views, the
//! complex float elimination and the state-space form built on them.
//!
//! The matrices are assembled once; damping enters only through the multipliers passed to
//! each call, so trying other damping never re-assembles anything.

use faer::{Mat, c64};
use nalgebra::{DMatrix, DVector};
use pendkit_assembly::{Assembled, MassMatrix, OffHessian};
use pendkit_system::{Damping, System};

use crate::DynamicsError;
use crate::pattern::Pattern;
use crate::schur::eliminate;

pub(crate) const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// One term's tension-off Hessian, kept for the per-term noise breakdown.
#[derive(Clone, Debug, PartialEq)]
pub struct TermLoss {
    /// Term name.
    pub label: String,
    /// Damping tag.
    pub tag: String,
    /// Master-matrix rows of the term's coordinates.
    pub positions: Vec<usize>,
    /// Tension-off Hessian over those coordinates (row-major; N/m, N/rad, N m/rad).
    pub off: Vec<f64>,
}

/// The frequency-independent matrices of one stage, every one stored as values on the
/// same symmetric pattern `pattern` (master-matrix order: variables, floats, parameters):
/// P(f) = lossless + Σ_tag (ε'_tag(f) + i ε''_tag(f)) P_tag.
///
/// Build it with [`StageModel::new`]; the fields are the record of the stage (edit none of
/// them: the pattern's blocks are computed from them once).
#[derive(Clone, Debug)]
pub struct StageModel {
    /// Numbers of variables, floats and parameters (master-matrix order x, q, s).
    pub sizes: (usize, usize, usize),
    /// Variable names.
    pub variables: Vec<String>,
    /// Float names.
    pub floats: Vec<String>,
    /// Parameter names.
    pub parameters: Vec<String>,
    /// Where any part of the master matrix or the mass matrix can be non-zero.
    pub pattern: Pattern,
    /// Σ(P_on − P_off) on the pattern: stiffness from static loads through changing
    /// geometry, lossless (N/m, N/rad, N m/rad).
    pub lossless: Vec<f64>,
    /// Σ P_off of each damping tag that has lossy terms, on the pattern, tags in name order.
    pub by_tag: Vec<(String, Vec<f64>)>,
    /// Per-term tension-off Hessians (for the per-term noise breakdown).
    pub terms: Vec<TermLoss>,
    /// Mass matrix over the variables (kg, kg m, kg m²).
    pub mass: MassMatrix,
    /// The mass matrix on the pattern (zero outside the variables' block).
    pub mass_on_pattern: Vec<f64>,
    /// Connected component of each unknown (variables, then floats) in the pattern: the
    /// exactly decoupled blocks.
    pub(crate) blocks: Vec<usize>,
    /// Terms whose stiffness depends on frequency beyond the damping multipliers (none
    /// unless a caller adds them: continuum fibres), used by the responses and the noise;
    /// the modes and the state space keep the static model.
    pub frequency_terms: Vec<std::sync::Arc<dyn FrequencyTerm>>,
}

/// A damping multiplier as a function of (tag, frequency in Hz): (ε', ε'').
pub type Multiplier<'a> = dyn Fn(&str, f64) -> (f64, f64) + 'a;

/// A resonance of a frequency term's own interior with its end frames held (a fibre's
/// clamped–clamped modes): its parts are infinite there, and a mode of the whole model sits
/// there whenever the term's end forces in that resonance cancel on the bodies.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldResonance {
    /// Frequency (Hz) of the lossless resonance (multipliers ε' + 0i).
    pub frequency_hz: f64,
    /// Its imaginary part (Hz) with the loss, to first order in ε'': the resonance decays
    /// as e^{−2π Im f t}, so its quality factor is f/(2 Im f).
    pub imag_hz: f64,
    /// The motion that resonates (for messages: "transverse", "axial", "torsion").
    pub motion: &'static str,
}

/// A part of the dynamic stiffness that depends on frequency otherwise than through the
/// damping multipliers: a continuum fibre's D(f) less the static stack the model already
/// holds for it (docs/continuum-fibres.md). It is added to E(f) over its master rows, on
/// the static model's pattern (the fibre's static terms put its entries there; entries the
/// pattern lacks, zero in the static model by symmetry, are left out), and its dissipation
/// is split among its parts, one per damping tag.
///
/// The term works in its own displacements y = J x (J: [`FrequencyTerm::jacobian`]), which
/// fall into groups ([`FrequencyTerm::groups`]): its matrix over y is block diagonal, one
/// small block per group and each block in one part. A fibre's own displacements are its
/// one-dimensional coordinates (the axial wave's, the two beams', the twist wave's), so a
/// frequency point costs a few small blocks and their projection J_gᵀ V_g J_g, no 12 × 12
/// form over the end frames.
pub trait FrequencyTerm: Send + Sync + std::fmt::Debug {
    /// A name for messages (the wire's).
    fn label(&self) -> &str;
    /// Master rows of the term's coordinates (variables, floats, parameters order).
    fn positions(&self) -> &[usize];
    /// The term's own displacements per unit of each of its coordinates, J (m × n,
    /// [`FrequencyTerm::positions`] order; m, n, m, m or rad per unit coordinate).
    fn jacobian(&self) -> &DMatrix<f64>;
    /// The damping tag of each part.
    fn tags(&self) -> &[String];
    /// The groups of the own displacements, in the order [`FrequencyTerm::parts`] writes
    /// their blocks: rows of J, disjoint, and the part each block belongs to.
    fn groups(&self) -> &[Group];
    /// At `f_hz` (Hz), with the tags' multipliers ε′ + iε″ `multipliers` (in
    /// [`FrequencyTerm::tags`] order), writes each group's block V_g (s × s over the
    /// group's s own displacements, row-major; N/m, N/rad, N m/rad) into `values`, one after
    /// the other in group order ([`block_len`] entries in all): the term adds
    /// Σ_g J_gᵀ V_g J_g to E(f), and Im V_g is the dissipation of the group's part.
    fn parts(&self, f_hz: f64, multipliers: &[c64], values: &mut [c64]);
    /// The term's held resonances ([`HeldResonance`]) in [`lo_hz`, `hi_hz`], each once per
    /// independent motion (a round fibre's two transverse planes: twice), with the tags'
    /// multipliers at each frequency given by `multipliers(f_hz)` ([`FrequencyTerm::tags`]
    /// order). None by default: a term whose parts are finite at every frequency.
    fn held_resonances(
        &self,
        _lo_hz: f64,
        _hi_hz: f64,
        _multipliers: &dyn Fn(f64) -> Vec<c64>,
    ) -> Vec<HeldResonance> {
        Vec::new()
    }
    /// The frequencies (Hz) of the term's first `n` violin harmonics (a fibre's transverse
    /// held resonances, lossless), around which `StageModel::violin_modes` looks for the
    /// whole model's roots. None by default.
    fn harmonics(&self, _n: usize) -> Vec<f64> {
        Vec::new()
    }
}

/// A group of a frequency term's own displacements: rows `rows` of its Jacobian, whose
/// block belongs to part `part` (index into [`FrequencyTerm::tags`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Group {
    /// Rows of the Jacobian (own displacements).
    pub rows: std::ops::Range<usize>,
    /// The part (tag) the block belongs to.
    pub part: usize,
}

/// Number of values a term's blocks take ([`FrequencyTerm::parts`]): Σ_g s_g².
pub fn block_len(groups: &[Group]) -> usize {
    groups.iter().map(|g| g.rows.len() * g.rows.len()).sum()
}

/// A frequency term's Jacobian as the non-zeros of each own displacement's row, worked out
/// once per term: a fibre's end rows depend on one body each, and the projection skips the
/// zeros.
#[derive(Clone, Debug)]
pub(crate) struct Projection {
    /// Number of the term's coordinates (n).
    n: usize,
    /// Per own displacement, its (coordinate, weight) non-zeros.
    rows: Vec<Vec<(usize, f64)>>,
    groups: Vec<Group>,
}

impl Projection {
    /// The projection of `term`.
    pub(crate) fn new(term: &dyn FrequencyTerm) -> Self {
        let j = term.jacobian();
        let (m, n) = j.shape();
        let rows = (0..m)
            .map(|r| {
                (0..n)
                    .filter(|&c| j[(r, c)] != 0.0)
                    .map(|c| (c, j[(r, c)]))
                    .collect()
            })
            .collect();
        Projection {
            n,
            rows,
            groups: term.groups().to_vec(),
        }
    }

    /// Number of the term's coordinates.
    pub(crate) fn coordinates(&self) -> usize {
        self.n
    }

    /// Number of own displacements.
    pub(crate) fn own(&self) -> usize {
        self.rows.len()
    }

    /// Each group with its block of `values` ([`FrequencyTerm::parts`]); a group outside J's
    /// rows or past the values (a term breaking its contract) is left out.
    fn blocks<'a>(&'a self, values: &'a [c64]) -> impl Iterator<Item = (&'a Group, &'a [c64])> {
        let mut offset = 0;
        self.groups.iter().filter_map(move |g| {
            let s = g.rows.len();
            let block = values.get(offset..offset + s * s);
            offset += s * s;
            block
                .filter(|_| g.rows.end <= self.rows.len())
                .map(|b| (g, b))
        })
    }

    /// Σ_g J_gᵀ V_g J_g (n × n, row-major) into `out` for the blocks `values`
    /// ([`FrequencyTerm::parts`]), with `scratch` of n values. The upper triangle is
    /// formed and mirrored: V is complex symmetric (a stiffness), and so is the sum.
    pub(crate) fn project(&self, values: &[c64], out: &mut [c64], scratch: &mut [c64]) {
        let n = self.n;
        let zero = c64::new(0.0, 0.0);
        out.fill(zero);
        for (g, block) in self.blocks(values) {
            let (r0, s) = (g.rows.start, g.rows.len());
            for i in 0..s {
                // h = row i of V_g J_g, then out += J_g[i]ᵀ h over the upper triangle
                scratch.fill(zero);
                for (k, &v) in block[i * s..(i + 1) * s].iter().enumerate() {
                    if v == zero {
                        continue;
                    }
                    for &(c, w) in &self.rows[r0 + k] {
                        scratch[c] += v * w;
                    }
                }
                for &(a, w) in &self.rows[r0 + i] {
                    let row = &mut out[a * n..(a + 1) * n];
                    for (o, h) in row[a..].iter_mut().zip(&scratch[a..]) {
                        *o += h * w;
                    }
                }
            }
        }
        for a in 0..n {
            for b in 0..a {
                out[a * n + b] = out[b * n + a];
            }
        }
    }

    /// Adds, per part, ȳᵀ Im(V_g) y over the part's groups to `out[tag[part]]` (a part
    /// whose tag is `None` is left out), y = J z the own displacements of the response `z`
    /// over the term's coordinates (zero where a coordinate does not move); `y` is scratch
    /// of one value per own displacement.
    pub(crate) fn dissipation(
        &self,
        values: &[c64],
        z: &[c64],
        tags: &[Option<usize>],
        y: &mut [c64],
        out: &mut [f64],
    ) {
        for (yr, row) in y.iter_mut().zip(&self.rows) {
            *yr = row.iter().map(|&(c, w)| z[c] * w).sum();
        }
        for (g, block) in self.blocks(values) {
            let (r0, s) = (g.rows.start, g.rows.len());
            let Some(slot) = tags
                .get(g.part)
                .copied()
                .flatten()
                .and_then(|t| out.get_mut(t))
            else {
                continue;
            };
            let y = &y[r0..r0 + s];
            for (i, yi) in y.iter().enumerate() {
                for (k, yk) in y.iter().enumerate() {
                    // Re(ȳ_i y_k)
                    *slot += block[i * s + k].im * (yi.re * yk.re + yi.im * yk.im);
                }
            }
        }
    }
}

/// A displacement or force input.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// Displacement of the parameters (m or rad per unit input), one entry per parameter.
    Displacement(DVector<f64>),
    /// Generalised force on the variables (N or N m per unit input), one per variable; or
    /// on the variables and then the floats (a force on a body posed by a float, such as
    /// a massless blade tip).
    Force(DVector<f64>),
}

/// A displacement or support-force output.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// A linear combination of the variables (m or rad), one entry per variable; or of the
    /// variables and the floats (a point on a body a float poses); or of the variables,
    /// the floats and the parameters (a point whose motion includes the support's own,
    /// which a displacement input passes straight to the output).
    Displacement(DVector<f64>),
    /// A linear combination of the generalised forces on the parameters (N or N m).
    SupportForce(DVector<f64>),
}

/// Real state-space matrices with names (docs/physics.md §3), damping as viscous at `f_d`.
#[derive(Clone, Debug)]
pub struct StateSpace {
    /// State matrix (2n × 2n).
    pub a: DMatrix<f64>,
    /// Input matrix (2n × (n_s + n)).
    pub b: DMatrix<f64>,
    /// Output matrix ((n + n_s) × 2n).
    pub c: DMatrix<f64>,
    /// Feedthrough ((n + n_s) × (n_s + n)).
    pub d: DMatrix<f64>,
    /// State names: the variables, then their rates (`<name>_dot`).
    pub states: Vec<String>,
    /// Input names: support displacements, then `force:<variable>`.
    pub inputs: Vec<String>,
    /// Output names: the variables, then `force:<parameter>` (forces on the support).
    pub outputs: Vec<String>,
    /// Frequency (Hz) at which frequency-dependent damping was represented as viscous.
    pub damping_frequency: f64,
}

/// Complex K_eff, C_XS,eff and S_eff at one frequency.
#[derive(Clone, Debug)]
pub struct ReducedComplex {
    /// K_eff over the variables.
    pub k_eff: Mat<c64>,
    /// C_XS,eff: variables × parameters.
    pub c_xs_eff: Mat<c64>,
    /// S_eff over the parameters.
    pub s_eff: Mat<c64>,
}

/// For every master row, the (term, local index) pairs that put a row of their local
/// Hessian there, in term order: compressed rows over the terms' positions.
struct RowEntries {
    start: Vec<usize>,
    entries: Vec<(usize, usize)>,
}

impl RowEntries {
    fn new(dim: usize, positions: &[&[usize]]) -> Self {
        let mut start = vec![0; dim + 1];
        for p in positions {
            for &r in p.iter() {
                start[r + 1] += 1;
            }
        }
        for i in 0..dim {
            start[i + 1] += start[i];
        }
        let mut next = start.clone();
        let mut entries = vec![(0, 0); start[dim]];
        for (t, p) in positions.iter().enumerate() {
            for (a, &r) in p.iter().enumerate() {
                entries[next[r]] = (t, a);
                next[r] += 1;
            }
        }
        RowEntries { start, entries }
    }

    fn row(&self, i: usize) -> &[(usize, usize)] {
        &self.entries[self.start[i]..self.start[i + 1]]
    }
}

/// The parts of the master matrix a term's Hessians go to.
#[derive(Clone, Copy)]
enum Destination {
    /// Lossless entirely: P_on into the lossless sum.
    Lossless,
    /// Entirely lossy: P_on into its tag.
    Tag(usize),
    /// P_on − P_off lossless, P_off into its tag.
    Split(usize),
}

impl StageModel {
    /// Collects the stage's matrices from an assembly: one pattern for every part, the
    /// lossless part Σ(P_on − P_off), each damping tag's Σ P_off and the mass matrix on it.
    ///
    /// Linear in the terms' entries: the candidate pattern is built row by row from the
    /// terms that touch each row (a marker per column instead of sorting duplicates), and
    /// each row's local Hessian rows are added through a column-to-slot map of that row
    /// (no search per entry). Each slot still receives its terms in term order, the order of
    /// a dense scatter, so the sums are the same numbers a dense assembly gives.
    #[expect(
        clippy::too_many_lines,
        reason = "the linear-time assembly described above: the flat term positions, the candidate \
                  pattern and the column-to-slot map are built once and shared by the scatter that \
                  follows, whose term-order sums make the numbers a dense assembly gives"
    )]
    pub fn new(system: &System, assembled: &Assembled) -> Self {
        const NONE: usize = usize::MAX;
        let layout = &assembled.layout;
        let (nx, nq, ns) = layout.sizes();
        let dim = nx + nq + ns;
        let names = |ids: &[usize]| ids.iter().map(|&i| system.coords[i].name.clone()).collect();
        let terms = &assembled.terms;
        // master rows of every term's coordinates, one flat array
        let mut first_position = Vec::with_capacity(terms.len() + 1);
        first_position.push(0);
        let mut flat_positions = Vec::new();
        for t in terms {
            flat_positions.extend(t.coords.iter().map(|&g| layout.position[g]));
            first_position.push(flat_positions.len());
        }
        let positions: Vec<&[usize]> = first_position
            .windows(2)
            .map(|w| &flat_positions[w[0]..w[1]])
            .collect();
        let rows = RowEntries::new(dim, &positions);
        let mass = &assembled.mass;
        // the columns of each row's mass entries (and of their transposes)
        let mut mass_columns: Vec<Vec<usize>> = vec![Vec::new(); nx];
        for (i, j, m) in mass.entries() {
            if m != 0.0 && i < nx && j < nx {
                mass_columns[i].push(j);
                mass_columns[j].push(i);
            }
        }

        // candidate pattern: every position pair of every term, and the mass entries
        let mut mark = vec![NONE; dim];
        let mut row_start = Vec::with_capacity(dim + 1);
        let mut cols = Vec::new();
        row_start.push(0);
        for i in 0..dim {
            let first = cols.len();
            for &(t, _) in rows.row(i) {
                for &j in positions[t] {
                    if mark[j] != i {
                        mark[j] = i;
                        cols.push(j);
                    }
                }
            }
            for &j in mass_columns.get(i).map_or(&[][..], Vec::as_slice) {
                if mark[j] != i {
                    mark[j] = i;
                    cols.push(j);
                }
            }
            cols[first..].sort_unstable();
            row_start.push(cols.len());
        }
        let candidates = Pattern::from_sorted_rows(dim, row_start, cols);
        let nnz = candidates.len();

        // tags with lossy terms, in name order, and where each term's Hessians go
        let mut tag_names: Vec<&str> = terms
            .iter()
            .filter(|t| t.off != OffHessian::Zero)
            .map(|t| t.tag.as_str())
            .collect();
        tag_names.sort_unstable();
        tag_names.dedup();
        let tag_of = |tag: &str| tag_names.binary_search(&tag).unwrap_or(0);
        let destinations: Vec<Destination> = terms
            .iter()
            .map(|t| match &t.off {
                OffHessian::Zero => Destination::Lossless,
                OffHessian::Same => Destination::Tag(tag_of(&t.tag)),
                OffHessian::Matrix(_) => Destination::Split(tag_of(&t.tag)),
            })
            .collect();

        // lossless = Σ_zero P_on + (Σ_replaced P_on − Σ_replaced P_off), as the dense
        // dilution split adds them
        let (mut zero_on, mut replaced_on, mut replaced_off) =
            (vec![0.0; nnz], vec![0.0; nnz], vec![0.0; nnz]);
        let mut by_tag: Vec<Vec<f64>> = vec![vec![0.0; nnz]; tag_names.len()];
        let mut mass_on_candidates = vec![0.0; nnz];
        let mut slot_of_column = vec![NONE; dim];
        for i in 0..dim {
            let slots = candidates.row_slots(i);
            for s in slots.clone() {
                slot_of_column[candidates.row(i)[s - slots.start]] = s;
                if i < nx {
                    let j = candidates.position(s).1;
                    if j < nx {
                        mass_on_candidates[s] = mass[(i, j)];
                    }
                }
            }
            for &(t, a) in rows.row(i) {
                let term = &terms[t];
                let pos = positions[t];
                let m = pos.len();
                // row a of the local matrices (row-major, m × m)
                let local_row = a * m..(a + 1) * m;
                let on = &term.on[local_row.clone()];
                let slot = |b: usize| slot_of_column[b];
                match (destinations[t], &term.off) {
                    (Destination::Lossless, _) => {
                        for (&b, &v) in pos.iter().zip(on) {
                            zero_on[slot(b)] += v;
                        }
                    }
                    (Destination::Tag(k), _) => {
                        let tag = &mut by_tag[k];
                        for (&b, &v) in pos.iter().zip(on) {
                            tag[slot(b)] += v;
                        }
                    }
                    (Destination::Split(k), off) => {
                        let off = match off {
                            OffHessian::Matrix(off) => &off[local_row],
                            _ => on,
                        };
                        let tag = &mut by_tag[k];
                        for ((&b, &v_on), &v_off) in pos.iter().zip(on).zip(off) {
                            let s = slot(b);
                            replaced_on[s] += v_on;
                            replaced_off[s] += v_off;
                            tag[s] += v_off;
                        }
                    }
                }
            }
        }
        let lossless: Vec<f64> = (0..nnz)
            .map(|s| zero_on[s] + (replaced_on[s] - replaced_off[s]))
            .collect();
        // the pattern holds what is non-zero after the sums: a term's local Hessian has
        // exact zeros (a vertical wire does not couple x to y), and those decouple blocks
        let mut nonzero: Vec<bool> = lossless
            .iter()
            .zip(&mass_on_candidates)
            .map(|(&p, &m)| p != 0.0 || m != 0.0)
            .collect();
        for values in &by_tag {
            for (nz, &v) in nonzero.iter_mut().zip(values) {
                *nz |= v != 0.0;
            }
        }
        let (pattern, old) = candidates.retain(|s| nonzero[s]);
        let on_pattern = |values: &[f64]| old.iter().map(|&s| values[s]).collect::<Vec<f64>>();
        let (blocks, _) = pattern.components(nx + nq);
        let lossy_terms = terms
            .iter()
            .zip(&positions)
            .filter_map(|(t, positions)| {
                let off = match &t.off {
                    OffHessian::Zero => return None,
                    OffHessian::Same => t.on.clone(),
                    OffHessian::Matrix(m) => m.clone(),
                };
                Some(TermLoss {
                    label: t.label.clone(),
                    tag: t.tag.clone(),
                    positions: positions.to_vec(),
                    off,
                })
            })
            .collect();
        StageModel {
            sizes: (nx, nq, ns),
            variables: names(&layout.variables),
            floats: names(&layout.floats),
            parameters: names(&layout.parameters),
            lossless: on_pattern(&lossless),
            mass_on_pattern: on_pattern(&mass_on_candidates),
            by_tag: tag_names
                .iter()
                .zip(&by_tag)
                .map(|(name, values)| (name.to_string(), on_pattern(values)))
                .collect(),
            pattern,
            terms: lossy_terms,
            mass: mass.clone(),
            blocks,
            frequency_terms: Vec::new(),
        }
    }

    /// The blocks of frequency term `term` at `f_hz` (Hz) with `damping`'s multipliers
    /// ([`FrequencyTerm::parts`]).
    pub fn frequency_parts(term: &dyn FrequencyTerm, damping: &Damping, f_hz: f64) -> Vec<c64> {
        Self::frequency_parts_with(term, f_hz, &|tag, f| damping.at(tag, f))
    }

    /// [`StageModel::frequency_parts`] with the multiplier (ε', ε'') of each tag given by
    /// `multiplier(tag, f_hz)`.
    fn frequency_parts_with(
        term: &dyn FrequencyTerm,
        f_hz: f64,
        multiplier: &Multiplier<'_>,
    ) -> Vec<c64> {
        let m: Vec<c64> = term
            .tags()
            .iter()
            .map(|tag| {
                let (re, im) = multiplier(tag, f_hz);
                c64::new(re, im)
            })
            .collect();
        let mut values = vec![c64::new(0.0, 0.0); block_len(term.groups())];
        term.parts(f_hz, &m, &mut values);
        values
    }

    /// Number of unknowns solved for in a response: variables and floats.
    pub fn unknowns(&self) -> usize {
        self.sizes.0 + self.sizes.1
    }

    /// The real and imaginary parts of P(f) on the pattern, tags added in name order.
    pub fn master_values(&self, damping: &Damping, f_hz: f64) -> (Vec<f64>, Vec<f64>) {
        self.master_values_with(f_hz, &|tag, f| damping.at(tag, f))
    }

    /// [`StageModel::master_values`] with the multipliers of `multiplier(tag, f_hz)`.
    fn master_values_with(&self, f_hz: f64, multiplier: &Multiplier<'_>) -> (Vec<f64>, Vec<f64>) {
        let mut re = self.lossless.clone();
        let mut im = vec![0.0; re.len()];
        for (tag, p) in &self.by_tag {
            let (mr, mi) = multiplier(tag, f_hz);
            for ((r, i), &v) in re.iter_mut().zip(im.iter_mut()).zip(p) {
                *r += v * mr;
                if mi != 0.0 {
                    *i += v * mi;
                }
            }
        }
        (re, im)
    }

    /// Values on the pattern (one per slot, as [`StageModel::lossless`]) as a dense master
    /// matrix; an error when `values` has another length.
    pub fn dense(&self, values: &[f64]) -> Result<DMatrix<f64>, DynamicsError> {
        if values.len() != self.pattern.len() {
            return Err(DynamicsError::Length {
                what: "values on the pattern",
                expected: self.pattern.len(),
                got: values.len(),
            });
        }
        Ok(self.dense_on_pattern(values))
    }

    /// [`StageModel::dense`] of values this model made on its own pattern.
    fn dense_on_pattern(&self, values: &[f64]) -> DMatrix<f64> {
        let n = self.pattern.dim();
        let mut m = DMatrix::zeros(n, n);
        for (s, &v) in values.iter().enumerate().take(self.pattern.len()) {
            m[self.pattern.position(s)] = v;
        }
        m
    }

    /// The parts of the dynamic stiffness E(f) = P(f) − ω² M over every master row, each
    /// as (multiplier, values on the pattern): the lossless part (1), every damping tag's
    /// tension-off part (ε'_tag(f) + i ε''_tag(f), in `by_tag` order) and the mass (−ω²,
    /// zero outside the variables' block). Their sum is the matrix the sweeps factorise;
    /// [`StageModel::sum_parts`] puts it together on the pattern.
    pub fn dynamic_parts(&self, damping: &Damping, f_hz: f64) -> Vec<(c64, &[f64])> {
        let w2 = (TWO_PI * f_hz).powi(2);
        let mut parts = Vec::with_capacity(self.by_tag.len() + 2);
        parts.push((c64::new(1.0, 0.0), self.lossless.as_slice()));
        for (tag, values) in &self.by_tag {
            let (re, im) = damping.at(tag, f_hz);
            parts.push((c64::new(re, im), values.as_slice()));
        }
        parts.push((c64::new(-w2, 0.0), self.mass_on_pattern.as_slice()));
        parts
    }

    /// The matrix Σ_k m_k V_k as complex values on this model's pattern (into `out`, one
    /// per slot), for parts (m_k, V_k) given as values on the pattern: E(f) from
    /// [`StageModel::dynamic_parts`], or a change of E with a parameter. Put together once,
    /// it multiplies any number of vectors ([`StageModel::multiply`]). An error when a part
    /// or `out` has another length.
    pub fn sum_parts(&self, parts: &[(c64, &[f64])], out: &mut [c64]) -> Result<(), DynamicsError> {
        let len = self.pattern.len();
        for got in std::iter::once(out.len()).chain(parts.iter().map(|(_, v)| v.len())) {
            if got != len {
                return Err(DynamicsError::Length {
                    what: "values on the pattern",
                    expected: len,
                    got,
                });
            }
        }
        out.fill(c64::new(0.0, 0.0));
        for &(m, values) in parts {
            if m == c64::new(0.0, 0.0) {
                continue;
            }
            for (o, &v) in out.iter_mut().zip(values) {
                *o += m * v;
            }
        }
        Ok(())
    }

    /// Adds A w to `out` (both over every master row) for the matrix A given as complex
    /// values on this model's pattern ([`StageModel::sum_parts`]), sparse, without forming
    /// A. An error when `values`, `w` or `out` has another length.
    pub fn multiply(
        &self,
        values: &[c64],
        w: &[c64],
        out: &mut [c64],
    ) -> Result<(), DynamicsError> {
        let n = self.pattern.dim();
        for (what, expected, got) in [
            ("values on the pattern", self.pattern.len(), values.len()),
            ("multiply: w", n, w.len()),
            ("multiply: out", n, out.len()),
        ] {
            if got != expected {
                return Err(DynamicsError::Length {
                    what,
                    expected,
                    got,
                });
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            let slots = self.pattern.row_slots(i);
            let mut sum = c64::new(0.0, 0.0);
            for (a, &j) in values[slots].iter().zip(self.pattern.row(i)) {
                // w is often zero over whole blocks (a support displacement, the
                // parameters' rows of a response)
                let wj = w[j];
                if wj != c64::new(0.0, 0.0) {
                    sum += a * wj;
                }
            }
            *o += sum;
        }
        Ok(())
    }

    /// Real stiffness at f = 0 (ε' of each tag at DC), dense: the matrix the modes use.
    pub fn real_stiffness(&self, damping: &Damping) -> DMatrix<f64> {
        self.dense_on_pattern(&self.master_values(damping, 0.0).0)
    }

    /// Complex master matrix P(f) (layout order x, q, s), dense real and imaginary parts.
    /// With frequency terms ([`StageModel::frequency_terms`]) their parts are added.
    pub fn master(&self, damping: &Damping, f_hz: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        self.master_with(f_hz, &|tag, f| damping.at(tag, f))
    }

    /// [`StageModel::master`] with the multiplier (ε', ε'') of each tag given by
    /// `multiplier(tag, f_hz)`: the violin-mode search evaluates the model with the loss
    /// set aside (ε'' = 0) and with it.
    pub fn master_with(
        &self,
        f_hz: f64,
        multiplier: &Multiplier<'_>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let (re, im) = self.master_values_with(f_hz, multiplier);
        let (mut re, mut im) = (self.dense_on_pattern(&re), self.dense_on_pattern(&im));
        for term in &self.frequency_terms {
            let projection = Projection::new(term.as_ref());
            let n = projection.coordinates();
            let p = term.positions();
            let values = Self::frequency_parts_with(term.as_ref(), f_hz, multiplier);
            let mut local = vec![c64::new(0.0, 0.0); n * n];
            projection.project(&values, &mut local, &mut vec![c64::new(0.0, 0.0); n]);
            for (k, z) in local.iter().enumerate() {
                re[(p[k / n], p[k % n])] += z.re;
                im[(p[k / n], p[k % n])] += z.im;
            }
        }
        (re, im)
    }

    /// Checks that an input and an output have one entry per parameter or variable (or,
    /// for a force, per variable and float; for a displacement output, per variable and
    /// float, or per variable, float and parameter), all finite.
    pub fn check(&self, input: &Input, output: &Output) -> Result<(), DynamicsError> {
        let (nx, nq, ns) = self.sizes;
        let checks: [(&'static str, &DVector<f64>, &[usize]); 2] = [
            match input {
                Input::Displacement(s) => ("displacement input", s, &[ns]),
                Input::Force(f) => ("force input", f, &[nx, nx + nq]),
            },
            match output {
                Output::Displacement(o) => ("displacement output", o, &[nx, nx + nq, nx + nq + ns]),
                Output::SupportForce(o) => ("support-force output", o, &[ns]),
            },
        ];
        for (what, vector, allowed) in checks {
            if !allowed.contains(&vector.len()) {
                return Err(DynamicsError::Length {
                    what,
                    expected: allowed[0],
                    got: vector.len(),
                });
            }
            if let Some(k) = vector.iter().position(|x| !x.is_finite()) {
                return Err(DynamicsError::NotFinite {
                    what,
                    row: k,
                    column: 0,
                });
            }
        }
        Ok(())
    }

    /// Complex reduced matrices K_eff(f), C_XS,eff(f), S_eff(f): the Schur complement of
    /// the floats done on the complex matrices, per frequency (docs/physics.md §3); an error when
    /// the float block is singular there or a damping multiplier is out of range.
    pub fn reduced(&self, damping: &Damping, f_hz: f64) -> Result<ReducedComplex, DynamicsError> {
        if f_hz != 0.0 {
            crate::validate::check_frequency("frequency", f_hz)?;
        }
        self.check_damping_at(damping, f_hz)?;
        let (reduced, singular) = self.reduced_checked(damping, f_hz);
        match singular {
            Some(k) => Err(DynamicsError::SingularFloats {
                float: self.floats.get(k).cloned().unwrap_or_default(),
            }),
            None => Ok(reduced),
        }
    }

    /// Checks every lossy tag's multiplier at `f_hz` (see [`crate::validate`]).
    pub fn check_damping_at(&self, damping: &Damping, f_hz: f64) -> Result<(), DynamicsError> {
        crate::validate::check_damping(
            damping,
            self.by_tag.iter().map(|(t, _)| t.as_str()),
            &[f_hz],
        )
    }

    /// Checks the storage multiplier ε'(0) of every lossy tag (the real stiffness the modes
    /// use): finite and not negative. The loss at f = 0 is not used there.
    pub fn check_damping_at_dc(&self, damping: &Damping) -> Result<(), DynamicsError> {
        for (tag, _) in &self.by_tag {
            let (re, _) = damping.at(tag, 0.0);
            crate::validate::check_multiplier(tag, 0.0, re, 0.0)?;
        }
        Ok(())
    }

    fn reduced_checked(&self, damping: &Damping, f_hz: f64) -> (ReducedComplex, Option<usize>) {
        let (nx, nq, ns) = self.sizes;
        let (re, im) = self.master_values(damping, f_hz);
        let n = self.pattern.dim();
        let mut p = Mat::<c64>::zeros(n, n);
        for s in 0..re.len() {
            let (i, j) = self.pattern.position(s);
            p[(i, j)] = c64::new(re[s], im[s]);
        }
        let kept: Vec<usize> = (0..nx).chain(nx + nq..n).collect();
        let floats: Vec<usize> = (nx..nx + nq).collect();
        let e = eliminate(|i, j| p[(i, j)], &kept, &floats);
        let a = e.matrix;
        let block = |r0: usize, c0: usize, nr: usize, nc: usize| {
            Mat::<c64>::from_fn(nr, nc, |i, j| a[(r0 + i, c0 + j)])
        };
        (
            ReducedComplex {
                k_eff: block(0, 0, nx, nx),
                c_xs_eff: block(0, nx, nx, ns),
                s_eff: block(nx, nx, ns, ns),
            },
            e.singular,
        )
    }

    /// State-space matrices with damping represented as viscous at `f_d` (Hz, > 0); exact
    /// for viscous damping only.
    pub fn state_space(&self, damping: &Damping, f_d: f64) -> Result<StateSpace, DynamicsError> {
        if f_d.is_nan() || f_d <= 0.0 {
            return Err(DynamicsError::DampingFrequency(f_d));
        }
        crate::validate::check_frequency("damping frequency", f_d)?;
        self.check_damping_at(damping, f_d)?;
        let (nx, _, ns) = self.sizes;
        let (r, singular) = self.reduced_checked(damping, f_d);
        if let Some(k) = singular {
            return Err(DynamicsError::SingularFloats {
                float: self.floats.get(k).cloned().unwrap_or_default(),
            });
        }
        let m_inv = self
            .mass
            .to_dense()
            .cholesky()
            .ok_or_else(|| DynamicsError::SingularMass {
                variable: self.variables.first().cloned().unwrap_or_default(),
            })?
            .inverse();
        let re = |m: &Mat<c64>| DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)].re);
        let im = |m: &Mat<c64>| DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)].im);
        let mk_re = -(&m_inv * re(&r.k_eff));
        let mk_im = -(&m_inv * im(&r.k_eff)) / (TWO_PI * f_d);
        let mc_re = -(&m_inv * re(&r.c_xs_eff));
        let mut a = DMatrix::zeros(2 * nx, 2 * nx);
        a.view_mut((0, nx), (nx, nx)).fill_with_identity();
        a.view_mut((nx, 0), (nx, nx)).copy_from(&mk_re);
        a.view_mut((nx, nx), (nx, nx)).copy_from(&mk_im);
        let mut b = DMatrix::zeros(2 * nx, ns + nx);
        b.view_mut((nx, 0), (nx, ns)).copy_from(&mc_re);
        b.view_mut((nx, ns), (nx, nx)).copy_from(&m_inv);
        let mut c = DMatrix::zeros(nx + ns, 2 * nx);
        c.view_mut((0, 0), (nx, nx)).fill_with_identity();
        c.view_mut((nx, 0), (ns, nx))
            .copy_from(&(-re(&r.c_xs_eff).transpose()));
        let mut d = DMatrix::zeros(nx + ns, ns + nx);
        d.view_mut((nx, 0), (ns, ns)).copy_from(&(-re(&r.s_eff)));
        let forces = |names: &[String]| {
            names
                .iter()
                .map(|n| format!("force:{n}"))
                .collect::<Vec<_>>()
        };
        for (what, m) in [
            ("state matrix A", &a),
            ("input matrix B", &b),
            ("output matrix C", &c),
            ("feedthrough D", &d),
        ] {
            if let Some(k) = m.iter().position(|x| !x.is_finite()) {
                return Err(DynamicsError::NotFinite {
                    what,
                    row: k % m.nrows().max(1),
                    column: k / m.nrows().max(1),
                });
            }
        }
        Ok(StateSpace {
            a,
            b,
            c,
            d,
            states: self
                .variables
                .iter()
                .cloned()
                .chain(self.variables.iter().map(|n| format!("{n}_dot")))
                .collect(),
            inputs: self
                .parameters
                .iter()
                .cloned()
                .chain(forces(&self.variables))
                .collect(),
            outputs: self
                .variables
                .iter()
                .cloned()
                .chain(forces(&self.parameters))
                .collect(),
            damping_frequency: f_d,
        })
    }
}
