//! Where the command line's results go, and how a failure to put them there is reported:
//! standard output ([`Output`], [`print`]) and files ([`write_file`], [`OutputDir`]).
//!
//! The rule (docs/cli.md, "Output files"): a result that cannot be written is an error
//! exit with one line naming where it should have gone, never a silent success; a file is
//! written whole or not at all (`pendkit::export::write_whole`, which every output file
//! goes through); an existing output file is replaced, by every command alike, since a
//! re-run script expects its outputs to be the new ones.

use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::CliError;

/// What a command prints on standard output.
pub enum Output {
    /// Text built in memory (every table, CSV and small JSON).
    Text(String),
    /// Text written piece by piece as it is produced: for outputs too large to build in
    /// memory first (`modes --json` of a model with thousands of coordinates). The writer
    /// is buffered; an error writing to it is returned as [`CliError::Stdout`].
    Stream(Box<WriteOut>),
}

/// A writer of a streamed output: writes it all to the writer it is given.
pub type WriteOut = dyn FnOnce(&mut dyn Write) -> Result<(), CliError>;

impl From<String> for Output {
    fn from(text: String) -> Self {
        Output::Text(text)
    }
}

/// Writes the output to standard output. A closed pipe (`pendkit ... | head`: the reader
/// has all it wanted) is not an error; every other write or flush error is, since the
/// results are lost (`> /dev/full`, a full disk, a revoked terminal).
pub fn print(output: Output) -> Result<(), CliError> {
    let stdout = io::stdout().lock();
    // buffered in large blocks: stdout's own buffer flushes at every line, which for a
    // streamed JSON of a million lines is a million system calls
    let mut w = BufWriter::with_capacity(1 << 16, stdout);
    let written = match output {
        Output::Text(text) => w.write_all(text.as_bytes()).map_err(CliError::Stdout),
        Output::Stream(write) => write(&mut w),
    }
    .and_then(|()| w.flush().map_err(CliError::Stdout));
    match written {
        Err(CliError::Stdout(e)) if e.kind() == io::ErrorKind::BrokenPipe => {
            // the rest is discarded (a flush at the BufWriter's drop would fail again)
            let _ = w.into_parts();
            Ok(())
        }
        other => other,
    }
}

/// From the first call on, SIGINT and SIGTERM remove the temporary files of the outputs
/// being written and exit with status 130 (`error: interrupted`). Installed by every path
/// that writes a file, when it first does, not at start: the handler is a thread, which a
/// command that writes no file (most runs) should not pay for at start-up. Not fatal if it
/// cannot be installed (another handler in an embedding program): files are still whole or
/// absent, but a stray `.NAME.PID-N.tmp` may remain after an interrupt.
pub fn clean_up_on_interrupt() {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            pendkit::export::remove_temporaries();
            eprintln!("error: interrupted");
            std::process::exit(130);
        });
    });
}

/// Writes `bytes` to the file `path` whole or not at all, replacing an existing file:
/// every output file of the command line other than figures (which go through
/// `plotting::save`, the same helper underneath) and state-space exports (`pendkit ss`,
/// ditto).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    clean_up_on_interrupt();
    pendkit::export::write_bytes_whole(path, bytes).map_err(CliError::from)
}

/// An output folder (`report --out DIR`, `tradeoff --out DIR`): created if missing, and
/// removed again if this run created it and then wrote nothing into it, so that a failed
/// run leaves nothing behind.
pub struct OutputDir {
    path: PathBuf,
    created: bool,
    kept: bool,
}

impl OutputDir {
    /// Creates the folder (and its missing parents, as `mkdir -p`), or takes the existing
    /// one. An error names the folder.
    pub fn create(path: &Path) -> Result<OutputDir, CliError> {
        clean_up_on_interrupt();
        let existed = path.is_dir();
        std::fs::create_dir_all(path).map_err(|source| CliError::Write {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(OutputDir {
            path: path.to_path_buf(),
            created: !existed,
            kept: false,
        })
    }

    /// The path of a file in the folder.
    pub fn join(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    /// The run succeeded: keep the folder.
    pub fn keep(mut self) {
        self.kept = true;
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if self.created && !self.kept {
            // only an empty folder is removed: never anything a user put there meanwhile
            // (only the leaf: parents created by `create_dir_all` stay, as `mkdir -p`'s)
            let _ = std::fs::remove_dir(&self.path);
        }
    }
}
