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

#[cfg(test)]
mod tests {
    //! The element's energy against the tensioned-beam closed form (docs/physics.md §1,
    //! docs/reference-values.md §9): a round fibre clamped at both ends hangs along z from a
    //! fixed support to a free body; pitching that body about the wire's end turns the end's
    //! clamp by the pitch θ relative to the unchanged chord. The beam then stores
    //! U = (EI/2l) s_ii(u) θ², of which U_b = EI ∂U/∂EI = (EI/2l)[s_ii − (u/2) s_ii'] θ² is
    //! bending, so the extra stretch is U − U_b = (EI/2l)(u/2) s_ii'(u) θ², the term's
    //! pitch–pitch Hessian entry is (EI/l)(u/2) s_ii'(u), and with the tension off it
    //! vanishes (pure tension work). The reference is the textbook cosh/sinh form with an
    //! exact (dual-number) derivative, evaluated here; the element uses the bending crate's
    //! overflow-free rewriting.
    use super::*;
    use nalgebra::Vector3;
    use num_dual::DualNum;
    use pendkit_energy::OffHessian;
    use pendkit_system::{EndDirection, System, Wire, WireEnd, WireSection, WireTags};

    const RADIUS: f64 = 2e-4;
    const YOUNG: f64 = 7.2e10;
    const LENGTH: f64 = 0.6;
    /// EI (N m²) of the round section: E π r⁴/4 (the REF fibre of docs/reference-values.md §0,
    /// 9.0477868e-5 N m²).
    const EI: f64 = YOUNG * std::f64::consts::PI * RADIUS * RADIUS * RADIUS * RADIUS / 4.0;
    /// The tension that makes u = l √(T/EI) = 10, a row of docs/reference-values.md §9.
    const TENSION: f64 = 100.0 * EI / (LENGTH * LENGTH);

    /// A fixed support (six parameters) and a free body whose origin hangs `LENGTH` below
    /// it on one round fibre, clamped (auto) at both ends, from the support's origin to the
    /// body's origin, at tension `TENSION`.
    fn hanging_fibre() -> (System, Vec<f64>) {
        let end = |body| WireEnd {
            body,
            point: Vector3::zeros(),
            direction: EndDirection::Auto,
        };
        let wire = Wire::from_tension(
            "fibre",
            [end(0), end(1)],
            WireSection::round(RADIUS, YOUNG, YOUNG / 2.34, 2200.0),
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

    /// s_ii(u) and ds_ii/du from the textbook form u (u coth u − 1)/(u − 2 tanh(u/2))
    /// (docs/reference-values.md §9), differentiated exactly by a dual number: independent
    /// of `beam.rs`, which evaluates it in e^(−u) and by series.
    fn textbook_s_ii(u: f64) -> (f64, f64) {
        let u = Dual64::from(u).derivative();
        let s = u * (u * u.cosh() / u.sinh() - 1.0) / (u - (u / 2.0).tanh() * 2.0);
        (s.re, s.eps)
    }

    #[test]
    fn pitch_stiffness_is_the_tension_work_of_the_clamped_beam() {
        // Tolerance 1e-10 relative: at u = 10 the textbook form loses nothing to
        // cancellation, the bending crate's beam agrees with it to 1e-12 (its own tests), and
        // the Hessian at the reference is exact (the coefficient form in ∇θ).
        let (system, x) = hanging_fibre();
        let terms = WireExtraStretch
            .terms(&Reference::new(&system, &x))
            .unwrap();
        assert_eq!(terms.len(), 1);
        let term = &terms[0];
        let n = term.coords.len();
        let pitch = term.coords.iter().position(|&g| g == 6 + 4).unwrap();
        let u = LENGTH * (TENSION / EI).sqrt();
        let (_, ds_ii) = textbook_s_ii(u);
        let expected = EI / LENGTH * u / 2.0 * ds_ii;
        for fast in [true, false] {
            let (on, off) = term.hessians(&x, fast).unwrap();
            let k = on[pitch * n + pitch];
            assert!(
                (k - expected).abs() <= 1e-10 * expected,
                "fast {fast}: {k} vs (EI/l)(u/2) s_ii' = {expected}"
            );
            assert_eq!(
                off,
                OffHessian::Zero,
                "fast {fast}: tension work is lossless"
            );
        }
    }

    #[test]
    fn energy_for_a_known_end_rotation() {
        // U − U_b = (EI/2l)(u/2) s_ii'(u) θ² for an end rotation θ = 1e-4 rad. The element
        // reads the slope from the turned clamp direction (a sine of θ, and the chord's
        // length unchanged), so its energy is the quadratic form to O(θ²) relative, ~1e-8;
        // 1e-6 leaves margin and still catches a wrong factor or part.
        let (system, x) = hanging_fibre();
        let terms = WireExtraStretch
            .terms(&Reference::new(&system, &x))
            .unwrap();
        let u = LENGTH * (TENSION / EI).sqrt();
        let (_, ds_ii) = textbook_s_ii(u);
        let theta = 1e-4;
        let mut turned = x.clone();
        turned[6 + 4] = theta;
        let energy = terms[0].energy(&turned).unwrap();
        let expected = EI / (2.0 * LENGTH) * u / 2.0 * ds_ii * theta * theta;
        assert!(
            (energy - expected).abs() <= 1e-6 * expected,
            "{energy} vs (EI/2l)(u/2) s_ii' θ² = {expected}"
        );
    }
}
