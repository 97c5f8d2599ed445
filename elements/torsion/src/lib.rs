//! Plug-in element: torsion of wires (stage 1A). E = ½ κ Δθ², κ = (G J_e + T J/A)/l
//! (DESIGN.md §3; the source prints the bracket without the 1/l), with Δθ the twist of the
//! end frames about the wire relative to the reference configuration. With the tension off
//! only G J_e / l remains: the T J/A part is tension stiffening and so lossless. A hinged
//! end frees bending, not twist, so every wire twists.

use nalgebra::{Matrix3, Vector3};
use pendkit_energy::{
    Element, EnergyError, LocalFrames, Potential, Reference, Registration, Stage, TensionOff, Term,
    inventory,
};
use pendkit_geometry::FrameMap;
use pendkit_rotations::{Real, small_rotation};

/// Twist energy of one wire.
#[derive(Clone, Debug)]
struct TorsionEnergy {
    frames: [FrameMap; 2],
    points: [Vector3<f64>; 2],
    /// Orientation of end 1's body seen from end 0's body at the reference.
    reference_relative: Matrix3<f64>,
    /// κ (N m/rad).
    stiffness: f64,
    /// G J_e / l (N m/rad): κ with the tension off.
    stiffness_unloaded: f64,
}

impl Potential for TorsionEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let f0 = self.frames[0].eval(x);
        let f1 = self.frames[1].eval(x);
        // rotation of end 1 relative to end 0 since the reference, in end 0's axes
        let change = f0.rotation.transpose()
            * f1.rotation
            * self.reference_relative.map(D::from).transpose();
        let chord = f1.point(&self.points[1]) - f0.point(&self.points[0]);
        let axis = f0.rotation.transpose() * chord;
        let axis_len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let w = small_rotation(&change);
        let twist = (w[0] * axis[0] + w[1] * axis[1] + w[2] * axis[2]) / axis_len;
        twist * twist * (0.5 * self.stiffness)
    }

    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(TorsionEnergy {
            stiffness: self.stiffness_unloaded,
            ..self.clone()
        })
    }
}

/// The wire-torsion element kind (stage 1A).
pub struct WireTorsion;

impl Element for WireTorsion {
    fn kind(&self) -> &'static str {
        "wire-torsion"
    }
    fn stage(&self) -> Stage {
        Stage::S1A
    }
    fn summary(&self) -> &'static str {
        "twist ½ κ Δθ² of each wire, κ = (G Je + T J/A)/l"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        let mut terms = Vec::new();
        for wire in &system.wires {
            let s = &wire.section;
            if s.shear_modulus * s.torsion_constant == 0.0 && s.polar_moment == 0.0 {
                continue;
            }
            let l = reference.wire_length(wire);
            let tension = reference.wire_tension(wire);
            let unloaded = s.shear_modulus * s.torsion_constant / l;
            let stiffening = if s.area > 0.0 {
                tension * s.polar_moment / s.area / l
            } else {
                0.0
            };
            let local = LocalFrames::new(system, &[wire.ends[0].body, wire.ends[1].body]);
            let r0 = system.bodies[wire.ends[0].body]
                .frame
                .eval(reference.coords)
                .rotation;
            let r1 = system.bodies[wire.ends[1].body]
                .frame
                .eval(reference.coords)
                .rotation;
            terms.push(Term::new(
                format!("wire-torsion {}", wire.name),
                "wire-torsion",
                wire.tags.torsion.clone(),
                local.coords,
                TorsionEnergy {
                    frames: [local.frames[0].clone(), local.frames[1].clone()],
                    points: [wire.ends[0].point, wire.ends[1].point],
                    reference_relative: r0.transpose() * r1,
                    stiffness: unloaded + stiffening,
                    stiffness_unloaded: unloaded,
                },
            ));
        }
        Ok(terms)
    }
}

inventory::submit! { Registration(&WireTorsion) }
