//! `pendkit tradeoff`: the speed–accuracy chart of a ladder of variants of one suspension
//! (stages, violin beads, blade-tip variants, restricted or full solve), each timed from
//! the model's name to the answer and measured against the richest; the ladder and the
//! measurements are the library's (`pendkit::tradeoff`).

use std::fmt::Write as _;
use std::path::PathBuf;

use pendkit::Case;
use pendkit::tradeoff::{Ladder, Question, Timing, Tradeoff, tradeoff};
use pendkit_plot::{TradeoffChart, TradeoffPoint, pareto_front};

use crate::error::CliError;
use crate::format::sci;
use crate::output::{OutputDir, write_file};
use crate::progress::Progress;

// Arguments of `pendkit tradeoff` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    /// Bundled model name or path to a case file (.toml): the base of the ladder.
    model: String,
    /// Displacement output of the noise (and of the transfer function): a variable or
    /// <body>@x,y,z/dx,dy,dz.
    #[arg(long)]
    output: String,
    /// Also compare the transfer function from this input (x00, force:x3, ...).
    #[arg(long)]
    input: Option<String>,
    /// Band F1:F2 (Hz): the noise and transfer function over it, the modes below F2.
    #[arg(long, value_name = "F1:F2", default_value = "0.1:100")]
    band: String,
    /// Log-spaced points over the band.
    #[arg(long, default_value_t = 200)]
    points: usize,
    /// Largest relative error accepted when naming the cheapest variant.
    #[arg(long, default_value_t = 1e-3, value_parser = crate::common::number, allow_hyphen_values = true)]
    tolerance: f64,
    /// Violin beads per fibre to try, comma-separated (models with n_beads only).
    #[arg(long, value_name = "N,...", default_value = "0,1,2,5,10,20,40")]
    beads: String,
    /// Leave out the continuum-fibre variants: the reference is then the richest finite
    /// variant (most beads) for the noise and transfer function too.
    #[arg(long)]
    no_continuum: bool,
    /// Time spent repeating each variant (s): the minimum of up to 5 runs within it is
    /// reported (the first run always completes).
    #[arg(long, value_name = "S", default_value_t = 0.5, value_parser = crate::common::number, allow_hyphen_values = true)]
    budget: f64,
    /// Override a parameter or damping field of every variant (as for `modes`; repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
    /// Directory for tradeoff.csv and tradeoff.svg (made if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// `F1:F2` as two frequencies (Hz), 0 < F1 < F2.
fn band(text: &str) -> Result<(f64, f64), CliError> {
    let bad = || {
        CliError::usage(format!(
            "--band '{text}': expected F1:F2 in Hz, 0 < F1 < F2"
        ))
    };
    let (a, b) = text.split_once(':').ok_or_else(bad)?;
    let (a, b) = (
        crate::common::number(a).map_err(|_| bad())?,
        crate::common::number(b).map_err(|_| bad())?,
    );
    if a > 0.0 && a < b {
        Ok((a, b))
    } else {
        Err(bad())
    }
}

fn beads(text: &str) -> Result<Vec<usize>, CliError> {
    text.split(',')
        .map(|t| {
            t.trim().parse::<usize>().map_err(|_| {
                CliError::usage(format!(
                    "--beads '{text}': '{}' is not a whole number",
                    t.trim()
                ))
            })
        })
        .collect()
}

/// Runs the command and returns what it prints; the last line names the cheapest variant
/// within the tolerance.
pub fn run(a: Args) -> Result<String, CliError> {
    if !(a.tolerance.is_finite() && a.tolerance > 0.0) {
        return Err(CliError::usage(format!(
            "--tolerance {}: must be finite and > 0",
            a.tolerance
        )));
    }
    if !(a.budget.is_finite() && a.budget >= 0.0) {
        return Err(CliError::usage(format!(
            "--budget {}: must be finite and >= 0 (s)",
            a.budget
        )));
    }
    let question = Question {
        output: a.output.clone(),
        input: a.input.clone(),
        band_hz: band(&a.band)?,
        points: a.points,
    };
    question.grid()?;
    let ladder = Ladder {
        beads: beads(&a.beads)?,
        continuum: !a.no_continuum,
        ..Ladder::default()
    };
    let timing = Timing {
        budget_s: a.budget,
        ..Timing::default()
    };
    let case = Case::open(&a.model)?.with_sets(&a.sets)?;
    let dir = OutputDir::create(&a.out)?;
    let progress = Progress::spinner(format!("{}: trade-off", case.name));
    let result = tradeoff(&case, &question, &ladder, &timing, |name| {
        progress.message(format!("{}: trade-off, {name}", case.name));
    })?;
    drop(progress);

    let csv_path = dir.join("tradeoff.csv");
    write_file(&csv_path, result.to_csv().as_bytes())?;
    let svg_path = dir.join("tradeoff.svg");
    let mut chart = TradeoffChart::new(
        format!(
            "{}: time to answer against error, {}–{} Hz",
            case.name, question.band_hz.0, question.band_hz.1
        ),
        points(&result),
    );
    chart.error_quantity = "max relative error (modes, noise ASD, |TF|; dimensionless)".into();
    chart.tolerance = Some(a.tolerance);
    crate::plotting::save(&chart, &svg_path)?;
    dir.keep();

    let mut out = table(&case.name, &question, &result, a.tolerance);
    let _ = writeln!(
        out,
        "wrote {} and {}",
        csv_path.display(),
        svg_path.display()
    );
    if let Some(best) = result.cheapest_within(a.tolerance) {
        let _ = writeln!(
            out,
            "cheapest within {}: {} ({} s, {})",
            a.tolerance,
            best.variant,
            sci(best.seconds, 3, 0),
            sci(best.errors.max(), 2, 0)
        );
    }
    Ok(out)
}

fn points(result: &Tradeoff) -> Vec<TradeoffPoint> {
    result
        .rows
        .iter()
        .map(|r| TradeoffPoint::new(&r.variant, r.seconds, r.errors.max()))
        .collect()
}

fn table(model: &str, question: &Question, result: &Tradeoff, tolerance: f64) -> String {
    let mut out = String::new();
    let reference = result.reference().map_or("", |r| r.variant.as_str());
    let reference = match &result.modes_reference {
        Some(modes) => format!("{reference} (modes: {modes})"),
        None => reference.to_string(),
    };
    let _ = writeln!(
        out,
        "{model}: modes below {} Hz, noise at {}{} over {}–{} Hz ({} points); errors against {reference}",
        question.band_hz.1,
        question.output,
        question
            .input
            .as_ref()
            .map(|i| format!(", |TF| {i} -> {}", question.output))
            .unwrap_or_default(),
        question.band_hz.0,
        question.band_hz.1,
        question.points,
    );
    let _ = writeln!(
        out,
        "time: minimum of up to 5 runs each from the model's name; * on the Pareto front, = within {tolerance}"
    );
    // the names' column as wide as the longest (at least 30)
    let width = result
        .rows
        .iter()
        .map(|r| r.variant.chars().count())
        .fold(30, usize::max);
    let _ = writeln!(
        out,
        "{:<width$} {:>10} {:>4} {:>10} {:>10} {:>10}",
        "variant", "seconds", "runs", "modes", "noise", "tf"
    );
    let front = pareto_front(&points(result));
    for (i, r) in result.rows.iter().enumerate() {
        let marks = format!(
            "{}{}",
            if front.contains(&i) { "*" } else { " " },
            if r.errors.max() <= tolerance {
                "="
            } else {
                " "
            }
        );
        let _ = writeln!(
            out,
            "{:<width$} {} {:>4} {} {} {} {marks}",
            r.variant,
            sci(r.seconds, 3, 10),
            r.runs,
            sci(r.errors.modes, 2, 10),
            sci(r.errors.noise, 2, 10),
            r.errors
                .transfer
                .map_or(format!("{:>10}", "-"), |e| sci(e, 2, 10)),
        );
    }
    for s in &result.skipped {
        let _ = writeln!(out, "skipped {}: {}", s.variant, s.reason);
    }
    // a variant with a neutral direction answers with a mode at 0 Hz (and a response
    // that grows toward 0 Hz): said beside the table, as `modes` says it beside its own
    for r in result.rows.iter().filter(|r| !r.neutral_modes.is_empty()) {
        let _ = writeln!(
            out,
            "neutral {}: mode{} {} {} neutral (nothing in this variant resists {}): `pendkit modes` of it says which coordinates move and how to remove {}",
            r.variant,
            if r.neutral_modes.len() == 1 { "" } else { "s" },
            r.neutral_modes
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            if r.neutral_modes.len() == 1 {
                "is"
            } else {
                "are"
            },
            if r.neutral_modes.len() == 1 {
                "it"
            } else {
                "them"
            },
            if r.neutral_modes.len() == 1 {
                "it"
            } else {
                "them"
            },
        );
    }
    out
}
