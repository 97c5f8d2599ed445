//! pendkit for Python: the compiled core of the `pendkit` package, binding the library
//! facade (models, case files, stages, modes, transfer functions, thermal noise, state
//! space) to Python objects and numpy arrays, with the GIL released while Rust computes.
//!
//! The physics is all in the `pendkit` crate: each method here parses its arguments as the
//! command line does (`crates/interface/cli/src/common.rs`), calls the same library function, and
//! converts the answer to numpy. Errors are `pendkit.PendkitError` (a `ValueError`) with the
//! library's one-line message, the line the command line prints after `error: `.

use std::fmt::Display;
use std::path::Path;
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{
    Complex64, IntoPyArray, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods,
};
use pendkit::params::Resolved;
use pendkit::stage::NamedStateSpace;
use pendkit::stage::RunOptions;
use pendkit::stage::run_stage_with;
use pendkit::{Case, Error, NoiseOptions, Stage, StageResult};
use pyo3::create_exception;
use pyo3::exceptions::{PyImportError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

create_exception!(
    _pendkit,
    PendkitError,
    PyValueError,
    "A pendkit error: bad input (model, parameter, name, frequency) or a failed calculation; \
     the message is the one line the command line prints."
);

/// Any printable error as a `PendkitError`.
fn error(e: impl Display) -> PyErr {
    PendkitError::new_err(e.to_string())
}

/// Where a model's case comes from, kept so that the model can be rebuilt in another
/// process (pickling).
#[derive(Clone, Debug)]
enum Source {
    /// A bundled model, by name.
    Bundled(String),
    /// A case file: the path it was read from and its text.
    CaseFile { path: String, text: String },
}

/// A model or case with parameter overrides, ready to run.
///
/// `Model(spec, set=None)`: `spec` is a bundled model name (`"quad"`, see
/// `pendkit.models()`) or the path of a case file (`.toml`); `set` overrides parameters,
/// as a dict `{"d4": 0.01, "m3": "scale(1.1)"}` or a list of `"NAME=EXPR"` strings, applied
/// in order after the case file's own (`damping.<tag>.<field>` sets a damping field), as
/// the command line's `--set`.
///
/// Models pickle (by model name or case-file text, and the overrides), so they can be
/// sent to worker processes and Dask clusters.
#[pyclass(module = "pendkit._pendkit", frozen)]
struct Model {
    source: Source,
    sets: Vec<String>,
    case: Case,
}

/// `NAME=EXPR` strings from a dict (values as `str()` gives them: Python's `repr` of a
/// float reads back exactly) or a sequence of strings.
fn set_strings(set: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(set) = set else {
        return Ok(Vec::new());
    };
    if set.is_none() {
        return Ok(Vec::new());
    }
    if let Ok(dict) = set.cast::<PyDict>() {
        return dict
            .iter()
            .map(|(k, v)| {
                let name: String = k.str()?.extract()?;
                let value = if v.is_instance_of::<PyString>() {
                    v.extract::<String>()?
                } else {
                    v.repr()?.extract::<String>()?
                };
                Ok(format!("{name}={value}"))
            })
            .collect();
    }
    if set.is_instance_of::<PyString>() {
        return Err(error(
            "set: expected a dict {name: value} or a list of 'NAME=EXPR' strings, not one string",
        ));
    }
    let items = set.try_iter().map_err(|_| {
        error("set: expected a dict {name: value} or a list of 'NAME=EXPR' strings")
    })?;
    items
        .map(|item| {
            item?
                .extract::<String>()
                .map_err(|_| error("set: each item of the list must be a 'NAME=EXPR' string"))
        })
        .collect()
}

/// A stage given as `"0a"` … `"2"` (any object whose `str()` is one), or stage 2, the
/// complete model, when none is given (as the command line).
fn stage_or_complete(stage: Option<&Bound<'_, PyAny>>) -> PyResult<Stage> {
    match stage {
        None => Ok(Stage::S2),
        Some(s) => s
            .str()?
            .extract::<String>()?
            .parse::<Stage>()
            .map_err(error),
    }
}

/// A path given as a str or an os.PathLike.
fn fspath(path: &Bound<'_, PyAny>) -> PyResult<String> {
    path.py()
        .import("os")?
        .call_method1("fspath", (path,))
        .and_then(|p| p.extract::<String>())
        .map_err(|_| error("expected a path (str or os.PathLike)"))
}

/// Measured modes from a CSV file's path, or from a list of `(label, hz, sigma_hz[,
/// shape])` tuples (checked as a file's lines are; the errors name item k, from 0, `modes:k+1`).
fn measured_modes(modes: &Bound<'_, PyAny>) -> PyResult<pendkit::fit::MeasuredModes> {
    if modes.is_instance_of::<PyString>() || modes.hasattr("__fspath__")? {
        return pendkit::fit::MeasuredModes::read(Path::new(&fspath(modes)?)).map_err(error);
    }
    let mut rows: Vec<Vec<String>> = Vec::new();
    for item in modes.try_iter().map_err(|_| {
        error("modes: expected a file path or a list of (label, hz, sigma_hz[, shape]) tuples")
    })? {
        let item = item?;
        let k = rows.len();
        // a str is iterable too: its characters would pass for fields
        if item.is_instance_of::<PyString>() {
            return Err(error(format!(
                "modes[{k}]: expected a tuple (label, hz, sigma_hz[, shape]), got a str"
            )));
        }
        let fields: Vec<String> = item
            .try_iter()
            .map_err(|_| {
                error(format!(
                    "modes[{k}]: expected a tuple (label, hz, sigma_hz[, shape])"
                ))
            })?
            .map(|f| f.and_then(|f| f.str()?.extract::<String>()))
            .collect::<PyResult<_>>()?;
        rows.push(fields);
    }
    // the items are rows, not a file's lines: a '#' or ',' in a label is the label's
    pendkit::fit::MeasuredModes::from_rows(Path::new("modes"), &rows).map_err(error)
}

impl Model {
    fn open(source: Source, sets: Vec<String>) -> Result<Model, Error> {
        let case = match &source {
            Source::Bundled(name) => Case::model(name)?,
            Source::CaseFile { path, text } => Case::from_text(Path::new(path), text)?,
        }
        .with_sets(&sets)?;
        Ok(Model { source, sets, case })
    }
}

#[pymethods]
impl Model {
    #[new]
    #[pyo3(signature = (spec, set = None, *, _case_text = None))]
    fn new(
        spec: &Bound<'_, PyAny>,
        set: Option<&Bound<'_, PyAny>>,
        _case_text: Option<String>,
    ) -> PyResult<Model> {
        // a str, or an os.PathLike (pathlib.Path) naming a case file
        let spec: String = match spec.extract::<String>() {
            Ok(s) => s,
            Err(_) => spec
                .py()
                .import("os")?
                .call_method1("fspath", (spec,))
                .and_then(|p| p.extract::<String>())
                .map_err(|_| error("spec: expected a model name or a case-file path"))?,
        };
        let sets = set_strings(set)?;
        let path = Path::new(&spec);
        let source = match _case_text {
            Some(text) => Source::CaseFile { path: spec, text },
            // the rule of `Case::open`: a `.toml` name or an existing file is a case file
            None if spec.ends_with(".toml") || path.is_file() => {
                let text = pendkit_limits::read_text(path).map_err(|e| {
                    error(Error::Case {
                        path: path.to_path_buf(),
                        message: e.to_string(),
                    })
                })?;
                Source::CaseFile { path: spec, text }
            }
            None => Source::Bundled(spec),
        };
        Model::open(source, sets).map_err(error)
    }

    /// The arguments that rebuild this model in another process (pickle).
    fn __getnewargs_ex__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let kwargs = PyDict::new(py);
        kwargs.set_item("set", PyList::new(py, &self.sets)?)?;
        let spec = match &self.source {
            Source::Bundled(name) => name.clone(),
            Source::CaseFile { path, text } => {
                kwargs.set_item("_case_text", text)?;
                path.clone()
            }
        };
        Ok((PyTuple::new(py, [spec])?, kwargs))
    }

    fn __repr__(&self) -> String {
        let spec = match &self.source {
            Source::Bundled(name) => name,
            Source::CaseFile { path, .. } => path,
        };
        if self.sets.is_empty() {
            format!("pendkit.Model({spec:?})")
        } else {
            format!("pendkit.Model({spec:?}, set={:?})", self.sets)
        }
    }

    /// Case name: the model name, or the case file's stem.
    #[getter]
    fn name(&self) -> String {
        self.case.name.clone()
    }

    /// The bundled model the case refines.
    #[getter]
    fn model(&self) -> String {
        self.case.model.name().to_string()
    }

    /// The case file's description, if any.
    #[getter]
    fn description(&self) -> Option<String> {
        self.case.description.clone()
    }

    /// The overrides given to this model, as `NAME=EXPR` strings in order.
    #[getter]
    fn sets(&self) -> Vec<String> {
        self.sets.clone()
    }

    /// This model with more overrides (applied after this model's own): a dict or a list
    /// of `NAME=EXPR` strings.
    fn with_set(&self, set: &Bound<'_, PyAny>) -> PyResult<Model> {
        let mut sets = self.sets.clone();
        sets.extend(set_strings(Some(set))?);
        Model::open(self.source.clone(), sets).map_err(error)
    }

    /// Every numeric parameter as resolved (with the overrides): a list of `Parameter`
    /// (name, value, unit, definition, overridden).
    fn parameters(&self, py: Python<'_>) -> PyResult<Vec<Parameter>> {
        let case = &self.case;
        py.detach(|| {
            let (_, resolved) = case.build()?;
            parameters(case, &resolved)
        })
        .map_err(error)
    }

    /// Fits the parameters named in `free` (a list of names) to measured mode frequencies,
    /// starting from this model's values, as `pendkit fit`: `modes` is the path of a
    /// measured-modes CSV file (`label,hz,sigma_hz[,shape]`) or a list of tuples
    /// `(label, hz, sigma_hz)` or `(label, hz, sigma_hz, shape)`; `tf` the path of a
    /// measured |TF| file. Returns a dict: `parameters` (name, unit, start, value,
    /// uncertainty: None when undetermined), `correlation`, `modes` (residuals), `tf`,
    /// `chi_squared`, `dof`, `reduced_chi_squared`, `singular_values`, `undetermined`
    /// (combinations), `iterations`, `solves`, `jacobian` (how the Jacobian was computed:
    /// `"exact"`, the default — the modes' rows exact, the |TF| rows from the same
    /// sensitivities — or `"differences"`, central differences of the re-solved model, as
    /// `jacobian=` asks), and
    /// `case_file` (the text of the fitted case file when the model is a bundled one, else
    /// None).
    #[pyo3(signature = (modes, free, *, tf = None, stage = None, jacobian = "exact"))]
    fn fit<'py>(
        &self,
        py: Python<'py>,
        modes: &Bound<'py, PyAny>,
        free: Vec<String>,
        tf: Option<&Bound<'py, PyAny>>,
        stage: Option<&Bound<'py, PyAny>>,
        jacobian: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let stage = stage_or_complete(stage)?;
        let jacobian: pendkit::fit::JacobianMethod = jacobian
            .parse()
            .map_err(|e: String| PyValueError::new_err(e))?;
        let measured = measured_modes(modes)?;
        let tf = match tf {
            None => None,
            Some(path) => {
                Some(pendkit::fit::MeasuredTf::read(Path::new(&fspath(path)?)).map_err(error)?)
            }
        };
        let case = self.case.clone();
        let options = pendkit::fit::FitOptions {
            stage,
            jacobian,
            ..pendkit::fit::FitOptions::default()
        };
        let result = py
            .detach(|| pendkit::fit::fit(&case, &measured, tf.as_ref(), &free, &options))
            .map_err(error)?;
        let case_file = match &self.source {
            Source::Bundled(name) => Some(result.case_file(name, &case)),
            Source::CaseFile { .. } => None,
        };
        let text = serde_json::to_string(&result).map_err(error)?;
        let dict = py.import("json")?.call_method1("loads", (text,))?;
        dict.set_item("case_file", case_file)?;
        Ok(dict)
    }

    /// Builds the model and runs `stage` (`"0a"`, `"0b"`, `"1a"`, `"1b"` or `"2"`; default
    /// `"2"`, the complete model, as the command line): equilibrium, matrices and every
    /// normal mode. Returns a `Result`.
    #[pyo3(signature = (stage = None))]
    fn run(&self, py: Python<'_>, stage: Option<&Bound<'_, PyAny>>) -> PyResult<StageRun> {
        let stage = stage_or_complete(stage)?;
        let case = self.case.clone();
        let run = py
            .detach(move || -> std::result::Result<Run, Error> {
                let (system, resolved) = case.build()?;
                let result = run_stage_with(system, stage, &RunOptions::default(), None)?;
                Ok(Run {
                    case,
                    stage,
                    resolved,
                    result,
                })
            })
            .map_err(error)?;
        Ok(StageRun { run: Arc::new(run) })
    }

    /// Derivatives with respect to the parameters at `stage` (default `"2"`), as
    /// `pendkit sensitivity`: of every mode frequency (`modes=True`), of |H| of the transfer
    /// function `tf=(input, output)` and of the thermal-noise ASD of the displacement
    /// output `noise`, at `freqs` (Hz, array-like; needed with `tf` or `noise`).
    /// `parameters` (names) restricts the columns (default: every parameter).
    /// `allow_unstable=True` goes on from an unstable equilibrium (the warning is in
    /// `Sensitivities.warning`). `differences=True` differences the stage's matrices for
    /// every parameter, even where the exact route is open. Returns a `Sensitivities`.
    #[pyo3(signature = (stage = None, *, modes = true, tf = None, noise = None, freqs = None, parameters = None, allow_unstable = false, differences = false))]
    #[allow(clippy::too_many_arguments)]
    fn sensitivities(
        &self,
        py: Python<'_>,
        stage: Option<&Bound<'_, PyAny>>,
        modes: bool,
        tf: Option<(String, String)>,
        noise: Option<String>,
        freqs: Option<&Bound<'_, PyAny>>,
        parameters: Option<Vec<String>>,
        allow_unstable: bool,
        differences: bool,
    ) -> PyResult<Sensitivities> {
        let stage = stage_or_complete(stage)?;
        let freqs = match freqs {
            Some(f) => frequencies(f)?,
            None => Vec::new(),
        };
        let request = pendkit::sensitivity::SensitivityRequest {
            stage,
            modes,
            tf,
            noise,
            freqs,
            parameters,
            allow_unstable,
            threads: 0,
            differences,
        };
        let case = &self.case;
        let s = py
            .detach(|| pendkit::sensitivity::sensitivities(case, &request))
            .map_err(error)?;
        let rows = |m: &[Vec<f64>], columns: usize| {
            let data: Vec<f64> = m.iter().flatten().copied().collect();
            Array2::from_shape_vec((m.len(), columns), data)
                .map(|a| a.into_pyarray(py).unbind())
                .map_err(error)
        };
        let np = s.parameters.len();
        let pair = |x: &Option<(Vec<f64>, Vec<Vec<f64>>)>| -> PyResult<_> {
            Ok(match x {
                Some((v, d)) => (
                    Some(PyArray1::from_slice(py, v).unbind()),
                    Some(rows(d, np)?),
                ),
                None => (None, None),
            })
        };
        let (tf_abs, dtf_abs_dp) = pair(&s.tf_abs)?;
        let (noise_asd, dnoise_asd_dp) = pair(&s.noise_asd)?;
        Ok(Sensitivities {
            values: PyArray1::from_slice(py, &s.values).unbind(),
            modes_hz: PyArray1::from_slice(py, &s.modes_hz).unbind(),
            dfdp: rows(&s.dfdp, np)?,
            freqs: PyArray1::from_slice(py, &request.freqs).unbind(),
            parameters: s.parameters,
            units: s.units,
            mode_labels: s.mode_labels,
            tf_abs,
            dtf_abs_dp,
            noise_asd,
            dnoise_asd_dp,
            not_differentiable: s.not_differentiable,
            exact: s.exact,
            warning: s.warning,
        })
    }
}

/// Derivatives of a stage's answers with respect to the parameters (`Model.sensitivities`):
/// `parameters`, `values`, `units` (the columns), `modes_hz` and `mode_labels` (the rows of
/// `dfdp`), `dfdp` (modes × parameters, Hz per unit of the parameter; no rows when the
/// modes were not asked for), `freqs` (Hz), `tf_abs` and `dtf_abs_dp` (frequencies ×
/// parameters), `noise_asd` and `dnoise_asd_dp` (None unless asked for),
/// `not_differentiable` ((name, why) of switches and counts left out), `exact` (per
/// parameter: its mode sensitivities differentiated exactly by dual numbers and the
/// implicit function theorem, or exactly 0 for a parameter nothing or only the loss angles
/// read, else by differences of the stage's matrices; the |H| and
/// noise sensitivities are always differenced) and `warning`.
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct Sensitivities {
    parameters: Vec<String>,
    values: Py<PyArray1<f64>>,
    units: Vec<String>,
    modes_hz: Py<PyArray1<f64>>,
    mode_labels: Vec<String>,
    dfdp: Py<PyArray2<f64>>,
    freqs: Py<PyArray1<f64>>,
    tf_abs: Option<Py<PyArray1<f64>>>,
    dtf_abs_dp: Option<Py<PyArray2<f64>>>,
    noise_asd: Option<Py<PyArray1<f64>>>,
    dnoise_asd_dp: Option<Py<PyArray2<f64>>>,
    not_differentiable: Vec<(String, String)>,
    exact: Vec<bool>,
    warning: Option<String>,
}

#[pymethods]
impl Sensitivities {
    fn __repr__(&self) -> String {
        format!(
            "<pendkit.Sensitivities: {} modes × {} parameters>",
            self.mode_labels.len(),
            self.parameters.len()
        )
    }
}

fn parameters(case: &Case, resolved: &Resolved) -> std::result::Result<Vec<Parameter>, Error> {
    Ok(case
        .provenance(resolved)?
        .parameters
        .into_iter()
        .map(|p| Parameter {
            name: p.name,
            value: p.value,
            unit: p.unit.unwrap_or_default(),
            definition: p.definition,
            overridden: p.overridden,
        })
        .collect())
}

/// One parameter as resolved: `name`, `value` (in `unit`), `unit` (SI; empty for a pure
/// number), `definition` (the expression: the model's default or the override) and
/// `overridden` (whether an override set it).
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct Parameter {
    name: String,
    value: f64,
    unit: String,
    definition: String,
    overridden: bool,
}

#[pymethods]
impl Parameter {
    fn __repr__(&self) -> String {
        format!(
            "Parameter(name={:?}, value={:?}, unit={:?}, definition={:?}, overridden={})",
            self.name,
            self.value,
            self.unit,
            self.definition,
            if self.overridden { "True" } else { "False" }
        )
    }
}

/// One run of a stage.
struct Run {
    case: Case,
    stage: Stage,
    resolved: Resolved,
    result: StageResult,
}

impl Run {
    /// A coordinate's name in `scheme` (the model's own without one).
    fn coord(&self, scheme: Option<&str>, name: &str) -> String {
        match scheme {
            Some(s) => self
                .result
                .name_scheme(s)
                .map_or(name, |n| n.coord(name))
                .to_string(),
            None => name.to_string(),
        }
    }

    /// `scheme` unless it is `None` or `"model"`, after checking the model declares it.
    fn scheme<'a>(&self, naming: Option<&'a str>) -> PyResult<Option<&'a str>> {
        match naming {
            None | Some("model") => Ok(None),
            Some(s) => {
                self.result.name_scheme(s).map_err(error)?;
                Ok(Some(s))
            }
        }
    }

    /// Transfer functions, noise and state space need losses (stage 0B or later).
    fn check_lossy(&self) -> PyResult<()> {
        if self.stage == Stage::S0A {
            return Err(error(Error::StageTooEarly));
        }
        Ok(())
    }
}

/// Frequencies (Hz) from any array-like: one-dimensional, not empty, each finite and
/// positive, or a `PendkitError` naming the first bad one as the command line does.
fn frequencies(freqs: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let values: Vec<f64> = match freqs.cast::<PyArray1<f64>>() {
        // the common case, read in place (any strides); a misaligned buffer (as unpickled
        // out of band, e.g. by Dask) cannot be viewed and takes the copying path
        Ok(array) if array.is_aligned() => array.readonly().as_array().iter().copied().collect(),
        _ => {
            // a fresh float64 copy of anything array-like: aligned, any shape
            let array = freqs
                .py()
                .import("numpy")?
                .call_method1("array", (freqs, "float64"))
                .map_err(|e| error(format!("freqs: not an array of numbers (Hz): {e}")))?;
            let array = array.cast_into::<PyArrayDyn<f64>>().map_err(error)?;
            if array.ndim() != 1 {
                return Err(error(format!(
                    "freqs: expected a one-dimensional array of frequencies (Hz), got shape {:?}",
                    array.shape()
                )));
            }
            array.readonly().as_array().iter().copied().collect()
        }
    };
    if values.is_empty() {
        return Err(error("freqs: no frequencies"));
    }
    if let Some((i, f)) = values
        .iter()
        .enumerate()
        .find(|(_, f)| !(f.is_finite() && **f > 0.0))
    {
        // the command line's words for the same value (`--freqs nan`, `--freqs -2`)
        return Err(error(if f.is_finite() {
            format!("freqs[{i}]: frequency {f} Hz must be positive")
        } else {
            let text = if f.is_nan() {
                "nan"
            } else if *f > 0.0 {
                "inf"
            } else {
                "-inf"
            };
            format!("freqs[{i}]: '{text}' is not a finite number (Hz)")
        }));
    }
    Ok(values)
}

/// The result of running one stage of a model: equilibrium, matrices and normal modes, from
/// which transfer functions, thermal noise and the state space are computed.
#[pyclass(module = "pendkit._pendkit", name = "Result", frozen)]
struct StageRun {
    run: Arc<Run>,
}

#[pymethods]
impl StageRun {
    fn __repr__(&self) -> String {
        format!(
            "<pendkit.Result {} ({}), stage {}: {} modes>",
            self.run.case.name,
            self.run.case.model.name(),
            self.run.stage,
            self.run.result.modes.modes.len()
        )
    }

    /// Stage name (`"0A"` ... `"2"`).
    #[getter]
    fn stage(&self) -> &'static str {
        self.run.stage.name()
    }

    /// Case name.
    #[getter]
    fn name(&self) -> String {
        self.run.case.name.clone()
    }

    /// Model name.
    #[getter]
    fn model(&self) -> String {
        self.run.case.model.name().to_string()
    }

    /// Temperature of the thermal noise (K).
    #[getter]
    fn temperature(&self) -> f64 {
        self.run.result.system.temperature
    }

    /// The parameters this run resolved (as `Model.parameters()`).
    fn parameters(&self) -> PyResult<Vec<Parameter>> {
        parameters(&self.run.case, &self.run.resolved).map_err(error)
    }

    /// Equilibrium value of every coordinate (m or rad), by name (in `naming`, e.g.
    /// `"ligo"`, or the model's own names).
    #[pyo3(signature = (naming = None))]
    fn equilibrium<'py>(
        &self,
        py: Python<'py>,
        naming: Option<&str>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let scheme = self.run.scheme(naming)?;
        let r = &self.run.result;
        let out = PyDict::new(py);
        for (c, v) in r.system.coords.iter().zip(&r.assembled.equilibrium.coords) {
            out.set_item(self.run.coord(scheme, &c.name), v)?;
        }
        Ok(out)
    }

    /// The normal modes (ascending in ω²): a `Modes` with numpy arrays of frequencies (Hz),
    /// ω², mass-normalised shapes and kinetic-energy fractions, and the labels, families
    /// and coordinate names (in `naming`, e.g. `"ligo"`, or the model's own names).
    #[pyo3(signature = (naming = None))]
    fn modes(&self, py: Python<'_>, naming: Option<&str>) -> PyResult<Modes> {
        let scheme = self.run.scheme(naming)?;
        let r = &self.run.result;
        let list = &r.modes.modes;
        let n = r.modes.coordinates.len();
        let rows = |f: &dyn Fn(&pendkit::dynamics::Mode) -> &Vec<f64>| {
            Array2::from_shape_fn((list.len(), n), |(i, j)| {
                f(&list[i]).get(j).copied().unwrap_or(f64::NAN)
            })
            .into_pyarray(py)
            .unbind()
        };
        Ok(Modes {
            frequencies: PyArray1::from_iter(py, list.iter().map(|m| m.hz)).unbind(),
            omega_squared: PyArray1::from_iter(py, list.iter().map(|m| m.omega_squared)).unbind(),
            stable: PyArray1::from_iter(py, list.iter().map(|m| m.is_stable())).unbind(),
            labels: list
                .iter()
                .map(|m| self.run.coord(scheme, &m.label))
                .collect(),
            families: list.iter().map(|m| r.mode_family(m)).collect(),
            coordinates: r
                .modes
                .coordinates
                .iter()
                .map(|c| self.run.coord(scheme, c))
                .collect(),
            coordinate_units: r
                .modes
                .coordinates
                .iter()
                .map(|c| r.coordinate_unit(c).unwrap_or_default().to_string())
                .collect(),
            shapes: rows(&|m| &m.vector),
            energy_fractions: rows(&|m| &m.energy_fractions),
        })
    }

    /// The stability verdict: a `Stability` (stable, the message naming the first growing
    /// mode, the indices of the unstable modes). An unstable mode has ω² < 0.
    fn stability(&self) -> Stability {
        let r = &self.run.result;
        Stability {
            stable: r.stability().is_ok(),
            message: r.stability().err().map(|e| e.to_string()),
            unstable_modes: r
                .modes
                .modes
                .iter()
                .enumerate()
                .filter(|(_, m)| !m.is_stable())
                .map(|(i, _)| i)
                .collect(),
        }
    }

    /// Raises `PendkitError` with the command line's message if the equilibrium is
    /// unstable (as `pendkit modes` without `--allow-unstable`).
    fn check_stable(&self) -> PyResult<()> {
        self.run.result.stability().map_err(error)
    }

    /// The standard transfer functions as (input, output) names: support to test mass in
    /// each degree of freedom both have, then force (torque) on the test mass to it.
    fn standard_transfer_functions(&self) -> Vec<(String, String)> {
        self.run.result.standard_transfer_functions()
    }

    /// Unit of the transfer function from `input` to `output`, e.g. `"m/m"`, `"rad/(N m)"`.
    fn transfer_unit(&self, input: &str, output: &str) -> String {
        self.run
            .result
            .transfer_unit(input, output)
            .unwrap_or_default()
    }

    /// Transfer function from `input` to `output` at `freqs` (Hz, array-like), with the
    /// model's damping: a complex numpy array, one value per frequency, in one vectorised
    /// call. `input`: a support parameter (`"x00"`, `"GND_L"`), `"force:<variable>"` or
    /// `"force:<body>@x,y,z/dx,dy,dz"`; `output`: a variable (`"x3"`, `"L3_L"`),
    /// `"<body>@x,y,z/dx,dy,dz"` or `"force:<parameter>"`. `full=True` solves every variable
    /// instead of only the blocks the pair couples to (the same numbers, for checking).
    #[pyo3(signature = (input, output, freqs, *, full = false))]
    fn tf<'py>(
        &self,
        py: Python<'py>,
        input: &str,
        output: &str,
        freqs: &Bound<'py, PyAny>,
        full: bool,
    ) -> PyResult<Bound<'py, PyArray1<Complex64>>> {
        self.run.check_lossy()?;
        let freqs = frequencies(freqs)?;
        let run = &self.run;
        let values = py
            .detach(|| {
                run.result
                    .transfer_with(input, output, &freqs, solver(full))
            })
            .map_err(error)?;
        Ok(PyArray1::from_iter(
            py,
            values.iter().map(|z| Complex64::new(z.re, z.im)),
        ))
    }

    /// Thermal noise of the displacement `output` (a variable, or
    /// `"<body>@x,y,z/dx,dy,dz"`) at `freqs` (Hz, array-like), at the model's temperature:
    /// a `Noise` with the PSD (m²/Hz or rad²/Hz) and ASD (m/√Hz or rad/√Hz) and their
    /// breakdown by damping tag (dicts of numpy arrays, adding up to the PSD).
    #[pyo3(signature = (output, freqs, *, full = false))]
    fn noise(
        &self,
        py: Python<'_>,
        output: &str,
        freqs: &Bound<'_, PyAny>,
        full: bool,
    ) -> PyResult<Noise> {
        self.run.check_lossy()?;
        let freqs = frequencies(freqs)?;
        let run = &self.run;
        let options = NoiseOptions {
            solver: solver(full),
            per_term: false,
        };
        let noise = py
            .detach(|| run.result.noise_with(output, &freqs, &options))
            .map_err(error)?;
        let psd_by_tag = PyDict::new(py);
        let asd_by_tag = PyDict::new(py);
        for (tag, psd) in noise.psd_by_tag() {
            psd_by_tag.set_item(tag, PyArray1::from_slice(py, psd))?;
        }
        for (tag, asd) in noise.asd_by_tag() {
            asd_by_tag.set_item(tag, asd.into_pyarray(py))?;
        }
        Ok(Noise {
            unit: format!("{}/√Hz", run.result.output_unit(output).unwrap_or_default()),
            temperature: run.result.system.temperature,
            freqs: freqs.into_pyarray(py).unbind(),
            psd: PyArray1::from_slice(py, noise.psd()).unbind(),
            asd: noise.asd().into_pyarray(py).unbind(),
            psd_by_tag: psd_by_tag.unbind(),
            asd_by_tag: asd_by_tag.unbind(),
        })
    }

    /// State-space matrices with damping represented as viscous at `damping_frequency`
    /// (Hz): exact for viscous damping, and for any damping at `damping_frequency` itself
    /// from forces; without the damping force of the support's velocity. `inputs` and
    /// `outputs` select (and order) columns and rows by name (default: all); names are those
    /// of the state space in `naming` (inputs: support parameters then `force:<variable>`;
    /// outputs: variables then `force:<parameter>`). Returns a `StateSpace`.
    #[pyo3(signature = (inputs = None, outputs = None, *, damping_frequency = 1.0, naming = None))]
    fn state_space<'py>(
        &self,
        py: Python<'py>,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
        damping_frequency: f64,
        naming: Option<&str>,
    ) -> PyResult<StateSpace> {
        self.run.check_lossy()?;
        let scheme = self.run.scheme(naming)?;
        let run = &self.run;
        let named = py
            .detach(|| run.result.named_state_space(damping_frequency, scheme))
            .map_err(error)?;
        StateSpace::select(py, named, inputs, outputs)
    }
}

fn solver(full: bool) -> pendkit::Solver {
    if full {
        pendkit::Solver::Full
    } else {
        pendkit::Solver::Restricted
    }
}

/// Normal modes, ascending in ω²: `frequencies` (Hz; minus the growth rate for an unstable
/// mode), `omega_squared` (rad²/s²), `stable` (bool per mode), `labels` (dominant
/// coordinate), `families` (degree-of-freedom family), `coordinates` and
/// `coordinate_units` (the columns of the next two), `shapes` (modes × coordinates,
/// mass-normalised, m or rad) and `energy_fractions` (modes × coordinates, rows sum to 1).
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct Modes {
    frequencies: Py<PyArray1<f64>>,
    omega_squared: Py<PyArray1<f64>>,
    stable: Py<PyArray1<bool>>,
    labels: Vec<String>,
    families: Vec<String>,
    coordinates: Vec<String>,
    coordinate_units: Vec<String>,
    shapes: Py<PyArray2<f64>>,
    energy_fractions: Py<PyArray2<f64>>,
}

#[pymethods]
impl Modes {
    fn __len__(&self) -> usize {
        self.labels.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<pendkit.Modes: {} modes over {} coordinates>",
            self.labels.len(),
            self.coordinates.len()
        )
    }
}

/// Thermal noise: `freqs` (Hz), `psd` (one-sided, m²/Hz or rad²/Hz), `asd` (m/√Hz or
/// rad/√Hz, `unit`), `psd_by_tag` and `asd_by_tag` (dicts tag → numpy array; the PSDs add
/// up to `psd`), `temperature` (K).
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct Noise {
    freqs: Py<PyArray1<f64>>,
    psd: Py<PyArray1<f64>>,
    asd: Py<PyArray1<f64>>,
    psd_by_tag: Py<PyDict>,
    asd_by_tag: Py<PyDict>,
    unit: String,
    temperature: f64,
}

#[pymethods]
impl Noise {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "<pendkit.Noise: {} frequencies, {} tags, ASD in {}>",
            self.freqs.bind(py).len(),
            self.psd_by_tag.bind(py).len(),
            self.unit
        )
    }
}

/// The stability verdict: `stable` (no mode with ω² < 0), `message` (the command line's
/// one-line error naming the first growing mode, or None) and `unstable_modes` (indices
/// into `Result.modes()`).
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct Stability {
    stable: bool,
    message: Option<String>,
    unstable_modes: Vec<usize>,
}

#[pymethods]
impl Stability {
    fn __bool__(&self) -> bool {
        self.stable
    }

    fn __repr__(&self) -> String {
        match &self.message {
            None => "Stability(stable=True)".into(),
            Some(m) => format!("Stability(stable=False, message={m:?})"),
        }
    }
}

/// A state space ẋ = A x + B u, y = C x + D u: `A`, `B`, `C`, `D` (numpy), the names
/// `states`, `inputs`, `outputs` and their SI units, and `damping_frequency` (Hz).
/// `to_control()` makes a python-control `StateSpace` with the same names.
#[pyclass(module = "pendkit._pendkit", frozen, get_all)]
struct StateSpace {
    #[pyo3(name = "A")]
    a: Py<PyArray2<f64>>,
    #[pyo3(name = "B")]
    b: Py<PyArray2<f64>>,
    #[pyo3(name = "C")]
    c: Py<PyArray2<f64>>,
    #[pyo3(name = "D")]
    d: Py<PyArray2<f64>>,
    states: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    state_units: Vec<String>,
    input_units: Vec<String>,
    output_units: Vec<String>,
    damping_frequency: f64,
}

/// Indices of `wanted` in `names` (all of them when `None`), or an error listing the
/// valid names.
fn pick(what: &str, names: &[String], wanted: Option<Vec<String>>) -> PyResult<Vec<usize>> {
    match wanted {
        None => Ok((0..names.len()).collect()),
        Some(list) => list
            .iter()
            .map(|w| {
                names.iter().position(|n| n == w).ok_or_else(|| {
                    error(format!(
                        "'{w}': not {what} of the state space (valid: {})",
                        names.join(" ")
                    ))
                })
            })
            .collect(),
    }
}

impl StateSpace {
    fn select(
        py: Python<'_>,
        named: NamedStateSpace,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
    ) -> PyResult<StateSpace> {
        let ss = &named.state_space;
        let cols = pick("an input", &ss.inputs, inputs)?;
        let rows = pick("an output", &ss.outputs, outputs)?;
        let n = ss.a.nrows();
        let matrix = |r: usize, c: usize, f: &dyn Fn(usize, usize) -> f64| {
            Array2::from_shape_fn((r, c), |(i, j)| f(i, j))
                .into_pyarray(py)
                .unbind()
        };
        let take = |names: &[String], idx: &[usize]| -> Vec<String> {
            idx.iter().map(|&k| names[k].clone()).collect()
        };
        Ok(StateSpace {
            a: matrix(n, n, &|i, j| ss.a[(i, j)]),
            b: matrix(n, cols.len(), &|i, j| ss.b[(i, cols[j])]),
            c: matrix(rows.len(), n, &|i, j| ss.c[(rows[i], j)]),
            d: matrix(rows.len(), cols.len(), &|i, j| ss.d[(rows[i], cols[j])]),
            states: ss.states.clone(),
            inputs: take(&ss.inputs, &cols),
            outputs: take(&ss.outputs, &rows),
            state_units: named.state_units.clone(),
            input_units: take(&named.input_units, &cols),
            output_units: take(&named.output_units, &rows),
            damping_frequency: ss.damping_frequency,
        })
    }
}

#[pymethods]
impl StateSpace {
    /// A python-control `StateSpace` (`control.ss`) with these matrices and names; needs
    /// python-control (`pip install control`).
    fn to_control<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let control = py.import("control").map_err(|e| {
            PyImportError::new_err(format!(
                "to_control needs python-control (pip install control): {e}"
            ))
        })?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("states", &self.states)?;
        kwargs.set_item("inputs", &self.inputs)?;
        kwargs.set_item("outputs", &self.outputs)?;
        control.call_method("ss", (&self.a, &self.b, &self.c, &self.d), Some(&kwargs))
    }

    fn __repr__(&self) -> String {
        format!(
            "<pendkit.StateSpace: {} states, {} inputs, {} outputs, damping viscous at {} Hz>",
            self.states.len(),
            self.inputs.len(),
            self.outputs.len(),
            self.damping_frequency
        )
    }
}

/// The bundled models as (name, one-line summary) pairs.
#[pyfunction]
fn models() -> Vec<(String, String)> {
    pendkit::catalogue::models()
        .into_iter()
        .map(|m| (m.name().to_string(), m.summary().to_string()))
        .collect()
}

/// `n` log-spaced frequencies from `start` to `stop` (Hz), both included, as the command
/// line's `--from/--to/--points` grid (numpy array).
#[pyfunction]
fn log_grid(py: Python<'_>, start: f64, stop: f64, n: usize) -> PyResult<Bound<'_, PyArray1<f64>>> {
    Ok(pendkit::log_grid(start, stop, n)
        .map_err(error)?
        .into_pyarray(py))
}

#[pymodule]
fn _pendkit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PendkitError", m.py().get_type::<PendkitError>())?;
    m.add("__version__", pendkit::VERSION)?;
    m.add_class::<Model>()?;
    m.add_class::<Parameter>()?;
    m.add_class::<StageRun>()?;
    m.add_class::<Modes>()?;
    m.add_class::<Noise>()?;
    m.add_class::<Stability>()?;
    m.add_class::<StateSpace>()?;
    m.add_class::<Sensitivities>()?;
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(log_grid, m)?)?;
    Ok(())
}
