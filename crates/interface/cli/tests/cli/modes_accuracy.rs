//! `pendkit modes` prints a mode's estimated accuracy when it is worse than 1e-6 relative
//! (issue 11, item 4), and that estimate bounds the error it states.

use crate::common;
use common::pendkit;

/// (frequency in Hz, stated relative accuracy) of every mode, from `pendkit modes --json`.
fn modes(args: &[&str]) -> Vec<(f64, f64)> {
    let (ok, stdout, stderr) = pendkit(&[&["modes"][..], args, &["--json"]].concat());
    assert!(ok, "{stderr}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    json["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["hz"].as_f64().unwrap(), m["accuracy"].as_f64().unwrap()))
        .collect()
}

#[test]
fn stiff_blades_print_an_accuracy_that_bounds_the_error() {
    // quad-full with the blades' non-working translations stiffened to 1e12 N/m: the
    // stiffness ratio to the pendulum modes (~1e12 / 1e1) limits the low modes' accuracy
    // to a few 1e-6. Independent reference: the well-conditioned runs at 1e9 and 1e10 N/m
    // (stated accuracy ~1e-9 and ~1e-8) follow f(k) = f∞ + c/k, which predicts f(1e12);
    // the extrapolation's own error (c/k² terms) is ~1e-3 of c/1e10, about 2e-11 relative.
    // Every mode whose stated accuracy is above 1e-6 must say so in the table, and
    // the first four modes' errors must lie within their stated accuracy.
    let stiff = |k: &str| format!("blade_stiff_translation={k}");
    let run = |k: &str| modes(&["quad-full", "--set", &stiff(k)]);
    let (a, b, c) = (run("1e9"), run("1e10"), run("1e12"));
    let mut worse = 0;
    for i in 0..4 {
        let slope = (a[i].0 - b[i].0) / (1.0 / 1e9 - 1.0 / 1e10);
        let predicted = b[i].0 - slope / 1e10 + slope / 1e12;
        let (hz, accuracy) = c[i];
        let extrapolation = 1e-3 * (slope / 1e10).abs();
        assert!(
            (hz - predicted).abs() <= accuracy * hz + extrapolation,
            "mode {}: {hz} vs predicted {predicted} (stated {accuracy:e})",
            i + 1
        );
        worse += usize::from(accuracy > 1e-6);
    }
    assert!(
        worse >= 2,
        "the stiff blades leave the low modes at ~1e-6: {c:?}"
    );
    let (ok, table, stderr) = pendkit(&["modes", "quad-full", "--set", &stiff("1e12")]);
    assert!(ok, "{stderr}");
    let flagged: Vec<&str> = table.lines().filter(|l| l.contains("(accuracy ")).collect();
    assert_eq!(
        flagged.len(),
        c.iter().filter(|(_, acc)| *acc > 1e-6).count(),
        "{table}"
    );
    assert!(flagged[0].contains("relative)"), "{}", flagged[0]);
}

#[test]
fn a_nominal_quad_prints_no_accuracy() {
    // every mode of the nominal quad is known to better than 1e-6 relative
    let (ok, table, stderr) = pendkit(&["modes", "quad"]);
    assert!(ok, "{stderr}");
    assert!(!table.contains("accuracy"), "{table}");
    assert!(modes(&["quad"]).iter().all(|(_, acc)| *acc <= 1e-6));
}

#[test]
fn every_command_on_a_neutral_model_names_the_neutral_direction() {
    // issue 35, item 3: a body on two wires in one vertical plane, attached level with its
    // centre of mass, has no pitch stiffness before bending joins (stage 1A): `tf` and
    // `noise` printed their numbers without a word about it. Now every command that
    // answers from that model says which direction is neutral and how to remove it, as
    // `modes` does in its table.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("neutral-note");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("plane.toml");
    std::fs::write(
        &file,
        r#"name = "plane"
[parameters]
m = { value = 10, unit = "kg", description = "the body's mass" }
[materials.steel]
youngs_modulus = 200e9
poisson_ratio = 0.29
density = 7800
loss_angle = 1e-4
[bodies.support]
coordinates = "0"
driven = true
[bodies.top]
coordinates = "1"
mass = "m"
inertia = [0.1, 0.1, 0.1]
[stages.top]
from = "support"
wires = { upper = { at = [0, 0.1, 0], mirror = "y" }, lower = { at = [0, 0.1, 0], mirror = "y" }, length = 0.4, radius = 0.3e-3, material = "steel" }
"#,
    )
    .unwrap();
    let file = file.to_str().unwrap();
    let note = "is a neutral direction (pitch1 100%)";
    let (ok, stdout, stderr) = pendkit(&["modes", file, "--stage", "1a"]);
    assert!(ok && stdout.contains(note), "{stdout}{stderr}");
    for args in [
        &[
            "tf", file, "--stage", "1a", "--input", "x0", "--output", "x1",
        ][..],
        &["noise", file, "--stage", "1a", "--output", "x1"][..],
    ] {
        let (ok, _, stderr) = pendkit(args);
        assert!(ok, "{args:?}: {stderr}");
        assert!(
            stderr.contains(note) && stderr.contains("break-off"),
            "{args:?}: {stderr}"
        );
    }
    // a sweep says it at each step that has one, with the step's values
    let (ok, _, stderr) = pendkit(&[
        "sweep",
        file,
        "--stage",
        "1a",
        "--vary",
        "m=10:20:2",
        "--tf",
        "x0:x1",
        "--freqs",
        "1",
    ]);
    assert!(ok, "{stderr}");
    for step in ["m=10", "m=20"] {
        assert!(
            stderr.contains(&format!("note: at {step}: mode 1 {note}")),
            "{step}: {stderr}"
        );
    }
    // the report's stability verdict says "neutral", not "stable", and names the mode
    let report = dir.join("report");
    let (ok, _, stderr) = pendkit(&[
        "report",
        file,
        "--stage",
        "1a",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(ok && stderr.contains(note), "{stderr}");
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(
        html.contains("class=\"verdict neutral\">Neutral:") && html.contains(note),
        "the report's verdict"
    );
    // the trade-off chart names the variants that have one (stages 0B and 1A here; from
    // 1B on, wire bending resists the pitch)
    let chart = dir.join("tradeoff");
    let (ok, stdout, stderr) = pendkit(&[
        "tradeoff",
        file,
        "--output",
        "x1",
        "--out",
        chart.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let neutral: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("neutral "))
        .collect();
    assert_eq!(neutral.len(), 2, "{stdout}");
    assert!(
        neutral[0].starts_with("neutral plane s0B: mode 1 is neutral")
            && neutral[1].starts_with("neutral plane s1A: mode 1 is neutral"),
        "{stdout}"
    );
}
