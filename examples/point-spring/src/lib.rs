//! Example of adding an element kind as its own crate, without touching the core: an
//! isotropic spring between two body points, E = ½ k |Δ|², Δ the change of the points'
//! separation vector from the reference configuration (a magnet-coil pair; a negative k is
//! a magnetic anti-spring). A model adds instances as `PluginElement { kind: "point-spring",
//! bodies: [a, b], points: [pa, pb], values: {"k": N/m}, tag, .. }`; linking this crate
//! (any `use pendkit_example_point_spring as _;`) registers the kind.

use nalgebra::Vector3;
use pendkit_energy::{Element, EnergyError, LocalFrames, Potential, Reference, Term};
use pendkit_geometry::FrameMap;
use pendkit_rotations::Real;
use pendkit_system::Stage;

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
        "point-spring"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "isotropic spring ½ k |Δ|² between two body points (example plug-in)"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        let mut terms = Vec::new();
        for e in system
            .plugin_elements
            .iter()
            .filter(|e| e.kind == self.kind())
        {
            let fail = |message: &str| EnergyError::Element {
                kind: "point-spring",
                element: e.name.clone(),
                message: message.to_string(),
            };
            let ([b0, b1], [q0, q1]) = (
                <[usize; 2]>::try_from(e.bodies.as_slice())
                    .map_err(|_| fail("needs two bodies"))?,
                <[Vector3<f64>; 2]>::try_from(e.points.as_slice())
                    .map_err(|_| fail("needs two points"))?,
            );
            let stiffness = *e
                .values
                .get("k")
                .ok_or_else(|| fail("needs a value 'k' (N/m)"))?;
            let at = |b: usize, p: &Vector3<f64>| reference.frame(b).point(p);
            let local = LocalFrames::new(system, &[b0, b1]);
            terms.push(Term::new(
                format!("point-spring {}", e.name),
                "point-spring",
                e.tag.clone(),
                local.coords,
                PointSpringEnergy {
                    frames: [local.frames[0].clone(), local.frames[1].clone()],
                    points: [q0, q1],
                    rest: at(b1, &q1) - at(b0, &q0),
                    stiffness,
                },
            ));
        }
        Ok(terms)
    }
}

pendkit_energy::register_element!(PointSpring);
