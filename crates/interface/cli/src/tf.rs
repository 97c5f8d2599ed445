//! `pendkit tf`: transfer functions over a log-spaced grid or given frequencies, as a table
//! or CSV, and as a Bode plot.

use std::fmt::Write as _;
use std::path::PathBuf;

use pendkit::describe::unit_slug;

use crate::common::{GridArgs, ModelArgs, check_plot_path, solver};
use crate::error::CliError;
use crate::format::{csv, fixed, sci};
use crate::plotting::{self, Response};

// Arguments of `pendkit tf` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// A parameter (support displacement, e.g. x00), force:<variable>, or
    /// force:<body>@x,y,z/dx,dy,dz; declared names too (GND_L, force:L3_P). Repeatable:
    /// every input with every output.
    #[arg(long, required = true)]
    input: Vec<String>,
    /// A variable, <body>@x,y,z/dx,dy,dz, or force:<parameter> (force on the support);
    /// declared names too (L3_L). Repeatable.
    #[arg(long, required = true)]
    output: Vec<String>,
    #[command(flatten)]
    grid: GridArgs,
    /// Print CSV: f_hz,re_<unit>,im_<unit> (one pair), with the pair in each column's name
    /// for several.
    #[arg(long)]
    csv: bool,
    /// Solve every variable and float instead of only the blocks the input and output
    /// couple to (the same numbers, for checking).
    #[arg(long)]
    full: bool,
    /// Write a Bode plot (magnitude and phase) to this file (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

/// A CSV-safe form of a name: letters, digits and underscores.
fn column_name(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    check_plot_path(&a.plot)?;
    let run = a.args.run_lossy()?;
    let freqs = a.grid.frequencies()?;
    let mut responses = Vec::new();
    for input in &a.input {
        for output in &a.output {
            let values = run
                .result
                .transfer_with(input, output, &freqs, solver(a.full))?;
            responses.push((
                input.as_str(),
                output.as_str(),
                Response {
                    name: format!("{}/{}", run.port(output), run.port(input)),
                    unit: run.result.transfer_unit(input, output).unwrap_or_default(),
                    values,
                },
            ));
        }
    }
    if let Some(path) = &a.plot {
        let list: Vec<Response> = responses
            .iter()
            .map(|(_, _, r)| Response {
                name: r.name.clone(),
                unit: r.unit.clone(),
                values: r.values.clone(),
            })
            .collect();
        let title = format!("Transfer functions: {}", run.heading());
        plotting::save(&plotting::bode(&title, &freqs, &list)?, path)?;
    }
    let mut out = String::new();
    if a.csv {
        out.push_str("f_hz");
        let single = responses.len() == 1;
        for (input, output, r) in &responses {
            let unit = unit_slug(&r.unit);
            let pair = if single {
                String::new()
            } else {
                format!(
                    "{}_from_{}_",
                    column_name(&run.port(output)),
                    column_name(&run.port(input))
                )
            };
            let _ = write!(out, ",re_{pair}{unit},im_{pair}{unit}");
        }
        out.push('\n');
        for (i, f) in freqs.iter().enumerate() {
            out.push_str(&csv(*f));
            for (_, _, r) in &responses {
                let _ = write!(out, ",{},{}", csv(r.values[i].re), csv(r.values[i].im));
            }
            out.push('\n');
        }
        return Ok(out);
    }
    for (_, _, r) in &responses {
        let unit = unit_slug(&r.unit);
        let _ = writeln!(out, "{}: {} ({})", run.heading(), r.name, r.unit);
        let _ = writeln!(
            out,
            "{:>12}  {:>16}  {:>9}  {:>16}  {:>16}",
            "f_hz",
            format!("magnitude_{unit}"),
            "phase_deg",
            format!("re_{unit}"),
            format!("im_{unit}")
        );
        for (f, z) in freqs.iter().zip(&r.values) {
            let _ = writeln!(
                out,
                "{}  {}  {}  {}  {}",
                sci(*f, 6, 12),
                sci(z.norm(), 6, 16),
                fixed(z.arg().to_degrees(), 3, 9),
                sci(z.re, 6, 16),
                sci(z.im, 6, 16)
            );
        }
    }
    Ok(out)
}
