//! Helpers shared by the workspace tests: running a bundled model, finding a mode,
//! and tolerance assertions that say what they compared.

use pendkit::{Case, StageResult, run_stage};
use pendkit_system::Stage;

/// Runs a bundled model (with `NAME=EXPR` overrides) at `stage`.
pub fn run(model: &str, sets: &[&str], stage: Stage) -> StageResult {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = Case::model(model)
        .and_then(|c| c.with_sets(&sets))
        .expect("case");
    let (system, _) = case.build().expect("model builds");
    run_stage(system, stage).expect("stage runs")
}

/// Frequency (Hz) of the mode labelled `label`, `nth` of them (0-based) in ascending order.
pub fn hz(result: &StageResult, label: &str, nth: usize) -> f64 {
    result
        .modes
        .modes
        .iter()
        .filter(|m| m.label == label)
        .nth(nth)
        .unwrap_or_else(|| panic!("no mode #{nth} labelled {label}"))
        .hz
}

/// Asserts |a - b| <= rel * |b|.
#[track_caller]
pub fn assert_rel(a: f64, b: f64, rel: f64) {
    assert!(
        (a - b).abs() <= rel * b.abs(),
        "{a} vs {b}: relative difference {:.3e} > {rel:.1e}",
        ((a - b) / b).abs()
    );
}

/// Asserts that `a` rounds to the printed reference `printed` given with `digits`
/// significant digits (i.e. is within half a unit of its last digit).
#[track_caller]
pub fn assert_printed(a: f64, printed: f64, digits: i32) {
    let unit = 10f64.powi(printed.abs().log10().floor() as i32 - (digits - 1));
    assert!(
        (a - printed).abs() <= 0.5 * unit,
        "{a} does not round to the reference {printed} ({digits} significant digits)"
    );
}

/// 2π.
pub const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// One transfer function value (re, im) from a named input to a named output at `f` (Hz).
pub fn tf(r: &StageResult, input: &str, output: &str, f: f64) -> (f64, f64) {
    let h = r
        .transfer(input, output, &[f])
        .expect("valid input and output");
    (h[0].re, h[0].im)
}

/// The lowest `n` mode frequencies (Hz) of a bundled model with overrides at stage 0A.
pub fn lowest(model: &str, sets: &[&str], n: usize) -> Vec<f64> {
    run(model, sets, Stage::S0A)
        .modes
        .modes
        .iter()
        .take(n)
        .map(|m| m.hz)
        .collect()
}

/// Largest relative deviation of the lowest modes of `model` with overrides `sets` (stage
/// 0A) from the frequencies `reference` (as many modes as `reference` holds).
pub fn deviation(model: &str, sets: &[String], reference: &[f64]) -> f64 {
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    max_relative_difference(&lowest(model, &sets, reference.len()), reference)
}

/// Overrides of the `-full` blade-tip variants: tip mass (kg) and the stiffness of the
/// non-working directions (N/m, N m/rad).
pub fn full_blade_tips(mass: &str, translation: &str, rotation: &str) -> Vec<String> {
    vec![
        format!("blade_tip_mass={mass}"),
        format!("blade_stiff_translation={translation}"),
        format!("blade_stiff_rotation={rotation}"),
    ]
}

/// Largest |a_i / b_i − 1|.
pub fn max_relative_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| ((x - y) / y).abs())
        .fold(0.0, f64::max)
}

/// Block of a coordinate of a symmetric suspension: 0 longitudinal/pitch, 1
/// transverse/roll, 2 vertical, 3 yaw.
pub fn block(name: &str) -> usize {
    if name.starts_with('x') || name.starts_with("pitch") {
        0
    } else if name.starts_with('y') && !name.starts_with("yaw") || name.starts_with("roll") {
        1
    } else if name.starts_with('z') {
        2
    } else {
        3
    }
}

/// Asserts that the stage-0A stiffness and mass of `r` do not couple the four blocks
/// above rounding (1e-12 of the geometric mean of the diagonal entries), that every mode's
/// kinetic energy stays in one block (to 1e-9), and that the blocks hold `counts` modes.
#[track_caller]
pub fn assert_blocks(r: &StageResult, counts: [usize; 4]) {
    let k = pendkit::dynamics::eliminate_floats(
        &r.model.real_stiffness(&r.system.damping),
        &r.assembled.layout,
        &r.system,
    )
    .expect("floats eliminate")
    .k_eff;
    let names = &r.model.variables;
    for i in 0..names.len() {
        for j in 0..names.len() {
            if block(&names[i]) != block(&names[j]) {
                let scale = (k[(i, i)] * k[(j, j)]).sqrt();
                assert!(
                    k[(i, j)].abs() <= 1e-12 * scale,
                    "K[{}, {}] = {}",
                    names[i],
                    names[j],
                    k[(i, j)]
                );
                assert_eq!(r.assembled.mass[(i, j)], 0.0);
            }
        }
    }
    let mut found = [0; 4];
    for m in &r.modes.modes {
        let b = block(&m.label);
        let share: f64 = names
            .iter()
            .zip(&m.energy_fractions)
            .filter(|(n, _)| block(n) == b)
            .map(|(_, f)| f)
            .sum();
        assert!(
            (share - 1.0).abs() < 1e-9,
            "mode at {} Hz leaks out of its block",
            m.hz
        );
        found[b] += 1;
    }
    assert_eq!(found, counts);
}

/// First violin frequency (Hz) of a continuum stiff string clamped at both ends, tension
/// `t` (N), bending stiffness `ei` (N m²), linear density `mu` (kg/m), length `l` (m): the
/// root of 2 k kₑ (1 − cos kL cosh kₑL) + (kₑ² − k²) sin kL sinh kₑL = 0 (divided by
/// cosh kₑL), k² = (−T + s)/2EI, kₑ² = (T + s)/2EI, s = sqrt(T² + 4 EI μ ω²)
/// (docs/reference-values.md §5), by bisection between the ideal string's f₁ and 1.5 times it.
pub fn stiff_string_f1(t: f64, ei: f64, mu: f64, l: f64) -> f64 {
    let residual = |f: f64| {
        let w = TWO_PI * f;
        let s = (t * t + 4.0 * ei * mu * w * w).sqrt();
        let (k, ke) = (((s - t) / (2.0 * ei)).sqrt(), ((s + t) / (2.0 * ei)).sqrt());
        let sech = 1.0 / (ke * l).cosh();
        2.0 * k * ke * (sech - (k * l).cos()) + (ke * ke - k * k) * (k * l).sin() * (ke * l).tanh()
    };
    let ideal = (t / mu).sqrt() / (2.0 * l);
    // bending only raises f₁ (by ~2λ/L, λ = √(EI/T)); the second root is near 2× ideal
    let (mut a, mut b) = (ideal * 0.999, ideal * 1.5);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if residual(a) * residual(m) <= 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
    0.5 * (a + b)
}

/// The two frequencies (Hz) of a 2-DOF system with stiffness `k` and diagonal mass
/// `(m1, m2)`: the roots of det(K − ω² M) = 0.
pub fn two_dof_frequencies(k: [[f64; 2]; 2], (m1, m2): (f64, f64)) -> [f64; 2] {
    let (a, b, c) = (
        m1 * m2,
        -(k[0][0] * m2 + k[1][1] * m1),
        k[0][0] * k[1][1] - k[0][1] * k[1][0],
    );
    let disc = (b * b - 4.0 * a * c).sqrt();
    [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)].map(|w2| w2.sqrt() / TWO_PI)
}

/// Frequencies (Hz) of the modes labelled with any of `labels`, ascending.
pub fn labelled(r: &StageResult, labels: &[&str]) -> Vec<f64> {
    r.modes
        .modes
        .iter()
        .filter(|m| labels.contains(&m.label.as_str()))
        .map(|m| m.hz)
        .collect()
}

/// Asserts that the support-to-`output` transfer function along x (and y, z) tends to +1 at
/// 1e-4 Hz (inertial corrections there are below 1e-7 for modes above 0.3 Hz), and that
/// |x_out/x00| falls as f^`-power` between 40 and 80 Hz, well above the modes (corrections
/// (f_mode/f)² keep the slope within 0.05).
#[track_caller]
pub fn assert_support_limits(r: &StageResult, stage: &str, power: f64) {
    for axis in ["x", "y", "z"] {
        let (re, im) = tf(r, &format!("{axis}00"), &format!("{axis}{stage}"), 1e-4);
        assert!(
            (re - 1.0).abs() < 1e-6 && im.abs() < 1e-6,
            "{axis}{stage}/{axis}00 = {re} + {im}i"
        );
    }
    let output = format!("x{stage}");
    let mag = |f: f64| {
        let (a, b) = tf(r, "x00", &output, f);
        (a * a + b * b).sqrt()
    };
    let slope = (mag(80.0) / mag(40.0)).ln() / 2f64.ln();
    assert!((slope + power).abs() < 0.05, "slope {slope}");
}

/// Asserts that `model`'s equilibrium lies on its start (nominal) geometry: every
/// coordinate within 1e-6 (m or rad). The models derive unstretched lengths and blade
/// preloads from the static loads so that it should.
#[track_caller]
pub fn assert_nominal_equilibrium(model: &str) {
    let r = run(model, &[], Stage::S0A);
    let start = r.system.start();
    for (c, (x, s)) in r
        .system
        .coords
        .iter()
        .zip(r.assembled.equilibrium.coords.iter().zip(&start))
    {
        assert!(
            (x - s).abs() < 1e-6,
            "{model}: {} at {x}, nominal {s}",
            c.name
        );
    }
}

/// A suspension file's text: a bob of mass `m` on four hinged vertical silica fibres of
/// length `length` m (the suspension-file crate's documentation example), with `parameters`
/// the lines of its `[parameters]` table (which must define `m`, kg).
pub fn hinged_bob(parameters: &str, length: f64) -> String {
    format!(
        r#"
[parameters]
{parameters}
[materials.silica]
youngs_modulus = 72e9
poisson_ratio = 0.17
density = 2200
loss_angle = 1e-7
[bodies.support]
coordinates = "00"
driven = true
[bodies.bob]
coordinates = "1"
dof = "xyz"
mass = "m"
[stages.bob]
from = "support"
[stages.bob.fibres]
upper = {{ at = [0.005, 0.17, 0], mirror = ["y", "x"] }}
lower = {{ at = [0.005, 0.17, 0], mirror = ["y", "x"], hinged = 1 }}
length = {length}
radius = 0.2e-3
material = "silica"
"#
    )
}

/// Whether the opt-in tests gated by the environment variable `var` run: they do when it is
/// `1`. Otherwise this prints one line naming `test`, what it needs and how to enable it, and
/// the caller returns (Rust has no run-time skip: the test passes). The line is written to
/// the process's stderr directly, past the test harness's capture, so `cargo test` shows it.
/// With the variable set, the test runs and a missing tool fails it with its own message.
pub fn opted_in(var: &str, test: &str, needs: &str) -> bool {
    if std::env::var(var).is_ok_and(|v| v == "1") {
        return true;
    }
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED {test}: needs {needs}; run it with {var}=1"
    );
    false
}
