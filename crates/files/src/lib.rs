//! pendkit's input files: reads case files (TOML) into the model name and the parameter
//! and damping overrides they apply, with one-line errors that name the line.
//!
//! A case file names its model and overrides some of its defaults:
//!
//! ```
//! let case = pendkit_files::parse_case(r#"
//! model = "quad"
//! description = "heavier test mass, lossier fibres"
//! [parameters]
//! m3 = 50                      # a value, an expression, "scale(1.2)" or "increment(0.5)"
//! [damping.fibre_bending]
//! structural = "10*silica_phi" # real, structural, viscous, imag, thermoelastic = [delta, tau]
//! "#)?;
//! assert_eq!(case.model, "quad");
//! assert_eq!(case.overrides.parameters, vec![("m3".to_string(), "50".to_string())]);
//! # Ok::<(), pendkit_files::FileError>(())
//! ```
//!
//! This crate is where pendkit's file formats live, so that the library proper needs no
//! TOML parser: the `pendkit` facade uses it behind its `files` feature.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pendkit_model::{DampingSpec, Overrides};

/// A parsed case file.
#[derive(Clone, Debug, Default)]
pub struct CaseFile {
    /// The model the case refines: a bundled model name, or a suspension file's path
    /// (ending in `.toml`, relative to the case file's folder).
    pub model: String,
    /// What the case is for.
    pub description: Option<String>,
    /// Parameter and damping overrides, in file order.
    pub overrides: Overrides,
}

/// What can go wrong reading a case file; each message is one line.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file cannot be read.
    #[error("case file {}: {source}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The text is not a valid case file.
    #[error("{message}")]
    Parse {
        /// What is wrong, starting with `line N:` where the parser knows the line.
        message: String,
    },
}

/// Form of a case file: `model = "name"`, a `[parameters]` table whose values are numbers
/// or expression strings (including `scale(x)` and `increment(x)`), and `[damping.<tag>]`
/// tables with `real`, `structural`, `viscous`, `imag` (expressions, `f` in Hz allowed in
/// `real` and `imag`) and `thermoelastic = [delta, tau]`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseToml {
    model: String,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    parameters: toml::Table,
    #[serde(default)]
    damping: BTreeMap<String, DampingToml>,
}

/// A `[damping.<tag>]` table of a case file.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct DampingToml {
    real: Option<toml::Value>,
    structural: Option<toml::Value>,
    viscous: Option<toml::Value>,
    imag: Option<toml::Value>,
    thermoelastic: Option<[toml::Value; 2]>,
}

/// A TOML number or string as expression text.
fn expression_text(what: &str, value: &toml::Value) -> Result<String, FileError> {
    match value {
        toml::Value::String(s) => Ok(s.clone()),
        toml::Value::Integer(i) => Ok(i.to_string()),
        toml::Value::Float(f) => Ok(format!("{f:e}")),
        other => Err(FileError::Parse {
            message: format!(
                "{what}: expected a number or an expression string, got {}",
                other.type_str()
            ),
        }),
    }
}

/// Parses the text of a case file.
pub fn parse_case(text: &str) -> Result<CaseFile, FileError> {
    let file: CaseToml = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text.get(..s.start).unwrap_or(text).lines().count().max(1));
        let at = line.map(|l| format!("line {l}: ")).unwrap_or_default();
        FileError::Parse {
            message: format!("{at}{}", e.message().trim()),
        }
    })?;
    let mut overrides = Overrides::default();
    for (name, value) in &file.parameters {
        let text = expression_text(&format!("parameter '{name}'"), value)?;
        overrides.parameters.push((name.clone(), text));
    }
    for (tag, d) in &file.damping {
        let field = |name: &str, v: &Option<toml::Value>| {
            v.as_ref()
                .map(|v| expression_text(&format!("damping.{tag}.{name}"), v))
                .transpose()
        };
        let thermoelastic = match &d.thermoelastic {
            None => None,
            Some([delta, tau]) => {
                let what = format!("damping.{tag}.thermoelastic");
                Some((expression_text(&what, delta)?, expression_text(&what, tau)?))
            }
        };
        let spec = DampingSpec {
            real: field("real", &d.real)?,
            structural: field("structural", &d.structural)?,
            viscous: field("viscous", &d.viscous)?,
            imag: field("imag", &d.imag)?,
            thermoelastic,
        };
        overrides.damping.insert(tag.clone(), spec);
    }
    Ok(CaseFile {
        model: file.model,
        description: file.description,
        overrides,
    })
}

/// Whether `text` is a case file (a TOML table with a top-level `model`) rather than a
/// suspension file (which describes the model itself and has no `model` key). Text that is
/// not TOML is not a case file: the suspension reader then reports where it breaks.
pub fn is_case_file(text: &str) -> bool {
    text.parse::<toml::Table>()
        .is_ok_and(|table| table.contains_key("model"))
}

/// Reads and parses a case file.
pub fn read_case(path: &Path) -> Result<CaseFile, FileError> {
    let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_case(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_line_and_the_field() {
        let e = parse_case("model = \"pendulum\"\n[parameters\nm1 = 3\n").unwrap_err();
        assert!(e.to_string().starts_with("line 2: "), "{e}");
        let e = parse_case("model = \"pendulum\"\n[parameters]\nm1 = true\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "parameter 'm1': expected a number or an expression string, got boolean"
        );
        let e = parse_case("model = \"toy\"\nextra = 1\n").unwrap_err();
        assert!(e.to_string().contains("unknown field"), "{e}");
        assert!(!e.to_string().contains('\n'), "{e}");
    }

    #[test]
    fn case_files_name_a_model_suspension_files_do_not() {
        assert!(is_case_file("model = \"quad\"\n[parameters]\nm3 = 50\n"));
        assert!(is_case_file("model = \"my-susp.toml\"\n"));
        assert!(!is_case_file("[bodies.top]\nmass = 1\n"));
        assert!(!is_case_file("model = \n"));
    }

    #[test]
    fn damping_fields_become_expression_texts() {
        let c = parse_case(
            "model = \"quad\"\n[damping.w2_bending]\nstructural = 0\nthermoelastic = [\"1e-3\", 0.5]\n",
        )
        .unwrap();
        let d = &c.overrides.damping["w2_bending"];
        assert_eq!(d.structural.as_deref(), Some("0"));
        assert_eq!(
            d.thermoelastic,
            Some(("1e-3".to_string(), "5e-1".to_string()))
        );
        assert_eq!(d.real, None);
    }
}
