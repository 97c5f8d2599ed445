//! pendkit's library facade: the catalogue of bundled models, case files, and the whole
//! pipeline from a model or case to equilibrium, normal modes, transfer functions, thermal
//! noise and state space, and their sensitivities to the parameters, for downstream tools that
//! want one call.
//!
//! The example in the README (`crates/pendkit/tests/readme.rs` checks that the two agree):
//!
//! ```
//! use pendkit::{Case, NoiseOptions, Solver, Stage, log_grid, run_stage};
//!
//! // the aLIGO quad with a heavier test mass, at stage 2 (the complete model)
//! let case = Case::model("quad")?.with_sets(&["m3=50".into()])?;
//! let (system, _parameters) = case.build()?;
//! let r = run_stage(system, Stage::S2)?;
//! assert_eq!(r.modes.modes.len(), 24); // four bodies, six degrees of freedom each
//! for mode in &r.modes.modes {
//!     println!("{:9.4} Hz  {:8}  {}", mode.hz, mode.label, r.mode_family(mode));
//! }
//! let freqs = log_grid(0.1, 100.0, 1000)?;
//! let h = r.transfer("x00", "x3", &freqs)?; // complex, m/m: support to test mass
//! assert!((h[0].re - 1.0).abs() < 0.1); // the test mass follows the support at 0.1 Hz
//! let noise = r.noise("x3", &freqs)?; // thermal noise of the test mass along x
//! println!("{:.3e} m/√Hz at {} Hz", noise.asd()[666], freqs[666]); // psd() in m²/Hz
//! for (tag, asd) in noise.asd_by_tag() {
//!     println!("{tag:>16}: {:.3e} m/√Hz", asd[666]);
//! }
//! // every unknown solved, and the share of every lossy term too
//! let h_full = r.transfer_with("x00", "x3", &freqs, Solver::Full)?;
//! assert!((h_full[500] - h[500]).norm() <= 1e-9 * h[500].norm());
//! let options = NoiseOptions { solver: Solver::Full, per_term: true };
//! let detailed = r.noise_with("x3", &freqs, &options)?; // .by_term: (term, tag, PSD)
//! assert!(!detailed.by_term.is_empty());
//! // the modes below 1 Hz, by shift-invert on the sparse factorisation
//! let low = r.model.modes_below(&r.system.damping, 1.0)?;
//! assert!(low.modes.iter().all(|m| m.hz < 1.0));
//! # Ok::<(), pendkit::Error>(())
//! ```
//!
//! # Features
//!
//! | feature | adds | pulls in |
//! |---|---|---|
//! | `files` | [`Case::from_file`], [`Case::open`] taking a path, [`load_suspension`]: case files and suspension files read at run time | `pendkit-files`, `pendkit-suspension/toml` (a TOML parser) |
//! | `export` | [`StageResult::write_state_space`]: the state space to `.mat`, `.npz` or JSON, with units and provenance | `pendkit-export` (zip) |
//!
//! Neither is on by default; the `pendkit` command-line program enables both. The bundled
//! models need no feature: each is a suspension file embedded already read (its tree packed
//! at build time, [`bundled_files`]), so the library carries no TOML parser by default.
//!
//! # What it links
//!
//! This crate names every bundled element crate (wire torsion, bending, extra stretch) so
//! that the linker keeps their `inventory` registrations (inventory issue #50): a program
//! that depends on `pendkit` alone sees all of them in [`energy::registry`]. It also
//! re-exports the crates whose types its functions take and return ([`nalgebra`], [`faer`],
//! [`geometry`], [`energy`], [`assembly`], [`dynamics`], [`noise`], [`model`], [`params`],
//! [`expr`], and with the features [`files`] and [`export`]), so downstream code needs no
//! version-matched dependencies of its own.

mod describe;
pub mod fit;
mod parameters;
pub mod sensitivity;
mod state_space;
#[cfg(feature = "files")]
mod suspension_files;
pub mod tradeoff;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{DVector, Vector3};
use pendkit_assembly::{Assembled, AssemblyError, assemble_with, timed};
use pendkit_dynamics::{
    DynamicsError, TermRounding, eliminate_floats, float_directions, inverted_bodies,
    normal_modes_with_rounding,
};
use pendkit_energy::{NamedSignal, SignalTerm};
use pendkit_model::BuildError;
use pendkit_noise::thermal_noise_with;

// Name every bundled element crate so the linker keeps its registration.
use pendkit_element_bending as _;
use pendkit_element_extra_stretch as _;
use pendkit_element_torsion as _;

pub use faer;
pub use nalgebra;
pub use pendkit_assembly as assembly;
pub use pendkit_dynamics as dynamics;
pub use pendkit_energy as energy;
#[cfg(feature = "export")]
pub use pendkit_export as export;
pub use pendkit_expr as expr;
#[cfg(feature = "files")]
pub use pendkit_files as files;
pub use pendkit_geometry as geometry;
pub use pendkit_model as model;
pub use pendkit_models as bundled_files;
pub use pendkit_noise as noise;
pub use pendkit_params as params;
pub use pendkit_suspension as suspension;

pub use pendkit_assembly::{AssemblyOptions, PhaseTimes};
pub use pendkit_dynamics::{
    Input, Modes, Output, Solver, Stability, StageModel, StateSpace, Verdict,
};
pub use pendkit_energy::{Stage, System};
pub use pendkit_model::{Model, Overrides};

pub use pendkit_noise::{NoiseOptions, ThermalNoise};
pub use pendkit_params::Resolved;

pub use describe::{DOF_FAMILIES, OTHER_FAMILY, unit_ratio, unit_slug};
pub use fit::{
    FitError, FitOptions, FitResult, JacobianMethod, MeasuredModes, MeasuredTf, exact_jacobian,
    exact_mode_jacobian, fit, mode_jacobian, pair_modes_by_overlap,
};
pub use parameters::{ParameterRow, parameter_table};
pub use sensitivity::{Sensitivities, SensitivityRequest, sensitivities};
pub use state_space::NamedStateSpace;
#[cfg(feature = "files")]
pub use suspension_files::{load_suspension, suspension_from_text};

/// pendkit's version, recorded in exports and reports.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Errors of the whole pipeline, one line each.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A model name nobody bundles.
    #[error("unknown model '{name}' (bundled: {known}; or give a case file path)")]
    UnknownModel {
        /// The name asked for.
        name: String,
        /// Bundled model names.
        known: String,
    },
    /// A case file that cannot be read or parsed.
    #[error("case file {path}: {message}")]
    Case {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A suspension file that cannot be read or describes no valid suspension: its file,
    /// line and field.
    #[error(transparent)]
    SuspensionFile(#[from] pendkit_suspension::FileError),
    /// An override written as text (`NAME=EXPR`, `damping.<tag>.<field>=EXPR`) without '=',
    /// or with nothing on one side of it.
    #[error("override '{0}': expected NAME=EXPR or damping.<tag>.<field>=EXPR")]
    OverrideSyntax(String),
    /// An override the parameter or the damping field refuses: a damping field that does
    /// not exist, a value that is not a finite number.
    #[error("override '{key}': {message}")]
    OverrideRefused {
        /// The parameter's name or `damping.<tag>.<field>`.
        key: String,
        /// What is wrong with it.
        message: String,
    },
    /// Two overrides of the same parameter or damping field in one list: the later would
    /// silently replace the earlier.
    #[error("'{0}' is overridden twice: give each parameter or damping field once")]
    OverriddenTwice(String),
    /// An override of a parameter that nothing the model builds reads.
    #[error(
        "parameter '{name}' is read by nothing in model '{model}': overriding it would change nothing (parameters read: {read})"
    )]
    Unread {
        /// The parameter overridden.
        name: String,
        /// The model.
        model: String,
        /// The parameters the model does read, directly or through other definitions.
        read: String,
    },
    /// Building the model failed.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// Equilibrium or assembly failed.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    /// Two element crates registered the same kind name.
    #[error(transparent)]
    Registry(#[from] pendkit_energy::DuplicateKind),
    /// An input or output name that means nothing in this model.
    #[error("'{name}': {message}")]
    Name {
        /// The name given.
        name: String,
        /// What is wrong, with the valid names.
        message: String,
    },
    /// A frequency grid that cannot be made.
    #[error(
        "frequency grid from {} Hz to {} Hz with {n} points: need 1e-9 <= from <= to <= 1e9 (Hz, finite) and 1 to 1000000 points",
        pendkit_expr::number_text(*from),
        pendkit_expr::number_text(*to)
    )]
    Grid {
        /// Start (Hz).
        from: f64,
        /// End (Hz).
        to: f64,
        /// Points.
        n: usize,
    },
    /// Losses asked for at stage 0A.
    #[error(
        "transfer functions, noise and state space need stage 0b or later (0A has no dissipation dilution)"
    )]
    StageTooEarly,
    /// Writing an export file failed.
    #[cfg(feature = "export")]
    #[error(transparent)]
    Export(pendkit_export::ExportError),
    /// Modes or eliminations failed.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// The reference variant of a trade-off ladder cannot answer the question.
    #[error("reference variant '{variant}' cannot answer: {message}")]
    Reference {
        /// The reference variant's name.
        variant: String,
        /// Why.
        message: String,
    },
    /// A sensitivity request that cannot be answered (what and why).
    #[error("sensitivity: {0}")]
    Sensitivity(String),
    /// A benchmark asked to repeat nothing, or too often.
    #[error("--repeat must be from 1 to {MAX_REPEAT}")]
    ZeroRepeat,
    /// Measurements that cannot be read, or a fit that cannot be made.
    #[error(transparent)]
    Fit(#[from] fit::FitError),
    /// A result that came out NaN or infinite (never returned as a success).
    #[error("{what} is not finite at {f_hz} Hz")]
    NotFinite {
        /// What was computed.
        what: String,
        /// Where (Hz).
        f_hz: f64,
    },
    /// An argument of a library function whose size does not fit the others.
    #[error("{function}: {argument} is {given}, expected {expected}")]
    Argument {
        /// The function called, e.g. `pair_modes_by_overlap`.
        function: &'static str,
        /// The argument, e.g. `new_mass`.
        argument: &'static str,
        /// What it should be, e.g. `6 x 6`.
        expected: String,
        /// What it is.
        given: String,
    },
}

/// Most repetitions `pendkit bench` makes.
pub const MAX_REPEAT: usize = 100_000;

/// Every bundled model: each is a suspension file under `models/`, embedded in the
/// program ([`bundled_files`]).
pub fn models() -> Vec<Arc<dyn Model>> {
    pendkit_models::models()
}

/// The bundled model called `name`.
pub fn find_model(name: &str) -> Result<Arc<dyn Model>, Error> {
    pendkit_models::find(name)
        .map(|m| m as Arc<dyn Model>)
        .ok_or_else(|| Error::UnknownModel {
            name: name.to_string(),
            known: models()
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// One change a case makes to its model ([`Case::with`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Override {
    /// A parameter set to a number, in the parameter's SI unit.
    Value {
        /// The parameter.
        name: String,
        /// Its new value (finite).
        value: f64,
    },
    /// A parameter set to an expression of the model's parameters, or `scale(x)` /
    /// `increment(x)` of its current definition.
    Expression {
        /// The parameter.
        name: String,
        /// The expression.
        expression: String,
    },
    /// A field of a damping tag ([`model::schema::DAMPING_FIELDS`]: `structural`,
    /// `thermoelastic.tau`, `temperature`, ...), as an expression of the parameters (and of
    /// `f`, Hz, in `real` and `imag`).
    Damping {
        /// The damping tag (`fibre_bending`).
        tag: String,
        /// The field's name.
        field: String,
        /// The expression.
        expression: String,
    },
}

impl Override {
    /// Parameter `name` set to `value` (in its SI unit).
    pub fn value(name: impl Into<String>, value: f64) -> Override {
        Override::Value {
            name: name.into(),
            value,
        }
    }

    /// Parameter `name` set to `expression`.
    pub fn expression(name: impl Into<String>, expression: impl Into<String>) -> Override {
        Override::Expression {
            name: name.into(),
            expression: expression.into(),
        }
    }

    /// Damping field `field` of tag `tag` set to `expression`.
    pub fn damping(
        tag: impl Into<String>,
        field: impl Into<String>,
        expression: impl Into<String>,
    ) -> Override {
        Override::Damping {
            tag: tag.into(),
            field: field.into(),
            expression: expression.into(),
        }
    }

    /// Reads `NAME=EXPR` (an [`Override::Expression`]) or `damping.<tag>.<field>=EXPR` (an
    /// [`Override::Damping`]).
    pub fn parse(text: &str) -> Result<Override, Error> {
        let syntax = || Error::OverrideSyntax(text.to_string());
        let (name, expression) = text.split_once('=').ok_or_else(syntax)?;
        let (name, expression) = (name.trim(), expression.trim());
        // `=3`, `m1=` or `damping.tag.field=`: a half that is missing is named as such, not
        // looked up as the parameter '' or parsed as the expression "()"
        if name.is_empty() || expression.is_empty() {
            return Err(syntax());
        }
        Ok(
            match name
                .strip_prefix("damping.")
                .and_then(|rest| rest.split_once('.'))
            {
                Some((tag, field)) => Override::damping(tag, field, expression),
                None => Override::expression(name, expression),
            },
        )
    }

    /// What the override changes: the parameter's name, or `damping.<tag>.<field>`.
    pub fn key(&self) -> String {
        match self {
            Override::Value { name, .. } | Override::Expression { name, .. } => name.clone(),
            Override::Damping { tag, field, .. } => format!("damping.{tag}.{field}"),
        }
    }
}

/// A case: a model with parameter and damping overrides.
#[derive(Clone)]
pub struct Case {
    /// Case name (the model name, or the case file's stem).
    pub name: String,
    /// What the case is for (from the case file).
    pub description: Option<String>,
    /// The model it refines, shared between the cases made from it.
    pub model: Arc<dyn Model>,
    /// Parameter and damping overrides.
    pub overrides: Overrides,
}

impl Case {
    /// A bundled model with its defaults.
    pub fn model(name: &str) -> Result<Case, Error> {
        Ok(Case {
            name: name.to_string(),
            description: None,
            model: find_model(name)?,
            overrides: Overrides::default(),
        })
    }

    /// Reads a case file (TOML; see [`files`]), or a suspension file (a `.toml` without a
    /// top-level `model`; see [`suspension`]) as a case of that model with its defaults. A
    /// case file's `model` may itself be a suspension file's path, relative to the case
    /// file's folder.
    #[cfg(feature = "files")]
    pub fn from_file(path: &Path) -> Result<Case, Error> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Case {
            path: path.to_path_buf(),
            message: source.to_string(),
        })?;
        Case::from_text(path, &text)
    }

    /// A case from the text of a case file that was read from `path` (which names the case
    /// and the errors): for callers that keep the text, e.g. to rebuild the case in another
    /// process.
    #[cfg(feature = "files")]
    pub fn from_text(path: &Path, text: &str) -> Result<Case, Error> {
        let err = |message: String| Error::Case {
            path: path.to_path_buf(),
            message,
        };
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !pendkit_files::is_case_file(text) {
            return Ok(Case {
                name,
                description: None,
                model: suspension_from_text(path, text)?,
                overrides: Overrides::default(),
            });
        }
        let file = pendkit_files::parse_case(text).map_err(|e| match e {
            pendkit_files::FileError::Read { source, .. } => err(source.to_string()),
            pendkit_files::FileError::Parse { message } => err(message),
        })?;
        let model = if file.model.ends_with(".toml") {
            let folder = path.parent().unwrap_or_else(|| Path::new(""));
            let model_path = folder.join(&file.model);
            let model_text = std::fs::read_to_string(&model_path).map_err(|e| {
                err(format!(
                    "model '{}': cannot read: {e}",
                    model_path.display()
                ))
            })?;
            // a case names a model, never another case (which could name this one back)
            if pendkit_files::is_case_file(&model_text) {
                return Err(err(format!(
                    "model '{}' is a case file: a case refines a bundled model or a suspension file",
                    file.model
                )));
            }
            suspension_from_text(&model_path, &model_text)?
        } else {
            find_model(&file.model).map_err(|e| err(e.to_string()))?
        };
        Ok(Case {
            name,
            description: file.description,
            model,
            overrides: file.overrides,
        })
    }

    /// A bundled model name, or a path to a case file or a suspension file (anything ending
    /// in `.toml` or naming an existing file).
    ///
    /// Without the `files` feature a path is an error saying so.
    pub fn open(spec: &str) -> Result<Case, Error> {
        let path = Path::new(spec);
        if spec.ends_with(".toml") || path.is_file() {
            #[cfg(feature = "files")]
            return Case::from_file(path);
            #[cfg(not(feature = "files"))]
            return Err(Error::Case {
                path: path.to_path_buf(),
                message: "reading case and suspension files needs pendkit's `files` feature".into(),
            });
        }
        Case::model(spec)
    }

    /// The case with `overrides` applied after its own (a case file's, or earlier calls'):
    /// each parameter or damping field at most once in the list.
    ///
    /// ```
    /// use pendkit::{Case, Override};
    /// let case = Case::model("quad")?.with([
    ///     Override::value("m3", 40.5),                       // kg
    ///     Override::expression("l3", "scale(1.01)"),         // 1 % longer fibres
    ///     Override::damping("fibre_bending", "structural", "2*silica_phi"),
    /// ])?;
    /// assert_eq!(case.overrides.parameters.len(), 2);
    /// # Ok::<(), pendkit::Error>(())
    /// ```
    pub fn with(mut self, overrides: impl IntoIterator<Item = Override>) -> Result<Case, Error> {
        let mut seen = std::collections::BTreeSet::new();
        for o in overrides {
            let key = o.key();
            if !seen.insert(key.clone()) {
                return Err(Error::OverriddenTwice(key));
            }
            match o {
                Override::Value { name, value } => {
                    if !value.is_finite() {
                        return Err(Error::OverrideRefused {
                            key,
                            message: format!("{value} is not a finite number"),
                        });
                    }
                    // `{:e}` prints the shortest text that reads back as the same f64
                    let text = format!("{value:e}");
                    self.overrides.parameters.push((name, text));
                }
                Override::Expression { name, expression } => {
                    self.overrides.parameters.push((name, expression));
                }
                Override::Damping {
                    tag,
                    field,
                    expression,
                } => {
                    let spec = self.overrides.damping.entry(tag).or_default();
                    spec.set_field(&field, &expression)
                        .map_err(|message| Error::OverrideRefused { key, message })?;
                }
            }
        }
        Ok(self)
    }

    /// [`Case::with`] overrides written as text, `NAME=EXPR` or
    /// `damping.<tag>.<field>=EXPR` ([`Override::parse`]): what the command line's `--set`
    /// and the Python package's `sets` take.
    pub fn with_sets(self, sets: &[String]) -> Result<Case, Error> {
        let overrides = sets
            .iter()
            .map(|s| Override::parse(s))
            .collect::<Result<Vec<_>, _>>()?;
        self.with(overrides)
    }

    /// Resolves the parameters and builds the numeric model. An override of a parameter
    /// that nothing reads (neither the model's build, nor its damping, nor the definition
    /// of a parameter read) is an error: it would change nothing, silently.
    pub fn build(&self) -> Result<(System, Resolved), Error> {
        let (system, resolved) = pendkit_model::build_with(&*self.model, &self.overrides)?;
        self.check_overrides_read(&resolved)?;
        Ok((system, resolved))
    }

    /// [`Case::build`], with the parameters the model's own build read directly
    /// ([`pendkit_model::build_with_mechanical_reads`]).
    pub(crate) fn build_with_mechanical_reads(
        &self,
    ) -> Result<(System, Resolved, Vec<String>), Error> {
        let (system, resolved, mechanical_reads) =
            pendkit_model::build_with_mechanical_reads(&*self.model, &self.overrides)?;
        self.check_overrides_read(&resolved)?;
        Ok((system, resolved, mechanical_reads))
    }

    /// An override of a parameter that nothing read in the build that gave `resolved` is
    /// an error.
    fn check_overrides_read(&self, resolved: &Resolved) -> Result<(), Error> {
        let read = self.parameters_read(resolved)?;
        if let Some((name, _)) = self
            .overrides
            .parameters
            .iter()
            .find(|(name, _)| !read.contains(name.as_str()))
        {
            return Err(Error::Unread {
                name: name.clone(),
                model: self.model.name().to_string(),
                read: read.iter().cloned().collect::<Vec<_>>().join(" "),
            });
        }
        Ok(())
    }

    /// The parameters a build that gave `resolved` depends on: those it read, and what
    /// their definitions (with this case's overrides) refer to, transitively.
    pub fn parameters_read(
        &self,
        resolved: &Resolved,
    ) -> Result<std::collections::BTreeSet<String>, Error> {
        self.parameters_behind(resolved.read_names().into_iter().map(String::from))
    }

    /// `names` and what their definitions (with this case's overrides) refer to,
    /// transitively: every parameter a quantity that reads `names` depends on.
    pub fn parameters_behind(
        &self,
        names: impl IntoIterator<Item = String>,
    ) -> Result<std::collections::BTreeSet<String>, Error> {
        let mut params = pendkit_model::Defaults::of(&*self.model)?.params.clone();
        for (name, text) in &self.overrides.parameters {
            params
                .apply_text(name, text)
                .map_err(pendkit_model::BuildError::from)?;
        }
        let mut read: std::collections::BTreeSet<String> = names.into_iter().collect();
        let mut pending: Vec<String> = read.iter().cloned().collect();
        while let Some(name) = pending.pop() {
            if let Some(definition) = params.get(&name) {
                for symbol in definition.expr.symbols() {
                    if read.insert(symbol.clone()) {
                        pending.push(symbol);
                    }
                }
            }
        }
        Ok(read)
    }
}

/// One parameter of a case as resolved for a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParameterValue {
    /// Name.
    pub name: String,
    /// Resolved value, in its unit.
    pub value: f64,
    /// Unit, where the model declares one (empty for a pure number).
    pub unit: Option<String>,
    /// The definition as written: the model's default, or the case's override.
    pub definition: String,
    /// Whether the case (or a `--set`) overrides the model's default.
    pub overridden: bool,
}

/// Where a result comes from: the model, the case and every resolved parameter.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Provenance {
    /// Model name.
    pub model: String,
    /// Case name (the model name, or the case file's stem).
    pub case: String,
    /// The case's description, if it has one.
    pub description: Option<String>,
    /// The numeric parameters in definition order.
    pub parameters: Vec<ParameterValue>,
    /// pendkit's version.
    pub version: String,
}

impl Case {
    /// The provenance of a build of this case that resolved to `resolved`: each parameter
    /// with its value, its unit where the model declares one, and its definition.
    pub fn provenance(&self, resolved: &Resolved) -> Result<Provenance, Error> {
        let defaults = pendkit_model::Defaults::of(&*self.model)?;
        let parameters = resolved
            .iter()
            .map(|(name, value)| {
                let overridden = self
                    .overrides
                    .parameters
                    .iter()
                    .rev()
                    .find(|(n, _)| n == name);
                ParameterValue {
                    name: name.to_string(),
                    value,
                    unit: defaults.params.unit(name).map(str::to_string),
                    definition: match overridden {
                        Some((_, text)) => text.clone(),
                        None => defaults
                            .params
                            .get(name)
                            .map(|d| d.source.clone())
                            .unwrap_or_default(),
                    },
                    overridden: overridden.is_some(),
                }
            })
            .collect();
        Ok(Provenance {
            model: self.model.name().to_string(),
            case: self.name.clone(),
            description: self.description.clone(),
            parameters,
            version: VERSION.to_string(),
        })
    }
}

/// The result of running one stage of a model.
pub struct StageResult {
    /// The numeric model.
    pub system: System,
    /// Equilibrium and per-term matrices.
    pub assembled: Assembled,
    /// The stage's frequency-independent matrices for responses and noise.
    pub model: StageModel,
    /// Normal modes (possibly with unstable ones: see `stability`). Each carries its
    /// estimated error ([`pendkit_dynamics::Mode::omega_squared_error`]).
    pub modes: Modes,
    /// The stability verdict of the equilibrium: growing modes, floats without a stable
    /// position, bodies upside down. [`StageResult::check_stable`] turns it into an error.
    pub stability: Stability,
}

/// Which normal modes a stage run computes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ModeSelection {
    /// Every mode, by the dense eigensolver block by block.
    #[default]
    All,
    /// The modes below this frequency (Hz): by the dense eigensolver up to
    /// [`DENSE_MODES_LIMIT`] variables, by shift-invert Lanczos on the sparse factorisation
    /// above ([`StageModel::modes_below`]).
    Below(f64),
}

/// Largest number of variables for which [`ModeSelection::Below`] uses the dense
/// eigensolver (a few ms at this size); larger models use shift-invert.
pub const DENSE_MODES_LIMIT: usize = 200;

/// Equilibrium, stiffness, mass and modes of `system` at `stage`. The modes use the real
/// stiffness at f = 0 (each tag's ε'(0); 1 unless a model says otherwise).
pub fn run_stage(system: System, stage: Stage) -> Result<StageResult, Error> {
    run_stage_with(system, stage, &RunOptions::default(), None)
}

/// How [`run_stage_with`] runs a stage: assembly options (equilibrium controls, derivative
/// path) and which modes to compute.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Equilibrium controls and derivative path.
    pub assembly: AssemblyOptions,
    /// All modes, or those below a frequency.
    pub modes: ModeSelection,
}

/// [`run_stage`] with options, recording the time of each phase into `times` when given:
/// the assembly's (`terms`, `equilibrium`, `hessian:<kind>`, `mass`), then `stage-model`
/// (the stage's matrices by tag), `rounding` (each term's share of the stiffness rounding,
/// for the modes' accuracy), `floats` (their elimination), `modes` and `stability` (the
/// float block's and the bodies' checks for the verdict).
pub fn run_stage_with(
    system: System,
    stage: Stage,
    options: &RunOptions,
    mut times: Option<&mut PhaseTimes>,
) -> Result<StageResult, Error> {
    if let ModeSelection::Below(hz) = options.modes
        && !(hz > 0.0 && hz.is_finite())
    {
        return Err(DynamicsError::BelowFrequency(hz).into());
    }
    pendkit_energy::check_registrations()?;
    let assembled = assemble_with(&system, stage, &options.assembly, times.as_deref_mut())?;
    let model = timed(&mut times, "stage-model", 1, || {
        StageModel::new(&system, &assembled)
    });
    model.check_damping_at_dc(&system.damping)?;
    let rounding = timed(&mut times, "rounding", 1, || {
        TermRounding::new(&model, &assembled, &system.damping)
    });
    let modes = match options.modes {
        ModeSelection::Below(hz) if model.sizes.0 > DENSE_MODES_LIMIT => {
            let below = timed(&mut times, "modes", 1, || {
                model.modes_below_with_rounding(&system.damping, hz, &rounding)
            });
            match below {
                Ok(modes) => modes,
                // the shift-invert iteration could not resolve every mode below the bound
                // (a growing mode beyond its shift's resolution, a shift on an eigenvalue):
                // the dense solve, slower but complete, decides instead
                Err(DynamicsError::Solver(_)) => {
                    dense_modes(&model, &assembled, &system, &rounding, Some(hz), &mut times)?
                }
                Err(e) => return Err(e.into()),
            }
        }
        ModeSelection::Below(hz) => {
            dense_modes(&model, &assembled, &system, &rounding, Some(hz), &mut times)?
        }
        ModeSelection::All => {
            dense_modes(&model, &assembled, &system, &rounding, None, &mut times)?
        }
    };
    // after the modes, so that a model the modes refuse outright (a massless body, whose
    // wires then carry no tension) is refused for that
    pendkit_dynamics::validate::check_wire_stretch(&system, &assembled.equilibrium.coords)?;
    let stability = timed(&mut times, "stability", 1, || {
        let floats = float_directions(&model, &system.damping, Some(&rounding))?;
        let inverted = inverted_bodies(&system, &assembled.equilibrium.coords);
        Ok::<_, Error>(Stability::assess(&modes, floats, model.sizes.1, inverted))
    })?;
    Ok(StageResult {
        system,
        assembled,
        model,
        modes,
        stability,
    })
}

/// The stage's modes by the dense eigensolver block by block (those below `below` Hz when
/// given, every growing mode among them), recording the `floats` and `modes` phases.
fn dense_modes(
    model: &StageModel,
    assembled: &Assembled,
    system: &System,
    rounding: &TermRounding,
    below: Option<f64>,
    times: &mut Option<&mut PhaseTimes>,
) -> Result<Modes, Error> {
    let reduced = timed(times, "floats", 1, || {
        eliminate_floats(
            &model.real_stiffness(&system.damping),
            &assembled.layout,
            system,
        )
    })?;
    let mut modes = timed(times, "modes", 1, || {
        normal_modes_with_rounding(&reduced.k_eff, &assembled.mass, &model.variables, rounding)
    })?;
    if let Some(hz) = below {
        modes.modes.retain(|m| m.hz < hz);
    }
    Ok(modes)
}

/// A point on a body as the linearised geometry at equilibrium sees it: how far it moves
/// along a lab direction per unit of each unknown (variables, then floats) and of each
/// parameter.
struct PointWeights {
    unknowns: DVector<f64>,
    parameters: DVector<f64>,
}

impl StageResult {
    /// One line saying what grows, as an error, unless the equilibrium is stable (or
    /// neutral). Every calculation that answers with a linearised model checks this first.
    pub fn check_stable(&self) -> Result<(), Error> {
        Ok(self.stability.check()?)
    }

    /// The check every command answering with a linearised model (transfer functions,
    /// noise, state space, ...) makes before it answers: `Ok(None)` when nothing grows;
    /// when something does, the error, or with `allow_unstable` `Ok(Some(warning))`, the
    /// one line to show the user before going on (control design needs unstable plants).
    /// A neutral verdict that rests on a float stiffness rounding cannot sign (nothing
    /// shown to grow) goes on, with the verdict as the line to show.
    pub fn require_stable(&self, allow_unstable: bool) -> Result<Option<String>, Error> {
        match (self.check_stable(), allow_unstable) {
            (Ok(()), _) if !self.stability.neutral_floats.is_empty() => {
                Ok(Some(self.stability.to_string()))
            }
            (Ok(()), _) => Ok(None),
            (Err(e), true) => Ok(Some(format!("{e} (going on: --allow-unstable)"))),
            (Err(e), false) => Err(e),
        }
    }
}

impl StageResult {
    /// A point on a body and a direction, written `<body>@x,y,z/dx,dy,dz` (m, body
    /// coordinates; direction in lab axes, normalised): how far the point moves along the
    /// direction per unit of every unknown and parameter (the linearised geometry at
    /// equilibrium). The same weights are the generalised force of a unit force there.
    fn point_weights(&self, spec: &str) -> Option<Result<PointWeights, Error>> {
        let (body, rest) = spec.split_once('@')?;
        Some((|| {
            let bad = |why: &str| Error::Name {
                name: spec.to_string(),
                message: format!("expected <body>@x,y,z/dx,dy,dz ({why})"),
            };
            let (point, dir) = rest
                .split_once('/')
                .ok_or_else(|| bad("no '/' before the direction"))?;
            let nums = |t: &str, what: &str| -> Result<Vector3<f64>, Error> {
                let v: Vec<f64> = t
                    .split(',')
                    .map(pendkit_expr::number_literal)
                    .collect::<Result<_, _>>()
                    .map_err(|e| bad(&format!("the {what} is not three numbers: {e}")))?;
                if v.len() == 3 {
                    Ok(Vector3::new(v[0], v[1], v[2]))
                } else {
                    Err(bad(&format!("the {what} must be three finite numbers")))
                }
            };
            let (p, d) = (nums(point, "point")?, nums(dir, "direction")?);
            // scaled by its largest component first: a tiny or huge (finite) direction
            // would otherwise underflow or overflow in its norm
            let largest = d.amax();
            if largest == 0.0 {
                return Err(bad("the direction is zero"));
            }
            let d = d / largest;
            let b = self.system.body(body).ok_or_else(|| Error::Name {
                name: spec.to_string(),
                message: format!(
                    "unknown body '{body}' (bodies: {})",
                    self.system
                        .bodies
                        .iter()
                        .map(|b| b.name.as_str())
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
            })?;
            self.weights_of_point(b, &p, &d)
                .ok_or_else(|| bad("its motion is not finite at the equilibrium"))
        })())
    }

    /// How far `point` (m, body coordinates) on body `body` moves along `direction` (lab
    /// axes, normalised here) per unit of every unknown (variables, then floats) and every
    /// parameter: the linearised geometry at the equilibrium. `None` when a weight is not
    /// finite (or the body index is out of range).
    fn weights_of_point(
        &self,
        body: usize,
        point: &Vector3<f64>,
        direction: &Vector3<f64>,
    ) -> Option<PointWeights> {
        let jac = self
            .system
            .bodies
            .get(body)?
            .frame
            .try_jacobian(&self.assembled.equilibrium.coords, point)
            .ok()?;
        let d = direction.normalize();
        let layout = &self.assembled.layout;
        let along = |ids: &[usize]| {
            DVector::from_iterator(
                ids.len(),
                ids.iter().map(|&g| jac.position.column(g).dot(&d)),
            )
        };
        let unknowns: Vec<usize> = layout
            .variables
            .iter()
            .chain(&layout.floats)
            .copied()
            .collect();
        let weights = PointWeights {
            unknowns: along(&unknowns),
            parameters: along(&layout.parameters),
        };
        let finite = weights
            .unknowns
            .iter()
            .chain(weights.parameters.iter())
            .all(|x| x.is_finite());
        finite.then_some(weights)
    }

    /// The vector of a model's named input or output (`[inputs]`/`[outputs]` of a
    /// suspension file), laid out as the built-in forms are:
    ///
    /// - a displacement output: over the variables, floats and parameters (a point's whole
    ///   motion, as `<body>@x,y,z/dx,dy,dz`: through the variables, the floats that pose
    ///   its body, and the support);
    /// - a force input: over the variables and floats (a force on a float-posed body such
    ///   as a blade tip reaches the variables through the float elimination);
    /// - a displacement input or a support-force output: over the parameters; a point there
    ///   must be one the support alone moves (driven as `support@x,y,z/dx,dy,dz` is).
    fn named_vector(&self, signal: &NamedSignal, input: bool) -> Result<DVector<f64>, Error> {
        let m = &self.model;
        let (nx, nq, ns) = m.sizes;
        let on_parameters = input != signal.force;
        let n = match (on_parameters, input) {
            (true, _) => ns,
            (false, true) => nx + nq,
            (false, false) => nx + nq + ns,
        };
        let bad = |message: String| Error::Name {
            name: signal.name.clone(),
            message,
        };
        let mut v = DVector::zeros(n);
        for (coefficient, term) in &signal.terms {
            match term {
                SignalTerm::Coordinate(c) => {
                    let coordinate = self
                        .system
                        .coords
                        .get(*c)
                        .map(|c| c.name.as_str())
                        .unwrap_or_default();
                    let position = |names: &[String]| names.iter().position(|n| n == coordinate);
                    let k = if on_parameters {
                        position(&m.parameters)
                    } else {
                        // variables first, then floats, then (outputs) the parameters
                        position(&m.variables)
                            .or_else(|| position(&m.floats).map(|k| nx + k))
                            .or_else(|| position(&m.parameters).map(|k| nx + nq + k))
                            .filter(|&k| k < n)
                    };
                    let k = k.ok_or_else(|| {
                        bad(format!(
                            "combines '{coordinate}', which this stage does not keep as a {}",
                            if on_parameters {
                                "parameter"
                            } else if input {
                                "variable or float"
                            } else {
                                "variable, float or parameter"
                            }
                        ))
                    })?;
                    v[k] += coefficient;
                }
                SignalTerm::Point {
                    body,
                    point,
                    direction,
                } => {
                    let w = self
                        .weights_of_point(*body, point, direction)
                        .ok_or_else(|| {
                            bad("a point whose motion is not finite at the equilibrium".into())
                        })?;
                    if !on_parameters {
                        v.rows_mut(0, nx + nq).axpy(*coefficient, &w.unknowns, 1.0);
                        if n == nx + nq + ns {
                            v.rows_mut(nx + nq, ns)
                                .axpy(*coefficient, &w.parameters, 1.0);
                        }
                    } else if signal.force {
                        return Err(bad(
                            "a point cannot carry the support force: name the support's coordinates".into(),
                        ));
                    } else {
                        // a driven point: the smallest change of the parameters that moves
                        // it by one unit along the direction, as support@x,y,z/dx,dy,dz
                        let norm2 = w.parameters.norm_squared();
                        if w.unknowns.iter().any(|&x| x != 0.0)
                            || norm2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                        {
                            return Err(bad(
                                "a displacement input must be a point that only the support moves"
                                    .into(),
                            ));
                        }
                        v.axpy(*coefficient / norm2, &w.parameters, 1.0);
                    }
                }
            }
        }
        Ok(v)
    }

    fn unit(n: usize, k: usize) -> DVector<f64> {
        let mut v = DVector::zeros(n);
        v[k] = 1.0;
        v
    }

    fn names_error(&self, name: &str, what: &str, valid: &[String]) -> Error {
        Error::Name {
            name: name.to_string(),
            message: format!("not {what} (valid: {})", valid.join(" ")),
        }
    }

    /// Parses an input: a named input the model declares, a parameter (support
    /// displacement, e.g. `x00`), a point on a body the support alone moves
    /// (`support@x,y,z/dx,dy,dz`: the smallest change of the parameters, metres and radians
    /// alike, that moves the point by one unit along the direction), `force:<variable>` or
    /// `force:<body>@x,y,z/dx,dy,dz` (a force at a point, also on a body a float poses, such
    /// as a blade tip). Names of a scheme the model declares are accepted too (`GND_L`,
    /// `force:L3_P`).
    pub fn input(&self, name: &str) -> Result<Input, Error> {
        if let Some(signal) = self.system.inputs.iter().find(|s| s.name == name) {
            let v = self.named_vector(signal, true)?;
            return Ok(if signal.force {
                Input::Force(v)
            } else {
                Input::Displacement(v)
            });
        }
        let name = &self.unalias(name);
        let m = &self.model;
        let err = |message: &str| Error::Name {
            name: name.to_string(),
            message: message.to_string(),
        };
        if let Some(target) = name.strip_prefix("force:") {
            if let Some(w) = self.point_weights(target) {
                let w = w?;
                if w.unknowns.iter().all(|&x| x == 0.0) {
                    return Err(err(if w.parameters.iter().any(|&x| x != 0.0) {
                        "a force on a point the support alone moves does nothing (the support is driven): use the point as a displacement input"
                    } else {
                        "the point does not move with any coordinate"
                    }));
                }
                return Ok(Input::Force(w.unknowns));
            }
            return match m.variables.iter().position(|v| v == target) {
                Some(k) => Ok(Input::Force(Self::unit(m.variables.len(), k))),
                None => Err(self.names_error(target, "a variable to push on", &m.variables)),
            };
        }
        if let Some(w) = self.point_weights(name) {
            let w = w?;
            if w.unknowns.iter().any(|&x| x != 0.0) {
                return Err(err(
                    "a displacement input must be a point that only the support moves: push on a moving body with force:<body>@x,y,z/dx,dy,dz",
                ));
            }
            let norm2 = w.parameters.norm_squared();
            if norm2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(err("the point does not move with any parameter"));
            }
            return Ok(Input::Displacement(w.parameters / norm2));
        }
        match m.parameters.iter().position(|v| v == name) {
            Some(k) => Ok(Input::Displacement(Self::unit(m.parameters.len(), k))),
            None => Err(self.names_error(
                name,
                "a parameter to drive (or <support body>@x,y,z/dx,dy,dz, force:<variable>, force:<body>@x,y,z/dx,dy,dz)",
                &m.parameters,
            )),
        }
    }

    /// Parses an output: a named output the model declares, a variable,
    /// `<body>@x,y,z/dx,dy,dz` (the point's whole motion: through the variables, the floats
    /// that pose its body and the support), or `force:<parameter>` (the force on the
    /// support). Names of a scheme the model declares are accepted too (`L3_L`,
    /// `L3@0,0,0/1,0,0`).
    pub fn output(&self, name: &str) -> Result<Output, Error> {
        if let Some(signal) = self.system.outputs.iter().find(|s| s.name == name) {
            let v = self.named_vector(signal, false)?;
            return Ok(if signal.force {
                Output::SupportForce(v)
            } else {
                Output::Displacement(v)
            });
        }
        let name = &self.unalias(name);
        let m = &self.model;
        if let Some(target) = name.strip_prefix("force:") {
            return match m.parameters.iter().position(|v| v == target) {
                Some(k) => Ok(Output::SupportForce(Self::unit(m.parameters.len(), k))),
                None => Err(self.names_error(target, "a parameter", &m.parameters)),
            };
        }
        if let Some(w) = self.point_weights(name) {
            let w = w?;
            let all: Vec<f64> = w
                .unknowns
                .iter()
                .chain(w.parameters.iter())
                .copied()
                .collect();
            return Ok(Output::Displacement(DVector::from_vec(all)));
        }
        match m.variables.iter().position(|v| v == name) {
            Some(k) => Ok(Output::Displacement(Self::unit(m.variables.len(), k))),
            None => Err(self.names_error(
                name,
                "a variable (or <body>@x,y,z/dx,dy,dz, force:<parameter>)",
                &m.variables,
            )),
        }
    }
}

/// Every value finite, or an error naming the first frequency where one is not.
fn check_finite<'a>(
    what: &str,
    freqs: &[f64],
    values: impl IntoIterator<Item = &'a f64>,
    per_frequency: usize,
) -> Result<(), Error> {
    let per = per_frequency.max(1);
    match values.into_iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::NotFinite {
            what: what.to_string(),
            f_hz: freqs.get(k / per).copied().unwrap_or(f64::NAN),
        }),
    }
}

impl StageResult {
    /// Transfer function from the named input to the named output (see
    /// [`StageResult::input`], [`StageResult::output`]) at `freqs` (Hz), with the model's
    /// damping, solved over the blocks they couple to.
    pub fn transfer(
        &self,
        input: &str,
        output: &str,
        freqs: &[f64],
    ) -> Result<Vec<faer::c64>, Error> {
        self.transfer_with(input, output, freqs, Solver::Restricted)
    }

    /// [`StageResult::transfer`] solved as `solver` says (restricted, full, or the dense
    /// reference).
    pub fn transfer_with(
        &self,
        input: &str,
        output: &str,
        freqs: &[f64],
        solver: Solver,
    ) -> Result<Vec<faer::c64>, Error> {
        let (i, o) = (self.input(input)?, self.output(output)?);
        let h = self
            .model
            .transfer_with(&self.system.damping, &i, &o, freqs, solver)?;
        check_finite(
            &format!("transfer function {output}/{input}"),
            freqs,
            h.iter().flat_map(|z| [&z.re, &z.im]),
            2,
        )?;
        Ok(h)
    }

    /// Thermal noise (PSD, m²/Hz or rad²/Hz) of the named displacement output at `freqs`
    /// (Hz), at the model's temperature, with its breakdown by damping tag.
    pub fn noise(&self, output: &str, freqs: &[f64]) -> Result<ThermalNoise, Error> {
        self.noise_with(output, freqs, &NoiseOptions::default())
    }

    /// [`StageResult::noise`] solved and broken down as `options` says (per term too, full
    /// or restricted solve).
    pub fn noise_with(
        &self,
        output: &str,
        freqs: &[f64],
        options: &NoiseOptions,
    ) -> Result<ThermalNoise, Error> {
        match self.output(output)? {
            Output::Displacement(v) => {
                let noise = thermal_noise_with(
                    &self.model,
                    &self.system.damping,
                    &v,
                    self.system.temperature,
                    freqs,
                    options,
                )
                .map_err(|e| match e {
                    DynamicsError::NoLoss { lossless, .. } => DynamicsError::NoLoss {
                        output: format!("'{output}'"),
                        lossless,
                    },
                    other => other,
                })?;
                let what = format!("thermal noise of {output}");
                check_finite(&what, freqs, &noise.total, 1)?;
                for (_, series) in &noise.tags {
                    check_finite(&what, freqs, series, 1)?;
                }
                Ok(noise)
            }
            Output::SupportForce(_) => Err(Error::Name {
                name: output.to_string(),
                message: "thermal noise needs a displacement output".into(),
            }),
        }
    }
}

/// One phase of a benchmark: its median and minimum time per repetition and how many
/// items it processes in one repetition (terms for `hessian:<kind>`, frequencies for
/// `noise`, 1 otherwise).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchPhase {
    /// Phase name.
    pub name: String,
    /// Median over repetitions (s).
    pub median_s: f64,
    /// Minimum over repetitions (s).
    pub min_s: f64,
    /// Items per repetition.
    pub calls: usize,
}

/// Where the time of a whole calculation goes, phase by phase (`pendkit bench`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchReport {
    /// Model name.
    pub model: String,
    /// Stage name (`0A` ... `2`).
    pub stage: String,
    /// Phases in the order they run.
    pub phases: Vec<BenchPhase>,
    /// Median over repetitions of the time from the build to the modes (s), noise excluded.
    pub total_median_s: f64,
}

/// Times every phase of building `spec` (a model or case file, with `sets` overrides) and
/// running `stage`, `repeat` times in this process: `build` (parameters and the numeric
/// model), the assembly's phases (`equilibrium`, `hessian:<kind>`, `mass`), `stage-model`,
/// `floats`, `modes`, and with `noise = Some((output, points))` the thermal noise of
/// `output` at `points` log-spaced frequencies from 0.1 to 100 Hz (`noise`).
pub fn bench(
    spec: &str,
    sets: &[String],
    stage: Stage,
    repeat: usize,
    noise: Option<(&str, usize)>,
) -> Result<BenchReport, Error> {
    if repeat == 0 || repeat > MAX_REPEAT {
        return Err(Error::ZeroRepeat);
    }
    if noise.is_some() && stage == Stage::S0A {
        return Err(Error::StageTooEarly);
    }
    let grid = match noise {
        Some((_, points)) => log_grid(0.1, 100.0, points)?,
        None => Vec::new(),
    };
    let mut runs: Vec<PhaseTimes> = Vec::with_capacity(repeat);
    let mut model = String::new();
    for _ in 0..repeat {
        let mut times = PhaseTimes::new();
        let (case, system) = times.time("build", 1, || -> Result<_, Error> {
            let case = Case::open(spec)?.with_sets(sets)?;
            let (system, _) = case.build()?;
            Ok((case, system))
        })?;
        model = case.model.name().to_string();
        let result = run_stage_with(system, stage, &RunOptions::default(), Some(&mut times))?;
        if let Some((output, points)) = noise {
            times.time("noise", points, || result.noise(output, &grid))?;
        }
        runs.push(times);
    }
    let median = |mut v: Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        let m = v.len() / 2;
        if v.len() % 2 == 1 {
            v[m]
        } else {
            0.5 * (v[m - 1] + v[m])
        }
    };
    let mut phases: Vec<BenchPhase> = Vec::new();
    for name in runs.iter().flat_map(|r| r.phases().iter().map(|p| &p.name)) {
        if phases.iter().any(|p| &p.name == name) {
            continue;
        }
        // a phase absent from a repetition took no time there
        let samples: Vec<(f64, usize)> = runs
            .iter()
            .map(|r| {
                r.phases()
                    .iter()
                    .find(|p| &p.name == name)
                    .map_or((0.0, 0), |p| (p.seconds, p.calls))
            })
            .collect();
        phases.push(BenchPhase {
            name: name.clone(),
            median_s: median(samples.iter().map(|s| s.0).collect()),
            min_s: samples.iter().map(|s| s.0).fold(f64::INFINITY, f64::min),
            calls: samples.iter().map(|s| s.1).max().unwrap_or(0),
        });
    }
    let totals = runs
        .iter()
        .map(|r| {
            r.phases()
                .iter()
                .filter(|p| p.name != "noise")
                .map(|p| p.seconds)
                .sum()
        })
        .collect();
    Ok(BenchReport {
        model,
        stage: stage.name().to_string(),
        phases,
        total_median_s: median(totals),
    })
}

/// `n` log-spaced frequencies from `from` to `to` (Hz): finite, 1e-9 Hz ≤ from ≤ to ≤
/// 1e9 Hz ([`pendkit_dynamics::validate`]), 1 ≤ n ≤ 1 000 000.
pub fn log_grid(from: f64, to: f64, n: usize) -> Result<Vec<f64>, Error> {
    use pendkit_dynamics::validate::{MAX_FREQUENCY, MAX_POINTS, MIN_FREQUENCY};
    let in_range = |f: f64| f.is_finite() && (MIN_FREQUENCY..=MAX_FREQUENCY).contains(&f);
    if !in_range(from) || !in_range(to) || to < from || n == 0 || n > MAX_POINTS {
        return Err(Error::Grid { from, to, n });
    }
    if n == 1 {
        return Ok(vec![from]);
    }
    let (a, b) = (from.ln(), to.ln());
    let mut grid: Vec<f64> = (0..n)
        .map(|i| (a + (b - a) * i as f64 / (n - 1) as f64).exp())
        .collect();
    // the end points exactly as given, not as exp(ln(x)) rounds them
    grid[0] = from;
    grid[n - 1] = to;
    Ok(grid)
}
