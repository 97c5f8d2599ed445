//! pendkit's library facade: the catalogue of bundled models, case files, and the whole
//! pipeline from a model or case to equilibrium, normal modes, transfer functions, thermal
//! noise and state space, for downstream tools that want one call.
//!
//! ```
//! use pendkit::{Case, energy::Stage, log_grid, run_stage};
//!
//! let case = Case::model("pendulum")?.with_sets(&["m1=20".into()])?;
//! let (system, _parameters) = case.build()?;
//! let result = run_stage(system, Stage::S2)?;
//! let lowest = &result.modes.modes[0];
//! assert!((lowest.hz - 0.644).abs() < 1e-3); // sqrt(g/l)/2π with l = 0.6 m, plus flexure
//! let freqs = log_grid(1.0, 100.0, 3)?;
//! let noise = result.noise("x1", &freqs)?;
//! assert_eq!(noise.asd().len(), 3); // m/√Hz; noise.psd() is the PSD in m²/Hz
//! # Ok::<(), pendkit::Error>(())
//! ```
//!
//! # Features
//!
//! | feature | adds | pulls in |
//! |---|---|---|
//! | `files` | [`Case::from_file`], and [`Case::open`] taking a case-file path | `pendkit-files` (a TOML parser) |
//! | `export` | [`StageResult::write_state_space`]: the state space to `.mat`, `.npz` or JSON, with units and provenance | `pendkit-export` (zip) |
//!
//! Neither is on by default, so the library alone has no command-line or file-format
//! dependencies; the `pendkit` command-line program enables both.
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
mod state_space;

use std::path::{Path, PathBuf};

use nalgebra::{DVector, Vector3};
use pendkit_assembly::{Assembled, AssemblyError, assemble_with, timed};
use pendkit_dynamics::{DynamicsError, eliminate_floats, normal_modes};
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
pub use pendkit_noise as noise;
pub use pendkit_params as params;

pub use pendkit_assembly::{AssemblyOptions, PhaseTimes};
pub use pendkit_dynamics::{Input, Modes, Output, Solver, StageModel, StateSpace};
pub use pendkit_energy::{Stage, System};
pub use pendkit_model::{Model, Overrides};
pub use pendkit_noise::{NoiseOptions, ThermalNoise};
pub use pendkit_params::Resolved;

pub use describe::{DOF_FAMILIES, OTHER_FAMILY, unit_ratio, unit_slug};
pub use state_space::NamedStateSpace;

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
    /// A `--set NAME=EXPR` argument without '='.
    #[error("--set '{0}': expected NAME=EXPR or damping.<tag>.<field>=EXPR")]
    SetSyntax(String),
    /// Building the model failed.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// Equilibrium or assembly failed.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
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
        "frequency grid from {from} Hz to {to} Hz with {n} points: need 0 < from <= to and at least one point"
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
    /// A benchmark asked to repeat nothing.
    #[error("--repeat must be at least 1")]
    ZeroRepeat,
}

/// Every bundled model.
pub fn models() -> Vec<&'static dyn Model> {
    let mut all = pendkit_models_basic::models();
    all.extend(pendkit_models_ligo::models());
    all
}

/// The bundled model called `name`.
pub fn find_model(name: &str) -> Result<&'static dyn Model, Error> {
    models()
        .into_iter()
        .find(|m| m.name() == name)
        .ok_or_else(|| Error::UnknownModel {
            name: name.to_string(),
            known: models()
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// A case: a model with parameter and damping overrides.
#[derive(Clone)]
pub struct Case {
    /// Case name (the model name, or the case file's stem).
    pub name: String,
    /// What the case is for (from the case file).
    pub description: Option<String>,
    /// The model it refines.
    pub model: &'static dyn Model,
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

    /// Reads a case file (TOML; see [`files`]).
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
        let file = pendkit_files::parse_case(text).map_err(|e| match e {
            pendkit_files::FileError::Read { source, .. } => err(source.to_string()),
            pendkit_files::FileError::Parse { message } => err(message),
        })?;
        Ok(Case {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            description: file.description,
            model: find_model(&file.model).map_err(|e| err(e.to_string()))?,
            overrides: file.overrides,
        })
    }

    /// A bundled model name, or a path to a case file (anything ending in `.toml` or naming
    /// an existing file).
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
                message: "reading case files needs pendkit's `files` feature".into(),
            });
        }
        Case::model(spec)
    }

    /// Adds `NAME=EXPR` overrides (applied after the case's own); `damping.<tag>.<field>=EXPR`
    /// sets a damping field.
    pub fn with_sets(mut self, sets: &[String]) -> Result<Case, Error> {
        for s in sets {
            let (name, expr) = s
                .split_once('=')
                .ok_or_else(|| Error::SetSyntax(s.clone()))?;
            let (name, expr) = (name.trim(), expr.trim());
            match name
                .strip_prefix("damping.")
                .and_then(|rest| rest.split_once('.'))
            {
                Some((tag, field)) => {
                    let spec = self.overrides.damping.entry(tag.to_string()).or_default();
                    spec.set_field(field, expr)
                        .map_err(|m| Error::SetSyntax(format!("{s}: {m}")))?;
                }
                None => self
                    .overrides
                    .parameters
                    .push((name.to_string(), expr.to_string())),
            }
        }
        Ok(self)
    }

    /// Resolves the parameters and builds the numeric model.
    pub fn build(&self) -> Result<(System, Resolved), Error> {
        Ok(pendkit_model::build_with(self.model, &self.overrides)?)
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
        let defaults = pendkit_model::Defaults::of(self.model)?;
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
    /// Normal modes (possibly with unstable ones: check [`Modes::check_stable`]).
    pub modes: Modes,
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
/// (the stage's matrices by tag), `floats` (their elimination) and `modes`.
pub fn run_stage_with(
    system: System,
    stage: Stage,
    options: &RunOptions,
    mut times: Option<&mut PhaseTimes>,
) -> Result<StageResult, Error> {
    let assembled = assemble_with(&system, stage, &options.assembly, times.as_deref_mut())?;
    let model = timed(&mut times, "stage-model", 1, || {
        StageModel::new(&system, &assembled)
    });
    let modes = match options.modes {
        ModeSelection::Below(hz) if !(hz > 0.0 && hz.is_finite()) => {
            return Err(DynamicsError::BelowFrequency(hz).into());
        }
        ModeSelection::Below(hz) if model.sizes.0 > DENSE_MODES_LIMIT => {
            timed(&mut times, "modes", 1, || {
                model.modes_below(&system.damping, hz)
            })?
        }
        selection => {
            let reduced = timed(&mut times, "floats", 1, || {
                eliminate_floats(
                    &model.real_stiffness(&system.damping),
                    &assembled.layout,
                    &system,
                )
            })?;
            let mut modes = timed(&mut times, "modes", 1, || {
                normal_modes(&reduced.k_eff, &assembled.mass, &model.variables)
            })?;
            if let ModeSelection::Below(hz) = selection {
                modes.modes.retain(|m| m.hz < hz);
            }
            modes
        }
    };
    Ok(StageResult {
        system,
        assembled,
        model,
        modes,
    })
}

impl StageResult {
    /// A point on a body and a direction, written `<body>@x,y,z/dx,dy,dz` (m, body
    /// coordinates; direction in lab axes, normalised): the generalised-force vector over
    /// the variables of a unit force there, equal to the displacement-output vector of that
    /// point along that direction (the linearised geometry at equilibrium).
    fn point_vector(&self, spec: &str) -> Option<Result<DVector<f64>, Error>> {
        let (body, rest) = spec.split_once('@')?;
        Some((|| {
            let bad = || Error::Name {
                name: spec.to_string(),
                message: "expected <body>@x,y,z/dx,dy,dz".into(),
            };
            let (point, dir) = rest.split_once('/').ok_or_else(bad)?;
            let nums = |t: &str| -> Result<Vector3<f64>, Error> {
                let v: Vec<f64> = t
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad())?;
                if v.len() == 3 && v.iter().all(|x| x.is_finite()) {
                    Ok(Vector3::new(v[0], v[1], v[2]))
                } else {
                    Err(bad())
                }
            };
            let (p, d) = (nums(point)?, nums(dir)?);
            if d.norm() == 0.0 {
                return Err(bad());
            }
            let b = self.system.body(body).ok_or_else(|| Error::Name {
                name: spec.to_string(),
                message: format!("unknown body '{body}'"),
            })?;
            let jac = self.system.bodies[b]
                .frame
                .jacobian(&self.assembled.equilibrium.coords, &p);
            let d = d.normalize();
            Ok(DVector::from_iterator(
                self.assembled.layout.variables.len(),
                self.assembled
                    .layout
                    .variables
                    .iter()
                    .map(|&g| jac.position.column(g).dot(&d)),
            ))
        })())
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

    /// Parses an input: a parameter (support displacement, e.g. `x00`), `force:<variable>`
    /// or `force:<body>@x,y,z/dx,dy,dz`. Names of a scheme the model declares are accepted
    /// too (`GND_L`, `force:L3_P`).
    pub fn input(&self, name: &str) -> Result<Input, Error> {
        let name = &self.unalias(name);
        let m = &self.model;
        if let Some(target) = name.strip_prefix("force:") {
            if let Some(v) = self.point_vector(target) {
                return Ok(Input::Force(v?));
            }
            return match m.variables.iter().position(|v| v == target) {
                Some(k) => Ok(Input::Force(Self::unit(m.variables.len(), k))),
                None => Err(self.names_error(target, "a variable to push on", &m.variables)),
            };
        }
        match m.parameters.iter().position(|v| v == name) {
            Some(k) => Ok(Input::Displacement(Self::unit(m.parameters.len(), k))),
            None => Err(self.names_error(
                name,
                "a parameter to drive (or force:<variable>)",
                &m.parameters,
            )),
        }
    }

    /// Parses an output: a variable, `<body>@x,y,z/dx,dy,dz`, or `force:<parameter>` (the
    /// force on the support). Names of a scheme the model declares are accepted too
    /// (`L3_L`, `L3@0,0,0/1,0,0`).
    pub fn output(&self, name: &str) -> Result<Output, Error> {
        let name = &self.unalias(name);
        let m = &self.model;
        if let Some(target) = name.strip_prefix("force:") {
            return match m.parameters.iter().position(|v| v == target) {
                Some(k) => Ok(Output::SupportForce(Self::unit(m.parameters.len(), k))),
                None => Err(self.names_error(target, "a parameter", &m.parameters)),
            };
        }
        if let Some(v) = self.point_vector(name) {
            return Ok(Output::Displacement(v?));
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
        Ok(self
            .model
            .transfer_with(&self.system.damping, &i, &o, freqs, solver)?)
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
            Output::Displacement(v) => Ok(thermal_noise_with(
                &self.model,
                &self.system.damping,
                &v,
                self.system.temperature,
                freqs,
                options,
            )?),
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
    if repeat == 0 {
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

/// `n` log-spaced frequencies from `from` to `to` (Hz).
pub fn log_grid(from: f64, to: f64, n: usize) -> Result<Vec<f64>, Error> {
    if from.is_nan() || to.is_nan() || from <= 0.0 || to < from || n == 0 {
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
