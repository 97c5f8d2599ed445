//! `pendkit ss`: state-space matrices A, B, C, D with names, units and provenance, written
//! to .mat, .npz or .json.

use std::fmt::Write as _;

use crate::common::ModelArgs;
use crate::error::CliError;

// Arguments of `pendkit ss` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// Output file; the extension (.mat, .npz, .json) picks the format.
    #[arg(long)]
    out: std::path::PathBuf,
    /// Frequency (Hz) at which damping is represented as viscous.
    #[arg(long, default_value_t = 1.0, value_parser = crate::common::number, allow_hyphen_values = true)]
    damping_frequency: f64,
    /// Accepted for scripts written when `ss` refused to replace an existing file; every
    /// command now replaces its outputs (docs/cli.md, "Output files").
    #[arg(long, hide = true)]
    force: bool,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    let _ = a.force;
    let run = a.args.run_lossy()?;
    // continuum fibres asked for, or marked in the model's file
    if !run.result.model.frequency_terms.is_empty() {
        eprintln!(
            "note: a state space needs a finite model: `ss` keeps the static wires (violin beads where the model has them, --set n_beads=N); continuum fibres change tf and noise only"
        );
    }
    let damping_frequency = a.damping_frequency;
    let provenance = run.provenance()?;
    crate::output::clean_up_on_interrupt();
    let named = run.result.write_state_space(
        &a.out,
        damping_frequency,
        run.scheme.as_deref(),
        &provenance,
        // one policy for every output: replace (docs/cli.md, "Output files")
        &pendkit::export::WriteOptions { overwrite: true },
    )?;
    let ss = &named.state_space;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: wrote {} ({} states, {} inputs, {} outputs, with units and provenance); damping represented as viscous at {damping_frequency} Hz: exact for viscous damping only, and without the damping force of the support's velocity (B and D use Re C_XS,eff and Re S_eff)",
        run.heading(),
        a.out.display(),
        ss.states.len(),
        ss.inputs.len(),
        ss.outputs.len()
    );
    Ok(out)
}
