//! Suspension files as models (with the `files` feature): read once per path and text while
//! a case holds the model, with `extends` finding the bundled files.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, LazyLock, Mutex, Weak};

use pendkit_model::Model;
use pendkit_models::Bundled;
use pendkit_suspension::{Source, Suspension};

use crate::Error;

/// Suspension files read and still in use, by path and text: a second read of the same text
/// shares the first's model (its parsed defaults with it) while any case holds it; a file
/// edited between two reads is read again, and a model no case holds any more is freed.
type Loaded = HashMap<(PathBuf, String), Weak<Suspension>>;
static LOADED: LazyLock<Mutex<Loaded>> = LazyLock::new(|| Mutex::new(HashMap::new()));

/// The suspension file at `path` as a model; its `extends` may name files beside it or
/// bundled models. Errors name the file, the line and the field. The file is read only if
/// it is a regular file within [`pendkit_limits::FILE_BYTES`].
pub fn load_suspension(path: &Path) -> Result<Arc<dyn Model>, Error> {
    let name = path.display().to_string();
    let text = pendkit_limits::read_text(path).map_err(|e| {
        Error::from(pendkit_suspension::FileError::file(
            &name,
            format!("cannot read: {e}"),
        ))
    })?;
    suspension_from_text(path, &text)
}

/// A suspension file's `text`, read from `path` (which names it in errors and locates the
/// files it `extends`), as a model.
pub fn suspension_from_text(path: &Path, text: &str) -> Result<Arc<dyn Model>, Error> {
    let key = (path.to_path_buf(), text.to_string());
    // a poisoned lock only means another thread panicked while reading: the map is intact
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(suspension) = loaded.get(&key).and_then(Weak::upgrade) {
        return Ok(suspension);
    }
    // the entries of models no longer held go (the map holds only what is in use)
    loaded.retain(|_, held| held.strong_count() > 0);
    let source = Source::new(path.display().to_string(), Some(path), text);
    let suspension = Arc::new(Suspension::from_source(source, &Bundled)?);
    loaded.insert(key, Arc::downgrade(&suspension));
    Ok(suspension)
}
