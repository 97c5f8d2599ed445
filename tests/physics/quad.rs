//! The aLIGO quad against physics (issue 5): nominal equilibrium, block structure,
//! transfer-function limits, agreement between variants, and violin modes.

use pendkit_system::Stage;
use pendkit_tests::{
    TWO_PI, assert_blocks, assert_nominal_equilibrium, assert_rel, assert_support_limits,
    deviation, full_blade_tips, lowest, max_relative_difference, run, stiff_string_f1, tf,
};

const G: f64 = 9.81;

#[test]
fn equilibrium_is_the_nominal_geometry_to_a_micrometre() {
    for model in [
        "quad",
        "quad-lite",
        "quad-full",
        "quad-lateral",
        "quad-v5",
        "quad-aligo",
    ] {
        assert_nominal_equilibrium(model);
    }
}

#[test]
fn derived_rows_of_the_parameter_table_agree() {
    // quad2005.csv's rounded derived rows against the exact values the model uses:
    // vertical c.o.m. separations and per-blade / per-side stiffnesses.
    let r = run("quad", &[], Stage::S0A);
    let z = |n: &str| r.assembled.equilibrium.coords[r.system.coord(n).unwrap()];
    for (derived, value) in [
        ("tln", -z("z0")),
        ("tl1", z("z0") - z("z1")),
        ("tl2", z("z1") - z("z2")),
        ("tl3", z("z2") - z("z3")),
    ] {
        let printed = [
            ("tln", 0.4162),
            ("tl1", 0.2769),
            ("tl2", 0.3411),
            ("tl3", 0.602),
        ]
        .iter()
        .find(|(n, _)| *n == derived)
        .unwrap()
        .1;
        assert!(
            (value - printed).abs() <= 0.5e-4,
            "{derived}: {value} vs {printed}"
        );
    }
    let kc = |f: f64, m: f64| 0.5 * (TWO_PI * f).powi(2) * m;
    assert!((kc(2.33, 22.11) - 2369.36).abs() < 0.005);
    assert!((kc(2.48, 22.011) - 2672.22).abs() < 0.005);
    assert!((kc(1.78, 39.6) - 2476.65).abs() < 0.005);
    let kw = |y: f64, r: f64, l: f64, n: f64| y * std::f64::consts::PI * r * r / l * n / 2.0;
    assert!((kw(220e9, 0.00054, 0.445, 2.0) - 452900.0).abs() < 50.0);
    assert!((kw(220e9, 0.00035, 0.3085, 4.0) - 548900.0).abs() < 50.0);
    assert!((kw(220e9, 0.00031, 0.341, 4.0) - 389600.0).abs() < 50.0);
    assert!((kw(70e9, 0.0002, 0.6, 4.0) - 29320.0).abs() < 5.0);
}

#[test]
fn symmetric_quad_separates_into_four_blocks() {
    // x/pitch, y/roll, z, yaw: 8 + 8 + 4 + 4 modes, no coupling above rounding.
    let r = run("quad", &[], Stage::S0A);
    assert_blocks(&r, [8, 8, 4, 4]);
}

#[test]
fn support_to_test_mass_tends_to_one_and_falls_as_f_to_the_minus_8() {
    // four pendulum stages in series: f^-8 well above the highest x mode (3.4 Hz)
    assert_support_limits(&run("quad", &[], Stage::S2), "3", 8.0);
}

#[test]
fn low_frequency_force_compliance_is_the_sum_of_the_stage_pendulums() {
    // With every wire break-off at its body's centre-of-mass height (all d = 0), a
    // horizontal force on the test mass tilts each wire stage without pitching any body,
    // so x3/F = Σ_k l_k / W_k, with l_k the stage's vertical wire extent and W_k the weight
    // hung from it (a taut wire of length L and tension T resists sideways motion with T/L;
    // T/L summed over a stage is W_k / l_k). Exact at DC; at 1e-4 Hz the inertial
    // correction is ~1e-7.
    let zero_d = ["dm=0", "dn=0", "d0=0", "d1=0", "d2=0", "d3=0", "d4=0"];
    let r = run("quad", &zero_d, Stage::S2);
    let (mn, m1, m2, m3) = (22.11, 22.011, 39.6, 39.6);
    let vertical = |l: f64, dy: f64| (l * l - dy * dy).sqrt();
    let stages = [
        (vertical(0.445, 0.25 - 0.09), mn + m1 + m2 + m3),
        (vertical(0.3085, 0.2 - 0.06), m1 + m2 + m3),
        (vertical(0.341, 0.14 - 0.1762), m2 + m3),
        (0.6, m3),
    ];
    let compliance: f64 = stages.iter().map(|(l, m)| l / (m * G)).sum();
    let (re, _) = tf(&r, "force:x3", "x3", 1e-4);
    // stage 2 adds the wires' flexure stiffness, which shortens each pendulum by about
    // λ ~ 1 mm: compare stage 0B for the exact statement and stage 2 to 1 %
    let r0 = run("quad", &zero_d, Stage::S0B);
    let (re0, _) = tf(&r0, "force:x3", "x3", 1e-4);
    assert_rel(re0, compliance, 1e-6);
    assert!((re / compliance - 1.0).abs() < 0.01 && re < re0);
}

#[test]
fn variants_converge_to_the_xtra_lite_quad() {
    let quad = lowest("quad", &[], 24);
    // A blade tip with (almost) no mass rides where the float would: the lite quad's 24
    // suspension modes approach the xtra-lite ones linearly in the tip mass (the tips add
    // m r² to the bodies' inertia): measured 4.4e-8 at 1e-6 kg and 4.4e-11 at 1e-9 kg.
    let lite_6 = deviation("quad-lite", &["blade_tip_mass=1e-6".into()], &quad);
    let lite_9 = deviation("quad-lite", &["blade_tip_mass=1e-9".into()], &quad);
    assert!(
        lite_9 < 1e-10 && lite_6 > 100.0 * lite_9,
        "{lite_6:e} {lite_9:e}"
    );
    // 6-DOF tips: the massless limit plus very stiff non-working directions. Measured
    // 3.5e-6 at (1e-6 kg, 1e10 N/m, 1e8 N m/rad) and 4.1e-7 at (1e-7, 1e11, 1e9); stiffer
    // still, rounding in the Hessian (1e13 N/m next to ~1e2 N/m pendulum stiffness) takes
    // over and the agreement gets worse (1.1e-5 at 1e13), so 1e-6 is the reachable level.
    let full = |m, kt, kr| deviation("quad-full", &full_blade_tips(m, kt, kr), &quad);
    let (coarse, fine) = (full("1e-6", "1e10", "1e8"), full("1e-7", "1e11", "1e9"));
    assert!(fine < 1e-6 && fine < coarse / 5.0, "{coarse:e} {fine:e}");
    // lateral compliance → infinite stiffness: measured 1.4e-8 at ratio 1e9, 1.4e-11 at 1e12
    let lateral = lowest("quad-lateral", &["blade_lateral_ratio=1e12"], 24);
    assert!(
        max_relative_difference(&lateral, &quad) < 1e-10,
        "{lateral:?}"
    );
    // and finite lateral compliance lowers the pitch modes (the source's reason for it)
    let soft = lowest("quad-lateral", &[], 1);
    assert!(soft[0] < quad[0]);
}

#[test]
fn violin_modes_of_v5_follow_the_loaded_string() {
    // docs/reference-values.md: for the quad's 39.6 kg test mass (T = 97.119 N) the V5 loaded
    // string (beads of one segment's mass) gives 488.2949, 943.3133, 1334.046 Hz.
    // Stage 0B (no bending, as the loaded string). Tolerance 2e-5: the segments above carry
    // the weight of the beads below (a 1e-5 tension gradient) and the fibre ends sit on
    // 39.6 kg masses, not fixed points.
    let r = run("quad-v5", &[], Stage::S0B);
    for (n, expected) in [488.2949, 943.3133, 1334.046].into_iter().enumerate() {
        let modes: Vec<&pendkit_dynamics::Mode> = r
            .modes
            .modes
            .iter()
            .filter(|m| (m.hz / expected - 1.0).abs() < 2e-5)
            .collect();
        // 4 fibres × 2 directions of displacement, each direction 4 times
        assert_eq!(
            modes.len(),
            8,
            "harmonic {}: {:?}",
            n + 1,
            modes.iter().map(|m| m.hz).collect::<Vec<_>>()
        );
        // four of the eight modes swing the beads along x and four along y: the beads'
        // kinetic energy over the group is 4 in x and 4 in y, a sum that does not depend on
        // how the solver picks a basis in the near-degenerate group (the beads' x also
        // couples to the test mass's yaw through each fibre's end, so modes may mix x and y
        // beads; what is not in the beads, a few 1e-5, moves the masses)
        let share = |prefix: &str| -> f64 {
            modes
                .iter()
                .map(|m| {
                    r.modes
                        .coordinates
                        .iter()
                        .zip(&m.energy_fractions)
                        .filter(|(c, _)| c.starts_with(prefix))
                        .map(|(_, f)| f)
                        .sum::<f64>()
                })
                .sum()
        };
        for prefix in ["xf", "yf"] {
            let beads = share(prefix);
            assert!(
                (beads - 4.0).abs() < 1e-3,
                "violin modes come in x and y: {prefix} share {beads}"
            );
        }
    }
}

#[test]
fn violin_modes_approach_the_stiff_continuum_as_beads_are_added() {
    // With bending (stage 2) and more beads, the first violin mode converges (as 1/N²) to
    // the clamped stiff string; Richardson extrapolation of N = 20 and 40 lands within
    // 5e-5 of the continuum root, against 3.2e-3 for the ideal string without bending.
    let (e, r, rho, l) = (70e9, 0.2e-3, 2200.0, 0.6);
    let area = std::f64::consts::PI * r * r;
    let (ei, mu, t) = (e * area * r * r / 4.0, rho * area, 39.6 * G / 4.0);
    let exact = stiff_string_f1(t, ei, mu, l);
    let ideal = (t / mu).sqrt() / (2.0 * l);
    assert!((exact / ideal - 1.0) > 3e-3);
    let f1 = |n: usize| {
        let sets = [format!("n_beads={n}")];
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        run("quad", &sets, Stage::S2)
            .modes
            .modes
            .iter()
            .find(|m| m.hz > 100.0)
            .unwrap()
            .hz
    };
    let (f10, f20, f40) = (f1(10), f1(20), f1(40));
    assert!((f40 - exact).abs() < (f20 - exact).abs() && (f20 - exact).abs() < (f10 - exact).abs());
    let extrapolated = (4.0 * f40 - f20) / 3.0;
    assert!(
        (extrapolated / exact - 1.0).abs() < 5e-5,
        "{extrapolated} vs {exact}"
    );
}
