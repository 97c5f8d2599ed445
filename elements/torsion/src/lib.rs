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
use num_dual::Dual64;
use pendkit_energy::{
    Derivatives, Element, EnergyError, JetPoint, LocalFrames, OffForm, Potential, Reference,
    SharedBodies, TangentPotential, TangentTerm, TensionOff, Term, hyper_dual_over_frames,
};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{
    Constant, Lift, Real, any_moves, dot, mul_tr_const, small_rotation, tr_mul, tr_mul_vec, vee,
};
use pendkit_system::{Stage, Wire};

/// Twist energy of one wire (constants `f64`, or `Dual64` for the parameter derivatives).
#[derive(Clone, Debug)]
struct TorsionEnergy<C = f64> {
    frames: [FrameMap; 2],
    points: [Vector3<C>; 2],
    /// Orientation of end 1's body seen from end 0's body at the reference.
    reference_relative: Matrix3<C>,
    /// κ (N m/rad).
    stiffness: C,
    /// G J_e / l (N m/rad): κ with the tension off.
    stiffness_unloaded: C,
    /// The local coordinates of the reference (their values), where the twist vanishes.
    reference: Vec<f64>,
}

impl<C: Constant> TorsionEnergy<C> {
    /// Δθ (rad): the rotation of end 1 relative to end 0 since the reference, in end 0's
    /// axes, about the wire.
    fn twist<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let change = mul_tr_const(
            &tr_mul(&f0.rotation, &f1.rotation),
            &self.reference_relative,
        );
        let chord = f1.point(&self.points[1]) - f0.point(&self.points[0]);
        let axis = tr_mul_vec(&f0.rotation, &chord);
        let w = small_rotation(&change);
        dot(&w, &axis) / dot(&axis, &axis).sqrt()
    }

    /// ½ κ Δθ² (J) with the end bodies at `f0`, `f1`.
    fn energy_on<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let twist = self.twist(f0, f1);
        (twist * twist).times(self.stiffness * 0.5)
    }
}

impl TangentPotential for TorsionEnergy<Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        self.energy_on(frames[0], frames[1])
    }
    fn moves(&self) -> bool {
        self.stiffness.moves()
            || self.stiffness_unloaded.moves()
            || any_moves(&self.reference_relative)
            || self.points.iter().any(any_moves)
    }
}

impl TorsionEnergy {
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
        self.energy_on(&self.frames[0].eval(x), &self.frames[1].eval(x))
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
        for wire in system.wires.iter().filter(|w| reference.keeps_wire(w)) {
            let local = shared.frames(system, &[wire.ends[0].body, wire.ends[1].body])?;
            if let Some(energy) = torsion_energy(reference, wire, &local)? {
                let label = pendkit_energy::term_label("wire-torsion", &wire.name);
                let tag = wire.tags.torsion.clone();
                terms.push(Term::on_frames(label, "wire-torsion", tag, local, energy));
            }
        }
        Ok(terms)
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        let system = reference.system;
        let mut terms = Vec::new();
        for wire in system.wires.iter().filter(|w| reference.keeps_wire(w)) {
            let local = shared.frames(system, &[wire.ends[0].body, wire.ends[1].body])?;
            if let Some(energy) = torsion_energy(reference, wire, &local)? {
                let label = pendkit_energy::term_label("wire-torsion", &wire.name);
                let tag = wire.tags.torsion.clone();
                terms.push(TangentTerm::on_frames(
                    label,
                    "wire-torsion",
                    tag,
                    local,
                    energy,
                ));
            }
        }
        Ok(Some(terms))
    }
}

/// The twist energy of `wire` on the frames `local`, built around `reference`; `None` for
/// a wire with neither torsion constant nor polar moment; an error for a wire on a body the
/// system does not have.
fn torsion_energy<S: Constant>(
    reference: &Reference<S>,
    wire: &Wire<S>,
    local: &LocalFrames,
) -> Result<Option<TorsionEnergy<S>>, EnergyError> {
    let s = &wire.section;
    if (s.shear_modulus * s.torsion_constant).is_exactly_zero() && s.polar_moment.is_exactly_zero()
    {
        return Ok(None);
    }
    let l = reference.wire_length(wire)?;
    let tension = reference.wire_tension(wire)?;
    let unloaded = s.shear_modulus * s.torsion_constant / l;
    let stiffening = if s.area.re() > 0.0 {
        tension * s.polar_moment / s.area / l
    } else {
        S::from(0.0)
    };
    let rotation =
        |k: usize| -> Result<_, EnergyError> { Ok(reference.frame(wire.ends[k].body)?.rotation) };
    Ok(Some(TorsionEnergy {
        frames: [local.frames[0].clone(), local.frames[1].clone()],
        points: [wire.ends[0].point, wire.ends[1].point],
        reference_relative: tr_mul(&rotation(0)?, &rotation(1)?),
        stiffness: unloaded + stiffening,
        stiffness_unloaded: unloaded,
        reference: local
            .coords
            .iter()
            .map(|&g| reference.coords[g].re())
            .collect(),
    }))
}

pendkit_energy::register_element!(WireTorsion);

#[cfg(test)]
mod tests {
    //! The element's stiffness against the closed form of a round fibre (docs/physics.md §1,
    //! docs/reference-values.md §4): κ = (G J + T J/A)/l with J = π r⁴/2 and J/A = r²/2, and
    //! G J/l with the tension off. The wire hangs along z from a fixed support to a free
    //! body; yawing that body about its attachment point twists the wire by exactly the yaw,
    //! so the term's yaw–yaw Hessian entry is κ. The reference is evaluated here from the
    //! inputs, not from the element's own section constants.
    //!
    //! Tolerance 1e-12 relative: both sides are a few products of the same inputs, and the
    //! Hessian at the reference is exact (κ ∇Δθ ∇Δθᵀ, ∇Δθ = 1 along the yaw), so only
    //! rounding (~1e-15) separates them.

    use super::*;
    use pendkit_energy::OffHessian;
    use pendkit_system::{EndDirection, System, WireEnd, WireSection, WireTags};

    const RADIUS: f64 = 2e-4;
    const YOUNG: f64 = 7.2e10;
    const SHEAR: f64 = 3.1e10;
    const LENGTH: f64 = 0.6;
    const TENSION: f64 = 98.1;

    /// A fixed support (six parameters) and a free body whose origin hangs `LENGTH` below
    /// it on one round fibre from the support's origin to the body's origin.
    fn hanging_fibre() -> (System, Vec<f64>) {
        let end = |body| WireEnd {
            body,
            point: Vector3::zeros(),
            direction: EndDirection::Auto,
        };
        let wire = Wire::from_tension(
            "fibre",
            [end(0), end(1)],
            WireSection::round(RADIUS, YOUNG, SHEAR, 2200.0),
            LENGTH,
            TENSION,
            WireTags {
                stretch: "s".into(),
                bending: "b".into(),
                torsion: "t".into(),
            },
        );
        let mut system = System::free_bodies(&[("support", 0.0), ("mass", 10.0)])
            .expect("fixed coordinate names compile");
        system.wires.push(wire);
        let mut x = vec![0.0; 12];
        x[6 + 2] = -LENGTH;
        (system, x)
    }

    #[test]
    fn twist_stiffness_is_the_round_fibre_closed_form() {
        let (system, x) = hanging_fibre();
        let terms = WireTorsion.terms(&Reference::new(&system, &x)).unwrap();
        assert_eq!(terms.len(), 1);
        let term = &terms[0];
        let n = term.coords.len();
        let yaw = term.coords.iter().position(|&g| g == 6 + 3).unwrap();
        // closed forms from the inputs: J = π r⁴/2, A = π r²
        let j = std::f64::consts::PI * RADIUS.powi(4) / 2.0;
        let area = std::f64::consts::PI * RADIUS * RADIUS;
        let unloaded = SHEAR * j / LENGTH;
        let loaded = (SHEAR * j + TENSION * j / area) / LENGTH;
        for fast in [true, false] {
            let (on, off) = term.hessians(&x, fast).unwrap();
            let k_on = on[yaw * n + yaw];
            assert!(
                (k_on - loaded).abs() <= 1e-12 * loaded,
                "fast {fast}: {k_on} vs (GJ + TJ/A)/l = {loaded}"
            );
            let OffHessian::Matrix(off) = off else {
                panic!("the tension-off torsion Hessian is its own matrix, not {off:?}");
            };
            let k_off = off[yaw * n + yaw];
            assert!(
                (k_off - unloaded).abs() <= 1e-12 * unloaded,
                "fast {fast}: {k_off} vs GJ/l = {unloaded}"
            );
        }
    }

    #[test]
    fn energy_of_a_small_twist_is_half_kappa_theta_squared() {
        // E = ½ κ Δθ² with Δθ the yaw θ. The element measures the twist as the vee of the
        // relative rotation, sin θ, so E = ½ κ sin²θ: at θ = 1e-4 rad that is θ²/3 ≈ 3e-9
        // relative below ½κθ²; 1e-6 leaves margin and still catches a factor or a wrong κ.
        let (system, x) = hanging_fibre();
        let terms = WireTorsion.terms(&Reference::new(&system, &x)).unwrap();
        let j = std::f64::consts::PI * RADIUS.powi(4) / 2.0;
        let kappa = (SHEAR * j + TENSION * RADIUS * RADIUS / 2.0) / LENGTH;
        let theta = 1e-4;
        let mut twisted = x.clone();
        twisted[6 + 3] = theta;
        let energy = terms[0].energy(&twisted).unwrap();
        let expected = 0.5 * kappa * theta * theta;
        assert!(
            (energy - expected).abs() <= 1e-6 * expected,
            "{energy} vs ½κθ² = {expected}"
        );
    }
}
