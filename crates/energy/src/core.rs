//! The core element kinds of stage 0A: gravity, springs and wire stretch (DESIGN.md §3).

use nalgebra::{Matrix6, Vector3, Vector6};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Real, angles, c};

use crate::{
    Element, EnergyError, LocalFrames, Potential, Reference, Registration, SpringEnd, Stage,
    TensionOff, Term,
};

/// Tag of gravity terms (lossless whatever multipliers the tag is given).
pub const GRAVITY_TAG: &str = "gravity";

/// Gravitational energy m g z of one body's centre of mass.
#[derive(Clone, Debug)]
pub struct GravityEnergy {
    frame: FrameMap,
    centre_of_mass: Vector3<f64>,
    /// m g (N).
    weight: f64,
}

impl Potential for GravityEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.frame.eval(x).point(&self.centre_of_mass)[2] * self.weight
    }

    /// Gravity stores energy without deforming anything: it is lossless.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Vanishes
    }
}

struct Gravity;

impl Element for Gravity {
    fn kind(&self) -> &'static str {
        "gravity"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "m g z of every massive body (lossless)"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        Ok((0..system.bodies.len())
            .filter(|&b| system.bodies[b].mass != 0.0)
            .map(|b| {
                let body = &system.bodies[b];
                let local = LocalFrames::new(system, &[b]);
                Term::new(
                    format!("gravity {}", body.name),
                    "gravity",
                    GRAVITY_TAG,
                    local.coords,
                    GravityEnergy {
                        frame: local.frames[0].clone(),
                        centre_of_mass: body.centre_of_mass,
                        weight: body.mass * system.gravity,
                    },
                )
            })
            .collect())
    }
}

/// Energy ½ k (l - l0)² of a wire's straight-line stretch between its attachment points.
#[derive(Clone, Debug)]
pub struct WireStretchEnergy {
    frames: [FrameMap; 2],
    points: [Vector3<f64>; 2],
    /// k (N/m).
    stiffness: f64,
    /// l0 (m).
    unstretched_length: f64,
}

impl WireStretchEnergy {
    /// Chord length (m) at local coordinates `x`.
    pub fn length<D: Real>(&self, x: &[D]) -> D {
        let p0 = self.frames[0].eval(x).point(&self.points[0]);
        let p1 = self.frames[1].eval(x).point(&self.points[1]);
        (p1 - p0).map(|v| v * v).sum().sqrt()
    }
}

impl Potential for WireStretchEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let stretch = self.length(x) - self.unstretched_length;
        stretch * stretch * (0.5 * self.stiffness)
    }

    /// With the tension off the wire is unstretched at its equilibrium length, so only
    /// first-order length changes store energy (DESIGN.md §4).
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(WireStretchEnergy {
            unstretched_length: self.length(x_eq),
            ..self.clone()
        })
    }
}

struct WireStretch;

impl Element for WireStretch {
    fn kind(&self) -> &'static str {
        "wire-stretch"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "½ k (l - l0)² of each wire's chord length"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        system
            .wires
            .iter()
            .map(|wire| {
                let length = reference.wire_length(wire);
                if length.is_nan() || length <= 0.0 {
                    return Err(EnergyError::ZeroLengthWire {
                        wire: wire.name.clone(),
                    });
                }
                let local = LocalFrames::new(system, &[wire.ends[0].body, wire.ends[1].body]);
                Ok(Term::new(
                    format!("wire-stretch {}", wire.name),
                    "wire-stretch",
                    wire.tags.stretch.clone(),
                    local.coords,
                    WireStretchEnergy {
                        frames: [local.frames[0].clone(), local.frames[1].clone()],
                        points: [wire.ends[0].point, wire.ends[1].point],
                        stiffness: wire.stiffness,
                        unstretched_length: wire.unstretched_length,
                    },
                ))
            })
            .collect()
    }
}

/// Energy ½ Δᵀ K Δ + fᵀ Δ of a six-axis spring, Δ = (x, y, z, yaw, pitch, roll) of end 1's
/// attachment frame seen from end 0's.
#[derive(Clone, Debug)]
pub struct SpringEnergy {
    frames: [FrameMap; 2],
    ends: [SpringEnd; 2],
    stiffness: Matrix6<f64>,
    preload: Vector6<f64>,
}

impl SpringEnergy {
    /// Deflection Δ (m, rad) at local coordinates `x`.
    pub fn deflection<D: Real>(&self, x: &[D]) -> Vector6<D> {
        let attach = |k: usize| -> Frame<D> {
            let body = self.frames[k].eval(x);
            let at_point = Frame {
                origin: body.point(&self.ends[k].point),
                rotation: body.rotation,
            };
            at_point.turned(&self.ends[k].angles)
        };
        let rel = attach(0).relative(&attach(1));
        let [yaw, pitch, roll] = angles(&rel.rotation);
        Vector6::new(
            rel.origin[0],
            rel.origin[1],
            rel.origin[2],
            yaw,
            pitch,
            roll,
        )
    }
}

impl Potential for SpringEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let d = self.deflection(x);
        let mut e = c::<D>(0.0);
        for i in 0..6 {
            e += d[i] * self.preload[i];
            for j in 0..6 {
                if self.stiffness[(i, j)] != 0.0 {
                    e += d[i] * d[j] * (0.5 * self.stiffness[(i, j)]);
                }
            }
        }
        e
    }

    /// Without preload only the spring's own deformation stores energy.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(SpringEnergy {
            preload: Vector6::zeros(),
            ..self.clone()
        })
    }
}

struct SpringKind;

impl Element for SpringKind {
    fn kind(&self) -> &'static str {
        "spring"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "six-axis spring ½ Δᵀ K Δ + fᵀ Δ between two attachment frames"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        Ok(system
            .springs
            .iter()
            .map(|s| {
                let local = LocalFrames::new(system, &[s.ends[0].body, s.ends[1].body]);
                Term::new(
                    format!("spring {}", s.name),
                    "spring",
                    s.tag.clone(),
                    local.coords,
                    SpringEnergy {
                        frames: [local.frames[0].clone(), local.frames[1].clone()],
                        ends: s.ends.clone(),
                        stiffness: s.stiffness,
                        preload: s.preload,
                    },
                )
            })
            .collect())
    }
}

inventory::submit! { Registration(&Gravity) }
inventory::submit! { Registration(&WireStretch) }
inventory::submit! { Registration(&SpringKind) }
