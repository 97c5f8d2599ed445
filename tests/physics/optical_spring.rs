//! The optical spring between two rigid mirrors, each held in pitch and yaw by a spring of
//! known stiffness (a six-axis spring at its centre of mass, no gravity): the rigid-mirror
//! limit, in which each angular pair's stiffness matrix is k 1 + K with K the cavity's
//! (Sidles & Sigg, Phys. Lett. A 354 (2006) 167, eq. for the torque matrix; written out
//! in elements/optical-spring), so the modes are ω² = (k + k_hard) / I and
//! (k + k_soft) / I with k_hard, k_soft the closed-form eigenvalues
//! (P L / c) / (1 − g1 g2) · (−(g1 + g2) ± √((g1 − g2)² + 4)). The closed form is
//! evaluated here from its own formula, not from the kind. Tolerance 1e-9 relative: the
//! model is exactly this linear system, so only the eigensolver's rounding (~1e-14) remains.
//! The model is examples/two-mirrors.toml.

use std::f64::consts::PI;
use std::path::Path;

use pendkit::{Case, Override, Stage, run_stage};

/// aLIGO's arm: length (m) and the radii of curvature of the input and end test masses (m).
const L: f64 = 3994.5;
const R1: f64 = 1934.0;
const R2: f64 = 2245.0;
const C: f64 = 299_792_458.0;
/// examples/two-mirrors.toml's numbers: each mirror's mass (kg) and principal moments of
/// inertia (kg m²) about x, y, z.
const M: f64 = 40.0;
const I: [f64; 3] = [0.3, 0.4, 0.5];
/// The holding springs: x, y, z (N/m), yaw, pitch, roll (N m/rad).
const K: [f64; 6] = [2000.0, 3000.0, 5000.0, 800.0, 1000.0, 700.0];

/// examples/two-mirrors.toml, whose parameters are the constants above.
fn file() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/two-mirrors.toml");
    std::fs::read_to_string(path).unwrap()
}

/// The closed form's twelve mode frequencies (Hz), ascending, at power `p` (W).
fn closed_form_hz(p: f64) -> Vec<f64> {
    let (g1, g2) = (1.0 - L / R1, 1.0 - L / R2);
    let scale = p * L / C / (1.0 - g1 * g2);
    let root = ((g1 - g2).powi(2) + 4.0).sqrt();
    let (hard, soft) = (scale * (-(g1 + g2) + root), scale * (-(g1 + g2) - root));
    let hz = |k: f64, inertia: f64| (k / inertia).sqrt() / (2.0 * PI);
    let mut all = vec![
        hz(K[0], M),
        hz(K[1], M),
        hz(K[2], M),
        hz(K[5], I[0]),
        hz(K[4] + hard, I[1]),
        hz(K[4] + soft, I[1]),
        hz(K[3] + hard, I[2]),
        hz(K[3] + soft, I[2]),
    ];
    // the translations and roll are the same for both mirrors
    all.extend([hz(K[0], M), hz(K[1], M), hz(K[2], M), hz(K[5], I[0])]);
    all.sort_by(f64::total_cmp);
    all
}

fn case_at(power: f64) -> Case {
    Case::from_text(Path::new("two-mirrors.toml"), &file())
        .unwrap()
        .with([Override::value("power", power)])
        .unwrap()
}

#[test]
fn rigid_mirrors_with_the_optical_spring_have_the_closed_form_modes() {
    for power in [0.0, 2e5, 1e6] {
        let (system, _) = case_at(power).build().unwrap();
        let r = run_stage(system, Stage::S2).unwrap();
        let hz: Vec<f64> = r.modes.modes.iter().map(|m| m.hz).collect();
        let expected = closed_form_hz(power);
        assert_eq!(hz.len(), expected.len());
        for (got, want) in hz.iter().zip(&expected) {
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "at {power} W: {got} Hz against the closed form's {want} Hz"
            );
        }
    }
}

#[test]
fn the_soft_mode_goes_unstable_where_the_closed_form_says() {
    // yaw is the softer hold: k_yaw + k_soft(P) = 0 at P = k_yaw / |k_soft per watt|
    let (g1, g2) = (1.0 - L / R1, 1.0 - L / R2);
    let soft_per_watt = L / C / (1.0 - g1 * g2) * (-(g1 + g2) - ((g1 - g2).powi(2) + 4.0).sqrt());
    let threshold = -K[3] / soft_per_watt;
    let run = |p: f64| run_stage(case_at(p).build().unwrap().0, Stage::S2).unwrap();
    assert!(run(0.99 * threshold).check_stable().is_ok());
    let above = run(1.01 * threshold);
    let error = above.check_stable().unwrap_err().to_string();
    assert!(error.contains("yaw"), "{error}");
}

#[test]
fn a_cavity_outside_the_stable_range_is_refused_naming_the_element() {
    // R = L/2 for both mirrors: g = −1, g1 g2 = 1, the edge of stability
    let text = file()
        .replace("roc_itm = { value = 1934", "roc_itm = { value = 1997.25")
        .replace("roc_etm = { value = 2245", "roc_etm = { value = 1997.25");
    let error = Case::from_text(Path::new("two-mirrors.toml"), &text)
        .unwrap()
        .build()
        .and_then(|(s, _)| run_stage(s, Stage::S2))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("optical-spring 'arm'") && error.contains("g1 g2"),
        "{error}"
    );
}

#[test]
fn the_modes_sensitivity_to_the_power_is_the_closed_forms() {
    use pendkit::sensitivity::{SensitivityRequest, sensitivities};
    // f = sqrt((k + λ(P))/I)/2π with λ linear in P: df/dP = (λ/P) / (8π² I f)
    let power = 1e6;
    let request = SensitivityRequest {
        parameters: Some(vec!["power".to_string()]),
        ..SensitivityRequest::modes(Stage::S2)
    };
    let s = sensitivities(&case_at(power), &request).unwrap();
    assert!(
        s.exact[0],
        "the optical spring's power should be differentiated exactly"
    );
    let (g1, g2) = (1.0 - L / R1, 1.0 - L / R2);
    let per_watt = L / C / (1.0 - g1 * g2);
    let root = ((g1 - g2).powi(2) + 4.0).sqrt();
    let hz = |k: f64, inertia: f64| (k / inertia).sqrt() / (2.0 * PI);
    let mut expected: Vec<(f64, f64)> = Vec::new();
    for (k, inertia) in [(K[4], I[1]), (K[3], I[2])] {
        for lambda in [
            per_watt * (-(g1 + g2) + root),
            per_watt * (-(g1 + g2) - root),
        ] {
            let f = hz(k + lambda * power, inertia);
            expected.push((f, lambda / (8.0 * PI * PI * inertia * f)));
        }
    }
    let (system, _) = case_at(power).build().unwrap();
    let result = run_stage(system, Stage::S2).unwrap();
    let modes = &result.modes.modes;
    // exact derivatives: 1e-8 relative covers the modes' rounding
    for (f, dfdp) in expected {
        let k = modes
            .iter()
            .position(|m| (m.hz - f).abs() < 1e-9 * f)
            .unwrap_or_else(|| panic!("no mode at {f} Hz"));
        let got = s.dfdp[k][0];
        assert!(
            (got - dfdp).abs() <= 1e-8 * dfdp.abs(),
            "mode at {f} Hz: {got} against {dfdp}"
        );
    }
}
