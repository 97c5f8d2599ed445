//! The models a case can refine: the bundled ones (each a suspension file embedded in the
//! program, [`bundled`]) and, with the `files` feature, suspension files read at run time.

use std::sync::Arc;

use pendkit_model::Model;

use crate::Error;

#[cfg(feature = "files")]
pub use crate::suspension_files::{load_suspension, suspension_from_text};
pub use pendkit_models as bundled;

/// Every bundled model: each is a suspension file under `models/`, embedded in the
/// program ([`bundled`]).
pub fn models() -> Vec<Arc<dyn Model>> {
    pendkit_models::models()
}

/// The bundled model called `name`.
pub fn find_model(name: &str) -> Result<Arc<dyn Model>, Error> {
    pendkit_models::find(name)
        .map(|m| m as Arc<dyn Model>)
        .ok_or_else(|| Error::UnknownModel {
            name: name.to_string(),
            known: models()
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}
