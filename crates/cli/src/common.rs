//! Arguments every calculation shares: the model or case, its stage and overrides, and the
//! frequency grid.

use pendkit::{Case, Error, ModeSelection, RunOptions, StageResult, run_stage_with};
use pendkit_dynamics::Solver;
use pendkit_energy::Stage;

/// The model or case, stage and parameter overrides every calculation takes.
#[derive(clap::Args)]
pub struct ModelArgs {
    /// Bundled model name or path to a case file (.toml).
    pub model: String,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2 (modes default to 0a, responses to 2).
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
}

impl ModelArgs {
    /// Builds the case and runs its stage (default `default`), computing the modes `modes`
    /// selects.
    pub fn run(
        &self,
        default: Stage,
        modes: ModeSelection,
    ) -> Result<(Case, Stage, StageResult), Error> {
        let case = Case::open(&self.model)?.with_sets(&self.sets)?;
        let stage = self.stage.unwrap_or(default);
        let (system, _) = case.build()?;
        let options = RunOptions {
            modes,
            ..Default::default()
        };
        Ok((case, stage, run_stage_with(system, stage, &options, None)?))
    }

    /// As [`ModelArgs::run`], for results that need losses (stage 0B or later) and answer
    /// with the linearised model: an unstable equilibrium is refused unless
    /// `--allow-unstable`.
    pub fn run_lossy(&self) -> Result<(Case, Stage, StageResult), Error> {
        if self.stage == Some(Stage::S0A) {
            return Err(Error::StageTooEarly);
        }
        let (case, stage, result) = self.run(Stage::S2, ModeSelection::All)?;
        self.stability_gate(&result)?;
        Ok((case, stage, result))
    }

    /// Refuses an unstable equilibrium, or with `--allow-unstable` warns on stderr.
    pub fn stability_gate(&self, result: &StageResult) -> Result<(), Error> {
        if let Some(warning) = result.require_stable(self.allow_unstable)? {
            eprintln!("warning: {warning}");
        }
        Ok(())
    }
}

/// A log-spaced frequency grid.
#[derive(clap::Args)]
pub struct GridArgs {
    /// First frequency (Hz).
    #[arg(long, default_value_t = 0.1)]
    pub from: f64,
    /// Last frequency (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub to: f64,
    /// Number of log-spaced points.
    #[arg(long, default_value_t = 200)]
    pub points: usize,
}

/// The solver `--full` asks for.
pub fn solver(full: bool) -> Solver {
    if full {
        Solver::Full
    } else {
        Solver::Restricted
    }
}
