//! The command line's errors: the library's, the figures', and its own usage errors, each
//! printed as one line after `error: `.

use std::path::PathBuf;

use pendkit_plot::PlotError;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The calculation failed (the library's message, with the overrides named as the
    /// `--set` arguments that gave them).
    #[error("{}", in_flag_terms(.0))]
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
    /// An input file was not read: missing, not a regular file, or past the size limit
    /// ([`pendkit_limits::read_text`]).
    #[error("cannot read '{}': {source}", .path.display())]
    Input {
        /// The file.
        path: PathBuf,
        /// Why it was not read.
        source: pendkit_limits::ReadError,
    },
    /// A limit of [`pendkit_limits`] passed, or its variable set wrongly: `what` names the
    /// option or file at fault.
    #[error("{what}: {source}")]
    Limit {
        /// The option or file at fault (`--vary`, `--freqs-file grid.txt`).
        what: String,
        /// The limit and how to raise it.
        source: pendkit_limits::LimitError,
    },
    /// A file could not be written.
    #[error("cannot write '{}': {source}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Standard output could not be written (not a closed pipe, which is no error).
    #[error("cannot write the output to stdout: {0}")]
    Stdout(std::io::Error),
    /// A fit that ran but does not explain its data: its results (`output`) are printed
    /// as a success's would be, then `message`, and the exit status is
    /// [`EXIT_UNEXPLAINED`].
    #[error("{message}")]
    Unexplained {
        /// What the command prints.
        output: String,
        /// The verdict, naming the worst residuals.
        message: String,
    },
}

/// The exit status of a command that failed (docs/cli.md, "Exit statuses and errors").
pub const EXIT_FAILURE: u8 = 1;

/// The exit status of a fit that does not explain its data: its results are printed, but
/// a script must not take them for a determination.
pub const EXIT_UNEXPLAINED: u8 = 3;

impl From<pendkit::export::FileError> for CliError {
    fn from(e: pendkit::export::FileError) -> Self {
        use pendkit::export::FileError;
        match e {
            FileError::Io { path, source } => CliError::Write { path, source },
            // the command line replaces its outputs (docs/cli.md): never refused, but if
            // it were, the line names the file
            FileError::Exists { path } => CliError::Write {
                path,
                source: std::io::ErrorKind::AlreadyExists.into(),
            },
        }
    }
}

/// The library's error as the command line says it: an override is a `--set` argument.
fn in_flag_terms(e: &pendkit::Error) -> String {
    use pendkit::Error;
    match e {
        Error::OverrideSyntax(text) => {
            format!("--set '{text}': expected NAME=EXPR or damping.<tag>.<field>=EXPR")
        }
        Error::OverrideRefused { key, message } => format!("--set {key}=...: {message}"),
        Error::OverriddenTwice(key) => {
            format!("--set '{key}' is given twice: give each parameter or damping field once")
        }
        other => other.to_string(),
    }
}

impl CliError {
    /// The exit status this error ends the program with.
    pub fn exit_status(&self) -> u8 {
        match self {
            CliError::Unexplained { .. } => EXIT_UNEXPLAINED,
            _ => EXIT_FAILURE,
        }
    }

    /// A usage error from anything printable.
    pub fn usage(message: impl Into<String>) -> Self {
        CliError::Usage(message.into())
    }
}
