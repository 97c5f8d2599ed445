//! pendkit for Python: the compiled core of the `pendkit` package, binding the library
//! facade (models, case files, stages, modes, transfer functions, thermal noise, state
//! space) to Python objects and numpy arrays, with the GIL released while Rust computes.
//!
//! The physics is all in the `pendkit` crate: each method here parses its arguments as the
//! command line does (`crates/interface/cli/src/common.rs`), calls the same library function, and
//! converts the answer to numpy, or to the result classes of `pendkit/_results.py` (plain
//! Python dataclasses, so that they pickle and compare by value). Errors are
//! `pendkit.PendkitError` (a `ValueError`, defined in the module `pendkit` so that it
//! pickles) with the library's one-line message, the line the command line prints after
//! `error: `; an argument of the wrong type is a `TypeError` naming it.

use std::fmt::Display;
use std::path::Path;
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pendkit::Override;
use pendkit::params::Resolved;
use pendkit::stage::NamedStateSpace;
use pendkit::stage::RunOptions;
use pendkit::stage::{Fibres, run_stage_with};
use pendkit::{Case, Error, NoiseOptions, Stage, StageResult};
use pyo3::create_exception;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString, PyTuple};

create_exception!(
    pendkit,
    PendkitError,
    PyValueError,
    "A pendkit error: bad input (model, parameter, name, frequency) or a failed calculation; \
     the message is the one line the command line prints."
);

/// Any printable error as a `PendkitError`.
fn error(e: impl Display) -> PyErr {
    PendkitError::new_err(e.to_string())
}

/// A `TypeError` with `message` (which names the argument).
fn type_error(message: String) -> PyErr {
    PyTypeError::new_err(message)
}

/// The name of `v`'s type, for messages (`list`, `numpy.ndarray`).
fn type_name(v: &Bound<'_, PyAny>) -> String {
    let t = v.get_type();
    let name = t
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    match t.module().map(|m| m.to_string()) {
        Ok(module) if module != "builtins" => format!("{module}.{name}"),
        _ => name,
    }
}

/// A `pendkit._results` object of class `$class` with the fields `"name": value`.
macro_rules! result {
    ($py:expr, $class:literal, { $($field:literal : $value:expr),* $(,)? }) => {{
        let kw = PyDict::new($py);
        $( kw.set_item($field, $value)?; )*
        make($py, $class, &kw)
    }};
}

/// A real number as its `f64` (exactly the value, no decimal text in between): a Python
/// `int` or `float`, any `numbers.Real` (numpy's integer and floating scalars, `Fraction`)
/// or a numpy 0-d array of an integer or floating type; `None` for anything else (a `bool`
/// too). `place` names the argument in the error of a value no `f64` holds.
fn real_number(v: &Bound<'_, PyAny>, place: &str) -> PyResult<Option<f64>> {
    if v.is_instance_of::<PyBool>() {
        return Ok(None);
    }
    let py = v.py();
    let real = if v.is_instance_of::<PyFloat>() || v.is_instance_of::<PyInt>() {
        true
    } else {
        let numpy = py.import("numpy")?;
        if v.is_instance(&numpy.getattr("bool_")?)? {
            false
        } else if v.is_instance(&py.import("numbers")?.getattr("Real")?)? {
            true
        } else if v.is_instance(&numpy.getattr("ndarray")?)? {
            v.getattr("ndim")?.extract::<usize>()? == 0
                && "fiu".contains(
                    v.getattr("dtype")?
                        .getattr("kind")?
                        .extract::<String>()?
                        .as_str(),
                )
        } else {
            false
        }
    };
    if !real {
        return Ok(None);
    }
    v.extract::<f64>()
        .map(Some)
        .map_err(|e| error(format!("{place}: {e}")))
}

/// Python's spelling of a number that is not finite (`nan`, `inf`, `-inf`), else the
/// shortest text that reads back as the same `f64`.
fn number_text(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        pendkit::expr::number_text(x)
    }
}

/// An override from `NAME` (a parameter or `damping.<tag>.<field>`) and a Python value: an
/// expression string as the command line's `--set NAME=EXPR`, or a real number, taken as
/// its `f64` (`Override::value`). `place` (`set['m3']`) names it in the errors: a `TypeError`
/// for any other type, a `PendkitError` for a number that is not finite.
fn override_from(name: &str, value: &Bound<'_, PyAny>, place: &str) -> PyResult<Override> {
    if value.is_instance_of::<PyString>() {
        let text: String = value.extract()?;
        return Override::parse(&format!("{name}={text}")).map_err(error);
    }
    let Some(x) = real_number(value, place)? else {
        return Err(type_error(format!(
            "{place}: expected a real number or an expression string, got {}",
            type_name(value)
        )));
    };
    if !x.is_finite() {
        return Err(error(format!(
            "{place}: value {} is not finite",
            number_text(x)
        )));
    }
    // the name read as the command line reads it (trimmed, `damping.<tag>.<field>`)
    Ok(
        match Override::parse(&format!("{name}=0")).map_err(error)? {
            Override::Damping { tag, field, .. } => {
                Override::damping(tag, field, pendkit::expr::number_text(x))
            }
            other => Override::value(other.key(), x),
        },
    )
}

/// The overrides of a `set` argument: a dict `{name: value}` (values as `override_from`
/// takes them) or a sequence of `NAME=EXPR` strings.
fn overrides_from(set: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Override>> {
    let Some(set) = set else {
        return Ok(Vec::new());
    };
    if set.is_none() {
        return Ok(Vec::new());
    }
    let expected = "set: expected a dict {name: value} or a list of 'NAME=EXPR' strings";
    if let Ok(dict) = set.cast::<PyDict>() {
        return dict
            .iter()
            .map(|(k, v)| {
                let name: String = k.extract().map_err(|_| {
                    type_error(format!(
                        "set: the keys are parameter names (str), got {}",
                        type_name(&k)
                    ))
                })?;
                override_from(&name, &v, &format!("set['{name}']"))
            })
            .collect();
    }
    if set.is_instance_of::<PyString>() {
        return Err(type_error(format!("{expected}, got one str")));
    }
    let items = set
        .try_iter()
        .map_err(|_| type_error(format!("{expected}, got {}", type_name(set))))?;
    items
        .enumerate()
        .map(|(k, item)| {
            let item = item?;
            let text: String = item.extract().map_err(|_| {
                type_error(format!(
                    "set[{k}]: expected a 'NAME=EXPR' string, got {}",
                    type_name(&item)
                ))
            })?;
            Override::parse(&text).map_err(error)
        })
        .collect()
}

/// An override as the command line's `NAME=EXPR` text (a number as the shortest text that
/// reads back as the same `f64`).
fn override_text(o: &Override) -> String {
    match o {
        Override::Value { name, value } => format!("{name}={}", number_text(*value)),
        Override::Expression { name, expression } => format!("{name}={expression}"),
        Override::Damping {
            tag,
            field,
            expression,
        } => format!("damping.{tag}.{field}={expression}"),
    }
}

/// An override as the case gets it: a number as the shortest text that reads back as the
/// same `f64` (the same value; `Parameter.definition` then shows `45`, where the library's
/// `Override::value` would write `4.5e1`).
fn applied(o: &Override) -> Override {
    match o {
        Override::Value { name, value } if value.is_finite() => {
            Override::expression(name.clone(), pendkit::expr::number_text(*value))
        }
        other => other.clone(),
    }
}

/// What an override sets, for comparing models: a number (a value, or an expression that
/// is one number literal) or the expression's text.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Setting {
    /// The bits of the number (-0 as 0).
    Number(u64),
    /// The expression, trimmed.
    Text(String),
}

impl Setting {
    fn of(o: &Override) -> Setting {
        let number = |x: f64| Setting::Number((x + 0.0).to_bits());
        match o {
            Override::Value { value, .. } => number(*value),
            Override::Expression { expression, .. } | Override::Damping { expression, .. } => {
                match pendkit::expr::number_literal(expression) {
                    Ok(x) => number(x),
                    Err(_) => Setting::Text(expression.trim().to_string()),
                }
            }
        }
    }
}

/// Where a model's case comes from, kept so that the model can be rebuilt in another
/// process (pickling).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
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
/// as a dict `{"d4": 0.01, "m3": "scale(1.1)"}` (a real number, numpy's too, is taken as
/// its exact value, a string as an expression) or a list of `"NAME=EXPR"` strings, applied
/// in order after the case file's own (`damping.<tag>.<field>` sets a damping field), as
/// the command line's `--set`.
///
/// Models pickle (by model name or case-file text, and the overrides), so they can be
/// sent to worker processes and Dask clusters, and compare by value: the same model name
/// (or case file path and text) and the same overrides, in any order.
#[pyclass(module = "pendkit._pendkit", frozen)]
struct Model {
    source: Source,
    overrides: Vec<Override>,
    /// The case as its source gives it, before `overrides`.
    base: Case,
    case: Case,
}

/// A stage given as a name, `"0a"` … `"2"`, or an integer (`2`, numpy's too), or stage 2,
/// the complete model, when none is given (as the command line); any other type is a
/// `TypeError` naming `stage`.
fn stage_or_complete(stage: Option<&Bound<'_, PyAny>>) -> PyResult<Stage> {
    match stage {
        None => Ok(Stage::S2),
        Some(s) if s.is_none() => Ok(Stage::S2),
        Some(s) => {
            // a name ("1b"), or an integer (2, numpy's too) for the stages that are one
            let text = if s.is_instance_of::<PyString>() {
                s.extract::<String>()?
            } else if !s.is_instance_of::<PyBool>() && s.hasattr("__index__")? {
                s.call_method0("__index__")?.str()?.extract::<String>()?
            } else {
                return Err(type_error(format!(
                    "stage: expected a stage name (\"0a\", \"0b\", \"1a\", \"1b\", \"2\"), got {}",
                    type_name(s)
                )));
            };
            text.parse::<Stage>().map_err(error)
        }
    }
}

/// The `fibres` argument of `Model.run`: `None` (as the model says: the wire sets its file
/// marks `continuum = true`), `"static"`, `"continuum"` or a sequence of wire names.
fn fibres_choice(fibres: Option<&Bound<'_, PyAny>>) -> PyResult<Fibres> {
    let Some(f) = fibres.filter(|f| !f.is_none()) else {
        return Ok(Fibres::AsModelled);
    };
    if f.is_instance_of::<PyString>() {
        return match f.extract::<String>()?.as_str() {
            "static" => Ok(Fibres::Static),
            "continuum" => Ok(Fibres::Continuum),
            other => Err(PyValueError::new_err(format!(
                "fibres: expected \"static\", \"continuum\" or a list of wire names, got {other:?}"
            ))),
        };
    }
    let names: Vec<String> = f.extract().map_err(|_| {
        type_error(format!(
            "fibres: expected \"static\", \"continuum\" or a list of wire names, got {}",
            type_name(f)
        ))
    })?;
    Ok(Fibres::ContinuumNamed(names))
}

/// The `fibres` argument that gives `choice` back (pickle).
fn fibres_argument<'py>(py: Python<'py>, choice: &Fibres) -> PyResult<Bound<'py, PyAny>> {
    Ok(match choice {
        Fibres::AsModelled => py.None().into_bound(py),
        Fibres::Static => PyString::new(py, "static").into_any(),
        Fibres::Continuum => PyString::new(py, "continuum").into_any(),
        Fibres::ContinuumNamed(names) => pyo3::types::PyList::new(py, names)?.into_any(),
    })
}

/// A path given as a str or an os.PathLike; `place` names the argument in the error.
fn fspath(path: &Bound<'_, PyAny>, place: &str) -> PyResult<String> {
    path.py()
        .import("os")?
        .call_method1("fspath", (path,))
        .and_then(|p| p.extract::<String>())
        .map_err(|_| {
            type_error(format!(
                "{place}: expected a path (str or os.PathLike), got {}",
                type_name(path)
            ))
        })
}

/// Measured modes from a CSV file's path, or from a list of `(label, hz, sigma_hz[,
/// shape])` tuples (checked as a file's lines are; the errors name item k, from 0, `modes:k+1`).
fn measured_modes(modes: &Bound<'_, PyAny>) -> PyResult<pendkit::fit::MeasuredModes> {
    if modes.is_instance_of::<PyString>() || modes.hasattr("__fspath__")? {
        return pendkit::fit::MeasuredModes::read(Path::new(&fspath(modes, "modes")?))
            .map_err(error);
    }
    let mut rows: Vec<Vec<String>> = Vec::new();
    for item in modes.try_iter().map_err(|_| {
        type_error(format!(
            "modes: expected a file path or a list of (label, hz, sigma_hz[, shape]) tuples, got {}",
            type_name(modes)
        ))
    })? {
        let item = item?;
        let k = rows.len();
        // a str is iterable too: its characters would pass for fields
        if item.is_instance_of::<PyString>() {
            return Err(type_error(format!(
                "modes[{k}]: expected a tuple (label, hz, sigma_hz[, shape]), got a str"
            )));
        }
        let fields: Vec<String> = item
            .try_iter()
            .map_err(|_| {
                type_error(format!(
                    "modes[{k}]: expected a tuple (label, hz, sigma_hz[, shape]), got {}",
                    type_name(&item)
                ))
            })?
            .enumerate()
            .map(|(j, f)| {
                let f = f?;
                // hz and sigma_hz: a number as its exact f64's shortest text, a string as
                // a file's field
                if (j == 1 || j == 2) && !f.is_instance_of::<PyString>() {
                    let place = format!("modes[{k}][{j}]");
                    return match real_number(&f, &place)? {
                        Some(x) => Ok(number_text(x)),
                        None => Err(type_error(format!(
                            "{place}: expected a real number (Hz), got {}",
                            type_name(&f)
                        ))),
                    };
                }
                f.str()?.extract::<String>()
            })
            .collect::<PyResult<_>>()?;
        rows.push(fields);
    }
    // the items are rows, not a file's lines: a '#' or ',' in a label is the label's
    pendkit::fit::MeasuredModes::from_rows(Path::new("modes"), &rows).map_err(error)
}

impl Model {
    fn open(source: Source, overrides: Vec<Override>) -> Result<Model, Error> {
        let base = match &source {
            Source::Bundled(name) => Case::model(name)?,
            Source::CaseFile { path, text } => Case::from_text(Path::new(path), text)?,
        };
        let case = base.clone().with(overrides.iter().map(applied))?;
        Ok(Model {
            source,
            overrides,
            base,
            case,
        })
    }

    /// What makes two models equal: the source and the overrides by what they set, in
    /// any order (each is given at most once).
    fn identity(&self) -> (&Source, Vec<(String, Setting)>) {
        let mut settings: Vec<(String, Setting)> = self
            .overrides
            .iter()
            .map(|o| (o.key(), Setting::of(o)))
            .collect();
        settings.sort();
        (&self.source, settings)
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
                .map_err(|_| {
                    type_error(format!(
                        "spec: expected a model name or a case-file path (str or os.PathLike), got {}",
                        type_name(spec)
                    ))
                })?,
        };
        let overrides = overrides_from(set)?;
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
        Model::open(source, overrides).map_err(error)
    }

    /// The arguments that rebuild this model in another process (pickle): the overrides
    /// as a dict, numbers as floats (exact), expressions as strings.
    fn __getnewargs_ex__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let kwargs = PyDict::new(py);
        let set = PyDict::new(py);
        for o in &self.overrides {
            match o {
                Override::Value { name, value } => set.set_item(name, value)?,
                Override::Expression { name, expression } => set.set_item(name, expression)?,
                Override::Damping { expression, .. } => set.set_item(o.key(), expression)?,
            }
        }
        kwargs.set_item("set", set)?;
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
        if self.overrides.is_empty() {
            format!("pendkit.Model({spec:?})")
        } else {
            format!("pendkit.Model({spec:?}, set={:?})", self.sets())
        }
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.identity() == other.identity()
    }

    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        self.identity().hash(&mut hasher);
        hasher.finish()
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
        self.overrides.iter().map(override_text).collect()
    }

    /// This model with more overrides (applied after this model's own): a dict or a list
    /// of `NAME=EXPR` strings.
    fn with_set(&self, set: &Bound<'_, PyAny>) -> PyResult<Model> {
        let mut overrides = self.overrides.clone();
        overrides.extend(overrides_from(Some(set))?);
        Model::open(self.source.clone(), overrides).map_err(error)
    }

    /// Every numeric parameter as resolved (with the overrides): a list of `Parameter`
    /// (name, value, unit, definition, overridden).
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        let case = &self.case;
        py.detach(|| {
            let (_, resolved) = case.build()?;
            parameters(case, &resolved)
        })
        .map_err(error)?
        .into_iter()
        .map(|p| p.into_python(py))
        .collect()
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
    /// `jacobian=` asks), `starts` (how many starts were tried: `starts=` of them, and up to
    /// `more_starts=` more when none explains the data, as `--starts` and `--more-starts`
    /// do), `would_help` (when the fit does not explain its data: the parameters whose
    /// freeing would lower χ² most), and
    /// `case_file` (the text of the fitted case file when the model is a bundled one, else
    /// None).
    #[pyo3(signature = (modes, free, *, tf = None, stage = None, jacobian = "exact", starts = 1, more_starts = 4))]
    #[expect(
        clippy::too_many_arguments,
        reason = "Python's keyword arguments, each one option of `pendkit fit`"
    )]
    fn fit<'py>(
        &self,
        py: Python<'py>,
        modes: &Bound<'py, PyAny>,
        free: Vec<String>,
        tf: Option<&Bound<'py, PyAny>>,
        stage: Option<&Bound<'py, PyAny>>,
        jacobian: &str,
        starts: usize,
        more_starts: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let stage = stage_or_complete(stage)?;
        let jacobian: pendkit::fit::JacobianMethod = jacobian
            .parse()
            .map_err(|e: String| error(format!("jacobian: {e}")))?;
        let measured = measured_modes(modes)?;
        let tf = match tf {
            None => None,
            Some(path) => Some(
                pendkit::fit::MeasuredTf::read(Path::new(&fspath(path, "tf")?)).map_err(error)?,
            ),
        };
        let case = self.case.clone();
        let options = pendkit::fit::FitOptions {
            stage,
            jacobian,
            starts,
            more_starts,
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
    /// normal mode. Returns a `Result`. `fibres` chooses how wires move in its `tf` and
    /// `noise`, as the command line's `--fibres`: `"static"`, `"continuum"` (the lowest
    /// wires and any the file marks, by their exact dynamic stiffness with the violin
    /// modes: docs/continuum-fibres.md), a list of wire names to take as continua, or
    /// `None` (the default: as the model's file says). The modes and the state space keep
    /// the static model.
    #[pyo3(signature = (stage = None, fibres = None))]
    fn run(
        slf: &Bound<'_, Self>,
        stage: Option<&Bound<'_, PyAny>>,
        fibres: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<StageRun> {
        let py = slf.py();
        let stage = stage_or_complete(stage)?;
        let fibres = fibres_choice(fibres)?;
        let case = slf.get().case.clone();
        let run = py
            .detach(move || -> std::result::Result<Run, Error> {
                let (system, resolved) = case.build()?;
                let mut result = run_stage_with(system, stage, &RunOptions::default(), None)?;
                if fibres != Fibres::AsModelled {
                    result = result.with_fibres(&fibres)?;
                }
                Ok(Run {
                    case,
                    stage,
                    resolved,
                    result,
                    fibres,
                })
            })
            .map_err(error)?;
        Ok(StageRun {
            run: Arc::new(run),
            model: slf.clone().unbind(),
        })
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
    fn sensitivities<'py>(
        &self,
        py: Python<'py>,
        stage: Option<&Bound<'py, PyAny>>,
        modes: bool,
        tf: Option<(String, String)>,
        noise: Option<String>,
        freqs: Option<&Bound<'py, PyAny>>,
        parameters: Option<Vec<String>>,
        allow_unstable: bool,
        differences: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
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
        result!(py, "Sensitivities", {
            "parameters": s.parameters,
            "values": PyArray1::from_slice(py, &s.values),
            "units": s.units,
            "modes_hz": PyArray1::from_slice(py, &s.modes_hz),
            "mode_labels": s.mode_labels,
            "dfdp": rows(&s.dfdp, np)?,
            "freqs": PyArray1::from_slice(py, &request.freqs),
            "tf_abs": tf_abs,
            "dtf_abs_dp": dtf_abs_dp,
            "noise_asd": noise_asd,
            "dnoise_asd_dp": dnoise_asd_dp,
            "not_differentiable": s.not_differentiable,
            "exact": s.exact,
            "warning": s.warning,
        })
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

/// One parameter as resolved (`pendkit.Parameter`).
struct Parameter {
    name: String,
    value: f64,
    unit: String,
    definition: String,
    overridden: bool,
}

impl Parameter {
    fn into_python(self, py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
        let kw = PyDict::new(py);
        kw.set_item("name", self.name)?;
        kw.set_item("value", self.value)?;
        kw.set_item("unit", self.unit)?;
        kw.set_item("definition", self.definition)?;
        kw.set_item("overridden", self.overridden)?;
        make(py, "Parameter", &kw)
    }
}

/// An object of the result class `class` of `pendkit._results` made with `kwargs`.
fn make<'py>(
    py: Python<'py>,
    class: &str,
    kwargs: &Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyAny>> {
    py.import("pendkit._results")?
        .getattr(class)?
        .call((), Some(kwargs))
}

/// One run of a stage.
struct Run {
    case: Case,
    stage: Stage,
    resolved: Resolved,
    result: StageResult,
    /// How the wires move in responses and noise, as asked.
    fibres: Fibres,
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
///
/// A result pickles as its model, stage and fibres, and is computed again when unpickled
/// (pendkit is deterministic: the same numbers); two results are equal when their models,
/// stages and fibres are.
#[pyclass(module = "pendkit._pendkit", name = "Result", frozen)]
struct StageRun {
    run: Arc<Run>,
    /// The model that was run.
    model: Py<Model>,
}

#[pymethods]
impl StageRun {
    /// `Model.run` of the model, with the stage and the fibres: what rebuilds this result
    /// (pickle).
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (&'static str, Bound<'py, PyAny>))> {
        Ok((
            self.model.bind(py).getattr("run")?,
            (
                self.run.stage.name(),
                fibres_argument(py, &self.run.fibres)?,
            ),
        ))
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.run.stage == other.run.stage
            && self.run.fibres == other.run.fibres
            && self.model.get().identity() == other.model.get().identity()
    }

    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        (
            self.run.stage.name(),
            format!("{:?}", self.run.fibres),
            self.model.get().identity(),
        )
            .hash(&mut hasher);
        hasher.finish()
    }

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
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        parameters(&self.run.case, &self.run.resolved)
            .map_err(error)?
            .into_iter()
            .map(|p| p.into_python(py))
            .collect()
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
    fn modes<'py>(&self, py: Python<'py>, naming: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
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
        let labels: Vec<String> = list
            .iter()
            .map(|m| self.run.coord(scheme, &m.label))
            .collect();
        let families: Vec<String> = list.iter().map(|m| r.mode_family(m)).collect();
        let coordinates: Vec<String> = r
            .modes
            .coordinates
            .iter()
            .map(|c| self.run.coord(scheme, c))
            .collect();
        let coordinate_units: Vec<String> = r
            .modes
            .coordinates
            .iter()
            .map(|c| r.coordinate_unit(c).unwrap_or_default().to_string())
            .collect();
        result!(py, "Modes", {
            "frequencies": PyArray1::from_iter(py, list.iter().map(|m| m.hz)),
            "omega_squared": PyArray1::from_iter(py, list.iter().map(|m| m.omega_squared)),
            "stable": PyArray1::from_iter(py, list.iter().map(|m| m.is_stable())),
            "labels": labels,
            "families": families,
            "coordinates": coordinates,
            "coordinate_units": coordinate_units,
            "shapes": rows(&|m| &m.vector),
            "energy_fractions": rows(&|m| &m.energy_fractions),
        })
    }

    /// The stability verdict: a `Stability` (stable, the message naming the first growing
    /// mode, the indices of the unstable modes). An unstable mode has ω² < 0.
    fn stability<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.run.result;
        let unstable: Vec<usize> = r
            .modes
            .modes
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.is_stable())
            .map(|(i, _)| i)
            .collect();
        result!(py, "Stability", {
            "stable": r.stability().is_ok(),
            "message": r.stability().err().map(|e| e.to_string()),
            "unstable_modes": unstable,
        })
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
    fn noise<'py>(
        &self,
        py: Python<'py>,
        output: &str,
        freqs: &Bound<'py, PyAny>,
        full: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
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
        result!(py, "Noise", {
            "freqs": freqs.into_pyarray(py),
            "psd": PyArray1::from_slice(py, noise.psd()),
            "asd": noise.asd().into_pyarray(py),
            "psd_by_tag": psd_by_tag,
            "asd_by_tag": asd_by_tag,
            "unit": format!("{}/√Hz", run.result.output_unit(output).unwrap_or_default()),
            "temperature": run.result.system.temperature,
        })
    }

    /// State-space matrices with damping represented as viscous at `damping_frequency`
    /// (Hz): exact for viscous damping, and for any damping at `damping_frequency` itself
    /// from forces; without the damping force of the support's velocity. `inputs` and
    /// `outputs` select (and order) columns and rows by name (default: all); names are those
    /// of the state space in `naming` (inputs: support parameters then `force:<variable>`;
    /// outputs: variables then `force:<parameter>`, and any state, e.g. the velocity
    /// `x0_dot`). Returns a `StateSpace`.
    #[pyo3(signature = (inputs = None, outputs = None, *, damping_frequency = 1.0, naming = None))]
    fn state_space<'py>(
        &self,
        py: Python<'py>,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
        damping_frequency: f64,
        naming: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.run.check_lossy()?;
        let scheme = self.run.scheme(naming)?;
        let run = &self.run;
        let named = py
            .detach(|| run.result.named_state_space(damping_frequency, scheme))
            .map_err(error)?;
        state_space(py, &named, inputs, outputs)
    }

    /// `state_space(...)` as a python-control `StateSpace` (`StateSpace.to_control`): its
    /// inputs, outputs and states named as valid identifiers (`force:x0` → `force_x0`),
    /// the system named `name`. Needs python-control.
    #[pyo3(signature = (inputs = None, outputs = None, *, damping_frequency = 1.0, naming = None, name = None))]
    fn to_control<'py>(
        &self,
        py: Python<'py>,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
        damping_frequency: f64,
        naming: Option<&str>,
        name: Option<String>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.state_space(py, inputs, outputs, damping_frequency, naming)?
            .call_method1("to_control", (name,))
    }
}

fn solver(full: bool) -> pendkit::Solver {
    if full {
        pendkit::Solver::Full
    } else {
        pendkit::Solver::Restricted
    }
}

/// A row of the state space's output matrices: an output, or a state read directly.
#[derive(Clone, Copy)]
enum Row {
    Output(usize),
    State(usize),
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

/// The rows of `wanted`: outputs, or states (all the outputs when `None`).
fn pick_rows(
    outputs: &[String],
    states: &[String],
    wanted: Option<Vec<String>>,
) -> PyResult<Vec<Row>> {
    match wanted {
        None => Ok((0..outputs.len()).map(Row::Output).collect()),
        Some(list) => list
            .iter()
            .map(|w| {
                if let Some(k) = outputs.iter().position(|n| n == w) {
                    Ok(Row::Output(k))
                } else if let Some(k) = states.iter().position(|n| n == w) {
                    Ok(Row::State(k))
                } else {
                    Err(error(format!(
                        "'{w}': not an output of the state space (valid: {}, or a state: {})",
                        outputs.join(" "),
                        states.join(" ")
                    )))
                }
            })
            .collect(),
    }
}

/// A `pendkit.StateSpace` of `named`'s `inputs` and `outputs` (outputs or states), in the
/// order given (all of them when `None`).
fn state_space<'py>(
    py: Python<'py>,
    named: &NamedStateSpace,
    inputs: Option<Vec<String>>,
    outputs: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyAny>> {
    let ss = &named.state_space;
    let cols = pick("an input", &ss.inputs, inputs)?;
    let rows = pick_rows(&ss.outputs, &ss.states, outputs)?;
    let n = ss.a.nrows();
    let matrix = |r: usize, c: usize, f: &dyn Fn(usize, usize) -> f64| {
        Array2::from_shape_fn((r, c), |(i, j)| f(i, j)).into_pyarray(py)
    };
    let c_row = |row: Row, j: usize| match row {
        Row::Output(k) => ss.c[(k, j)],
        Row::State(k) => f64::from(u8::from(k == j)),
    };
    let d_row = |row: Row, j: usize| match row {
        Row::Output(k) => ss.d[(k, cols[j])],
        Row::State(_) => 0.0,
    };
    let take = |names: &[String], idx: &[usize]| -> Vec<String> {
        idx.iter().map(|&k| names[k].clone()).collect()
    };
    let row_names = |output_names: &[String], state_names: &[String]| -> Vec<String> {
        rows.iter()
            .map(|row| match *row {
                Row::Output(k) => output_names[k].clone(),
                Row::State(k) => state_names[k].clone(),
            })
            .collect()
    };
    result!(py, "StateSpace", {
        "A": matrix(n, n, &|i, j| ss.a[(i, j)]),
        "B": matrix(n, cols.len(), &|i, j| ss.b[(i, cols[j])]),
        "C": matrix(rows.len(), n, &|i, j| c_row(rows[i], j)),
        "D": matrix(rows.len(), cols.len(), &|i, j| d_row(rows[i], j)),
        "states": ss.states.clone(),
        "inputs": take(&ss.inputs, &cols),
        "outputs": row_names(&ss.outputs, &ss.states),
        "state_units": named.state_units.clone(),
        "input_units": take(&named.input_units, &cols),
        "output_units": row_names(&named.output_units, &named.state_units),
        "damping_frequency": ss.damping_frequency,
    })
}

/// What a sweep computes at each point (`pendkit.sweep`'s `what`).
enum SweepWhat {
    /// Every mode's frequency (Hz).
    Modes,
    /// The transfer function from `input` to `output` at `freqs` (complex).
    Tf {
        input: String,
        output: String,
        freqs: Vec<f64>,
    },
    /// The thermal-noise ASD of `output` at `freqs`.
    Noise { output: String, freqs: Vec<f64> },
}

/// One sweep point's row.
enum SweepRow {
    Real(Vec<f64>),
    Complex(Vec<Complex64>),
}

/// One sweep point: `model` with `names` set to `values`, run to `stage`, and `what` of it,
/// by the same calls as `Model.with_set`, `Model.run` and `Result.modes`, `.tf` or
/// `.noise(...).asd` (the same numbers).
fn sweep_point(
    model: &Model,
    names: &[String],
    values: &[f64],
    stage: Stage,
    what: &SweepWhat,
) -> Result<SweepRow, Error> {
    let point = names
        .iter()
        .zip(values)
        .map(|(name, &value)| Override::value(name.clone(), value));
    let overrides: Vec<Override> = model.overrides.iter().cloned().chain(point).collect();
    // as `Model::open` applies them (`Model.with_set`)
    let case = model.base.clone().with(overrides.iter().map(applied))?;
    let (system, _) = case.build()?;
    let result = run_stage_with(system, stage, &RunOptions::default(), None)?;
    if !matches!(what, SweepWhat::Modes) && stage == Stage::S0A {
        return Err(Error::StageTooEarly);
    }
    Ok(match what {
        SweepWhat::Modes => SweepRow::Real(result.modes.modes.iter().map(|m| m.hz).collect()),
        SweepWhat::Tf {
            input,
            output,
            freqs,
        } => SweepRow::Complex(
            result
                .transfer_with(input, output, freqs, solver(false))?
                .iter()
                .map(|z| Complex64::new(z.re, z.im))
                .collect(),
        ),
        SweepWhat::Noise { output, freqs } => {
            let options = NoiseOptions {
                solver: solver(false),
                per_term: false,
            };
            SweepRow::Real(result.noise_with(output, freqs, &options)?.asd())
        }
    })
}

/// A numpy array of `rows`, `n_columns` wide, with `nan` in the rows that are `None`.
fn sweep_table<'py, T: numpy::Element + Copy>(
    py: Python<'py>,
    rows: &[Option<&Vec<T>>],
    n_columns: usize,
    nan: T,
) -> Bound<'py, PyAny> {
    Array2::from_shape_fn((rows.len(), n_columns), |(i, j)| match rows[i] {
        Some(row) => row[j],
        None => nan,
    })
    .into_pyarray(py)
    .into_any()
}

/// A sweep chunk's rows and failures (row, message).
type SweepChunk<'py> = (Bound<'py, PyAny>, Vec<(usize, String)>);

/// The points of one chunk of a sweep (`pendkit.sweep`, which documents it), with the GIL
/// released: `values` (points × names) sets `names` on `model`, each point runs `stage`
/// and computes `what` (`"modes"`, `"tf"` with `input`, `output` and `freqs`, or
/// `"noise"` with `output` and `freqs`). Returns (the rows as an array, NaN where a point
/// failed, and the failures as (row, message)).
#[pyfunction]
#[pyo3(signature = (model, names, values, what, *, input = None, output = None, freqs = None, stage = None))]
#[allow(clippy::too_many_arguments)]
fn _sweep_chunk<'py>(
    py: Python<'py>,
    model: &Bound<'py, Model>,
    names: Vec<String>,
    values: numpy::PyReadonlyArray2<'py, f64>,
    what: &str,
    input: Option<String>,
    output: Option<String>,
    freqs: Option<&Bound<'py, PyAny>>,
    stage: Option<&Bound<'py, PyAny>>,
) -> PyResult<SweepChunk<'py>> {
    let stage = stage_or_complete(stage)?;
    let needs = |x: Option<String>, name: &str| {
        x.ok_or_else(|| error(format!("what: '{what}' needs {name}")))
    };
    let grid = |f: Option<&Bound<'py, PyAny>>| match f {
        Some(f) => frequencies(f),
        None => Err(error(format!("what: '{what}' needs freqs"))),
    };
    let what = match what {
        "modes" => SweepWhat::Modes,
        "tf" => SweepWhat::Tf {
            input: needs(input, "an input")?,
            output: needs(output, "an output")?,
            freqs: grid(freqs)?,
        },
        "noise" => SweepWhat::Noise {
            output: needs(output, "an output")?,
            freqs: grid(freqs)?,
        },
        other => {
            return Err(error(format!("what: '{other}' is not modes, tf or noise")));
        }
    };
    let values = values.as_array();
    if values.ncols() != names.len() {
        return Err(error(format!(
            "values: {} columns for {} names",
            values.ncols(),
            names.len()
        )));
    }
    let model = model.get();
    let rows: Vec<Result<SweepRow, String>> = py.detach(|| {
        values
            .rows()
            .into_iter()
            .map(|point| {
                let point: Vec<f64> = point.iter().copied().collect();
                sweep_point(model, &names, &point, stage, &what).map_err(|e| e.to_string())
            })
            .collect()
    });
    let mut errors: Vec<(usize, String)> = Vec::new();
    let width = match &what {
        SweepWhat::Modes => rows
            .iter()
            .find_map(|r| match r {
                Ok(SweepRow::Real(v)) => Some(v.len()),
                _ => None,
            })
            .unwrap_or(0),
        SweepWhat::Tf { freqs, .. } | SweepWhat::Noise { freqs, .. } => freqs.len(),
    };
    let mut real: Vec<Option<&Vec<f64>>> = Vec::new();
    let mut complex: Vec<Option<&Vec<Complex64>>> = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        match row {
            Err(message) => {
                errors.push((i, message.clone()));
                real.push(None);
                complex.push(None);
            }
            Ok(SweepRow::Real(v)) if v.len() != width => {
                errors.push((
                    i,
                    format!(
                        "{} modes, where the sweep's first point has {width}",
                        v.len()
                    ),
                ));
                real.push(None);
            }
            Ok(SweepRow::Real(v)) => real.push(Some(v)),
            Ok(SweepRow::Complex(v)) => complex.push(Some(v)),
        }
    }
    let table = match what {
        SweepWhat::Tf { .. } => {
            sweep_table(py, &complex, width, Complex64::new(f64::NAN, f64::NAN))
        }
        _ => sweep_table(py, &real, width, f64::NAN),
    };
    Ok((table, errors))
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
    m.add_class::<StageRun>()?;
    // the result types are Python classes (pendkit/_results.py), here under their names too
    let results = m.py().import("pendkit._results")?;
    for class in [
        "Modes",
        "Noise",
        "Parameter",
        "Sensitivities",
        "Stability",
        "StateSpace",
    ] {
        m.add(class, results.getattr(class)?)?;
    }
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(log_grid, m)?)?;
    m.add_function(wrap_pyfunction!(_sweep_chunk, m)?)?;
    Ok(())
}
