//! Element kind `point-spring`: an isotropic spring between two body points,
//! E = ½ k |Δ|², Δ the change of the points' separation vector from the reference
//! configuration (a magnet-coil pair; a negative k is a magnetic anti-spring). It joins at
//! stage 0A, so it takes part in the equilibrium; its rest separation is the one at the
//! model's start (the spring exerts no force there).
//!
//! In a suspension file:
//!
//! ```toml
//! [[element]]
//! kind = "point-spring"
//! name = "coil_magnet_1"
//! between = ["top", "support"]
//! points = [["0.1", "0.05", "0"], ["0.1", "0.05", "0.002"]]
//! values = { k = "k_magnet" }
//! tag = "magnet"
//! ```
//!
//! The instance's values are checked against [`SCHEMA`] before any term is built, so the
//! kind reads them without checking them again.

use nalgebra::Vector3;
use num_dual::Dual64;
use pendkit_energy::{
    Domain, Element, EnergyError, InstanceSchema, LocalFrames, Potential, Reference, SharedBodies,
    TangentPotential, TangentTerm, Term, ValueField,
};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Constant, Lift, Real, any_moves};
use pendkit_system::{PluginElement, Stage};

/// The kind's name.
pub const KIND: &str = "point-spring";

/// What an instance needs: two bodies, a point on each, the stiffness k.
pub const SCHEMA: InstanceSchema = InstanceSchema {
    bodies: 2,
    points: 2,
    values: &[ValueField {
        name: "k",
        unit: "N/m",
        domain: Domain::Finite,
        default: None,
        description: "stiffness, the same along every axis (negative: a magnetic anti-spring)",
    }],
};

/// ½ k |(p1 − p0) − d_ref|² for one instance (constants `f64`, or `Dual64` for the
/// parameter derivatives).
#[derive(Clone, Debug)]
struct PointSpringEnergy<C = f64> {
    frames: [FrameMap; 2],
    points: [Vector3<C>; 2],
    /// Separation at the reference configuration (m).
    rest: Vector3<C>,
    /// k (N/m).
    stiffness: C,
}

impl<C: Constant> PointSpringEnergy<C> {
    /// ½ k |Δ|² (J) with the two bodies at `f0`, `f1`.
    fn energy_on<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let p0 = f0.point(&self.points[0]);
        let p1 = f1.point(&self.points[1]);
        let d = |i: usize| p1[i] - p0[i] - D::lift(self.rest[i]);
        let (dx, dy, dz) = (d(0), d(1), d(2));
        (dx * dx + dy * dy + dz * dz).times(self.stiffness * 0.5)
    }
}

impl Potential for PointSpringEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.energy_on(&self.frames[0].eval(x), &self.frames[1].eval(x))
    }
}

impl TangentPotential for PointSpringEnergy<Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        self.energy_on(frames[0], frames[1])
    }
    fn moves(&self) -> bool {
        self.stiffness.moves() || any_moves(&self.rest) || self.points.iter().any(any_moves)
    }
}

/// The energy of instance `e` (checked against [`SCHEMA`]) on the frames `local`, built
/// around `reference`.
fn energy<S: Constant>(
    reference: &Reference<S>,
    e: &PluginElement<S>,
    local: &LocalFrames,
) -> PointSpringEnergy<S> {
    let (b, q) = ([e.bodies[0], e.bodies[1]], [e.points[0], e.points[1]]);
    let at = |k: usize| reference.frame(b[k]).point(&q[k]);
    PointSpringEnergy {
        frames: [local.frames[0].clone(), local.frames[1].clone()],
        points: q,
        rest: at(1) - at(0),
        stiffness: SCHEMA.value(e, "k"),
    }
}

/// The point-spring element kind; it joins at stage 0A.
pub struct PointSpring;

impl PointSpring {
    /// The instances of this kind in `reference`'s model.
    fn instances<'r, S: Constant>(
        reference: &'r Reference<S>,
    ) -> impl Iterator<Item = &'r PluginElement<S>> {
        reference
            .system
            .plugin_elements
            .iter()
            .filter(|e| e.kind == KIND)
    }
}

impl Element for PointSpring {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "isotropic spring ½ k |Δ|² between two body points (a magnet-coil pair)"
    }
    fn instance_schema(&self) -> Option<InstanceSchema> {
        Some(SCHEMA)
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        Ok(Self::instances(reference)
            .map(|e| {
                let local = LocalFrames::new(system, &e.bodies);
                let label = pendkit_energy::term_label(KIND, &e.name);
                let energy = energy(reference, e, &local);
                Term::new(label, KIND, e.tag.clone(), local.coords, energy)
            })
            .collect())
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        let system = reference.system;
        Ok(Some(
            Self::instances(reference)
                .map(|e| {
                    let local = shared.frames(system, &e.bodies);
                    let label = pendkit_energy::term_label(KIND, &e.name);
                    let energy = energy(reference, e, &local);
                    TangentTerm::on_frames(label, KIND, e.tag.clone(), local, energy)
                })
                .collect(),
        ))
    }
}

pendkit_energy::register_element!(PointSpring);
