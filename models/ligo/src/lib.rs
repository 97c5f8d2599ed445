//! The Rust LIGO model that is not yet a suspension file: `quad-aligo`, the aLIGO quad as
//! built (its file, `models/ligo/quad-aligo.toml`, gives the same model without violin
//! beads, which files do not yet carry on tapered fibres). The other LIGO models (the 2005
//! quad and the triple in their variants) are files under `models/ligo/`.

pub mod chain;
pub mod quad;
pub mod tables;

use pendkit_model::Model;

pub use chain::Blades;

/// Every model of this crate.
pub fn models() -> Vec<&'static dyn Model> {
    quad::QUADS.iter().map(|q| q as &dyn Model).collect()
}
