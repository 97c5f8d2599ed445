//! The `pendkit` command line: one module per subcommand, each with its arguments and a
//! `run` that returns what the command prints (docs/cli.md is the contract). The program
//! is [`main`], public so that a binary of your own with extra element kinds linked in is
//! the whole command line in a few lines (docs/elements.md, "Reaching the tools"):
//!
//! ```no_run
//! // use my_kinds as _; // links the kinds: they register themselves
//! fn main() -> std::process::ExitCode {
//!     pendkit_cli::main()
//! }
//! ```

mod bench;
mod common;
mod error;
mod fit;
mod format;
mod modes;
mod noise;
mod output;
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
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pendkit::energy::registrations;

use crate::error::CliError;
use crate::output::Output;

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

// Deferred: clap builds the arguments of the one subcommand given, not of all sixteen (a
// third of the instructions of `pendkit --version`). A deferred subcommand's arguments are
// added after its description, so an arguments struct's doc comment would replace the
// description in its `--help`: those structs carry plain comments instead.
#[derive(Subcommand)]
#[command(defer = true)]
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
    /// List the registered element kinds, the stage each joins at, the crate that
    /// registered it and the fields of an instance; with a KIND, that kind's schema (units,
    /// domains, defaults) and a suspension-file snippet to copy.
    Elements(ElementsArgs),
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

// `pendkit elements [KIND]` (a plain comment: see `Command`).
#[derive(clap::Args, Debug)]
struct ElementsArgs {
    /// A registered kind: print its instance schema and a `[[element]]` snippet.
    kind: Option<String>,
}

/// The registered kinds, or one kind's schema with a snippet to copy.
fn elements(args: ElementsArgs) -> Result<String, CliError> {
    let mut out = String::new();
    let Some(name) = args.kind else {
        let _ = writeln!(
            out,
            "{:<20} {:<5} {:<32} {:<14} what",
            "kind", "stage", "crate", "fields"
        );
        for r in registrations() {
            let kind = r.element;
            let fields = kind.instance_schema().map_or("-".to_string(), |s| {
                s.values
                    .iter()
                    .map(|f| f.name)
                    .collect::<Vec<_>>()
                    .join(",")
            });
            let _ = writeln!(
                out,
                "{:<20} {:<5} {:<32} {:<14} {}",
                kind.kind(),
                kind.stage().name(),
                r.crate_name,
                fields,
                kind.summary()
            );
        }
        return Ok(out);
    };
    let Some(r) = registrations().iter().find(|r| r.element.kind() == name) else {
        let known: Vec<&str> = registrations().iter().map(|r| r.element.kind()).collect();
        return Err(CliError::Usage(format!(
            "unknown element kind '{name}' (registered: {})",
            known.join(", ")
        )));
    };
    let kind = r.element;
    let _ = writeln!(out, "{}: {}", kind.kind(), kind.summary());
    let _ = writeln!(
        out,
        "stage {}, registered by crate {}",
        kind.stage().name(),
        r.crate_name
    );
    let Some(schema) = kind.instance_schema() else {
        let _ = writeln!(
            out,
            "owns no instances: it acts on every wire of a stage (a suspension file moves it or switches it off in [elements])"
        );
        return Ok(out);
    };
    let points = if schema.points == 0 {
        "and reads no points".to_string()
    } else {
        format!(
            "with {} points (m, each in its body's coordinates)",
            schema.points
        )
    };
    let _ = writeln!(
        out,
        "an instance connects {} bodies, {points}",
        schema.bodies
    );
    let _ = writeln!(
        out,
        "{:<12} {:<10} {:<10} {:<12} what",
        "value", "unit", "domain", "default"
    );
    for f in schema.values {
        let default = f
            .default
            .map_or("required".to_string(), pendkit::expr::number_text);
        let _ = writeln!(
            out,
            "{:<12} {:<10} {:<10} {:<12} {}",
            f.name,
            f.unit,
            f.domain.describe(),
            default,
            f.description
        );
    }
    let _ = writeln!(out, "\nin a suspension file:\n");
    snippet(&mut out, kind.kind(), &schema);
    Ok(out)
}

/// A `[[element]]` of `kind` to copy into a suspension file, its bodies, points and
/// parameters placeholders to rename.
fn snippet(out: &mut String, kind: &str, schema: &pendkit::energy::InstanceSchema) {
    let snake = kind.replace('-', "_");
    let _ = writeln!(out, "[[element]]");
    let _ = writeln!(out, "kind = \"{kind}\"");
    let _ = writeln!(out, "name = \"my_{snake}\"");
    let bodies: Vec<String> = (1..=schema.bodies)
        .map(|k| format!("\"body{k}\""))
        .collect();
    let _ = writeln!(out, "between = [{}]", bodies.join(", "));
    if schema.points > 0 {
        let points = vec!["[0, 0, 0]"; schema.points];
        let _ = writeln!(out, "points = [{}]", points.join(", "));
    }
    // a required value reads a parameter of its own (so --set and sensitivity reach it),
    // which the file must declare: the comment names each with its unit
    let mut declare = Vec::new();
    let values: Vec<String> = schema
        .values
        .iter()
        .map(|f| {
            let v = f.default.map_or_else(
                || {
                    let parameter = format!("{}_{snake}", f.name);
                    declare.push(format!("{parameter} ({})", f.unit));
                    format!("\"{parameter}\"")
                },
                pendkit::expr::number_text,
            );
            format!("{} = {v}", f.name)
        })
        .collect();
    let _ = write!(out, "values = {{ {} }}", values.join(", "));
    if declare.is_empty() {
        let _ = writeln!(out);
    } else {
        let _ = writeln!(out, "  # declare in [parameters]: {}", declare.join(", "));
    }
    let _ = writeln!(out, "tag = \"my_{snake}\"");
}

/// The `pendkit` program: parses the process's arguments, runs the command, prints its
/// output (or the error, one line on stderr) and returns the exit code. Every element kind
/// linked into the calling binary is available to it.
///
/// Once a command starts writing a file, SIGINT and SIGTERM remove the output files being
/// written (their temporary files) and exit with status 130: an interrupted command leaves
/// no half-written file (`output::clean_up_on_interrupt`).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let printed = match run(cli) {
        Ok(output) => output::print(output),
        // results whose verdict fails (a fit that does not explain its data): printed in
        // full, then the verdict as the error line
        Err(CliError::Unexplained { output, message }) => {
            output::print(Output::Text(output)).and(Err(CliError::Unexplained {
                output: String::new(),
                message,
            }))
        }
        Err(e) => Err(e),
    };
    match printed {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_status())
        }
    }
}

/// Runs one command and returns what it prints.
fn run(cli: Cli) -> Result<Output, CliError> {
    let text = match cli.command {
        // the one command whose output can be too large to build in memory first
        Command::Modes(a) => return modes::run(a),
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
        Command::Elements(a) => elements(a),
        Command::Models => {
            let mut out = String::new();
            for m in pendkit::catalogue::models() {
                let _ = writeln!(out, "{:<18} {}", m.name(), m.summary());
            }
            Ok(out)
        }
    };
    text.map(Output::Text)
}
