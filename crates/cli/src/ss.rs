//! `pendkit ss`: state-space matrices A, B, C, D with names, written to .mat, .npz or .json.

use std::fmt::Write as _;

use pendkit::Error;
use pendkit_export::{Matrix, Names};

use crate::common::ModelArgs;

/// Arguments of `pendkit ss`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// Output file; the extension (.mat, .npz, .json) picks the format.
    #[arg(long)]
    out: std::path::PathBuf,
    /// Frequency (Hz) at which damping is represented as viscous.
    #[arg(long, default_value_t = 1.0)]
    damping_frequency: f64,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, Error> {
    let (case, stage, r) = a.args.run_lossy()?;
    let damping_frequency = a.damping_frequency;
    let ss = r.model.state_space(&r.system.damping, damping_frequency)?;
    let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<f64> {
        (0..m.nrows())
            .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
            .collect()
    };
    let data = [rows(&ss.a), rows(&ss.b), rows(&ss.c), rows(&ss.d)];
    let matrices: Vec<Matrix> = [("A", &ss.a), ("B", &ss.b), ("C", &ss.c), ("D", &ss.d)]
        .iter()
        .zip(&data)
        .map(|((name, m), d)| Matrix {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            data: d,
        })
        .collect();
    let names = [
        Names {
            name: "states",
            items: &ss.states,
        },
        Names {
            name: "inputs",
            items: &ss.inputs,
        },
        Names {
            name: "outputs",
            items: &ss.outputs,
        },
    ];
    let options = pendkit_export::WriteOptions {
        overwrite: a.force,
    };
    pendkit_export::write_with(&a.out, &matrices, &names, &options).map_err(Error::Export)?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({}), stage {stage}: wrote {} ({} states, {} inputs, {} outputs); damping represented as viscous at {damping_frequency} Hz: exact for viscous damping only, and without the damping force of the support's velocity (B and D use Re C_XS,eff and Re S_eff)",
        case.name,
        case.model.name(),
        a.out.display(),
        ss.states.len(),
        ss.inputs.len(),
        ss.outputs.len()
    );
    Ok(out)
}
