//! `pendkit fit`: fits free parameters of a model to measured mode frequencies (and
//! optionally |TF| points), prints the fitted values with their uncertainties, the
//! correlation matrix, the residuals and the undetermined combinations, and writes the
//! fitted case file.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use pendkit::Case;
use pendkit::fit::FitOptions;
use pendkit::fit::FitResult;
use pendkit::fit::MeasuredModes;
use pendkit::fit::MeasuredTf;
use pendkit::fit::fit;
use pendkit::system::Stage;
use serde_json::json;

use crate::common::DEFAULT_STAGE;
use crate::error::CliError;
use crate::format::{fixed, sci};

// Arguments of `pendkit fit` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    /// Bundled model name, or path to a case file or a suspension file (.toml): the start.
    model: String,
    /// Measured modes: CSV label,hz,sigma_hz[,shape] (see docs/cli.md).
    #[arg(long, value_name = "FILE")]
    modes: PathBuf,
    /// The parameters to fit, comma-separated (e.g. m1,m2,l1).
    #[arg(long, value_name = "P1,P2,...", value_delimiter = ',', required = true)]
    free: Vec<String>,
    /// Measured |TF| too: CSV freq_hz,abs,sigma_abs with `# input = NAME` and
    /// `# output = NAME` lines before the data.
    #[arg(long, value_name = "FILE")]
    tf: Option<PathBuf>,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2 (default 2, the complete model).
    #[arg(long)]
    stage: Option<Stage>,
    /// Override a parameter first: NAME=EXPR, scale(x) or increment(x); or a damping
    /// field, damping.<tag>.<field>=EXPR (repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
    /// How the Jacobian is computed: exact (the exact mode sensitivities, and the |TF| rows
    /// from the same request; default) or differences (central differences of the
    /// re-solved model).
    #[arg(long, value_name = "METHOD", default_value = "exact")]
    jacobian: pendkit::fit::JacobianMethod,
    /// Above this chi^2/dof the fit does not explain its data: the results are printed,
    /// then the worst residuals on stderr, and the exit status is 3.
    #[arg(long = "max-reduced-chi2", value_name = "X", default_value_t = 100.0)]
    max_reduced_chi2: f64,
    /// A measurement matches only a model mode within this factor of its frequency.
    #[arg(long = "match-window", value_name = "FACTOR", default_value_t = 2.0)]
    match_window: f64,
    /// Fit from N starts: the case's values and N-1 others a few per cent from them (a
    /// fixed pattern per start, up to 20 %); the lowest chi^2 is the result.
    #[arg(long, value_name = "N", default_value_t = 1)]
    starts: usize,
    /// When no start explains the data, try up to N more starts, one at a time.
    #[arg(long = "more-starts", value_name = "N", default_value_t = 4)]
    more_starts: usize,
    /// Write the fitted case file (TOML) here.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    // said in the flags' terms, before anything is read
    if a.max_reduced_chi2.is_nan() || a.max_reduced_chi2 <= 0.0 {
        return Err(CliError::usage(format!(
            "--max-reduced-chi2 must be positive, got {}",
            a.max_reduced_chi2
        )));
    }
    if !(a.match_window.is_finite() && a.match_window > 1.0) {
        return Err(CliError::usage(format!(
            "--match-window must be a factor above 1, got {}",
            a.match_window
        )));
    }
    let case = Case::open(&a.model)?.with_sets(&a.sets)?;
    let measured = MeasuredModes::read(&a.modes).map_err(pendkit::Error::from)?;
    let tf = match &a.tf {
        Some(path) => Some(MeasuredTf::read(path).map_err(pendkit::Error::from)?),
        None => None,
    };
    let options = FitOptions {
        stage: a.stage.unwrap_or(DEFAULT_STAGE),
        jacobian: a.jacobian,
        max_reduced_chi_squared: a.max_reduced_chi2,
        frequency_window: a.match_window,
        starts: a.starts,
        more_starts: a.more_starts,
        ..FitOptions::default()
    };
    let result = fit(&case, &measured, tf.as_ref(), &a.free, &options)?;
    let mut written = None;
    if let Some(path) = &a.out {
        let text = result.case_file(&model_reference(&a.model)?, &case);
        crate::output::write_file(path, text.as_bytes())?;
        written = Some(path);
    }
    if a.json {
        let out = json!({
            "model": case.model.name(),
            "case": case.name,
            "stage": options.stage.name(),
            "fit": result,
            "written": written,
        });
        let text = serde_json::to_string_pretty(&out).unwrap_or_default() + "\n";
        return with_verdict(text, &result, &a);
    }
    let mut out = table(&case, options.stage, &result, tf.as_ref());
    if let Some(path) = written {
        let _ = writeln!(out, "\nwrote {}", path.display());
    }
    with_verdict(out, &result, &a)
}

/// How many of the largest residuals the verdict names.
const WORST_NAMED: usize = 3;

/// The printed results `output`, or, when the fit does not explain its data, the error
/// that prints them and then names the worst residuals (exit status 3): a script must not
/// go on with a fit whose numbers look right and are not.
fn with_verdict(output: String, r: &FitResult, a: &Args) -> Result<String, CliError> {
    if r.explains_data {
        return Ok(output);
    }
    let at = |path: &Path, line: usize| format!("{}:{line}", path.display());
    // (what, where, (m - f)/σ) of every measurement, largest |(m - f)/σ| first
    let mut residuals: Vec<(String, String, f64)> = r
        .modes
        .iter()
        .map(|m| (m.label.clone(), at(&a.modes, m.line), m.normalized))
        .collect();
    if let Some(tf) = &a.tf {
        residuals.extend(r.tf.iter().map(|t| {
            let what = format!("|TF| at {} Hz", sci(t.freq_hz, 4, 0));
            (what, at(tf, t.line), t.normalized)
        }));
    }
    residuals.sort_by(|x, y| y.2.abs().total_cmp(&x.2.abs()));
    let worst: Vec<String> = residuals
        .iter()
        .take(WORST_NAMED)
        .map(|(what, place, n)| format!("{what} ({place}) {}", normalized(*n).trim()))
        .collect();
    // what the model lacks, from the sensitivities: the parameters whose freeing would
    // lower chi^2 most (to first order)
    let help = if r.would_help.is_empty() {
        String::new()
    } else {
        format!(
            "; freeing {} would help most (chi^2/dof to first order: {})",
            r.would_help
                .iter()
                .map(|h| h.parameter.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            r.would_help
                .iter()
                .map(|h| format!("{} {}", h.parameter, sci(h.reduced_chi_squared, 2, 0)))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Err(CliError::Unexplained {
        output,
        message: format!(
            "the fit does not explain its data: chi^2/dof = {} is above {} (--max-reduced-chi2); worst residuals (m-f)/s: {}{help}",
            r.reduced_chi_squared
                .map_or_else(|| "-".to_string(), |x| sci(x, 3, 0)),
            pendkit::expr::number_text(r.max_reduced_chi_squared),
            worst.join(", ")
        ),
    })
}

/// What the written case file names as its model: the bundled model's name, or the
/// suspension file's absolute path (directly, or as the case file given names it).
fn model_reference(spec: &str) -> Result<String, CliError> {
    let path = Path::new(spec);
    if !(spec.ends_with(".toml") || path.is_file()) {
        return Ok(spec.to_string());
    }
    let absolute = |p: &Path| -> Result<String, CliError> {
        std::fs::canonicalize(p)
            .map(|p| p.display().to_string())
            .map_err(|source| CliError::Read {
                path: p.to_path_buf(),
                source,
            })
    };
    let text = pendkit_limits::read_text(path).map_err(|source| CliError::Input {
        path: path.to_path_buf(),
        source,
    })?;
    if !pendkit::files::is_case_file(&text) {
        return absolute(path);
    }
    let file = pendkit::files::parse_case(&text)
        .map_err(|e| CliError::usage(format!("{}: {e}", path.display())))?;
    if file.model.ends_with(".toml") {
        let folder = path.parent().unwrap_or_else(|| Path::new(""));
        absolute(&folder.join(&file.model))
    } else {
        Ok(file.model)
    }
}

fn table(case: &Case, stage: Stage, r: &FitResult, tf: Option<&MeasuredTf>) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({}), stage {}: {} modes{} fitted with {} free parameters in {} iterations{}{} ({} model solutions, {})",
        case.name,
        case.model.name(),
        stage,
        r.modes.len(),
        tf.map_or_else(String::new, |t| format!(
            " and {} |TF| points of {}/{}",
            r.tf.len(),
            t.output,
            t.input
        )),
        r.parameters.len(),
        r.iterations,
        match r.restarts {
            0 => String::new(),
            1 => ", restarted once".to_string(),
            n => format!(", restarted {n} times"),
        },
        match r.starts {
            1 => String::new(),
            n => format!(", the best of {n} starts"),
        },
        r.solves,
        match r.jacobian {
            pendkit::fit::JacobianMethod::Exact => "exact Jacobian",
            pendkit::fit::JacobianMethod::Differences => "central-difference Jacobian",
        }
    );
    let _ = writeln!(
        out,
        "chi^2 = {} for {} degrees of freedom: chi^2/dof = {} (the uncertainties follow from the stated sigmas, not scaled by chi^2/dof)",
        sci(r.chi_squared, 4, 0),
        r.dof,
        r.reduced_chi_squared
            .map_or_else(|| "-".to_string(), |x| fixed(x, 4, 0))
    );
    let _ = writeln!(
        out,
        "\n{:<16} {:>14} {:>14} {:>12} unit",
        "parameter", "start", "fitted", "uncertainty"
    );
    for p in &r.parameters {
        let _ = writeln!(
            out,
            "{:<16} {} {} {} {}",
            p.name,
            sci(p.start, 6, 14),
            sci(p.value, 6, 14),
            p.uncertainty
                .map_or_else(|| format!("{:>12}", "undetermined"), |u| sci(u, 2, 12)),
            p.unit.as_deref().unwrap_or("-")
        );
    }
    correlation_table(&mut out, r);
    residual_tables(&mut out, r);
    determination(&mut out, r);
    out
}

/// The correlation matrix of the fitted parameters, names (cut to 8 characters) across the top.
fn correlation_table(out: &mut String, r: &FitResult) {
    let _ = writeln!(out, "\ncorrelation");
    let _ = write!(out, "{:<16}", "");
    for p in &r.parameters {
        let _ = write!(out, " {:>8}", truncate(&p.name, 8));
    }
    out.push('\n');
    for (p, row) in r.parameters.iter().zip(&r.correlation) {
        let _ = write!(out, "{:<16}", p.name);
        for c in row {
            let _ = write!(
                out,
                " {}",
                c.map_or_else(|| format!("{:>8}", "-"), |c| fixed(c, 3, 8))
            );
        }
        out.push('\n');
    }
}

/// Each measured mode against the model's, and each |TF| point (when fitted) against the
/// model's, with the normalized residual (m − f)/σ.
fn residual_tables(out: &mut String, r: &FitResult) {
    let _ = writeln!(
        out,
        "\n{:<10} {:>4}  {:<10} {:>12} {:>10} {:>12} {:>9}",
        "measured", "mode", "model", "measured_hz", "sigma_hz", "model_hz", "(m-f)/s"
    );
    for m in &r.modes {
        let _ = writeln!(
            out,
            "{:<10} {:>4}  {:<10} {} {} {} {}",
            m.label,
            m.mode,
            m.model_label,
            fixed(m.measured_hz, 6, 12),
            sci(m.sigma_hz, 2, 10),
            fixed(m.model_hz, 6, 12),
            normalized(m.normalized)
        );
    }
    if !r.tf.is_empty() {
        let _ = writeln!(
            out,
            "\n{:>12} {:>12} {:>10} {:>12} {:>9}",
            "freq_hz", "measured", "sigma", "model", "(m-f)/s"
        );
        for t in &r.tf {
            let _ = writeln!(
                out,
                "{} {} {} {} {}",
                sci(t.freq_hz, 4, 12),
                sci(t.measured, 4, 12),
                sci(t.sigma, 2, 10),
                sci(t.model, 4, 12),
                normalized(t.normalized)
            );
        }
    }
}

/// Whether every parameter is determined (the singular values' range), or the
/// combinations that are not.
fn determination(out: &mut String, r: &FitResult) {
    if !r.explains_data {
        // a fit that misses its data determines nothing, whatever the singular values say
        let _ = writeln!(
            out,
            "\nthe parameters are not determined: the fit does not explain its data (chi^2/dof {} above {}); the values are the model's best compromise and the uncertainties do not hold",
            r.reduced_chi_squared
                .map_or_else(|| "-".to_string(), |x| sci(x, 3, 0)),
            pendkit::expr::number_text(r.max_reduced_chi_squared),
        );
    }
    if r.undetermined.is_empty() {
        if !r.explains_data {
            return;
        }
        let _ = writeln!(
            out,
            "\nevery parameter is determined (singular values {} to {})",
            sci(r.singular_values.last().copied().unwrap_or(0.0), 2, 0),
            sci(r.singular_values.first().copied().unwrap_or(0.0), 2, 0)
        );
    } else {
        let _ = writeln!(
            out,
            "\nundetermined combinations (relative changes; left at their start values):"
        );
        for u in &r.undetermined {
            let terms: Vec<String> = u
                .combination
                .iter()
                .map(|(name, c)| format!("{} {name}", fixed(*c, 3, 0)))
                .collect();
            let _ = writeln!(
                out,
                "  singular value / largest {}: {}",
                sci(u.relative_singular_value, 1, 0),
                terms.join(" + ")
            );
        }
    }
}

/// At most `n` characters of `s`.
fn truncate(s: &str, n: usize) -> String {
    s.chars().take(n).collect()
}

/// A normalized residual (m − f)/σ: two decimals, or scientific from 10⁵ on, where the
/// decimals would only widen the column.
fn normalized(x: f64) -> String {
    if x.abs() >= 1e5 {
        sci(x, 2, 9)
    } else {
        fixed(x, 2, 9)
    }
}
