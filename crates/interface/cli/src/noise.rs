//! `pendkit noise`: thermal noise at an output, with the dominant damping tag (or term) at
//! each frequency, as a table or CSV, and as a noise budget figure.

use std::fmt::Write as _;
use std::path::PathBuf;

use pendkit::NoiseOptions;
use pendkit::describe::unit_slug;

use crate::common::{GridArgs, ModelArgs, check_plot_path, solver};
use crate::error::CliError;
use crate::format::{csv, sci};
use crate::plotting;

// Arguments of `pendkit noise` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// A variable or <body>@x,y,z/dx,dy,dz; declared names too (L3_L).
    #[arg(long)]
    output: String,
    #[command(flatten)]
    grid: GridArgs,
    /// Print CSV: f_hz,asd_<unit> (e.g. asd_m_per_rthz).
    #[arg(long)]
    csv: bool,
    /// Add one ASD column per damping tag (CSV) or name the dominant term instead of the
    /// dominant tag (table; computes the per-term shares).
    #[arg(long)]
    breakdown: bool,
    /// Solve every variable and float instead of only the blocks the output couples to
    /// (the same numbers, for checking).
    #[arg(long)]
    full: bool,
    /// Write a noise budget (total and each damping tag, ASD, log-log) to this file (.svg
    /// or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    check_plot_path(&a.plot)?;
    let run = a.args.run_lossy()?;
    let freqs = a.grid.frequencies()?;
    let options = NoiseOptions {
        solver: solver(a.full),
        // the table names the dominant term; the CSV adds per-tag columns only
        per_term: a.breakdown && !a.csv,
    };
    let noise = run.result.noise_with(&a.output, &freqs, &options)?;
    // lossy parts that leave this output still: a column of exact zeros is a result, but
    // not one to print without saying why
    if noise.total.iter().all(|&psd| psd == 0.0) {
        eprintln!(
            "warning: the thermal noise of {} is exactly 0 at every frequency: no lossy term moves it (the model's tags: {})",
            a.output,
            noise
                .tags
                .iter()
                .map(|(tag, _)| tag.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if let Some(path) = &a.plot {
        plotting::save(
            &plotting::noise_budget(&run, &a.output, &freqs, &noise),
            path,
        )?;
    }
    let unit = format!(
        "{}/√Hz",
        run.result.output_unit(&a.output).unwrap_or_default()
    );
    let slug = unit_slug(&unit);
    let asd = noise.asd();
    let tags = noise.asd_by_tag();
    let mut out = String::new();
    if a.csv {
        let _ = write!(out, "f_hz,asd_{slug}");
        if a.breakdown {
            for (tag, _) in &tags {
                let _ = write!(out, ",asd_{tag}_{slug}");
            }
        }
        out.push('\n');
        for (i, f) in freqs.iter().enumerate() {
            let _ = write!(out, "{},{}", csv(*f), csv(asd[i]));
            if a.breakdown {
                for (_, series) in &tags {
                    let _ = write!(out, ",{}", csv(series[i]));
                }
            }
            out.push('\n');
        }
        return Ok(out);
    }
    let _ = writeln!(
        out,
        "{}: thermal noise of {} at {} K (ASD, {unit})",
        run.heading(),
        run.port(&a.output),
        run.result.system.temperature
    );
    let _ = writeln!(
        out,
        "{:>12}  {:>16}  dominant (share of the PSD)",
        "f_hz",
        format!("asd_{slug}")
    );
    let psd = noise.psd();
    for (i, f) in freqs.iter().enumerate() {
        let top = if a.breakdown {
            dominant(
                noise.by_term.iter().map(|(n, _, s)| (n.as_str(), s[i])),
                psd[i],
            )
        } else {
            dominant(
                noise.psd_by_tag().iter().map(|(t, s)| (t.as_str(), s[i])),
                psd[i],
            )
        };
        let _ = writeln!(out, "{}  {}  {top}", sci(*f, 6, 12), sci(asd[i], 6, 16));
    }
    Ok(out)
}

/// "name NN%" of the largest share, as a percentage of `total`; "-" when nothing
/// dissipates (a lossless model's PSD is exactly 0: no share dominates).
fn dominant<'a>(shares: impl Iterator<Item = (&'a str, f64)>, total: f64) -> String {
    if total == 0.0 {
        return "-".to_string();
    }
    shares
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(name, share)| {
            format!(
                "{name} {}%",
                crate::format::fixed(100.0 * share / total.max(f64::MIN_POSITIVE), 0, 0)
            )
        })
        .unwrap_or_default()
}
