//! pendkit's library: from a suspension model to its equilibrium, normal modes, transfer
//! functions, thermal noise and state space, and their sensitivities to the parameters, for
//! downstream tools. One path, model → case → stage result → answers:
//!
//! ```
//! use pendkit::{Case, NoiseOptions, Override, Solver, Stage, log_grid, run_stage};
//!
//! // the aLIGO quad with a heavier test mass (kg), at stage 2 (the complete model)
//! let case = Case::model("quad")?.with([Override::value("m3", 50.0)])?;
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
//! (The README shows the same example; `crates/interface/pendkit/tests/readme.rs` keeps the two the
//! same.) A [`Case`] holds its model by `Arc`: cases share a model and
//! its parsed defaults, and can be sent to other threads (a Monte Carlo study builds
//! thousands in parallel: `examples/downstream`). Overrides are typed ([`Override`]: a
//! value, an expression, a damping field); [`Case::with_sets`] reads the command line's
//! `NAME=EXPR` text. Errors ([`Error`]) are one line each, in the library's own terms.
//!
//! # Where things are
//!
//! | module | what |
//! |---|---|
//! | the root | [`Case`], [`Override`], [`Model`], [`Stage`], [`run_stage`], [`StageResult`], [`Solver`], [`NoiseOptions`], [`log_grid`], [`Error`], [`VERSION`] |
//! | [`catalogue`] | the bundled models ([`catalogue::models`], [`catalogue::find_model`]) and suspension files read at run time |
//! | [`stage`] | running a stage with options ([`stage::run_stage_with`], over [`dynamics::StageRun`]), provenance, the named state space, [`stage::bench`] |
//! | [`describe`] | units, mode families and the parameter table (`pendkit params`) |
//! | [`fit`], [`sensitivity`], [`tradeoff`] | fitting measured modes, exact sensitivities, the speed–accuracy ladder |
//! | the layers | [`model`] (builder, [`model::schema`]: the fields with units and domains), [`suspension`] (the file format), [`system`] (the numeric description, `System`), [`energy`] (the terms), [`assembly`], [`dynamics`], [`noise`], [`geometry`], [`params`], [`expr`], [`nalgebra`] |
//!
//! # Features
//!
//! | feature | adds | pulls in |
//! |---|---|---|
//! | `files` | [`Case::from_file`], [`Case::open`] taking a path, `catalogue::load_suspension`: case files and suspension files read at run time | `pendkit-files`, `pendkit-suspension/toml` (a TOML parser) |
//! | `export` | `StageResult::write_state_space`: the state space to `.mat`, `.npz` or JSON, with units and provenance | `pendkit-export` (zip) |
//!
//! Neither is on by default; the `pendkit` command-line program enables both. The bundled
//! models need no feature: each is a suspension file embedded already read (its tree packed
//! at build time, [`catalogue::bundled`]), so the library carries no TOML parser by default.
//!
//! # What it links
//!
//! This crate names every bundled element crate (wire torsion, bending, extra stretch, the
//! point spring) so that the linker keeps their `inventory` registrations (inventory issue
//! #50): a program
//! that depends on `pendkit` alone sees all of them in [`energy::registry`]. It also
//! re-exports the crates whose types its functions take and return, so downstream code
//! needs no version-matched dependencies of its own.

mod bench;
pub mod catalogue;
pub mod describe;
pub mod fit;
mod parameters;
pub mod sensitivity;
pub mod stage;
mod state_space;
#[cfg(feature = "files")]
mod suspension_files;
pub mod tradeoff;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pendkit_assembly::AssemblyError;
use pendkit_dynamics::DynamicsError;
use pendkit_model::{BuildError, Overrides};
use pendkit_params::Resolved;
use pendkit_system::System;

use catalogue::find_model;
#[cfg(feature = "files")]
use catalogue::suspension_from_text;
use stage::MAX_REPEAT;

// Name every bundled element crate so the linker keeps its registration.
use pendkit_element_bending as _;
use pendkit_element_extra_stretch as _;
use pendkit_element_optical_spring as _;
use pendkit_element_point_spring as _;
use pendkit_element_torsion as _;

// the layers, each reachable as a module
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
pub use pendkit_noise as noise;
pub use pendkit_params as params;
pub use pendkit_suspension as suspension;
pub use pendkit_system as system;

// the one obvious path: model -> case -> stage result -> modes, responses, noise
pub use pendkit_dynamics::Solver;
pub use pendkit_model::Model;
pub use pendkit_noise::NoiseOptions;
pub use pendkit_system::Stage;
pub use stage::{StageResult, run_stage};

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
    Assembly(AssemblyError),
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
        "frequency grid from {} Hz to {} Hz with {n} points: need 1e-9 <= from <= to <= 1e9 (Hz, finite) and at least 1 point",
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

/// The assembly's refusal; a duplicate element kind, which it finds first, as the
/// registry's.
impl From<AssemblyError> for Error {
    fn from(e: AssemblyError) -> Error {
        match e {
            AssemblyError::Registry(e) => Error::Registry(e),
            e => Error::Assembly(e),
        }
    }
}

/// A stage run's refusal, as the variant of the layer that refused it.
impl From<pendkit_dynamics::RunError> for Error {
    fn from(e: pendkit_dynamics::RunError) -> Error {
        match e {
            pendkit_dynamics::RunError::Assembly(e) => e.into(),
            pendkit_dynamics::RunError::Dynamics(e) => Error::Dynamics(e),
        }
    }
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
    /// file's folder. Files are read only if they are regular files within
    /// [`pendkit_limits::FILE_BYTES`].
    #[cfg(feature = "files")]
    pub fn from_file(path: &Path) -> Result<Case, Error> {
        let text = pendkit_limits::read_text(path).map_err(|source| Error::Case {
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
            let model_text = pendkit_limits::read_text(&model_path).map_err(|e| {
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
        // no override, nothing to check: what the build read (a closure over every
        // definition) is only worked out for one
        if self.overrides.parameters.is_empty() {
            return Ok(());
        }
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

/// `n` log-spaced frequencies from `from` to `to` (Hz): finite, 1e-9 Hz ≤ from ≤ to ≤
/// 1e9 Hz ([`pendkit_dynamics::validate`]), 1 ≤ n ≤ [`pendkit_limits::FREQUENCY_POINTS`]
/// (checked before the grid is made).
pub fn log_grid(from: f64, to: f64, n: usize) -> Result<Vec<f64>, Error> {
    use pendkit_dynamics::validate::{MAX_FREQUENCY, MIN_FREQUENCY};
    let in_range = |f: f64| f.is_finite() && (MIN_FREQUENCY..=MAX_FREQUENCY).contains(&f);
    if !in_range(from) || !in_range(to) || to < from || n == 0 {
        return Err(Error::Grid { from, to, n });
    }
    pendkit_limits::FREQUENCY_POINTS
        .check(n)
        .map_err(DynamicsError::TooManyPoints)?;
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
