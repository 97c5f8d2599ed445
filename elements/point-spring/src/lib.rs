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
//! The whole kind is its schema and one energy function ([`InstanceKind`]); every
//! derivative the calculations need comes from that function.

use nalgebra::Vector3;
use pendkit_energy::{Domain, InstanceAt, InstanceKind, InstanceSchema, ValueField};
use pendkit_geometry::Frame;
use pendkit_rotations::{Constant, Lift};
use pendkit_system::Stage;

/// The point-spring element kind.
pub struct PointSpring;

/// One spring: its points (m, body coordinates), rest separation (m) and stiffness (N/m).
#[derive(Clone, Debug)]
pub struct Spring<C> {
    points: [Vector3<C>; 2],
    rest: Vector3<C>,
    stiffness: C,
}

impl InstanceKind for PointSpring {
    const KIND: &'static str = "point-spring";
    const STAGE: Stage = Stage::S0A;
    const SUMMARY: &'static str =
        "isotropic spring ½ k |Δ|² between two body points (a magnet-coil pair)";
    const SCHEMA: InstanceSchema = InstanceSchema {
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

    type Instance<C: Constant> = Spring<C>;

    fn instance<C: Constant>(at: &InstanceAt<'_, C>) -> Spring<C> {
        Spring {
            points: [at.point(0), at.point(1)],
            rest: at.lab_point(1) - at.lab_point(0),
            stiffness: at.value("k"),
        }
    }

    fn energy<C: Constant, D: Lift<C>>(s: &Spring<C>, frames: &[&Frame<D>]) -> D {
        let p0 = frames[0].point(&s.points[0]);
        let p1 = frames[1].point(&s.points[1]);
        let d = |i: usize| p1[i] - p0[i] - D::lift(s.rest[i]);
        let (dx, dy, dz) = (d(0), d(1), d(2));
        (dx * dx + dy * dy + dz * dz).times(s.stiffness * 0.5)
    }
}

pendkit_energy::register_kind!(PointSpring);
