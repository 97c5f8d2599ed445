//! The optical spring from the command line: `sweep --modes` over the circulating power of
//! examples/two-mirrors.toml finds where the soft yaw mode starts to grow, against the
//! closed form k_yaw + k_soft(P) = 0 with k_soft = (P L / c)/(1 − g1 g2) ·
//! (−(g1 + g2) − √((g1 − g2)² + 4)) (Sidles & Sigg; elements/optical-spring), and `modes`
//! above it is refused naming the soft mode. Tolerance 1e-6: the threshold is bisected to
//! 1e-9 of the range and then interpolated where the mode's ω² is linear in P, and printed
//! to 7 significant digits.

use std::path::Path;

use crate::common::pendkit;

fn two_mirrors() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../examples/two-mirrors.toml")
        .display()
        .to_string()
}

/// The closed form's threshold power (W) for the yaw hold of examples/two-mirrors.toml.
fn threshold() -> f64 {
    let (l, r1, r2, k_yaw): (f64, f64, f64, f64) = (3994.5, 1934.0, 2245.0, 800.0);
    let (g1, g2) = (1.0 - l / r1, 1.0 - l / r2);
    let soft_per_watt: f64 =
        l / 299_792_458.0 / (1.0 - g1 * g2) * (-(g1 + g2) - ((g1 - g2).powi(2) + 4.0).sqrt());
    -k_yaw / soft_per_watt
}

#[test]
fn a_power_sweep_finds_the_soft_modes_threshold() {
    let file = two_mirrors();
    let (ok, stdout, stderr) = pendkit(&[
        "sweep",
        &file,
        "--vary",
        "power=0:1e8:11",
        "--modes",
        "--family",
        "Y",
    ]);
    assert!(ok, "{stderr}");
    // two yaw modes per step, the soft one at minus its growth rate above the threshold
    assert_eq!(stdout.lines().count(), 1 + 2 * 11, "{stdout}");
    let line = stderr
        .lines()
        .find(|l| l.contains("unstable above at power ="))
        .unwrap_or_else(|| panic!("no threshold line: {stderr}"));
    let value: f64 = line
        .split("power = ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap();
    let expected = threshold();
    assert!(
        (value - expected).abs() <= 1e-6 * expected,
        "{value} W against {expected} W"
    );
    assert!(line.contains("mode 'yaw"), "{line}");
}

#[test]
fn modes_above_the_threshold_are_refused_naming_the_soft_mode() {
    let file = two_mirrors();
    let above = format!("power={:e}", 1.01 * threshold());
    let (ok, _, stderr) = pendkit(&["modes", &file, "--set", &above]);
    assert!(!ok);
    assert!(stderr.contains("yaw"), "{stderr}");
    let below = format!("power={:e}", 0.99 * threshold());
    let (ok, _, stderr) = pendkit(&["modes", &file, "--set", &below]);
    assert!(ok, "{stderr}");
}

#[test]
fn a_sweep_without_a_crossing_says_so() {
    let (ok, _, stderr) = pendkit(&[
        "sweep",
        &two_mirrors(),
        "--vary",
        "power=0:1e6:3",
        "--modes",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("stable at every step: no instability for power from 0 to"),
        "{stderr}"
    );
}

#[test]
fn fit_recovers_the_power_from_the_closed_form_modes() {
    // the hard and soft pitch and yaw modes at P = 3e7 W, from the closed form
    // f = sqrt((k + λ)/I)/2π (k_pitch 1000, k_yaw 800 N m/rad; I 0.4, 0.5 kg m²)
    let (l, r1, r2, c, p): (f64, f64, f64, f64, f64) = (3994.5, 1934.0, 2245.0, 299_792_458.0, 3e7);
    let (g1, g2) = (1.0 - l / r1, 1.0 - l / r2);
    let scale = p * l / c / (1.0 - g1 * g2);
    let root = ((g1 - g2).powi(2) + 4.0).sqrt();
    let (hard, soft) = (scale * (-(g1 + g2) + root), scale * (-(g1 + g2) - root));
    let hz = |k: f64, i: f64| (k / i).sqrt() / (2.0 * std::f64::consts::PI);
    let csv = format!(
        "label,hz,sigma_hz\npitch2,{},0.001\npitch1,{},0.001\nyaw2,{},0.001\nyaw1,{},0.001\n",
        hz(1000.0 + hard, 0.4),
        hz(1000.0 + soft, 0.4),
        hz(800.0 + hard, 0.5),
        hz(800.0 + soft, 0.5)
    );
    let measured = Path::new(env!("CARGO_TARGET_TMPDIR")).join("two-mirrors-modes.csv");
    std::fs::write(&measured, csv).unwrap();
    let (ok, stdout, stderr) = pendkit(&[
        "fit",
        &two_mirrors(),
        "--modes",
        measured.to_str().unwrap(),
        "--free",
        "power",
        "--set",
        "power=2e7",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let fitted = json["fit"]["parameters"][0]["value"].as_f64().unwrap();
    // noise-free data: the fit lands on P to its convergence, far below 1e-6
    assert!((fitted - p).abs() <= 1e-6 * p, "{fitted} W against {p} W");
}

#[test]
fn the_arm_cavity_is_refused_above_its_threshold_naming_the_soft_pitch_mode() {
    // the sweep's threshold for the bundled arm, then `modes` on either side of it: the
    // verdict bisected by the sweep and the one `modes` gives must agree
    let (ok, _, stderr) = pendkit(&[
        "sweep",
        "arm-cavity",
        "--vary",
        "power=0:1e6:5",
        "--modes",
        "--family",
        "P",
    ]);
    assert!(ok, "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.contains("unstable above at power ="))
        .unwrap_or_else(|| panic!("no threshold below 1 MW: {stderr}"));
    assert!(
        line.contains("pitch3"),
        "the soft mode is the test masses' pitch: {line}"
    );
    let threshold: f64 = line
        .split("power = ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap();
    let (ok, _, stderr) = pendkit(&[
        "modes",
        "arm-cavity",
        "--set",
        &format!("power={}", 0.999 * threshold),
    ]);
    assert!(ok, "{stderr}");
    let (ok, _, stderr) = pendkit(&[
        "modes",
        "arm-cavity",
        "--set",
        &format!("power={}", 1.001 * threshold),
    ]);
    assert!(!ok && stderr.contains("pitch3"), "{stderr}");
}
