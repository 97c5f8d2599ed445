//! Stage 0A against closed forms (docs/reference-values.md §2, §3, §4, §8).
//!
//! Each test computes its reference from the closed-form expression of the oracle file and
//! also checks that the result rounds to the value printed there. Tolerances: the closed
//! forms are exact second-order expansions of the same potential (the oracle file checked
//! them against finite-difference Hessians), so the only differences are floating-point
//! rounding in the assembly and eigen-solve (about 1e-14) and the equilibrium residual
//! (forces below 1e-11 of the weight); 1e-10 relative leaves margin above both and is far
//! tighter than the 1e-7.

use pendkit_dynamics::eliminate_floats;
use pendkit_system::Stage;
use pendkit_tests::{TWO_PI, assert_printed, assert_rel, hz, labelled, run, two_dof_frequencies};

const G: f64 = 9.81;
const REL: f64 = 1e-10;

#[test]
fn toy_effective_matrices_and_frequency() {
    // §8: K_eff = k1 k2/(k1 + k2), C_XS,eff = -K_eff, S_eff = K_eff; f0 = sqrt(K_eff/m)/2π
    let r = run("toy", &[], Stage::S0A);
    let reduced =
        eliminate_floats(&r.assembled.stiffness(), &r.assembled.layout, &r.system).unwrap();
    let (k1, k2, m) = (1000.0, 3000.0, 1.0);
    let k = k1 * k2 / (k1 + k2);
    assert_rel(reduced.k_eff[(0, 0)], k, 1e-13);
    assert_rel(reduced.c_xs_eff[(0, 0)], -k, 1e-13);
    assert_rel(reduced.s_eff[(0, 0)], k, 1e-13);
    assert_printed(reduced.k_eff[(0, 0)], 750.0, 7);
    let f0 = hz(&r, "x", 0);
    assert_rel(f0, (k / m).sqrt() / TWO_PI, REL);
    assert_printed(f0, 4.358638, 7);
}

#[test]
fn simple_pendulum_frequency() {
    // sqrt(g/l)/2π at stage 0A: no flexure, the wire is a straight line between hinges.
    let r = run("pendulum", &[], Stage::S0A);
    let expected = (G / 0.6).sqrt() / TWO_PI;
    for label in ["x1", "y1"] {
        assert_rel(hz(&r, label, 0), expected, REL);
        assert_printed(hz(&r, label, 0), 0.6435451, 7);
    }
}

#[test]
fn pendulum_bounce_mode() {
    // §3: K_v = N E A / l, f = sqrt(K_v/m)/2π.
    let r = run("pendulum", &[], Stage::S0A);
    let kw = 72e9 * std::f64::consts::PI * 0.2e-3f64.powi(2) / 0.6;
    let expected = (4.0 * kw / 40.0).sqrt() / TWO_PI;
    assert_rel(hz(&r, "z1", 0), expected, REL);
    assert_printed(hz(&r, "z1", 0), 6.180387, 7);
}

#[test]
fn double_pendulum_frequencies() {
    // §2: ω±² = (g/2)[a ± sqrt(a² − 4b)], a = ((m1+m2)/m1)(1/l1 + 1/l2), b = (m1+m2)/(m1 l1 l2).
    let check = |sets: &[&str], (m1, m2, l1, l2): (f64, f64, f64, f64), printed: [f64; 2]| {
        let r = run("double-pendulum", sets, Stage::S0A);
        let a = (m1 + m2) / m1 * (1.0 / l1 + 1.0 / l2);
        let b = (m1 + m2) / (m1 * l1 * l2);
        let lo = (G / 2.0 * (a - (a * a - 4.0 * b).sqrt())).sqrt() / TWO_PI;
        let hi = (G / 2.0 * (a + (a * a - 4.0 * b).sqrt())).sqrt() / TWO_PI;
        let x: Vec<f64> = r
            .modes
            .modes
            .iter()
            .filter(|m| m.label.starts_with('x'))
            .map(|m| m.hz)
            .collect();
        assert_eq!(x.len(), 2);
        assert_rel(x[0], lo, REL);
        assert_rel(x[1], hi, REL);
        assert_printed(x[0], printed[0], 7);
        assert_printed(x[1], printed[1], 8);
    };
    check(&[], (40.0, 40.0, 0.6, 0.6), [0.4925481, 1.1891164]);
    check(
        &["m1=20", "l1=0.4"],
        (20.0, 40.0, 0.4, 0.6),
        [0.5218952, 1.6833755],
    );
}

/// §2 x–pitch pair of a body on N vertical wires attached at height d with separations ±s:
/// K_xx = mg/l, K_xθ = −mgd/l, K_θθ = mgd + mgd²/l + k_w Σs².
fn x_pitch_pair(d: f64, s: f64) -> [f64; 2] {
    let (m, ip, l) = (40.0, 0.42, 0.6);
    let kw = 72e9 * std::f64::consts::PI * 0.2e-3f64.powi(2) / l;
    let (kxx, kxt, ktt) = (
        m * G / l,
        -m * G * d / l,
        m * G * d + m * G * d * d / l + kw * 4.0 * s * s,
    );
    two_dof_frequencies([[kxx, kxt], [kxt, ktt]], (m, ip))
}

#[test]
fn rigid_body_x_pitch_pair() {
    let cases: [(&[&str], f64, f64, [f64; 2]); 3] = [
        (&[], 0.010, 0.005, [0.5613036, 0.6562285]),
        (&["d_fibre=0.002"], 0.002, 0.005, [0.3717501, 0.6437291]),
        (
            &["a_fibre=0", "d_fibre=0.010"],
            0.010,
            0.0,
            [0.4813011, 0.6504623],
        ),
    ];
    for (sets, d, s, printed) in cases {
        let r = run("rigid-body", sets, Stage::S0A);
        let expected = x_pitch_pair(d, s);
        let pair = labelled(&r, &["x1", "pitch1"]);
        assert_eq!(pair.len(), 2, "{sets:?}");
        assert_rel(pair[0], expected[0], REL);
        assert_rel(pair[1], expected[1], REL);
        assert_printed(pair[0], printed[0], 7);
        assert_printed(pair[1], printed[1], 7);
    }
}

#[test]
fn rigid_body_yaw_tension_part() {
    // §4: K_yaw = (T/l) Σ r_i², T = mg/4, r_i² = a² + b².
    let r = run("rigid-body", &[], Stage::S0A);
    let sum_r2 = 4.0 * (0.005f64.powi(2) + 0.17f64.powi(2));
    let k = 40.0 * G / 4.0 / 0.6 * sum_r2;
    assert_rel(hz(&r, "yaw1", 0), (k / 0.42).sqrt() / TWO_PI, REL);
    assert_printed(hz(&r, "yaw1", 0), 1.068122, 7);
}

#[test]
fn mode_vectors_are_mass_normalised_and_ascending() {
    let r = run("rigid-body", &[], Stage::S0A);
    let m = &r.assembled.mass.to_dense();
    let modes = &r.modes.modes;
    for (i, a) in modes.iter().enumerate() {
        let va = nalgebra::DVector::from_column_slice(&a.vector);
        for (j, b) in modes.iter().enumerate() {
            let vb = nalgebra::DVector::from_column_slice(&b.vector);
            let expected = if i == j { 1.0 } else { 0.0 };
            assert!((va.dot(&(m * &vb)) - expected).abs() < 1e-12);
        }
        let total: f64 = a.energy_fractions.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
    }
    assert!(modes.windows(2).all(|w| w[0].hz <= w[1].hz));
}

#[test]
fn mass_matrix_of_a_rigid_body_is_diag_m_and_inertia() {
    // At zero angles Ω_B is a permutation: yaw → z, pitch → y, roll → x.
    let r = run("rigid-body", &[], Stage::S0A);
    let expected = [40.0, 40.0, 40.0, 0.42, 0.42, 0.57];
    for (i, e) in expected.iter().enumerate() {
        assert!((r.assembled.mass[(i, i)] - e).abs() < 1e-9, "M[{i}]");
    }
}
