//! Plug-in element: the extra stretch of bent wires (stage 2): U_T = U − U_b, the part of
//! the tensioned-beam energy that is work against the static tension as the wire bows away
//! from its chord. It is pure tension work, so it is lossless (it vanishes with the
//! tension off) and carries the wire's stretch tag. The beam itself is the bending crate's.

use num_dual::Dual64;
use pendkit_element_bending::{EXTRA_STRETCH_PART, beam_tangent_terms, beam_terms};
use pendkit_energy::{Element, EnergyError, Reference, SharedBodies, TangentTerm, Term};
use pendkit_system::Stage;

/// The wire-extra-stretch element kind (stage 2): part [`EXTRA_STRETCH_PART`] of each
/// wire's beam, shared with the bending kind (so one evaluation gives both).
pub struct WireExtraStretch;

impl Element for WireExtraStretch {
    fn kind(&self) -> &'static str {
        "wire-extra-stretch"
    }
    fn stage(&self) -> Stage {
        Stage::S2
    }
    fn summary(&self) -> &'static str {
        "work against tension of each bent wire, U - EI dU/dEI (lossless)"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        self.terms_shared(reference, &SharedBodies::new())
    }
    /// U − U_b of each wire: pure tension work, lossless (it vanishes with the tension off).
    fn terms_shared(
        &self,
        reference: &Reference,
        shared: &SharedBodies,
    ) -> Result<Vec<Term>, EnergyError> {
        beam_terms(reference, shared, self.kind(), EXTRA_STRETCH_PART)
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        beam_tangent_terms(reference, shared, self.kind(), EXTRA_STRETCH_PART).map(Some)
    }
}

pendkit_energy::register_element!(WireExtraStretch);
