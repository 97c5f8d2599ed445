//! Example of adding an element kind from outside the repository's element crates, without
//! touching the core: `example-point-spring`, a copy of the shipped `point-spring` kind
//! (elements/point-spring) under its own name. An isotropic spring between two body points, E = ½ k |Δ|², Δ the change of the points'
//! separation vector from the reference configuration (a magnet-coil pair; a negative k is
//! a magnetic anti-spring). A model adds instances as `PluginElement { kind: "example-point-spring",
//! bodies: [a, b], points: [pa, pb], values: {"k": N/m}, tag, .. }`; linking this crate
//! (any `use pendkit_example_point_spring as _;`) registers the kind.

use nalgebra::Vector3;
use pendkit_energy::{
    Domain, Element, EnergyError, InstanceSchema, LocalFrames, Potential, Reference, Term,
    ValueField,
};
use pendkit_geometry::FrameMap;
use pendkit_rotations::Real;
use pendkit_system::Stage;

/// What an instance needs: two bodies, a point on each, the stiffness k. Every instance is
/// checked against it before any term is built, so `terms` reads the values unchecked.
pub const SCHEMA: InstanceSchema = InstanceSchema {
    bodies: 2,
    points: 2,
    values: &[ValueField {
        name: "k",
        unit: "N/m",
        domain: Domain::Finite,
        default: None,
        description: "stiffness (negative: a magnetic anti-spring)",
    }],
};

/// ½ k |(p1 − p0) − d_ref|² for one instance.
#[derive(Clone, Debug)]
struct PointSpringEnergy {
    frames: [FrameMap; 2],
    points: [Vector3<f64>; 2],
    /// Separation at the reference configuration (m).
    rest: Vector3<f64>,
    /// k (N/m).
    stiffness: f64,
}

impl Potential for PointSpringEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let p0 = self.frames[0].eval(x).point(&self.points[0]);
        let p1 = self.frames[1].eval(x).point(&self.points[1]);
        let d = p1 - p0 - self.rest.map(D::from);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * (0.5 * self.stiffness)
    }
}

/// The point-spring element kind; it joins at stage 0A.
pub struct PointSpring;

impl Element for PointSpring {
    fn kind(&self) -> &'static str {
        "example-point-spring"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "isotropic spring ½ k |Δ|² between two body points (an example kind from outside)"
    }
    fn instance_schema(&self) -> Option<InstanceSchema> {
        Some(SCHEMA)
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        let mut terms = Vec::new();
        for e in system
            .plugin_elements
            .iter()
            .filter(|e| e.kind == self.kind())
        {
            // checked against SCHEMA: two bodies, two points, k finite
            let (b, q) = ([e.bodies[0], e.bodies[1]], [e.points[0], e.points[1]]);
            let at = |k: usize| reference.frame(b[k]).point(&q[k]);
            let local = LocalFrames::new(system, &b);
            terms.push(Term::new(
                format!("example-point-spring {}", e.name),
                "example-point-spring",
                e.tag.clone(),
                local.coords,
                PointSpringEnergy {
                    frames: [local.frames[0].clone(), local.frames[1].clone()],
                    points: q,
                    rest: at(1) - at(0),
                    stiffness: SCHEMA.value(e, "k"),
                },
            ));
        }
        Ok(terms)
    }
}

pendkit_energy::register_element!(PointSpring);
