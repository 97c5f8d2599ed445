//! Fitting a model to measured mode frequencies (and optionally |TF| points): which model
//! mode each measurement is (by label and shape, then tracked by shape overlap), a
//! Levenberg–Marquardt fit of chosen parameters weighted by the stated uncertainties, the
//! covariance of the result, and the parameter combinations the data cannot determine.
//!
//! # Measured modes file
//!
//! CSV, one mode a line: `label,hz,sigma_hz[,shape]`. Blank lines and lines starting with
//! `#` are skipped; a first line starting with `label` is a header.
//! - `label`: the model mode it is, as `pendkit modes` prints it: its label (the dominant
//!   coordinate, e.g. `pitch2`) or its family (`L`, `T`, `V`, `Y`, `P`, `R`, ...), in the
//!   model's names or a naming scheme's (`L2_P`).
//! - `hz`: the measured frequency (Hz, positive); `sigma_hz`: its standard uncertainty
//!   (Hz, positive, and not below the rounding of `hz`: 2.2·10⁻¹⁶ of it).
//! - `shape` (optional): more coordinates the mode mostly moves, joined by `+`
//!   (`yaw1+yaw3`); needed with a family label.
//!
//! All measurements are matched at once to distinct model modes (at the start values) by
//! optimal assignment: a mode with at least 10 % of its kinetic energy in the coordinates
//! a measurement's label and shape name (each once, in any order), within a factor
//! [`FitOptions::frequency_window`] in frequency, the sum of the distances in log
//! frequency less the shares as small as it can be ([`MatchedModes::by_label_within`]).
//! From then on each matched mode is followed by the overlap of its shape
//! ([`MatchedModes::follow`]), so that modes that cross in frequency keep their identity.
//!
//! # Measured transfer-function file
//!
//! CSV `freq_hz,abs,sigma_abs` (|TF| in the unit of the transfer function, e.g. m/m, and
//! its standard uncertainty, not below the rounding of `abs`), with the input and output
//! named in two comment lines before the data, each once: `# input = x00` and
//! `# output = x3` (any name `pendkit tf` takes).
//!
//! # The fit
//!
//! Residuals are (model − measured)/σ. The free parameters are stepped in units of their
//! start values (|p₀|, or 1 for a parameter that starts at 0), so that a kilogram and a
//! micrometre weigh alike. Each step is a damped, truncated-SVD Gauss–Newton step
//! (Levenberg's damping in the scaled parameters): directions of the weighted Jacobian
//! whose singular value is below [`FitOptions::undetermined_below`] times the largest are
//! not stepped in, and are reported as undetermined combinations. Uncertainties are the
//! square roots of the diagonal of the covariance (JᵀWJ)⁺ on the determined directions,
//! *not* scaled by χ²/dof: they are what the stated σ imply; the reduced χ² says whether
//! the σ and the model agree with the scatter.
//!
//! A step that would leave a parameter's declared domain stops nine tenths of the way to
//! its edge. A descent that stalls, or ends where it cannot explain its data, starts again
//! from where it got to, its measurements matched afresh (up to three times). The result's
//! verdict, [`FitResult::explains_data`], is χ²/dof ≤
//! [`FitOptions::max_reduced_chi_squared`]: a fit that misses its data by more determines
//! nothing.
//!
//! # The Jacobian
//!
//! The modes' rows are the exact sensitivities by default ([`exact_mode_jacobian`]: the
//! implicit function theorem through the equilibrium and Hellmann–Feynman through the
//! eigenproblem, [`crate::sensitivity::sensitivities`]), one stage solution and no step per iteration;
//! [`JacobianMethod::Differences`] takes central differences of the re-solved model
//! instead ([`mode_jacobian`], two solutions per free parameter, the modes followed by
//! shape at each step). The |TF| points' rows come with the exact Jacobian from the same
//! sensitivities (the stage's matrices differenced, everything after them exact: a point
//! on a sharp resonance gets its true derivative), with `Differences` from central
//! differences of |H| (which, on a resonance whose width the step moves the peak by a
//! fraction of, are far off: −62 367 against −127 602 m/m per kg for the quad's |x3/x00|
//! at its x3 mode and m3, with the relative step 10⁻⁴).

use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector};
use pendkit_params::Domain;
use pendkit_system::Stage;

use crate::{Case, Error, StageResult, run_stage};

/// What can go wrong reading measurements or fitting; each message is one line.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// A line of a measurements file that is not valid.
    #[error("{}:{line}: {message}", .path.display())]
    Line {
        /// The file.
        path: PathBuf,
        /// Its line (from 1).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A measurements file that cannot be read, or says nothing.
    #[error("{}: {message}", .path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A free parameter the model does not have, or listed twice.
    #[error("free parameter '{name}': {message}")]
    Parameter {
        /// The parameter.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// Fewer measurements than free parameters plus one.
    #[error(
        "{measurements} measurements for {free} free parameters: need at least one more measurement than free parameters"
    )]
    TooFewMeasurements {
        /// Measurements (modes and TF points).
        measurements: usize,
        /// Free parameters.
        free: usize,
    },
    /// A measured mode that no model mode matches, or that two measurements claim.
    #[error("{}:{line}: {message}", .path.display())]
    Unmatched {
        /// The measurements file.
        path: PathBuf,
        /// The measurement's line.
        line: usize,
        /// What is wrong, with the model's modes.
        message: String,
    },
    /// The model cannot be solved at the start values.
    #[error("the model at the start values: {0}")]
    Start(Box<Error>),
    /// The fit did not converge.
    #[error(
        "{}: the fit did not converge in {iterations} iterations (chi^2 = {chi_squared:.6e}, last values: {values}; damping {damping:.1e}){at_edge}",
        .path.display()
    )]
    NotConverged {
        /// The measured modes file fitted to.
        path: PathBuf,
        /// Iterations made.
        iterations: usize,
        /// χ² at the last accepted values.
        chi_squared: f64,
        /// The last accepted values, `name=value` joined by spaces.
        values: String,
        /// Levenberg damping reached.
        damping: f64,
        /// The free parameters pressed against the edge of their declared domain (the
        /// data ask for a value outside it), as `"; d4 = 0.17 is at the edge of its domain
        /// in (-0.17, 0.17): ..."`; empty when none is.
        at_edge: String,
    },
    /// A model value that came out NaN or infinite.
    #[error("{0} is not finite")]
    NotFinite(String),
}

/// One measured mode.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MeasuredMode {
    /// The model mode it is: a mode label (dominant coordinate) or family.
    pub label: String,
    /// Measured frequency (Hz).
    pub hz: f64,
    /// Its standard uncertainty (Hz).
    pub sigma_hz: f64,
    /// Coordinates the mode mostly moves (may be empty).
    pub shape: Vec<String>,
    /// Line in the file (from 1), for messages.
    pub line: usize,
}

/// Measured modes and where they come from.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredModes {
    /// The file (names the errors).
    pub path: PathBuf,
    /// The modes, in file order.
    pub modes: Vec<MeasuredMode>,
}

/// One measured point of |TF|.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TfPoint {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Measured |TF| (the transfer function's unit).
    pub abs: f64,
    /// Its standard uncertainty (same unit).
    pub sigma_abs: f64,
    /// Its line in the file (from 1; names the errors).
    #[serde(skip)]
    pub line: usize,
}

/// A measured transfer-function magnitude.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredTf {
    /// The file (names the errors).
    pub path: PathBuf,
    /// Input name (as `pendkit tf` takes it).
    pub input: String,
    /// Output name.
    pub output: String,
    /// The points, in file order.
    pub points: Vec<TfPoint>,
}

/// `text` without a UTF-8 byte-order mark (which spreadsheet programs write at the start
/// of a CSV file, and which made line 1's label or number unreadable).
fn without_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The data lines of a CSV measurements file: (line number, fields), comments and blank
/// lines skipped, a header starting with `header` skipped. Line ends may be LF or CRLF,
/// and fields may have spaces around them.
fn data_lines<'a>(text: &'a str, header: &str) -> Vec<(usize, Vec<&'a str>)> {
    let mut lines = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if lines.is_empty() && line.starts_with(header) {
            continue;
        }
        lines.push((k + 1, line.split(',').map(str::trim).collect()));
    }
    lines
}

/// A field that must be a positive finite number.
fn positive(field: &str, what: &str) -> Result<f64, String> {
    use pendkit_expr::NumberError;
    let x = pendkit_expr::number_literal(field).map_err(|e| match e {
        NumberError::NotANumber(_) => format!("{what} '{field}' is not a number"),
        NumberError::NotFinite(_) => {
            format!("{what} must be positive and finite, got {field}")
        }
        // a literal an f64 cannot hold, named as such (1e-400 is not 0)
        too_small_or_large => format!("{what}: {too_small_or_large}"),
    })?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{what} must be positive and finite, got {field}"))
    }
}

/// A standard uncertainty: positive, finite, and not below the rounding of the value it
/// belongs to (a smaller one asks the fit to resolve differences an `f64` cannot hold, and
/// its weight 1/σ² can overflow).
fn uncertainty(field: &str, what: &str, value: f64, value_name: &str) -> Result<f64, String> {
    let sigma = positive(field, what)?;
    if sigma < value * f64::EPSILON {
        return Err(format!(
            "{what} = {field} is below the rounding of {value_name} = {} (relative {:.1e}, \
             an f64 resolves {:.1e})",
            pendkit_expr::number_text(value),
            sigma / value,
            f64::EPSILON
        ));
    }
    Ok(sigma)
}

/// An error at a line of the file at `path`.
fn line_error(path: &Path) -> impl Fn(usize, String) -> FitError + '_ {
    move |line, message| FitError::Line {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// The text of a measured-data file: a regular file within the input-file size limit
/// (`pendkit_limits::read_text`).
fn read_text(path: &Path) -> Result<String, FitError> {
    pendkit_limits::read_text(path).map_err(|e| FitError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// The data rows of a measured-data file within [`pendkit_limits::MEASURED_ROWS`]; past it
/// (every row costs a model evaluation at every iteration), an error at the first row
/// beyond.
fn within_row_limit(path: &Path, rows: &[(usize, Vec<&str>)]) -> Result<(), FitError> {
    let limit = &pendkit_limits::MEASURED_ROWS;
    limit.check(rows.len()).map_err(|e| {
        let max = limit.value().unwrap_or(0);
        FitError::Line {
            path: path.to_path_buf(),
            line: rows.get(max).map_or(0, |row| row.0),
            message: e.to_string(),
        }
    })
}

impl MeasuredModes {
    /// Every mode of `modes` as a noise-free measurement, as a commissioner would write
    /// it: labelled by its dominant coordinate, its `shape` the three coordinates with the
    /// largest shares of its kinetic energy, σ = `relative_sigma` × its frequency (Hz).
    /// Rows are numbered from 2 (after a header) in the errors of `path`. For planning a
    /// measurement (which parameters would the modes determine?) and for testing fits
    /// against a model whose truth is known.
    pub fn of_modes(path: &Path, modes: &pendkit_dynamics::Modes, relative_sigma: f64) -> Self {
        let measured = modes
            .modes
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let mut order: Vec<usize> = (0..m.energy_fractions.len()).collect();
                order.sort_by(|&a, &b| m.energy_fractions[b].total_cmp(&m.energy_fractions[a]));
                MeasuredMode {
                    label: m.label.clone(),
                    hz: m.hz,
                    sigma_hz: relative_sigma * m.hz,
                    shape: order
                        .iter()
                        .take(3)
                        .map(|&c| modes.coordinates[c].clone())
                        .collect(),
                    line: k + 2,
                }
            })
            .collect();
        MeasuredModes {
            path: path.to_path_buf(),
            modes: measured,
        }
    }

    /// Reads a measured modes file (see the [module documentation](self)).
    pub fn read(path: &Path) -> Result<MeasuredModes, FitError> {
        MeasuredModes::parse(path, &read_text(path)?)
    }

    /// Parses the text of a measured modes file read from `path`.
    pub fn parse(path: &Path, text: &str) -> Result<MeasuredModes, FitError> {
        let text = without_bom(text);
        let rows = data_lines(text, "label");
        within_row_limit(path, &rows)?;
        let modes = rows
            .into_iter()
            .map(|(line, fields)| MeasuredMode::from_fields(path, line, &fields))
            .collect::<Result<Vec<_>, _>>()?;
        MeasuredModes::new(path, modes)
    }

    /// Measured modes given as rows of fields `label, hz, sigma_hz[, shape]` (as a
    /// program holds them, not as text: no comments or header; row k is named line k + 1
    /// of `path` in the errors), checked as a file's lines are.
    pub fn from_rows<S: AsRef<str>>(
        path: &Path,
        rows: &[Vec<S>],
    ) -> Result<MeasuredModes, FitError> {
        let modes = rows
            .iter()
            .enumerate()
            .map(|(k, row)| {
                let fields: Vec<&str> = row.iter().map(|f| f.as_ref().trim()).collect();
                MeasuredMode::from_fields(path, k + 1, &fields)
            })
            .collect::<Result<Vec<_>, _>>()?;
        MeasuredModes::new(path, modes)
    }

    fn new(path: &Path, modes: Vec<MeasuredMode>) -> Result<MeasuredModes, FitError> {
        if modes.is_empty() {
            return Err(FitError::File {
                path: path.to_path_buf(),
                message: "no measured modes (expected lines label,hz,sigma_hz[,shape])".into(),
            });
        }
        Ok(MeasuredModes {
            path: path.to_path_buf(),
            modes,
        })
    }
}

impl MeasuredMode {
    /// One measured mode from its fields `label, hz, sigma_hz[, shape]` at `line` of `path`.
    fn from_fields(path: &Path, line: usize, fields: &[&str]) -> Result<MeasuredMode, FitError> {
        let at = |message| FitError::Line {
            path: path.to_path_buf(),
            line,
            message,
        };
        if !(3..=4).contains(&fields.len()) {
            return Err(at(format!(
                "expected label,hz,sigma_hz[,shape], got {} fields",
                fields.len()
            )));
        }
        let label = fields[0];
        if label.is_empty() {
            return Err(at("empty label".into()));
        }
        let hz = positive(fields[1], "hz").map_err(at)?;
        let sigma_hz = uncertainty(fields[2], "sigma_hz", hz, "hz").map_err(at)?;
        let shape: Vec<String> = match fields.get(3) {
            Some(s) if !s.is_empty() => s.split('+').map(|c| c.trim().to_string()).collect(),
            _ => Vec::new(),
        };
        if shape.iter().any(String::is_empty) {
            return Err(at(
                "shape: coordinates joined by '+' (e.g. yaw1+yaw3)".into()
            ));
        }
        Ok(MeasuredMode {
            label: label.to_string(),
            hz,
            sigma_hz,
            shape,
            line,
        })
    }
}

impl MeasuredTf {
    /// Reads a measured transfer-function file (see the [module documentation](self)).
    pub fn read(path: &Path) -> Result<MeasuredTf, FitError> {
        MeasuredTf::parse(path, &read_text(path)?)
    }

    /// Parses the text of a measured transfer-function file read from `path`.
    pub fn parse(path: &Path, text: &str) -> Result<MeasuredTf, FitError> {
        let text = without_bom(text);
        let at = line_error(path);
        let data = data_lines(text, "freq_hz");
        within_row_limit(path, &data)?;
        let first_data = data.first().map(|(line, _)| *line);
        // (value, line) of the `# input = ...` and `# output = ...` lines: each once, before
        // the data (a second one, or one among the points, is not silently obeyed)
        let mut input: Option<(String, usize)> = None;
        let mut output: Option<(String, usize)> = None;
        for (k, raw) in text.lines().enumerate() {
            let line = k + 1;
            let directive = raw.trim().strip_prefix('#').map(str::trim);
            let Some((key, value)) = directive.and_then(|d| d.split_once('=')) else {
                continue;
            };
            let key = key.trim();
            let slot = match key {
                "input" => &mut input,
                "output" => &mut output,
                _ => continue,
            };
            if let Some((_, first)) = slot {
                return Err(at(
                    line,
                    format!("a second '# {key} = NAME' line (the first is line {first})"),
                ));
            }
            if let Some(data) = first_data.filter(|&data| line > data) {
                return Err(at(
                    line,
                    format!(
                        "'# {key} = NAME' after the data (line {data}): it goes before the points"
                    ),
                ));
            }
            let value = value.trim();
            if value.is_empty() {
                return Err(at(line, format!("'# {key} =' names no {key}")));
            }
            *slot = Some((value.to_string(), line));
        }
        let mut points = Vec::new();
        for (line, fields) in data {
            if fields.len() != 3 {
                return Err(at(
                    line,
                    format!(
                        "expected freq_hz,abs,sigma_abs, got {} fields",
                        fields.len()
                    ),
                ));
            }
            let abs = positive(fields[1], "abs").map_err(|m| at(line, m))?;
            points.push(TfPoint {
                freq_hz: positive(fields[0], "freq_hz").map_err(|m| at(line, m))?,
                abs,
                sigma_abs: uncertainty(fields[2], "sigma_abs", abs, "abs")
                    .map_err(|m| at(line, m))?,
                line,
            });
        }
        let missing = |what: &str| FitError::File {
            path: path.to_path_buf(),
            message: format!("no '# {what} = NAME' line before the data"),
        };
        let (input, _) = input.ok_or_else(|| missing("input"))?;
        let (output, _) = output.ok_or_else(|| missing("output"))?;
        if points.is_empty() {
            return Err(FitError::File {
                path: path.to_path_buf(),
                message: "no points (expected lines freq_hz,abs,sigma_abs)".into(),
            });
        }
        Ok(MeasuredTf {
            path: path.to_path_buf(),
            input,
            output,
            points,
        })
    }
}

/// How [`fit`] runs.
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// The stage whose modes are fitted.
    pub stage: Stage,
    /// Most Levenberg–Marquardt iterations (Jacobians).
    pub max_iterations: usize,
    /// A direction of the weighted, scaled Jacobian whose singular value is below this
    /// fraction of the largest is undetermined: not stepped in, and reported. 1e-6: the
    /// data then constrain it a million times less than the best-determined combination,
    /// and the Jacobian is good to about 1e-8 relative (central differences; the exact one
    /// to rounding), so that no direction falls below by numerical noise alone.
    pub undetermined_below: f64,
    /// Step of the central differences, relative to each parameter's scale (|p|, or 1 for
    /// p = 0): 1e-4 balances truncation (~1e-8 relative) against the eigenvalues' own
    /// rounding divided by the step.
    pub relative_step: f64,
    /// How the Jacobian is computed (see [`JacobianMethod`]).
    pub jacobian: JacobianMethod,
    /// Above this χ²/dof the fit does not explain its data ([`FitResult::explains_data`]
    /// is false): 100 by default, the model then missing its measurements by ten of their
    /// σ on average, which no honest σ and no right model do. A fit that lands in a wrong
    /// minimum, or matches a measurement to a mode it is not, ends far above it.
    pub max_reduced_chi_squared: f64,
    /// The first match pairs a measurement only with a model mode whose frequency is
    /// within this factor of the measured one (2 by default): a start so far off that the
    /// right mode is outside it needs a better start, not a fit to a wrong mode.
    pub frequency_window: f64,
    /// Starts the fit descends from: the case's values, and `starts − 1` more, each of
    /// them with every free parameter moved by a few per cent (a fixed pseudo-random
    /// pattern per start, up to ±20 %); the fit with the lowest χ² is the result. 1 by
    /// default. A Levenberg–Marquardt descent from 20 % away can end in a wrong minimum
    /// (χ²/dof from 0.1 to 10⁵ with noise-free data) or stall; from a start a few per cent
    /// away it mostly does not (docs/fitting.md has the measured rates).
    pub starts: usize,
    /// More starts, as [`FitOptions::starts`] makes them, tried one at a time when no start
    /// so far gives a fit that explains its data: 4 by default, 0 to never try more. Each
    /// costs up to a whole fit's iterations.
    pub more_starts: usize,
}

/// How the fit differentiates the model's mode frequencies (and |TF| points) with respect
/// to the free parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JacobianMethod {
    /// The exact mode sensitivities, and the |TF| rows from the same request
    /// ([`exact_jacobian`]).
    #[default]
    Exact,
    /// Central differences of the re-solved model ([`mode_jacobian`], and of |H|).
    Differences,
}

impl std::str::FromStr for JacobianMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "exact" => Ok(JacobianMethod::Exact),
            "differences" => Ok(JacobianMethod::Differences),
            _ => Err(format!(
                "'{s}' is not a Jacobian method (exact or differences)"
            )),
        }
    }
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            stage: Stage::S2,
            max_iterations: 50,
            undetermined_below: 1e-6,
            relative_step: 1e-4,
            jacobian: JacobianMethod::Exact,
            max_reduced_chi_squared: 100.0,
            frequency_window: 2.0,
            starts: 1,
            more_starts: 4,
        }
    }
}

/// Least kinetic-energy share a mode must have in a measurement's coordinates to be its
/// match: below it, the measurement names a motion no mode left makes.
const MIN_SHARE: f64 = 0.1;

/// The cost of a pair the assignment must not make (a mode outside the frequency window,
/// or with too small a share): above any sum of allowed costs (each within
/// [−1, ln window]), so that the assignment makes as few of them as it can, and finite, so
/// that the assignment's arithmetic stays exact enough to compare.
const FORBIDDEN: f64 = 1e6;

/// The assignment of each row of `cost` (no more rows than columns) to a distinct column
/// that minimises the sum of their costs: the Hungarian method (Kuhn–Munkres) with
/// potentials, O(rows² · columns). Costs must be finite (the matcher's are). Row `i` goes
/// to column `result[i]`.
fn assign(cost: &DMatrix<f64>) -> Vec<usize> {
    let (rows, columns) = cost.shape();
    // 1-based, index 0 a virtual column: `owner[j]` is the row (1-based, 0 for none) that
    // holds column j, `u` and `v` the row and column potentials (dual variables), with
    // cost − u − v ≥ 0 everywhere and 0 on the assigned pairs
    let mut u = vec![0.0; rows + 1];
    let mut v = vec![0.0; columns + 1];
    let mut owner = vec![0usize; columns + 1];
    let mut previous = vec![0usize; columns + 1];
    for row in 1..=rows {
        // a shortest augmenting path (reduced costs as lengths) from this row to a free
        // column, Dijkstra-like; `slack[j]` is the shortest distance to column j so far
        owner[0] = row;
        let mut column = 0;
        let mut slack = vec![f64::INFINITY; columns + 1];
        let mut visited = vec![false; columns + 1];
        loop {
            visited[column] = true;
            let i = owner[column];
            let mut delta = f64::INFINITY;
            let mut next = 0;
            for j in 1..=columns {
                if visited[j] {
                    continue;
                }
                let reduced = cost[(i - 1, j - 1)] - u[i] - v[j];
                if reduced < slack[j] {
                    slack[j] = reduced;
                    previous[j] = column;
                }
                if slack[j] < delta {
                    delta = slack[j];
                    next = j;
                }
            }
            for j in 0..=columns {
                if visited[j] {
                    u[owner[j]] += delta;
                    v[j] -= delta;
                } else {
                    slack[j] -= delta;
                }
            }
            column = next;
            // a free column ends the path (with finite costs and rows ≤ columns an
            // unvisited column is always found, and one of them is free)
            if owner[column] == 0 {
                break;
            }
        }
        // flip the path: each column on it to the row before it
        while column != 0 {
            let before = previous[column];
            owner[column] = owner[before];
            column = before;
        }
    }
    let mut chosen = vec![0; rows];
    for (j, &i) in owner.iter().enumerate().skip(1) {
        if i != 0 {
            chosen[i - 1] = j - 1;
        }
    }
    chosen
}

/// A measured mode's identity in the model: which mode it is, and its shape to follow it
/// from one solution to the next.
#[derive(Clone, Debug)]
pub struct MatchedModes {
    /// For each measured mode, its mode's index in the model's mode list.
    pub indices: Vec<usize>,
    /// For each measured mode, its model frequency (Hz).
    pub hz: Vec<f64>,
    /// For each measured mode, its model mode's label.
    pub labels: Vec<String>,
    /// Mode shapes (mass-normalised, over the variables), one column per measured mode.
    pub shapes: DMatrix<f64>,
    /// The mass matrix of the solution the shapes come from.
    pub mass: DMatrix<f64>,
    /// Each mode's overlap with the one it continues (1 at the first match).
    pub overlaps: Vec<f64>,
}

/// Pairs the modes with shapes `new_shapes` (columns, in mass metric `new_mass`) with those
/// of `old_shapes` (`old_mass`) by their overlap in the mean mass metric,
/// |u_iᵀ M̄ v_j| / sqrt(u_iᵀ M̄ u_i · v_jᵀ M̄ v_j), M̄ = (M_old + M_new)/2 (1 for the same
/// shape, 0 for shapes that share no kinetic energy): pairs are taken in order of
/// decreasing overlap. Returns, for each new mode, the old mode it continues and their
/// overlap, or `None` when every old mode is taken. Shapes and masses over different
/// numbers of coordinates are an error naming the argument.
pub fn pair_modes_by_overlap(
    old_shapes: &DMatrix<f64>,
    old_mass: &DMatrix<f64>,
    new_shapes: &DMatrix<f64>,
    new_mass: &DMatrix<f64>,
) -> Result<Vec<Option<(usize, f64)>>, Error> {
    // every matrix over the old shapes' coordinates (their rows)
    let n = old_shapes.nrows();
    let square = |m: &DMatrix<f64>| m.shape() == (n, n);
    for (argument, fits, given) in [
        ("old_mass", square(old_mass), old_mass.shape()),
        ("new_mass", square(new_mass), new_mass.shape()),
        (
            "new_shapes (rows)",
            new_shapes.nrows() == n,
            new_shapes.shape(),
        ),
    ] {
        if !fits {
            return Err(Error::Argument {
                function: "pair_modes_by_overlap",
                argument,
                expected: format!("over old_shapes' {n} coordinates"),
                given: format!("{} x {}", given.0, given.1),
            });
        }
    }
    let mean = (old_mass + new_mass) * 0.5;
    let cross = old_shapes.transpose() * &mean * new_shapes;
    let norm = |u: &DMatrix<f64>| -> Vec<f64> {
        (0..u.ncols())
            .map(|j| {
                let c = u.column(j);
                (c.transpose() * &mean * c)[(0, 0)].abs().sqrt()
            })
            .collect()
    };
    let (old_norm, new_norm) = (norm(old_shapes), norm(new_shapes));
    let mut pairs: Vec<(usize, usize, f64)> = Vec::with_capacity(cross.len());
    for i in 0..cross.nrows() {
        for j in 0..cross.ncols() {
            let scale = old_norm[i] * new_norm[j];
            let overlap = if scale > 0.0 {
                cross[(i, j)].abs() / scale
            } else {
                0.0
            };
            pairs.push((i, j, overlap));
        }
    }
    pairs.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)).then(a.1.cmp(&b.1)));
    let mut taken_old = vec![false; cross.nrows()];
    let mut matched = vec![None; cross.ncols()];
    for (i, j, overlap) in pairs {
        if !taken_old[i] && matched[j].is_none() {
            taken_old[i] = true;
            matched[j] = Some((i, overlap));
        }
    }
    Ok(matched)
}

/// The shapes of all modes of `result`, one column each.
pub(crate) fn all_shapes(result: &StageResult) -> DMatrix<f64> {
    let modes = &result.modes.modes;
    let n = result.modes.coordinates.len();
    DMatrix::from_fn(n, modes.len(), |i, j| {
        modes[j].vector.get(i).copied().unwrap_or(0.0)
    })
}

/// The model coordinates (indices, each once, whatever the order they are named in) that
/// the measurement `mm`'s label and shape name, and the family its label names if it is
/// one (then only that family's modes may match); or why they cannot be found.
/// `families` holds each mode's family.
fn measured_columns(
    result: &StageResult,
    families: &[String],
    mm: &MeasuredMode,
) -> Result<(Option<String>, Vec<usize>), String> {
    let coordinates = &result.modes.coordinates;
    let label = result.unalias(&mm.label);
    let family = families.contains(&label) && !coordinates.contains(&label);
    let mut names: Vec<&str> = mm.shape.iter().map(String::as_str).collect();
    if !family {
        names.push(&mm.label);
    }
    if names.is_empty() {
        return Err(format!(
            "label '{}' is a mode family: give the shape column (the coordinates the mode mostly moves, joined by '+')",
            mm.label
        ));
    }
    let mut columns = Vec::with_capacity(names.len());
    for c in names {
        let native = result.unalias(c);
        match coordinates.iter().position(|x| *x == native) {
            Some(k) => columns.push(k),
            None => {
                let catalogue: Vec<String> = result
                    .modes
                    .modes
                    .iter()
                    .zip(families)
                    .map(|(m, f)| format!("{} {} {:.4} Hz", m.label, f, m.hz))
                    .collect();
                return Err(format!(
                    "'{c}' is neither a variable of the model nor a mode family (variables: {}; modes: {})",
                    coordinates.join(" "),
                    catalogue.join(", ")
                ));
            }
        }
    }
    // each coordinate once: the label's own coordinate named again in the shape was
    // counted twice when the two were not adjacent, and the shape's order changed the match
    columns.sort_unstable();
    columns.dedup();
    Ok((family.then_some(label), columns))
}

/// The first match's measurement × mode tables and the assignment made from them.
struct Pairs {
    /// Each mode's kinetic-energy share in each measurement's coordinates.
    share: DMatrix<f64>,
    /// Whether the mode may be the measurement's match (share and frequency window).
    allowed: DMatrix<bool>,
    /// Each measurement's mode.
    chosen: Vec<usize>,
}

impl Pairs {
    /// Why measurement `row` has no mode: none within the frequency `window` moves its
    /// coordinates enough (then the mode that moves them most, wherever it is), or every
    /// one that does is another measurement's (then which, by line).
    fn why_unmatched(
        &self,
        result: &StageResult,
        families: &[String],
        measured: &MeasuredModes,
        row: usize,
        window: f64,
    ) -> String {
        let modes = &result.modes.modes;
        let describe = |k: usize| {
            format!(
                "mode {} ({} {}, {:.4} Hz)",
                k + 1,
                modes[k].label,
                families[k],
                modes[k].hz
            )
        };
        let mm = &measured.modes[row];
        let what = if mm.shape.is_empty() {
            mm.label.clone()
        } else {
            format!("{} / {}", mm.label, mm.shape.join("+"))
        };
        let window = pendkit_expr::number_text(window);
        let hz = pendkit_expr::number_text(mm.hz);
        let candidates: Vec<usize> = (0..modes.len())
            .filter(|&k| self.allowed[(row, k)])
            .collect();
        if candidates.is_empty() {
            let best = (0..modes.len())
                .max_by(|&a, &b| self.share[(row, a)].total_cmp(&self.share[(row, b)]))
                .filter(|&k| self.share[(row, k)] > 0.0);
            return format!(
                "no model mode within a factor {window} of {hz} Hz moves {what} (at least {:.0} % of its kinetic energy){}",
                100.0 * MIN_SHARE,
                best.map_or_else(String::new, |k| format!(
                    "; the one that moves it most is {} with {:.0} %",
                    describe(k),
                    100.0 * self.share[(row, k)]
                ))
            );
        }
        let taken: Vec<String> = candidates
            .iter()
            .filter_map(|&k| {
                let other = self.chosen.iter().position(|&c| c == k)?;
                Some(format!(
                    "{} by line {}",
                    describe(k),
                    measured.modes[other].line
                ))
            })
            .collect();
        format!(
            "no model mode left that moves {what} within a factor {window} of {hz} Hz: each one that does is another measurement's ({}); a mode is measured once",
            taken.join(", ")
        )
    }
}

impl MatchedModes {
    fn from_indices(result: &StageResult, indices: Vec<usize>, overlaps: Vec<f64>) -> Self {
        let modes = &result.modes.modes;
        let n = result.modes.coordinates.len();
        MatchedModes {
            hz: indices.iter().map(|&k| modes[k].hz).collect(),
            labels: indices.iter().map(|&k| modes[k].label.clone()).collect(),
            shapes: DMatrix::from_fn(n, indices.len(), |i, j| {
                modes[indices[j]].vector.get(i).copied().unwrap_or(0.0)
            }),
            mass: result.assembled.mass.to_dense(),
            indices,
            overlaps,
        }
    }

    /// The first match with the default frequency window
    /// ([`FitOptions::frequency_window`]): see [`MatchedModes::by_label_within`].
    pub fn by_label(result: &StageResult, measured: &MeasuredModes) -> Result<Self, FitError> {
        let window = FitOptions::default().frequency_window;
        MatchedModes::by_label_within(result, measured, window)
    }

    /// The first match: all measured modes at once to distinct model modes, by optimal
    /// assignment (the Hungarian method). A measurement may match a mode that has at least 10 % of
    /// its kinetic energy in the coordinates the measurement's label and shape name (for a
    /// family label, a mode of that family, by its shape's coordinates) and whose frequency
    /// is within a factor `window` of the measured one; among those the assignment
    /// minimises the sum of |ln(f_model/f_measured)| less the share (a mode e times off in
    /// frequency needs a share larger by 1, so that modes moving the same coordinates, in
    /// and out of phase, go to the nearest frequencies). Taking the measurements one at a
    /// time, best first, let one take the mode another needed, and then report the other
    /// unmatched; all at once, neither their order nor a crossing can do that. A
    /// measurement that no mode left can match is an error naming its line.
    pub fn by_label_within(
        result: &StageResult,
        measured: &MeasuredModes,
        window: f64,
    ) -> Result<Self, FitError> {
        let modes = &result.modes.modes;
        let file_error = |message: String| FitError::File {
            path: measured.path.clone(),
            message,
        };
        if !(window.is_finite() && window > 1.0) {
            return Err(file_error(format!(
                "the frequency window must be a factor above 1, got {window}"
            )));
        }
        if measured.modes.len() > modes.len() {
            return Err(file_error(format!(
                "{} measured modes, but the model has {} modes: each measurement is a different mode",
                measured.modes.len(),
                modes.len()
            )));
        }
        let families: Vec<String> = modes.iter().map(|m| result.mode_family(m)).collect();
        // per measurement and model mode: the mode's kinetic-energy share in the
        // measurement's coordinates, whether it may be its match at all, and the cost
        let mut pairs = Pairs {
            share: DMatrix::zeros(measured.modes.len(), modes.len()),
            allowed: DMatrix::from_element(measured.modes.len(), modes.len(), false),
            chosen: Vec::new(),
        };
        let mut cost = DMatrix::from_element(measured.modes.len(), modes.len(), FORBIDDEN);
        for (row, mm) in measured.modes.iter().enumerate() {
            let (family, columns) =
                measured_columns(result, &families, mm).map_err(|message| FitError::Unmatched {
                    path: measured.path.clone(),
                    line: mm.line,
                    message,
                })?;
            for k in (0..modes.len()).filter(|&k| family.as_ref().is_none_or(|f| families[k] == *f))
            {
                let share: f64 = columns
                    .iter()
                    .map(|&c| modes[k].energy_fractions.get(c).copied().unwrap_or(0.0))
                    .sum();
                let distance = (modes[k].hz.abs() / mm.hz).ln().abs();
                pairs.share[(row, k)] = share;
                // a non-finite distance (a mode at 0 Hz) is never within the window
                let allowed = share >= MIN_SHARE && distance <= window.ln();
                pairs.allowed[(row, k)] = allowed;
                if allowed {
                    cost[(row, k)] = distance - share;
                }
            }
        }
        pairs.chosen = assign(&cost);
        // a measurement the assignment could only give a forbidden pair: no mode it may
        // match, or every such mode another measurement's
        if let Some(row) =
            (0..measured.modes.len()).find(|&row| !pairs.allowed[(row, pairs.chosen[row])])
        {
            return Err(FitError::Unmatched {
                path: measured.path.clone(),
                line: measured.modes[row].line,
                message: pairs.why_unmatched(result, &families, measured, row, window),
            });
        }
        let indices = pairs.chosen;
        let overlaps = vec![1.0; indices.len()];
        Ok(MatchedModes::from_indices(result, indices, overlaps))
    }

    /// The same modes in a new solution `result`: each followed by the overlap of its shape
    /// with this match's (so that modes that cross in frequency keep their identity). A
    /// `result` over other coordinates than this match's is an error.
    pub fn follow(&self, result: &StageResult) -> Result<MatchedModes, Error> {
        if self.shapes.ncols() != self.indices.len() {
            return Err(Error::Argument {
                function: "MatchedModes::follow",
                argument: "self.shapes (columns)",
                expected: format!("one per matched mode ({})", self.indices.len()),
                given: self.shapes.ncols().to_string(),
            });
        }
        let pairs = pair_modes_by_overlap(
            &self.shapes,
            &self.mass,
            &all_shapes(result),
            &result.assembled.mass.to_dense(),
        )?;
        let mut indices = vec![0; self.indices.len()];
        let mut overlaps = vec![0.0; self.indices.len()];
        for (new, pair) in pairs.iter().enumerate() {
            if let Some((old, overlap)) = *pair {
                indices[old] = new;
                overlaps[old] = overlap;
            }
        }
        Ok(MatchedModes::from_indices(result, indices, overlaps))
    }
}

/// `case` with the free parameters set to `values`, solved at `stage`.
fn solve(case: &Case, free: &[String], values: &[f64], stage: Stage) -> Result<StageResult, Error> {
    let (system, _) = case.clone().with_sets(&sets(free, values))?.build()?;
    run_stage(system, stage)
}

/// `name=value` overrides; a value's `Display` is the shortest text that reads back to the
/// same f64.
fn sets(free: &[String], values: &[f64]) -> Vec<String> {
    free.iter()
        .zip(values)
        .map(|(name, value)| format!("{name}={value}"))
        .collect()
}

/// Each free parameter's step scale: |value|, or 1 for a parameter at 0.
fn scales(values: &[f64]) -> Vec<f64> {
    values
        .iter()
        .map(|v| if *v != 0.0 { v.abs() } else { 1.0 })
        .collect()
}

/// The frequencies (Hz) of the `matched` modes of `case` with the free parameters at
/// `values` (the solution `matched` comes from), and their derivatives with respect to
/// each free parameter (Hz per unit of the parameter; one row per matched mode, one column
/// per free parameter): central differences of the re-solved model with steps
/// `relative_step` × |value|, the modes followed by shape at each step.
///
/// The fit's Jacobian with [`JacobianMethod::Differences`] ([`exact_mode_jacobian`] is
/// the default). `values` must hold one value per free parameter and `relative_step` be
/// finite and positive.
pub fn mode_jacobian(
    case: &Case,
    stage: Stage,
    free: &[String],
    values: &[f64],
    matched: &MatchedModes,
    relative_step: f64,
) -> Result<(Vec<f64>, DMatrix<f64>), Error> {
    let argument = |argument, expected: String, given: String| Error::Argument {
        function: "mode_jacobian",
        argument,
        expected,
        given,
    };
    if values.len() != free.len() {
        let expected = format!("one value per free parameter ({})", free.len());
        return Err(argument("values", expected, values.len().to_string()));
    }
    if !(relative_step.is_finite() && relative_step > 0.0) {
        let expected = "finite and positive".to_string();
        return Err(argument(
            "relative_step",
            expected,
            relative_step.to_string(),
        ));
    }
    let jacobian = central_differences(case, stage, free, values, relative_step, |result| {
        Ok(matched.follow(result)?.hz)
    })?;
    Ok((matched.hz.clone(), jacobian))
}

/// [`mode_jacobian`] by the exact sensitivities ([`crate::sensitivity::sensitivities`]) instead of
/// differences: the frequencies of the `matched` modes of `case` with the free parameters
/// at `values` (the solution `matched` comes from), and d(frequency)/d(parameter) (Hz per
/// unit of the parameter; one row per matched mode, one column per free parameter), with
/// no step. A parameter the exact route is closed to has its stage matrices differenced
/// there (see [`crate::sensitivity::sensitivities`]), still without following any mode. Modes within a
/// cluster of equal frequencies get the eigenvalues of the cluster's derivative in
/// ascending order, as their frequencies are ordered.
pub fn exact_mode_jacobian(
    case: &Case,
    stage: Stage,
    free: &[String],
    values: &[f64],
    matched: &MatchedModes,
) -> Result<(Vec<f64>, DMatrix<f64>), Error> {
    let at = (values, matched);
    let (modes, _) = exact_rows("exact_mode_jacobian", case, stage, free, at, None)?;
    Ok((matched.hz.clone(), modes))
}

/// The fit's whole Jacobian with [`JacobianMethod::Exact`]: the rows of
/// [`exact_mode_jacobian`], and with `tf` d|H|/dp at its points' frequencies (one row per
/// point, |H|'s unit per unit of the parameter) from the same request: the stage's
/// matrices differenced and everything after them exact (see [`crate::sensitivity::sensitivities`]),
/// so that a point on a sharp resonance gets its true derivative, which a difference of
/// |H| itself misses when the step moves the peak by a fraction of its width.
pub fn exact_jacobian(
    case: &Case,
    stage: Stage,
    free: &[String],
    values: &[f64],
    matched: &MatchedModes,
    tf: Option<&MeasuredTf>,
) -> Result<(DMatrix<f64>, Option<DMatrix<f64>>), Error> {
    exact_rows("exact_jacobian", case, stage, free, (values, matched), tf)
}

/// [`exact_jacobian`], its errors naming `function` (the public function called).
fn exact_rows(
    function: &'static str,
    case: &Case,
    stage: Stage,
    free: &[String],
    (values, matched): (&[f64], &MatchedModes),
    tf: Option<&MeasuredTf>,
) -> Result<(DMatrix<f64>, Option<DMatrix<f64>>), Error> {
    let freqs: Vec<f64> =
        tf.map_or_else(Vec::new, |t| t.points.iter().map(|p| p.freq_hz).collect());
    if values.len() != free.len() {
        return Err(Error::Argument {
            function,
            argument: "values",
            expected: format!("one value per free parameter ({})", free.len()),
            given: values.len().to_string(),
        });
    }
    let at = case.clone().with_sets(&sets(free, values))?;
    let request = crate::sensitivity::SensitivityRequest {
        parameters: Some(free.to_vec()),
        tf: tf.map(|t| (t.input.clone(), t.output.clone())),
        freqs,
        ..crate::sensitivity::SensitivityRequest::modes(stage)
    };
    let sensitivities = crate::sensitivity::sensitivities(&at, &request).map_err(|e| match e {
        // a count or a switch among the free parameters, a neutral mode: said as the fit's
        Error::Sensitivity(why) => Error::Sensitivity(format!("the fit's exact Jacobian: {why}")),
        e => e,
    })?;
    // the same build and stage as the solution `matched` comes from, so the same modes in
    // the same order, to the last bit
    let mut rows = Vec::with_capacity(matched.indices.len());
    for (&index, &hz) in matched.indices.iter().zip(&matched.hz) {
        match (
            sensitivities.modes_hz.get(index),
            sensitivities.dfdp.get(index),
        ) {
            (Some(&f), Some(row)) if f == hz && row.len() == free.len() => rows.push(row),
            _ => {
                return Err(Error::Argument {
                    function,
                    argument: "matched",
                    expected: "modes of the solution at `values`".into(),
                    given: format!("mode {} at {hz} Hz", index + 1),
                });
            }
        }
    }
    let modes = DMatrix::from_fn(rows.len(), free.len(), |i, p| rows[i][p]);
    let tf_rows = match (&sensitivities.tf_abs, tf) {
        (Some((_, d)), Some(_)) => Some(DMatrix::from_fn(d.len(), free.len(), |i, p| {
            d[i].get(p).copied().unwrap_or(f64::NAN)
        })),
        _ => None,
    };
    Ok((modes, tf_rows))
}

/// The derivatives of `quantities` (of a solution) with respect to each free parameter at
/// `values`: central differences with steps `relative_step` × the parameter's scale, one
/// row per quantity, one column per parameter.
fn central_differences(
    case: &Case,
    stage: Stage,
    free: &[String],
    values: &[f64],
    relative_step: f64,
    quantities: impl Fn(&StageResult) -> Result<Vec<f64>, Error>,
) -> Result<DMatrix<f64>, Error> {
    let scale = scales(values);
    let mut columns = Vec::with_capacity(free.len());
    for p in 0..free.len() {
        let h = relative_step * scale[p];
        let at = |sign: f64| -> Result<Vec<f64>, Error> {
            let mut shifted = values.to_vec();
            shifted[p] += sign * h;
            quantities(&solve(case, free, &shifted, stage)?)
        };
        let (up, down) = (at(1.0)?, at(-1.0)?);
        columns.push(
            up.iter()
                .zip(&down)
                .map(|(u, d)| (u - d) / (2.0 * h))
                .collect::<Vec<f64>>(),
        );
    }
    let rows = columns.first().map_or(0, Vec::len);
    Ok(DMatrix::from_fn(rows, free.len(), |i, p| {
        columns[p].get(i).copied().unwrap_or(0.0)
    }))
}

/// |TF| (the transfer function's unit) of `result` at the measured points' frequencies.
fn tf_values(result: &StageResult, tf: &MeasuredTf, freqs: &[f64]) -> Result<Vec<f64>, Error> {
    Ok(result
        .transfer(&tf.input, &tf.output, freqs)?
        .iter()
        .map(|z| z.norm())
        .collect())
}

/// A fitted parameter.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FittedParameter {
    /// Name.
    pub name: String,
    /// Unit, where the model declares one.
    pub unit: Option<String>,
    /// Start value (its unit).
    pub start: f64,
    /// Fitted value (its unit); the start value when undetermined.
    pub value: f64,
    /// Standard uncertainty (its unit), from the covariance on the determined directions;
    /// `None` when the data do not determine the parameter.
    pub uncertainty: Option<f64>,
}

/// A measured mode against the fitted model.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ModeResidual {
    /// The measurement's label.
    pub label: String,
    /// The model mode's number (from 1, ascending frequency, as `pendkit modes` numbers it).
    pub mode: usize,
    /// The model mode's label (dominant coordinate).
    pub model_label: String,
    /// Measured frequency (Hz).
    pub measured_hz: f64,
    /// Its uncertainty (Hz).
    pub sigma_hz: f64,
    /// Fitted model frequency (Hz).
    pub model_hz: f64,
    /// (measured − model)/σ.
    pub normalized: f64,
    /// The measurement's line in its file (from 1).
    pub line: usize,
}

/// A measured |TF| point against the fitted model.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TfResidual {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Measured |TF|.
    pub measured: f64,
    /// Its uncertainty.
    pub sigma: f64,
    /// Fitted model |TF|.
    pub model: f64,
    /// (measured − model)/σ.
    pub normalized: f64,
    /// The point's line in its file (from 1).
    pub line: usize,
}

/// A combination of parameters the data cannot determine: a right singular vector of the
/// weighted Jacobian in relative units (changing each parameter p by `coefficient` × |p|
/// changes no fitted quantity to first order, relative to the best-determined direction,
/// by more than `relative_singular_value`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Undetermined {
    /// Singular value over the largest.
    pub relative_singular_value: f64,
    /// (parameter, coefficient) of the unit vector, largest first, coefficients below 1e-3
    /// left out.
    pub combination: Vec<(String, f64)>,
}

/// A parameter the fit did not free that would explain more of the data: the first-order
/// estimate of χ² with it freed too, from the sensitivities of the matched modes (and |TF|
/// points) to every parameter at the fitted values. Of the part of the residual the free
/// parameters cannot move, its share is what freeing it removes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct WouldHelp {
    /// The parameter.
    pub parameter: String,
    /// χ²/dof with it freed as well (one degree of freedom fewer), to first order.
    pub reduced_chi_squared: f64,
}

/// The result of a fit.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FitResult {
    /// The free parameters, fitted.
    pub parameters: Vec<FittedParameter>,
    /// Correlation coefficients between the parameters (`None` where one is undetermined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// The measured modes against the fitted model.
    pub modes: Vec<ModeResidual>,
    /// The measured |TF| points against the fitted model (empty without one).
    pub tf: Vec<TfResidual>,
    /// χ² = Σ ((measured − model)/σ)².
    pub chi_squared: f64,
    /// Degrees of freedom: measurements minus determined directions.
    pub dof: usize,
    /// χ²/dof (`None` when dof = 0). The uncertainties are not scaled by it.
    pub reduced_chi_squared: Option<f64>,
    /// The verdict: whether the fit explains its data, χ²/dof at most
    /// `max_reduced_chi_squared`. When it does not, the values are the model's best
    /// compromise (or a wrong minimum), no parameter is determined by them, and the
    /// uncertainties, which assume the model right, do not hold.
    pub explains_data: bool,
    /// The χ²/dof above which the fit does not explain its data
    /// ([`FitOptions::max_reduced_chi_squared`]).
    pub max_reduced_chi_squared: f64,
    /// Singular values of the weighted Jacobian in relative parameter units, largest first.
    pub singular_values: Vec<f64>,
    /// The combinations the data cannot determine.
    pub undetermined: Vec<Undetermined>,
    /// Levenberg–Marquardt iterations (Jacobians computed).
    pub iterations: usize,
    /// Model solutions made (an exact Jacobian counts as one, plus four per free parameter
    /// for its |TF| rows).
    pub solves: usize,
    /// How many times the fit started again from where it had got to, its measurements
    /// matched afresh (0 when the first descent converged and explains the data); the
    /// iterations and solutions count every start.
    pub restarts: usize,
    /// How many starts were tried ([`FitOptions::starts`], and [`FitOptions::more_starts`]
    /// when none explained the data); the result is the best of them.
    pub starts: usize,
    /// When the fit does not explain its data: the parameters not free whose freeing would
    /// lower χ² most, best first (at most three, each lowering it by at least 1 %).
    pub would_help: Vec<WouldHelp>,
    /// How the Jacobian was computed.
    pub jacobian: JacobianMethod,
}

impl FitResult {
    /// The fitted values as `name=value` overrides (as `--set` takes them).
    pub fn sets(&self) -> Vec<String> {
        self.parameters
            .iter()
            .map(|p| format!("{}={}", p.name, p.value))
            .collect()
    }

    /// A case file (see [`Case::from_file`]) of model `model` (a bundled name or a
    /// suspension file's path) with `case`'s overrides and the fitted values.
    pub fn case_file(&self, model: &str, case: &Case) -> String {
        let fitted = |name: &str| self.parameters.iter().find(|p| p.name == name);
        let mut overrides = case.overrides.clone();
        overrides
            .parameters
            .retain(|(name, _)| fitted(name).is_none());
        // `{:e}`: every digit of the f64, whatever the magnitude
        overrides.parameters.extend(
            self.parameters
                .iter()
                .map(|p| (p.name.clone(), format!("{:e}", p.value))),
        );
        let note = |name: &str| {
            fitted(name).map(|p| match p.uncertainty {
                Some(u) => format!("+- {u:.3e}"),
                None => "undetermined: start value".to_string(),
            })
        };
        let header = format!(
            "# written by pendkit fit {}: {} free parameters, chi^2/dof = {}\n",
            crate::VERSION,
            self.parameters.len(),
            self.reduced_chi_squared.map_or_else(
                || "- (no degrees of freedom)".to_string(),
                |r| format!("{r:.4}")
            ),
        );
        header
            + &overrides.case_file(
                model,
                &format!("{} fitted to measured modes", case.name),
                &note,
            )
    }
}

/// The residual vector r = (model − measured)/σ over the modes, then the |TF| points.
fn residuals(
    model_hz: &[f64],
    measured: &MeasuredModes,
    tf: Option<&MeasuredTf>,
    tf_model: &[f64],
) -> DVector<f64> {
    let modes = measured
        .modes
        .iter()
        .zip(model_hz)
        .map(|(m, f)| (f - m.hz) / m.sigma_hz);
    let points = tf
        .into_iter()
        .flat_map(|t| t.points.iter())
        .zip(tf_model)
        .map(|(p, model)| (model - p.abs) / p.sigma_abs);
    DVector::from_iterator(measured.modes.len() + tf_model.len(), modes.chain(points))
}

/// The error for the `i`-th weighted residual `r` (modes first, then |TF| points), which is
/// not finite or too large to square.
fn residual_error(measured: &MeasuredModes, tf: Option<&MeasuredTf>, i: usize, r: f64) -> FitError {
    let point = tf.and_then(|t| {
        let p = t.points.get(i.checked_sub(measured.modes.len())?)?;
        Some((&t.path, p.line, "sigma_abs"))
    });
    let mode = measured
        .modes
        .get(i)
        .map(|m| (&measured.path, m.line, "sigma_hz"));
    // residuals() makes one per mode, then one per point: one of the two is there
    let Some((path, line, what)) = mode.or(point) else {
        return FitError::NotFinite(format!("residual {i}"));
    };
    let message = if r.is_finite() {
        format!(
            "the weighted residual (model - measured)/{what} = {r:.3e} is too large to square: \
             {what} is far below the model's distance from the measurement"
        )
    } else {
        format!("the model's value for this measurement is not finite ({r})")
    };
    FitError::Line {
        path: path.clone(),
        line,
        message,
    }
}

/// What is fitted to what: the measurements, the free parameters, their start values,
/// scales and units, and how the Jacobian was computed.
struct Problem<'a> {
    case: &'a Case,
    options: &'a FitOptions,
    measured: &'a MeasuredModes,
    tf: Option<&'a MeasuredTf>,
    free: &'a [String],
    start: Vec<f64>,
    scale: Vec<f64>,
    units: Vec<Option<String>>,
    domains: Vec<Option<Domain>>,
    /// The σ of every measurement, modes then |TF| points.
    sigma: Vec<f64>,
    /// The |TF| points' frequencies (Hz).
    tf_freqs: Vec<f64>,
}

/// One point of the fit: the solution, its matched modes and residuals.
struct State {
    values: Vec<f64>,
    matched: MatchedModes,
    tf_model: Vec<f64>,
    r: DVector<f64>,
    chi_squared: f64,
}

/// Fits the free parameters of `case` to the measured modes (and |TF| points), starting
/// from the case's values: see the [module documentation](self).
pub fn fit(
    case: &Case,
    measured: &MeasuredModes,
    tf: Option<&MeasuredTf>,
    free: &[String],
    options: &FitOptions,
) -> Result<FitResult, Error> {
    check_options(options)?;
    let start = start_values(case, free)?;
    let n_data = measured.modes.len() + tf.map_or(0, |t| t.points.len());
    if n_data <= free.len() {
        return Err(FitError::TooFewMeasurements {
            measurements: n_data,
            free: free.len(),
        }
        .into());
    }
    let Declarations { units, domains } = parameter_declarations(case, free)?;
    let problem = Problem {
        case,
        options,
        measured,
        tf,
        free,
        scale: scales(&start),
        start,
        units,
        domains,
        sigma: sigmas(measured, tf),
        tf_freqs: tf.map_or_else(Vec::new, |t| t.points.iter().map(|p| p.freq_hz).collect()),
    };
    let mut counts = (0, 0);
    // the user's start first: an error there (a start the model refuses) is the answer
    let mut best = from_start(&problem, &problem.start, &mut counts, true)?;
    let mut tried = 1;
    while tried < options.starts
        || (tried < options.starts + options.more_starts && !best.explains_data())
    {
        let start = jittered(&problem, tried);
        tried += 1;
        // a start the model or the matcher refuses leaves the best fit so far as it is
        if let Ok(outcome) = from_start(&problem, &start, &mut counts, false) {
            best = best.better(outcome);
        }
    }
    match best {
        Outcome::Converged { mut result, state } => {
            (result.iterations, result.solves) = counts;
            result.starts = tried;
            if !result.explains_data {
                // what the model lacks: a first-order estimate from the sensitivities to
                // every parameter; a model it cannot differentiate leaves it unsaid
                result.would_help = would_help(&problem, &state).unwrap_or_default();
            }
            Ok(*result)
        }
        Outcome::Stalled { state, damping } => {
            Err(not_converged(measured, &problem, &state, counts.0, damping))
        }
    }
}

/// The start `k` (from 1) besides the case's values: each free parameter moved by
/// [`JITTER`] times a sum of eight pseudo-random signs (SplitMix64 seeded by `k` and the
/// parameter's position: a fixed pattern per start), so up to ±20 % and mostly a few per
/// cent; a move that would leave a parameter's domain goes nine tenths of the way to its
/// edge, as a step does.
fn jittered(problem: &Problem, k: usize) -> Vec<f64> {
    problem
        .start
        .iter()
        .zip(&problem.domains)
        .enumerate()
        .map(|(p, (&value, domain))| {
            let mut state = (k as u64) << 32 | p as u64;
            let sum: f64 = (0..8)
                .map(|_| {
                    state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
                    let mut z = state;
                    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                    if (z ^ (z >> 31)) & 1 == 1 { 1.0 } else { -1.0 }
                })
                .sum();
            within(*domain, value, value * (1.0 + JITTER * sum))
        })
        .collect()
}

/// The size of one of the eight signs of a start's move ([`jittered`]), relative: moves
/// of up to ±20 % (standard deviation 7 %), as far as the starts of the hard case
/// were from the truth. Measured on the quad (20 free parameters, 20 % offsets, 30 sign
/// patterns, 4 starts and up to 8 more): 30 of 30 to the truth with 2.5 %, 29 with 1.25 %.
const JITTER: f64 = 0.025;

/// One start of the fit: a descent from `values`, and restarts from where it got to.
///
/// Restarts: a descent that stalls, or ends where it cannot explain the data, starts again
/// from where it got to, with its measurements matched afresh there and the damping reset.
/// Followed by overlap across large steps, a mode can be taken for another that crosses
/// it; re-matched by label the match is right again.
fn from_start(
    problem: &Problem,
    values: &[f64],
    counts: &mut (usize, usize),
    first: bool,
) -> Result<Outcome, Error> {
    let mut outcome = descend(problem, values, counts, first)?;
    for restart in 1..=RESTARTS {
        let values = match &outcome {
            Outcome::Converged { result, .. } if result.explains_data => break,
            Outcome::Converged { state, .. } => state.values.clone(),
            Outcome::Stalled { state, .. } => state.values.clone(),
        };
        let Ok(next) = descend(problem, &values, counts, false) else {
            // a start the model or the matcher refuses: what the last descent found stands
            break;
        };
        outcome = outcome.better(next);
        if let Outcome::Converged { result, .. } = &mut outcome {
            result.restarts = restart;
        }
    }
    Ok(outcome)
}

/// At most this many parameters are named as [`FitResult::would_help`].
const WOULD_HELP: usize = 3;

/// The parameters whose freeing would lower χ² most at `state` (see [`WouldHelp`]): the
/// weighted sensitivities of every parameter (rows / σ, columns × |value|), their part
/// outside the span of the free parameters' determined directions, and the χ² it removes,
/// (rᵀq)²/(qᵀq) for that part q and the weighted residual r.
fn would_help(problem: &Problem, state: &State) -> Result<Vec<WouldHelp>, Error> {
    let Problem {
        case,
        options,
        free,
        tf,
        ..
    } = *problem;
    let at = case.clone().with_sets(&sets(free, &state.values))?;
    let request = crate::sensitivity::SensitivityRequest {
        tf: tf.map(|t| (t.input.clone(), t.output.clone())),
        freqs: problem.tf_freqs.clone(),
        ..crate::sensitivity::SensitivityRequest::modes(options.stage)
    };
    let sens = crate::sensitivity::sensitivities(&at, &request)?;
    let n = sens.parameters.len();
    // the rows in the residual's order: the matched modes, then the |TF| points
    let mut rows: Vec<&Vec<f64>> = Vec::with_capacity(problem.sigma.len());
    // the same build and stage as the state's solution: the same modes in the same order
    for (&index, &hz) in state.matched.indices.iter().zip(&state.matched.hz) {
        match (sens.modes_hz.get(index), sens.dfdp.get(index)) {
            (Some(&f), Some(row)) if f == hz => rows.push(row),
            _ => {
                return Err(Error::Sensitivity(format!(
                    "mode {} at {hz} Hz is not the sensitivities' mode",
                    index + 1
                )));
            }
        }
    }
    if let Some((_, d)) = &sens.tf_abs {
        rows.extend(d.iter());
    }
    if rows.len() != problem.sigma.len() || rows.iter().any(|r| r.len() != n) {
        return Err(Error::Sensitivity(
            "the sensitivities do not match the data".into(),
        ));
    }
    let weighted = DMatrix::from_fn(rows.len(), n, |i, p| {
        let scale = if sens.values[p] != 0.0 {
            sens.values[p].abs()
        } else {
            1.0
        };
        rows[i][p] / problem.sigma[i] * scale
    });
    let is_free: Vec<bool> = sens.parameters.iter().map(|p| free.contains(p)).collect();
    let free_columns: Vec<usize> = (0..n).filter(|&p| is_free[p]).collect();
    let svd = weighted.select_columns(&free_columns).svd(true, false);
    let u = svd.u.ok_or_else(|| {
        Error::Sensitivity("the SVD of the free parameters' sensitivities".into())
    })?;
    let s_max = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let basis: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > problem.options.undetermined_below * s_max)
        .collect();
    let u = u.select_columns(&basis);
    let dof = state.r.len().saturating_sub(basis.len() + 1);
    let mut gains: Vec<(usize, f64)> = (0..n)
        .filter(|&p| !is_free[p])
        .filter_map(|p| {
            let w = weighted.column(p);
            let q = w - &u * (u.transpose() * w);
            let norm = q.norm_squared();
            // a column the free parameters' span holds (to rounding) adds nothing
            (norm > 1e-12 * w.norm_squared() && norm > 0.0)
                .then(|| (p, q.dot(&state.r).powi(2) / norm))
        })
        .filter(|&(_, gain)| gain.is_finite() && gain >= 0.01 * state.chi_squared)
        .collect();
    gains.sort_by(|a, b| b.1.total_cmp(&a.1));
    Ok(gains
        .into_iter()
        .take(WOULD_HELP)
        .filter(|_| dof > 0)
        .map(|(p, gain)| WouldHelp {
            parameter: sens.parameters[p].clone(),
            reduced_chi_squared: (state.chi_squared - gain).max(0.0) / dof as f64,
        })
        .collect())
}

/// How many times a fit that stalls or cannot explain its data starts again from where it
/// got to (see [`fit`]); each start may take [`FitOptions::max_iterations`].
const RESTARTS: usize = 3;

/// How one descent ended: converged, or stalled at `state` (out of iterations, or no step
/// that lowers χ²) with Levenberg's damping at `damping`.
enum Outcome {
    Converged {
        result: Box<FitResult>,
        state: State,
    },
    Stalled {
        state: State,
        damping: f64,
    },
}

impl Outcome {
    fn chi_squared(&self) -> f64 {
        match self {
            Outcome::Converged { state, .. } | Outcome::Stalled { state, .. } => state.chi_squared,
        }
    }

    fn explains_data(&self) -> bool {
        matches!(self, Outcome::Converged { result, .. } if result.explains_data)
    }

    /// The better of two outcomes: a converged fit unless the other converged with a lower
    /// χ² (a stalled descent is no minimum), else the later.
    fn better(self, other: Outcome) -> Outcome {
        match (self, other) {
            (old @ Outcome::Converged { .. }, Outcome::Converged { state: new, .. })
                if old.chi_squared() <= new.chi_squared =>
            {
                old
            }
            (old @ Outcome::Converged { .. }, Outcome::Stalled { .. }) => old,
            (_, other) => other,
        }
    }
}

/// One Levenberg–Marquardt descent of `problem` from `values`, its measurements matched by
/// label there; adds its (iterations, solves) to `counts`. An error at the start names the
/// start values as such when `first` (the user's start), not when a restart's.
fn descend(
    problem: &Problem,
    values: &[f64],
    counts: &mut (usize, usize),
    first: bool,
) -> Result<Outcome, Error> {
    let Problem {
        case,
        options,
        measured,
        tf,
        free,
        ..
    } = *problem;
    let stage = options.stage;
    let evaluate = |values: &[f64], matched: &MatchedModes, result: &StageResult| {
        state_at(measured, tf, &problem.tf_freqs, values, matched, result)
    };
    let at_start = |e: Error| -> Error {
        if first {
            FitError::Start(Box::new(e)).into()
        } else {
            e
        }
    };
    let solution = solve(case, free, values, stage).map_err(at_start)?;
    solution.check_stable().map_err(at_start)?;
    counts.1 += 1;
    let matched = MatchedModes::by_label_within(&solution, measured, options.frequency_window)?;
    let mut state = evaluate(values, &matched, &solution)?;
    let n_data = problem.sigma.len();
    let mut damping: Option<f64> = None;
    let mut iterations = 0;
    loop {
        // the weighted Jacobian in relative parameter units: rows / σ, columns × scale
        let (jacobian, jacobian_solves) =
            jacobian(case, options, free, &state, tf, &problem.tf_freqs)?;
        counts.1 += jacobian_solves;
        iterations += 1;
        let svd = weighted_svd(
            &jacobian,
            &problem.sigma,
            &problem.scale,
            n_data,
            free.len(),
        )?;
        let (Some(u), Some(v_t)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
            return Err(FitError::NotFinite("the SVD of the Jacobian".into()).into());
        };
        let s = &svd.singular_values;
        let (s_max, determined, c) =
            determined_directions(u, s, &state.r, options.undetermined_below);
        // what a full Gauss–Newton step would still gain in χ²; at the minimum, zero
        let gain: f64 = c.iter().map(|x| x * x).sum();
        let converged = gain <= 1e-9 * state.chi_squared.max(1.0);
        if converged || iterations > options.max_iterations {
            counts.0 += iterations - usize::from(!converged);
            if !converged {
                let damping = damping.unwrap_or(0.0);
                return Ok(Outcome::Stalled { state, damping });
            }
            let result = finish(problem, &state, &svd, &determined, *counts);
            return Ok(Outcome::Converged {
                result: Box::new(result),
                state,
            });
        }
        let mut lambda = damping.unwrap_or(1e-3 * s_max * s_max);
        let mut accepted = false;
        for _ in 0..30 {
            let mut delta = DVector::zeros(free.len());
            for (&i, ci) in determined.iter().zip(&c) {
                delta -= v_t.row(i).transpose() * (s[i] * ci / (s[i] * s[i] + lambda));
            }
            let trial = stepped(&state.values, &delta, &problem.scale, &problem.domains);
            counts.1 += 1;
            let candidate = solve(case, free, &trial, stage).and_then(|result| {
                result.check_stable()?;
                let matched = state.matched.follow(&result)?;
                evaluate(&trial, &matched, &result)
            });
            match candidate {
                Ok(next) if next.chi_squared < state.chi_squared => {
                    state = next;
                    lambda /= 10.0;
                    accepted = true;
                    break;
                }
                // worse, or the model cannot be solved there: a shorter step
                _ => lambda = (lambda * 10.0).max(1e-12 * s_max * s_max),
            }
        }
        damping = Some(lambda);
        if !accepted {
            counts.0 += iterations;
            return Ok(Outcome::Stalled {
                state,
                damping: lambda,
            });
        }
    }
}

/// Refuses options that cannot judge a fit or match a measurement.
fn check_options(options: &FitOptions) -> Result<(), Error> {
    let refuse = |argument, expected: &str, given: f64| Error::Argument {
        function: "fit",
        argument,
        expected: expected.into(),
        given: given.to_string(),
    };
    let threshold = options.max_reduced_chi_squared;
    // NaN would make every verdict false, 0 every fit with noise a failure
    if threshold.is_nan() || threshold <= 0.0 {
        return Err(refuse(
            "options.max_reduced_chi_squared",
            "positive",
            threshold,
        ));
    }
    let window = options.frequency_window;
    if !(window.is_finite() && window > 1.0) {
        return Err(refuse(
            "options.frequency_window",
            "a factor above 1",
            window,
        ));
    }
    if options.starts == 0 {
        return Err(Error::Argument {
            function: "fit",
            argument: "options.starts",
            expected: "at least 1 (the case's values)".into(),
            given: "0".into(),
        });
    }
    Ok(())
}

/// The start values of the `free` parameters of `case`: each a parameter of its model, read
/// by it, listed once and finite.
fn start_values(case: &Case, free: &[String]) -> Result<Vec<f64>, Error> {
    // the free parameters: known, read, listed once
    if free.is_empty() {
        return Err(FitError::Parameter {
            name: String::new(),
            message: "no free parameters (--free p1,p2,...)".into(),
        }
        .into());
    }
    let (_, resolved) = case.build()?;
    let read = case.parameters_read(&resolved)?;
    let mut start = Vec::with_capacity(free.len());
    for (k, name) in free.iter().enumerate() {
        if free[..k].contains(name) {
            return Err(FitError::Parameter {
                name: name.clone(),
                message: "listed twice".into(),
            }
            .into());
        }
        let value = resolved.get(name).map_err(|_| FitError::Parameter {
            name: name.clone(),
            message: format!(
                "not a parameter of model '{}' (see pendkit params)",
                case.model.name()
            ),
        })?;
        if !read.contains(name) {
            return Err(FitError::Parameter {
                name: name.clone(),
                message: "read by nothing in the model".into(),
            }
            .into());
        }
        if !value.is_finite() {
            return Err(FitError::NotFinite(format!("start value of '{name}'")).into());
        }
        refuse_count(case, name, value)?;
        start.push(value);
    }
    Ok(start)
}

/// Refuses a free parameter `name` (at `value`) that the model takes only at whole or
/// listed values (a count such as `n_beads`, a switch such as `allowed = [0, 1]`): a fit
/// moves every parameter continuously, and such a parameter failed later with a Jacobian's
/// error about a step of −2e-6. A value a millionth away (the sensitivities' step) that the
/// model refuses is the sign; the parameters' own domains, checked on build, give the
/// same refusal a continuous parameter's start could only meet at its domain's edge.
fn refuse_count(case: &Case, name: &str, value: f64) -> Result<(), Error> {
    let nearby = value + 1e-6 * value.abs().max(1.0);
    let probe = case
        .clone()
        .with_sets(&[format!("{name}={nearby}")])
        .and_then(|c| c.build());
    match probe {
        Ok(_) => Ok(()),
        Err(e) => Err(FitError::Parameter {
            name: name.to_string(),
            message: format!(
                "{name} is a count or a switch (the model refuses {name} = {nearby}: {e}): counts and switches cannot be fitted; fix it at a value instead"
            ),
        }
        .into()),
    }
}

/// The fit's state at `values`: the solution `result`'s |TF| at `tf_freqs` (when `tf` is
/// fitted) and the weighted residuals of its matched modes and |TF| points.
fn state_at(
    measured: &MeasuredModes,
    tf: Option<&MeasuredTf>,
    tf_freqs: &[f64],
    values: &[f64],
    matched: &MatchedModes,
    result: &StageResult,
) -> Result<State, Error> {
    let tf_model = match tf {
        Some(t) => tf_values(result, t, tf_freqs)?,
        None => Vec::new(),
    };
    let r = residuals(&matched.hz, measured, tf, &tf_model);
    // a residual that is not finite, or whose square overflows χ², names its line
    if let Some(i) = r.iter().position(|x| !(x * x).is_finite()) {
        return Err(residual_error(measured, tf, i, r[i]).into());
    }
    Ok(State {
        values: values.to_vec(),
        matched: matched.clone(),
        tf_model,
        chi_squared: r.norm_squared(),
        r,
    })
}

/// The Jacobian of the modes (and |TF| points) over the free parameters at `state`, by the
/// method `options` name; with the number of stage solutions it took.
fn jacobian(
    case: &Case,
    options: &FitOptions,
    free: &[String],
    state: &State,
    tf: Option<&MeasuredTf>,
    tf_freqs: &[f64],
) -> Result<(DMatrix<f64>, usize), Error> {
    let stage = options.stage;
    let mut solves = 0;
    let jacobian = match options.jacobian {
        JacobianMethod::Exact => {
            // one stage solution, and the |TF| rows' four rebuilds of the stage per
            // parameter (the matrices' stencil)
            let (modes, tf_rows) =
                exact_jacobian(case, stage, free, &state.values, &state.matched, tf)?;
            solves += 1 + tf.map_or(0, |_| 4 * free.len());
            match tf_rows {
                Some(t) => stack(&modes, &t),
                None => modes,
            }
        }
        JacobianMethod::Differences => {
            let (_, modes) = mode_jacobian(
                case,
                stage,
                free,
                &state.values,
                &state.matched,
                options.relative_step,
            )?;
            solves += 2 * free.len();
            match tf {
                Some(t) => {
                    let rows = central_differences(
                        case,
                        stage,
                        free,
                        &state.values,
                        options.relative_step,
                        |result| tf_values(result, t, tf_freqs),
                    )?;
                    solves += 2 * free.len();
                    stack(&modes, &rows)
                }
                None => modes,
            }
        }
    };
    Ok((jacobian, solves))
}

/// What the model declares of each free parameter: its unit and its domain.
struct Declarations {
    units: Vec<Option<String>>,
    domains: Vec<Option<Domain>>,
}

/// The unit and the domain each of the `free` parameters of `case`'s model declares.
fn parameter_declarations(case: &Case, free: &[String]) -> Result<Declarations, Error> {
    let defaults = pendkit_model::Defaults::of(&*case.model)?;
    Ok(Declarations {
        units: free
            .iter()
            .map(|name| defaults.params.unit(name).map(str::to_string))
            .collect(),
        domains: free
            .iter()
            .map(|name| defaults.params.domain(name))
            .collect(),
    })
}

/// The parameters `values` after the step `delta` in relative units (times `scale`), each
/// kept inside its domain ([`within`]).
fn stepped(
    values: &[f64],
    delta: &DVector<f64>,
    scale: &[f64],
    domains: &[Option<Domain>],
) -> Vec<f64> {
    values
        .iter()
        .zip(delta.iter().zip(scale))
        .zip(domains)
        .map(|((&x, (d, sc)), domain)| within(*domain, x, x + d * sc))
        .collect()
}

/// How far toward the edge of its domain one step may take a parameter: nine tenths of
/// the way, so that a parameter the data drive toward 0 (a length, a mass) approaches it
/// in a few shrinking steps instead of leaving the domain in one.
const TOWARD_EDGE: f64 = 0.9;

/// The value a step from `from` toward `to` takes a parameter with `domain` to: `to`
/// itself inside the domain, else nine tenths of the way from `from` to the edge it
/// crosses (the Gauss–Newton step of a length 1.9 times too long, −1.8 of it, would
/// otherwise make it negative, a value the model refuses and the fit could only back away
/// from by damping every parameter's step).
fn within(domain: Option<Domain>, from: f64, to: f64) -> f64 {
    let Some(domain) = domain else {
        return to;
    };
    if domain.contains(to) {
        return to;
    }
    let edge = match domain {
        Domain::Positive | Domain::NonNegative => 0.0,
        Domain::Between(low, high) => {
            if to <= low {
                low
            } else {
                high
            }
        }
        Domain::Finite => return to,
    };
    let shortened = from + TOWARD_EDGE * (edge - from);
    // a start on the edge itself (0 of a `>= 0` parameter) cannot move past it
    if domain.contains(shortened) {
        shortened
    } else {
        from
    }
}

/// The σ of every measurement, in the order of the residuals: the modes, then the |TF|
/// points.
fn sigmas(measured: &MeasuredModes, tf: Option<&MeasuredTf>) -> Vec<f64> {
    measured
        .modes
        .iter()
        .map(|m| m.sigma_hz)
        .chain(tf.iter().flat_map(|t| t.points.iter().map(|p| p.sigma_abs)))
        .collect()
}

/// The SVD of the `n_data` × `n_free` Jacobian weighted to relative parameter units: rows
/// / σ, columns × scale.
fn weighted_svd(
    jacobian: &DMatrix<f64>,
    sigma: &[f64],
    scale: &[f64],
    n_data: usize,
    n_free: usize,
) -> Result<nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>, Error> {
    let weighted = DMatrix::from_fn(n_data, n_free, |i, p| {
        jacobian[(i, p)] / sigma[i] * scale[p]
    });
    if weighted.iter().any(|x| !x.is_finite()) {
        return Err(FitError::NotFinite("the Jacobian".into()).into());
    }
    Ok(weighted.clone().svd(true, true))
}

/// The largest singular value in `s`, the directions the data determine (singular values
/// above `undetermined_below` of the largest) and the residual `r`'s component along each
/// (columns of `u`).
fn determined_directions(
    u: &DMatrix<f64>,
    s: &DVector<f64>,
    r: &DVector<f64>,
    undetermined_below: f64,
) -> (f64, Vec<usize>, Vec<f64>) {
    let s_max = s.iter().copied().fold(0.0, f64::max);
    let determined: Vec<usize> = (0..s.len())
        .filter(|&i| s_max > 0.0 && s[i] > undetermined_below * s_max)
        .collect();
    let c: Vec<f64> = determined.iter().map(|&i| u.column(i).dot(r)).collect();
    (s_max, determined, c)
}

/// The fit to `measured` stopped without converging after `iterations`, at `state` with
/// damping `damping`.
fn not_converged(
    measured: &MeasuredModes,
    problem: &Problem,
    state: &State,
    iterations: usize,
    damping: f64,
) -> Error {
    FitError::NotConverged {
        path: measured.path.clone(),
        iterations,
        chi_squared: state.chi_squared,
        values: sets(problem.free, &state.values).join(" "),
        damping,
        at_edge: at_domain_edges(problem, &state.values),
    }
    .into()
}

/// The free parameters whose `values` sit on the edge of their declared domain (within a
/// millionth of the edge or of the start value, whichever is larger): where a fit that
/// steps nine tenths of the way to an edge each time ends when the data pull a parameter
/// outside its domain (a break-off out of its body, a mass through zero). Each as `"; NAME
/// = VALUE UNIT is at the edge of its domain DOMAIN: the data ask for a value outside
/// it"`.
fn at_domain_edges(problem: &Problem, values: &[f64]) -> String {
    let mut said = String::new();
    for (k, &value) in values.iter().enumerate() {
        let Some(domain) = problem.domains[k] else {
            continue;
        };
        let edges: &[f64] = match domain {
            Domain::Positive | Domain::NonNegative => &[0.0],
            Domain::Between(low, high) => &[low, high],
            Domain::Finite => &[],
        };
        let tolerance = 1e-6 * problem.scale[k].abs();
        if let Some(edge) = edges
            .iter()
            .find(|&&edge| (value - edge).abs() <= tolerance.max(1e-6 * edge.abs()))
        {
            let unit = match problem.units[k].as_deref() {
                Some(unit) if !unit.is_empty() && unit != "-" => format!(" {unit}"),
                _ => String::new(),
            };
            said.push_str(&format!(
                "; {} = {edge}{unit} is at the edge of its domain {}: the data ask for a value outside it",
                problem.free[k],
                domain.describe()
            ));
        }
    }
    said
}

/// `a` above `b`.
fn stack(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows() + b.nrows(), a.ncols(), |i, j| {
        if i < a.nrows() {
            a[(i, j)]
        } else {
            b[(i - a.nrows(), j)]
        }
    })
}

/// Each measured mode against the model's mode matched to it at `state`.
fn mode_residuals(measured: &MeasuredModes, state: &State) -> Vec<ModeResidual> {
    measured
        .modes
        .iter()
        .zip(&state.matched.indices)
        .zip(&state.matched.hz)
        .zip(&state.matched.labels)
        .map(|(((m, &k), &f), model_label)| ModeResidual {
            label: m.label.clone(),
            mode: k + 1,
            model_label: model_label.clone(),
            measured_hz: m.hz,
            sigma_hz: m.sigma_hz,
            model_hz: f,
            normalized: (m.hz - f) / m.sigma_hz,
            line: m.line,
        })
        .collect()
}

/// Each measured |TF| point (when `tf` is fitted) against the model's at `state`.
fn tf_residuals(tf: Option<&MeasuredTf>, state: &State) -> Vec<TfResidual> {
    tf.map_or_else(Vec::new, |t| {
        t.points
            .iter()
            .zip(&state.tf_model)
            .map(|(p, &model)| TfResidual {
                freq_hz: p.freq_hz,
                measured: p.abs,
                sigma: p.sigma_abs,
                model,
                normalized: (p.abs - model) / p.sigma_abs,
                line: p.line,
            })
            .collect()
    })
}

/// Below this squared weight on the undetermined directions a parameter counts as
/// determined (its component there is numerical noise of the Jacobian).
const UNDETERMINED_WEIGHT: f64 = 1e-6;

/// The result at the converged `state`, whose Jacobian's SVD is `svd` with `determined`
/// directions; `counts` = (iterations, solves).
fn finish(
    problem: &Problem,
    state: &State,
    svd: &nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    determined: &[usize],
    counts: (usize, usize),
) -> FitResult {
    let Problem {
        options,
        measured,
        tf,
        free,
        start,
        scale,
        units,
        ..
    } = problem;
    let max_reduced_chi_squared = &options.max_reduced_chi_squared;
    let (iterations, solves) = counts;
    let n = free.len();
    let s = &svd.singular_values;
    let s_max = s.iter().copied().fold(0.0, f64::max);
    let v_t = svd.v_t.clone().unwrap_or_else(|| DMatrix::identity(n, n));
    let undetermined_dirs: Vec<usize> = (0..s.len()).filter(|i| !determined.contains(i)).collect();
    // covariance in relative units on the determined directions, then in the parameters'
    let mut cov = DMatrix::zeros(n, n);
    for &i in determined {
        let v = v_t.row(i).transpose();
        cov += &v * v.transpose() / (s[i] * s[i]);
    }
    let cov = DMatrix::from_fn(n, n, |a, b| cov[(a, b)] * scale[a] * scale[b]);
    let is_determined: Vec<bool> = (0..n)
        .map(|p| {
            undetermined_dirs
                .iter()
                .map(|&i| v_t[(i, p)] * v_t[(i, p)])
                .sum::<f64>()
                < UNDETERMINED_WEIGHT
        })
        .collect();
    let parameters = (0..n)
        .map(|p| FittedParameter {
            name: free[p].clone(),
            unit: units[p].clone(),
            start: start[p],
            value: state.values[p],
            uncertainty: is_determined[p].then(|| cov[(p, p)].sqrt()),
        })
        .collect();
    let correlation = (0..n)
        .map(|a| {
            (0..n)
                .map(|b| {
                    (is_determined[a] && is_determined[b])
                        .then(|| cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt())
                        .filter(|x| x.is_finite())
                })
                .collect()
        })
        .collect();
    let modes = mode_residuals(measured, state);
    let tf = tf_residuals(*tf, state);
    let undetermined = undetermined_dirs
        .iter()
        .map(|&i| {
            let mut combination: Vec<(String, f64)> = (0..n)
                .map(|p| (free[p].clone(), v_t[(i, p)]))
                .filter(|(_, c)| c.abs() >= 1e-3)
                .collect();
            combination.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            // a sign convention: the largest coefficient positive
            if combination.first().is_some_and(|(_, c)| *c < 0.0) {
                for (_, c) in &mut combination {
                    *c = -*c;
                }
            }
            Undetermined {
                relative_singular_value: if s_max > 0.0 { s[i] / s_max } else { 0.0 },
                combination,
            }
        })
        .collect();
    let n_data = state.r.len();
    let dof = n_data.saturating_sub(determined.len());
    let mut singular_values: Vec<f64> = s.iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let reduced_chi_squared = (dof > 0).then(|| state.chi_squared / dof as f64);
    FitResult {
        parameters,
        correlation,
        modes,
        tf,
        chi_squared: state.chi_squared,
        dof,
        reduced_chi_squared,
        // with no degree of freedom there is nothing to judge by (fit() asks for more
        // measurements than free parameters, so it does not happen there)
        explains_data: reduced_chi_squared.is_none_or(|r| r <= *max_reduced_chi_squared),
        max_reduced_chi_squared: *max_reduced_chi_squared,
        singular_values,
        undetermined,
        iterations,
        solves,
        restarts: 0,
        starts: 1,
        would_help: Vec::new(),
        jacobian: options.jacobian,
    }
}
