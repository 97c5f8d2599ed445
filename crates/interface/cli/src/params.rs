//! `pendkit params`: every parameter of a model, case or suspension file, with its value,
//! unit, description and the parts that read it; `pendkit chain-file`, which writes an
//! N-stage chain suspension file; and `pendkit model-file`, which prints a bundled model's
//! file to start a new suspension from.

use std::fmt::Write as _;

use pendkit::Case;
use pendkit::describe::parameter_table;

use crate::error::CliError;
use crate::format::sci;

// Arguments of `pendkit params` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    /// Bundled model name, or path to a case file or a suspension file (.toml).
    model: String,
    /// Override a parameter first: NAME=EXPR, scale(x) or increment(x) (repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// Runs the command and returns what it prints: one row per parameter, then (indented) the
/// parts that read it.
pub fn run(a: Args) -> Result<String, CliError> {
    let case = Case::open(&a.model)?.with_sets(&a.sets)?;
    let rows = parameter_table(&case)?;
    if a.json {
        let value = serde_json::to_value(&rows).map_err(|e| CliError::usage(e.to_string()))?;
        return Ok(format!("{value:#}\n"));
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# {} ({}): {} parameters",
        case.name,
        case.model.name(),
        rows.len()
    );
    let _ = writeln!(
        out,
        "{:<24} {:>14} {:<10} description",
        "name", "value", "unit"
    );
    for r in &rows {
        let unit = if r.unit.is_empty() { "-" } else { &r.unit };
        let _ = writeln!(
            out,
            "{:<24} {} {:<10} {}",
            r.name,
            sci(r.value, 6, 14),
            unit,
            r.description
        );
        // an expression's definition, under its value
        if r.definition.trim().parse::<f64>().is_err() {
            let _ = writeln!(out, "    = {}", r.definition);
        }
        if !r.domain.is_empty() {
            let _ = writeln!(out, "    domain: {}", r.domain);
        }
        if !r.read_by.is_empty() {
            let _ = writeln!(out, "    read by: {}", r.read_by.join(", "));
        }
    }
    Ok(out)
}

// Arguments of `pendkit chain-file` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct ChainArgs {
    /// Number of stages (bodies), 1 to 10 000.
    stages: usize,
}

/// The text of an N-stage chain suspension file.
pub fn chain_file(a: ChainArgs) -> Result<String, CliError> {
    let max = pendkit::suspension::generate::MAX_GENERATED_STAGES;
    let written = pendkit::suspension::generate::chain(a.stages).map_err(|_| {
        CliError::usage(format!("chain-file: {} stages; give 1 to {max}", a.stages))
    })?;
    Ok(written.source.text.clone())
}

// Arguments of `pendkit model-file` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct ModelFileArgs {
    /// Bundled model name (`pendkit models` lists them), or a file a bundled model extends
    /// (`ligo-materials`).
    model: String,
}

/// The text of a bundled suspension file, as embedded in the program: saved beside a new
/// file, it reads as the bundled model does (its `extends` names bundled files, which are
/// found wherever the copy is).
pub fn model_file(a: ModelFileArgs) -> Result<String, CliError> {
    use pendkit::suspension::Library as _;
    pendkit::catalogue::bundled::Bundled
        .file(&a.model)
        .map(|file| file.text.to_string())
        .ok_or_else(|| {
            let known: Vec<&str> = pendkit::catalogue::bundled::files()
                .map(|(name, _, _)| name.trim_end_matches(".toml"))
                .collect();
            CliError::usage(format!(
                "model-file: no bundled file '{}' (bundled: {})",
                a.model,
                known.join(", ")
            ))
        })
}
