//! `pendkit tf`: a transfer function over a log-spaced grid, as a table or CSV.

use std::fmt::Write as _;

use pendkit::{Error, log_grid};

use crate::common::{GridArgs, ModelArgs, solver};

/// Arguments of `pendkit tf`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// A parameter (support displacement, e.g. x00), force:<variable>, or
    /// force:<body>@x,y,z/dx,dy,dz.
    #[arg(long)]
    input: String,
    /// A variable, <body>@x,y,z/dx,dy,dz, or force:<parameter> (force on the support).
    #[arg(long)]
    output: String,
    #[command(flatten)]
    grid: GridArgs,
    /// Print f_hz,re,im rows.
    #[arg(long)]
    csv: bool,
    /// Solve every variable and float instead of only the blocks the input and output
    /// couple to (the same numbers, for checking).
    #[arg(long)]
    full: bool,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, Error> {
    let (case, stage, r) = a.args.run_lossy()?;
    let freqs = log_grid(a.grid.from, a.grid.to, a.grid.points)?;
    let h = r.transfer_with(&a.input, &a.output, &freqs, solver(a.full))?;
    let mut out = String::new();
    if a.csv {
        out.push_str("f_hz,re,im\n");
    } else {
        let _ = writeln!(
            out,
            "{} ({}), stage {stage}: {} / {}",
            case.name,
            case.model.name(),
            a.output,
            a.input
        );
        let _ = writeln!(
            out,
            "{:>12}  {:>14}  {:>9}  {:>14}  {:>14}",
            "f_hz", "magnitude", "phase_deg", "re", "im"
        );
    }
    for (f, z) in freqs.iter().zip(&h) {
        if a.csv {
            let _ = writeln!(out, "{f:e},{:e},{:e}", z.re, z.im);
        } else {
            let _ = writeln!(
                out,
                "{f:>12.6e}  {:>14.6e}  {:>9.3}  {:>14.6e}  {:>14.6e}",
                z.norm(),
                z.arg().to_degrees(),
                z.re,
                z.im
            );
        }
    }
    Ok(out)
}
