//! `pendkit sweep`: modes, thermal noise or a transfer function over a grid of parameter
//! values, as CSV against the swept values, with the modes tracked from step to step by
//! the overlap of their shapes (so a mode keeps its number and label through a crossing).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use pendkit::describe::unit_slug;
use pendkit::dynamics::Verdict;
use pendkit::stage::ModeSelection;
use pendkit::{NoiseOptions, Solver};
use pendkit_plot::{Axis, BodePlot, BodeSeries, LinePlot, Scale, Series};

use crate::common::{GridArgs, ModelArgs, Run, check_plot_path, split_pair};
use crate::error::CliError;
use crate::format::{csv, fixed};
use crate::progress::Progress;

// Arguments of `pendkit sweep` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("result").required(true).args(["modes", "noise", "tf"])))]
pub struct Args {
    #[command(flatten)]
    args: ModelArgs,
    /// A parameter and its values: NAME=START:STOP:N (N evenly spaced values, ends
    /// included), or NAME=START:STOP:N:log (log-spaced). Repeatable: every combination,
    /// the last --vary changing fastest; at most 10000 steps in all
    /// (PENDKIT_MAX_SWEEP_STEPS raises it).
    #[arg(long = "vary", required = true, value_name = "NAME=START:STOP:N")]
    vary: Vec<String>,
    /// The normal modes at every step, tracked by shape. Unstable steps are data here:
    /// growing modes are listed at minus their growth rate, and over one --vary the value
    /// where the equilibrium turns unstable (or stable) is found and reported.
    #[arg(long)]
    modes: bool,
    /// With --modes: only the modes of this family at the first step (`P` for pitch, as
    /// `pendkit modes` prints the families), in the table and the figure.
    #[arg(long, value_name = "FAMILY", requires = "modes")]
    family: Option<String>,
    /// The thermal noise (ASD) of this output at every step.
    #[arg(long, value_name = "OUTPUT")]
    noise: Option<String>,
    /// The transfer function INPUT:OUTPUT at every step (e.g. x00:x3, force:x3:x3).
    #[arg(long, value_name = "IN:OUT")]
    tf: Option<String>,
    #[command(flatten)]
    grid: GridArgs,
    /// Write a figure (.svg or .png): tracked mode frequencies against the swept value
    /// (one --vary), or the noise or transfer function of every step.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

/// One swept parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    /// Parameter name.
    pub name: String,
    /// Its values.
    pub values: Vec<f64>,
}

/// Parses `NAME=START:STOP:N[:log]` (1 ≤ N ≤ [`pendkit_limits::SWEEP_STEPS`], checked
/// before the values are made).
pub fn parse_vary(text: &str) -> Result<Vary, CliError> {
    let bad = |why: &str| {
        CliError::usage(format!(
            "--vary '{text}': {why} (expected NAME=START:STOP:N or NAME=START:STOP:N:log)"
        ))
    };
    let (name, range) = text.split_once('=').ok_or_else(|| bad("no '='"))?;
    let parts: Vec<&str> = range.split(':').map(str::trim).collect();
    let log = match parts.len() {
        3 => false,
        4 if parts[3] == "log" => true,
        _ => return Err(bad("wrong number of fields")),
    };
    let number = |t: &str, what: &str| -> Result<f64, CliError> {
        crate::common::number(t).map_err(|e| bad(&format!("{what}: {e}")))
    };
    let (start, stop) = (number(parts[0], "START")?, number(parts[1], "STOP")?);
    let n: usize = parts[2]
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| bad(&format!("N '{}' is not a whole number from 1 up", parts[2])))?;
    pendkit_limits::SWEEP_STEPS
        .check(n)
        .map_err(|source| CliError::Limit {
            what: format!("--vary '{text}'"),
            source,
        })?;
    if log && !(start > 0.0 && stop > 0.0) {
        return Err(bad("log spacing needs START and STOP > 0"));
    }
    let values = (0..n)
        .map(|k| {
            let t = if n == 1 {
                0.0
            } else {
                k as f64 / (n - 1) as f64
            };
            if n > 1 && k + 1 == n {
                // the last value exactly STOP (no rounding); one value is START
                stop
            } else if log {
                (start.ln() + (stop.ln() - start.ln()) * t).exp()
            } else {
                start + (stop - start) * t
            }
        })
        .collect();
    let name = name.trim();
    if name.is_empty() {
        return Err(bad("no parameter name"));
    }
    Ok(Vary {
        name: name.to_string(),
        values,
    })
}

/// The steps of a sweep: every combination of the swept values, the last parameter
/// changing fastest. A step is its index; its point (one value index per swept parameter)
/// and its neighbours are computed from it, not stored.
struct Grid {
    /// The number of values of each swept parameter.
    sizes: Vec<usize>,
    /// How far apart in index two steps are that differ by one value of each parameter.
    strides: Vec<usize>,
    /// The number of steps (checked against [`pendkit_limits::SWEEP_STEPS`]).
    len: usize,
}

impl Grid {
    /// The grid of `varies`, each with at least one value, whose product of sizes has
    /// been checked to fit.
    fn new(varies: &[Vary]) -> Grid {
        let sizes: Vec<usize> = varies.iter().map(|v| v.values.len()).collect();
        let mut strides = vec![1; sizes.len()];
        for d in (0..sizes.len().saturating_sub(1)).rev() {
            strides[d] = strides[d + 1] * sizes[d + 1];
        }
        let len = sizes.iter().product();
        Grid {
            sizes,
            strides,
            len,
        }
    }

    /// The value index of each swept parameter at step `index`.
    fn point(&self, index: usize) -> Vec<usize> {
        self.sizes
            .iter()
            .zip(&self.strides)
            .map(|(&size, &stride)| index / stride % size)
            .collect()
    }

    /// The step a step's modes are matched to: one step back along the last parameter
    /// that is not at its first value (so neighbours always differ by one step of one
    /// parameter). `None` for the first step.
    fn predecessor(&self, index: usize) -> Option<usize> {
        let d = self.point(index).iter().rposition(|&k| k > 0)?;
        Some(index - self.strides[d])
    }

    /// The last step whose predecessor is `index` (`None`: no step continues it), after
    /// which its modes are no longer needed. The steps continuing it are one value further
    /// along a parameter at or after its last that is not at its first value (the
    /// parameters after that are at their first); the furthest is along the first such.
    fn last_use(&self, index: usize) -> Option<usize> {
        let point = self.point(index);
        let from = point.iter().rposition(|&k| k > 0).unwrap_or(0);
        (from..point.len())
            .find(|&d| point[d] + 1 < self.sizes[d])
            .map(|d| index + self.strides[d])
    }
}

/// The modes of one step, for tracking.
struct StepModes {
    frequencies: Vec<f64>,
    labels: Vec<String>,
    families: Vec<String>,
    /// Mass-normalised shapes, one column per mode.
    shapes: DMatrix<f64>,
    mass: DMatrix<f64>,
}

impl StepModes {
    fn of(run: &Run) -> StepModes {
        let modes = &run.result.modes.modes;
        let n = run.result.modes.coordinates.len();
        StepModes {
            frequencies: modes.iter().map(|m| m.hz).collect(),
            labels: modes.iter().map(|m| run.coord(&m.label)).collect(),
            families: modes.iter().map(|m| run.result.mode_family(m)).collect(),
            shapes: DMatrix::from_fn(n, modes.len(), |i, j| {
                modes[j].vector.get(i).copied().unwrap_or(0.0)
            }),
            mass: run.result.assembled.mass.to_dense(),
        }
    }
}

/// Matches the modes of `new` to those of `old` by the overlap of their shapes in the mean
/// mass metric, |u_iᵀ M̄ v_j| / sqrt(u_iᵀ M̄ u_i · v_jᵀ M̄ v_j) with M̄ = (M_old + M_new)/2
/// (1 for the same shape, 0 for shapes that share no kinetic energy): pairs are taken in
/// order of decreasing overlap. Returns, for each mode of `new`, the mode of `old` it
/// continues and their overlap.
pub fn match_modes(
    old_shapes: &DMatrix<f64>,
    old_mass: &DMatrix<f64>,
    new_shapes: &DMatrix<f64>,
    new_mass: &DMatrix<f64>,
) -> Result<Vec<(usize, f64)>, pendkit::Error> {
    Ok(
        pendkit::fit::pair_modes_by_overlap(old_shapes, old_mass, new_shapes, new_mass)?
            .into_iter()
            .enumerate()
            .map(|(j, m)| m.unwrap_or((j, 0.0)))
            .collect(),
    )
}

/// The unit the model declares for parameter `name` (empty if none).
fn parameter_unit(run: &Run, name: &str) -> String {
    run.provenance()
        .ok()
        .and_then(|p| p.parameters.into_iter().find(|q| q.name == name))
        .and_then(|q| q.unit)
        .unwrap_or_default()
}

/// A header column for a swept parameter: its name and unit.
fn parameter_column(run: &Run, name: &str) -> String {
    let unit = parameter_unit(run, name);
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name}_{}", unit_slug(&unit))
    }
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, CliError> {
    check_plot_path(&a.plot)?;
    let varies: Vec<Vary> = a
        .vary
        .iter()
        .map(|t| parse_vary(t))
        .collect::<Result<_, _>>()?;
    check_varies(&a, &varies)?;
    let tf = a.tf.as_deref().map(split_pair).transpose()?;
    let lossy = a.noise.is_some() || tf.is_some();
    if lossy && a.args.stage == Some(pendkit::system::Stage::S0A) {
        return Err(pendkit::Error::StageTooEarly.into());
    }
    let freqs = if lossy {
        a.grid.frequencies()?
    } else {
        Vec::new()
    };
    let grid = Grid::new(&varies);
    if lossy {
        // the table's size is known before the first step: one row per step and frequency
        check_rows(grid.len.checked_mul(freqs.len()))?;
    }
    let progress = Progress::new(
        Some(grid.len as u64),
        format!(
            "sweep {}",
            varies
                .iter()
                .map(|v| v.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let mut out = String::new();
    let mut table = ModeTable::default();
    // for the response figures: (step name, response)
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut unit = String::new();
    let mut x_unit = String::new();
    // per step of a modes sweep: whether the equilibrium is unstable there
    let mut unstable: Vec<bool> = Vec::new();
    for index in 0..grid.len {
        let (values, run, step_name) = step_run(&a, &varies, &grid.point(index))?;
        unstable.push(is_unstable(&run));
        if index == 0 {
            (x_unit, unit) = write_header(&mut out, &a, &varies, &run, tf.as_ref());
        }
        if a.modes {
            if index == 0 {
                // the table's size is known after the first step: one row per step and mode
                check_rows(grid.len.checked_mul(run.result.modes.modes.len()))?;
            }
            table.add(&a, (&grid, index, &step_name), &run, &values, &mut out)?;
        } else {
            let prefix: String = values.iter().map(|x| csv(*x) + ",").collect();
            let response = step_response(&a, &run, tf.as_ref(), &freqs)?;
            write_response_rows(&mut out, &prefix, &freqs, &response, a.noise.is_some());
            // kept only for the figure: a sweep without one holds no response
            if a.plot.is_some() {
                curves.push((step_name, response));
            }
        }
        progress.step();
    }
    drop(progress);
    table.write(&mut out);
    if let Some(family) = &a.family
        && !table.in_family.contains(&true)
    {
        return Err(CliError::usage(format!(
            "--family {family}: no mode of that family at any step (families are those `pendkit modes` prints)"
        )));
    }
    let mut crossings = Vec::new();
    if a.modes && varies.len() == 1 {
        crossings = stability_crossings(&a, &varies[0], &unstable, &x_unit)?;
    }
    if let Some(path) = &a.plot {
        if a.modes {
            plot_modes(path, &varies[0], x_unit, table.series(), &crossings)?;
        } else if a.noise.is_some() {
            plot_noise(
                path,
                a.noise.as_deref().unwrap_or_default(),
                unit,
                &freqs,
                curves,
            )?;
        } else if let Some((input, output)) = &tf {
            plot_transfer(path, input, output, unit, &freqs, curves)?;
        }
    }
    Ok(out)
}

/// The run at one grid point `point`: the swept values set after the --set ones, the
/// equilibrium checked stable. Returns the swept values, the run and the step's name.
fn step_run(
    a: &Args,
    varies: &[Vary],
    point: &[usize],
) -> Result<(Vec<f64>, Run, String), CliError> {
    let mut sets = a.args.sets.clone();
    let values: Vec<f64> = point
        .iter()
        .zip(varies)
        .map(|(&k, v)| v.values[k])
        .collect();
    for (v, value) in varies.iter().zip(&values) {
        sets.push(format!("{}={value:e}", v.name));
    }
    let run = a.args.run_with(ModeSelection::All, &sets, false)?;
    // a modes sweep scans for instability: an unstable step is a result (its growing
    // modes at minus their growth rate), not an error; responses need a stable plant
    if !a.modes {
        run.check_stable(a.args.allow_unstable)?;
    }
    let step_name = varies
        .iter()
        .zip(&values)
        .map(|(v, x)| format!("{}={}", v.name, fixed_or_sci(*x)))
        .collect::<Vec<_>>()
        .join(", ");
    // a step's numbers with a neutral direction say so, with the step's values
    for note in run.neutral_notes() {
        let note = note.strip_prefix("note: ").unwrap_or(&note);
        eprintln!("note: at {step_name}: {note}");
    }
    Ok((values, run, step_name))
}

/// Checks the rows a sweep's table will have (`None`: more than a `usize` holds) against
/// [`pendkit_limits::SWEEP_ROWS`]: the table is held in memory until the sweep ends.
fn check_rows(rows: Option<usize>) -> Result<(), CliError> {
    pendkit_limits::SWEEP_ROWS
        .check_counted(rows)
        .map_err(|source| CliError::Limit {
            what: "sweep".into(),
            source,
        })
}

/// A modes sweep's table as it grows: the modes of the steps still to be continued, the
/// rows, which tracked modes `--family` keeps, and the series of the figure.
#[derive(Default)]
struct ModeTable {
    /// By step index: its modes and the tracked id of each, in the step's order; a step
    /// is dropped once the last step that continues it has been matched to it (a sweep
    /// holds a few steps' shapes and mass matrices, not all of them).
    live: HashMap<usize, (StepModes, Vec<usize>)>,
    /// The labels and families of the first step's modes: the tracked modes' names.
    first: (Vec<String>, Vec<String>),
    /// The labels, families and tracked ids of the last step's modes.
    last: (Vec<String>, Vec<String>, Vec<usize>),
    /// With `--family`: the CSV lines (text, and each line's tracked id and end), written
    /// at the end when it is known which tracked modes the family keeps; without, the
    /// lines go to the output as they come.
    rows: (String, Vec<(usize, usize)>),
    /// Per tracked id: of the `--family` at some step (every mode without one).
    in_family: Vec<bool>,
    /// Per tracked id: (series name, swept values, frequencies), over one `--vary`, with
    /// `--plot`.
    series: Vec<(String, Vec<f64>, Vec<f64>)>,
}

impl ModeTable {
    /// The modes of `run`, the step `index` of `grid` (named `step_name`) at the swept
    /// `values`, tracked from the steps before; its rows go to `out` (or are kept, with
    /// `--family`).
    fn add(
        &mut self,
        a: &Args,
        (grid, index, step_name): (&Grid, usize, &str),
        run: &Run,
        values: &[f64],
        out: &mut String,
    ) -> Result<(), CliError> {
        let modes = StepModes::of(run);
        let previous = grid.predecessor(index);
        // the first step numbers its modes in its own order
        let (step_ids, overlaps) = match previous {
            None => (
                (0..modes.frequencies.len()).collect::<Vec<_>>(),
                vec![1.0; modes.frequencies.len()],
            ),
            Some(q) => {
                let (old, ids) = self.live.get(&q).ok_or_else(|| {
                    CliError::usage(format!(
                        "sweep: the modes of the step before {step_name} were not kept (a bug in pendkit: please report it)"
                    ))
                })?;
                track(old, ids, &modes, step_name)?
            }
        };
        // the step before is done with when this was the last step to continue it
        if let Some(q) = previous
            && grid.last_use(q) == Some(index)
        {
            self.live.remove(&q);
        }
        if index == 0 {
            self.first = (modes.labels.clone(), modes.families.clone());
        }
        let prefix: String = values.iter().map(|x| csv(*x) + ",").collect();
        let first = &self.first;
        let mut order: Vec<(usize, usize)> = step_ids
            .iter()
            .copied()
            .enumerate()
            .map(|(j, id)| (id, j))
            .collect();
        order.sort();
        for (id, j) in order {
            // --family keeps a tracked mode that is of the family at any step (a mode can
            // change family where it meets another, as a soft pitch mode meeting a
            // longitudinal one does)
            if self.in_family.len() <= id {
                self.in_family.resize(id + 1, false);
            }
            self.in_family[id] |= a.family.as_ref().is_none_or(|f| modes.families[j] == *f);
            // a step's modes are as many as the first step's (checked by `track`)
            let (label, family) = (&first.0[id], &first.1[id]);
            let target = if a.family.is_some() {
                &mut self.rows.0
            } else {
                &mut *out
            };
            let _ = writeln!(
                target,
                "{prefix}{},{label},{family},{},{},{}",
                id + 1,
                csv(modes.frequencies[j]),
                modes.labels[j],
                fixed(overlaps[j], 6, 0)
            );
            if a.family.is_some() {
                self.rows.1.push((id, self.rows.0.len()));
            }
            if a.plot.is_some() && values.len() == 1 {
                let name = format!("{} {label} ({family})", id + 1);
                extend_series(&mut self.series, id, name, values[0], modes.frequencies[j]);
            }
        }
        self.last = (
            modes.labels.clone(),
            modes.families.clone(),
            step_ids.clone(),
        );
        if grid.last_use(index).is_some() {
            self.live.insert(index, (modes, step_ids));
        }
        Ok(())
    }

    /// The rows of the modes `--family` keeps, in step order (without `--family` they are
    /// written already).
    fn write(&self, out: &mut String) {
        let (text, ends) = &self.rows;
        let mut start = 0;
        for &(id, end) in ends {
            if self.in_family[id] {
                out.push_str(&text[start..end]);
            }
            start = end;
        }
    }

    /// The figure's series of the modes `--family` keeps, each named at its first and
    /// last steps.
    fn series(self) -> Vec<(String, Vec<f64>, Vec<f64>)> {
        let (last, in_family) = (self.last, self.in_family);
        self.series
            .into_iter()
            .enumerate()
            .filter(|(id, _)| in_family.get(*id).copied().unwrap_or(false))
            .map(|(id, (name, x, y))| (last_label(&last, id, name), x, y))
            .collect()
    }
}

/// Adds mode `id`'s frequency `hz` at swept value `x` to its series of the mode figure,
/// called `name` (after the mode at the first step).
fn extend_series(
    mode_series: &mut Vec<(String, Vec<f64>, Vec<f64>)>,
    id: usize,
    name: String,
    x: f64,
    hz: f64,
) {
    if mode_series.len() <= id {
        mode_series.resize(id + 1, (String::new(), Vec::new(), Vec::new()));
    }
    let series = &mut mode_series[id];
    series.0 = name;
    series.1.push(x);
    series.2.push(hz);
}

/// One CSV row per frequency after the step's `prefix`: the ASD alone (`asd`), else the
/// real and imaginary parts.
fn write_response_rows(
    out: &mut String,
    prefix: &str,
    freqs: &[f64],
    response: &[(f64, f64)],
    asd: bool,
) {
    for (f, (re, im)) in freqs.iter().zip(response) {
        if asd {
            let _ = writeln!(out, "{prefix}{},{}", csv(*f), csv(*re));
        } else {
            let _ = writeln!(out, "{prefix}{},{},{}", csv(*f), csv(*re), csv(*im));
        }
    }
}

/// The tracked id of each of `modes` (the step named `step_name`) and its overlap with the
/// mode it continues: matched by shape to the modes of the step before it (`old`, their
/// tracked ids `ids`).
fn track(
    old: &StepModes,
    ids: &[usize],
    modes: &StepModes,
    step_name: &str,
) -> Result<(Vec<usize>, Vec<f64>), CliError> {
    if old.shapes.nrows() != modes.shapes.nrows() || old.shapes.ncols() != modes.shapes.ncols() {
        return Err(CliError::usage(format!(
            "sweep: the model's variables change at {step_name}; modes can only be tracked over a fixed set of variables"
        )));
    }
    let matched = match_modes(&old.shapes, &old.mass, &modes.shapes, &modes.mass)?;
    Ok((
        matched.iter().map(|&(i, _)| ids[i]).collect(),
        matched.iter().map(|&(_, o)| o).collect(),
    ))
}

/// What the sweep is for at one step, at every frequency: the noise ASD (with 0 beside it)
/// or the transfer function (real, imaginary), or nothing when sweeping modes.
fn step_response(
    a: &Args,
    run: &Run,
    tf: Option<&(String, String)>,
    freqs: &[f64],
) -> Result<Vec<(f64, f64)>, CliError> {
    // the stability was checked (or let through by --allow-unstable) when the step ran
    Ok(if let Some(output) = &a.noise {
        let noise = run
            .result
            .noise_with(output, freqs, &NoiseOptions::default())?;
        noise.asd().into_iter().map(|x| (x, 0.0)).collect()
    } else if let Some((input, output)) = tf {
        run.result
            .transfer_with(input, output, freqs, Solver::Restricted)?
            .into_iter()
            .map(|z| (z.re, z.im))
            .collect()
    } else {
        Vec::new()
    })
}

/// Refuses a sweep the table could not state truthfully or that is past its limit: more
/// than [`pendkit_limits::SWEEP_STEPS`] steps, a parameter swept twice or swept and also
/// set, or a mode plot over more than one parameter.
fn check_varies(a: &Args, varies: &[Vary]) -> Result<(), CliError> {
    let steps = varies
        .iter()
        .try_fold(1usize, |n, v| n.checked_mul(v.values.len()));
    pendkit_limits::SWEEP_STEPS
        .check_counted(steps)
        .map_err(|source| CliError::Limit {
            what: format!(
                "--vary: {} combinations in all",
                varies
                    .iter()
                    .map(|v| v.values.len().to_string())
                    .collect::<Vec<_>>()
                    .join(" x ")
            ),
            source,
        })?;
    // a parameter swept twice, or swept and also set, would take only the last value
    // given while the table's columns claim the others
    for (k, v) in varies.iter().enumerate() {
        if varies[..k].iter().any(|w| w.name == v.name) {
            return Err(CliError::usage(format!(
                "--vary: '{}' is swept twice: sweep each parameter once",
                v.name
            )));
        }
        let set_name = |s: &String| s.split_once('=').map(|(n, _)| n.trim().to_string());
        if a.args.sets.iter().filter_map(set_name).any(|n| n == v.name) {
            return Err(CliError::usage(format!(
                "--vary: '{}' is swept and also given by --set: the sweep would replace the --set",
                v.name
            )));
        }
    }
    if a.modes && a.plot.is_some() && varies.len() != 1 {
        return Err(CliError::usage(
            "--plot with --modes draws frequencies against one swept parameter: give one --vary",
        ));
    }
    Ok(())
}

/// Writes the CSV header: a column per swept parameter (with its unit), then the columns
/// of what is swept for. Returns the first swept parameter's unit and the unit of the noise
/// or transfer function (empty for modes), for the figure's axes.
fn write_header(
    out: &mut String,
    a: &Args,
    varies: &[Vary],
    run: &Run,
    tf: Option<&(String, String)>,
) -> (String, String) {
    let mut unit = String::new();
    let columns: Vec<String> = varies
        .iter()
        .map(|v| parameter_column(run, &v.name))
        .collect();
    out.push_str(&columns.join(","));
    let x_unit = parameter_unit(run, &varies[0].name);
    if a.modes {
        out.push_str(",mode,label,family,frequency_hz,dominant,overlap\n");
    } else if let Some(output) = &a.noise {
        unit = format!("{}/√Hz", run.result.output_unit(output).unwrap_or_default());
        let _ = writeln!(out, ",f_hz,asd_{}", unit_slug(&unit));
    } else if let Some((input, output)) = tf {
        unit = run.result.transfer_unit(input, output).unwrap_or_default();
        let slug = unit_slug(&unit);
        let _ = writeln!(out, ",f_hz,re_{slug},im_{slug}");
    }
    (x_unit, unit)
}

/// The tracked mode frequencies against the one swept parameter `v` (in `x_unit`), one
/// series (name, values, frequencies) per mode.
fn plot_modes(
    path: &Path,
    v: &Vary,
    x_unit: String,
    mode_series: Vec<(String, Vec<f64>, Vec<f64>)>,
    crossings: &[Crossing],
) -> Result<(), CliError> {
    let values = || mode_series.iter().flat_map(|s| s.2.iter().copied());
    // a growing mode is drawn at minus its growth rate, which a log axis cannot show
    let scale = if values().all(|y| y > 0.0) {
        Scale::Log
    } else {
        Scale::Linear
    };
    let (low, high) = values().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| {
        (l.min(y), h.max(y))
    });
    let mut plot = LinePlot::new(
        format!("Modes against {}", v.name),
        Axis::new(v.name.clone(), x_unit, Scale::Linear),
        Axis::new("frequency (growth rate < 0)", "Hz", scale),
    );
    plot.markers = v.values.len() <= 30;
    for (name, x, y) in mode_series {
        plot.series.push(Series::new(name, x, y));
    }
    for c in crossings {
        plot.series.push(Series::new(
            c.describe_short(&v.name),
            vec![c.value, c.value],
            vec![low, high],
        ));
    }
    crate::plotting::save(&plot, path)?;
    Ok(())
}

/// The ASD of `output` (in `unit`) at every step, one curve per step.
fn plot_noise(
    path: &Path,
    output: &str,
    unit: String,
    freqs: &[f64],
    curves: Vec<(String, Vec<(f64, f64)>)>,
) -> Result<(), CliError> {
    let mut plot = LinePlot::new(
        format!("Thermal noise of {output}"),
        Axis::new("frequency", "Hz", Scale::Log),
        Axis::new("ASD", unit, Scale::Log),
    );
    for (name, values) in curves {
        plot.series.push(Series::new(
            name,
            freqs.to_vec(),
            values.into_iter().map(|(x, _)| x).collect(),
        ));
    }
    crate::plotting::save(&plot, path)?;
    Ok(())
}

/// The transfer function `input` to `output` (in `unit`) at every step, one Bode curve per
/// step.
fn plot_transfer(
    path: &Path,
    input: &str,
    output: &str,
    unit: String,
    freqs: &[f64],
    curves: Vec<(String, Vec<(f64, f64)>)>,
) -> Result<(), CliError> {
    let mut plot = BodePlot::new(
        format!("{output}/{input} over the sweep"),
        format!("|{output}/{input}|"),
        unit,
    );
    for (name, values) in curves {
        plot.series
            .push(BodeSeries::new(name, freqs.to_vec(), values));
    }
    crate::plotting::save(&plot, path)?;
    Ok(())
}

/// A swept value for a legend: a few significant digits.
fn fixed_or_sci(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) {
        crate::format::sci(x, 3, 0)
    } else {
        format!("{}", (x * 1e6).round() / 1e6)
    }
}

/// A mode series' name (`id label (family)` at the first step) with the label and family
/// at the last step (`last`: its labels, families and tracked ids) added when they differ:
/// `1 itm_x3 (L) → itm_pitch3 (P)`.
fn last_label(last: &(Vec<String>, Vec<String>, Vec<usize>), id: usize, name: String) -> String {
    let (labels, families, ids) = last;
    let last = ids
        .iter()
        .position(|&i| i == id)
        .map(|j| format!("{} ({})", labels[j], families[j]));
    match last {
        Some(end) if !name.ends_with(&end) => format!("{name} → {end}"),
        _ => name,
    }
}

/// Whether the equilibrium of `run` is unstable (a mode grows or a float runs away).
fn is_unstable(run: &Run) -> bool {
    run.result.stability.verdict == Verdict::Unstable
}

/// The most negative ω² (rad²/s²) among the modes of `run`: it crosses zero where a mode
/// starts to grow.
fn lowest_omega_squared(run: &Run) -> f64 {
    run.result
        .modes
        .modes
        .iter()
        .map(|m| m.omega_squared)
        .fold(f64::INFINITY, f64::min)
}

/// Where the equilibrium changes from stable to unstable (or back) along one swept
/// parameter.
#[derive(Clone, Debug)]
struct Crossing {
    /// The parameter's value there.
    value: f64,
    /// Unstable above `value` (else below it).
    unstable_above: bool,
    /// The mode that grows on the unstable side: its label and family.
    mode: String,
    /// The parameter's unit.
    unit: String,
}

impl Crossing {
    /// `unstable above power = 3.1e5 W`, for the figure.
    fn describe_short(&self, name: &str) -> String {
        format!(
            "unstable {} {name} = {} {}",
            if self.unstable_above {
                "above"
            } else {
                "below"
            },
            crate::format::sci(self.value, 6, 0),
            self.unit
        )
    }
}

/// Bisections of the verdict to a relative 1e-9 of the swept range, at most.
const BISECTIONS: usize = 60;

/// Each place along the one swept parameter `v` where the verdict changes between
/// neighbouring steps (`unstable`, one per value): the verdict is bisected between the two
/// steps, then the growing mode's ω² is interpolated to zero between the last two values
/// (the growth rate's zero crossing). Reported on stderr, with a line when there is none.
fn stability_crossings(
    a: &Args,
    v: &Vary,
    unstable: &[bool],
    unit: &str,
) -> Result<Vec<Crossing>, CliError> {
    let run_at = |x: f64| -> Result<Run, CliError> {
        let mut sets = a.args.sets.clone();
        sets.push(format!("{}={x:e}", v.name));
        a.args.run_with(ModeSelection::All, &sets, false)
    };
    let width = (v.values[v.values.len() - 1] - v.values[0]).abs();
    let mut crossings = Vec::new();
    for k in 1..v.values.len() {
        if unstable[k] == unstable[k - 1] {
            continue;
        }
        // stable at `lo`, unstable at `hi`
        let (mut lo, mut hi) = if unstable[k] {
            (v.values[k - 1], v.values[k])
        } else {
            (v.values[k], v.values[k - 1])
        };
        let (mut lo_run, mut hi_run) = (run_at(lo)?, run_at(hi)?);
        for _ in 0..BISECTIONS {
            if (hi - lo).abs() <= 1e-9 * width {
                break;
            }
            let mid = 0.5 * (lo + hi);
            let run = run_at(mid)?;
            if is_unstable(&run) {
                (hi, hi_run) = (mid, run);
            } else {
                (lo, lo_run) = (mid, run);
            }
        }
        let (w_lo, w_hi) = (lowest_omega_squared(&lo_run), lowest_omega_squared(&hi_run));
        let value = if w_lo > 0.0 && w_hi < 0.0 {
            lo + (hi - lo) * w_lo / (w_lo - w_hi)
        } else {
            // the verdict turned on something other than a mode (a float), or on a
            // neutral mode: the bisected bracket is the answer
            0.5 * (lo + hi)
        };
        let mode = hi_run
            .result
            .stability
            .growing
            .first()
            .and_then(|g| hi_run.result.modes.modes.get(g.index - 1))
            .map_or("a float direction".to_string(), |m| {
                format!(
                    "mode '{}' ({})",
                    hi_run.coord(&m.label),
                    hi_run.result.mode_family(m)
                )
            });
        crossings.push(Crossing {
            value,
            unstable_above: hi > lo,
            mode,
            unit: unit.to_string(),
        });
    }
    let range = format!(
        "{} from {} to {} {unit}",
        v.name,
        fixed_or_sci(v.values[0]),
        fixed_or_sci(v.values[v.values.len() - 1])
    );
    if crossings.is_empty() {
        let state = if unstable.iter().all(|&u| u) {
            "unstable at every step"
        } else {
            "stable at every step: no instability"
        };
        eprintln!("sweep: {state} for {range}");
    }
    for c in &crossings {
        eprintln!(
            "sweep: the equilibrium is {} at {} = {} {unit}: {} grows {} it (the verdict bisected between the steps, then the mode's ω² interpolated to zero)",
            if c.unstable_above {
                "stable below and unstable above"
            } else {
                "unstable below and stable above"
            },
            v.name,
            crate::format::sci(c.value, 6, 0),
            c.mode,
            if c.unstable_above { "above" } else { "below" },
        );
    }
    Ok(crossings)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_ranges_and_errors() {
        let v = parse_vary("m3=10:20:3").unwrap();
        assert_eq!((v.name.as_str(), v.values), ("m3", vec![10.0, 15.0, 20.0]));
        let v = parse_vary("r=1e-4:1e-2:3:log").unwrap();
        assert!((v.values[1] - 1e-3).abs() < 1e-15 && v.values[2] == 1e-2);
        assert_eq!(parse_vary("x=2:3:1").unwrap().values, vec![2.0]);
        for bad in [
            "m3",
            "m3=1:2",
            "m3=1:2:0",
            "m3=a:2:3",
            "m3=1:inf:3",
            "m3=0:1:3:log",
            "=1:2:3",
        ] {
            let e = parse_vary(bad).unwrap_err().to_string();
            assert!(e.contains(bad) && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn grid_neighbours_differ_by_one_step_of_one_parameter() {
        let varies = [
            Vary {
                name: "a".into(),
                values: vec![1.0, 2.0, 3.0],
            },
            Vary {
                name: "b".into(),
                values: vec![1.0, 2.0],
            },
        ];
        let grid = Grid::new(&varies);
        assert_eq!(grid.len, 6);
        assert_eq!(grid.point(1), vec![0, 1]);
        assert_eq!(grid.point(4), vec![2, 0]);
        for p in 1..grid.len {
            let q = grid.predecessor(p).unwrap();
            assert!(q < p);
            let steps: usize = grid
                .point(p)
                .iter()
                .zip(&grid.point(q))
                .map(|(a, b)| a.abs_diff(*b))
                .sum();
            assert_eq!(steps, 1, "{:?} from {:?}", grid.point(p), grid.point(q));
        }
        assert_eq!(grid.predecessor(0), None);
    }

    #[test]
    fn a_step_is_kept_exactly_until_the_last_step_that_continues_it() {
        let vary = |n: usize| Vary {
            name: "p".into(),
            values: vec![0.0; n],
        };
        for sizes in [
            vec![5],
            vec![3, 2],
            vec![2, 3, 4],
            vec![1, 4],
            vec![4, 1, 3],
        ] {
            let varies: Vec<Vary> = sizes.iter().map(|&n| vary(n)).collect();
            let grid = Grid::new(&varies);
            for q in 0..grid.len {
                // every later step, asked whom it continues
                let last = (0..grid.len)
                    .filter(|&p| grid.predecessor(p) == Some(q))
                    .max();
                assert_eq!(grid.last_use(q), last, "{sizes:?} step {q}");
            }
        }
    }

    #[test]
    fn matching_follows_shapes_not_order() {
        // two modes that swap order: the shapes (columns) are the same up to sign, listed
        // the other way round; the mass metric is diagonal and different at the two steps
        let old = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.5]);
        let new = DMatrix::from_row_slice(2, 2, &[0.0, 0.9, -0.4, 0.0]);
        let m_old = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 4.0]);
        let m_new = DMatrix::from_row_slice(2, 2, &[1.2, 0.0, 0.0, 5.0]);
        let matched = match_modes(&old, &m_old, &new, &m_new).unwrap();
        assert_eq!(matched[0].0, 1);
        assert_eq!(matched[1].0, 0);
        assert!((matched[0].1 - 1.0).abs() < 1e-15 && (matched[1].1 - 1.0).abs() < 1e-15);
    }
}
