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
