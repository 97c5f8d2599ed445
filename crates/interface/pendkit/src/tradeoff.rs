//! The speed–accuracy trade-off (`pendkit tradeoff`): a ladder of variants of one
//! suspension, each timed from the model's name to the answer of one question (the modes
//! below a frequency, the thermal noise at an output over a band, optionally a transfer
//! function) and measured against the richest variant.
//!
//! # The ladder
//!
//! The *base* is the case as given, at stage 2, with its own number of violin beads,
//! solved over the restricted blocks. The ladder holds:
//!
//! - the base at each stage: 0A, 0B, 1A, 1B, 2 (0A has no losses, so it cannot answer a
//!   noise question and is listed as skipped, with the reason);
//! - at stage 2, every blade-tip variant of the same family with every number of violin
//!   beads per fibre (`n_beads`, where the model has that parameter; default 0, 1, 2, 5,
//!   10, 20, 40). The family, where the model has one, by the LIGO toolkit's names:
//!   `<base>` (xtra-lite: tips are massless floats), `<base>-lite` (tips with mass, 1
//!   DOF), `<base>-lateral` (xtra-lite plus lateral compliance) and `<base>-full` (tips as
//!   6-DOF bodies on 6x6 springs), in that order of richness. Both refinements together,
//!   because they act on different parts (blade tips move the pitch modes, beads carry
//!   the fibres' mass) and a question may need some of each;
//! - the base solved over every variable and float ([`Solver::Full`]) instead of only the
//!   blocks the output couples to;
//! - at stage 2, every blade-tip variant with continuum fibres (no beads; the lowest wires'
//!   exact dynamic stiffness, docs/continuum-fibres.md), where [`Ladder::continuum`] asks.
//!
//! The *reference* is the richest of everything: the last family member, stage 2, the full
//! solve, with continuum fibres (exact at every frequency, violin modes included), or,
//! without them, the most beads of the ladder. Every variant's noise and transfer function
//! are measured against it, so a row's error is the whole error of that simplification of
//! the question, not of one step. The modes are measured against the richest finite
//! variant (the same, with the most beads): a continuum model's modes are its static
//! model's (`modes` and `ss` need a finite model), so the continuum rows carry the modes
//! error of leaving the fibres' mass out, and the bead rows are not charged for having it.
//!
//! # Errors
//!
//! - modes: the largest |f − f_ref| / f_ref over the reference's modes below the band's
//!   top, each matched to a variant mode by shape (see [`match_modes`]);
//! - noise: the largest |ASD / ASD_ref − 1| over the band (log-spaced points);
//! - transfer function (with an input): the largest ||H| / |H_ref| − 1| over the band.
//!
//! A variant's error ([`Errors::max`]) is the largest of the three; the Pareto front and the
//! cheapest variant within a tolerance use it.
//!
//! # Timing
//!
//! Each variant runs the whole question from the model's name (build, equilibrium, stage,
//! modes below the top, noise, transfer function) at least once and again until
//! [`Timing::max_runs`] runs or [`Timing::budget_s`] seconds are spent, and reports the
//! minimum: the run least disturbed by the rest of the machine.

use std::time::Instant;

use faer::c64;
use nalgebra::DMatrix;
use pendkit_dynamics::Mode;

use pendkit_model::BuildError;

use crate::catalogue::find_model;
use crate::stage::{Fibres, ModeSelection, RunOptions, run_stage_with};
use crate::{Case, Error, NoiseOptions, Solver, Stage, log_grid};

/// Modes are computed below the band's top times this, so that a reference mode just under
/// the top can find its counterpart in a variant where it sits just over.
pub const MODE_SEARCH_MARGIN: f64 = 1.5;

/// The violin-bead counts of the default ladder.
pub const DEFAULT_BEADS: [usize; 7] = [0, 1, 2, 5, 10, 20, 40];

/// Family suffixes of the LIGO toolkit's blade-tip variants, poorest first; `""` is the
/// xtra-lite base model. `-v5` only presets the beads, which the ladder sets itself.
const FAMILY_SUFFIXES: [&str; 4] = ["", "-lite", "-lateral", "-full"];
const BEADED_SUFFIX: &str = "-v5";

/// The question every variant answers.
#[derive(Clone, Debug, PartialEq)]
pub struct Question {
    /// Displacement output of the noise (and of the transfer function): a variable or
    /// `<body>@x,y,z/dx,dy,dz`.
    pub output: String,
    /// Input of the transfer function, if one is asked for.
    pub input: Option<String>,
    /// Band (Hz): first and last frequency of the log-spaced grid.
    pub band_hz: (f64, f64),
    /// Points of the grid.
    pub points: usize,
}

impl Question {
    /// The frequencies (Hz).
    pub fn grid(&self) -> Result<Vec<f64>, Error> {
        log_grid(self.band_hz.0, self.band_hz.1, self.points)
    }
}

/// Which variants the ladder holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Ladder {
    /// Stages to try.
    pub stages: Vec<Stage>,
    /// Violin beads per fibre to try (models with `n_beads` only).
    pub beads: Vec<usize>,
    /// Whether to try the other blade-tip variants of the family.
    pub family: bool,
    /// Whether to try the full solve next to the restricted one.
    pub solvers: bool,
    /// Whether to try continuum fibres and take them as the reference of the noise and
    /// transfer function (the richest finite variant stays the modes' reference).
    pub continuum: bool,
}

impl Default for Ladder {
    fn default() -> Self {
        Ladder {
            stages: Stage::ALL.to_vec(),
            beads: DEFAULT_BEADS.to_vec(),
            family: true,
            solvers: true,
            continuum: true,
        }
    }
}

/// How long each variant is timed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Stop repeating once this much time (s) is spent on a variant (the first run always
    /// completes).
    pub budget_s: f64,
    /// At most this many runs per variant.
    pub max_runs: usize,
}

impl Default for Timing {
    fn default() -> Self {
        Timing {
            budget_s: 0.5,
            max_runs: 5,
        }
    }
}

/// One variant of the suspension.
#[derive(Clone)]
pub struct Variant {
    /// The case (model and overrides).
    pub case: Case,
    /// Stage.
    pub stage: Stage,
    /// Violin beads per fibre, for models with `n_beads` (0 with continuum fibres).
    pub beads: Option<usize>,
    /// How responses are solved.
    pub solver: Solver,
    /// Whether the lowest wires are continua ([`crate::stage::Fibres::Continuum`]) in the
    /// noise and transfer function; static wires (and `beads`) otherwise.
    pub continuum: bool,
}

impl Variant {
    /// `<model> s<stage> [b<beads> | continuum] [full-solve]`, e.g.
    /// `quad-full s2 b40 full-solve`, `quad-aligo s2 continuum`.
    pub fn name(&self) -> String {
        let mut name = format!("{} s{}", self.case.model.name(), self.stage);
        if self.continuum {
            name += " continuum";
        } else if let Some(beads) = self.beads {
            name += &format!(" b{beads}");
        }
        if self.solver == Solver::Full {
            name += " full-solve";
        }
        name
    }

    fn key(&self) -> (&str, Stage, Option<usize>, bool, bool) {
        (
            self.case.model.name(),
            self.stage,
            self.beads,
            self.solver == Solver::Full,
            self.continuum,
        )
    }

    /// The case with this variant's beads.
    fn case(&self) -> Case {
        let mut case = self.case.clone();
        if let Some(beads) = self.beads {
            case.overrides
                .parameters
                .push(("n_beads".to_string(), beads.to_string()));
        }
        case
    }
}

/// A variant's answer to the question.
pub struct Answer {
    /// Variable names, the order of the mode vectors and of `mass`.
    pub coordinates: Vec<String>,
    /// Modes below the band's top times [`MODE_SEARCH_MARGIN`], ascending.
    pub modes: Vec<Mode>,
    /// Whether each mode is a violin mode (its largest motion in violin beads).
    pub violin: Vec<bool>,
    /// Mass matrix over the variables (kg, kg m, kg m²).
    pub mass: DMatrix<f64>,
    /// Noise ASD at the output over the grid (m/√Hz or rad/√Hz).
    pub noise_asd: Vec<f64>,
    /// Transfer function input → output over the grid, if asked.
    pub transfer: Option<Vec<c64>>,
}

impl Answer {
    /// Its mass matrix is square over its coordinates, as `function`'s argument `argument`
    /// needs (a hand-built answer may not be).
    fn check(&self, function: &str, argument: &str) -> Result<(), String> {
        let n = self.coordinates.len();
        if self.mass.shape() != (n, n) {
            return Err(format!(
                "{function}: {argument}.mass is {} x {}, its {n} coordinates need {n} x {n}",
                self.mass.nrows(),
                self.mass.ncols()
            ));
        }
        Ok(())
    }
}

/// Answers `question` with `variant`, from the model's name: build, equilibrium, stage,
/// modes below the top (stable ones only: an unstable variant is an error), noise and the
/// transfer function.
pub fn answer(variant: &Variant, question: &Question, grid: &[f64]) -> Result<Answer, Error> {
    if variant.stage == Stage::S0A {
        return Err(Error::StageTooEarly);
    }
    let (system, _) = variant.case().build()?;
    let options = RunOptions {
        modes: ModeSelection::Below(question.band_hz.1 * MODE_SEARCH_MARGIN),
        ..Default::default()
    };
    let fibres = if variant.continuum {
        Fibres::Continuum
    } else {
        Fibres::Static
    };
    let result = run_stage_with(system, variant.stage, &options, None)?.with_fibres(&fibres)?;
    result.stability()?;
    let noise = result.noise_with(
        &question.output,
        grid,
        &NoiseOptions {
            solver: variant.solver,
            per_term: false,
        },
    )?;
    let transfer = match &question.input {
        Some(input) => Some(result.transfer_with(input, &question.output, grid, variant.solver)?),
        None => None,
    };
    let violin = result
        .modes
        .modes
        .iter()
        .map(|m| result.mode_family(m) == "violin")
        .collect();
    let run = result.into_run();
    Ok(Answer {
        coordinates: run.modes.coordinates,
        modes: run.modes.modes,
        violin,
        mass: run.assembled.mass.to_dense(),
        noise_asd: noise.asd(),
        transfer,
    })
}

/// A variant's largest relative errors against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// Modes below the band's top: max |f − f_ref| / f_ref.
    pub modes: f64,
    /// Noise ASD over the band: max |ASD / ASD_ref − 1|.
    pub noise: f64,
    /// |transfer function| over the band: max ||H| / |H_ref| − 1|; `None` without an input.
    pub transfer: Option<f64>,
}

impl Errors {
    /// Zero errors (the reference against itself).
    pub fn zero(with_transfer: bool) -> Errors {
        Errors {
            modes: 0.0,
            noise: 0.0,
            transfer: with_transfer.then_some(0.0),
        }
    }

    /// The largest of the three: the variant's error.
    pub fn max(&self) -> f64 {
        self.modes.max(self.noise).max(self.transfer.unwrap_or(0.0))
    }
}

/// Matches each reference mode below `top_hz` to a mode of the variant, and returns for
/// each (reference index, variant index, overlap).
///
/// Variants have different coordinates (beads, blade tips), so shapes are compared on the
/// coordinates both have, in the reference's mass metric restricted to them: overlap
/// |rᵀ M v| / sqrt(rᵀ M r · vᵀ M v), 1 for the same shape, 0 for shapes that share no
/// kinetic energy; this tells the in-phase and anti-phase combinations of the same
/// coordinates apart (kinetic-energy fractions alone would not). Pairs are taken in order
/// of decreasing overlap, ties (degenerate shapes) by the nearer frequency, each mode at
/// most once. A reference mode left without a partner (the variant has fewer modes below
/// its search limit) is an error naming it.
pub fn match_modes(
    reference: &Answer,
    variant: &Answer,
    top_hz: f64,
) -> Result<Vec<(usize, usize, f64)>, String> {
    reference.check("match_modes", "reference")?;
    // shared coordinates: (index in reference, index in variant)
    let shared: Vec<(usize, usize)> = reference
        .coordinates
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            variant
                .coordinates
                .iter()
                .position(|c| c == name)
                .map(|j| (i, j))
        })
        .collect();
    let mass = DMatrix::from_fn(shared.len(), shared.len(), |a, b| {
        reference.mass[(shared[a].0, shared[b].0)]
    });
    let restrict = |mode: &Mode, pick: fn(&(usize, usize)) -> usize| {
        nalgebra::DVector::from_iterator(
            shared.len(),
            shared
                .iter()
                .map(|s| mode.vector.get(pick(s)).copied().unwrap_or(0.0)),
        )
    };
    let wanted: Vec<usize> = (0..reference.modes.len())
        .filter(|&i| reference.modes[i].hz < top_hz)
        .collect();
    let refs: Vec<_> = wanted
        .iter()
        .map(|&i| restrict(&reference.modes[i], |s| s.0))
        .collect();
    let vars: Vec<_> = variant.modes.iter().map(|m| restrict(m, |s| s.1)).collect();
    let norm = |v: &nalgebra::DVector<f64>| v.dot(&(&mass * v)).abs().sqrt();
    let mut pairs = Vec::with_capacity(refs.len() * vars.len());
    for (a, r) in refs.iter().enumerate() {
        let mr = &mass * r;
        let nr = norm(r);
        for (j, v) in vars.iter().enumerate() {
            let scale = nr * norm(v);
            let overlap = if scale > 0.0 {
                mr.dot(v).abs() / scale
            } else {
                0.0
            };
            let gap = (variant.modes[j].hz - reference.modes[wanted[a]].hz).abs();
            pairs.push((a, j, overlap, gap));
        }
    }
    // overlaps equal to 1e-9 count as ties, decided by frequency
    let rounded = |x: f64| (x * 1e9).round();
    pairs.sort_by(|p, q| {
        rounded(q.2)
            .total_cmp(&rounded(p.2))
            .then(p.3.total_cmp(&q.3))
    });
    let mut partner: Vec<Option<(usize, f64)>> = vec![None; wanted.len()];
    let mut taken = vec![false; vars.len()];
    for (a, j, overlap, _) in pairs {
        if partner[a].is_none() && !taken[j] {
            partner[a] = Some((j, overlap));
            taken[j] = true;
        }
    }
    wanted
        .iter()
        .zip(partner)
        .map(|(&i, p)| match p {
            Some((j, overlap)) => Ok((i, j, overlap)),
            None => {
                let m = &reference.modes[i];
                Err(format!(
                    "reference mode {} ({}, {:.6} Hz) has no counterpart among the variant's {} modes",
                    i + 1,
                    m.label,
                    m.hz,
                    variant.modes.len()
                ))
            }
        })
        .collect()
}

/// The errors of `variant`'s answer against the reference's (see the module's doc); an
/// error message when they cannot be measured (a missing mode, a curve that is not
/// finite, curves over different numbers of points, a mass matrix that does not fit the
/// coordinates).
pub fn compare(reference: &Answer, variant: &Answer, top_hz: f64) -> Result<Errors, String> {
    compare_with(reference, reference, variant, top_hz)
}

/// [`compare`] with the modes measured against `modes_reference` and the noise and
/// transfer function against `reference` (a continuum model, whose modes are its static
/// model's: see the module's doc).
pub fn compare_with(
    modes_reference: &Answer,
    reference: &Answer,
    variant: &Answer,
    top_hz: f64,
) -> Result<Errors, String> {
    let same_length = |what: &str, r: usize, v: usize| {
        if r == v {
            Ok(())
        } else {
            Err(format!(
                "compare: variant.{what} has {v} points, the reference's has {r}"
            ))
        }
    };
    same_length(
        "noise_asd",
        reference.noise_asd.len(),
        variant.noise_asd.len(),
    )?;
    if let (Some(r), Some(v)) = (&reference.transfer, &variant.transfer) {
        same_length("transfer", r.len(), v.len())?;
    }
    let mut modes: f64 = 0.0;
    for (i, j, _) in match_modes(modes_reference, variant, top_hz)? {
        let f_ref = modes_reference.modes[i].hz;
        modes = modes.max((variant.modes[j].hz - f_ref).abs() / f_ref.abs());
    }
    let noise = max_ratio_error(&reference.noise_asd, &variant.noise_asd, "noise ASD")?;
    let transfer = match (&reference.transfer, &variant.transfer) {
        (Some(r), Some(v)) => {
            let (r, v): (Vec<f64>, Vec<f64>) = (
                r.iter().map(|h| h.norm()).collect(),
                v.iter().map(|h| h.norm()).collect(),
            );
            Some(max_ratio_error(&r, &v, "|transfer function|")?)
        }
        _ => None,
    };
    if !modes.is_finite() {
        return Err(format!("mode frequency error {modes} is not finite"));
    }
    Ok(Errors {
        modes,
        noise,
        transfer,
    })
}

/// max |v / r − 1| over the points, or why it cannot be measured.
fn max_ratio_error(reference: &[f64], variant: &[f64], what: &str) -> Result<f64, String> {
    let mut worst: f64 = 0.0;
    for (k, (r, v)) in reference.iter().zip(variant).enumerate() {
        // equal values (a lossless model's zero noise too) differ by nothing
        let e = if v == r { 0.0 } else { (v / r - 1.0).abs() };
        if !e.is_finite() {
            return Err(format!(
                "{what} at point {}: {v} against the reference's {r}",
                k + 1
            ));
        }
        worst = worst.max(e);
    }
    Ok(worst)
}

/// One measured variant.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Variant name ([`Variant::name`]).
    pub variant: String,
    /// Time to answer (s): minimum over `runs`.
    pub seconds: f64,
    /// Runs timed.
    pub runs: usize,
    /// Errors against the reference.
    pub errors: Errors,
    /// The numbers (from 1, ascending frequency) of the variant's modes below the search
    /// limit that are neutral directions (ω² zero within its rounding: nothing in that
    /// variant resists them), whose errors above are those of a mode at 0 Hz.
    pub neutral_modes: Vec<usize>,
}

/// The numbers (from 1) of `answer`'s neutral modes.
fn neutral_modes(answer: &Answer) -> Vec<usize> {
    answer
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.omega_squared == 0.0)
        .map(|(i, _)| i + 1)
        .collect()
}

/// A variant that could not answer, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// Variant name.
    pub variant: String,
    /// Why (one line).
    pub reason: String,
}

/// The measured ladder.
#[derive(Clone, Debug, PartialEq)]
pub struct Tradeoff {
    /// The rows, the reference first (zero noise and transfer-function errors), then the
    /// ladder's order.
    pub rows: Vec<Row>,
    /// The variant the modes are measured against when it is not the reference (a
    /// continuum reference's modes are its static model's: see the module's doc).
    pub modes_reference: Option<String>,
    /// Variants that could not answer.
    pub skipped: Vec<Skipped>,
    /// Whether the question has a transfer function.
    pub with_transfer: bool,
}

impl Tradeoff {
    /// The reference row.
    pub fn reference(&self) -> Option<&Row> {
        self.rows.first()
    }

    /// The fastest row whose error ([`Errors::max`]) is at most `tolerance` (the reference
    /// always is).
    pub fn cheapest_within(&self, tolerance: f64) -> Option<&Row> {
        self.rows
            .iter()
            .filter(|r| r.errors.max() <= tolerance)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
    }

    /// `variant,seconds,modes_max_rel_err,noise_max_rel_err,tf_max_rel_err`, one line per
    /// row; the transfer-function field is empty when the question has no input.
    pub fn to_csv(&self) -> String {
        let mut out =
            String::from("variant,seconds,modes_max_rel_err,noise_max_rel_err,tf_max_rel_err\n");
        for r in &self.rows {
            let tf = r
                .errors
                .transfer
                .map(|e| format!("{e:e}"))
                .unwrap_or_default();
            out += &format!(
                "{},{:e},{:e},{:e},{tf}\n",
                r.variant, r.seconds, r.errors.modes, r.errors.noise
            );
        }
        out
    }
}

/// The variants of `case`'s ladder: the reference first, then the others (see the module's
/// doc), without repeats. With continuum fibres the reference is the continuum one and the
/// second the richest finite variant, the modes' reference.
pub fn ladder(case: &Case, ladder: &Ladder) -> Result<Vec<Variant>, Error> {
    let has_beads = pendkit_model::Defaults::of(&*case.model)?
        .params
        .get("n_beads")
        .is_some();
    let base_beads = if has_beads {
        let (_, resolved) = case.build()?;
        // a whole number by the model's own check (0–200)
        let beads = resolved
            .get("n_beads")
            .map_err(|e| Error::Build(BuildError::from(e)))?;
        Some(beads.round() as usize)
    } else {
        None
    };
    let base = Variant {
        case: case.clone(),
        stage: Stage::S2,
        beads: base_beads,
        solver: Solver::Restricted,
        continuum: false,
    };
    let family = if ladder.family {
        family_of(case)
    } else {
        vec![case.clone()]
    };
    let richest = family.last().cloned().unwrap_or_else(|| case.clone());
    let finite_reference = Variant {
        case: richest,
        stage: ladder.stages.iter().copied().max().unwrap_or(Stage::S2),
        beads: base_beads.map(|b| ladder.beads.iter().copied().max().unwrap_or(b)),
        solver: if ladder.solvers {
            Solver::Full
        } else {
            Solver::Restricted
        },
        continuum: false,
    };
    // continuum fibres carry no beads (the beads would be their mass a second time)
    let continuum_of = |v: &Variant| Variant {
        beads: v.beads.map(|_| 0),
        continuum: true,
        stage: Stage::S2,
        ..v.clone()
    };
    let mut variants = Vec::new();
    if ladder.continuum {
        variants.push(continuum_of(&finite_reference));
    }
    variants.push(finite_reference);
    let mut push = |v: Variant| {
        if !variants.iter().any(|w| w.key() == v.key()) {
            variants.push(v);
        }
    };
    for &stage in &ladder.stages {
        push(Variant {
            stage,
            ..base.clone()
        });
    }
    // every blade-tip variant with every bead count: the two refinements that matter
    // together (blade tips move the pitch modes, beads the fibres' mass)
    for member in family {
        let beads: Vec<Option<usize>> = if has_beads {
            ladder.beads.iter().map(|&b| Some(b)).collect()
        } else {
            vec![base.beads]
        };
        for beads in beads {
            push(Variant {
                case: member.clone(),
                beads,
                ..base.clone()
            });
        }
        if ladder.continuum {
            push(continuum_of(&Variant {
                case: member.clone(),
                ..base.clone()
            }));
        }
    }
    if ladder.solvers {
        push(Variant {
            solver: Solver::Full,
            ..base.clone()
        });
    }
    Ok(variants)
}

/// The blade-tip variants of `case`'s model that are bundled, poorest first, each with the
/// case's overrides; just the case if its model has none.
fn family_of(case: &Case) -> Vec<Case> {
    let name = case.model.name();
    let stem = FAMILY_SUFFIXES
        .iter()
        .chain([&BEADED_SUFFIX])
        .filter(|s| !s.is_empty())
        .find_map(|s| name.strip_suffix(s))
        .unwrap_or(name);
    let members: Vec<Case> = FAMILY_SUFFIXES
        .iter()
        .filter_map(|suffix| find_model(&format!("{stem}{suffix}")).ok())
        .map(|model| Case {
            name: model.name().to_string(),
            model,
            ..case.clone()
        })
        .collect();
    if members.iter().any(|m| m.model.name() == name) || name.ends_with(BEADED_SUFFIX) {
        members
    } else {
        vec![case.clone()]
    }
}

/// `answer` without its violin modes: the modes a continuum model's are measured on (its
/// violin modes are roots of its frequency-dependent problem, not modes of its static
/// model).
fn without_violins(answer: &Answer) -> Answer {
    Answer {
        coordinates: answer.coordinates.clone(),
        modes: answer
            .modes
            .iter()
            .zip(&answer.violin)
            .filter(|(_, violin)| !**violin)
            .map(|(m, _)| m.clone())
            .collect(),
        violin: Vec::new(),
        mass: answer.mass.clone(),
        noise_asd: answer.noise_asd.clone(),
        transfer: answer.transfer.clone(),
    }
}

/// Times `variant`'s answer as [`Timing`] says: (answer of the first run, minimum time in
/// s, runs).
fn timed_answer(
    variant: &Variant,
    question: &Question,
    grid: &[f64],
    timing: &Timing,
) -> Result<(Answer, f64, usize), Error> {
    let started = Instant::now();
    let mut best = f64::INFINITY;
    let mut first = None;
    let mut runs = 0;
    while runs == 0 || (runs < timing.max_runs && started.elapsed().as_secs_f64() < timing.budget_s)
    {
        let t = Instant::now();
        let answer = answer(variant, question, grid)?;
        best = best.min(t.elapsed().as_secs_f64());
        runs += 1;
        first.get_or_insert(answer);
    }
    match first {
        Some(answer) => Ok((answer, best, runs)),
        None => Err(Error::ZeroRepeat),
    }
}

/// Builds `case`'s ladder, answers `question` with every variant and measures each against
/// the reference (the first variant). The reference must answer; any other variant that
/// cannot is listed in [`Tradeoff::skipped`] with the reason. `progress` is told each
/// variant's name before it runs.
pub fn tradeoff(
    case: &Case,
    question: &Question,
    ladder_spec: &Ladder,
    timing: &Timing,
    mut progress: impl FnMut(&str),
) -> Result<Tradeoff, Error> {
    let grid = question.grid()?;
    let variants = ladder(case, ladder_spec)?;
    let mut rows = Vec::with_capacity(variants.len());
    let mut skipped = Vec::new();
    let top = question.band_hz.1;
    let mut measure = |variant: &Variant| {
        let name = variant.name();
        progress(&name);
        timed_answer(variant, question, &grid, timing).map(|(a, s, n)| (name, a, s, n))
    };
    let as_reference = |variant: &Variant, e: Error| Error::Reference {
        variant: variant.name(),
        message: e.to_string(),
    };
    // the references: the continuum one (when the ladder has it and it can answer) for the
    // responses, the richest finite one for the modes (and for everything without the
    // continuum)
    let (continuum, rest) = match variants.split_first() {
        Some((first, rest)) if first.continuum => (Some(first), rest),
        _ => (None, &variants[..]),
    };
    let Some((finite, others)) = rest.split_first() else {
        return Err(Error::Reference {
            variant: case.name.clone(),
            message: "the ladder has no variant".into(),
        });
    };
    let continuum_answer = match continuum.map(|v| (v, measure(v))) {
        Some((_, Ok(answer))) => Some(answer),
        Some((v, Err(e))) => {
            skipped.push(Skipped {
                variant: v.name(),
                reason: e.to_string(),
            });
            None
        }
        None => None,
    };
    let (finite_name, finite_answer, finite_seconds, finite_runs) =
        measure(finite).map_err(|e| as_reference(finite, e))?;
    let reference = continuum_answer.as_ref().map_or(&finite_answer, |c| &c.1);
    let finite_without_violins = without_violins(&finite_answer);
    let row = |variant: &Variant, name: String, answer: &Answer, seconds: f64, runs: usize| {
        let modes_reference = if variant.continuum {
            &finite_without_violins
        } else {
            &finite_answer
        };
        let errors = compare_with(modes_reference, reference, answer, top).map_err(|message| {
            Error::Reference {
                variant: name.clone(),
                message,
            }
        })?;
        Ok::<Row, Error>(Row {
            variant: name,
            seconds,
            runs,
            errors,
            neutral_modes: neutral_modes(answer),
        })
    };
    if let (Some(variant), Some((name, answer, seconds, runs))) = (continuum, &continuum_answer) {
        rows.push(row(variant, name.clone(), answer, *seconds, *runs)?);
    }
    rows.push(row(
        finite,
        finite_name.clone(),
        &finite_answer,
        finite_seconds,
        finite_runs,
    )?);
    for variant in others {
        match measure(variant).map_err(|e| e.to_string()).and_then(
            |(name, answer, seconds, runs)| {
                row(variant, name, &answer, seconds, runs).map_err(|e| e.to_string())
            },
        ) {
            Ok(r) => rows.push(r),
            Err(reason) => skipped.push(Skipped {
                variant: variant.name(),
                reason,
            }),
        }
    }
    Ok(Tradeoff {
        rows,
        modes_reference: continuum_answer.is_some().then_some(finite_name),
        skipped,
        with_transfer: question.input.is_some(),
    })
}
