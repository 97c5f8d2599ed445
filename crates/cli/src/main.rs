//! The `pendkit` command line (DESIGN.md §8).

use std::fmt::Write as _;
use std::io::Write as _;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use pendkit::{Case, Error, ModeSelection, RunOptions, StageResult, log_grid, run_stage_with};
use pendkit_dynamics::Solver;
use pendkit_dynamics::lab_motion;
use pendkit_energy::{Stage, registry};
use pendkit_export::{Matrix, Names};
use pendkit_noise::NoiseOptions;
use serde_json::json;

#[derive(Parser)]
#[command(
    name = "pendkit",
    version,
    about = "Multi-stage pendulum suspensions: equilibrium, modes and more"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The model or case, stage and parameter overrides every calculation takes.
#[derive(clap::Args)]
struct ModelArgs {
    /// Bundled model name or path to a case file (.toml).
    model: String,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2 (modes default to 0a, responses to 2).
    #[arg(long)]
    stage: Option<Stage>,
    /// Override a parameter: NAME=EXPR, scale(x) or increment(x); or a damping field,
    /// damping.<tag>.<field>=EXPR (repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
}

impl ModelArgs {
    /// Builds the case and runs its stage (default `default`), computing the modes `modes`
    /// selects.
    fn run(
        &self,
        default: Stage,
        modes: ModeSelection,
    ) -> Result<(Case, Stage, StageResult), Error> {
        let case = Case::open(&self.model)?.with_sets(&self.sets)?;
        let stage = self.stage.unwrap_or(default);
        let (system, _) = case.build()?;
        let options = RunOptions {
            modes,
            ..Default::default()
        };
        Ok((case, stage, run_stage_with(system, stage, &options, None)?))
    }

    /// As [`ModelArgs::run`], for results that need losses (stage 0B or later).
    fn run_lossy(&self) -> Result<(Case, Stage, StageResult), Error> {
        if self.stage == Some(Stage::S0A) {
            return Err(Error::StageTooEarly);
        }
        self.run(Stage::S2, ModeSelection::All)
    }
}

/// A log-spaced frequency grid.
#[derive(clap::Args)]
struct GridArgs {
    /// First frequency (Hz).
    #[arg(long, default_value_t = 0.1)]
    from: f64,
    /// Last frequency (Hz).
    #[arg(long, default_value_t = 100.0)]
    to: f64,
    /// Number of log-spaced points.
    #[arg(long, default_value_t = 200)]
    points: usize,
}

#[derive(Subcommand)]
enum Command {
    /// Equilibrium and normal modes of a model or case file.
    Modes {
        #[command(flatten)]
        args: ModelArgs,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Also print each mode's lab-frame body motions (table output).
        #[arg(long)]
        lab: bool,
        /// Print the modes even if the equilibrium is unstable (exit status stays 0).
        #[arg(long)]
        allow_unstable: bool,
        /// Only the modes below this frequency (Hz); large models find them by shift-invert
        /// on a sparse factorisation instead of the dense eigensolver.
        #[arg(long, value_name = "HZ")]
        below: Option<f64>,
    },
    /// Transfer function from a support displacement or a force to a displacement or a
    /// force on the support.
    Tf {
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
    },
    /// Thermal noise (fluctuation-dissipation) at an output, with its breakdown by tag.
    Noise {
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
    },
    /// State-space matrices A, B, C, D with names, to .mat, .npz or .json.
    Ss {
        #[command(flatten)]
        args: ModelArgs,
        /// Output file; the extension (.mat, .npz, .json) picks the format.
        #[arg(long)]
        out: std::path::PathBuf,
        /// Frequency (Hz) at which damping is represented as viscous.
        #[arg(long, default_value_t = 1.0)]
        damping_frequency: f64,
    },
    /// Time each phase of a calculation in this process (build, equilibrium, Hessians per
    /// element kind, mass matrix, modes, and optionally noise): median and minimum over
    /// repetitions.
    Bench {
        /// Bundled model name or path to a case file (.toml).
        model: String,
        /// Calculation stage: 0a, 0b, 1a, 1b or 2.
        #[arg(long, default_value = "2")]
        stage: Stage,
        /// Number of repetitions.
        #[arg(long, default_value_t = 20)]
        repeat: usize,
        /// Override a parameter or damping field (as for `modes`; repeatable).
        #[arg(long = "set", value_name = "NAME=EXPR")]
        sets: Vec<String>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Also time the thermal noise of this output (a variable or <body>@x,y,z/dx,dy,dz).
        #[arg(long, value_name = "OUTPUT")]
        noise: Option<String>,
        /// Frequencies of the noise calculation (log-spaced, 0.1 to 100 Hz).
        #[arg(long, default_value_t = 200, requires = "noise")]
        points: usize,
    },
    /// List the registered element kinds and the stage each joins at.
    Elements,
    /// List the bundled models.
    Models,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Writes the output; a closed pipe (`pendkit ... | head`) is not an error.
fn emit(text: &str) {
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn run(cli: Cli) -> Result<(), Error> {
    let mut out = String::new();
    match cli.command {
        Command::Elements => {
            for kind in registry() {
                let _ = writeln!(
                    out,
                    "{:<16} stage {:<3} {}",
                    kind.kind(),
                    kind.stage(),
                    kind.summary()
                );
            }
        }
        Command::Bench {
            model,
            stage,
            repeat,
            sets,
            json,
            noise,
            points,
        } => {
            let noise = noise.as_deref().map(|output| (output, points));
            let report = pendkit::bench(&model, &sets, stage, repeat, noise)?;
            out = if json {
                serde_json::to_string_pretty(&report).unwrap_or_default() + "\n"
            } else {
                bench_table(&report, repeat)
            };
        }
        Command::Models => {
            for m in pendkit::models() {
                let _ = writeln!(out, "{:<18} {}", m.name(), m.summary());
            }
        }
        Command::Modes {
            args,
            json,
            lab,
            allow_unstable,
            below,
        } => {
            let selection = below.map_or(ModeSelection::All, ModeSelection::Below);
            let (case, stage, result) = args.run(Stage::S0A, selection)?;
            let stable = result.modes.check_stable();
            if let (Err(e), false) = (&stable, allow_unstable) {
                return Err(Error::Dynamics(e.clone()));
            }
            out = if json {
                modes_json(&case, stage, &result)
            } else {
                modes_table(&case, stage, &result, lab)
            };
        }
        Command::Tf {
            args,
            input,
            output,
            grid,
            csv,
            full,
        } => {
            let (case, stage, r) = args.run_lossy()?;
            let freqs = log_grid(grid.from, grid.to, grid.points)?;
            let h = r.transfer_with(&input, &output, &freqs, solver(full))?;
            if csv {
                out.push_str("f_hz,re,im\n");
            } else {
                let _ = writeln!(
                    out,
                    "{} ({}), stage {stage}: {output} / {input}",
                    case.name,
                    case.model.name()
                );
                let _ = writeln!(
                    out,
                    "{:>12}  {:>14}  {:>9}  {:>14}  {:>14}",
                    "f_hz", "magnitude", "phase_deg", "re", "im"
                );
            }
            for (f, z) in freqs.iter().zip(&h) {
                if csv {
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
        }
        Command::Noise {
            args,
            output,
            grid,
            csv,
            breakdown,
            full,
        } => {
            let (case, stage, r) = args.run_lossy()?;
            let freqs = log_grid(grid.from, grid.to, grid.points)?;
            let options = NoiseOptions {
                solver: solver(full),
                // the table names the dominant term; the CSV adds per-tag columns only
                per_term: breakdown && !csv,
            };
            let noise = r.noise_with(&output, &freqs, &options)?;
            let tags = noise.by_tag();
            if csv {
                out.push_str("f_hz,asd");
                if breakdown {
                    for (tag, _) in tags {
                        let _ = write!(out, ",{tag}");
                    }
                }
                out.push('\n');
            } else {
                let _ = writeln!(
                    out,
                    "{} ({}), stage {stage}: thermal noise of {output} at {} K (ASD per sqrt(Hz))",
                    case.name,
                    case.model.name(),
                    r.system.temperature
                );
                let _ = writeln!(out, "{:>12}  {:>12}  dominant", "f_hz", "asd");
            }
            for (i, f) in freqs.iter().enumerate() {
                let asd = noise.total[i].sqrt();
                if csv {
                    let _ = write!(out, "{f:e},{asd:e}");
                    if breakdown {
                        for (_, series) in tags {
                            let _ = write!(out, ",{:e}", series[i].max(0.0).sqrt());
                        }
                    }
                    out.push('\n');
                } else {
                    let total = noise.total[i];
                    let top = if breakdown {
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
        }
        Command::Ss {
            args,
            out: path,
            damping_frequency,
        } => {
            let (case, stage, r) = args.run_lossy()?;
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
            pendkit_export::write(&path, &matrices, &names).map_err(Error::Export)?;
            let _ = writeln!(
                out,
                "{} ({}), stage {stage}: wrote {} ({} states, {} inputs, {} outputs); damping represented as viscous at {damping_frequency} Hz: exact for viscous damping only, and without the damping force of the support's velocity (B and D use Re C_XS,eff and Re S_eff)",
                case.name,
                case.model.name(),
                path.display(),
                ss.states.len(),
                ss.inputs.len(),
                ss.outputs.len()
            );
        }
    }
    emit(&out);
    Ok(())
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

/// The solver `--full` asks for.
fn solver(full: bool) -> Solver {
    if full {
        Solver::Full
    } else {
        Solver::Restricted
    }
}

fn modes_json(case: &Case, stage: Stage, r: &pendkit::StageResult) -> String {
    let x = &r.assembled.equilibrium.coords;
    let modes: Vec<_> = r
        .modes
        .modes
        .iter()
        .map(|m| {
            let lab: Vec<_> = lab_motion(&r.system, &r.assembled.layout, x, m)
                .into_iter()
                .map(|b| json!({"body": b.body, "translation": b.translation, "rotation": b.rotation}))
                .collect();
            json!({
                "hz": m.hz,
                "omega_squared": m.omega_squared,
                "stable": m.is_stable(),
                "label": m.label,
                "vector": m.vector,
                "energy_fractions": m.energy_fractions,
                "lab": lab,
            })
        })
        .collect();
    let equilibrium: serde_json::Map<String, serde_json::Value> = r
        .system
        .coords
        .iter()
        .zip(x)
        .map(|(c, v)| (c.name.clone(), json!(v)))
        .collect();
    let out = json!({
        "model": case.model.name(),
        "case": case.name,
        "stage": stage.name(),
        "coordinates": r.modes.coordinates,
        "equilibrium": equilibrium,
        "modes": modes,
    });
    serde_json::to_string_pretty(&out).unwrap_or_default() + "\n"
}

fn modes_table(case: &Case, stage: Stage, r: &pendkit::StageResult, lab: bool) -> String {
    let mut out = String::new();
    let eq = &r.assembled.equilibrium;
    let _ = writeln!(
        out,
        "{} ({}), stage {}: {} modes; equilibrium in {} Newton steps, residual {:.2e}",
        case.name,
        case.model.name(),
        stage,
        r.modes.modes.len(),
        eq.iterations,
        eq.max_residual
    );
    let _ = writeln!(
        out,
        "{:>4}  {:>14}  {:<10} kinetic energy",
        "mode", "frequency Hz", "label"
    );
    for (i, m) in r.modes.modes.iter().enumerate() {
        let mut shares: Vec<(usize, f64)> =
            m.energy_fractions.iter().copied().enumerate().collect();
        shares.sort_by(|a, b| b.1.total_cmp(&a.1));
        let top: Vec<String> = shares
            .iter()
            .take(3)
            .filter(|(_, f)| *f >= 0.01)
            .map(|(k, f)| format!("{} {:.0}%", r.modes.coordinates[*k], 100.0 * f))
            .collect();
        let flag = if m.is_stable() {
            ""
        } else {
            "  UNSTABLE (growth rate)"
        };
        let _ = writeln!(
            out,
            "{:>4}  {:>14.7}  {:<10} {}{}",
            i + 1,
            m.hz,
            m.label,
            top.join(", "),
            flag
        );
        if lab {
            for b in lab_motion(&r.system, &r.assembled.layout, &eq.coords, m) {
                let _ = writeln!(
                    out,
                    "        {:<10} x {:>10.3e} y {:>10.3e} z {:>10.3e}  yaw {:>10.3e} pitch {:>10.3e} roll {:>10.3e}",
                    b.body,
                    b.translation[0],
                    b.translation[1],
                    b.translation[2],
                    b.rotation[0],
                    b.rotation[1],
                    b.rotation[2]
                );
            }
        }
    }
    out
}

fn bench_table(r: &pendkit::BenchReport, repeat: usize) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}, stage {}: time per repetition over {repeat} repetitions",
        r.model, r.stage
    );
    let _ = writeln!(
        out,
        "{:<44} {:>12} {:>12} {:>7}",
        "phase", "median", "min", "calls"
    );
    let ms = |s: f64| format!("{:.4} ms", 1e3 * s);
    for p in &r.phases {
        let _ = writeln!(
            out,
            "{:<44} {:>12} {:>12} {:>7}",
            p.name,
            ms(p.median_s),
            ms(p.min_s),
            p.calls
        );
    }
    let _ = writeln!(
        out,
        "{:<44} {:>12}",
        "total (build to modes, noise excluded)",
        ms(r.total_median_s)
    );
    out
}
