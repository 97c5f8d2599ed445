//! The LIGO suspension models (T020205 §6): the aLIGO quadruple test-mass suspension with
//! the public 2005 parameter set, and a GEO-style triple, each in the source's variants —
//! xtra-lite (blade tips as floats), lite (blade tips with mass, 1 DOF), full (blade tips
//! as 6-DOF bodies), lateral (blade tips with lateral compliance) and violin versions with
//! beads on the lowest wires.

mod chain;
pub mod quad;
pub mod tables;
pub mod triple;

use pendkit_model::Model;

pub use chain::Blades;

/// Every model of this crate.
pub fn models() -> Vec<&'static dyn Model> {
    quad::QUADS
        .iter()
        .map(|q| q as &dyn Model)
        .chain(triple::TRIPLES.iter().map(|t| t as &dyn Model))
        .collect()
}
