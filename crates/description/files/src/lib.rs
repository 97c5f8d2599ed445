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
//! structural = "10*silica_phi" # the fields of pendkit_model::schema::DAMPING_FIELDS
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
use toml::Spanned;
use toml::de::{DeTable, DeValue};

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
        /// Why it was not read (missing, not a regular file, past the size limit).
        source: pendkit_limits::ReadError,
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
/// tables of the fields of [`pendkit_model::schema::DAMPING_FIELDS`] (expressions; `f` in
/// Hz allowed in `real` and `imag`; `thermoelastic` the pair `[delta, tau]` or the table
/// `{ delta, tau }`, also written as dotted keys `thermoelastic.tau = ...`). Serde checks
/// the form; the values are then read from the file's own parse ([`DeTable`]), which keeps
/// every value's span, so that a number is read from the literal the file writes and every
/// error names its line.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseToml {
    model: String,
    #[serde(default)]
    description: Option<String>,
    #[serde(default, rename = "parameters")]
    _parameters: BTreeMap<String, toml::Value>,
    #[serde(default, rename = "damping")]
    _damping: BTreeMap<String, toml::Table>,
}

/// The 1-based line of byte offset `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.get(..offset).unwrap_or(text).lines().count().max(1)
}

/// A TOML number or string of the case file `text` as expression text; `what` names the
/// field. A float is read from the literal the file writes (TOML parsers round it to an
/// `f64` first, so `1e-400` would arrive as 0): one that an `f64` cannot hold is refused here.
fn expression_text(text: &str, what: &str, value: &Spanned<DeValue>) -> Result<String, FileError> {
    let error = |message: String| FileError::Parse {
        message: format!(
            "line {}: {what}: {message}",
            line_of(text, value.span().start)
        ),
    };
    match value.get_ref() {
        DeValue::String(s) => Ok(s.to_string()),
        DeValue::Integer(i) => i64::from_str_radix(&i.as_str().replace('_', ""), i.radix())
            .map(|i| i.to_string())
            .map_err(|e| error(format!("integer {}: {e}", i.as_str()))),
        // the literal as written (checked by `check_float_literals`): the parsed f64 of
        // `0e-999` or `1.5e-7` prints differently, and that of `nan` means nothing
        DeValue::Float(f) => {
            let literal = f.as_str().replace('_', "");
            pendkit_expr::number_literal(&literal).map_err(|e| error(e.to_string()))?;
            Ok(literal.trim_start_matches('+').to_string())
        }
        other => Err(error(format!(
            "expected a number or an expression string, got {}",
            other.type_str()
        ))),
    }
}

/// Refuses, naming its line and field, the first float literal of the TOML `text` that an
/// `f64` cannot hold: the TOML parser reads `1e-400` as 0 and refuses `1e400` without
/// naming the field, so the literals are checked as written, before the values are read.
fn check_float_literals(text: &str, root: &DeTable) -> Result<(), FileError> {
    fn walk(text: &str, path: &str, value: &Spanned<DeValue>) -> Result<(), FileError> {
        match value.get_ref() {
            DeValue::Float(f) => {
                pendkit_expr::number_literal(&f.as_str().replace('_', "")).map_err(|e| {
                    FileError::Parse {
                        message: format!("line {}: {path}: {e}", line_of(text, value.span().start)),
                    }
                })?;
            }
            DeValue::Array(items) => {
                for item in items.iter() {
                    walk(text, path, item)?;
                }
            }
            DeValue::Table(table) => walk_table(text, path, table)?,
            _ => {}
        }
        Ok(())
    }
    fn walk_table(text: &str, path: &str, table: &DeTable) -> Result<(), FileError> {
        for (key, value) in table.iter() {
            let key: &str = key.get_ref();
            let path = if path.is_empty() {
                key.to_string()
            } else {
                format!("{path}.{key}")
            };
            walk(text, &path, value)?;
        }
        Ok(())
    }
    walk_table(text, "", root)
}

/// Parses the text of a case file.
pub fn parse_case(text: &str) -> Result<CaseFile, FileError> {
    // one parse keeping every value's span (a text that is not TOML is reported by serde
    // below, with its line)
    let root = DeTable::parse(text).ok();
    if let Some(root) = &root {
        check_float_literals(text, root.get_ref())?;
    }
    let file: CaseToml = toml::from_str(text).map_err(|e| {
        let at = e
            .span()
            .map(|s| format!("line {}: ", line_of(text, s.start)))
            .unwrap_or_default();
        FileError::Parse {
            message: format!("{at}{}", e.message().trim()),
        }
    })?;
    // serde accepted the form, so the text is TOML and `root` was read
    let Some(root) = root else {
        return Err(FileError::Parse {
            message: "not a TOML document".into(),
        });
    };
    let section = |key: &str| -> Vec<(&str, &Spanned<DeValue>)> {
        let mut entries: Vec<_> = match root.get_ref().get(key).map(Spanned::get_ref) {
            Some(DeValue::Table(table)) => table
                .iter()
                .map(|(name, value)| (name.get_ref().as_ref(), value))
                .collect(),
            _ => Vec::new(),
        };
        // in file order
        entries.sort_by_key(|(_, value)| value.span().start);
        entries
    };
    let mut overrides = Overrides::default();
    for (name, value) in section("parameters") {
        let expression = expression_text(text, &format!("parameters.{name}"), value)?;
        overrides.parameters.push((name.to_string(), expression));
    }
    for (tag, table) in section("damping") {
        if let DeValue::Table(table) = table.get_ref() {
            overrides
                .damping
                .insert(tag.to_string(), damping_spec(text, tag, table)?);
        }
    }
    Ok(CaseFile {
        model: file.model,
        description: file.description,
        overrides,
    })
}

/// The damping fields of the case file `text`'s table `[damping.<tag>]`, each set through
/// [`DampingSpec::set_field`] (the one list of fields and their names).
fn damping_spec(text: &str, tag: &str, table: &DeTable) -> Result<DampingSpec, FileError> {
    let mut spec = DampingSpec::default();
    let mut set = |name: &str, value: &Spanned<DeValue>| {
        let expression = expression_text(text, &format!("damping.{tag}.{name}"), value)?;
        spec.set_field(name, &expression)
            .map_err(|message| FileError::Parse {
                message: format!(
                    "line {}: damping.{tag}: {message}",
                    line_of(text, value.span().start)
                ),
            })
    };
    for (name, value) in table {
        let name: &str = name.get_ref();
        match (name, value.get_ref()) {
            ("thermoelastic", DeValue::Array(pair)) => match &pair[..] {
                [delta, tau] => {
                    set("thermoelastic.delta", delta)?;
                    set("thermoelastic.tau", tau)?;
                }
                _ => {
                    return Err(FileError::Parse {
                        message: format!(
                            "line {}: damping.{tag}.thermoelastic: expected [delta, tau], got {} entries",
                            line_of(text, value.span().start),
                            pair.len()
                        ),
                    });
                }
            },
            ("thermoelastic", DeValue::Table(halves)) => {
                for (half, entry) in halves {
                    set(&format!("thermoelastic.{}", half.get_ref()), entry)?;
                }
            }
            _ => set(name, value)?,
        }
    }
    Ok(spec)
}

/// Whether `text` is a case file (a TOML table with a top-level `model`) rather than a
/// suspension file (which describes the model itself and has no `model` key). Text that is
/// not TOML is not a case file: the suspension reader then reports where it breaks.
pub fn is_case_file(text: &str) -> bool {
    // parsed without converting values, so that a case file whose numbers an f64 cannot
    // hold (`1e400`) is still read as one, and refused as one
    toml::de::DeTable::parse(text).is_ok_and(|table| table.get_ref().contains_key("model"))
}

/// Reads and parses a case file (read only if it is a regular file within
/// [`pendkit_limits::FILE_BYTES`]).
pub fn read_case(path: &Path) -> Result<CaseFile, FileError> {
    let text = pendkit_limits::read_text(path).map_err(|source| FileError::Read {
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
            "line 3: parameters.m1: expected a number or an expression string, got boolean"
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
        assert!(is_case_file("model = \"quad\"\n[parameters]\nm3 = 1e400\n"));
    }

    #[test]
    fn damping_fields_become_expression_texts() {
        let c = parse_case(
            "model = \"quad\"\n[damping.w2_bending]\nstructural = 0\nthermoelastic = [\"1e-3\", 0.5]\n",
        )
        .unwrap();
        let d = &c.overrides.damping["w2_bending"];
        assert_eq!(d.structural.as_deref(), Some("0"));
        assert_eq!(d.thermoelastic_delta.as_deref(), Some("1e-3"));
        assert_eq!(d.thermoelastic_tau.as_deref(), Some("0.5"));
        assert_eq!(d.real, None);
    }

    #[test]
    fn every_damping_field_of_the_schema_is_read_in_each_form() {
        // the pair, the table and the dotted keys are one field each; `temperature` too (a
        // case file once refused it though `fit --out` wrote it)
        for (te, delta, tau) in [
            ("thermoelastic = [1e-3, \"0.5\"]", Some("1e-3"), Some("0.5")),
            ("thermoelastic = { tau = 0.5 }", None, Some("0.5")),
            ("thermoelastic.delta = \"d\"", Some("d"), None),
        ] {
            let c = parse_case(&format!(
                "model = \"quad\"\n[damping.t]\n{te}\ntemperature = 100\nviscous = \"1e-9\"\n"
            ))
            .unwrap();
            let d = &c.overrides.damping["t"];
            assert_eq!(d.thermoelastic_delta.as_deref(), delta, "{te}");
            assert_eq!(d.thermoelastic_tau.as_deref(), tau, "{te}");
            assert_eq!(d.temperature.as_deref(), Some("100"));
            assert_eq!(d.viscous.as_deref(), Some("1e-9"));
        }
        let e = parse_case("model = \"quad\"\n[damping.t]\nthermoelastic = { tua = 1 }\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 3: damping.t: unknown damping field 'thermoelastic.tua'"),
            "{e}"
        );
    }

    #[test]
    fn number_literals_an_f64_cannot_hold_are_refused_with_line_and_field() {
        // the TOML parser refuses 1e400 without naming the field, rounds 1e-400 to 0 and
        // takes inf and nan: the literal is checked instead
        for (value, problem) in [
            ("1e400", "too large"),
            ("1e-400", "too small"),
            ("-2.5e-320", "too small"),
            ("inf", "not a finite number"),
            ("nan", "not a finite number"),
        ] {
            let e = parse_case(&format!(
                "model = \"quad\"\n[parameters]\nm1 = 2\nm3 = {value}\n"
            ))
            .unwrap_err()
            .to_string();
            assert!(e.starts_with("line 4: parameters.m3: "), "{e}");
            assert!(e.contains(problem), "{e}");
            let e = parse_case(&format!(
                "model = \"quad\"\n[damping.w]\nstructural = 1\nthermoelastic = [1e-3,\n {value}]\n"
            ))
            .unwrap_err()
            .to_string();
            assert!(e.starts_with("line 5: damping.w.thermoelastic: "), "{e}");
            assert!(e.contains(problem), "{e}");
        }
        // zero written with a huge exponent is zero; underscores and '+' are TOML's own
        let c = parse_case("model = \"quad\"\n[parameters]\nb = 0e-999\na = +1_000.5\n").unwrap();
        assert_eq!(
            c.overrides.parameters,
            [
                ("b".to_string(), "0e-999".to_string()),
                ("a".to_string(), "1000.5".to_string())
            ]
        );
    }
}
