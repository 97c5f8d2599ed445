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

pub mod beam;

use nalgebra::Vector3;
use pendkit_energy::{
    Element, EnergyError, LocalFrames, Potential, Reference, Registration, Stage, Term, Wire,
    inventory,
};
use pendkit_geometry::FrameMap;
use pendkit_rotations::{Real, c};

/// How the wire resists bending across its section.
#[derive(Clone, Debug)]
enum Section {
    /// Same EI (N m²) in every direction.
    Round { ei: f64 },
    /// EI along the principal axis (body coordinates of end 0) and across it (N m²).
    Oblong { axis: Vector3<f64>, ei: [f64; 2] },
}

/// The geometry and section of one wire, as a function of its bodies' coordinates.
#[derive(Clone, Debug)]
pub struct WireBeam {
    frames: [FrameMap; 2],
    points: [Vector3<f64>; 2],
    /// Clamp directions in each end's body coordinates, pointing into the wire; None for
    /// a hinged end.
    directions: [Option<Vector3<f64>>; 2],
    section: Section,
    /// Static tension at the reference configuration (N).
    tension: f64,
}

/// Energy of a wire as a beam: total (bending + tension work) and bending part (J).
#[derive(Clone, Copy, Debug)]
pub struct BeamEnergy<D> {
    /// U: bending strain energy plus work against tension.
    pub total: D,
    /// U_b = EI ∂U/∂EI: the bending strain energy alone.
    pub bending: D,
}

fn dot<D: Real>(a: &Vector3<D>, b: &Vector3<D>) -> D {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl WireBeam {
    /// The beam of `wire` built around `reference`, with its local coordinates; `None` when
    /// the wire has no bending stiffness or both ends are hinged (no bending energy).
    pub fn new(
        reference: &Reference,
        wire: &Wire,
    ) -> Result<Option<(WireBeam, Vec<usize>)>, EnergyError> {
        let sec = &wire.section;
        let fail = |message: String| EnergyError::Element {
            kind: "wire-bending",
            element: wire.name.clone(),
            message,
        };
        let directions = reference.wire_end_directions(wire);
        let ei = [
            sec.youngs_modulus * sec.moment_1,
            sec.youngs_modulus * sec.moment_2,
        ];
        if directions.iter().all(Option::is_none) || ei.iter().all(|&e| e == 0.0) {
            return Ok(None);
        }
        // a tension within rounding of the stretch (k l ε) is zero, not compression
        let rounding = 1e-12 * wire.stiffness * reference.wire_length(wire);
        let tension = match reference.wire_tension(wire) {
            t if t.abs() <= rounding => 0.0,
            t => t,
        };
        if tension.is_nan() || tension < 0.0 {
            return Err(fail(format!(
                "not under tension (T = {tension:.4e} N): the beam model needs a taut wire"
            )));
        }
        let section = if ei[0] == ei[1] {
            Section::Round { ei: ei[0] }
        } else {
            let rotation = reference.system.bodies[wire.ends[0].body]
                .frame
                .eval(reference.coords)
                .rotation;
            let [p0, p1] = reference.wire_points(wire);
            let chord = (p1 - p0).normalize();
            let axis = rotation * sec.principal_axis;
            if (axis - chord * axis.dot(&chord)).norm() < 1e-6 * axis.norm() {
                return Err(fail("principal axis is parallel to the wire".into()));
            }
            Section::Oblong {
                axis: sec.principal_axis,
                ei,
            }
        };
        let local = LocalFrames::new(reference.system, &[wire.ends[0].body, wire.ends[1].body]);
        let beam = WireBeam {
            frames: [local.frames[0].clone(), local.frames[1].clone()],
            points: [wire.ends[0].point, wire.ends[1].point],
            directions,
            section,
            tension,
        };
        Ok(Some((beam, local.coords)))
    }

    /// Total and bending energy at local coordinates `x`.
    pub fn energy<D: Real>(&self, x: &[D]) -> BeamEnergy<D> {
        let f0 = self.frames[0].eval(x);
        let f1 = self.frames[1].eval(x);
        let chord = f1.point(&self.points[1]) - f0.point(&self.points[0]);
        let l = dot(&chord, &chord).sqrt();
        let unit = chord / l;
        // end slopes relative to the chord (small-angle vectors ⟂ chord); the wire's tangent
        // runs from end 0 to end 1, so at end 1 it is minus the clamp direction
        let slope = |k: usize| -> Vector3<D> {
            match &self.directions[k] {
                None => Vector3::from_element(c(0.0)),
                Some(d) => {
                    let frame = if k == 0 { &f0 } else { &f1 };
                    let t = frame.direction(&(d * if k == 0 { 1.0 } else { -1.0 }));
                    t - unit * dot(&t, &unit)
                }
            }
        };
        let (t0, t1) = (slope(0), slope(1));
        let clamped = [self.directions[0].is_some(), self.directions[1].is_some()];
        // one principal direction: (EI, component of a slope along it)
        let axis_energy = |ei: f64, a: D, b: D, ab: D| -> BeamEnergy<D> {
            let u = l * (self.tension / ei).sqrt();
            let (tot, bend) = beam::coefficients(u, clamped);
            let scale = (l * 2.0).recip() * ei;
            let q = |k: &beam::Coefficients<D>| (k.c11 * a + k.c22 * b + k.c12 * ab * 2.0) * scale;
            BeamEnergy {
                total: q(&tot),
                bending: q(&bend),
            }
        };
        match &self.section {
            Section::Round { ei } => axis_energy(*ei, dot(&t0, &t0), dot(&t1, &t1), dot(&t0, &t1)),
            Section::Oblong { axis, ei } => {
                let a = f0.direction(axis);
                let e1 = a - unit * dot(&a, &unit);
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

/// U_b of one wire: the bending strain energy, entirely lossy (tension-off unchanged).
#[derive(Clone, Debug)]
struct BendingEnergy(WireBeam);

impl Potential for BendingEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.0.energy(x).bending
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
        let mut terms = Vec::new();
        for wire in &reference.system.wires {
            if let Some((beam, coords)) = WireBeam::new(reference, wire)? {
                terms.push(Term::new(
                    format!("wire-bending {}", wire.name),
                    "wire-bending",
                    wire.tags.bending.clone(),
                    coords,
                    BendingEnergy(beam),
                ));
            }
        }
        Ok(terms)
    }
}

inventory::submit! { Registration(&WireBending) }
