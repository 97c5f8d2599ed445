//! Source files, positions in them, and the one-line errors that name file, line and field.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The text of one suspension file and where it came from.
#[derive(Debug)]
pub struct Source {
    /// How errors name the file: its path as given, or `models/ligo/quad.toml` for a
    /// bundled file.
    pub name: String,
    /// The file on disk, if it is one (bundled files are not): `extends` paths are relative
    /// to its folder.
    pub path: Option<PathBuf>,
    /// The file's text.
    pub text: String,
    /// Byte offset of the start of each line, found when a line is first asked for (only
    /// messages ask: a bundled model's run reads its files' texts for none).
    line_starts: OnceLock<Vec<usize>>,
}

impl Source {
    /// A source called `name` with `text`, read from `path` if it is a file.
    pub fn new(name: impl Into<String>, path: Option<&Path>, text: impl Into<String>) -> Arc<Self> {
        Arc::new(Source {
            name: name.into(),
            path: path.map(Path::to_path_buf),
            text: text.into(),
            line_starts: OnceLock::new(),
        })
    }

    /// The 1-based line of byte offset `offset`.
    pub fn line(&self, offset: usize) -> usize {
        let line_starts = self.line_starts.get_or_init(|| {
            std::iter::once(0)
                .chain(self.text.match_indices('\n').map(|(i, _)| i + 1))
                .collect()
        });
        line_starts.partition_point(|&start| start <= offset)
    }
}

/// A place in a source: the span of a key or value.
#[derive(Clone, Debug)]
pub struct Origin {
    /// The file.
    pub source: Arc<Source>,
    /// Byte range in it.
    pub span: Range<usize>,
}

impl Origin {
    /// The 1-based line where the span starts.
    pub fn line(&self) -> usize {
        self.source.line(self.span.start)
    }
}

/// Where a value of the description sits: its file and line, and its field path
/// (`stages.uim.wires.radius`).
#[derive(Clone, Debug)]
pub struct At {
    /// The file and span.
    pub origin: Origin,
    /// Dotted path of the field.
    pub path: String,
}

impl At {
    /// An error at this place.
    pub fn error(&self, message: impl Into<String>) -> FileError {
        FileError {
            file: self.origin.source.name.clone(),
            line: Some(self.origin.line()),
            field: self.path.clone(),
            message: message.into(),
        }
    }

    /// `file:line: field` (how every error about this value starts).
    pub fn label(&self) -> String {
        format!(
            "{}:{}: {}",
            self.origin.source.name,
            self.origin.line(),
            self.path
        )
    }

    /// The place of a field inside this one.
    pub fn child(&self, origin: Origin, key: &str) -> At {
        At {
            origin,
            path: join(&self.path, key),
        }
    }
}

/// `parent.key` (or `key` at the top).
pub fn join(parent: &str, key: &str) -> String {
    if parent.is_empty() {
        return key.to_string();
    }
    // Built by hand rather than with `format!`: every field read joins a path, and the
    // formatting machinery was a noticeable share of reading a bundled model.
    let mut path = String::with_capacity(parent.len() + 1 + key.len());
    path.push_str(parent);
    path.push('.');
    path.push_str(key);
    path
}

/// A problem in a suspension file: the file, the line, the field and what is wrong, printed
/// on one line as `file:line: field: message`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", self.render())]
pub struct FileError {
    /// The file (its name as given, or the bundled file's path).
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// Dotted path of the field (`bodies.top.mass`), empty when the whole file is meant.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl FileError {
    /// An error about a whole file (one that cannot be read, say).
    pub fn file(file: impl Into<String>, message: impl Into<String>) -> FileError {
        FileError {
            file: file.into(),
            line: None,
            field: String::new(),
            message: message.into(),
        }
    }

    fn render(&self) -> String {
        let mut out = self.file.clone();
        if let Some(line) = self.line {
            out += &format!(":{line}");
        }
        if !self.field.is_empty() {
            out += &format!(": {}", self.field);
        }
        // messages are single lines; a multi-line one from a parser is folded
        let message = self
            .message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        format!("{out}: {message}")
    }
}

/// A value with the place it came from.
#[derive(Clone, Debug)]
pub struct Located<T> {
    /// The value.
    pub value: T,
    /// Its place.
    pub at: At,
}
