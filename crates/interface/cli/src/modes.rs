//! `pendkit modes`: equilibrium and normal modes, as a table or JSON, with a mode chart or
//! one mode's shape as a figure.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use pendkit::dynamics::lab_motion;
use pendkit::stage::{MAX_VIOLIN_HARMONICS, ModeSelection, ViolinMode};
use serde::Serialize;

use crate::common::{ModelArgs, Run, check_plot_path};
use crate::error::CliError;
use crate::format::{fixed, sci};
use crate::output::Output;
use crate::plotting;

// Arguments of `pendkit modes` (a plain comment: see `Command` on why clap must not read it).
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
    #[arg(long, value_name = "HZ", value_parser = crate::common::number, allow_hyphen_values = true)]
    below: Option<f64>,
    /// Write a figure (.svg or .png): the mode chart (frequencies by degree-of-freedom
    /// family), or with --shape the shape of one mode.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// With --plot: draw the shape of mode N (numbered from 1 as in the table) instead of
    /// the chart.
    #[arg(long, value_name = "N", requires = "plot")]
    shape: Option<usize>,
    /// Also list the first N violin modes of each set of alike fibres: the roots of the
    /// model with its lowest wires as continuum fibres (their exact D(f)), each with its
    /// quality factor and accuracy (docs/continuum-fibres.md). The rigid-body table keeps
    /// the static model.
    #[arg(long, value_name = "N")]
    violin: Option<usize>,
}

/// The violin modes of a run (`--violin N`): refused for N out of range, static fibres
/// asked for, and a model with no wires to take as continuum fibres.
fn violin_modes(run: &Run, n: usize) -> Result<Vec<ViolinMode>, CliError> {
    if run.result.model.frequency_terms.is_empty() {
        return Err(CliError::usage(
            "--violin: the model has no wires to take as continuum fibres",
        ));
    }
    Ok(run.result.violin_modes(n)?)
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<Output, CliError> {
    check_plot_path(&a.plot)?;
    let selection = a.below.map_or(ModeSelection::All, ModeSelection::Below);
    let mut a = a;
    if let Some(n) = a.violin {
        if n == 0 || n > MAX_VIOLIN_HARMONICS {
            return Err(CliError::usage(format!(
                "--violin: the number of harmonics must be 1 to {MAX_VIOLIN_HARMONICS} (got {n})"
            )));
        }
        if a.args.fibres.as_deref() == Some("static") {
            return Err(CliError::usage(
                "--violin needs continuum fibres: drop --fibres static",
            ));
        }
        a.args.fibres = Some("continuum".into());
    } else if a.args.fibres.as_deref() == Some("continuum") {
        eprintln!(
            "note: the modes are those of the static model (massless fibres); --fibres continuum changes tf and noise only (violin modes: --violin N)"
        );
    }
    let run = a.args.run(selection)?;
    run.check_stable(a.args.allow_unstable)?;
    let violin = a.violin.map(|n| violin_modes(&run, n)).transpose()?;
    if let Some(path) = &a.plot {
        match a.shape {
            Some(n) => plotting::save(&plotting::mode_shape(&run, n)?, path)?,
            None => plotting::save(&plotting::mode_chart(&run), path)?,
        }
    }
    if a.json {
        Ok(modes_json(run, violin))
    } else {
        let mut table = modes_table(&run, a.lab)?;
        if let Some(v) = &violin {
            table += &violin_table(v);
        }
        Ok(table.into())
    }
}

/// The violin table: one row per root, grouped by fibre set and harmonic.
fn violin_table(modes: &[ViolinMode]) -> String {
    let mut out = String::new();
    let mut set: Option<&[String]> = None;
    for m in modes {
        if set != Some(m.wires.as_slice()) {
            set = Some(&m.wires);
            let _ = writeln!(
                out,
                "violin modes of fibres {} (continuum; the rigid-body modes above are the static model's)",
                m.wires.join(" ")
            );
            let _ = writeln!(
                out,
                "{:>8}  {:>16}  {:>10}  {:>11}  motion",
                "harmonic", "frequency_hz", "q", "accuracy_hz"
            );
        }
        let motion = match &m.held {
            Some(h) => format!("fibres only ({h}), bodies still"),
            None => "bodies move".to_string(),
        };
        let q = if m.q.is_finite() {
            sci(m.q, 4, 10)
        } else {
            format!("{:>10}", "inf")
        };
        let _ = writeln!(
            out,
            "{:>8}  {}  {}  {}  {motion}",
            m.harmonic,
            fixed(m.frequency_hz, 9, 16),
            q,
            sci(m.accuracy_hz, 1, 11),
        );
    }
    out
}

/// The bodies' lab-frame motion in mode `m` of the run.
fn lab(
    run: &Run,
    m: &pendkit::dynamics::Mode,
) -> Result<Vec<pendkit::dynamics::BodyMotion>, CliError> {
    let r = &run.result;
    lab_motion(
        &r.system,
        &r.assembled.layout,
        &r.assembled.equilibrium.coords,
        m,
    )
    .map_err(|e| CliError::Pendkit(e.into()))
}

/// `modes --json`, streamed: each mode is formatted as it is written, so that the memory
/// taken is the model's and not a second copy of a possibly gigabyte-sized document (the
/// quad with 200 beads per fibre prints 0.9 GB; built as one `serde_json::Value` and then
/// one `String`, it took 5.6 GB).
///
/// The document is byte for byte what the earlier `json!` form printed: the keys of every
/// object in alphabetical order (the order of serde_json's `Map`, a `BTreeMap`), hence the
/// field order of the structs below, which is not their reading order.
fn modes_json(run: Run, violin: Option<Vec<ViolinMode>>) -> Output {
    Output::Stream(Box::new(move |w| {
        let document = ModesDocument {
            case: &run.case.name,
            coordinate_units: run
                .result
                .modes
                .coordinates
                .iter()
                .map(|c| run.result.coordinate_unit(c).unwrap_or_default())
                .collect(),
            coordinates: run
                .result
                .modes
                .coordinates
                .iter()
                .map(|c| run.coord(c))
                .collect(),
            equilibrium: run
                .result
                .system
                .coords
                .iter()
                .zip(&run.result.assembled.equilibrium.coords)
                .map(|(c, v)| (run.coord(&c.name), *v))
                .collect(),
            model: run.case.model.name(),
            modes: ModesJson(&run),
            naming: run.scheme.as_deref().unwrap_or("model"),
            stage: run.stage.name(),
            violin: violin.as_ref().map(|v| {
                v.iter()
                    .map(|m| ViolinJson {
                        accuracy_hz: m.accuracy_hz,
                        frequency_hz: m.frequency_hz,
                        harmonic: m.harmonic,
                        held: m.held.as_deref(),
                        // null when infinite (no loss)
                        q: Some(m.q).filter(|q| q.is_finite()),
                        wires: &m.wires,
                    })
                    .collect()
            }),
        };
        serde_json::to_writer_pretty(&mut *w, &document)
            .and_then(|()| w.write_all(b"\n").map_err(serde_json::Error::io))
            .map_err(|e| {
                if e.is_io() {
                    CliError::Stdout(e.into())
                } else {
                    // a mode's lab-frame motion could not be computed (its message)
                    CliError::usage(e.to_string())
                }
            })
    }))
}

/// The `modes --json` document (keys in alphabetical order: see [`modes_json`]).
#[derive(Serialize)]
struct ModesDocument<'a> {
    case: &'a str,
    coordinate_units: Vec<&'static str>,
    coordinates: Vec<String>,
    equilibrium: BTreeMap<String, f64>,
    model: &'a str,
    modes: ModesJson<'a>,
    naming: &'a str,
    stage: &'a str,
    /// With `--violin N` only, so that the document without it is unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    violin: Option<Vec<ViolinJson<'a>>>,
}

/// One violin mode in `modes --json` (keys in alphabetical order).
#[derive(Serialize)]
struct ViolinJson<'a> {
    accuracy_hz: f64,
    frequency_hz: f64,
    harmonic: usize,
    held: Option<&'a str>,
    q: Option<f64>,
    wires: &'a [String],
}

/// The modes of a run, each formatted (with its lab-frame motion) only when written.
struct ModesJson<'a>(&'a Run);

impl Serialize for ModesJson<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error as _, SerializeSeq as _};
        let run = self.0;
        let modes = &run.result.modes.modes;
        let mut seq = serializer.serialize_seq(Some(modes.len()))?;
        for m in modes {
            let lab = lab(run, m).map_err(|e| S::Error::custom(e.to_string()))?;
            seq.serialize_element(&ModeJson {
                // null for infinity (the relative accuracy of a neutral mode)
                accuracy: Some(m.accuracy()).filter(|a| a.is_finite()),
                energy_fractions: &m.energy_fractions,
                family: run.result.mode_family(m),
                hz: m.hz,
                lab: lab
                    .into_iter()
                    .map(|b| LabJson {
                        body: run.body(&b.body),
                        rotation: b.rotation,
                        translation: b.translation,
                    })
                    .collect(),
                label: run.coord(&m.label),
                omega_squared: m.omega_squared,
                stable: m.is_stable(),
                vector: &m.vector,
                vector_accuracy: m.vector_error,
            })?;
        }
        seq.end()
    }
}

/// One mode in `modes --json` (keys in alphabetical order).
#[derive(Serialize)]
struct ModeJson<'a> {
    accuracy: Option<f64>,
    energy_fractions: &'a [f64],
    family: String,
    hz: f64,
    lab: Vec<LabJson>,
    label: String,
    omega_squared: f64,
    stable: bool,
    vector: &'a [f64],
    vector_accuracy: f64,
}

/// One body's lab-frame motion in a mode (keys in alphabetical order).
#[derive(Serialize)]
struct LabJson {
    body: String,
    rotation: [f64; 3],
    translation: [f64; 3],
}

/// Relative accuracy worse than this is printed next to the frequency.
const PRINT_ACCURACY_ABOVE: f64 = 1e-6;

/// A mode's largest kinetic-energy shares (at most three, each at least 1 %), as
/// "coordinate N%" in the run's naming: the mode table's and the report's last column.
pub fn top_shares(run: &Run, coordinates: &[String], fractions: &[f64]) -> Vec<String> {
    // only shares of 1 % or more are shown, at most a hundred of them: sorting those
    // (stable, as sorting all would order them) keeps a table of n modes linear in n per mode
    let mut shares: Vec<(usize, f64)> = fractions
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, f)| *f >= 0.01)
        .collect();
    shares.sort_by(|a, b| b.1.total_cmp(&a.1));
    shares
        .iter()
        .take(3)
        .map(|(k, f)| {
            format!(
                "{} {}%",
                run.coord(&coordinates[*k]),
                fixed(100.0 * f, 0, 0)
            )
        })
        .collect()
}

fn modes_table(run: &Run, with_lab: bool) -> Result<String, CliError> {
    let r = &run.result;
    let mut out = String::new();
    let eq = &r.assembled.equilibrium;
    let _ = writeln!(
        out,
        "{}: {} modes; equilibrium in {} Newton steps, residual {}",
        run.heading(),
        r.modes.modes.len(),
        eq.iterations,
        sci(eq.max_residual, 2, 0)
    );
    let _ = writeln!(
        out,
        "{:>4}  {:>14}  {:<6}  {:<10}  kinetic energy share",
        "mode", "frequency_hz", "family", "label"
    );
    for (i, m) in r.modes.modes.iter().enumerate() {
        let top = top_shares(run, &r.modes.coordinates, &m.energy_fractions);
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
            "{:>4}  {}  {:<6}  {:<10}  {}{}",
            i + 1,
            fixed(m.hz, 7, 14),
            r.mode_family(m),
            run.coord(&m.label),
            top.join(", "),
            flag
        );
        if with_lab {
            for b in lab(run, m)? {
                let t = b.translation.map(|v| sci(v, 3, 10));
                let w = b.rotation.map(|v| sci(v, 3, 10));
                let _ = writeln!(
                    out,
                    "        {:<10} x_m {} y_m {} z_m {}  yaw_rad {} pitch_rad {} roll_rad {}",
                    run.body(&b.body),
                    t[0],
                    t[1],
                    t[2],
                    w[0],
                    w[1],
                    w[2]
                );
            }
        }
    }
    for line in run.neutral_notes() {
        let _ = writeln!(out, "{line}");
    }
    Ok(out)
}
