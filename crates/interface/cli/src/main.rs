//! The `pendkit` command line: one module per subcommand, each with its arguments and a
//! `run` that returns what the command prints (docs/cli.md is the contract).

mod bench;
mod common;
mod error;
mod fit;
mod format;
mod modes;
mod noise;
mod params;
mod plotting;
mod progress;
mod report;
mod sensitivity;
mod ss;
mod sweep;
mod tf;
mod tradeoff;

use std::fmt::Write as _;
use std::io::Write as _;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pendkit::energy::registrations;

use crate::error::CliError;

#[derive(Parser)]
#[command(
    name = "pendkit",
    version,
    about = "Multi-stage pendulum suspensions: equilibrium, modes and more"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Equilibrium and normal modes of a model or case file.
    Modes(modes::Args),
    /// Transfer function from a support displacement or a force to a displacement or a
    /// force on the support.
    Tf(tf::Args),
    /// Thermal noise (fluctuation-dissipation) at an output, with its breakdown by tag.
    Noise(noise::Args),
    /// State-space matrices A, B, C, D with names, to .mat, .npz or .json.
    Ss(ss::Args),
    /// A self-contained HTML report (DIR/index.html): parameters, equilibrium, stability,
    /// modes, standard transfer functions, thermal noise and timing, with inline figures.
    Report(report::Args),
    /// Modes (tracked by shape), thermal noise or a transfer function over a grid of
    /// parameter values, as CSV against the swept values.
    Sweep(sweep::Args),
    /// Derivatives of the mode frequencies (and of |TF| and thermal-noise ASD at given
    /// frequencies) with respect to every parameter: the largest relative sensitivities
    /// first, or JSON.
    Sensitivity(sensitivity::Args),
    /// Fit free parameters to measured mode frequencies (and |TF| points): fitted values
    /// with uncertainties, correlations, residuals, undetermined combinations, and the
    /// fitted case file.
    Fit(fit::Args),
    /// Time each phase of a calculation in this process (build, equilibrium, Hessians per
    /// element kind, mass matrix, modes, and optionally noise): median and minimum over
    /// repetitions.
    Bench(bench::Args),
    /// Speed against accuracy: a ladder of variants of one suspension (stages, violin
    /// beads, blade-tip variants, restricted or full solve), each timed from the model's
    /// name to the answer and measured against the richest; tradeoff.csv and tradeoff.svg,
    /// and the cheapest variant within a tolerance.
    Tradeoff(tradeoff::Args),
    /// List the registered element kinds, the stage each joins at and the crate that
    /// registered it.
    Elements,
    /// List the bundled models.
    Models,
    /// List every parameter of a model, case or suspension file: value, unit,
    /// description, and the parts that read it.
    Params(params::Args),
    /// Write an N-stage chain suspension file to standard output.
    ChainFile(params::ChainArgs),
    /// Print a bundled model's suspension file, to copy and edit into a new suspension.
    ModelFile(params::ModelFileArgs),
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(text) => {
            // a closed pipe (`pendkit ... | head`) is not an error
            let _ = std::io::stdout().lock().write_all(text.as_bytes());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs one command and returns what it prints.
fn run(cli: Cli) -> Result<String, CliError> {
    match cli.command {
        Command::Modes(a) => modes::run(a),
        Command::Tf(a) => tf::run(a),
        Command::Noise(a) => noise::run(a),
        Command::Ss(a) => ss::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Report(a) => report::run(a),
        Command::Sensitivity(a) => sensitivity::run(a),
        Command::Bench(a) => Ok(bench::run(a)?),
        Command::Fit(a) => fit::run(a),
        Command::Tradeoff(a) => tradeoff::run(a),
        Command::Params(a) => params::run(a),
        Command::ChainFile(a) => params::chain_file(a),
        Command::ModelFile(a) => params::model_file(a),
        Command::Elements => {
            let mut out = String::new();
            let _ = writeln!(out, "{:<20} {:<5} {:<32} what", "kind", "stage", "crate");
            for r in registrations() {
                let kind = r.element;
                let _ = writeln!(
                    out,
                    "{:<20} {:<5} {:<32} {}",
                    kind.kind(),
                    kind.stage().name(),
                    r.crate_name,
                    kind.summary()
                );
            }
            Ok(out)
        }
        Command::Models => {
            let mut out = String::new();
            for m in pendkit::catalogue::models() {
                let _ = writeln!(out, "{:<18} {}", m.name(), m.summary());
            }
            Ok(out)
        }
    }
}
