//! Plug-in element: the extra stretch of bent wires (stage 2): U_T = U − U_b, the part of
//! the tensioned-beam energy that is work against the static tension as the wire bows away
//! from its chord. It is pure tension work, so it is lossless (it vanishes with the
//! tension off) and carries the wire's stretch tag. The beam itself is the bending crate's.

use pendkit_element_bending::WireBeam;
use pendkit_energy::{
    Element, EnergyError, Potential, Reference, Registration, Stage, TensionOff, Term, inventory,
};
use pendkit_rotations::Real;

/// U − U_b of one wire.
#[derive(Clone, Debug)]
struct ExtraStretchEnergy(WireBeam);

impl Potential for ExtraStretchEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let e = self.0.energy(x);
        e.total - e.bending
    }

    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Vanishes
    }
}

/// The wire-extra-stretch element kind (stage 2).
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
        let mut terms = Vec::new();
        for wire in &reference.system.wires {
            if let Some((beam, coords)) = WireBeam::new(reference, wire)? {
                terms.push(Term::new(
                    format!("wire-extra-stretch {}", wire.name),
                    "wire-extra-stretch",
                    wire.tags.stretch.clone(),
                    coords,
                    ExtraStretchEnergy(beam),
                ));
            }
        }
        Ok(terms)
    }
}

inventory::submit! { Registration(&WireExtraStretch) }
