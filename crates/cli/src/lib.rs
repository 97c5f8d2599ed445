//! pendkit's facade: the catalogue of bundled models, case files, and the whole pipeline
//! from a model or case to equilibrium and normal modes, for the command line and for
//! downstream tools that want one call.
//!
//! This crate names every bundled element and model crate so that the linker keeps their
//! `inventory` registrations (inventory issue #50); link against it, not the parts, to get
//! the full registry.

use std::path::{Path, PathBuf};

use pendkit_assembly::{Assembled, AssemblyError, EquilibriumOptions, assemble};
use pendkit_dynamics::{DynamicsError, Modes, eliminate_floats, normal_modes};
use pendkit_energy::{Stage, System};
use pendkit_model::{BuildError, Model};
use pendkit_params::Resolved;

pub use pendkit_assembly as assembly;
pub use pendkit_dynamics as dynamics;
pub use pendkit_energy as energy;
pub use pendkit_model as model;
pub use pendkit_params as params;

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
    #[error("--set '{0}': expected NAME=EXPR")]
    SetSyntax(String),
    /// Building the model failed.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// Equilibrium or assembly failed.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    /// Modes or eliminations failed.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
}

/// Every bundled model.
pub fn models() -> Vec<&'static dyn Model> {
    pendkit_models_basic::models()
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

/// A case: a model and parameter overrides (name, expression text), in application order.
#[derive(Clone)]
pub struct Case {
    /// Case name (the model name, or the case file's stem).
    pub name: String,
    /// The model it refines.
    pub model: &'static dyn Model,
    /// Overrides, applied in order.
    pub overrides: Vec<(String, String)>,
}

/// Parsed form of a case file (TOML): `model = "name"` and a `[parameters]` table whose
/// values are numbers or expression strings (including `scale(x)` and `increment(x)`).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    model: String,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    parameters: toml::Table,
}

impl Case {
    /// A bundled model with its defaults.
    pub fn model(name: &str) -> Result<Case, Error> {
        Ok(Case {
            name: name.to_string(),
            model: find_model(name)?,
            overrides: Vec::new(),
        })
    }

    /// Reads a case file.
    pub fn from_file(path: &Path) -> Result<Case, Error> {
        let err = |message: String| Error::Case {
            path: path.to_path_buf(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let file: CaseFile = toml::from_str(&text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start].lines().count().max(1));
            let at = line.map(|l| format!("line {l}: ")).unwrap_or_default();
            err(format!("{at}{}", e.message().trim()))
        })?;
        let _ = file.description;
        let mut overrides = Vec::new();
        for (name, value) in &file.parameters {
            let text = match value {
                toml::Value::String(s) => s.clone(),
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::Float(f) => format!("{f:e}"),
                other => {
                    return Err(err(format!(
                        "parameter '{name}': expected a number or an expression string, got {}",
                        other.type_str()
                    )));
                }
            };
            overrides.push((name.clone(), text));
        }
        Ok(Case {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            model: find_model(&file.model).map_err(|e| err(e.to_string()))?,
            overrides,
        })
    }

    /// A bundled model name, or a path to a case file (anything ending in `.toml` or naming
    /// an existing file).
    pub fn open(spec: &str) -> Result<Case, Error> {
        let path = Path::new(spec);
        if spec.ends_with(".toml") || path.is_file() {
            Case::from_file(path)
        } else {
            Case::model(spec)
        }
    }

    /// Adds `NAME=EXPR` overrides (applied after the case's own).
    pub fn with_sets(mut self, sets: &[String]) -> Result<Case, Error> {
        for s in sets {
            let (name, expr) = s
                .split_once('=')
                .ok_or_else(|| Error::SetSyntax(s.clone()))?;
            self.overrides
                .push((name.trim().to_string(), expr.trim().to_string()));
        }
        Ok(self)
    }

    /// Resolves the parameters and builds the numeric model.
    pub fn build(&self) -> Result<(System, Resolved), Error> {
        Ok(pendkit_model::build_with(self.model, &self.overrides)?)
    }
}

/// The result of running one stage of a model.
pub struct StageResult {
    /// The numeric model.
    pub system: System,
    /// Equilibrium and per-term matrices.
    pub assembled: Assembled,
    /// Normal modes (possibly with unstable ones: check [`Modes::check_stable`]).
    pub modes: Modes,
}

/// Equilibrium, stiffness, mass and modes of `system` at `stage`.
pub fn run_stage(system: System, stage: Stage) -> Result<StageResult, Error> {
    let assembled = assemble(&system, stage, &EquilibriumOptions::default())?;
    let reduced = eliminate_floats(&assembled.stiffness(), &assembled.layout, &system)?;
    let names: Vec<String> = assembled
        .layout
        .variables
        .iter()
        .map(|&i| system.coords[i].name.clone())
        .collect();
    let modes = normal_modes(&reduced.k_eff, &assembled.mass, &names)?;
    Ok(StageResult {
        system,
        assembled,
        modes,
    })
}
