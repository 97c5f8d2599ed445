//! `pendkit noise`: thermal noise at an output, with the dominant damping tag (or term) at
//! each frequency, as a table or CSV.

use std::fmt::Write as _;

use pendkit::{Error, log_grid};
use pendkit_noise::NoiseOptions;

use crate::common::{GridArgs, ModelArgs, solver};

/// Arguments of `pendkit noise`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// A variable or <body>@x,y,z/dx,dy,dz.
    #[arg(long)]
    output: String,
    #[command(flatten)]
    grid: GridArgs,
    /// Print f_hz,asd rows.
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
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, Error> {
    let (case, stage, r) = a.args.run_lossy()?;
    let freqs = log_grid(a.grid.from, a.grid.to, a.grid.points)?;
    let options = NoiseOptions {
        solver: solver(a.full),
        // the table names the dominant term; the CSV adds per-tag columns only
        per_term: a.breakdown && !a.csv,
    };
    let noise = r.noise_with(&a.output, &freqs, &options)?;
    let tags = noise.by_tag();
    let mut out = String::new();
    if a.csv {
        out.push_str("f_hz,asd");
        if a.breakdown {
            for (tag, _) in tags {
                let _ = write!(out, ",{tag}");
            }
        }
        out.push('\n');
    } else {
        let _ = writeln!(
            out,
            "{} ({}), stage {stage}: thermal noise of {} at {} K (ASD per sqrt(Hz))",
            case.name,
            case.model.name(),
            a.output,
            r.system.temperature
        );
        let _ = writeln!(out, "{:>12}  {:>12}  dominant", "f_hz", "asd");
    }
    for (i, f) in freqs.iter().enumerate() {
        let asd = noise.total[i].sqrt();
        if a.csv {
            let _ = write!(out, "{f:e},{asd:e}");
            if a.breakdown {
                for (_, series) in tags {
                    let _ = write!(out, ",{:e}", series[i].max(0.0).sqrt());
                }
            }
            out.push('\n');
        } else {
            let total = noise.total[i];
            let top = if a.breakdown {
                dominant(
                    noise.by_term.iter().map(|(n, _, s)| (n.as_str(), s[i])),
                    total,
                )
            } else {
                dominant(tags.iter().map(|(t, s)| (t.as_str(), s[i])), total)
            };
            let _ = writeln!(out, "{f:>12.6e}  {asd:>12.6e}  {top}");
        }
    }
    Ok(out)
}

/// "name NN%" of the largest share, as a percentage of `total`.
fn dominant<'a>(shares: impl Iterator<Item = (&'a str, f64)>, total: f64) -> String {
    shares
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(name, share)| {
            format!(
                "{name} {:.0}%",
                100.0 * share / total.max(f64::MIN_POSITIVE)
            )
        })
        .unwrap_or_default()
}
