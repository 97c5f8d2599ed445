//! The `pendkit` command line (DESIGN.md §8).

use std::fmt::Write as _;
use std::io::Write as _;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pendkit::{Case, Error, run_stage};
use pendkit_dynamics::lab_motion;
use pendkit_energy::{Stage, registry};
use serde_json::json;

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
    Modes {
        /// Bundled model name or path to a case file (.toml).
        model: String,
        /// Calculation stage: 0a, 0b, 1a, 1b or 2.
        #[arg(long, default_value = "0a")]
        stage: Stage,
        /// Override a parameter: NAME=EXPR, scale(x) or increment(x) (repeatable).
        #[arg(long = "set", value_name = "NAME=EXPR")]
        sets: Vec<String>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Also print each mode's lab-frame body motions (table output).
        #[arg(long)]
        lab: bool,
        /// Print the modes even if the equilibrium is unstable (exit status stays 0).
        #[arg(long)]
        allow_unstable: bool,
    },
    /// List the registered element kinds and the stage each joins at.
    Elements,
    /// List the bundled models.
    Models,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Writes the output; a closed pipe (`pendkit ... | head`) is not an error.
fn emit(text: &str) {
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn run(cli: Cli) -> Result<(), Error> {
    let mut out = String::new();
    match cli.command {
        Command::Elements => {
            for kind in registry() {
                let _ = writeln!(
                    out,
                    "{:<16} stage {:<3} {}",
                    kind.kind(),
                    kind.stage(),
                    kind.summary()
                );
            }
        }
        Command::Models => {
            for m in pendkit::models() {
                let _ = writeln!(out, "{:<18} {}", m.name(), m.summary());
            }
        }
        Command::Modes {
            model,
            stage,
            sets,
            json,
            lab,
            allow_unstable,
        } => {
            let case = Case::open(&model)?.with_sets(&sets)?;
            let (system, _) = case.build()?;
            let result = run_stage(system, stage)?;
            let stable = result.modes.check_stable();
            if let (Err(e), false) = (&stable, allow_unstable) {
                return Err(Error::Dynamics(e.clone()));
            }
            out = if json {
                modes_json(&case, stage, &result)
            } else {
                modes_table(&case, stage, &result, lab)
            };
        }
    }
    emit(&out);
    Ok(())
}

fn modes_json(case: &Case, stage: Stage, r: &pendkit::StageResult) -> String {
    let x = &r.assembled.equilibrium.coords;
    let modes: Vec<_> = r
        .modes
        .modes
        .iter()
        .map(|m| {
            let lab: Vec<_> = lab_motion(&r.system, &r.assembled.layout, x, m)
                .into_iter()
                .map(|b| json!({"body": b.body, "translation": b.translation, "rotation": b.rotation}))
                .collect();
            json!({
                "hz": m.hz,
                "omega_squared": m.omega_squared,
                "stable": m.is_stable(),
                "label": m.label,
                "vector": m.vector,
                "energy_fractions": m.energy_fractions,
                "lab": lab,
            })
        })
        .collect();
    let equilibrium: serde_json::Map<String, serde_json::Value> = r
        .system
        .coords
        .iter()
        .zip(x)
        .map(|(c, v)| (c.name.clone(), json!(v)))
        .collect();
    let out = json!({
        "model": case.model.name(),
        "case": case.name,
        "stage": stage.name(),
        "coordinates": r.modes.coordinates,
        "equilibrium": equilibrium,
        "modes": modes,
    });
    serde_json::to_string_pretty(&out).unwrap_or_default() + "\n"
}

fn modes_table(case: &Case, stage: Stage, r: &pendkit::StageResult, lab: bool) -> String {
    let mut out = String::new();
    let eq = &r.assembled.equilibrium;
    let _ = writeln!(
        out,
        "{} ({}), stage {}: {} modes; equilibrium in {} Newton steps, residual {:.2e}",
        case.name,
        case.model.name(),
        stage,
        r.modes.modes.len(),
        eq.iterations,
        eq.max_residual
    );
    let _ = writeln!(
        out,
        "{:>4}  {:>14}  {:<10} kinetic energy",
        "mode", "frequency Hz", "label"
    );
    for (i, m) in r.modes.modes.iter().enumerate() {
        let mut shares: Vec<(usize, f64)> =
            m.energy_fractions.iter().copied().enumerate().collect();
        shares.sort_by(|a, b| b.1.total_cmp(&a.1));
        let top: Vec<String> = shares
            .iter()
            .take(3)
            .filter(|(_, f)| *f >= 0.01)
            .map(|(k, f)| format!("{} {:.0}%", r.modes.coordinates[*k], 100.0 * f))
            .collect();
        let flag = if m.is_stable() {
            ""
        } else {
            "  UNSTABLE (growth rate)"
        };
        let _ = writeln!(
            out,
            "{:>4}  {:>14.7}  {:<10} {}{}",
            i + 1,
            m.hz,
            m.label,
            top.join(", "),
            flag
        );
        if lab {
            for b in lab_motion(&r.system, &r.assembled.layout, &eq.coords, m) {
                let _ = writeln!(
                    out,
                    "        {:<10} x {:>10.3e} y {:>10.3e} z {:>10.3e}  yaw {:>10.3e} pitch {:>10.3e} roll {:>10.3e}",
                    b.body,
                    b.translation[0],
                    b.translation[1],
                    b.translation[2],
                    b.rotation[0],
                    b.rotation[1],
                    b.rotation[2]
                );
            }
        }
    }
    out
}
