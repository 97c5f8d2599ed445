//! The command line's errors: the library's, the figures', and its own usage errors, each
//! printed as one line after `error: `.

use std::path::PathBuf;

use pendkit_plot::PlotError;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The calculation failed.
    #[error(transparent)]
    Pendkit(#[from] pendkit::Error),
    /// A figure could not be drawn or written.
    #[error("--plot: {0}")]
    Plot(#[from] PlotError),
    /// Arguments that do not fit together, or a value out of range.
    #[error("{0}")]
    Usage(String),
    /// A file could not be read.
    #[error("cannot read '{}': {source}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write '{}': {source}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

impl CliError {
    /// A usage error from anything printable.
    pub fn usage(message: impl Into<String>) -> Self {
        CliError::Usage(message.into())
    }
}
