//! Writes named real matrices and lists of names to MATLAB .mat (level 5), NumPy .npz and
//! JSON files, for state-space models other tools load.
//!
//! Every [`Matrix`] and every [`Names`] list becomes one variable of the file, under its own
//! name:
//!
//! | input      | `.mat` (MATLAB, `scipy.io.loadmat`)    | `.npz` (`numpy.load`)             | JSON                |
//! |------------|----------------------------------------|-----------------------------------|---------------------|
//! | [`Matrix`] | `rows x cols` double                   | `<f8` array of shape (rows, cols) | array of row arrays |
//! | [`Names`]  | `n x 1` cell array of char row vectors | `<U{maxlen}` array of shape (n,)  | array of strings    |
//!
//! Variable names must be valid MATLAB names (a letter first, then letters, digits or
//! underscores, at most 63 characters, not a keyword) and distinct; matrix data is row-major
//! with `rows * cols` values, all finite (NaN and infinity are never written). [`validate`]
//! checks all three, and every writer calls it first. Units are the caller's business.
//!
//! Files are written to a temporary file in the same directory and renamed into place
//! ([`write_whole`], which pendkit's other outputs use too), so a failed write never leaves
//! a truncated file under the name asked for; an existing file is refused unless
//! [`WriteOptions::overwrite`] says otherwise.
//! Units and provenance travel as more variables ([`Metadata`], [`write_with_metadata`]).

use std::collections::HashSet;
use std::io::{self, Seek, Write};
use std::path::{Path, PathBuf};

use serde_json::Value;

mod file;
mod mat;
mod npz;

pub use file::{Existing, FileError, remove_temporaries, write_bytes_whole, write_whole};

/// A named real matrix, `rows x cols`, its `data` in row-major order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Matrix<'a> {
    /// Variable name in the file.
    pub name: &'a str,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// Row-major values, `rows * cols` of them.
    pub data: &'a [f64],
}

/// A named list of strings, e.g. the state, input or output names of a state-space model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Names<'a> {
    /// Variable name in the file.
    pub name: &'a str,
    /// The strings, in order.
    pub items: &'a [String],
}

/// File format, chosen by the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// MATLAB level-5 MAT-file (`.mat`).
    Mat,
    /// NumPy zip of `.npy` arrays (`.npz`).
    Npz,
    /// JSON object (`.json`).
    Json,
}

impl Format {
    /// The format for `path`'s extension (`.mat`, `.npz` or `.json`, any letter case).
    pub fn from_path(path: &Path) -> Result<Format, ExportError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("mat") => Ok(Format::Mat),
            Some("npz") => Ok(Format::Npz),
            Some("json") => Ok(Format::Json),
            _ => Err(ExportError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Everything that can go wrong while exporting.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The path has none of the known extensions.
    #[error(
        "cannot tell the export format of '{}': use a .mat, .npz or .json extension",
        .path.display()
    )]
    UnknownFormat {
        /// The path given.
        path: PathBuf,
    },
    /// Creating or writing the file failed.
    #[error("cannot write '{}': {source}", .path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// Writing to a caller-supplied writer failed (see [`write_mat`], [`write_npz`]).
    #[error("export write failed: {0}")]
    Write(#[from] io::Error),
    /// A matrix whose data length is not `rows * cols`.
    #[error("matrix '{name}' is declared {rows}x{cols} but has {len} values")]
    DataLength {
        /// The matrix.
        name: String,
        /// Declared rows.
        rows: usize,
        /// Declared columns.
        cols: usize,
        /// Values given.
        len: usize,
    },
    /// A variable name MATLAB would not accept.
    #[error(
        "'{name}' is not a valid variable name: use a letter, then letters, digits or underscores, at most 63 characters, not a MATLAB keyword"
    )]
    InvalidName {
        /// The name given.
        name: String,
    },
    /// Two variables with the same name.
    #[error("variable '{name}' is given more than once")]
    DuplicateName {
        /// The repeated name.
        name: String,
    },
    /// A variable too large for the 32-bit sizes of a level-5 MAT-file.
    #[error("variable '{name}' is too large for a level-5 MAT-file (4 GiB per variable)")]
    TooLarge {
        /// The variable.
        name: String,
    },
    /// NaN or infinity, which is never written.
    #[error(
        "matrix '{name}' has a non-finite value (NaN or infinity) at row {row}, column {col}: nothing was written"
    )]
    NonFinite {
        /// The matrix.
        name: String,
        /// Row, counted from 1.
        row: usize,
        /// Column, counted from 1.
        col: usize,
    },
    /// The file exists and overwriting was not asked for.
    #[error("'{}' exists: not overwritten (use --force to replace it)", .path.display())]
    Exists {
        /// The file.
        path: PathBuf,
    },
}

/// How [`write_with`] writes a file.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriteOptions {
    /// Replace an existing file (default: refuse it).
    pub overwrite: bool,
}

/// MATLAB's reserved words, which `isvarname` rejects.
const MATLAB_KEYWORDS: [&str; 20] = [
    "break",
    "case",
    "catch",
    "classdef",
    "continue",
    "else",
    "elseif",
    "end",
    "for",
    "function",
    "global",
    "if",
    "otherwise",
    "parfor",
    "persistent",
    "return",
    "spmd",
    "switch",
    "try",
    "while",
];

/// Whether `name` is a valid MATLAB variable name (and so also a safe `.npz` entry name).
fn is_valid_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && name.len() <= 63
        && !MATLAB_KEYWORDS.contains(&name)
}

/// Checks variable names (valid, distinct), matrix data lengths and that every value is
/// finite.
pub fn validate(matrices: &[Matrix], names: &[Names]) -> Result<(), ExportError> {
    let mut seen = HashSet::new();
    let all_names = matrices
        .iter()
        .map(|m| m.name)
        .chain(names.iter().map(|n| n.name));
    for name in all_names {
        if !is_valid_name(name) {
            return Err(ExportError::InvalidName { name: name.into() });
        }
        if !seen.insert(name) {
            return Err(ExportError::DuplicateName { name: name.into() });
        }
    }
    for m in matrices {
        if m.rows.checked_mul(m.cols) != Some(m.data.len()) {
            return Err(ExportError::DataLength {
                name: m.name.into(),
                rows: m.rows,
                cols: m.cols,
                len: m.data.len(),
            });
        }
    }
    check_finite(matrices)
}

/// Writes the variables to `path`, in the format its extension names ([`Format::from_path`]),
/// refusing to replace an existing file: [`write_with`] with the default options.
pub fn write(path: &Path, matrices: &[Matrix], names: &[Names]) -> Result<(), ExportError> {
    write_with(path, matrices, names, &WriteOptions::default())
}

/// Writes the variables to `path`, in the format its extension names.
///
/// Input is validated before anything is created (names, lengths, finite values). The file
/// is written whole or not at all ([`write_whole`]), so `path` holds either the whole new
/// file or what it held before. Without `options.overwrite` an existing `path` is refused
/// ([`ExportError::Exists`]).
pub fn write_with(
    path: &Path,
    matrices: &[Matrix],
    names: &[Names],
    options: &WriteOptions,
) -> Result<(), ExportError> {
    let format = Format::from_path(path)?;
    validate(matrices, names)?;
    let existing = if options.overwrite {
        Existing::Replace
    } else {
        Existing::Refuse
    };
    write_whole(path, existing, |w| {
        let result = match format {
            Format::Mat => mat::write(&mut *w, matrices, names),
            Format::Npz => npz::write(&mut *w, matrices, names),
            Format::Json => serde_json::to_writer_pretty(&mut *w, &to_json(matrices, names))
                .map_err(io::Error::from)
                .and_then(|()| w.write_all(b"\n"))
                .map_err(ExportError::from),
        };
        // the writers know no file name: the error names the file asked for
        result.map_err(|e| match e {
            ExportError::Write(source) => ExportError::Io {
                path: path.to_path_buf(),
                source,
            },
            other => other,
        })
    })
}

impl From<FileError> for ExportError {
    fn from(e: FileError) -> Self {
        match e {
            FileError::Io { path, source } => ExportError::Io { path, source },
            FileError::Exists { path } => ExportError::Exists { path },
        }
    }
}

/// Units and provenance stored beside the matrices of an export, as more variables of the
/// same file (so every format carries them and every loader reads them as it reads the
/// rest): lists of strings (e.g. `state_units`, `model`, `pendkit_version`) and columns of
/// numbers (e.g. `parameter_values`). Variable names follow the rules of [`validate`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Metadata {
    /// Lists of strings, by variable name.
    pub texts: Vec<(String, Vec<String>)>,
    /// Columns of numbers, by variable name.
    pub numbers: Vec<(String, Vec<f64>)>,
}

impl Metadata {
    /// An empty set.
    pub fn new() -> Self {
        Metadata::default()
    }

    /// Adds a list of strings (a one-item list for a single value such as a version).
    pub fn text(&mut self, name: &str, items: Vec<String>) -> &mut Self {
        self.texts.push((name.to_string(), items));
        self
    }

    /// Adds a column of numbers (an `n x 1` matrix).
    pub fn numbers(&mut self, name: &str, values: Vec<f64>) -> &mut Self {
        self.numbers.push((name.to_string(), values));
        self
    }

    /// The string lists as [`Names`] variables.
    pub fn names(&self) -> Vec<Names<'_>> {
        self.texts
            .iter()
            .map(|(name, items)| Names { name, items })
            .collect()
    }

    /// The number columns as [`Matrix`] variables.
    pub fn matrices(&self) -> Vec<Matrix<'_>> {
        self.numbers
            .iter()
            .map(|(name, data)| Matrix {
                name,
                rows: data.len(),
                cols: 1,
                data,
            })
            .collect()
    }
}

/// [`write_with`] with `metadata`'s variables after the others.
pub fn write_with_metadata(
    path: &Path,
    matrices: &[Matrix],
    names: &[Names],
    metadata: &Metadata,
    options: &WriteOptions,
) -> Result<(), ExportError> {
    let matrices: Vec<Matrix> = matrices
        .iter()
        .copied()
        .chain(metadata.matrices())
        .collect();
    let names: Vec<Names> = names.iter().copied().chain(metadata.names()).collect();
    write_with(path, &matrices, &names, options)
}

/// Writes a level-5 MAT-file: a 128-byte header, then one variable per matrix and name list.
pub fn write_mat<W: Write>(w: W, matrices: &[Matrix], names: &[Names]) -> Result<(), ExportError> {
    validate(matrices, names)?;
    mat::write(w, matrices, names)
}

/// Writes an `.npz` archive: one stored (uncompressed) `<name>.npy` entry per variable.
pub fn write_npz<W: Write + Seek>(
    w: W,
    matrices: &[Matrix],
    names: &[Names],
) -> Result<(), ExportError> {
    validate(matrices, names)?;
    npz::write(w, matrices, names)
}

/// The variables as one JSON object: each matrix an array of row arrays, each name list an
/// array of strings, e.g. `{"A": [[0.0, 1.0], [-4.0, 0.0]], "states": ["x", "v"]}`.
///
/// Keys come out sorted by name. Non-finite values become `null` (as in JavaScript), and rows
/// past the end of a too-short `data` come out empty; [`write()`] rejects both instead.
pub fn to_json(matrices: &[Matrix], names: &[Names]) -> Value {
    let mut object = serde_json::Map::new();
    for m in matrices {
        let rows = (0..m.rows)
            .map(|r| {
                // checked: a hand-made `rows`/`cols` must not overflow the row's bounds
                let row = r
                    .checked_mul(m.cols)
                    .and_then(|start| m.data.get(start..start.checked_add(m.cols)?))
                    .unwrap_or_default();
                Value::from(row.to_vec())
            })
            .collect();
        object.insert(m.name.to_string(), Value::Array(rows));
    }
    for n in names {
        object.insert(n.name.to_string(), Value::from(n.items.to_vec()));
    }
    Value::Object(object)
}

fn check_finite(matrices: &[Matrix]) -> Result<(), ExportError> {
    for m in matrices {
        if let Some(i) = m.data.iter().position(|v| !v.is_finite()) {
            return Err(ExportError::NonFinite {
                name: m.name.into(),
                row: i / m.cols + 1,
                col: i % m.cols + 1,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(items: &[&str]) -> Vec<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/ss.mat")).unwrap(),
            Format::Mat
        );
        assert_eq!(Format::from_path(Path::new("ss.NPZ")).unwrap(), Format::Npz);
        assert_eq!(
            Format::from_path(Path::new("ss.json")).unwrap(),
            Format::Json
        );
        for bad in ["ss.txt", "ss", "mat"] {
            let msg = Format::from_path(Path::new(bad)).unwrap_err().to_string();
            assert!(
                msg.contains(bad) && msg.contains(".mat, .npz or .json"),
                "{msg}"
            );
            assert!(!msg.contains('\n'));
        }
    }

    #[test]
    fn names_are_checked() {
        for good in ["A", "x1", "state_names", &"a".repeat(63)] {
            assert!(is_valid_name(good), "{good}");
        }
        for bad in ["", "1x", "_x", "x-y", "x y", "é", "end", &"a".repeat(64)] {
            assert!(!is_valid_name(bad), "{bad}");
            let m = Matrix {
                name: bad,
                rows: 0,
                cols: 0,
                data: &[],
            };
            let err = validate(&[m], &[]).unwrap_err();
            assert!(matches!(err, ExportError::InvalidName { .. }));
            assert!(err.to_string().contains(&format!("'{bad}'")), "{err}");
        }
    }

    #[test]
    fn duplicates_and_lengths_are_checked() {
        let a = Matrix {
            name: "A",
            rows: 1,
            cols: 2,
            data: &[1.0, 2.0],
        };
        let list = strings(&["x"]);
        let dup = Names {
            name: "A",
            items: &list,
        };
        let err = write_mat(Vec::new(), &[a], &[dup]).unwrap_err();
        assert_eq!(err.to_string(), "variable 'A' is given more than once");

        let short = Matrix {
            name: "B",
            rows: 2,
            cols: 2,
            data: &[1.0, 2.0, 3.0],
        };
        let err = write_mat(Vec::new(), &[short], &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "matrix 'B' is declared 2x2 but has 3 values"
        );
        let huge = Matrix {
            name: "C",
            rows: usize::MAX,
            cols: 2,
            data: &[],
        };
        assert!(matches!(
            validate(&[huge], &[]),
            Err(ExportError::DataLength { .. })
        ));
    }

    #[test]
    fn json_shape() {
        let a = Matrix {
            name: "A",
            rows: 2,
            cols: 3,
            data: &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        };
        let b = Matrix {
            name: "B",
            rows: 3,
            cols: 1,
            data: &[7.0, 8.0, 9.0],
        };
        let e = Matrix {
            name: "E",
            rows: 0,
            cols: 0,
            data: &[],
        };
        let z = Matrix {
            name: "Z",
            rows: 2,
            cols: 0,
            data: &[],
        };
        let states = strings(&["x1", "φ"]);
        let none: Vec<String> = Vec::new();
        let names = [
            Names {
                name: "states",
                items: &states,
            },
            Names {
                name: "inputs",
                items: &none,
            },
        ];
        let json = to_json(&[a, b, e, z], &names);
        let expected = serde_json::json!({
            "A": [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
            "B": [[7.0], [8.0], [9.0]],
            "E": [],
            "Z": [[], []],
            "states": ["x1", "φ"],
            "inputs": [],
        });
        assert_eq!(json, expected);
    }

    #[test]
    fn json_refuses_non_finite_values() {
        let dir = std::env::temp_dir().join(format!("pendkit-export-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("nan.json");
        let a = Matrix {
            name: "A",
            rows: 2,
            cols: 2,
            data: &[1.0, 2.0, 3.0, f64::NAN],
        };
        let err = write(&path, &[a], &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "matrix 'A' has a non-finite value (NaN or infinity) at row 2, column 2: nothing was written"
        );
        assert!(!path.exists(), "invalid input must not create the file");
        assert_eq!(to_json(&[a], &[])["A"][1][1], Value::Null);

        let ok = Matrix {
            name: "A",
            rows: 1,
            cols: 2,
            data: &[0.5, -2.0],
        };
        write(&path, &[ok], &[]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let back: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back, serde_json::json!({"A": [[0.5, -2.0]]}));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn io_errors_name_the_path() {
        let path = Path::new("/nonexistent-pendkit-dir/ss.mat");
        let err = write(path, &[], &[]).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, ExportError::Io { .. }));
        assert!(
            msg.starts_with("cannot write '/nonexistent-pendkit-dir/ss.mat': "),
            "{msg}"
        );
    }
}
