//! Potential-energy terms of bodies, wires and springs, generic over the dual-number
//! scalar, with their derivatives (the hyper-dual reference path and the optional fast path
//! from shared frame jets); the `Element` trait and the link-time registry of element
//! kinds. The terms read the numeric description of a model, `pendkit_system::System`.

mod core;
mod element;
mod extra;
mod fast;
mod kind;
mod schema;
mod tangent;
mod term;

// the data model the terms read, by the names the modules use (`crate::System`, ...)
use pendkit_system::*;

pub use crate::core::{GravityEnergy, SpringEnergy, WireStretchEnergy};
pub use element::{
    DuplicateKind, Element, LocalFrames, Reference, Registration, SharedBodies,
    check_registrations, duplicate_kind, find_kind, registrations, registry, term_label,
};
pub use extra::{constraint_terms, extra_terms};
pub use fast::{
    Attached, Derivatives, FrameAt, JetPoint, MAX_FRAMES, MAX_PARTS, OffForm, Scratch,
    add_curvature, add_jacobian, hyper_dual_over_frames, on_stack,
};
pub use kind::{InstanceAt, InstanceKind, KindElement, check_fast_path};
// what a kind's energy is written with, so that a kind's crate needs only this one
pub use pendkit_geometry::Frame;
pub use pendkit_rotations::{Constant, Lift, Real};
pub use pendkit_system::{PluginElement, Stage};
pub use schema::{
    Domain, InstanceSchema, Misfit, Part, ValueField, check_plugin_elements, kinds_with_instances,
};
pub use tangent::{
    DualTangent, GradientFrames, HyperTangent, TangentDerivatives, TangentPotential,
    TangentSharedPotential, TangentSum, TangentTerm, tangent_frames, tangent_frames_along_lanes,
};
pub use term::{
    LocalDerivatives, OffHessian, PartOff, Potential, SharedPotential, TensionOff, Term,
};

/// Re-exported so plug-in crates can register without depending on `inventory` directly.
pub use inventory;

/// Errors raised while turning a model into terms.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnergyError {
    /// A wire whose attachment points coincide.
    #[error("wire '{wire}' has zero length: its attachment points coincide")]
    ZeroLengthWire {
        /// Wire name.
        wire: String,
    },
    /// A plug-in element instance names a kind nobody registered.
    #[error("element '{element}' has unknown kind '{kind}' (registered: {known})")]
    UnknownKind {
        /// Instance name.
        element: String,
        /// The kind it asks for.
        kind: String,
        /// Registered kinds, comma separated.
        known: String,
    },
    /// A user-written extra term that does not compile.
    #[error("extra term '{term}': {message}")]
    ExtraTerm {
        /// Term name.
        term: String,
        /// What is wrong.
        message: String,
    },
    /// An element kind could not build its terms.
    #[error("{kind} '{element}': {message}")]
    Element {
        /// Kind name.
        kind: &'static str,
        /// Instance name.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// An index of a hand-built `System` past the end of its list.
    #[error("{item}: {what} index {index} is out of range (the system has {len})")]
    Index {
        /// What holds the index, e.g. `wire 'w1'`.
        item: String,
        /// "body" or "coordinate".
        what: &'static str,
        /// The index.
        index: usize,
        /// How many there are.
        len: usize,
    },
    /// A frame jet asked for a derivative it does not have (see [`FrameAt`]).
    #[error(transparent)]
    Jet(#[from] pendkit_geometry::JetError),
    /// A coordinate vector too short for the term it is given to.
    #[error("{function}: {argument} has {given} entries, the term reads up to index {} (needs {expected})", expected - 1)]
    Length {
        /// The function called, e.g. `Term::energy`.
        function: &'static str,
        /// The argument that is too short.
        argument: &'static str,
        /// The length it needs.
        expected: usize,
        /// The length it has.
        given: usize,
    },
}

impl From<IndexError> for EnergyError {
    fn from(e: IndexError) -> Self {
        let IndexError {
            item,
            what,
            index,
            len,
        } = e;
        EnergyError::Index {
            item,
            what,
            index,
            len,
        }
    }
}

/// `part` of a shared energy body with `parts` parts, as an index error of the term
/// `label` when the body has no such part (both kinds of term check it alike).
pub(crate) fn check_part(label: &str, part: usize, parts: usize) -> Result<(), EnergyError> {
    if part >= parts {
        return Err(EnergyError::Index {
            item: format!("term '{label}'"),
            what: "energy part",
            index: part,
            len: parts,
        });
    }
    Ok(())
}
