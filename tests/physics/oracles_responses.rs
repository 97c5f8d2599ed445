//! Stages 0B–2 responses against closed forms (docs/reference-values.md §2,
//! §6, §8 and docs/physics.md §3): state space, transfer functions, complex float elimination,
//! dissipation dilution and thermal noise.
//!
//! Tolerances: every reference is a closed form evaluated in the test; the responses are
//! exact linear algebra on exact Hessians, so agreement is at rounding level (1e-10
//! relative or better) unless stated. The printed oracle digits are checked to half a unit
//! of their last digit.

use nalgebra::{DVector, Matrix6, Vector3, Vector6};
use pendkit_dynamics::StageModel;
use pendkit_model::{BodySpec, DampingSpec, SystemBuilder};
use pendkit_noise::BOLTZMANN;
use pendkit_params::ParamSet;
use pendkit_system::{Damping, SpringEnd, Stage};
use pendkit_tests::{TWO_PI, assert_printed, assert_rel, run, tf};

type C = (f64, f64);

fn cmul(a: C, b: C) -> C {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn cdiv(a: C, b: C) -> C {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}

#[test]
fn toy_state_space_matches_design() {
    // docs/physics.md §3 with inputs (s, F), outputs (x, f_s): A = [[0,1],[-750,0]],
    // B = [[0,0],[750,1]], C = [[1,0],[750,0]], D = [[0,0],[-750,0]].
    let r = run("toy", &[], Stage::S0B);
    let ss = r.model.state_space(&r.system.damping, 1.0).unwrap();
    let k = 750.0;
    let expect = [
        (&ss.a, [[0.0, 1.0], [-k, 0.0]]),
        (&ss.b, [[0.0, 0.0], [k, 1.0]]),
        (&ss.c, [[1.0, 0.0], [k, 0.0]]),
        (&ss.d, [[0.0, 0.0], [-k, 0.0]]),
    ];
    for (m, e) in expect {
        for i in 0..2 {
            for j in 0..2 {
                assert!((m[(i, j)] - e[i][j]).abs() <= 1e-12 * k, "{m}");
            }
        }
    }
    assert_eq!(ss.inputs, ["s", "force:x"]);
    assert_eq!(ss.outputs, ["x", "force:s"]);
    assert_eq!(ss.states, ["x", "x_dot"]);
}

#[test]
fn toy_transfer_functions() {
    // §8: x/F = 1/(k − mω²), x/s = k/(k − mω²), k = 750 N/m, m = 1 kg
    let r = run("toy", &[], Stage::S0B);
    let k = 750.0;
    for (f, printed_f, printed_s) in [
        (1.0, 1.407417e-3, 1.055563),
        (10.0, -3.127109e-4, -0.2345332),
    ] {
        let d = k - (TWO_PI * f).powi(2);
        let (xf, xf_im) = tf(&r, "force:x", "x", f);
        let (xs, xs_im) = tf(&r, "s", "x", f);
        assert_rel(xf, 1.0 / d, 1e-12);
        assert_rel(xs, k / d, 1e-12);
        assert!(xf_im == 0.0 && xs_im == 0.0);
        assert_printed(xf, printed_f, 7);
        assert_printed(xs, printed_s, 7);
        // force on the support, −∂U/∂s = k (x − s) per unit s: k (x/s − 1)
        let (fs, _) = tf(&r, "s", "force:s", f);
        assert_rel(fs, k * (k / d - 1.0), 1e-12);
    }
}

#[test]
fn lossy_float_is_eliminated_per_frequency_on_complex_stiffness() {
    // §8: k1 = 1000 (1 + 1e-3 i), k2 = 3000: K_eff = k1 k2 / (k1 + k2) = 750.00014 + 0.5625 i.
    let r = run("toy", &["damping.k1.structural=1e-3"], Stage::S0B);
    let red = r.model.reduced(&r.system.damping, 1.0).unwrap();
    let k1 = (1000.0, 1.0);
    let k2 = (3000.0, 0.0);
    let expected = cdiv(cmul(k1, k2), (k1.0 + k2.0, k1.1 + k2.1));
    let got = red.k_eff[(0, 0)];
    assert_rel(got.re, expected.0, 1e-13);
    assert_rel(got.im, expected.1, 1e-12);
    assert_printed(got.re, 750.00014, 8);
    assert_printed(got.im, 0.5625, 4);
    // eliminating with real values and adding loss afterwards would give 0.75 i instead
    assert!((got.im - 0.75).abs() > 0.1);
}

#[test]
fn double_pendulum_transfer_functions() {
    // §2 table: k1 = (m1+m2) g/l1, k2 = m2 g/l2, det = (k1+k2−m1ω²)(k2−m2ω²) − k2²;
    // x2/x0 = k1 k2/det, x2/F2 = (k1+k2−m1ω²)/det, x1/x0 = k1 (k2 − m2ω²)/det.
    // The issue asks for 1e-6; the closed form is exact, so 1e-10 holds.
    let r = run("double-pendulum", &[], Stage::S0B);
    let (m1, m2, l, g) = (40.0, 40.0, 0.6, 9.81);
    let (k1, k2) = ((m1 + m2) * g / l, m2 * g / l);
    let table = [
        (0.1, 1.050420, 2.389830e-3, 1.025057),
        (1.0, -1.094019, -4.896470e-4, 1.547580),
        (10.0, 3.488074e-5, -6.359020e-6, -8.387360e-3),
    ];
    for (f, p_x2x0, p_x2f2, p_x1x0) in table {
        let w2 = (TWO_PI * f).powi(2);
        let det = (k1 + k2 - m1 * w2) * (k2 - m2 * w2) - k2 * k2;
        let got = [
            tf(&r, "x00", "x2", f).0,
            tf(&r, "force:x2", "x2", f).0,
            tf(&r, "x00", "x1", f).0,
        ];
        let want = [
            k1 * k2 / det,
            (k1 + k2 - m1 * w2) / det,
            k1 * (k2 - m2 * w2) / det,
        ];
        for ((g, w), p) in got.iter().zip(want).zip([p_x2x0, p_x2f2, p_x1x0]) {
            assert_rel(*g, w, 1e-10);
            assert_printed(*g, p, 7);
        }
    }
}

#[test]
fn support_displacement_transfer_tends_to_one() {
    // Translating the support translates everything at DC; the residual is O((f/f0)²):
    // at 1e-4 Hz and f0 ≥ 0.49 Hz it is below 1e-7.
    let cases = [
        ("toy", vec![("s", "x")]),
        (
            "pendulum",
            vec![("x00", "x1"), ("y00", "y1"), ("z00", "z1")],
        ),
        (
            "double-pendulum",
            vec![("x00", "x2"), ("y00", "y2"), ("z00", "z2")],
        ),
        (
            "rigid-body",
            vec![("x00", "x1"), ("y00", "y1"), ("z00", "z1")],
        ),
    ];
    for (model, pairs) in cases {
        let r = run(model, &[], Stage::S2);
        for (input, output) in pairs {
            let (re, im) = tf(&r, input, output, 1e-4);
            assert!(
                (re - 1.0).abs() < 1e-6 && im.abs() < 1e-6,
                "{model} {output}/{input} = {re} + {im}i"
            );
        }
    }
}

#[test]
fn stretch_loss_is_fully_diluted_sideways_and_undiluted_vertically() {
    // Only the fibre stretch is lossy (φ = 1e-7 on the stretch tag, stage 0B): the pendulum
    // restoring force comes from tension through changing geometry, so the horizontal loss
    // angle is zero to rounding, while the bounce stiffness is the fibres' own: loss = φ.
    let r = run(
        "pendulum",
        &[
            "damping.fibre_bending.structural=0",
            "damping.fibre_torsion.structural=0",
        ],
        Stage::S0B,
    );
    let k = r.model.reduced(&r.system.damping, 1.0).unwrap().k_eff;
    let idx = |n: &str| r.model.variables.iter().position(|v| v == n).unwrap();
    for n in ["x1", "y1"] {
        let kk = k[(idx(n), idx(n))];
        assert!(kk.im.abs() <= 1e-15 * kk.re, "{n}: {kk}");
    }
    let kz = k[(idx("z1"), idx("z1"))];
    assert_rel(kz.im / kz.re, 1e-7, 1e-12);
}

/// A mass m on a spring k to ground with the given damping of tag "spring", at 300 K.
fn oscillator(k: f64, spec: DampingSpec) -> (StageModel, Damping, f64) {
    let mut b = SystemBuilder::new(9.81);
    b.parameter("s", 0.0).unwrap();
    b.variable("x", 0.0).unwrap();
    let ground = b
        .body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))
        .unwrap();
    let mass = b
        .body(
            BodySpec::new("mass")
                .pose(["x", "0", "0", "0", "0", "0"])
                .mass(1.0),
        )
        .unwrap();
    let end = |body| SpringEnd {
        body,
        point: Vector3::zeros(),
        angles: [0.0; 3],
    };
    let stiffness = Matrix6::from_diagonal(&Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
    b.spring(
        "spring",
        [end(ground), end(mass)],
        stiffness,
        Vector6::zeros(),
        "spring",
    )
    .unwrap();
    let system = b.build().unwrap();
    let r = pendkit::run_stage(system, Stage::S0B).unwrap();
    let mut damping = Damping::default();
    damping.set(
        "spring",
        spec.resolve("spring", &ParamSet::new().resolve().unwrap())
            .unwrap(),
    );
    (r.into_run().model, damping, 300.0)
}

#[test]
fn structural_mass_spring_noise() {
    // §6: S_x = 4 k_B T k φ / (ω [(k − mω²)² + k²φ²]), m = 1 kg, f0 = 1 Hz, φ = 1e-3, 300 K.
    let k = TWO_PI * TWO_PI;
    let phi = 1e-3;
    let (model, damping, t) = oscillator(k, DampingSpec::structural("1e-3"));
    let freqs = [0.1, 1.0, 10.0];
    let noise =
        pendkit_noise::thermal_noise(&model, &damping, &DVector::from_element(1, 1.0), t, &freqs)
            .unwrap();
    for ((f, s), printed) in
        freqs
            .iter()
            .zip(&noise.total)
            .zip([6.814815e-25, 6.679207e-20, 6.814822e-31])
    {
        let w = TWO_PI * f;
        let expected =
            4.0 * BOLTZMANN * t * k * phi / (w * ((k - w * w).powi(2) + (k * phi).powi(2)));
        assert_rel(*s, expected, 1e-10);
        assert_printed(*s, printed, 7);
    }
    // the breakdown adds up to the total
    let sum: f64 = noise.by_term.iter().map(|(_, _, s)| s[1]).sum();
    assert_rel(sum, noise.total[1], 1e-12);
}

#[test]
fn changing_damping_reuses_the_matrices() {
    // The stage's matrices are built once; a new damping is only a new argument.
    let k = TWO_PI * TWO_PI;
    let (model, damping, t) = oscillator(k, DampingSpec::structural("1e-3"));
    let before = model.clone();
    let mut doubled = damping.clone();
    doubled.set(
        "spring",
        DampingSpec::structural("2e-3")
            .resolve("spring", &ParamSet::new().resolve().unwrap())
            .unwrap(),
    );
    let v = DVector::from_element(1, 1.0);
    let s1 = pendkit_noise::thermal_noise(&model, &damping, &v, t, &[0.1])
        .unwrap()
        .total;
    let s2 = pendkit_noise::thermal_noise(&model, &doubled, &v, t, &[0.1])
        .unwrap()
        .total;
    assert_eq!(model.lossless, before.lossless);
    assert_eq!(model.by_tag[0].1, before.by_tag[0].1);
    let w = TWO_PI * 0.1;
    let exact =
        |phi: f64| 4.0 * BOLTZMANN * t * k * phi / (w * ((k - w * w).powi(2) + (k * phi).powi(2)));
    assert_rel(s1[0], exact(1e-3), 1e-10);
    assert_rel(s2[0], exact(2e-3), 1e-10);
}

#[test]
fn viscous_oscillator_satisfies_equipartition() {
    // §6: F = −c ẋ ⇒ ∫₀^∞ S_x df = k_B T / k exactly. Viscous loss: ε'' = (2π c / k) f.
    // m = 1 kg, f0 = 1 Hz, Q = 1000 (c = m ω0 / Q). The integral is done numerically on a
    // grid graded around the resonance (composite Simpson in ln f) plus the analytic tails;
    // 1e-6 relative is the quadrature's accuracy, far below any physics error.
    let k = TWO_PI * TWO_PI;
    let c = TWO_PI / 1000.0;
    let viscous = format!("{}", TWO_PI * c / k);
    let (model, damping, t) = oscillator(
        k,
        DampingSpec {
            viscous: Some(viscous),
            ..Default::default()
        },
    );
    let v = DVector::from_element(1, 1.0);
    // ln-spaced Simpson on [1e-4, 1e3] Hz with many points near f0 = 1 Hz
    let (a, b, n) = ((1e-4f64).ln(), (1e3f64).ln(), 400_000usize);
    let h = (b - a) / n as f64;
    let freqs: Vec<f64> = (0..=n).map(|i| (a + h * i as f64).exp()).collect();
    let s = pendkit_noise::thermal_noise(&model, &damping, &v, t, &freqs)
        .unwrap()
        .total;
    let mut integral = 0.0;
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        integral += w * s[i] * freqs[i];
    }
    integral *= h / 3.0;
    // tails: below 1e-4 Hz S ≈ 4 k_B T c / k², above 1e3 Hz S ≈ 4 k_B T c / (m² ω⁴)
    integral += 4.0 * BOLTZMANN * t * c / (k * k) * 1e-4;
    integral += 4.0 * BOLTZMANN * t * c / (3.0 * TWO_PI.powi(4) * 1e9);
    assert_rel(integral, BOLTZMANN * t / k, 1e-6);
}

#[test]
fn osem_point_output_follows_the_linearised_geometry() {
    // A point p = (0, 0.17, 0.01) m on the rigid body, sensed along lab x: the small-rotation
    // displacement δp = θ × p gives δx = x1 + p_z·pitch1 − p_y·yaw1 (lab pitch about y, yaw
    // about z; both equal the coordinates at zero angles).
    let r = run("rigid-body", &[], Stage::S2);
    for f in [0.3, 1.0, 3.0] {
        let point = tf(&r, "x00", "mass1@0,0.17,0.01/1,0,0", f);
        let x = tf(&r, "x00", "x1", f);
        let pitch = tf(&r, "x00", "pitch1", f);
        let yaw = tf(&r, "x00", "yaw1", f);
        let expected = x.0 + 0.01 * pitch.0 - 0.17 * yaw.0;
        assert!(
            (point.0 - expected).abs() <= 1e-12 * x.0.abs().max(1.0),
            "{f} Hz"
        );
        // and a force there in that direction is the transpose: the same vector as input
        let force_point = tf(&r, "force:mass1@0,0.17,0.01/1,0,0", "x1", f);
        let fx = tf(&r, "force:x1", "x1", f);
        let fp = tf(&r, "force:pitch1", "x1", f);
        let fy = tf(&r, "force:yaw1", "x1", f);
        assert!((force_point.0 - (fx.0 + 0.01 * fp.0 - 0.17 * fy.0)).abs() <= 1e-12 * fx.0.abs());
    }
    // Output is an unknown name: a clear error listing the valid ones.
    let e = r.output("x9").unwrap_err().to_string();
    assert!(e.contains("'x9'") && e.contains("x1"), "{e}");
}
