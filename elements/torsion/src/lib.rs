//! Plug-in element: torsion of wires (stage 1A). E = ½ κ Δθ², κ = (G J_e + T J/A)/l
//! (docs/physics.md §1; the source prints the bracket without the 1/l), with Δθ the twist of the
//! end frames about the wire relative to the reference configuration. With the tension off
//! only G J_e / l remains: the T J/A part is tension stiffening and so lossless. A hinged
//! end frees bending, not twist, so every wire twists.
//!
//! Fast derivatives: at the configuration the term was built around the twist vanishes
//! identically, so there the Hessian is exactly κ ∇Δθ ∇Δθᵀ (first derivatives only);
//! elsewhere the energy is differentiated over frames rebuilt from the bodies' jets.

use nalgebra::{Matrix3, Vector3};
use pendkit_energy::{
    Derivatives, Element, EnergyError, JetPoint, OffForm, Potential, Reference, SharedBodies,
    Stage, TensionOff, Term, hyper_dual_over_frames,
};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Real, dot, mul_tr_const, small_rotation, tr_mul, tr_mul_vec, vee};

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
    /// The local coordinates of the reference, where the twist vanishes.
    reference: Vec<f64>,
}

impl TorsionEnergy {
    /// Δθ (rad): the rotation of end 1 relative to end 0 since the reference, in end 0's
    /// axes, about the wire.
    fn twist<D: Real>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let change = mul_tr_const(
            &tr_mul(&f0.rotation, &f1.rotation),
            &self.reference_relative,
        );
        let chord = f1.point(&self.points[1]) - f0.point(&self.points[0]);
        let axis = tr_mul_vec(&f0.rotation, &chord);
        let w = small_rotation(&change);
        dot(&w, &axis) / dot(&axis, &axis).sqrt()
    }

    /// The Hessian at the reference. There Δθ = 0 identically (the change of relative
    /// orientation is the identity), so every term of ∇²(½κΔθ²) = κ(∇Δθ∇Δθᵀ + Δθ∇²Δθ) but
    /// the first vanishes and the gradient κΔθ∇Δθ is zero: H = κ ∇Δθ ∇Δθᵀ exactly. And
    /// ∇Δθ = ∇w · axis/|axis|, the derivative of the axis multiplying w = 0.
    fn at_reference(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let [f0, f1] = at.frames else {
            return false;
        };
        let n = out.n;
        let (r0, r1) = (f0.jet.rotation(), f1.jet.rotation());
        let chord = f1.jet.point(&self.points[1]) - f0.jet.point(&self.points[0]);
        let axis = r0.transpose() * chord;
        let axis = axis / axis.norm();
        // ∇Δθ_a = vee(∂C/∂q_a)·axis, C = R0ᵀ R1 Mᵀ
        let grad = &mut out.scratch.numbers;
        grad.clear();
        grad.resize(n, 0.0);
        let m_t = self.reference_relative.transpose();
        for (&l, dr0) in f0.local.iter().zip(f0.jet.d_rotations()) {
            grad[l] += vee(&(dr0.transpose() * r1 * m_t)).dot(&axis);
        }
        for (&l, dr1) in f1.local.iter().zip(f1.jet.d_rotations()) {
            grad[l] += vee(&(r0.transpose() * dr1 * m_t)).dot(&axis);
        }
        if out.hessian {
            for a in 0..n {
                for b in 0..n {
                    let g = grad[a] * grad[b];
                    out.on[a * n + b] = self.stiffness * g;
                    out.off[a * n + b] = self.stiffness_unloaded * g;
                }
            }
        }
        out.off_form = OffForm::Written;
        true
    }
}

impl Potential for TorsionEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let twist = self.twist(&self.frames[0].eval(x), &self.frames[1].eval(x));
        twist * twist * (0.5 * self.stiffness)
    }

    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(TorsionEnergy {
            stiffness: self.stiffness_unloaded,
            ..self.clone()
        })
    }

    /// At the reference the structured form (see [`TorsionEnergy::at_reference`]); elsewhere
    /// ½Δθ² by hyper-dual numbers over frames rebuilt from the jets, times κ and κ_off
    /// (the tension-off term differs only in its stiffness).
    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        if at.x == self.reference.as_slice() {
            return self.at_reference(at, out);
        }
        let computed = hyper_dual_over_frames(at, 1, out, |[f0, f1], e| {
            let twist = self.twist(f0, f1);
            e[0] = twist * twist * 0.5;
        });
        if !computed {
            return false;
        }
        let n = out.n;
        out.values[0] *= self.stiffness;
        for g in out.gradients.iter_mut() {
            *g *= self.stiffness;
        }
        if out.hessian {
            for (on, off) in out.on[..n * n].iter_mut().zip(out.off.iter_mut()) {
                *off = *on * self.stiffness_unloaded;
                *on *= self.stiffness;
            }
        }
        out.off_form = OffForm::Written;
        true
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
        self.terms_shared(reference, &SharedBodies::new())
    }
    /// One term per wire, on the wire's frames as the other wire kinds share them.
    fn terms_shared(
        &self,
        reference: &Reference,
        shared: &SharedBodies,
    ) -> Result<Vec<Term>, EnergyError> {
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
            let local = shared.frames(system, &[wire.ends[0].body, wire.ends[1].body]);
            let r0 = system.bodies[wire.ends[0].body]
                .frame
                .eval(reference.coords)
                .rotation;
            let r1 = system.bodies[wire.ends[1].body]
                .frame
                .eval(reference.coords)
                .rotation;
            let energy = TorsionEnergy {
                frames: [local.frames[0].clone(), local.frames[1].clone()],
                points: [wire.ends[0].point, wire.ends[1].point],
                reference_relative: r0.transpose() * r1,
                stiffness: unloaded + stiffening,
                stiffness_unloaded: unloaded,
                reference: local.coords.iter().map(|&g| reference.coords[g]).collect(),
            };
            terms.push(Term::on_frames(
                format!("wire-torsion {}", wire.name),
                "wire-torsion",
                wire.tags.torsion.clone(),
                local,
                energy,
            ));
        }
        Ok(terms)
    }
}

pendkit_energy::register_element!(WireTorsion);
