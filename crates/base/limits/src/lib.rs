//! The limits on the size of what pendkit is given, checked before the work they bound.
//!
//! Generated and adversarial inputs can ask for more than any suspension needs: a `mirror`
//! list that doubles a wire set thirty times, a "suspension file" that is a link to
//! `/dev/zero`, a sweep of a million steps. Each such expansion is sized before it is built
//! and refused at once when it passes its limit, with one line naming what, how many, the
//! limit, and how to raise it. The limits are listed in one place
//! (docs/checks-and-refusals.md, "Limits", written from [`ALL`]).
//!
//! Every limit here can be changed for one run by its environment variable,
//! `PENDKIT_MAX_<WHAT>=N` (a whole number from 1 up): the numbers are what the work costs on
//! one machine, not what is correct, so someone with more memory or patience may raise them.
//! The variable is read once per process, at the limit's first check (some are checked for
//! every coordinate a model adds, which must cost nothing), so a library user, the command
//! line and the Python package behave alike. Limits that guard correctness
//! or the stack rather than time and memory (the beads per wire, the depth of nested
//! includes, the depth of an expression) are constants of their crates and not raisable.

use std::fmt;
use std::io::Read;
use std::path::Path;
use std::sync::OnceLock;

/// One limit on the size of an input or of what it expands to.
#[derive(Debug)]
pub struct Limit {
    /// What is counted, plural, as the error says it (`wires in one set`).
    pub what: &'static str,
    /// The environment variable that sets another value for a run.
    pub variable: &'static str,
    /// The value when the variable is not set.
    pub default: usize,
    /// Why that number: what a count past it costs, or what needs no more.
    pub why: &'static str,
    /// The value for this process and whether the variable set it, read at the first
    /// check.
    setting: OnceLock<Result<(usize, bool), LimitError>>,
}

impl PartialEq for Limit {
    /// One limit is one variable.
    fn eq(&self, other: &Self) -> bool {
        self.variable == other.variable
    }
}

impl Eq for Limit {}

/// Bytes of one input file (a suspension file, a case file, a file it extends or includes,
/// a frequency list, `fit`'s measured data), read by [`read_text`] only if it is a regular
/// file of at most this size.
pub static FILE_BYTES: Limit = Limit {
    what: "bytes in one input file",
    variable: "PENDKIT_MAX_FILE_BYTES",
    default: 16 << 20,
    why: "the largest bundled file is 12 KB and a 200-stage chain 74 KB; a file is held \
          in memory several times while it is read (text, tree, description), so 16 MiB \
          keeps that under a few hundred MB and refuses a device or a runaway generator \
          before reading it",
    setting: OnceLock::new(),
};

/// Points of one attachment-point set after mirroring, and wires (or blade tips, springs)
/// of one set: counted from `points` and `mirror` before a point is made.
pub static WIRES_PER_SET: Limit = Limit {
    what: "parts in one set (wires, blades or springs)",
    variable: "PENDKIT_MAX_WIRES_PER_SET",
    default: 256,
    why: "suspensions hang a body from 2 to 8 wires; each wire is three energy terms \
          evaluated at every Newton step, and a set is written by one `mirror` or \
          `points` list, where hundreds are a generator's mistake (mirror = [\"x\"] x 30 \
          asks for 2^30)",
    setting: OnceLock::new(),
};

/// Wires of a whole model, violin-bead segments included: checked as each is added.
pub static WIRES: Limit = Limit {
    what: "wires in one model",
    variable: "PENDKIT_MAX_WIRES",
    default: 4096,
    why: "a four-fibre stage with 200 beads per fibre is 804 wire segments; each segment \
          adds three energy terms to every Newton step of the equilibrium, so 4096 keep an \
          equilibrium that fails within seconds",
    setting: OnceLock::new(),
};

/// Bodies of a whole model, violin beads and their joints included: checked as each is
/// added.
pub static BODIES: Limit = Limit {
    what: "bodies in one model",
    variable: "PENDKIT_MAX_BODIES",
    default: 10_000,
    why: "each body with mass is a gravity term at every Newton step, and a free one six \
          coordinates; quad-v5 with 200 beads per fibre has 1 611 bodies (a bead and its \
          joint per bead)",
    setting: OnceLock::new(),
};

/// Coordinates (variables, floats and driven parameters) of a whole model: checked as
/// each is added.
pub static COORDINATES: Limit = Limit {
    what: "coordinates in one model",
    variable: "PENDKIT_MAX_COORDINATES",
    default: 10_000,
    why: "a model's floats (their Schur complement) and each block of its modes are \
          dense: 10 000 coordinates are 800 MB in one n x n matrix; the largest bundled \
          model with 200 beads per fibre (quad-v5, n_beads = 200) has 4 836. Chains and \
          trees without floats take sparse paths and run far past it with the limit \
          raised (a 10 000-stage chain, 60 000 coordinates, in about 1 GB)",
    setting: OnceLock::new(),
};

/// Files one suspension reads through `extends` and `[[include]]`, counted over the whole
/// tree of files (a file included twice counts twice).
pub static INCLUDED_FILES: Limit = Limit {
    what: "files extended or included by one suspension",
    variable: "PENDKIT_MAX_INCLUDED_FILES",
    default: 256,
    why: "the bundled arm-cavity scene reads 7; includes nest, so a file that includes \
          another twice, which includes another twice, ... reads 2^depth files, and a cap \
          on the count refuses that before it is read",
    setting: OnceLock::new(),
};

/// Steps of one sweep, all `--vary` combined.
pub static SWEEP_STEPS: Limit = Limit {
    what: "sweep steps",
    variable: "PENDKIT_MAX_SWEEP_STEPS",
    default: 10_000,
    why: "each step is a whole run (build, equilibrium, modes): about 1.1 ms for the \
          quad's modes, so 10 000 steps take about 11 s",
    setting: OnceLock::new(),
};

/// Rows of one sweep's table: steps times the modes (or frequencies) of a step.
pub static SWEEP_ROWS: Limit = Limit {
    what: "rows in one sweep table",
    variable: "PENDKIT_MAX_SWEEP_ROWS",
    default: 2_000_000,
    why: "the table is written whole at the end (a failed sweep writes nothing), so it is \
          held in memory: 2 000 000 rows are about 100 MB",
    setting: OnceLock::new(),
};

/// Points of one frequency grid or list (`--points`, `--freqs`, `--freqs-file`, the
/// library's grids).
pub static FREQUENCY_POINTS: Limit = Limit {
    what: "frequencies in one grid",
    variable: "PENDKIT_MAX_FREQUENCY_POINTS",
    default: 1_000_000,
    why: "each frequency is a complex solve per block: a million points of the quad's \
          transfer function take 4 s and a 78 MB table, of quad-v5's noise 50 s (debug \
          build); no measurement resolves more, and a quadrature of a one-body \
          oscillator's noise uses 400 001",
    setting: OnceLock::new(),
};

/// Rows of one measured-data file (`fit`'s |TF| and mode tables), checked by `fit`'s readers
/// before a row is parsed.
pub static MEASURED_ROWS: Limit = Limit {
    what: "rows of measured data",
    variable: "PENDKIT_MAX_MEASURED_ROWS",
    default: 10_000,
    why: "a fit evaluates the model at every row at every iteration: 100 000 |TF| rows \
          took 334 s; measured transfer functions have hundreds to a few thousand points",
    setting: OnceLock::new(),
};

/// Every limit, in the order docs/checks-and-refusals.md lists them.
pub static ALL: [&Limit; 10] = [
    &FILE_BYTES,
    &WIRES_PER_SET,
    &WIRES,
    &BODIES,
    &COORDINATES,
    &INCLUDED_FILES,
    &SWEEP_STEPS,
    &SWEEP_ROWS,
    &FREQUENCY_POINTS,
    &MEASURED_ROWS,
];

/// A count past its limit, or a limit's variable set to something that is not a count.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LimitError {
    /// More than the limit allows.
    #[error(
        "{} {}: more than the limit of {max} ({})",
        count.map_or_else(|| "over 1.8e19".to_string(), |c| c.to_string()),
        limit.what,
        if *raised {
            format!("{} sets it; raise it further to go on", limit.variable)
        } else {
            format!("set {} to raise it", limit.variable)
        }
    )]
    Exceeded {
        /// The limit.
        limit: &'static Limit,
        /// How many were asked for (`None`: more than a `usize` holds).
        count: Option<usize>,
        /// The limit's value for this run.
        max: usize,
        /// Whether the value came from the environment variable.
        raised: bool,
    },
    /// The environment variable holds something other than a whole number from 1 up.
    #[error(
        "{}='{value}' is not a whole number from 1 up (the limit on {}; unset it for the default {})",
        limit.variable,
        limit.what,
        limit.default
    )]
    Setting {
        /// The limit.
        limit: &'static Limit,
        /// The variable's value as set.
        value: String,
    },
}

impl Limit {
    /// The limit's value for this run: its environment variable's, or the default; an
    /// error if the variable is set to something that is not a whole number from 1 up.
    pub fn value(&'static self) -> Result<usize, LimitError> {
        Ok(self.setting()?.0)
    }

    /// The value and whether the environment variable set it.
    fn setting(&'static self) -> Result<(usize, bool), LimitError> {
        self.setting.get_or_init(|| self.read()).clone()
    }

    /// [`Limit::setting`] from the environment.
    fn read(&'static self) -> Result<(usize, bool), LimitError> {
        match std::env::var_os(self.variable) {
            None => Ok((self.default, false)),
            Some(raw) => {
                let text = raw.to_string_lossy();
                text.trim()
                    .parse::<usize>()
                    .ok()
                    .filter(|&n| n >= 1)
                    .map(|n| (n, true))
                    .ok_or_else(|| LimitError::Setting {
                        limit: self,
                        value: text.into_owned(),
                    })
            }
        }
    }

    /// `count` is within the limit, or the error saying how many, the limit and how to
    /// raise it.
    pub fn check(&'static self, count: usize) -> Result<(), LimitError> {
        self.check_counted(Some(count))
    }

    /// [`Limit::check`] of a count computed with checked arithmetic: `None` (more than a
    /// `usize` holds) is past every limit.
    pub fn check_counted(&'static self, count: Option<usize>) -> Result<(), LimitError> {
        let (max, raised) = self.setting()?;
        match count {
            Some(n) if n <= max => Ok(()),
            _ => Err(LimitError::Exceeded {
                limit: self,
                count,
                max,
                raised,
            }),
        }
    }
}

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read (missing, no permission, ...).
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// Not a regular file (after following links): reading a device or a pipe may never
    /// end.
    #[error("not a regular file ({0}): input files must be regular files")]
    NotFile(&'static str),
    /// Past [`FILE_BYTES`].
    #[error("{0}")]
    TooLarge(LimitError),
    /// Not UTF-8 text.
    #[error("not UTF-8 text (at byte {0})")]
    NotText(usize),
}

/// The text of the input file at `path`: read only if, after following links, it is a
/// regular file of at most [`FILE_BYTES`] bytes (checked before reading, and again while
/// reading, for a file that grows or a special file that reports no size).
pub fn read_text(path: &Path) -> Result<String, ReadError> {
    let max = FILE_BYTES.value().map_err(ReadError::TooLarge)?;
    // the path's type first: opening a named pipe would wait for a writer
    let meta = std::fs::metadata(path)?;
    check_regular(&meta)?;
    FILE_BYTES
        .check_counted(usize::try_from(meta.len()).ok())
        .map_err(ReadError::TooLarge)?;
    let file = std::fs::File::open(path)?;
    // the file opened may not be the one looked at (replaced in between)
    check_regular(&file.metadata()?)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0).min(max));
    file.take(max as u64 + 1).read_to_end(&mut bytes)?;
    if bytes.len() > max {
        // grew while read, or a file whose size its metadata does not tell (/proc)
        return Err(ReadError::TooLarge(LimitError::Exceeded {
            limit: &FILE_BYTES,
            count: Some(bytes.len()),
            max,
            raised: FILE_BYTES.setting().is_ok_and(|(_, raised)| raised),
        }));
    }
    String::from_utf8(bytes).map_err(|e| ReadError::NotText(e.utf8_error().valid_up_to()))
}

/// A regular file, or what it is instead.
fn check_regular(meta: &std::fs::Metadata) -> Result<(), ReadError> {
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(());
    }
    Err(ReadError::NotFile(if kind.is_dir() {
        "a directory"
    } else {
        special_kind(&kind)
    }))
}

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_char_device() {
        "a character device"
    } else if kind.is_block_device() {
        "a block device"
    } else if kind.is_fifo() {
        "a named pipe"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

#[cfg(not(unix))]
fn special_kind(_kind: &std::fs::FileType) -> &'static str {
    "a device or a pipe"
}

impl fmt::Display for Limit {
    /// `what` (`variable`, default `default`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({}, default {})",
            self.what, self.variable, self.default
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_within_its_limit_passes_and_one_past_it_is_refused_naming_the_variable() {
        // the tests run without the variables set (nothing in the workspace sets them)
        assert!(WIRES_PER_SET.check(WIRES_PER_SET.default).is_ok());
        let e = WIRES_PER_SET
            .check(WIRES_PER_SET.default + 1)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "257 parts in one set (wires, blades or springs): more than the limit of 256 (set PENDKIT_MAX_WIRES_PER_SET to raise it)"
        );
        let e = WIRES_PER_SET.check_counted(None).unwrap_err().to_string();
        assert!(e.starts_with("over 1.8e19 parts in one set"), "{e}");
    }

    #[test]
    fn every_limit_has_its_own_variable_and_a_reason() {
        for (k, limit) in ALL.iter().enumerate() {
            assert!(limit.variable.starts_with("PENDKIT_MAX_"), "{limit}");
            assert!(limit.default >= 1 && !limit.why.is_empty(), "{limit}");
            assert!(
                ALL[..k].iter().all(|l| l.variable != limit.variable),
                "{limit}"
            );
        }
    }

    #[test]
    fn a_directory_or_a_device_is_not_read() {
        let dir = std::env::temp_dir();
        match read_text(&dir) {
            Err(ReadError::NotFile(kind)) => assert_eq!(kind, "a directory"),
            other => panic!("{other:?}"),
        }
        #[cfg(unix)]
        match read_text(Path::new("/dev/zero")) {
            Err(ReadError::NotFile(kind)) => assert_eq!(kind, "a character device"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_regular_file_is_read_and_a_missing_one_says_so() {
        let path = std::env::temp_dir().join(format!("pendkit-limits-{}.txt", std::process::id()));
        std::fs::write(&path, "mass = 1\n").unwrap();
        assert_eq!(read_text(&path).unwrap(), "mass = 1\n");
        std::fs::remove_file(&path).unwrap();
        assert!(matches!(read_text(&path), Err(ReadError::Io(_))));
    }
}
