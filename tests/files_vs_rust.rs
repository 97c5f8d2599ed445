//! `quad-aligo` built from its suspension file (models/ligo/quad-aligo.toml) against the Rust
//! model the name still loads (models/ligo/src/quad.rs), two implementations of the same
//! model: equal parameters, damping, equilibria and mode frequencies to 1e-12 at every
//! stage, equal transfer functions and noise. (Every other bundled model is only a file
//! now; tests/bundled_files.rs pins them against the published tables.)
//! Tolerance: the two builds evaluate the same formulas in possibly different orders (a
//! tension as (W/n)·l/v instead of W/n, a body's height as a running sum), so they may
//! differ by rounding, ~1e-16 relative; 1e-12 leaves room for the conditioning of the
//! stiffest modes and nothing more. Transfer functions and noise amplify a one-ulp change of
//! the geometry ~1e4 times, and so do the frequencies of the stiffest modes (measured below),
//! so these are compared at 1e-11.

use pendkit::run_stage;
use pendkit_energy::{Shape, Stage, System};
use pendkit_model::{Defaults, Model, Overrides, build_with, parameters_with};

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
    pendkit_models_ligo::models()
        .into_iter()
        .find(|m| m.name() == name)
        .unwrap()
}

fn file_model(name: &str) -> &'static dyn Model {
    use pendkit::suspension::{Library as _, Suspension};
    if let Some(m) = pendkit_models::models()
        .into_iter()
        .find(|m| m.name() == name)
    {
        return m;
    }
    // a bundled file whose name still loads the Rust model (quad-aligo)
    let (path, text) = pendkit_models::Bundled.file(name).unwrap();
    let s = Suspension::from_text(&path, text, &pendkit_models::Bundled)
        .unwrap_or_else(|e| panic!("{e}"));
    Box::leak(Box::new(s))
}

/// Relative tolerance of mode frequencies, transfer functions and noise: they are ~1e4
/// times more sensitive to rounding than the geometry (see
/// `response_tolerance_clears_one_ulp_of_geometry`), so 1e-11, a few times the measured
/// one-ulp floor; equilibria, damping and parameters stay at 1e-12.
const RESPONSE_TOLERANCE: f64 = 1e-11;

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
    // the parameters: same names, definitions' values and units (the file writes a pure
    // number's unit as `-`, the Rust tables as nothing; both read as no unit)
    let (rust_params, rust_values) =
        parameters_with(&Defaults::of(rust_model(name)).unwrap(), &o).unwrap();
    let (file_params, file_values) =
        parameters_with(&Defaults::of(file_model(name)).unwrap(), &o).unwrap();
    let listed =
        |r: &pendkit_params::Resolved| r.iter().map(|(n, _)| n.to_string()).collect::<Vec<_>>();
    let rust_names = listed(&rust_values);
    let file_names = listed(&file_values);
    // the Rust tables carry derived rows that the files compute where they are used (wire
    // tensions T*, wire counts nw*, the blade count bd)
    let derived = |n: &str| ["T1", "T2", "T3", "Tn", "nw1", "nw2", "nw3", "nwn", "bd"].contains(&n);
    let only_rust: Vec<_> = rust_names
        .iter()
        .filter(|n| !file_names.contains(n) && !derived(n))
        .collect();
    let only_file: Vec<_> = file_names
        .iter()
        .filter(|n| !rust_names.contains(n))
        .collect();
    assert!(
        only_rust.is_empty() && only_file.is_empty(),
        "{name}: parameters only in Rust {only_rust:?}, only in the file {only_file:?}"
    );
    let mut unit_differences = Vec::new();
    for n in rust_names.iter().filter(|n| file_names.contains(n)) {
        close(
            rust_values.get(n).unwrap(),
            file_values.get(n).unwrap(),
            0.0,
            &format!("{name}: parameter {n}"),
        );
        let unit = |p: &pendkit_params::ParamSet| p.unit(n).unwrap_or("").to_string();
        // where the Rust model declares a unit the file must give the same one (the Rust
        // triple declares none; its file does)
        if rust_params.unit(n).is_some() && unit(&rust_params) != unit(&file_params) {
            unit_differences.push(format!(
                "{n}: {} vs {}",
                unit(&rust_params),
                unit(&file_params)
            ));
        }
    }
    assert!(
        unit_differences.is_empty(),
        "{name}: units {unit_differences:?}"
    );
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
    // what figures and reports use: names, drawing shapes, own coordinates, mode families,
    // naming schemes
    for (a, b) in rust.bodies.iter().zip(&file.bodies) {
        assert_eq!(a.name, b.name, "{label}: body");
        assert_eq!(
            a.pose_coords, b.pose_coords,
            "{label}: {} coordinates",
            a.name
        );
        assert_eq!(
            a.mode_family, b.mode_family,
            "{label}: {} mode family",
            a.name
        );
        match (a.shape, b.shape) {
            (Some(Shape::Box { half_sizes: p }), Some(Shape::Box { half_sizes: q })) => {
                for k in 0..3 {
                    close(p[k], q[k], 0.0, &format!("{label}: {} box", a.name));
                }
            }
            (p, q) => assert_eq!(p, q, "{label}: {} shape", a.name),
        }
    }
    assert_eq!(
        rust.name_schemes, file.name_schemes,
        "{label}: name schemes"
    );
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
        let (ea, eb) = (
            &a.assembled.equilibrium.coords,
            &b.assembled.equilibrium.coords,
        );
        for (c, (x, y)) in rust.coords.iter().zip(ea.iter().zip(eb)) {
            close(
                *x,
                *y,
                1.0,
                &format!("{label} {stage}: equilibrium {}", c.name),
            );
        }
        assert_eq!(a.modes.modes.len(), b.modes.modes.len());
        for (k, (ma, mb)) in a.modes.modes.iter().zip(&b.modes.modes).enumerate() {
            assert!(
                (ma.hz - mb.hz).abs() <= RESPONSE_TOLERANCE * ma.hz.abs().max(1e-3),
                "{label} {stage}: mode {k}: {} vs {} Hz",
                ma.hz,
                mb.hz
            );
        }
        if stage == Stage::S0A {
            continue;
        }
        let freqs = [0.5, 3.0, 40.0];
        let output = a
            .model
            .variables
            .iter()
            .rev()
            .find(|v| v.starts_with('x') && !v.contains('b'));
        let output = output.unwrap().clone();
        // the support's x, or the toy's one parameter
        let input = a.model.parameters.first().unwrap().clone();
        let (ta, tb) = (
            a.transfer(&input, &output, &freqs).unwrap(),
            b.transfer(&input, &output, &freqs).unwrap(),
        );
        for (p, q) in ta.iter().zip(&tb) {
            assert!(
                (p - q).norm() <= RESPONSE_TOLERANCE * p.norm(),
                "{label} {stage}: tf {p} vs {q}"
            );
        }
        let (na, nb) = (
            a.noise(&output, &freqs).unwrap(),
            b.noise(&output, &freqs).unwrap(),
        );
        for (p, q) in na.total.iter().zip(&nb.total) {
            assert!(
                (p - q).abs() <= RESPONSE_TOLERANCE * p.abs(),
                "{label} {stage}: noise {p} vs {q}"
            );
        }
    }
}

/// quad-aligo's file (tapered fibres, surface loss, blade thermoelastic loss, per-set
/// temperatures and given dilutions written as file fields) against the Rust model.
#[test]
fn quad_aligo() {
    compare("quad-aligo", &[]);
    compare(
        "quad-aligo",
        &[
            "temp_fibre=145",
            "temp_blade_2=100",
            "dilution_w1=80",
            "l3_neck=0.03",
        ],
    );
}

/// A one-ulp change of one body's nominal height (what a different but equally exact sum of
/// the same lengths gives: the file adds the stage heights one by one, the Rust model
/// multiplies) moves the chain's own mode frequencies by ~1e-12 and its
/// transfer functions by up to ~1.4e-12 relative at 0.5-40 Hz (measured here): the responses' rounding floor, which
/// [`RESPONSE_TOLERANCE`] must clear.
#[test]
fn response_tolerance_clears_one_ulp_of_geometry() {
    let (rust, _) = build_with(file_model("chain"), &overrides(&["n_stages=4"])).unwrap();
    let mut shifted = rust.clone();
    let z4 = shifted.coords.iter().position(|c| c.name == "z4").unwrap();
    shifted.coords[z4].start -= f64::EPSILON * 2.47;
    let freqs = [0.5, 3.0, 40.0];
    let mut largest = 0.0_f64;
    for stage in [Stage::S0B, Stage::S1B, Stage::S2] {
        let a = run_stage(rust.clone(), stage).unwrap();
        let b = run_stage(shifted.clone(), stage).unwrap();
        for (ma, mb) in a.modes.modes.iter().zip(&b.modes.modes) {
            largest = largest.max((ma.hz - mb.hz).abs() / ma.hz.abs().max(1e-3));
        }
        let ta = a.transfer("x00", "x4", &freqs).unwrap();
        let tb = b.transfer("x00", "x4", &freqs).unwrap();
        for (p, q) in ta.iter().zip(&tb) {
            largest = largest.max((p - q).norm() / p.norm());
        }
    }
    assert!(
        largest > 1e-14 && largest < RESPONSE_TOLERANCE / 3.0,
        "one ulp of height moves the transfer function by {largest:e}"
    );
}

/// quad-aligo with violin beads on its tapered fibres: the file's beads (each segment the
/// slice of the profile it spans, bead masses from the profile, the weight of the beads on
/// the wires above) against the Rust model's, for 1 and 5 beads (0 is `quad_aligo`), with
/// clamped joints (the default; the Rust model has no other).
#[test]
fn quad_aligo_with_beads() {
    for (beads, count) in [("n_beads=1", 1), ("n_beads=5", 5)] {
        compare("quad-aligo", &[beads]);
        // the beads are there: 4 fibres of `count` beads, x y z each
        let (file, _) = build_with(file_model("quad-aligo"), &overrides(&[beads])).unwrap();
        let bead_coords = file
            .coords
            .iter()
            .filter(|c| ["xf", "yf", "zf"].iter().any(|p| c.name.starts_with(p)))
            .count();
        assert_eq!(bead_coords, 12 * count, "{beads}: bead coordinates");
    }
}
