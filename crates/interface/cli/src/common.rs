//! Arguments every calculation shares: the model or case, its stage, overrides and naming
//! scheme, and the frequencies; and one run of a stage with what its output needs (case,
//! resolved parameters, phase times, names).

use std::path::PathBuf;

use pendkit::assembly::PhaseTimes;
use pendkit::dynamics::Solver;
use pendkit::params::Resolved;
use pendkit::stage::ModeSelection;
use pendkit::stage::Provenance;
use pendkit::stage::RunOptions;
use pendkit::stage::run_stage_with;
use pendkit::system::Stage;
use pendkit::{Case, Error, StageResult};

use crate::error::CliError;
use crate::progress::Progress;

/// The stage every command runs unless `--stage` says otherwise: stage 2, the complete
/// model (wire torsion, bending and extra stretch included), so that `modes`, `tf`,
/// `noise`, `ss`, `sweep` and `report` describe the same physics by default.
pub const DEFAULT_STAGE: Stage = Stage::S2;

// The model or case, stage, parameter overrides and names every calculation takes (a plain
// comment: see `Command` in lib.rs on why clap must not read it).
#[derive(clap::Args, Clone)]
pub struct ModelArgs {
    /// Bundled model name, or path to a case file or a suspension file (.toml).
    pub model: String,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2 (default 2, the complete model).
    #[arg(long)]
    pub stage: Option<Stage>,
    /// Override a parameter: NAME=EXPR, scale(x) or increment(x); or a damping field,
    /// damping.<tag>.<field>=EXPR (repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    pub sets: Vec<String>,
    /// Go on when the equilibrium is unstable (a warning on stderr instead of an error):
    /// unstable modes are listed with minus their growth rate; responses of an unstable
    /// plant are those of its linearisation.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Names in tables and exports: `model` (the model's own, default) or a scheme the
    /// model declares, e.g. `ligo` (L, T, V, R, P, Y; M0, L1, L2, L3; GND).
    #[arg(long, value_name = "SCHEME")]
    pub naming: Option<String>,
    /// How the wires move in `tf` and `noise`: `static` (massless, or violin beads where the
    /// model has them) or `continuum` (the lowest wires, a quad's fibres, and any the file
    /// marks `continuum = true`, by their exact dynamic stiffness, violin modes included:
    /// docs/continuum-fibres.md). Without it, as the model says: the sets its file marks
    /// `continuum = true` are continua, the rest static. The modes and the state space keep
    /// the static model.
    #[arg(long, value_name = "MODEL", value_parser = ["static", "continuum"])]
    pub fibres: Option<String>,
}

/// One run of a stage, with everything its output needs.
pub struct Run {
    /// The case run.
    pub case: Case,
    /// Its stage.
    pub stage: Stage,
    /// Its parameters as resolved.
    pub resolved: Resolved,
    /// Equilibrium, matrices and modes.
    pub result: StageResult,
    /// Time of each phase of the run.
    pub times: PhaseTimes,
    /// The naming scheme asked for (`None`: the model's own names).
    pub scheme: Option<String>,
}

impl Run {
    /// The display name of a coordinate (in the naming scheme asked for).
    pub fn coord(&self, name: &str) -> String {
        match &self.scheme {
            Some(s) => self
                .result
                .name_scheme(s)
                .map_or(name, |n| n.coord(name))
                .to_string(),
            None => name.to_string(),
        }
    }

    /// The display name of a body.
    pub fn body(&self, name: &str) -> String {
        match &self.scheme {
            Some(s) => self
                .result
                .name_scheme(s)
                .map_or(name, |n| n.body(name))
                .to_string(),
            None => name.to_string(),
        }
    }

    /// The display form of an input or output name: coordinates (also after `force:`) and
    /// bodies (before `@`) in the naming scheme.
    pub fn port(&self, name: &str) -> String {
        if let Some(rest) = name.strip_prefix("force:") {
            return format!("force:{}", self.port(rest));
        }
        if let Some((body, rest)) = name.split_once('@') {
            return format!("{}@{rest}", self.body(body));
        }
        self.coord(name)
    }

    /// Where the results come from.
    pub fn provenance(&self) -> Result<Provenance, Error> {
        self.case.provenance(&self.resolved)
    }

    /// `case (model), stage S`, the first words of every table.
    pub fn heading(&self) -> String {
        format!(
            "{} ({}), stage {}",
            self.case.name,
            self.case.model.name(),
            self.stage
        )
    }

    /// The stability gate, in one place for every command: an unstable equilibrium is
    /// refused with one line naming the growing mode, or with `allow_unstable` the same
    /// line goes to stderr as a warning and the command goes on.
    pub fn check_stable(&self, allow_unstable: bool) -> Result<(), CliError> {
        if let Some(warning) = self.result.require_stable(allow_unstable)? {
            eprintln!("warning: {warning}");
        }
        Ok(())
    }

    /// One line per neutral mode, for the engineer who has to remove it: which coordinates
    /// move in it, why it is neutral (nothing in the model resists it: its ω² is zero within
    /// the rounding of the stiffnesses), and what would give it stiffness, by the family of
    /// the direction (pitch and roll from wires that meet the body at its centre of mass in
    /// one vertical plane, yaw from wires on one line or without torsion).
    pub fn neutral_notes(&self) -> Vec<String> {
        let (run, r) = (self, &self.result);
        r.modes
            .modes
            .iter()
            .enumerate()
            .filter(|(_, m)| m.omega_squared == 0.0)
            .map(|(i, m)| {
                let family = r.mode_family(m);
                let remedy = match family.as_str() {
                    "P" | "R" => {
                        "give the wires a break-off distance (their lower ends above the centre of mass), attach them out of one vertical plane, or include wire bending (stage 1B or 2)"
                    }
                    "Y" => "separate the wires, or include wire torsion (stage 1A or later)",
                    _ => "add a wire, blade or spring that this motion stretches",
                };
                let zero = if m.omega_squared_error > 0.0 {
                    format!(
                        "stiffness zero within rounding, |omega^2| < {:.1e} rad^2/s^2",
                        m.omega_squared_error
                    )
                } else {
                    "stiffness exactly zero".to_string()
                };
                format!(
                    "note: mode {} is a neutral direction ({}): no wire, blade, spring or element of this stage resists it ({zero}); to remove it, {remedy}",
                    i + 1,
                    crate::modes::top_shares(run, &r.modes.coordinates, &m.energy_fractions)
                        .join(", "),
                )
            })
            .collect()
    }
}

impl ModelArgs {
    /// Builds the case and runs its stage, computing the modes `modes` selects; a spinner
    /// shows on a terminal while it takes more than a second.
    pub fn run(&self, modes: ModeSelection) -> Result<Run, CliError> {
        self.run_with(modes, &self.sets, true)
    }

    /// As [`ModelArgs::run`] with these overrides instead of `--set`'s (a sweep's), and a
    /// spinner only if `spinner` (a sweep shows its own bar).
    pub fn run_with(
        &self,
        modes: ModeSelection,
        sets: &[String],
        spinner: bool,
    ) -> Result<Run, CliError> {
        let case = Case::open(&self.model)?.with_sets(sets)?;
        let stage = self.stage.unwrap_or(DEFAULT_STAGE);
        let _progress = spinner.then(|| Progress::spinner(format!("{}: stage {stage}", case.name)));
        let mut times = PhaseTimes::new();
        let (system, resolved) = times.time("build", 1, || case.build())?;
        let options = RunOptions {
            modes,
            ..Default::default()
        };
        let mut result = run_stage_with(system, stage, &options, Some(&mut times))?;
        match self.fibres.as_deref() {
            Some("continuum") => result = result.with_fibres(&pendkit::stage::Fibres::Continuum)?,
            Some("static") => result = result.with_fibres(&pendkit::stage::Fibres::Static)?,
            // as the model says (a file's `continuum = true`), which the run has done
            _ => {}
        }
        let scheme = match self.naming.as_deref() {
            None | Some("model") => None,
            Some(s) => {
                result.name_scheme(s)?;
                Some(s.to_string())
            }
        };
        Ok(Run {
            case,
            stage,
            resolved,
            result,
            times,
            scheme,
        })
    }

    /// As [`ModelArgs::run`], for results that need losses (stage 0B or later) and answer
    /// with the linearised model: an unstable equilibrium is refused unless
    /// `--allow-unstable`.
    pub fn run_lossy(&self) -> Result<Run, CliError> {
        if self.stage == Some(Stage::S0A) {
            return Err(Error::StageTooEarly.into());
        }
        let run = self.run(ModeSelection::All)?;
        run.check_stable(self.allow_unstable)?;
        // a response of a model with a neutral direction is a number with a caveat: the
        // same notes as `modes` prints, on stderr beside the result
        for note in run.neutral_notes() {
            eprintln!("{note}");
        }
        Ok(run)
    }
}

// The frequencies of a response: a log-spaced grid, or a list given explicitly (a plain
// comment: see `Command` in lib.rs).
#[derive(clap::Args, Clone)]
pub struct GridArgs {
    /// First frequency of the log-spaced grid (Hz).
    #[arg(long, default_value_t = 0.1, value_parser = number, allow_hyphen_values = true)]
    pub from: f64,
    /// Last frequency of the log-spaced grid (Hz).
    #[arg(long, default_value_t = 100.0, value_parser = number, allow_hyphen_values = true)]
    pub to: f64,
    /// Number of log-spaced points.
    #[arg(long, default_value_t = 200)]
    pub points: usize,
    /// Explicit frequencies (Hz), comma-separated, e.g. 1,10,100 (instead of the grid).
    #[arg(long, value_name = "HZ,...", allow_hyphen_values = true, conflicts_with_all = ["from", "to", "points", "freqs_file"])]
    pub freqs: Option<String>,
    /// A file of frequencies (Hz), separated by commas, spaces or new lines; `#` starts a
    /// comment (instead of the grid).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["from", "to", "points"])]
    pub freqs_file: Option<PathBuf>,
}

impl Default for GridArgs {
    fn default() -> Self {
        GridArgs {
            from: 0.1,
            to: 100.0,
            points: 200,
            freqs: None,
            freqs_file: None,
        }
    }
}

/// A number typed on the command line (the value parser of every numeric option, and of the
/// numbers inside text options): refuses `nan`, `inf`, and a literal an `f64` cannot hold
/// (`1e400`, or `1e-400`, which would read as 0).
pub fn number(text: &str) -> Result<f64, String> {
    pendkit::expr::number_literal(text).map_err(|e| e.to_string())
}

/// A frequency from text: finite and positive, or a one-line error naming `place`.
fn frequency(text: &str, place: &str) -> Result<f64, CliError> {
    match number(text) {
        Ok(f) if f > 0.0 => Ok(f),
        // as typed: `{}` of an f64 writes -1e-300 as 300 decimals
        Ok(_) => Err(CliError::usage(format!(
            "{place}: frequency {} Hz must be positive",
            text.trim()
        ))),
        Err(e) => Err(CliError::usage(format!("{place}: {e} (Hz)"))),
    }
}

impl GridArgs {
    /// The frequencies (Hz), each finite and positive, at most
    /// [`pendkit_limits::FREQUENCY_POINTS`] of them (counted before they are read).
    pub fn frequencies(&self) -> Result<Vec<f64>, CliError> {
        let too_many = |what: String| move |source| CliError::Limit { what, source };
        if let Some(list) = &self.freqs {
            pendkit_limits::FREQUENCY_POINTS
                .check(list.split(',').count())
                .map_err(too_many("--freqs".into()))?;
            let freqs = list
                .split(',')
                .map(|t| frequency(t, "--freqs"))
                .collect::<Result<Vec<f64>, _>>()?;
            return Ok(freqs);
        }
        if let Some(path) = &self.freqs_file {
            let text = pendkit_limits::read_text(path).map_err(|source| CliError::Input {
                path: path.clone(),
                source,
            })?;
            let mut freqs = Vec::new();
            for (n, line) in text.lines().enumerate() {
                let data = line.split('#').next().unwrap_or_default();
                for item in data
                    .split([',', ' ', '\t'])
                    .filter(|t| !t.trim().is_empty())
                {
                    let place = format!("--freqs-file {} line {}", path.display(), n + 1);
                    freqs.push(frequency(item, &place)?);
                }
                // checked as the list grows: a file within the size limit may still hold
                // millions of numbers
                pendkit_limits::FREQUENCY_POINTS
                    .check(freqs.len())
                    .map_err(too_many(format!("--freqs-file {}", path.display())))?;
            }
            if freqs.is_empty() {
                return Err(CliError::usage(format!(
                    "--freqs-file {}: no frequencies in the file",
                    path.display()
                )));
            }
            return Ok(freqs);
        }
        for (name, value) in [("--from", self.from), ("--to", self.to)] {
            if !value.is_finite() {
                return Err(CliError::usage(format!(
                    "{name} {value}: frequency must be finite and positive"
                )));
            }
        }
        pendkit_limits::FREQUENCY_POINTS
            .check(self.points)
            .map_err(too_many("--points".into()))?;
        Ok(pendkit::log_grid(self.from, self.to, self.points)?)
    }
}

/// The solver `--full` asks for.
pub fn solver(full: bool) -> Solver {
    if full {
        Solver::Full
    } else {
        Solver::Restricted
    }
}

/// Adds the extension's format check of `--plot FILE` before any work is done.
pub fn check_plot_path(path: &Option<PathBuf>) -> Result<(), CliError> {
    if let Some(path) = path {
        pendkit_plot::Format::from_path(path)?;
    }
    Ok(())
}

/// Splits `IN:OUT` at the one colon that is not a `force:` prefix.
pub fn split_pair(text: &str) -> Result<(String, String), CliError> {
    let separators: Vec<usize> = text
        .match_indices(':')
        .map(|(i, _)| i)
        .filter(|&i| {
            let before = &text[..i];
            let prefix = before.ends_with("force") && (i == 5 || before[..i - 5].ends_with(':'));
            !prefix
        })
        .collect();
    match separators.as_slice() {
        [i] if *i > 0 && *i + 1 < text.len() => {
            Ok((text[..*i].to_string(), text[i + 1..].to_string()))
        }
        _ => Err(CliError::usage(format!(
            "--tf '{text}': expected INPUT:OUTPUT, e.g. x00:x3 or force:x3:x3"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_split_at_the_colon_that_is_not_a_force_prefix() {
        let pair = |t: &str| split_pair(t).unwrap();
        assert_eq!(pair("x00:x3"), ("x00".into(), "x3".into()));
        assert_eq!(pair("force:x3:x3"), ("force:x3".into(), "x3".into()));
        assert_eq!(pair("x00:force:x00"), ("x00".into(), "force:x00".into()));
        assert_eq!(
            pair("force:x1:force:x00"),
            ("force:x1".into(), "force:x00".into())
        );
        for bad in ["x00", "x00:x3:x2", ":x3", "force:x3"] {
            assert!(split_pair(bad).is_err(), "{bad}");
        }
    }
}
