//! `pendkit modes`: equilibrium and normal modes, as a table or JSON.

use std::fmt::Write as _;

use pendkit::{Case, Error, ModeSelection, StageResult};
use pendkit_dynamics::lab_motion;
use pendkit_energy::Stage;
use serde_json::json;

use crate::common::ModelArgs;

/// Arguments of `pendkit modes`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Also print each mode's lab-frame body motions (table output).
    #[arg(long)]
    lab: bool,
    /// Only the modes below this frequency (Hz); large models find them by shift-invert
    /// on a sparse factorisation instead of the dense eigensolver.
    #[arg(long, value_name = "HZ")]
    below: Option<f64>,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, Error> {
    let selection = a.below.map_or(ModeSelection::All, ModeSelection::Below);
    let (case, stage, result) = a.args.run(Stage::S0A, selection)?;
    a.args.stability_gate(&result)?;
    Ok(if a.json {
        modes_json(&case, stage, &result)
    } else {
        modes_table(&case, stage, &result, a.lab)
    })
}

fn modes_json(case: &Case, stage: Stage, r: &StageResult) -> String {
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
                "accuracy": finite_or_null(m.accuracy()),
                "vector_accuracy": m.vector_error,
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

/// A JSON number, or null for infinity (the relative accuracy of a neutral mode).
fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() { json!(x) } else { serde_json::Value::Null }
}

/// Relative accuracy worse than this is printed next to the frequency.
const PRINT_ACCURACY_ABOVE: f64 = 1e-6;

fn modes_table(case: &Case, stage: Stage, r: &StageResult, lab: bool) -> String {
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
        let mut flag = if m.is_stable() {
            String::new()
        } else {
            "  UNSTABLE (growth rate)".to_string()
        };
        if m.omega_squared == 0.0 {
            flag += &format!(
                "  neutral (|omega^2| below its error {:.1e} rad^2/s^2)",
                m.omega_squared_error
            );
        } else if m.accuracy() > PRINT_ACCURACY_ABOVE {
            flag += &format!("  (accuracy {:.1e} relative)", m.accuracy());
        }
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
