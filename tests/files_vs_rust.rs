//! Every bundled model built from its suspension file against the same model built by the
//! Rust code it replaces (models/basic, models/ligo before the switch): equal equilibria and
//! mode frequencies to 1e-12 at every stage, equal damping, transfer functions and noise.
//! Tolerance: the two builds evaluate the same formulas in possibly different orders (a
//! tension as (W/n)·l/v instead of W/n), so they may differ by rounding, ~1e-16 relative;
//! 1e-12 leaves room for the conditioning of the stiffest modes and nothing more.

use pendkit::run_stage;
use pendkit_energy::{Stage, System};
use pendkit_model::{Model, Overrides, build_with};

fn overrides(sets: &[&str]) -> Overrides {
    Overrides {
        parameters: sets
            .iter()
            .map(|s| {
                let (n, v) = s.split_once('=').unwrap();
                (n.to_string(), v.to_string())
            })
            .collect(),
        ..Default::default()
    }
}

fn rust_model(name: &str) -> &'static dyn Model {
    pendkit_models_basic::models()
        .into_iter()
        .chain(pendkit_models_ligo::models())
        .find(|m| m.name() == name)
        .unwrap()
}

fn file_model(name: &str) -> &'static dyn Model {
    pendkit_models::models()
        .into_iter()
        .find(|m| m.name() == name)
        .unwrap()
}

#[track_caller]
fn close(a: f64, b: f64, scale: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-12 * scale.max(a.abs()).max(b.abs()),
        "{what}: {a} vs {b} (rel {:.2e})",
        ((a - b) / b).abs()
    );
}

fn compare(name: &str, sets: &[&str]) {
    let o = overrides(sets);
    let (rust, _) = build_with(rust_model(name), &o).unwrap();
    let (file, _) = build_with(file_model(name), &o).unwrap_or_else(|e| panic!("{name}: {e}"));
    let label = format!("{name} {sets:?}");
    compare_systems(&label, &rust, &file);
}

fn compare_systems(label: &str, rust: &System, file: &System) {
    let names = |s: &System| s.coords.iter().map(|c| c.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(rust), names(file), "{label}: coordinates");
    assert_eq!(rust.bodies.len(), file.bodies.len(), "{label}: bodies");
    assert_eq!(rust.wires.len(), file.wires.len(), "{label}: wires");
    assert_eq!(rust.springs.len(), file.springs.len(), "{label}: springs");
    assert_eq!(rust.tags(), file.tags(), "{label}: tags");
    assert_eq!(rust.temperature, file.temperature);
    for tag in rust.tags() {
        for f in [0.3, 10.0, 300.0] {
            let (a, b) = (rust.damping.at(&tag, f), file.damping.at(&tag, f));
            close(a.0, b.0, 0.0, &format!("{label}: damping {tag} re"));
            close(a.1, b.1, 0.0, &format!("{label}: damping {tag} im"));
        }
    }
    for (c, (x, y)) in rust
        .coords
        .iter()
        .zip(rust.start().iter().zip(file.start()))
    {
        close(*x, y, 1.0, &format!("{label}: start of {}", c.name));
    }
    for stage in Stage::ALL {
        let a = run_stage(rust.clone(), stage).unwrap();
        let b = run_stage(file.clone(), stage).unwrap();
        let (ea, eb) = (&a.assembled.equilibrium.coords, &b.assembled.equilibrium.coords);
        for (c, (x, y)) in rust.coords.iter().zip(ea.iter().zip(eb)) {
            close(*x, *y, 1.0, &format!("{label} {stage}: equilibrium {}", c.name));
        }
        assert_eq!(a.modes.modes.len(), b.modes.modes.len());
        for (k, (ma, mb)) in a.modes.modes.iter().zip(&b.modes.modes).enumerate() {
            close(ma.hz, mb.hz, 0.0, &format!("{label} {stage}: mode {k}"));
        }
        if stage == Stage::S0A {
            continue;
        }
        let freqs = [0.5, 3.0, 40.0];
        let output = a.model.variables.iter().rev().find(|v| v.starts_with('x') && !v.contains('b'));
        let output = output.unwrap().clone();
        // the support's x, or the toy's one parameter
        let input = a.model.parameters.first().unwrap().clone();
        let (ta, tb) = (
            a.transfer(&input, &output, &freqs).unwrap(),
            b.transfer(&input, &output, &freqs).unwrap(),
        );
        for (p, q) in ta.iter().zip(&tb) {
            assert!((p - q).norm() <= 1e-12 * p.norm(), "{label} {stage}: tf {p} vs {q}");
        }
        let (na, nb) = (
            a.noise(&output, &freqs).unwrap(),
            b.noise(&output, &freqs).unwrap(),
        );
        for (p, q) in na.total.iter().zip(&nb.total) {
            close(*p, *q, 0.0, &format!("{label} {stage}: noise"));
        }
    }
}

#[test]
fn small_models() {
    for name in ["toy", "pendulum", "double-pendulum", "rigid-body"] {
        compare(name, &[]);
    }
    compare("pendulum", &["hinged_bottom=0", "a_fibre=0"]);
    compare("rigid-body", &["hinged_bottom=1", "d_fibre=0.002"]);
}

#[test]
fn chains() {
    for n in ["1", "4", "7"] {
        compare("chain", &[&format!("n_stages={n}")]);
    }
}

#[test]
fn quads() {
    for name in ["quad", "quad-lite", "quad-full", "quad-lateral", "quad-v5"] {
        compare(name, &[]);
    }
    compare("quad", &["n_beads=2", "m3=50"]);
    compare("quad-lite", &["blade_tip_mass=0.2"]);
}

#[test]
fn triples() {
    for name in ["triple", "triple-lite", "triple-full", "triple-lateral", "triple-v5"] {
        compare(name, &[]);
    }
    compare("triple", &["fibre_silica=1", "n_beads=3"]);
}
