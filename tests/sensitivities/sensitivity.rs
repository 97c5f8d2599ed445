//! Sensitivities (`pendkit::sensitivity::sensitivities`) against independent references: closed forms
//! (a simple pendulum, a mass on two springs) and central differences of the answers of
//! the same model re-solved from scratch (`Case::with_sets`, the whole pipeline: build,
//! equilibrium, stage, modes or responses), with the modes matched by shape (MAC), not by
//! order.
//!
//! The library differences the stage's *matrices* and differentiates the eigenproblem and
//! the responses exactly; these references difference the *answers* (frequencies, |H|,
//! ASD) instead, so the two share only the model.

use pendkit::nalgebra::DMatrix;
use pendkit::sensitivity::Sensitivities;
use pendkit::sensitivity::SensitivityRequest;
use pendkit::sensitivity::sensitivities;
use pendkit::{Case, Stage, run_stage};

fn case(spec: &str) -> Case {
    Case::open(spec).expect("case")
}

fn modes_of(case: &Case, stage: Stage, parameters: Option<&[&str]>) -> Sensitivities {
    let mut request = SensitivityRequest::modes(stage);
    request.parameters = parameters.map(|p| p.iter().map(|s| s.to_string()).collect());
    sensitivities(case, &request).expect("sensitivities")
}

/// The nominal modes' frequencies (Hz), vectors (columns) and mass matrix.
fn modes_at(case: &Case, stage: Stage) -> (Vec<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (system, _) = case.build().expect("build");
    let r = run_stage(system, stage).expect("stage");
    let n = r.modes.coordinates.len();
    let hz = r.modes.modes.iter().map(|m| m.hz).collect();
    let v = DMatrix::from_fn(n, r.modes.modes.len(), |i, k| r.modes.modes[k].vector[i]);
    (hz, v, r.assembled.mass.to_dense())
}

/// Groups of modes whose frequencies are within 1e-6 relative of each other: their
/// individual derivatives are not differentiable functions of the parameter (the order
/// within the group can swap), but their sum is.
fn groups(hz: &[f64]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (k, f) in hz.iter().enumerate() {
        match out.last_mut() {
            Some(g) if (f - hz[g[g.len() - 1]]).abs() <= 1e-6 * f.abs() => g.push(k),
            _ => out.push(vec![k]),
        }
    }
    out
}

/// The frequencies of `case` with `name` set to `value`, re-solved from scratch, in the
/// order of the nominal modes: each nominal mode takes the perturbed mode of largest MAC
/// |v₀ᵀ M v|² (both mass-normalised).
fn matched_hz(case: &Case, stage: Stage, name: &str, value: f64, v0: &DMatrix<f64>) -> Vec<f64> {
    let perturbed = case
        .clone()
        .with_sets(&[format!("{name}={value:e}")])
        .expect("set");
    let (hz, v, m) = modes_at(&perturbed, stage);
    let mac = v0.transpose() * &m * &v;
    (0..v0.ncols())
        .map(|k| {
            let best = (0..v.ncols())
                .max_by(|&a, &b| mac[(k, a)].abs().total_cmp(&mac[(k, b)].abs()))
                .expect("modes");
            hz[best]
        })
        .collect()
}

/// Fourth-order central difference of the re-solved, matched frequencies with step `h`.
fn fd_modes(case: &Case, stage: Stage, name: &str, p0: f64, h: f64, v0: &DMatrix<f64>) -> Vec<f64> {
    let at = |k: f64| matched_hz(case, stage, name, p0 + k * h, v0);
    let (m2, m1, p1, p2) = (at(-2.0), at(-1.0), at(1.0), at(2.0));
    (0..v0.ncols())
        .map(|k| (m2[k] - 8.0 * m1[k] + 8.0 * p1[k] - p2[k]) / (12.0 * h))
        .collect()
}

/// Every mode sensitivity (summed over groups of equal frequencies) of `spec` at `stage`
/// against the re-solved difference, for `parameters` (all when `None`).
///
/// The reference difference is taken with two steps, 2·10⁻⁴ and 10⁻⁴ of |p| (fourth order:
/// truncation ~(10⁻⁴)⁴ relative; rounding of frequencies ~10⁻¹⁴ relative over the step
/// gives ~10⁻¹⁰ in p/f·df/dp). Where the two agree to 10⁻⁷ in the relative sensitivity
/// p/f·df/dp, the difference is converged and the library must agree with it to 10⁻⁶ of
/// |df/dp| plus 10⁻⁸ relative-sensitivity units (the floor is what rounding allows for
/// parameters that barely move a mode). Every comparison must have been converged.
fn check_against_re_solved(spec: &str, stage: Stage, parameters: Option<&[&str]>) {
    check_case_against_re_solved(spec, &case(spec), stage, parameters);
}

/// [`check_against_re_solved`] for a case (`spec` names it in the messages).
fn check_case_against_re_solved(
    spec: &str,
    case: &Case,
    stage: Stage,
    parameters: Option<&[&str]>,
) {
    let s = modes_of(case, stage, parameters);
    let (hz, v0, _) = modes_at(case, stage);
    assert_eq!(hz, s.modes_hz, "{spec}: the nominal modes");
    let groups = groups(&hz);
    let mut compared = 0;
    for (j, name) in s.parameters.iter().enumerate() {
        let p0 = s.values[j];
        if s.steps[j] == 0.0 {
            // read by nothing: the library says exactly zero, and so must every mode
            assert!(s.dfdp.iter().all(|row| row[j] == 0.0));
            continue;
        }
        let scale = if p0 == 0.0 { 1e-3 } else { p0.abs() };
        let coarse = fd_modes(case, stage, name, p0, 2e-4 * scale, &v0);
        let fine = fd_modes(case, stage, name, p0, 1e-4 * scale, &v0);
        for g in &groups {
            let sum = |d: &dyn Fn(usize) -> f64| g.iter().map(|&k| d(k)).sum::<f64>();
            let f: f64 = g.iter().map(|&k| hz[k]).sum();
            let (a, b) = (sum(&|k| coarse[k]), sum(&|k| fine[k]));
            let lib = sum(&|k| s.dfdp[k][j]);
            let rel = scale / f.abs();
            assert!(
                (a - b).abs() * rel < 1e-7,
                "{spec} {name} modes {g:?}: the reference difference is not converged ({a} vs {b})"
            );
            let tol = 1e-6 * b.abs() + 1e-8 / rel;
            assert!(
                (lib - b).abs() <= tol,
                "{spec} stage {stage} d f{g:?}/d {name}: library {lib:e}, re-solved {b:e} (tol {tol:e})"
            );
            compared += 1;
        }
    }
    assert!(compared > 0, "{spec}: nothing compared");
}

#[test]
fn pendulum_closed_forms() {
    // stage 0A of the pendulum is f = √(g/l)/2π for the swing modes (x1, y1, a degenerate
    // pair; the model's 0.6435451 Hz is √(9.81/0.6)/2π to 7 digits), so df/dl = −f/(2l) and
    // df/dg = f/(2g) exactly; the mass does not enter (the wires do not stretch into l).
    // Tolerance 1e-8 relative: the matrices' difference has truncation ~1e-12 and
    // rounding ~1e-13/1e-3 relative.
    let case = case("pendulum");
    let s = modes_of(&case, Stage::S0A, Some(&["l_fibre", "g", "m1"]));
    let (l, g) = (s.values[0], s.values[1]);
    for k in 0..2 {
        let f = s.modes_hz[k];
        assert!(s.mode_labels[k] == "x1" || s.mode_labels[k] == "y1");
        let expected_l = -f / (2.0 * l);
        let expected_g = f / (2.0 * g);
        assert!(
            (s.dfdp[k][0] - expected_l).abs() <= 1e-8 * expected_l.abs(),
            "df/dl {} vs {expected_l}",
            s.dfdp[k][0]
        );
        assert!(
            (s.dfdp[k][1] - expected_g).abs() <= 1e-8 * expected_g.abs(),
            "df/dg {} vs {expected_g}",
            s.dfdp[k][1]
        );
        // p/f df/dm below 1e-8: zero up to the difference's rounding
        assert!(
            s.dfdp[k][2].abs() * s.values[2] / f < 1e-8,
            "df/dm {}",
            s.dfdp[k][2]
        );
    }
}

#[test]
fn mass_on_springs_closed_forms() {
    // the toy: a mass m on springs k1 and k2 in series (a massless junction, a float):
    // f = √(k/m)/2π with k = k1 k2/(k1 + k2). So df/dm = −f/(2m), and
    // df/dk1 = f/(2k) · dk/dk1 = f/(2k) · (k/k1)², likewise for k2. The series stiffness is
    // the float's Schur complement, differentiated through the elimination. Tolerance
    // 1e-9 relative (linear springs: the difference is exact but for rounding).
    let s = modes_of(&case("toy"), Stage::S0A, Some(&["m", "k1", "k2"]));
    let (m, k1, k2) = (s.values[0], s.values[1], s.values[2]);
    let k = k1 * k2 / (k1 + k2);
    let f = s.modes_hz[0];
    assert!((f - (k / m).sqrt() / (2.0 * std::f64::consts::PI)).abs() < 1e-12 * f);
    let expected = [
        -f / (2.0 * m),
        f / (2.0 * k) * (k / k1).powi(2),
        f / (2.0 * k) * (k / k2).powi(2),
    ];
    for (j, e) in expected.iter().enumerate() {
        let got = s.dfdp[0][j];
        assert!(
            (got - e).abs() <= 1e-9 * e.abs(),
            "{}: {got} vs {e}",
            s.parameters[j]
        );
    }
}

#[test]
fn pendulum_every_parameter_against_re_solved() {
    check_against_re_solved("pendulum", Stage::S2, None);
}

#[test]
fn double_pendulum_against_re_solved() {
    check_against_re_solved("double-pendulum", Stage::S2, None);
    check_against_re_solved("double-pendulum", Stage::S0A, None);
}

#[test]
fn triple_against_re_solved() {
    check_against_re_solved("triple", Stage::S2, None);
}

#[test]
fn quad_against_re_solved() {
    check_against_re_solved("quad", Stage::S0A, None);
    check_against_re_solved("quad", Stage::S2, None);
}

#[test]
fn suspension_file_against_re_solved() {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/basic/rigid-body.toml"
    );
    check_against_re_solved(file, Stage::S2, None);
}

#[test]
fn pendulum_tf_and_noise_against_re_solved() {
    // |H| from the support x00 to the mass x1 and the thermal-noise ASD of x1, at
    // frequencies away from the modes (0.644 Hz swing, ~6 Hz bounce, violin modes above
    // 100 Hz): see `check_responses_against_re_solved` for the reference and tolerance
    let n = check_responses_against_re_solved(
        "pendulum",
        Stage::S2,
        ("x00", "x1"),
        &[0.1, 0.3, 2.0, 20.0],
    );
    // every parameter with a step (11), four frequencies, |H| and the ASD
    assert_eq!(n, 11 * 8);
}

/// |H| from `input` to `output` and the thermal-noise ASD of `output` at `freqs`, of `case`
/// with `name = value` re-solved from scratch at `stage`.
fn responses_at(
    case: &Case,
    stage: Stage,
    (input, output): (&str, &str),
    freqs: &[f64],
    (name, value): (&str, f64),
) -> (Vec<f64>, Vec<f64>) {
    let perturbed = case
        .clone()
        .with_sets(&[format!("{name}={value:e}")])
        .expect("set");
    let (system, _) = perturbed.build().expect("build");
    let r = run_stage(system, stage).expect("stage");
    let tf = r.transfer(input, output, freqs).expect("tf");
    let asd = r.noise(output, freqs).expect("noise").asd();
    (tf.iter().map(|h| h.norm()).collect(), asd)
}

/// Every parameter's d|H|/dp and d(ASD)/dp of `spec` at `stage` against fourth-order
/// central differences of the answers re-solved from scratch, with steps 2·10⁻⁴ and 10⁻⁴
/// of |p| (the reference converged to 1e-7 relative, checked), to 1e-6 relative plus a
/// floor of 1e-9 of the response per unit relative change of p. Returns how many
/// (parameter, frequency, response) triples were compared.
fn check_responses_against_re_solved(
    spec: &str,
    stage: Stage,
    ports: (&str, &str),
    freqs: &[f64],
) -> usize {
    let case = case(spec);
    let request = SensitivityRequest {
        stage,
        modes: false,
        tf: Some((ports.0.into(), ports.1.into())),
        noise: Some(ports.1.into()),
        freqs: freqs.to_vec(),
        parameters: None,
        allow_unstable: false,
        threads: 0,
        differences: false,
    };
    let s = sensitivities(&case, &request).expect("sensitivities");
    let (tf_abs, d_tf) = s.tf_abs.as_ref().expect("tf");
    let (asd, d_asd) = s.noise_asd.as_ref().expect("noise");
    // the nominal |H| and ASD are those `pendkit tf` and `pendkit noise` give (the
    // sensitivities solve their own dense systems, and sum the noise per tag themselves
    // where tags have their own temperatures: they must agree)
    let (system, _) = case.build().expect("build");
    let r = run_stage(system, stage).expect("stage");
    let h = r.transfer(ports.0, ports.1, freqs).expect("tf");
    let n = r.noise(ports.1, freqs).expect("noise").asd();
    for i in 0..freqs.len() {
        assert!(
            (tf_abs[i] - h[i].norm()).abs() <= 1e-9 * h[i].norm(),
            "{spec} |H|"
        );
        assert!(
            (asd[i] - n[i]).abs() <= 1e-9 * n[i],
            "{spec} ASD {} vs {}",
            asd[i],
            n[i]
        );
    }
    let mut compared = 0;
    for (j, name) in s.parameters.iter().enumerate() {
        if s.steps[j] == 0.0 {
            continue;
        }
        let p0 = s.values[j];
        let scale = if p0 == 0.0 { 1e-3 } else { p0.abs() };
        // both responses at every frequency from each re-solved model
        let fd = |h: f64| {
            let at = |k: f64| responses_at(&case, stage, ports, freqs, (name, p0 + k * h));
            let [m2, m1, p1, p2] = [at(-2.0), at(-1.0), at(1.0), at(2.0)];
            let d = |[a, b, c, e]: [&Vec<f64>; 4]| -> Vec<f64> {
                (0..freqs.len())
                    .map(|i| (a[i] - 8.0 * b[i] + 8.0 * c[i] - e[i]) / (12.0 * h))
                    .collect()
            };
            let tf = d([&m2.0, &m1.0, &p1.0, &p2.0]);
            let noise = d([&m2.1, &m1.1, &p1.1, &p2.1]);
            (tf, noise)
        };
        let (coarse, fine) = (fd(2e-4 * scale), fd(1e-4 * scale));
        for (i, &f) in freqs.iter().enumerate() {
            let cases = [
                ("|H|", tf_abs[i], d_tf[i][j], coarse.0[i], fine.0[i]),
                ("ASD", asd[i], d_asd[i][j], coarse.1[i], fine.1[i]),
            ];
            for (what, value, lib, a, b) in cases {
                let per_relative = value / scale;
                assert!(
                    (a - b).abs() <= 1e-7 * b.abs() + 1e-9 * per_relative,
                    "{spec} {stage} {name} at {f} Hz ({what}): reference not converged ({a:e} vs {b:e})"
                );
                let tol = 1e-6 * b.abs() + 1e-9 * per_relative;
                assert!(
                    (lib - b).abs() <= tol,
                    "{spec} {stage} {name} at {f} Hz ({what}): library {lib:e}, re-solved {b:e}"
                );
                compared += 1;
            }
        }
    }
    compared
}

#[test]
fn quad_and_triple_tf_and_noise_against_re_solved() {
    // Every parameter of the quad (at stages 1B and 2: without and with the wires' extra
    // stretch) and of the triple, |H| from the support to the test mass and the test
    // mass's thermal noise, below every mode (0.1 Hz), between or above the modes (quad:
    // 24 modes from 0.43 to 12.5 Hz; triple: 18 from 0.58 to 36 Hz), at 100 Hz: where the
    // answers are smooth enough for their differences to be a reference.
    let quad_freqs = [0.1, 20.0, 100.0];
    // (The vertical |H| z3/z00 above the bounce modes is a product of cancellations whose
    // rounding, ~1e-9 of |H| in every solve, makes re-solved differences good only to
    // ~1e-5 of the response per unit relative change: no reference at 1e-6 there.)
    // Every parameter with a step, each at three frequencies, for |H| and the ASD.
    let n = check_responses_against_re_solved("quad", Stage::S2, ("x00", "x3"), &quad_freqs);
    assert_eq!(n, 73 * 6);
    let n = check_responses_against_re_solved("quad", Stage::S1B, ("x00", "x3"), &quad_freqs);
    assert_eq!(n, 73 * 6);
    let n =
        check_responses_against_re_solved("triple", Stage::S2, ("x00", "x3"), &[0.1, 10.0, 100.0]);
    assert_eq!(n, 78 * 6);
    // ports that follow the equilibrium's geometry: a force at a point of the PUM off its
    // centre, the lengthwise motion of a point on the test-mass face off its axis (pitch
    // and yaw reach it through lever arms that move with the equilibrium)
    let ports = ("force:pum@0,0.1,0/1,0,0", "testmass@0.1,0.1,0.05/1,0,0");
    let n = check_responses_against_re_solved("quad", Stage::S2, ports, &quad_freqs);
    assert_eq!(n, 73 * 6);
}

#[test]
fn modes_asked_with_responses_keep_the_exact_route() {
    // the modes asked for together with |H| and the noise: the same exact mode
    // sensitivities (bit for bit, the same `exact` flags) as the modes alone, and the same
    // response sensitivities as the responses alone
    let case = case("quad");
    let both = SensitivityRequest {
        tf: Some(("x00".into(), "x3".into())),
        noise: Some("x3".into()),
        freqs: vec![0.1, 20.0],
        ..SensitivityRequest::modes(Stage::S2)
    };
    let modes = SensitivityRequest::modes(Stage::S2);
    let responses = SensitivityRequest {
        modes: false,
        ..both.clone()
    };
    let [b, m, r] =
        [both, modes, responses].map(|q| sensitivities(&case, &q).expect("sensitivities"));
    assert_eq!(b.dfdp, m.dfdp);
    assert_eq!(b.exact, m.exact);
    assert!(
        b.exact.iter().filter(|&&e| e).count() >= 70,
        "{:?}",
        b.exact
    );
    assert_eq!(b.tf_abs, r.tf_abs);
    assert_eq!(b.noise_asd, r.noise_asd);
    // without the modes nothing is called exact: the responses are differenced
    assert!(r.exact.iter().all(|&e| !e));
}

#[test]
fn noise_with_tags_at_their_own_temperatures_against_re_solved() {
    // quad-aligo gives every damping tag its own temperature (`temp_fibre`,
    // `temp_blade_n`, ...; each "temperature" by default), so its noise is the
    // fluctuation–dissipation sum over tags, 4 k_B/ω Σ T_tag ε''_tag z̄ᵀ P_tag z, whose
    // derivative takes each tag's temperature, loss and stiffness apart. Every parameter
    // (the tags' temperatures among them), the same reference and tolerance as above.
    let freqs = [0.1, 20.0, 100.0];
    let n = check_responses_against_re_solved("quad-aligo", Stage::S2, ("x00", "x3"), &freqs);
    assert!(n >= 90 * 6, "{n} compared");
}

#[test]
fn loss_angle_moves_no_mode_but_moves_the_noise() {
    // the modes use the storage part ε'(0) = 1 of the damping, so the loss angle moves no
    // mode; the noise ASD grows with the loss angle (to
    // first order PSD ∝ φ away from resonances, so d ASD/dφ ≈ ASD/(2φ), to the 1e-3 that
    // the nonlinearity of |Im R| in φ allows at 2 Hz with φ = 1e-7).
    let case = case("pendulum");
    let request = SensitivityRequest {
        stage: Stage::S2,
        modes: true,
        tf: None,
        noise: Some("x1".into()),
        freqs: vec![2.0],
        parameters: Some(vec!["phi_fibre".into()]),
        allow_unstable: false,
        threads: 0,
        differences: false,
    };
    let s = sensitivities(&case, &request).expect("sensitivities");
    // the build reads φ too (the fibres' material), so the stage is rebuilt: what is left
    // of the mode sensitivities is the rounding of the matrices over the step, ~1e-14 in
    // p/f·df/dp (a real dependence would show at the 1e-1 of a loss-driven shift)
    for (k, row) in s.dfdp.iter().enumerate() {
        assert!(
            row[0].abs() * s.values[0] / s.modes_hz[k] < 1e-12,
            "{row:?}"
        );
    }
    let (asd, d) = s.noise_asd.expect("noise");
    let expected = asd[0] / (2.0 * s.values[0]);
    assert!(
        (d[0][0] - expected).abs() <= 1e-3 * expected,
        "{} vs {expected}",
        d[0][0]
    );
}

#[test]
fn bad_requests_are_errors() {
    let case = case("pendulum");
    let base = SensitivityRequest::modes(Stage::S2);
    let err = |r: SensitivityRequest| sensitivities(&case, &r).expect_err("must fail").to_string();
    let e = err(SensitivityRequest {
        parameters: Some(vec!["no_such".into()]),
        ..base.clone()
    });
    assert!(
        e.contains("no_such") && e.contains("not a numeric parameter"),
        "{e}"
    );
    let e = err(SensitivityRequest {
        parameters: Some(vec![]),
        ..base.clone()
    });
    assert!(e.contains("empty list"), "{e}");
    let e = err(SensitivityRequest {
        parameters: Some(vec!["g".into(), "g".into()]),
        ..base.clone()
    });
    assert!(e.contains("twice"), "{e}");
    let e = err(SensitivityRequest {
        tf: Some(("x00".into(), "x1".into())),
        ..base.clone()
    });
    assert!(e.contains("at least one frequency"), "{e}");
    let e = err(SensitivityRequest {
        tf: Some(("x00".into(), "nowhere".into())),
        freqs: vec![1.0],
        ..base.clone()
    });
    assert!(e.contains("nowhere"), "{e}");
    let e = err(SensitivityRequest {
        noise: Some("x1".into()),
        freqs: vec![-1.0],
        ..base.clone()
    });
    assert!(e.contains("out of range"), "{e}");
    let e = err(SensitivityRequest {
        noise: Some("x1".into()),
        freqs: vec![f64::NAN],
        ..base.clone()
    });
    assert!(e.contains("out of range"), "{e}");
    let e = err(SensitivityRequest {
        freqs: vec![1.0],
        ..base.clone()
    });
    assert!(e.contains("without a transfer function"), "{e}");
    let e = err(SensitivityRequest {
        stage: Stage::S0A,
        noise: Some("x1".into()),
        freqs: vec![1.0],
        ..base.clone()
    });
    assert!(e.contains("stage 0b"), "{e}");
    let e = err(SensitivityRequest {
        modes: false,
        ..base.clone()
    });
    assert!(e.contains("nothing to differentiate"), "{e}");
    // answers with a corner at 0 have no derivative there: the lossless double pendulum's
    // noise, and |H| from the quad's support x to its transverse y (decoupled by symmetry)
    let zero = |spec: &str, tf: Option<(&str, &str)>, noise: Option<&str>| {
        let request = SensitivityRequest {
            modes: false,
            tf: tf.map(|(i, o)| (i.to_string(), o.to_string())),
            noise: noise.map(str::to_string),
            freqs: vec![0.3],
            parameters: Some(vec!["g".into()]),
            ..base.clone()
        };
        sensitivities(&Case::open(spec).expect("case"), &request)
            .unwrap_err()
            .to_string()
    };
    let e = zero("double-pendulum", None, Some("x1"));
    assert!(
        e.contains("thermal-noise ASD is exactly 0 at 0.3 Hz") && e.contains("no derivative"),
        "{e}"
    );
    let e = zero("quad", Some(("x00", "y3")), None);
    assert!(
        e.contains("|H| is exactly 0 at 0.3 Hz") && e.contains("no derivative"),
        "{e}"
    );
}

#[test]
fn unstable_equilibrium_is_refused_unless_allowed() {
    // d4 = −0.02 m makes the quad's test-mass pitch an inverted pendulum (tests/stability.rs)
    let case = case("quad").with_sets(&["d4=-0.02".into()]).expect("set");
    let mut request = SensitivityRequest::modes(Stage::S2);
    request.parameters = Some(vec!["m3".into()]);
    let e = sensitivities(&case, &request)
        .expect_err("unstable")
        .to_string();
    assert!(e.contains("pitch3"), "{e}");
    request.allow_unstable = true;
    let s = sensitivities(&case, &request).expect("allowed");
    assert!(s.warning.expect("a warning").contains("pitch3"));
}

#[test]
fn thread_count_does_not_change_the_numbers() {
    // each parameter's column is computed by the same code whichever thread runs it, so the
    // results on one thread and on three are bit-identical (no tolerance: any difference
    // would mean the threads share state they should not)
    let quad = case("quad");
    let mut request = SensitivityRequest::modes(Stage::S0A);
    request.threads = 1;
    let one = sensitivities(&quad, &request).expect("one thread");
    request.threads = 3;
    let three = sensitivities(&quad, &request).expect("three threads");
    assert_eq!(one, three);
    assert!(one.parameters.len() > 50, "{}", one.parameters.len());

    let pendulum = case("pendulum");
    let mut request = SensitivityRequest {
        modes: true,
        tf: Some(("x00".into(), "x1".into())),
        noise: Some("x1".into()),
        freqs: vec![0.3, 2.0],
        threads: 1,
        ..SensitivityRequest::modes(Stage::S2)
    };
    let one = sensitivities(&pendulum, &request).expect("one thread");
    request.threads = 2;
    assert_eq!(
        one,
        sensitivities(&pendulum, &request).expect("two threads")
    );
}

#[test]
fn the_first_parameter_in_order_names_the_error_whatever_the_threads() {
    // two switches the model refuses to move, asked for by name: a loop in order stops at
    // the first, and so must the threads, whichever finishes first
    let quad = case("quad");
    let mut request = SensitivityRequest::modes(Stage::S0A);
    request.parameters = Some(vec![
        "m3".into(),
        "n_beads".into(),
        "wire_terms_early".into(),
    ]);
    for threads in [1, 2, 3] {
        request.threads = threads;
        let e = sensitivities(&quad, &request)
            .expect_err("a switch has no derivative")
            .to_string();
        assert!(
            e.contains("'n_beads' has no derivative"),
            "{threads} threads: {e}"
        );
    }
}

#[test]
fn the_build_moves_along_its_exact_tangent_where_it_can() {
    // a mass, a wire length and a blade tip's position (a number in the tip's pose, whose
    // derivative moves the points on the tip) reach the quad's numbers with their exact
    // tangent (their sensitivities agree with re-solved differences:
    // quad_against_re_solved)
    let quad = case("quad");
    let mut request = SensitivityRequest::modes(Stage::S0A);
    request.parameters = Some(vec!["m3".into(), "l3".into(), "nn0".into()]);
    let s = sensitivities(&quad, &request).expect("sensitivities");
    assert_eq!(s.exact_build, vec![true, true, true]);
}

/// The pendulum with ε'(0) of its fibres' stretch set to 1 + `slope`·(p − p₀), p₀ the
/// nominal value of `parameter` (read from the model, so that ε'(0) is exactly 1 there):
/// `parameter` must take the difference route (the real stiffness moves with it beyond
/// dK/dp, through its tension-off part times dε'/dp, which the exact route does not carry),
/// the fibre length, which no ε' reads, the exact one, and both must agree with re-solved
/// frequencies. Returns the sensitivities to the two.
fn check_real_multiplier_moving_with(parameter: &str, slope: f64) -> Sensitivities {
    let (_, nominal) = case("pendulum").build().expect("build");
    let p0 = nominal.get(parameter).expect("the parameter");
    let set = format!("damping.fibre_stretch.real=1 + {slope:e}*({parameter} - {p0:e})");
    let pendulum = case("pendulum").with_sets(&[set]).expect("set");
    let asked = [parameter, "l_fibre"];
    let s = modes_of(&pendulum, Stage::S2, Some(&asked));
    assert_eq!(s.exact, vec![false, true], "{parameter}");
    check_case_against_re_solved(
        &format!("pendulum (ε' moving with {parameter})"),
        &pendulum,
        Stage::S2,
        Some(&asked),
    );
    s
}

#[test]
fn a_real_multiplier_that_moves_with_a_parameter_sends_it_the_difference_route() {
    // ε' = 1 + 0.01 (m1 − m1₀): the vertical mode moves by f/200 per kg through ε', against
    // −f/80 per kg through the mass
    check_real_multiplier_moving_with("m1", 0.01);
}

#[test]
fn a_damping_parameter_a_real_multiplier_reads_moves_the_modes() {
    // A parameter only the damping reads moves no mode, and its column is exactly 0 without
    // computing anything, unless a real multiplier ε' reads it: with ε' = 1 + 0.001 (T − T₀)
    // the vertical mode moves with the temperature (f/2000 per K), which must be
    // differenced, not taken for an exact zero; without that ε' it is an exact zero again.
    let s = check_real_multiplier_moving_with("temperature", 0.001);
    assert!(s.dfdp.iter().any(|row| row[0] != 0.0), "{:?}", s.dfdp);
    let s = modes_of(&case("pendulum"), Stage::S2, Some(&["temperature"]));
    assert_eq!(s.exact, vec![true]);
    assert!(s.dfdp.iter().all(|row| row[0] == 0.0), "{:?}", s.dfdp);
}

#[test]
fn mode_sensitivities_are_exact_wherever_the_build_has_a_tangent() {
    // the exact route (dual numbers through the build, the terms and the equilibrium) is
    // taken by every parameter whose build has an exact tangent, at every stage the quad's
    // kinds reach, and by none asked for with `differences`; the numbers of both routes are
    // checked against re-solved differences in quad_against_re_solved and above
    let quad = case("quad");
    for stage in [Stage::S0A, Stage::S1A, Stage::S2] {
        let s = modes_of(&quad, stage, None);
        // 82 differentiable parameters, all exact: 71 read by the mechanics, all with an
        // exact build; 11 exact zeros with nothing computed: the maraging loss angle and
        // the temperature, read only by the damping's loss angles and the noise (by no real
        // multiplier ε' and no switch), and 9 material constants nothing in the quad reads
        // (its wires carry their own moduli Yn, Y1..Y3, its blades a frequency; `pendkit
        // params quad` lists no reader for them)
        assert!(s.exact.iter().all(|&e| e), "stage {stage}: {:?}", s.exact);
        assert_eq!(
            s.exact_build.iter().filter(|&&e| e).count(),
            71,
            "stage {stage}"
        );
        let mut zeros: Vec<&str> = (0..s.parameters.len())
            .filter(|&j| s.exact[j] && !s.exact_build[j])
            .map(|j| s.parameters[j].as_str())
            .collect();
        zeros.sort_unstable();
        let mut expected = [
            "maraging_phi",
            "temperature",
            "silica_Y",
            "steel_Y",
            "maraging_rho",
            "maraging_C",
            "maraging_K",
            "maraging_alpha",
            "maraging_dlnE_dT",
            "maraging_Y",
            "maraging_dissdepth",
        ];
        expected.sort_unstable();
        assert_eq!(zeros, expected, "stage {stage}");
        for j in 0..s.parameters.len() {
            if s.exact[j] && !s.exact_build[j] {
                assert!(
                    s.dfdp.iter().all(|row| row[j] == 0.0),
                    "{}",
                    s.parameters[j]
                );
            }
        }
    }
    let mut request = SensitivityRequest::modes(Stage::S2);
    request.parameters = Some(vec!["m3".into(), "l3".into()]);
    request.differences = true;
    let s = sensitivities(&quad, &request).expect("sensitivities");
    assert_eq!(s.exact, vec![false, false]);
    // a response asked for too leaves the modes on the exact route (the response itself
    // is differenced); the responses alone are called exact nowhere
    let mut request = SensitivityRequest::modes(Stage::S2);
    request.parameters = Some(vec!["m3".into()]);
    request.tf = Some(("x00".into(), "x3".into()));
    request.freqs = vec![1.0];
    let s = sensitivities(&quad, &request).expect("sensitivities");
    assert_eq!(s.exact, vec![true]);
    request.modes = false;
    let s = sensitivities(&quad, &request).expect("sensitivities");
    assert_eq!(s.exact, vec![false]);
}

#[test]
fn every_bundled_model_exact_against_the_difference_route() {
    // every bundled model at stage 2, every parameter that takes the exact route, against
    // the difference route of the same library (a second method: the stage rebuilt and
    // re-solved at p ± h, p ± 2h and its matrices differenced, sharing with the exact route
    // only the energies and the eigenvector algebra). The difference route's error is its
    // rounding, ~10⁻¹⁶|X|/h = 10⁻¹³ of the matrices, and its truncation ~10⁻¹²; measured,
    // the two agree to 10⁻⁷ of a column's largest |df/dp| on the quad. Tolerance: 10⁻⁶ of
    // that largest entry, plus a floor for columns the modes barely feel, where the
    // difference is rounding noise around the exact value: 10⁻¹⁰ of the highest frequency
    // per unit relative change of p, and for a parameter whose value is 0 (stepped by
    // pendkit::sensitivity::ZERO_STEP = 10⁻⁶ of its unit) ε·f_max/10⁻⁶ ≈ 2·10⁻¹⁰ f_max
    // with a margin of 50: 10⁻⁸ f_max (the quad's top-wire separation sn = 0, whose
    // derivative is exactly 0 by symmetry, differences to ~10⁻⁸ Hz/m).
    for model in pendkit::catalogue::models() {
        let name = model.name();
        let case = case(name);
        let run = |differences: bool| {
            let mut request = SensitivityRequest::modes(Stage::S2);
            request.allow_unstable = true;
            request.differences = differences;
            sensitivities(&case, &request).unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let (exact, differenced) = (run(false), run(true));
        // a parameter on the edge of its declared domain (arm-cavity's power, 0 W by
        // default) has no central difference: the difference route refuses it, naming the
        // domain, and only the exact route gives its column (checked against the closed
        // form in tests/physics/optical_spring.rs)
        let on_edge = |p: &String| {
            differenced
                .not_differentiable
                .iter()
                .any(|(q, why)| q == p && why.contains("domain"))
        };
        let kept: Vec<&String> = exact.parameters.iter().filter(|p| !on_edge(p)).collect();
        assert_eq!(
            kept,
            differenced.parameters.iter().collect::<Vec<_>>(),
            "{name}"
        );
        let mut compared = 0;
        for (j, p) in exact.parameters.iter().enumerate() {
            if !exact.exact[j] || on_edge(p) {
                continue;
            }
            let d = differenced
                .parameters
                .iter()
                .position(|q| q == p)
                .unwrap_or(j);
            let column =
                |s: &Sensitivities, j: usize| -> Vec<f64> { s.dfdp.iter().map(|r| r[j]).collect() };
            let (a, b) = (column(&exact, j), column(&differenced, d));
            let largest = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let f_max = exact.modes_hz.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
            let floor = if exact.values[j] == 0.0 {
                1e-8 * f_max
            } else {
                1e-10 * f_max / exact.values[j].abs()
            };
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                let tol = 1e-6 * largest + floor;
                assert!(
                    (x - y).abs() <= tol,
                    "{name} d f{k}/d {p}: exact {x:e}, differenced {y:e} (tolerance {tol:e})"
                );
            }
            compared += 1;
        }
        assert!(compared > 0, "{name}: no parameter took the exact route");
    }
}

#[test]
fn wire_terms_in_the_equilibrium_close_the_exact_route() {
    // plug-in (wire) terms that join the equilibrium (1: for good, 2: for the equilibrium
    // only) are built around the start position, which moves with the parameters but whose
    // derivative the model does not carry: no parameter may take the exact route there
    // (measured before the route was closed: the pendulum's df/dl with 1 came out −0.538
    // against the difference route's −0.577), and the difference route answers
    for early in ["wire_terms_early=1", "wire_terms_early=2"] {
        let case = case("pendulum")
            .with_sets(&[early.to_string()])
            .expect("set");
        let s = modes_of(&case, Stage::S2, Some(&["l_fibre", "m1"]));
        assert_eq!(s.exact, vec![false, false], "{early}");
        assert_eq!(s.exact_build, vec![true, true], "{early}");
    }
}
