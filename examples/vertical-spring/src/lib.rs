//! The element-kind tutorial's kind (docs/elements.md), written against the public
//! `pendkit` crate alone: `example-vertical-spring`, a spring along the lab's vertical
//! between two body points, E = ½ k (Δz)², Δz the change of the points' height difference
//! from the model's start (a vertical blade or a magnet that holds only up and down; a
//! negative k is an anti-spring). Linking the crate registers the kind
//! (`use pendkit_example_vertical_spring as _;`); a suspension file then uses it:
//!
//! ```toml
//! [[element]]
//! kind = "example-vertical-spring"
//! name = "lift"
//! between = ["support", "mass1"]
//! points = [[0, 0, -0.6], [0, 0, 0]]
//! values = { k = "k_lift" }
//! ```

use pendkit::energy::{
    Constant, Domain, Frame, InstanceAt, InstanceKind, InstanceSchema, Lift, Stage, ValueField,
};
use pendkit::nalgebra::Vector3;

/// The kind.
pub struct VerticalSpring;

/// One instance: its points (m, body coordinates), the height difference at the start (m)
/// and the stiffness (N/m).
#[derive(Clone, Debug)]
pub struct Instance<C> {
    points: [Vector3<C>; 2],
    rest: C,
    k: C,
}

impl InstanceKind for VerticalSpring {
    const KIND: &'static str = "example-vertical-spring";
    // in the equilibrium: the spring is relaxed at the model's start
    const STAGE: Stage = Stage::S0A;
    const SUMMARY: &'static str = "spring ½ k (Δz)² along the vertical between two body points";
    const SCHEMA: InstanceSchema = InstanceSchema {
        bodies: 2,
        points: 2,
        values: &[ValueField {
            name: "k",
            unit: "N/m",
            domain: Domain::Finite,
            default: None,
            description: "vertical stiffness (negative: an anti-spring)",
        }],
    };

    type Instance<C: Constant> = Instance<C>;

    fn instance<C: Constant>(at: &InstanceAt<'_, C>) -> Instance<C> {
        Instance {
            points: [at.point(0), at.point(1)],
            rest: at.lab_point(1)[2] - at.lab_point(0)[2],
            k: at.value("k"),
        }
    }

    fn energy<C: Constant, D: Lift<C>>(s: &Instance<C>, frames: &[&Frame<D>]) -> D {
        let z = |b: usize| frames[b].point(&s.points[b])[2];
        let dz = z(1) - z(0) - D::lift(s.rest);
        (dz * dz).times(s.k * 0.5)
    }
}

pendkit::energy::register_kind!(VerticalSpring);
