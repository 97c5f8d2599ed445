//! Output files written whole or not at all: [`write_whole`], the one way pendkit writes a
//! file (exports, figures, reports, fitted case files, trade-off tables).
//!
//! The content goes to a temporary file beside the output (same folder, so the final
//! rename stays on one file system and is atomic), which is flushed, synced and renamed
//! onto the output's name only when complete. A reader of the output therefore sees the
//! whole previous file or the whole new one, never a truncated one. On any error the
//! temporary file is removed.
//!
//! A process killed by a signal cannot run that clean-up itself, so every temporary file is
//! also listed in a registry while it exists: a program that catches SIGINT/SIGTERM (the
//! `pendkit` command line does) calls [`remove_temporaries`] from its handler before it
//! exits. Creating a temporary file, renaming it into place and the handler's clean-up
//! take the same lock, so a temporary file is either removed by the handler or already
//! renamed, never left behind.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Why [`write_whole`] could not place the file (the content's own errors are the caller's).
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// Creating, writing, syncing or renaming the file failed.
    #[error("cannot write '{}': {source}", .path.display())]
    Io {
        /// The output file (not the temporary one, which the user never named).
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// The output exists and the caller asked not to replace it.
    #[error("'{}' exists: not replaced", .path.display())]
    Exists {
        /// The file.
        path: PathBuf,
    },
}

/// Whether an existing output file is replaced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Existing {
    /// Replace it (atomically: the rename swaps the old file for the new one).
    Replace,
    /// Refuse it with [`FileError::Exists`], also when it appears while writing.
    Refuse,
}

/// The temporary files alive in this process, and whether the process is shutting down
/// (after which no new temporary file is created).
struct Temporaries {
    paths: Vec<PathBuf>,
    closed: bool,
}

static TEMPORARIES: Mutex<Temporaries> = Mutex::new(Temporaries {
    paths: Vec::new(),
    closed: false,
});

/// Distinguishes the temporary files of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// The registry, also after a panic elsewhere while it was held (its list stays valid:
/// every change to it is a single push or remove).
fn temporaries() -> MutexGuard<'static, Temporaries> {
    TEMPORARIES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Removes every temporary file of this process and refuses new ones: for a signal
/// handler, just before the process exits. Files already renamed into place are kept (they
/// are complete).
pub fn remove_temporaries() {
    let mut list = temporaries();
    list.closed = true;
    for path in list.paths.drain(..) {
        let _ = std::fs::remove_file(path);
    }
}

/// Writes `path` whole or not at all: `write` fills a buffered temporary file in the same
/// folder, which is then flushed, synced and renamed to `path`. On any error (from `write`
/// or from the file system) the temporary file is removed and `path` is as it was.
///
/// `write`'s own errors are returned as they are; errors of the file itself come back as
/// [`FileError`] through `E: From<FileError>`. A `write` that reports an I/O error should
/// name `path`, the file the user asked for.
pub fn write_whole<E: From<FileError>>(
    path: &Path,
    existing: Existing,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E> {
    let with_path = |source: io::Error| FileError::Io {
        path: path.to_path_buf(),
        source,
    };
    if existing == Existing::Refuse && path.exists() {
        return Err(FileError::Exists {
            path: path.to_path_buf(),
        }
        .into());
    }
    let file_name = path
        .file_name()
        .ok_or_else(|| with_path(io::Error::new(io::ErrorKind::InvalidInput, "no file name")))?;
    // hidden, and named after the output and this process, so that a stray one (after
    // SIGKILL, which nothing can catch) says where it came from
    let temporary = path.with_file_name(format!(
        ".{}.{}-{}.tmp",
        file_name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = create(&temporary).map_err(with_path)?;
    let mut w = BufWriter::new(file);
    let written = write(&mut w).and_then(|()| {
        let file = w.into_inner().map_err(|e| with_path(e.into_error()))?;
        file.sync_all().map_err(with_path)?;
        place(&temporary, path, existing)?;
        Ok(())
    });
    if written.is_err() {
        forget(&temporary);
    }
    written
}

/// Creates the temporary file (never an existing one) and registers it, under the lock.
fn create(temporary: &Path) -> io::Result<File> {
    let mut list = temporaries();
    if list.closed {
        return Err(io::Error::new(
            io::ErrorKind::Interrupted,
            "interrupted: the program is exiting",
        ));
    }
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(temporary)?;
    list.paths.push(temporary.to_path_buf());
    Ok(file)
}

/// Removes a temporary file and its registration.
fn forget(temporary: &Path) {
    let mut list = temporaries();
    list.paths.retain(|p| p != temporary);
    let _ = std::fs::remove_file(temporary);
}

/// Moves the complete `temporary` file to `path`, under the registry's lock (so that a
/// signal handler sees it either before, and removes it, or after, and keeps the output).
/// Replacing is a rename, which swaps the old file for the new one at once. Refusing is a
/// hard link, which fails if `path` appeared meanwhile, falling back to a checked rename
/// on file systems without hard links.
fn place(temporary: &Path, path: &Path, existing: Existing) -> Result<(), FileError> {
    let with_path = |source: io::Error| FileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let exists = || FileError::Exists {
        path: path.to_path_buf(),
    };
    let mut list = temporaries();
    let placed = match existing {
        Existing::Replace => std::fs::rename(temporary, path).map_err(with_path),
        Existing::Refuse => match std::fs::hard_link(temporary, path) {
            Ok(()) => {
                let _ = std::fs::remove_file(temporary);
                Ok(())
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => Err(exists()),
            Err(_) if !path.exists() => std::fs::rename(temporary, path).map_err(with_path),
            Err(_) => Err(exists()),
        },
    };
    if placed.is_ok() {
        list.paths.retain(|p| p != temporary);
    }
    placed
}

/// Writes `bytes` to `path` whole or not at all, replacing an existing file: for content
/// already in memory (a figure, a page, a table).
pub fn write_bytes_whole(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_whole(path, Existing::Replace, |w| {
        w.write_all(bytes).map_err(|source| FileError::Io {
            path: path.to_path_buf(),
            source,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("pendkit-whole-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = dir("failed");
        let path = dir.join("out.txt");
        std::fs::write(&path, "old").unwrap();
        let result: Result<(), FileError> = write_whole(&path, Existing::Replace, |w| {
            w.write_all(b"half").unwrap();
            Err(FileError::Io {
                path: path.clone(),
                source: io::Error::other("the content failed"),
            })
        });
        assert!(result.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(entries(&dir), ["out.txt"]);
    }

    #[test]
    fn replace_swaps_the_file_and_refuse_keeps_it() {
        let dir = dir("policy");
        let path = dir.join("out.txt");
        write_bytes_whole(&path, b"first").unwrap();
        write_bytes_whole(&path, b"second").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "second");
        let refused: Result<(), FileError> = write_whole(&path, Existing::Refuse, |_| Ok(()));
        assert!(matches!(refused, Err(FileError::Exists { .. })));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "second");
        assert_eq!(entries(&dir), ["out.txt"]);
    }

    #[test]
    fn a_missing_folder_names_the_output() {
        let path = std::env::temp_dir().join("pendkit-no-such-folder-9f3a/out.svg");
        let e = write_bytes_whole(&path, b"x").unwrap_err();
        assert!(
            e.to_string()
                .contains("pendkit-no-such-folder-9f3a/out.svg"),
            "{e}"
        );
        assert!(!e.to_string().contains(".tmp"), "{e}");
    }
}
