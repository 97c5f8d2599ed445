//! `pendkit sensitivity`: derivatives of the mode frequencies, and of |TF| and the
//! thermal-noise ASD at given frequencies, with respect to the parameters, as a table (the
//! largest relative sensitivities first) or JSON.

use std::fmt::Write as _;

use pendkit::Case;
use pendkit::sensitivity::Sensitivities;
use pendkit::sensitivity::SensitivityRequest;
use pendkit::sensitivity::sensitivities;
use pendkit::system::Stage;
use serde_json::json;

use crate::common::{DEFAULT_STAGE, GridArgs};
use crate::error::CliError;
use crate::format::sci;

// Arguments of `pendkit sensitivity` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    /// Bundled model name, or path to a case file or a suspension file (.toml).
    model: String,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2 (default 2, the complete model).
    #[arg(long)]
    stage: Option<Stage>,
    /// Override a parameter: NAME=EXPR; or a damping field, damping.<tag>.<field>=EXPR
    /// (repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
    /// Go on when the equilibrium is unstable (a warning on stderr instead of an error).
    #[arg(long)]
    allow_unstable: bool,
    /// The mode frequencies' sensitivities (the default when neither --tf nor --noise is
    /// given).
    #[arg(long)]
    modes: bool,
    /// The sensitivities of |H| of a transfer function, INPUT:OUTPUT (names as `pendkit
    /// tf` takes them, e.g. x00:x3), at the frequencies.
    #[arg(long, value_name = "IN:OUT")]
    tf: Option<String>,
    /// The sensitivities of the thermal-noise ASD of a displacement output at the
    /// frequencies.
    #[arg(long, value_name = "OUT")]
    noise: Option<String>,
    #[command(flatten)]
    grid: GridArgs,
    /// Only these parameters, comma-separated (default: every parameter of the model).
    #[arg(long, value_name = "P1,P2,...")]
    parameters: Option<String>,
    /// Rows of the table (0: all).
    #[arg(long, default_value_t = 40)]
    top: usize,
    /// Threads that compute the parameters' columns (0: as many as the machine has); the
    /// results do not depend on it.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Difference the stage's matrices for every parameter, even where the exact route
    /// (dual numbers and the implicit function theorem) is open: a check, and a timing.
    #[arg(long)]
    differences: bool,
    /// Print JSON: {"parameters", "modes_hz", "dfdp", "exact_build", "exact"} (one row per
    /// mode, one column per parameter, Hz per unit; per parameter whether the model's
    /// numbers moved along their exact tangent, and whether its mode sensitivities are
    /// exact), with --tf also "freqs_hz", "tf_abs", "dtf_abs_dp", with
    /// --noise "freqs_hz", "noise_asd", "dnoise_asd_dp" (one row per frequency).
    #[arg(long)]
    json: bool,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    let case = Case::open(&a.model)?.with_sets(&a.sets)?;
    // at the colon that is not a `force:` prefix, as `sweep --tf` splits it
    let tf = a.tf.as_deref().map(crate::common::split_pair).transpose()?;
    let responses = tf.is_some() || a.noise.is_some();
    let freqs = if responses {
        a.grid.frequencies()?
    } else {
        // frequencies without a response to take them are a mistyped request, not nothing
        let grid = &a.grid;
        let default = GridArgs::default();
        if grid.freqs.is_some()
            || grid.freqs_file.is_some()
            || (grid.from, grid.to, grid.points) != (default.from, default.to, default.points)
        {
            return Err(CliError::usage(
                "frequencies (--freqs, --freqs-file, --from, --to, --points) are for --tf and \
                 --noise; the mode sensitivities take none",
            ));
        }
        Vec::new()
    };
    let parameters = match &a.parameters {
        Some(list) => {
            let names: Vec<String> = list.split(',').map(|p| p.trim().to_string()).collect();
            if list.trim().is_empty() {
                // the library's own message for an empty list
                Some(Vec::new())
            } else if names.iter().any(String::is_empty) {
                return Err(CliError::usage(format!(
                    "--parameters '{list}': an empty name between commas"
                )));
            } else {
                Some(names)
            }
        }
        None => None,
    };
    let request = SensitivityRequest {
        stage: a.stage.unwrap_or(DEFAULT_STAGE),
        modes: a.modes || !responses,
        tf,
        noise: a.noise.clone(),
        freqs,
        parameters,
        allow_unstable: a.allow_unstable,
        threads: a.threads,
        differences: a.differences,
    };
    let s = sensitivities(&case, &request)?;
    if let Some(warning) = &s.warning {
        eprintln!("warning: {warning}");
    }
    Ok(if a.json {
        to_json(&s, &request)
    } else {
        table(&case, &s, &request, a.top)
    })
}

fn to_json(s: &Sensitivities, request: &SensitivityRequest) -> String {
    let mut out = json!({
        "parameters": s.parameters,
        "modes_hz": s.modes_hz,
        "dfdp": s.dfdp,
        "exact_build": s.exact_build,
        "exact": s.exact,
    });
    if let Some((abs, d)) = &s.tf_abs {
        out["freqs_hz"] = json!(request.freqs);
        out["tf_abs"] = json!(abs);
        out["dtf_abs_dp"] = json!(d);
    }
    if let Some((asd, d)) = &s.noise_asd {
        out["freqs_hz"] = json!(request.freqs);
        out["noise_asd"] = json!(asd);
        out["dnoise_asd_dp"] = json!(d);
    }
    let mut text = out.to_string();
    text.push('\n');
    text
}

/// One row of a table: what is differentiated (a mode or a frequency), the parameter, the
/// derivative and the relative sensitivity (p/y · dy/dp).
struct Row {
    what: String,
    parameter: usize,
    derivative: f64,
    relative: f64,
}

/// Rows sorted by |relative sensitivity|, largest first, `top` of them (0: all).
fn sorted(mut rows: Vec<Row>, top: usize) -> Vec<Row> {
    rows.sort_by(|a, b| b.relative.abs().total_cmp(&a.relative.abs()));
    if top > 0 {
        rows.truncate(top);
    }
    rows
}

fn rows_of(
    s: &Sensitivities,
    values: &[f64],
    derivatives: &[Vec<f64>],
    what: impl Fn(usize) -> String,
) -> Vec<Row> {
    let mut rows = Vec::new();
    for (k, (y, row)) in values.iter().zip(derivatives).enumerate() {
        for (j, &d) in row.iter().enumerate() {
            if d != 0.0 {
                rows.push(Row {
                    what: what(k),
                    parameter: j,
                    derivative: d,
                    relative: s.values[j] / y * d,
                });
            }
        }
    }
    rows
}

fn print_rows(out: &mut String, s: &Sensitivities, rows: &[Row], column: &str, unit: &str) {
    let _ = writeln!(
        out,
        "{:<28} {:<20} {:>14} {:<10} {:>14} {:>12}",
        column,
        "parameter",
        "value",
        "unit",
        format!("d/dp ({unit}/unit)"),
        "p/y dy/dp"
    );
    for r in rows {
        let j = r.parameter;
        let _ = writeln!(
            out,
            "{:<28} {:<20} {} {:<10} {} {}",
            r.what,
            s.parameters[j],
            sci(s.values[j], 6, 14),
            if s.units[j].is_empty() {
                "-"
            } else {
                &s.units[j]
            },
            sci(r.derivative, 6, 14),
            sci(r.relative, 3, 12)
        );
    }
}

fn table(case: &Case, s: &Sensitivities, request: &SensitivityRequest, top: usize) -> String {
    let mut out = String::new();
    let heading = format!(
        "{} ({}), stage {}: {} parameters",
        case.name,
        case.model.name(),
        request.stage,
        s.parameters.len()
    );
    let shown = |n: usize| {
        if top == 0 || n <= top {
            format!("all {n}")
        } else {
            format!("the largest {top} of {n}")
        }
    };
    if request.modes {
        let rows = rows_of(s, &s.modes_hz, &s.dfdp, |k| {
            format!(
                "{:>2} {:>11.6} Hz {}",
                k + 1,
                s.modes_hz[k],
                s.mode_labels[k]
            )
        });
        let n = rows.len();
        let _ = writeln!(
            out,
            "{heading}: mode-frequency sensitivities, {} (y = f, Hz)",
            shown(n)
        );
        print_rows(&mut out, s, &sorted(rows, top), "mode", "Hz");
    }
    let at = |k: usize| format!("{} Hz", sci(request.freqs[k], 6, 0));
    if let (Some((abs, d)), Some((input, output))) = (&s.tf_abs, &request.tf) {
        let rows = rows_of(s, abs, d, at);
        let n = rows.len();
        let _ = writeln!(
            out,
            "{heading}: |H| {output}/{input} sensitivities, {} (y = |H|)",
            shown(n)
        );
        print_rows(&mut out, s, &sorted(rows, top), "frequency", "|H|");
    }
    if let (Some((asd, d)), Some(output)) = (&s.noise_asd, &request.noise) {
        let rows = rows_of(s, asd, d, at);
        let n = rows.len();
        let _ = writeln!(
            out,
            "{heading}: thermal-noise ASD of {output} sensitivities, {} (y = ASD)",
            shown(n)
        );
        print_rows(&mut out, s, &sorted(rows, top), "frequency", "ASD");
    }
    for (name, why) in &s.not_differentiable {
        let _ = writeln!(out, "not differentiable: {name}: {why}");
    }
    out
}
