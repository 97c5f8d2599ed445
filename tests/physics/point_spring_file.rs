//! A point spring declared in a suspension file (`[[element]]`) between a pendulum's bob and
//! the support: the closed form of a point mass m on vertical hinged fibres of length l
//! with an isotropic spring k at the mass, ω² = g/l + k/m for the swing along x (the
//! fibres' pull gives m g / l; the spring adds k in every direction; docs/reference-values.md
//! §0 for the pendulum alone). `--set` (an override) changes k, and the exact sensitivity of
//! that mode to k is the closed form's df/dk = 1/(8π² m f).

use std::f64::consts::PI;
use std::path::Path;

use pendkit::{Case, Override, Stage, run_stage};

const M: f64 = 40.0;
const L: f64 = 0.6;
const G: f64 = 9.81;

/// The hinged bob with a point spring `k_magnet` (N/m) to the support, at the bob's centre
/// of mass and 0.6 m above it on the support.
fn file() -> String {
    let mut text = pendkit_tests::hinged_bob(
        r#"m = { value = 40, unit = "kg", description = "the bob" }
k_magnet = { value = 100, unit = "N/m", description = "the magnet's stiffness" }"#,
        L,
    );
    text.push_str(
        r#"
[[element]]
kind = "point-spring"
name = "coil_magnet_1"
between = ["bob", "support"]
points = [[0, 0, 0], ["0", "0", "0"]]
values = { k = "k_magnet" }
tag = "magnet"
"#,
    );
    text
}

/// The closed form's swing frequency along x (Hz).
fn swing_hz(k: f64) -> f64 {
    (G / L + k / M).sqrt() / (2.0 * PI)
}

/// The case's mode frequencies at stage 0A (Hz), ascending.
fn modes_hz(case: &Case) -> Vec<f64> {
    let (system, _) = case.build().unwrap();
    let r = run_stage(system, Stage::S0A).unwrap();
    r.modes.modes.iter().map(|m| m.hz).collect()
}

#[test]
fn a_point_spring_from_a_file_stiffens_the_pendulum_as_the_closed_form_says() {
    let case = Case::from_text(Path::new("magnet.toml"), &file()).unwrap();
    // x and y swing alike (the spring is isotropic, the fibres' pull too): the two lowest
    // modes. 1e-9 relative: the closed form is exact for this model at stage 0A (the
    // fibres' length at equilibrium is l, their pull m g), so only rounding of the
    // eigenvalues remains, far below it.
    let hz = modes_hz(&case);
    let f = swing_hz(100.0);
    for mode in &hz[..2] {
        assert!((mode - f).abs() < 1e-9 * f, "{mode} vs {f}");
    }
    // an override of the parameter behind `values.k` changes the spring
    let stiffer = case.with([Override::value("k_magnet", 400.0)]).unwrap();
    let f = swing_hz(400.0);
    let hz = modes_hz(&stiffer);
    assert!((hz[0] - f).abs() < 1e-9 * f, "{} vs {f}", hz[0]);
}

#[test]
fn the_modes_sensitivity_to_the_springs_parameter_is_the_closed_forms() {
    use pendkit::sensitivity::{SensitivityRequest, sensitivities};
    let case = Case::from_text(Path::new("magnet.toml"), &file()).unwrap();
    let request = SensitivityRequest {
        parameters: Some(vec!["k_magnet".to_string()]),
        ..SensitivityRequest::modes(Stage::S0A)
    };
    let s = sensitivities(&case, &request).unwrap();
    // f = sqrt(g/l + k/m)/2π: df/dk = 1/(2π) · 1/(2 m ω) = 1/(8π² m f)
    let f = swing_hz(100.0);
    let expected = 1.0 / (8.0 * PI * PI * M * f);
    // exact (dual numbers through the file's expression into the kind's energy): 1e-8
    // relative covers the modes' rounding; the two lowest modes are the swings
    for row in &s.dfdp[..2] {
        assert!(
            (row[0] - expected).abs() < 1e-8 * expected,
            "{} vs {expected}",
            row[0]
        );
    }
    assert!(s.exact[0], "k_magnet should be differentiated exactly");
}
