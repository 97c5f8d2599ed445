//! Suspension files as models (with the `files` feature): read once per path and text, with
//! `extends` finding the bundled files, and kept for the rest of the program.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{LazyLock, Mutex};

use pendkit_model::Model;
use pendkit_models::Bundled;
use pendkit_suspension::{Source, Suspension};

use crate::Error;

/// Suspension files read so far, by path and text: a [`crate::Case`] holds its model as
/// `&'static dyn Model`, so each file read is kept for the program's life (once per path and
/// text: a file edited between two reads is read again).
type Loaded = HashMap<(PathBuf, String), &'static Suspension>;
static LOADED: LazyLock<Mutex<Loaded>> = LazyLock::new(|| Mutex::new(HashMap::new()));

/// The suspension file at `path` as a model; its `extends` may name files beside it or
/// bundled models. Errors name the file, the line and the field.
pub fn load_suspension(path: &Path) -> Result<&'static dyn Model, Error> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| {
        Error::from(pendkit_suspension::FileError::file(
            &name,
            format!("cannot read: {e}"),
        ))
    })?;
    suspension_from_text(path, &text)
}

/// A suspension file's `text`, read from `path` (which names it in errors and locates the
/// files it `extends`), as a model.
pub fn suspension_from_text(path: &Path, text: &str) -> Result<&'static dyn Model, Error> {
    let key = (path.to_path_buf(), text.to_string());
    // a poisoned lock only means another thread panicked while reading: the map is intact
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = loaded.get(&key) {
        return Ok(*s);
    }
    let source = Source::new(path.display().to_string(), Some(path), text);
    let suspension: &'static Suspension =
        Box::leak(Box::new(Suspension::from_source(source, &Bundled)?));
    loaded.insert(key, suspension);
    Ok(suspension)
}
