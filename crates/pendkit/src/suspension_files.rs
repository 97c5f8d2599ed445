//! Suspension files as models (with the `files` feature): read once per path, with `extends`
//! finding the bundled files, and kept for the rest of the program.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{LazyLock, Mutex};

use pendkit_model::Model;
use pendkit_models::Bundled;
use pendkit_suspension::Suspension;

use crate::Error;

/// Suspension files read so far, by path: a [`crate::Case`] holds its model as
/// `&'static dyn Model`, so each file read is kept (once per path) for the program's life.
static LOADED: LazyLock<Mutex<HashMap<PathBuf, &'static Suspension>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));

/// The suspension file at `path` as a model (read on first use, then shared); its
/// `extends` may name files beside it or bundled models. Errors name the file, the line
/// and the field.
pub fn load_suspension(path: &Path) -> Result<&'static dyn Model, Error> {
    let key = path.to_path_buf();
    // a poisoned lock only means another thread panicked while reading: the map is intact
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = loaded.get(&key) {
        return Ok(*s);
    }
    let suspension: &'static Suspension = Box::leak(Box::new(Suspension::load(path, &Bundled)?));
    loaded.insert(key, suspension);
    Ok(suspension)
}
