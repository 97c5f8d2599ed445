//! The tutorial's kind from a suspension file: the bundled `pendulum` (a 40 kg point mass
//! on four silica fibres of radius 0.2 mm and length 0.6 m) with a vertical spring k_lift
//! between the support and the mass. Closed forms (docs/reference-values.md §0 for the
//! pendulum alone): the swings keep ω² = g/l, the fibres' pull alone, since the spring
//! holds only vertically; the bounce is ω² = (k_fibres + k_lift)/m with k_fibres = 4 E π r²/l
//! the fibres' axial stiffness. Tolerance 1e-9 relative: the model is exactly this at
//! stage 0A, only the eigensolver's rounding remains.
//!
//! The tutorial's own `pendkit` binary (src/main.rs, three lines over `pendkit_cli::main`)
//! then lists the kind and runs a file that uses it, with the same bounce.

use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;

use pendkit::{Case, Stage, run_stage};
use pendkit_example_vertical_spring as _;

const FILE: &str = r#"
extends = "pendulum"
[parameters]
k_lift = { value = 5000, unit = "N/m", description = "the vertical spring" }

[[element]]
kind = "example-vertical-spring"
name = "lift"
between = ["support", "mass1"]
points = [[0, 0, -0.6], [0, 0, 0]]
values = { k = "k_lift" }
tag = "lift"
"#;

#[test]
fn the_kind_from_a_file_stiffens_only_the_bounce() {
    let case = Case::from_text(Path::new("lifted.toml"), FILE).unwrap();
    let (system, _) = case.build().unwrap();
    let r = run_stage(system, Stage::S0A).unwrap();
    let hz = |w2: f64| w2.sqrt() / (2.0 * PI);
    let (m, l, g, k) = (40.0, 0.6, 9.81, 5000.0);
    let k_fibres = 4.0 * 72e9 * PI * 0.2e-3f64.powi(2) / l;
    let expected = [hz(g / l), hz(g / l), hz((k_fibres + k) / m)];
    let got: Vec<f64> = r.modes.modes.iter().map(|mode| mode.hz).collect();
    assert_eq!(got.len(), 3);
    for (f, want) in got.iter().zip(expected) {
        assert!((f - want).abs() <= 1e-9 * want, "{f} Hz against {want} Hz");
    }
}

#[test]
fn the_kind_is_listed_with_its_crate() {
    let registration = pendkit::energy::registrations()
        .iter()
        .find(|r| r.element.kind() == "example-vertical-spring")
        .expect("linked, so registered");
    assert_eq!(registration.crate_name, "pendkit-example-vertical-spring");
}

// The tutorial's own `pendkit` binary.

fn pendkit(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit-with-vertical-spring"))
        .args(args)
        .output()
        .unwrap();
    let text = |b: Vec<u8>| String::from_utf8(b).unwrap();
    (out.status.success(), text(out.stdout), text(out.stderr))
}

#[test]
fn the_own_binary_lists_the_kind_with_its_schema() {
    let (ok, stdout, stderr) = pendkit(&["elements", "example-vertical-spring"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("vertical stiffness") && stdout.contains("N/m"),
        "{stdout}"
    );
    let (ok, stdout, _) = pendkit(&["elements"]);
    assert!(
        ok && stdout.contains("pendkit-example-vertical-spring"),
        "{stdout}"
    );
}

#[test]
fn the_own_binary_runs_a_file_that_uses_the_kind() {
    let dir = std::env::temp_dir().join(format!("vertical-spring-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("lifted.toml");
    std::fs::write(
        &file,
        r#"extends = "pendulum"
[parameters]
k_lift = { value = 5000, unit = "N/m", description = "the vertical spring" }
[[element]]
kind = "example-vertical-spring"
name = "lift"
between = ["support", "mass1"]
points = [[0, 0, -0.6], [0, 0, 0]]
values = { k = "k_lift" }
"#,
    )
    .unwrap();
    let (ok, stdout, stderr) = pendkit(&["modes", file.to_str().unwrap(), "--json"]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(ok, "{stderr}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let hz: Vec<f64> = json["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["hz"].as_f64().unwrap())
        .collect();
    // the bounce: ω² = (4 E π r²/l + k)/m for the pendulum's fibres and the spring
    let bounce = ((4.0 * 72e9 * PI * 0.2e-3f64.powi(2) / 0.6 + 5000.0) / 40.0).sqrt() / (2.0 * PI);
    let top = hz.iter().cloned().fold(0.0, f64::max);
    assert!(
        (top - bounce).abs() <= 1e-9 * bounce,
        "{top} Hz against {bounce} Hz"
    );
}
