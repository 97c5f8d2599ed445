//! Plug-in element: bending of tensioned wires near their clamps (stage 1B), and the
//! tensioned-beam closed form it shares with the extra-stretch element of stage 2.
//!
//! Each wire is a massless beam under its static tension T between two attachment points.
//! Its end slopes relative to the chord come from the clamp directions (explicit, or "auto"
//! = straight at the reference configuration); hinged ends are condensed out. Round wires
//! bend alike in every direction; oblong ones have two principal moments of area, the first
//! along the principal axis given in the body coordinates of end 0. Stage 1B adds only the
//! bending strain energy U_b = EI ∂U/∂EI, which is entirely lossy and carries the wire's
//! bending tag.
//!
//! One beam, two terms: the beam of a wire is a shared energy body
//! ([`pendkit_energy::SharedPotential`]) with two parts, U_b (this kind's term) and U − U_b
//! (the extra-stretch kind's term, stage 2). Both kinds get the same beam from the
//! assembly's [`pendkit_energy::SharedBodies`] ([`shared_beam`]), so one evaluation of the
//! beam gives both Hessians.
//!
//! Fast derivatives: U is a quadratic form in the end slopes θ with coefficients that
//! depend on l. With auto (or hinged) ends the slopes vanish identically at the reference
//! the beam was built around, so there every term of the Hessian but the coefficient form in
//! ∇θ vanishes: H = (EI/l)[c11 ∇θ1ᵀ∇θ1 + c22 ∇θ2ᵀ∇θ2 + c12(∇θ1ᵀ∇θ2 + ∇θ2ᵀ∇θ1)], which needs
//! first derivatives only. Elsewhere (another configuration, or an explicit clamp that is
//! not along the chord) the beam is differentiated over frames rebuilt from the bodies' jets.

pub mod beam;

use std::sync::Arc;

use nalgebra::Vector3;
use num_dual::Dual64;
use pendkit_energy::{
    Attached, Derivatives, Element, EnergyError, JetPoint, LocalFrames, PartOff, Reference,
    SharedBodies, SharedPotential, TangentSharedPotential, TangentTerm, Term, add_jacobian,
    hyper_dual_over_frames,
};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Constant, Lift, Real, any_moves, c, dot};
use pendkit_system::{EndDirection, Stage, Wire};

/// Index of the bending strain energy U_b among a beam's energy parts.
pub const BENDING_PART: usize = 0;
/// Index of the work against tension U − U_b among a beam's energy parts.
pub const EXTRA_STRETCH_PART: usize = 1;

/// How the wire resists bending across its section.
#[derive(Clone, Debug)]
enum Section<C> {
    /// Same EI (N m²) in every direction.
    Round { ei: C },
    /// EI along the principal axis (body coordinates of end 0) and across it (N m²).
    Oblong { axis: Vector3<C>, ei: [C; 2] },
}

/// The geometry and section of one wire, as a function of its bodies' coordinates (its
/// constants `f64`, or `Dual64` for the parameter derivatives).
#[derive(Clone, Debug)]
pub struct WireBeam<C: Constant = f64> {
    frames: [FrameMap; 2],
    points: [Vector3<C>; 2],
    /// Clamp directions in each end's body coordinates, pointing into the wire; None for
    /// a hinged end.
    directions: [Option<Vector3<C>>; 2],
    section: Section<C>,
    /// Static tension at the reference configuration (N).
    tension: C,
    /// Local coordinates of the reference configuration.
    reference: Vec<f64>,
    /// Whether every clamped end is "auto": then the slopes vanish at the reference.
    straight_at_reference: bool,
}

/// Energy of a wire as a beam: total (bending + tension work) and bending part (J).
#[derive(Clone, Copy, Debug)]
pub struct BeamEnergy<D> {
    /// U: bending strain energy plus work against tension.
    pub total: D,
    /// U_b = EI ∂U/∂EI: the bending strain energy alone.
    pub bending: D,
}

/// A wire's beam as the bending and extra-stretch kinds share it: the body and its frames
/// (constants `f64`, or `Dual64` for the parameter derivatives).
pub type SharedBeam<C = f64> = Option<(Arc<WireBeam<C>>, Arc<LocalFrames>)>;

/// The beam of wire number `index` of `reference.system`, from `shared` if another kind
/// already built it around this reference, else built now and put there;
/// [`EnergyError::Index`] for a wire the system does not have.
pub fn shared_beam<C: Constant>(
    reference: &Reference<C>,
    shared: &SharedBodies,
    index: usize,
) -> Result<Arc<SharedBeam<C>>, EnergyError> {
    let wires = &reference.system.wires;
    let wire = wires.get(index).ok_or_else(|| EnergyError::Index {
        item: "shared_beam".into(),
        what: "wire",
        index,
        len: wires.len(),
    })?;
    shared.get_or_try_insert(index, || {
        let frames = shared.frames(reference.system, &[wire.ends[0].body, wire.ends[1].body])?;
        Ok(WireBeam::new(reference, wire, &frames)?.map(|beam| (Arc::new(beam), frames)))
    })
}

/// `term(label, tag, off, frames, beam)` for every wire with a beam: part `part` of the
/// shared beam, as kind `kind` (the one builder of the `f64` and the dual terms).
fn each_beam<C: Constant, T>(
    reference: &Reference<C>,
    shared: &SharedBodies,
    kind: &'static str,
    part: usize,
    term: impl Fn(String, String, PartOff, Arc<LocalFrames>, Arc<WireBeam<C>>) -> Result<T, EnergyError>,
) -> Result<Vec<T>, EnergyError> {
    let mut terms = Vec::new();
    let wires = reference.system.wires.iter().enumerate();
    for (index, wire) in wires.filter(|(_, w)| reference.keeps_wire(w)) {
        if let Some((beam, frames)) = shared_beam(reference, shared, index)?.as_ref() {
            let (tag, off) = part_tag(wire, part);
            let label = pendkit_energy::term_label(kind, &wire.name);
            terms.push(term(label, tag, off, frames.clone(), beam.clone())?);
        }
    }
    Ok(terms)
}

/// One term per wire with a beam: part `part` of the shared beam, as kind `kind`.
pub fn beam_terms(
    reference: &Reference,
    shared: &SharedBodies,
    kind: &'static str,
    part: usize,
) -> Result<Vec<Term>, EnergyError> {
    each_beam(
        reference,
        shared,
        kind,
        part,
        |label, tag, off, frames, beam| Term::part(label, kind, tag, frames, beam, part, off),
    )
}

/// The damping tag and tension-off form of a beam's part: the bending strain energy is
/// lossy and carries the bending tag, the work against tension is lossless and carries
/// the stretch tag.
fn part_tag<S: Constant>(wire: &Wire<S>, part: usize) -> (String, PartOff) {
    if part == BENDING_PART {
        (wire.tags.bending.clone(), PartOff::Unchanged)
    } else {
        (wire.tags.stretch.clone(), PartOff::Vanishes)
    }
}

/// [`beam_terms`] for a model built with one parameter seeded: each wire's beam with its
/// constants' derivatives, built around `reference` (whose coordinates may move with the
/// parameter), part `part` as kind `kind`.
pub fn beam_tangent_terms(
    reference: &Reference<Dual64>,
    shared: &SharedBodies,
    kind: &'static str,
    part: usize,
) -> Result<Vec<TangentTerm>, EnergyError> {
    each_beam(
        reference,
        shared,
        kind,
        part,
        |label, tag, _, frames, beam| TangentTerm::part(label, kind, tag, frames, beam, part),
    )
}

impl<C: Constant> WireBeam<C> {
    /// The beam of `wire` built around `reference`, reading the frames `local` of the
    /// wire's two end bodies; `None` when the wire has no bending stiffness or both ends
    /// are hinged (no bending energy).
    pub fn new(
        reference: &Reference<C>,
        wire: &Wire<C>,
        local: &LocalFrames,
    ) -> Result<Option<WireBeam<C>>, EnergyError> {
        let sec = &wire.section;
        let fail = |message: String| EnergyError::Element {
            kind: "wire-bending",
            element: wire.name.clone(),
            message,
        };
        let directions = reference.wire_end_directions(wire)?;
        let ei = [
            sec.youngs_modulus * sec.moment_1,
            sec.youngs_modulus * sec.moment_2,
        ];
        if directions.iter().all(Option::is_none) || ei.iter().all(|e| e.is_exactly_zero()) {
            return Ok(None);
        }
        // a tension within rounding of the stretch (k l ε) is zero, not compression
        let rounding = 1e-12 * (wire.stiffness * reference.wire_length(wire)?).re();
        let tension = match reference.wire_tension(wire)? {
            t if t.re().abs() <= rounding => C::from(0.0),
            t => t,
        };
        if tension.re().is_nan() || tension.re() < 0.0 {
            return Err(fail(format!(
                "not under tension (T = {:.4e} N): the beam model needs a taut wire",
                tension.re()
            )));
        }
        let section = if (ei[0] - ei[1]).is_exactly_zero() {
            Section::Round { ei: ei[0] }
        } else {
            let rotation = reference.frame(wire.ends[0].body)?.rotation.map(|v| v.re());
            let [p0, p1] = reference.wire_points(wire)?.map(|p| p.map(|v| v.re()));
            let chord = (p1 - p0).normalize();
            let axis = rotation * sec.principal_axis.map(|v| v.re());
            if (axis - chord * axis.dot(&chord)).norm() < 1e-6 * axis.norm() {
                return Err(fail("principal axis is parallel to the wire".into()));
            }
            Section::Oblong {
                axis: sec.principal_axis,
                ei,
            }
        };
        let beam = WireBeam {
            frames: [local.frames[0].clone(), local.frames[1].clone()],
            points: [wire.ends[0].point, wire.ends[1].point],
            directions,
            section,
            tension,
            reference: local
                .coords
                .iter()
                .map(|&g| reference.coords[g].re())
                .collect(),
            straight_at_reference: wire
                .ends
                .iter()
                .all(|end| !matches!(end.direction, EndDirection::Explicit(_))),
        };
        Ok(Some(beam))
    }

    /// Total and bending energy at local coordinates `x`.
    pub fn energy<D: Lift<C>>(&self, x: &[D]) -> BeamEnergy<D> {
        self.energy_of_frames(&self.frames[0].eval(x), &self.frames[1].eval(x))
    }

    /// Total and bending energy with the two bodies' frames at `f0` and `f1`.
    pub fn energy_of_frames<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> BeamEnergy<D> {
        let chord = f1.point(&self.points[1]) - f0.point(&self.points[0]);
        let zero = Vector3::from_element(c(0.0));
        // the wire's tangent runs from end 0 to end 1: at end 1 it is minus the clamp
        let tangent = |k: usize| match &self.directions[k] {
            None => zero,
            Some(d) if k == 0 => f0.direction(d),
            Some(d) => f1.direction(&-d),
        };
        let axis = match &self.section {
            Section::Round { .. } => zero,
            Section::Oblong { axis, .. } => f0.direction(axis),
        };
        self.energy_of_inputs(&chord, &[tangent(0), tangent(1)], &axis)
    }

    /// Total and bending energy from the beam's geometric inputs in lab axes: the chord
    /// c = p1 − p0 (m), the clamp tangents (R0 d0 at end 0, −R1 d1 at end 1; ignored at a
    /// hinged end) and, for an oblong section, the principal axis R0 a (ignored otherwise).
    pub fn energy_of_inputs<D: Lift<C>>(
        &self,
        chord: &Vector3<D>,
        tangents: &[Vector3<D>; 2],
        axis: &Vector3<D>,
    ) -> BeamEnergy<D> {
        let l = dot(chord, chord).sqrt();
        let unit = chord / l;
        // end slopes relative to the chord (small-angle vectors ⟂ chord)
        let slope = |k: usize| -> Vector3<D> {
            match &self.directions[k] {
                None => Vector3::from_element(c(0.0)),
                Some(_) => {
                    let t = tangents[k];
                    t - unit * dot(&t, &unit)
                }
            }
        };
        let (t0, t1) = (slope(0), slope(1));
        let clamped = [self.directions[0].is_some(), self.directions[1].is_some()];
        // one principal direction: (EI, component of a slope along it)
        let axis_energy = |ei: C, a: D, b: D, ab: D| -> BeamEnergy<D> {
            let u = l.times((self.tension / ei).sqrt());
            let (tot, bend) = beam::coefficients(u, clamped);
            let scale = (l * 2.0).recip().times(ei);
            let q = |k: &beam::Coefficients<D>| (k.c11 * a + k.c22 * b + k.c12 * ab * 2.0) * scale;
            BeamEnergy {
                total: q(&tot),
                bending: q(&bend),
            }
        };
        match &self.section {
            Section::Round { ei } => axis_energy(*ei, dot(&t0, &t0), dot(&t1, &t1), dot(&t0, &t1)),
            Section::Oblong { ei, .. } => {
                let e1 = axis - unit * dot(axis, &unit);
                let e1 = e1 / dot(&e1, &e1).sqrt();
                let e2 = unit.cross(&e1);
                let mut out = BeamEnergy {
                    total: c(0.0),
                    bending: c(0.0),
                };
                for (e, ei) in [(e1, ei[0]), (e2, ei[1])] {
                    let (a0, a1) = (dot(&t0, &e), dot(&t1, &e));
                    let part = axis_energy(ei, a0 * a0, a1 * a1, a0 * a1);
                    out.total += part.total;
                    out.bending += part.bending;
                }
                out
            }
        }
    }
}

impl WireBeam {
    /// The Hessians of both parts at the reference with straight (auto or hinged) ends,
    /// where the slopes vanish (see the crate documentation). With D_k the clamp's tangent
    /// (R0 d0 at end 0, −R1 d1 at end 1), equal to the chord's unit vector u there, the
    /// slope t_k = D_k − u (u·D_k) has ∇t_k = (I − u uᵀ)(∇D_k − ∇c / l): the terms dropped
    /// multiply D_k − u = 0 or u·∇u = 0.
    fn at_reference(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let [f0, f1] = at.frames else {
            return false;
        };
        let n = out.n;
        let frames = [f0, f1];
        let chord = f1.jet.point(&self.points[1]) - f0.jet.point(&self.points[0]);
        let l = chord.norm();
        let u = chord / l;
        // columns: ∇c, then ∇t_0, ∇t_1 (zero for a hinged end, whose coefficients vanish)
        let columns = out.scratch.zero_vectors(3 * n);
        let (dc, slopes) = columns.split_at_mut(n);
        // on an error (buffers that do not fit the frames) the reference path answers
        if add_jacobian(f1, Attached::Point(&self.points[1]), 1.0, dc).is_err()
            || add_jacobian(f0, Attached::Point(&self.points[0]), -1.0, dc).is_err()
        {
            return false;
        }
        for k in 0..2 {
            let Some(d) = &self.directions[k] else {
                continue;
            };
            let tangent = d * if k == 0 { 1.0 } else { -1.0 };
            let dt = &mut slopes[k * n..(k + 1) * n];
            if add_jacobian(frames[k], Attached::Direction(&tangent), 1.0, dt).is_err() {
                return false;
            }
            for (t, c) in dt.iter_mut().zip(dc.iter()) {
                let v = *t - c / l;
                *t = v - u * u.dot(&v);
            }
        }
        let (dt0, dt1) = slopes.split_at(n);
        let clamped = [self.directions[0].is_some(), self.directions[1].is_some()];
        // one principal direction (or all, for a round wire: project = None): add
        // (EI/l)[c11 ∇a0∇a0ᵀ + c22 ∇a1∇a1ᵀ + c12(∇a0∇a1ᵀ + ∇a1∇a0ᵀ)] for each part
        let mut add_axis = |ei: f64, project: Option<&Vector3<f64>>| {
            let (total, bending) = beam::coefficients(l * (self.tension / ei).sqrt(), clamped);
            let parts = [
                (BENDING_PART, bending.c11, bending.c22, bending.c12),
                (
                    EXTRA_STRETCH_PART,
                    total.c11 - bending.c11,
                    total.c22 - bending.c22,
                    total.c12 - bending.c12,
                ),
            ];
            let scale = ei / l;
            for a in 0..n {
                for b in 0..n {
                    let (g00, g11, g01) = match project {
                        None => (
                            dt0[a].dot(&dt0[b]),
                            dt1[a].dot(&dt1[b]),
                            dt0[a].dot(&dt1[b]) + dt1[a].dot(&dt0[b]),
                        ),
                        Some(e) => {
                            let (p0a, p0b, p1a, p1b) =
                                (dt0[a].dot(e), dt0[b].dot(e), dt1[a].dot(e), dt1[b].dot(e));
                            (p0a * p0b, p1a * p1b, p0a * p1b + p1a * p0b)
                        }
                    };
                    for &(p, c11, c22, c12) in &parts {
                        out.on[p * n * n + a * n + b] +=
                            scale * (c11 * g00 + c22 * g11 + c12 * g01);
                    }
                }
            }
        };
        match &self.section {
            Section::Round { ei } => add_axis(*ei, None),
            Section::Oblong { axis, ei } => {
                let a = f0.jet.rotation() * axis;
                let e1 = (a - u * a.dot(&u)).normalize();
                let e2 = u.cross(&e1);
                add_axis(ei[0], Some(&e1));
                add_axis(ei[1], Some(&e2));
            }
        }
        true
    }
}

/// The beam with constants carrying their parameter derivatives: the same two parts.
impl TangentSharedPotential for WireBeam<Dual64> {
    fn parts(&self) -> usize {
        2
    }

    fn energies_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>], out: &mut [D]) {
        let e = self.energy_of_frames(frames[0], frames[1]);
        out[BENDING_PART] = e.bending;
        out[EXTRA_STRETCH_PART] = e.total - e.bending;
    }

    fn moves(&self) -> bool {
        let section = match &self.section {
            Section::Round { ei } => ei.moves(),
            Section::Oblong { axis, ei } => any_moves(axis) || any_moves(ei),
        };
        section
            || self.tension.moves()
            || self.points.iter().any(any_moves)
            || self.directions.iter().flatten().any(any_moves)
    }
}

/// The beam yields U_b ([`BENDING_PART`]) and U − U_b ([`EXTRA_STRETCH_PART`]).
impl SharedPotential for WireBeam {
    fn parts(&self) -> usize {
        2
    }

    fn energies<D: Real>(&self, x: &[D], out: &mut [D]) {
        let e = self.energy(x);
        out[BENDING_PART] = e.bending;
        out[EXTRA_STRETCH_PART] = e.total - e.bending;
    }

    /// At the reference with straight ends the coefficient form (exact there); elsewhere
    /// both parts from one hyper-dual pass over frames rebuilt from the jets. That general
    /// path was measured against differentiating the same energy with respect to its 12
    /// geometric inputs (chord, tangents, axis) by one second-order dual evaluation
    /// (`Dual2SVec64<12>`) and the chain rule: for a quad fibre (12 coordinates, both
    /// parts) 42 µs against 50 µs (the reference path: 2 × 47 µs), so the frames won.
    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        if self.straight_at_reference && at.x == self.reference.as_slice() {
            return self.at_reference(at, out);
        }
        hyper_dual_over_frames(at, 2, out, |[f0, f1], e| {
            let b = self.energy_of_frames(f0, f1);
            e[BENDING_PART] = b.bending;
            e[EXTRA_STRETCH_PART] = b.total - b.bending;
        })
    }
}

/// The wire-bending element kind (stage 1B).
pub struct WireBending;

impl Element for WireBending {
    fn kind(&self) -> &'static str {
        "wire-bending"
    }
    fn stage(&self) -> Stage {
        Stage::S1B
    }
    fn summary(&self) -> &'static str {
        "bending strain energy EI dU/dEI of each tensioned wire at its clamps"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        self.terms_shared(reference, &SharedBodies::new())
    }
    /// U_b of each wire: the bending strain energy, entirely lossy (tension-off unchanged).
    fn terms_shared(
        &self,
        reference: &Reference,
        shared: &SharedBodies,
    ) -> Result<Vec<Term>, EnergyError> {
        beam_terms(reference, shared, self.kind(), BENDING_PART)
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        beam_tangent_terms(reference, shared, self.kind(), BENDING_PART).map(Some)
    }
}

pendkit_energy::register_element!(WireBending);

#[cfg(test)]
mod tests {
    //! The element's stiffness against the tensioned-beam closed form (docs/physics.md §1,
    //! docs/reference-values.md §9): a round fibre clamped at both ends hangs along z from a
    //! fixed support to a free body; pitching that body about the wire's end turns the end's
    //! clamp by the pitch relative to the unchanged chord, so the beam stores
    //! U = (EI/2l) s_ii(u) θ² and its bending part U_b = EI ∂U/∂EI = (EI/2l)[s_ii − (u/2) s_ii'] θ²,
    //! and the term's pitch–pitch Hessian entry is (EI/l)[s_ii − (u/2) s_ii'](u). The
    //! reference is the textbook cosh/sinh form with an exact (dual-number) derivative,
    //! evaluated here; the element uses `beam.rs`'s overflow-free rewriting.
    //!
    //! Tolerance 1e-10 relative: at u = 10 the textbook form loses nothing to cancellation,
    //! `beam.rs` agrees with it to 1e-12 (its own tests), and the Hessian at the reference is
    //! exact (the coefficient form in ∇θ, no differencing).
    use super::*;
    use num_dual::DualNum;
    use pendkit_energy::OffHessian;
    use pendkit_system::{System, WireEnd, WireSection, WireTags};

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
    fn a_beam_of_a_wire_the_model_lacks_is_an_error() {
        let (system, x) = hanging_fibre();
        let reference = Reference::new(&system, &x);
        let shared = SharedBodies::new();
        assert!(shared_beam(&reference, &shared, 0).unwrap().is_some());
        let e = shared_beam(&reference, &shared, 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "shared_beam: wire index 1 is out of range (the system has 1)"
        );
    }

    #[test]
    fn pitch_stiffness_is_the_bending_part_of_the_clamped_beam() {
        let (system, x) = hanging_fibre();
        let terms = WireBending.terms(&Reference::new(&system, &x)).unwrap();
        assert_eq!(terms.len(), 1);
        let term = &terms[0];
        let n = term.coords.len();
        let pitch = term.coords.iter().position(|&g| g == 6 + 4).unwrap();
        let u = LENGTH * (TENSION / EI).sqrt();
        let (s_ii, ds_ii) = textbook_s_ii(u);
        // the printed row of docs/reference-values.md §9 (u = 10), to its digits: the
        // reference formula is the one the oracle file means
        assert!((s_ii - 11.24974).abs() < 5e-6, "s_ii(10) = {s_ii}");
        let expected = EI / LENGTH * (s_ii - u / 2.0 * ds_ii);
        for fast in [true, false] {
            let (on, off) = term.hessians(&x, fast).unwrap();
            let k = on[pitch * n + pitch];
            assert!(
                (k - expected).abs() <= 1e-10 * expected,
                "fast {fast}: {k} vs (EI/l)(s_ii - u s_ii'/2) = {expected}"
            );
            // bending strain energy is all lossy: the same with the tension off
            assert_eq!(off, OffHessian::Same, "fast {fast}");
        }
    }
}
