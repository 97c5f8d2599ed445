//! The builder as a downstream tool would use it: a pendulum built by hand, with the
//! per-coordinate constraint stiffness, extra potential terms before and after the
//! equilibrium, a constrained body (pose entries that are expressions of a coordinate),
//! full inertia tensors with products of inertia, and the lab-frame mode table.

use nalgebra::{Matrix3, Vector3};
use pendkit::run_stage;
use pendkit_dynamics::lab_motion;
use pendkit_model::{BodySpec, SystemBuilder};
use pendkit_system::{
    EndDirection, ExtraPhase, Stage, System, Wire, WireEnd, WireSection, WireTags,
};

const G: f64 = 9.81;
const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// A 10 kg point mass on one 1 m steel wire, hinged at both ends.
fn pendulum(extra: impl FnOnce(&mut SystemBuilder)) -> System {
    let mut b = SystemBuilder::new(G);
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    for (n, v) in [("x1", 0.0), ("y1", 0.0), ("z1", -1.0)] {
        b.variable(n, v).unwrap();
    }
    let bob = b
        .body(
            BodySpec::new("bob")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(10.0),
        )
        .unwrap();
    let hinge = |body| WireEnd {
        body,
        point: Vector3::zeros(),
        direction: EndDirection::Hinged,
    };
    let tags = WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    };
    let section = WireSection::round(0.5e-3, 200e9, 80e9, 7800.0);
    b.wire(Wire::from_tension(
        "wire",
        [hinge(support), hinge(bob)],
        section,
        1.0,
        10.0 * G,
        tags,
    ))
    .unwrap();
    extra(&mut b);
    b.build().unwrap()
}

fn hz(system: System, label: &str) -> f64 {
    let r = run_stage(system, Stage::S0A).unwrap();
    r.modes.modes.iter().find(|m| m.label == label).unwrap().hz
}

#[test]
fn constraint_stiffness_adds_to_the_coordinate() {
    // ½ k (x1 − x1_eq)² adds k to K_xx: f = sqrt((m g/l + k)/m)/2π
    let free = hz(pendulum(|_| {}), "x1");
    assert!((free - (G / 1.0f64).sqrt() / TWO_PI).abs() < 1e-10);
    let held = hz(
        pendulum(|b| b.constraint_stiffness("x1", 500.0).unwrap()),
        "x1",
    );
    assert!((held - ((10.0 * G + 500.0) / 10.0).sqrt() / TWO_PI).abs() < 1e-10);
}

#[test]
fn extra_terms_before_and_after_the_equilibrium() {
    // A constant force F = 1 N along x before the equilibrium (energy −F x1): the bob
    // settles where the wire's pull balances weight and force, T = sqrt((m g)² + F²) along
    // the wire, which stretches to l = l0 + T/k: x1 = F l / T.
    let system = pendulum(|b| {
        b.extra_term("push", "-1*x1", "push", ExtraPhase::BeforeEquilibrium)
            .unwrap()
    });
    let x1 = system.coord("x1").unwrap();
    let r = run_stage(system, Stage::S0A).unwrap();
    let t = ((10.0 * G).powi(2) + 1.0f64).sqrt();
    let k = 200e9 * std::f64::consts::PI * 0.5e-3f64.powi(2) / 1.0;
    let length = 1.0 - 10.0 * G / k + t / k;
    let expected = length / t;
    assert!((r.assembled.equilibrium.coords[x1] - expected).abs() < 1e-10);
    // After the equilibrium, a spring about the equilibrium value (`x1.eq`) changes the
    // stiffness but not the equilibrium.
    let stiffer = pendulum(|b| {
        b.extra_term(
            "spring",
            "0.5*200*(x1 - x1.eq)^2",
            "spring",
            ExtraPhase::AfterEquilibrium,
        )
        .unwrap()
    });
    assert!((hz(stiffer, "x1") - ((10.0 * G + 200.0) / 10.0).sqrt() / TWO_PI).abs() < 1e-10);
    // an unknown coordinate in an extra term is a clear error
    let mut b = SystemBuilder::new(G);
    let e = b
        .extra_term("bad", "x9^2", "t", ExtraPhase::BeforeEquilibrium)
        .unwrap_err();
    assert!(e.to_string().contains("'x9'"), "{e}");
}

#[test]
fn constrained_body_on_an_inclined_track() {
    // A 2 kg body sliding without rotation along a line at 30° to the horizontal in the
    // x–z plane (pose x = s cos θ, z = s sin θ), on a spring k = 50 N/m along x to the
    // support: its one coordinate s has mass 2 kg and stiffness k cos²θ, plus gravity's
    // constant pull, which only shifts the equilibrium.
    let (theta, k, m) = (30f64.to_radians(), 50.0, 2.0);
    let mut b = SystemBuilder::new(G);
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    b.variable("s", 0.0).unwrap();
    let (c, sn) = (theta.cos().to_string(), theta.sin().to_string());
    let slider = b
        .body(
            BodySpec::new("slider")
                .pose([&format!("s*{c}"), "0", &format!("s*{sn}"), "0", "0", "0"])
                .mass(m),
        )
        .unwrap();
    let end = |body| pendkit_system::SpringEnd {
        body,
        point: Vector3::zeros(),
        angles: [0.0; 3],
    };
    let stiffness =
        nalgebra::Matrix6::from_diagonal(&nalgebra::Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
    b.spring(
        "k",
        [end(support), end(slider)],
        stiffness,
        nalgebra::Vector6::zeros(),
        "k",
    )
    .unwrap();
    let r = run_stage(b.build().unwrap(), Stage::S0A).unwrap();
    let f = r.modes.modes[0].hz;
    assert!((f - (k * theta.cos().powi(2) / m).sqrt() / TWO_PI).abs() < 1e-10);
    // equilibrium: k (s cos θ) cos θ + m g sin θ = 0
    let s_eq = -m * G * theta.sin() / (k * theta.cos().powi(2));
    assert!((r.assembled.equilibrium.coords[r.system.coord("s").unwrap()] - s_eq).abs() < 1e-10);
}

#[test]
fn products_of_inertia_and_the_lab_table() {
    // A free-floating body held only by rotational constraint springs k about its own
    // coordinates, with inertia products: the yaw/pitch/roll frequencies are the
    // eigenvalues of the inertia pencil, and the lab table reproduces the mode vector
    // (at zero angles lab yaw/pitch/roll equal the coordinates).
    let inertia = Matrix3::new(0.5, 0.1, 0.0, 0.1, 0.4, 0.05, 0.0, 0.05, 0.3);
    let mut b = SystemBuilder::new(0.0);
    for n in ["yaw1", "pitch1", "roll1"] {
        b.variable(n, 0.0).unwrap();
        b.constraint_stiffness(n, 2.0).unwrap();
    }
    b.body(
        BodySpec::new("body")
            .pose(["0", "0", "0", "yaw1", "pitch1", "roll1"])
            .mass(1.0)
            .inertia(inertia),
    )
    .unwrap();
    let r = run_stage(b.build().unwrap(), Stage::S0A).unwrap();
    // with K = 2 I₃ the modes are ω² = 2/μ for the eigenvalues μ of the inertia matrix
    // expressed in the coordinates' order (yaw ↔ z, pitch ↔ y, roll ↔ x)
    let permuted = Matrix3::new(0.3, 0.05, 0.0, 0.05, 0.4, 0.1, 0.0, 0.1, 0.5);
    let mut expected: Vec<f64> = permuted
        .symmetric_eigenvalues()
        .iter()
        .map(|mu: &f64| (2.0 / mu).sqrt() / TWO_PI)
        .collect();
    expected.sort_by(f64::total_cmp);
    for (m, e) in r.modes.modes.iter().zip(&expected) {
        assert!((m.hz - e).abs() < 1e-10 * e, "{} vs {e}", m.hz);
        let lab = lab_motion(
            &r.system,
            &r.assembled.layout,
            &r.assembled.equilibrium.coords,
            m,
        )
        .expect("sizes of the library's own run match");
        for k in 0..3 {
            assert!((lab[0].rotation[k] - m.vector[k]).abs() < 1e-12);
        }
    }
}
