//! The equilibrium search: zero net force at the solution, wires at their nominal lengths,
//! pinned coordinates held, and convergence from poor starts.

use pendkit::Case;
use pendkit_assembly::{EquilibriumOptions, solve_equilibrium};
use pendkit_energy::{Reference, registry};
use pendkit_system::System;

fn system(model: &str) -> System {
    Case::model(model).unwrap().build().unwrap().0
}

fn set_start(system: &mut System, name: &str, value: f64) {
    let i = system.coord(name).unwrap();
    system.coords[i].start = value;
}

/// Net generalised force on every variable and float, from all stage-0A terms at `x`.
fn net_forces(system: &System, x: &[f64]) -> Vec<f64> {
    let mut g = vec![0.0; x.len()];
    let reference = Reference::new(system, x);
    for kind in registry() {
        for term in kind.terms(&reference).unwrap() {
            let d = term.derivatives(x).unwrap();
            for (a, &i) in term.coords.iter().enumerate() {
                g[i] += d.gradient[a];
            }
        }
    }
    g
}

#[test]
fn rigid_body_converges_from_a_tilted_start_to_the_nominal_geometry() {
    let mut s = system("rigid-body");
    for (name, v) in [
        ("x1", 0.05),
        ("y1", -0.03),
        ("z1", -0.55),
        ("yaw1", 0.2),
        ("pitch1", 0.3),
        ("roll1", -0.25),
    ] {
        set_start(&mut s, name, v);
    }
    let eq = solve_equilibrium(&s, &EquilibriumOptions::default()).unwrap();
    // forces vanish (weight 392 N; residual below 1e-11 of it, rounding of a few ulps)
    for (i, f) in net_forces(&s, &eq.coords).iter().enumerate() {
        if s.coords[i].kind != pendkit_system::CoordKind::Parameter {
            assert!(f.abs() < 1e-8, "{}: {f}", s.coords[i].name);
        }
    }
    // every wire is back at its nominal 0.6 m (the model derives l0 from the tension)
    let reference = Reference::new(&s, &eq.coords);
    for w in &s.wires {
        assert!(
            (reference.wire_length(w).unwrap() - 0.6).abs() < 1e-12,
            "{}",
            w.name
        );
        assert!((reference.wire_tension(w).unwrap() - 40.0 * 9.81 / 4.0).abs() < 1e-8);
    }
    // and the body hangs level at z = -(l + d); Newton stops once its next step would be
    // below 1e-12 m or rad, so the position is good to that order
    for (name, v) in [
        ("x1", 0.0),
        ("y1", 0.0),
        ("z1", -0.61),
        ("yaw1", 0.0),
        ("pitch1", 0.0),
        ("roll1", 0.0),
    ] {
        let i = s.coord(name).unwrap();
        assert!(
            (eq.coords[i] - v).abs() < 1e-11,
            "{name} = {}",
            eq.coords[i]
        );
    }
}

#[test]
fn pinned_coordinate_stays_put() {
    let mut s = system("pendulum");
    set_start(&mut s, "x1", 0.01);
    set_start(&mut s, "z1", -0.5);
    let i = s.coord("x1").unwrap();
    s.coords[i].pinned = true;
    let eq = solve_equilibrium(&s, &EquilibriumOptions::default()).unwrap();
    assert_eq!(eq.coords[i], 0.01);
    // the free coordinates balance: z1 and y1 carry no net force
    let forces = net_forces(&s, &eq.coords);
    for name in ["y1", "z1"] {
        assert!(forces[s.coord(name).unwrap()].abs() < 1e-8);
    }
    // held 10 mm aside, the pendulum leans on the pin with the restoring force ≈ (mg/l) x
    assert!((forces[i] - 40.0 * 9.81 / 0.6 * 0.01).abs() < 0.05);
}

#[test]
fn floats_settle_between_springs() {
    // toy with the support moved to s = 1 mm: the float sits where the two springs balance.
    let mut s = system("toy");
    set_start(&mut s, "s", 1e-3);
    set_start(&mut s, "x", 3e-3);
    let q = s.coord("q").unwrap();
    let x = s.coord("x").unwrap();
    let eq = solve_equilibrium(&s, &EquilibriumOptions::default()).unwrap();
    // no gravity, no preload: everything moves with the support
    assert!((eq.coords[q] - 1e-3).abs() < 1e-15);
    assert!((eq.coords[x] - 1e-3).abs() < 1e-15);
}
