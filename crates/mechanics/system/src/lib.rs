//! The numeric description of a suspension, [`System`]: its coordinates, bodies, wires,
//! springs, plug-in element instances and named signals, with every quantity in SI units,
//! plus the damping per tag and the calculation stages that the energy terms and the
//! dynamics read. Pure data: it computes no energy and knows no element kind.
//!
//! A `System`'s model numbers (masses, inertias, attachment points, wire sections,
//! stiffnesses, spring matrices) are generic over the scalar, `f64` by default: a model
//! built with dual numbers carries their exact derivatives with respect to an input
//! (docs/exact-sensitivities.md).

mod damping;
mod stage;
mod system;

pub use damping::{Damping, TagDamping};
pub use pendkit_rotations::Real;
pub use stage::{Stage, UnknownStage};
pub use system::*;

/// Tag of gravity terms (lossless whatever multipliers the tag is given).
pub const GRAVITY_TAG: &str = "gravity";

/// Tag of the debugging constraint springs.
pub const CONSTRAINT_TAG: &str = "constraint";

/// An index of a hand-built [`System`] past the end of its list ([`System::check_indices`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{item}: {what} index {index} is out of range (the system has {len})")]
pub struct IndexError {
    /// What holds the index, e.g. `wire 'w1'`.
    pub item: String,
    /// "body" or "coordinate".
    pub what: &'static str,
    /// The index.
    pub index: usize,
    /// How many there are.
    pub len: usize,
}
