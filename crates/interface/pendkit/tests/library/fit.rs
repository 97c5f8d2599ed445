//! The fit against synthetic measurements: mode frequencies of the quad solved with known
//! parameter offsets (an independent solve of the same model at the true values, not the
//! fit's output), plus Gaussian noise of known σ from a fixed seed. The fit starts from the
//! nominal values and must land within 3 of its stated uncertainties of the truth, with a
//! χ²/dof the noise makes plausible.

use std::path::Path;

use pendkit::fit::FitError;
use pendkit::fit::FitOptions;
use pendkit::fit::JacobianMethod;
use pendkit::fit::exact_jacobian;
use pendkit::fit::exact_mode_jacobian;
use pendkit::fit::fit;
use pendkit::fit::mode_jacobian;
use pendkit::fit::{MatchedModes, MeasuredMode, MeasuredModes};
use pendkit::{Case, Error, Stage, run_stage};

/// SplitMix64 and Box–Muller: a reproducible standard normal sequence.
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // in (0, 1]: never ln(0)
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }
    fn sample(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// The modes of the quad with `sets` (the truth), each labelled by its dominant coordinate
/// with its three largest coordinates as the shape, with σ = `relative_sigma` × f and
/// Gaussian noise of that σ.
fn synthetic(sets: &[&str], relative_sigma: f64, seed: u64) -> MeasuredModes {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    synthetic_modes(&sets, relative_sigma, Some(seed))
}

/// [`synthetic`], with the noise from `seed`, or none.
fn synthetic_modes(sets: &[String], relative_sigma: f64, seed: Option<u64>) -> MeasuredModes {
    synthetic_modes_of("quad", sets, relative_sigma, seed)
}

/// [`synthetic_modes`] of a bundled `model`.
fn synthetic_modes_of(
    model: &str,
    sets: &[String],
    relative_sigma: f64,
    seed: Option<u64>,
) -> MeasuredModes {
    synthetic_modes_of_case(&Case::model(model).unwrap(), sets, relative_sigma, seed)
}

/// [`synthetic_modes`] of `case`: its modes as measurements
/// ([`MeasuredModes::of_modes`]), each moved by Gaussian noise of its σ from `seed`.
fn synthetic_modes_of_case(
    case: &Case,
    sets: &[String],
    relative_sigma: f64,
    seed: Option<u64>,
) -> MeasuredModes {
    let case = case.clone().with_sets(sets).unwrap();
    let r = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let mut measured =
        MeasuredModes::of_modes(Path::new("synthetic.csv"), &r.modes, relative_sigma);
    if let Some(seed) = seed {
        let mut rng = Normal(seed);
        for m in &mut measured.modes {
            m.hz += m.sigma_hz * rng.sample();
        }
    }
    measured
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

#[test]
fn recovers_five_quad_parameters_and_leaves_a_loss_angle_undetermined() {
    // truth: UIM and PUM masses and three wire lengths off by 1-3 %
    let truth = [
        ("m1", 22.011 * 1.03),
        ("m2", 39.6 * 0.98),
        ("l1", 0.3085 * 1.02),
        ("l2", 0.341 * 0.985),
        ("l3", 0.6 * 1.01),
    ];
    let sets: Vec<String> = truth.iter().map(|(n, v)| format!("{n}={v}")).collect();
    let set_refs: Vec<&str> = sets.iter().map(String::as_str).collect();
    let measured = synthetic(&set_refs, 2e-4, 15);
    // a sixth free parameter no mode frequency depends on: the silica loss angle (it sets
    // the fibres' imaginary stiffness only; the modes use the real stiffness)
    let free = names(&["m1", "m2", "l1", "l2", "l3", "silica_phi"]);
    let case = Case::model("quad").unwrap();
    let result = fit(&case, &measured, None, &free, &FitOptions::default()).unwrap();

    for (p, (name, value)) in result.parameters.iter().zip(truth) {
        assert_eq!(p.name, name);
        let sigma = p.uncertainty.expect("determined");
        assert!(sigma > 0.0 && sigma < 0.01 * value, "{name}: σ = {sigma}");
        // 3 σ: a 0.3 % chance per parameter for a correct fit with correct uncertainties
        assert!(
            (p.value - value).abs() < 3.0 * sigma,
            "{name}: fitted {} ± {sigma}, true {value}; {:#?}",
            p.value,
            result.modes
        );
    }
    let phi = &result.parameters[5];
    assert_eq!(
        phi.value, phi.start,
        "an undetermined parameter is not stepped"
    );
    assert_eq!(phi.uncertainty, None);
    assert_eq!(result.undetermined.len(), 1);
    let combination = &result.undetermined[0].combination;
    assert_eq!(combination.len(), 1, "{combination:?}");
    assert_eq!(combination[0].0, "silica_phi");
    assert!((combination[0].1 - 1.0).abs() < 1e-9);
    // 24 modes, 5 determined directions: 19 degrees of freedom; χ²_19/19 lies between
    // 0.285 and 2.306 with probability 99.8 % (scipy.stats.chi2.ppf(0.001 / 0.999, 19)/19)
    assert_eq!(result.dof, 19);
    let reduced = result.reduced_chi_squared.unwrap();
    assert!((0.285..2.306).contains(&reduced), "χ²/dof = {reduced}");
    assert!(result.explains_data);
    assert_eq!(result.max_reduced_chi_squared, 100.0);
    // every measured mode is matched to the mode it was generated from
    for (m, r) in measured.modes.iter().zip(&result.modes) {
        assert_eq!(m.label, r.model_label);
        assert!(r.normalized.abs() < 4.0, "{r:?}");
    }
    assert_eq!(result.jacobian, JacobianMethod::Exact);

    // the same fit with central differences for the Jacobian: the same minimum (the
    // Jacobians agree to ~1e-8, so the converged values to far below their uncertainties;
    // 1e-3 σ leaves room for where each run's last step stopped, within the convergence
    // test's χ² gain of 1e-9 χ²), the same uncertainties to 1e-4 of themselves
    let options = FitOptions {
        jacobian: JacobianMethod::Differences,
        ..FitOptions::default()
    };
    let differenced = fit(&case, &measured, None, &free, &options).unwrap();
    assert_eq!(differenced.jacobian, JacobianMethod::Differences);
    for (a, b) in result.parameters.iter().zip(&differenced.parameters) {
        let sigma = a.uncertainty.unwrap_or(f64::INFINITY);
        assert!((a.value - b.value).abs() <= 1e-3 * sigma, "{a:?} {b:?}");
        match (a.uncertainty, b.uncertainty) {
            (Some(x), Some(y)) => assert!((x - y).abs() <= 1e-4 * x, "{a:?} {b:?}"),
            (x, y) => assert_eq!(x, y),
        }
    }
}

#[test]
fn the_exact_jacobian_agrees_with_central_differences() {
    // The fit's two Jacobians at the quad's nominal values, for parameters of every sort
    // the fit takes: masses, wire lengths, an inertia, a blade tip's position (n0, which
    // the dual build moves by the tip's points), and a loss angle no mode depends on. The
    // reference is the central difference of the re-solved frequencies (step 1e-4 of each
    // value): its truncation error ~(1e-4)² of a column's scale and its rounding ~1e-15 f
    // over 2e-4 both sit far below 1e-6 of the column's largest entry, the tolerance.
    // Measured: ≤ 3e-8 for all but I1y, 1.5e-7 there (its pitch mode sits 1.2 mHz from
    // the UIM's transverse mode, and the difference's truncation grows with the curvature
    // of the near crossing).
    let case = Case::model("quad").unwrap();
    let measured = synthetic(&[], 1e-4, 3);
    let free = names(&["m1", "m2", "l1", "l3", "I1y", "n0", "silica_phi"]);
    let (_, resolved) = case.build().unwrap();
    let values: Vec<f64> = free.iter().map(|n| resolved.get(n).unwrap()).collect();
    let solution = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let matched = MatchedModes::by_label(&solution, &measured).unwrap();
    let (hz, exact) = exact_mode_jacobian(&case, Stage::S2, &free, &values, &matched).unwrap();
    let (hz_d, differenced) =
        mode_jacobian(&case, Stage::S2, &free, &values, &matched, 1e-4).unwrap();
    assert_eq!(hz, hz_d);
    assert_eq!((exact.nrows(), exact.ncols()), (24, free.len()));
    for (p, name) in free.iter().enumerate() {
        let scale = differenced.column(p).amax();
        for i in 0..exact.nrows() {
            let (e, d) = (exact[(i, p)], differenced[(i, p)]);
            assert!(
                (e - d).abs() <= 1e-6 * scale,
                "{name}, mode {} ({}): exact {e:e}, differences {d:e}",
                i + 1,
                matched.labels[i]
            );
        }
    }
    // the loss angle moves no mode: both exactly 0
    assert_eq!(exact.column(6).amax(), 0.0);
    assert_eq!(differenced.column(6).amax(), 0.0);
    // a parameter list that does not fit the values is a one-line error naming it
    let e = exact_mode_jacobian(&case, Stage::S2, &free, &values[1..], &matched).unwrap_err();
    assert!(e.to_string().contains("values"), "{e}");
    // and so are modes matched in another solution than the one at `values`
    let mut shifted = values.clone();
    shifted[0] *= 1.01;
    let e = exact_mode_jacobian(&case, Stage::S2, &free, &shifted, &matched).unwrap_err();
    assert!(e.to_string().contains("matched"), "{e}");
}

#[test]
fn matching_by_shape_survives_a_mode_crossing() {
    // The UIM's pitch mode (3.3436 Hz) sits 1.2 mHz above its transverse mode (3.3424 Hz,
    // labelled y1); a 4 % larger UIM pitch inertia I1y moves it below. Check the crossing
    // independently first, then fit I1y (and m1) from the start value across it.
    let hz = |sets: &[String]| -> (f64, f64) {
        let case = Case::model("quad").unwrap().with_sets(sets).unwrap();
        let r = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
        let find = |label: &str| r.modes.modes.iter().find(|m| m.label == label).unwrap().hz;
        (find("pitch1"), find("y1"))
    };
    let true_i1y = 0.0598 * 1.04;
    let (pitch_start, y_start) = hz(&[]);
    let (pitch_true, y_true) = hz(&[format!("I1y={true_i1y}")]);
    assert!(pitch_start > y_start && pitch_true < y_true, "no crossing");

    let measured = synthetic(&[&format!("I1y={true_i1y}")], 1e-4, 7);
    let free = names(&["I1y", "m1"]);
    let case = Case::model("quad").unwrap();
    let result = fit(&case, &measured, None, &free, &FitOptions::default()).unwrap();
    let i1y = &result.parameters[0];
    let sigma = i1y.uncertainty.unwrap();
    assert!((i1y.value - true_i1y).abs() < 3.0 * sigma, "{i1y:?}");
    let m1 = &result.parameters[1];
    assert!(
        (m1.value - 22.011).abs() < 3.0 * m1.uncertainty.unwrap(),
        "{m1:?}"
    );
    // the pitch1 measurement is matched to the pitch1 mode, now below y1 in frequency
    let pitch = result.modes.iter().find(|r| r.label == "pitch1").unwrap();
    let y = result.modes.iter().find(|r| r.label == "y1").unwrap();
    assert_eq!(pitch.model_label, "pitch1");
    assert!(pitch.mode < y.mode, "{pitch:?} {y:?}");
    assert!(pitch.normalized.abs() < 4.0 && y.normalized.abs() < 4.0);
}

fn fit_error(text: &str, free: &[&str]) -> String {
    let measured = match MeasuredModes::parse(Path::new("measured.csv"), text) {
        Ok(m) => m,
        Err(e) => return e.to_string(),
    };
    let case = Case::model("quad").unwrap();
    match fit(&case, &measured, None, &names(free), &FitOptions::default()) {
        Ok(_) => "no error".into(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_measurements_are_refused_with_file_and_line() {
    let cases = [
        (
            "label,hz,sigma_hz\nx3,0.43,0.001\n\nz3,0.67,0\n",
            "measured.csv:4: sigma_hz must be positive",
        ),
        ("x3,0.43,-1\n", "measured.csv:1: sigma_hz must be positive"),
        (
            "# comment\nx3,nan,0.001\n",
            "measured.csv:2: hz must be positive and finite",
        ),
        ("x3,abc,0.001\n", "measured.csv:1: hz 'abc' is not a number"),
        (
            "x3,0.43\n",
            "measured.csv:1: expected label,hz,sigma_hz[,shape], got 2 fields",
        ),
        ("x3,0.43,0.001,yaw1+\n", "measured.csv:1: shape"),
        ("# nothing\n", "measured.csv: no measured modes"),
        // an uncertainty below an f64's rounding of the value (2.2e-16 relative): its
        // weight would overflow χ² (1e-300 did, and the fit reported chi^2 = inf)
        (
            "x3,0.43,0.001\ny3,0.46,1e-300\n",
            "measured.csv:2: sigma_hz = 1e-300 is below the rounding of hz = 0.46",
        ),
    ];
    for (text, expected) in cases {
        let message = fit_error(text, &["m1"]);
        assert!(message.starts_with(expected), "{message}");
    }
}

#[test]
fn fits_that_cannot_be_made_say_why() {
    let modes = "x3,0.4328,0.001\ny3,0.4681,0.001\npitch3,0.4919,0.001\n";
    let cases: [(&str, &[&str], &str); 7] = [
        (
            modes,
            &["m9"],
            "free parameter 'm9': not a parameter of model 'quad'",
        ),
        (modes, &["m1", "m1"], "free parameter 'm1': listed twice"),
        (
            modes,
            &["m1", "m2", "m3"],
            "3 measurements for 3 free parameters",
        ),
        (
            "x3,0.4328,0.001\nbanana,1,0.1\n",
            &["m1"],
            "measured.csv:2: 'banana' is neither a variable",
        ),
        (
            "x3,0.4328,0.001\nY,0.6,0.001\n",
            &["m1"],
            "measured.csv:2: label 'Y' is a mode family",
        ),
        // x3 moves mostly in modes 1 and 7 (64 % and 26 %): a third x3 finds no mode left
        // with a tenth of its energy there within a factor 2 of it (the third was at 2 Hz,
        // which the frequency window now refuses with its own message)
        (
            "x3,0.4328,0.001\nx3,0.98,0.001\nx3,0.9,0.001\n",
            &["m1"],
            "measured.csv:3: no model mode left that moves x3",
        ),
        // a count cannot be fitted: refused by name before the fit (it was the exact
        // Jacobian's error about its step)
        (
            "x3,0.4328,0.001\ny3,0.4681,0.001\npitch3,0.4919,0.001\n",
            &["m1", "n_beads"],
            "free parameter 'n_beads': n_beads is a count or a switch",
        ),
    ];
    for (text, free, expected) in cases {
        let message = fit_error(text, free);
        assert!(message.starts_with(expected), "{message}");
    }
    // a family label with a shape: the yaw mode that moves yaw1 most
    let ok = fit_error("x3,0.4328,0.001\nY,3.05,0.001,yaw1\n", &["m1"]);
    assert_eq!(ok, "no error");
}

#[test]
fn a_fit_out_of_iterations_says_so_with_its_last_state() {
    let measured = synthetic(&["m1=23"], 1e-4, 3);
    let case = Case::model("quad").unwrap();
    let options = FitOptions {
        max_iterations: 0,
        ..FitOptions::default()
    };
    let err = fit(&case, &measured, None, &names(&["m1"]), &options).unwrap_err();
    assert!(matches!(err, Error::Fit(FitError::NotConverged { .. })));
    let message = err.to_string();
    // the file fitted to is named (it was not)
    assert!(
        message.starts_with("synthetic.csv: the fit did not converge") && message.contains("m1="),
        "{message}"
    );
}

#[test]
fn a_measured_transfer_function_joins_the_modes() {
    // truth: fibres 1 % longer and a 2 % heavier test mass; measured: three test-mass modes
    // and |x3/x00| at five frequencies between the resonances, from an independent solve
    let sets = ["l3=0.606".to_string(), "m3=40.392".to_string()];
    let case = Case::model("quad").unwrap().with_sets(&sets).unwrap();
    let r = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let freqs = [0.2, 0.75, 1.6, 5.0, 20.0];
    let h = r.transfer("x00", "x3", &freqs).unwrap();
    let mut rng = Normal(11);
    let mut text = String::from("# input = x00\n# output = x3\nfreq_hz,abs,sigma_abs\n");
    for (f, z) in freqs.iter().zip(&h) {
        let sigma = 1e-3 * z.norm();
        text += &format!("{f},{},{sigma}\n", z.norm() + sigma * rng.sample());
    }
    let tf = pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), &text).unwrap();
    let all = synthetic(&["l3=0.606", "m3=40.392"], 1e-4, 5);
    let keep = ["x3", "pitch3", "z3"];
    let measured = MeasuredModes {
        path: all.path.clone(),
        modes: all
            .modes
            .into_iter()
            .filter(|m| keep.contains(&m.label.as_str()))
            .collect(),
    };
    assert_eq!(measured.modes.len(), 3);
    let result = fit(
        &Case::model("quad").unwrap(),
        &measured,
        Some(&tf),
        &names(&["l3", "m3"]),
        &FitOptions::default(),
    )
    .unwrap();
    assert_eq!(result.tf.len(), 5);
    for (p, truth) in result.parameters.iter().zip([0.606, 40.392]) {
        let sigma = p.uncertainty.unwrap();
        assert!((p.value - truth).abs() < 3.0 * sigma, "{p:?} {result:#?}");
    }
    // 8 measurements, 2 parameters
    assert_eq!(result.dof, 6);
}

#[test]
fn the_exact_jacobian_follows_a_resonance_that_differences_of_h_miss() {
    // |x3/x00| of the quad at its x3 mode's frequency (as the model solves it: |H| ≈ 1.3e5,
    // the peak a few 1e-6 of its frequency wide) and at two frequencies off resonance. The
    // reference: the fourth-order central difference of |H| re-solved at l3 and m3 ± h,
    // with h = 1e-7 and 5e-8 of the value on the peak (small enough not to move it across
    // its width) and 1e-4 and 5e-5 off it (where smaller steps meet the solves' rounding),
    // the two agreeing to 3e-6 first (a third of the tolerance; measured ≤ 5e-7, the
    // solves' rounding on the peak). The exact Jacobian's |TF| rows must match it to 1e-5
    // (measured ≤ 2.3e-6); the fit's central difference with its own step (1e-4) misses
    // the peak's row by tens of per cent.
    let case = Case::model("quad").unwrap();
    let solution = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let x3 = solution
        .modes
        .modes
        .iter()
        .find(|m| m.label == "x3")
        .unwrap()
        .hz;
    let freqs = [0.2, x3, 20.0];
    let mut text = String::from("# input = x00\n# output = x3\n");
    for f in freqs {
        text += &format!("{f:e},1,0.1\n");
    }
    let tf = pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), &text).unwrap();
    let free = names(&["l3", "m3"]);
    // the nominal values (the solution `matched` comes from)
    let (_, resolved) = case.build().unwrap();
    let values: Vec<f64> = free.iter().map(|n| resolved.get(n).unwrap()).collect();
    let matched = MatchedModes::by_label(&solution, &synthetic(&[], 1e-4, 3)).unwrap();
    let (_, rows) = exact_jacobian(&case, Stage::S2, &free, &values, &matched, Some(&tf)).unwrap();
    let rows = rows.expect("|TF| rows");
    let abs_h = |name: &str, value: f64, f: f64| {
        let c = case
            .clone()
            .with_sets(&[format!("{name}={value:e}")])
            .unwrap();
        let r = run_stage(c.build().unwrap().0, Stage::S2).unwrap();
        r.transfer("x00", "x3", &[f]).unwrap()[0].norm()
    };
    // fourth order: on the peak the second-order difference's truncation, (h/width)²,
    // would be 1e-5
    let central = |name: &str, p0: f64, f: f64, relative: f64| {
        let h = relative * p0;
        let at = |k: f64| abs_h(name, p0 + k * h, f);
        (at(-2.0) - 8.0 * at(-1.0) + 8.0 * at(1.0) - at(2.0)) / (12.0 * h)
    };
    let steps = [1e-4, 1e-7, 1e-4];
    for (i, (&f, step)) in freqs.iter().zip(steps).enumerate() {
        for (p, (name, p0)) in free.iter().zip(values.iter().copied()).enumerate() {
            let (a, b) = (central(name, p0, f, step), central(name, p0, f, step / 2.0));
            assert!(
                (a - b).abs() <= 3e-6 * b.abs(),
                "{name} at {f} Hz: {a} vs {b}"
            );
            let exact = rows[(i, p)];
            assert!(
                (exact - b).abs() <= 1e-5 * b.abs(),
                "{name} at {f} Hz: exact {exact}, reference {b}"
            );
        }
    }
    // on the peak the fit's central difference (second order, its step 1e-4) misses: m3's
    // row off by more than 10 %
    let coarse = {
        let m3 = values[1];
        let h = 1e-4 * m3;
        (abs_h("m3", m3 + h, freqs[1]) - abs_h("m3", m3 - h, freqs[1])) / (2.0 * h)
    };
    assert!(
        (coarse - rows[(1, 1)]).abs() > 0.1 * rows[(1, 1)].abs(),
        "{coarse}"
    );
    // values that do not fit the free parameters: a one-line error naming the function
    let e = exact_jacobian(&case, Stage::S2, &free, &values[..1], &matched, Some(&tf)).unwrap_err();
    let message = e.to_string();
    assert!(
        message.contains("exact_jacobian") && message.contains("values"),
        "{message}"
    );
}

#[test]
fn a_transfer_function_file_names_its_input_and_output() {
    let err =
        pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), "freq_hz,abs,sigma_abs\n1,2,0.1\n")
            .unwrap_err()
            .to_string();
    assert_eq!(err, "tf.csv: no '# input = NAME' line before the data");
    let err =
        pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), "# input = x00\n# output = x3\n1,2\n")
            .unwrap_err()
            .to_string();
    assert_eq!(
        err,
        "tf.csv:3: expected freq_hz,abs,sigma_abs, got 2 fields"
    );
    // the input and output each once, before the points: a second one or one among the
    // points was obeyed silently (the last one won)
    let cases = [
        (
            "# input = x00\n# output = x3\n# input = y00\n1,2,0.1\n",
            "tf.csv:3: a second '# input = NAME' line (the first is line 1)",
        ),
        (
            "# input = x00\n1,2,0.1\n# output = x3\n",
            "tf.csv:3: '# output = NAME' after the data (line 2): it goes before the points",
        ),
        (
            "# input =\n# output = x3\n1,2,0.1\n",
            "tf.csv:1: '# input =' names no input",
        ),
        (
            "# input = x00\n# output = x3\n1,2,1e-20\n",
            "tf.csv:3: sigma_abs = 1e-20 is below the rounding of abs = 2",
        ),
    ];
    for (text, expected) in cases {
        let err = pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), text)
            .unwrap_err()
            .to_string();
        assert!(err.starts_with(expected), "{err}");
    }
    // a header line before the directives is still a header
    let tf = pendkit::fit::MeasuredTf::parse(
        Path::new("tf.csv"),
        "freq_hz,abs,sigma_abs\n# input = x00\n# output = x3\n1,2,0.1\n",
    )
    .unwrap();
    assert_eq!((tf.input.as_str(), tf.output.as_str()), ("x00", "x3"));
    assert_eq!(tf.points[0].line, 4);
}

/// A residual whose square overflows χ² (an uncertainty legal for its own value, a model
/// value 10³⁰¹ of it away) names its line instead of a fit with chi^2 = inf.
#[test]
fn a_weighted_residual_too_large_to_square_names_its_line() {
    let measured =
        MeasuredModes::parse(Path::new("m.csv"), "x3,0.4328,0.001\ny3,0.4681,0.001\n").unwrap();
    let tf = pendkit::fit::MeasuredTf::parse(
        Path::new("tf.csv"),
        "# input = x00\n# output = x3\n0.5,1e-300,1e-301\n",
    )
    .unwrap();
    let case = Case::model("quad").unwrap();
    let err = fit(
        &case,
        &measured,
        Some(&tf),
        &names(&["m1"]),
        &FitOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.starts_with("tf.csv:3: the weighted residual (model - measured)/sigma_abs = "),
        "{err}"
    );
}

#[test]
fn match_modes_follows_each_mode_across_a_crossing() {
    // The same crossing as above (pitch1 moves below y1 with a 4 % larger I1y). The labels
    // (each mode's dominant coordinate) are computed without any overlap, so they are an
    // independent check of which new mode continues which old one.
    let run = |sets: &[String]| {
        let case = Case::model("quad").unwrap().with_sets(sets).unwrap();
        run_stage(case.build().unwrap().0, Stage::S2).unwrap()
    };
    let nominal = run(&[]);
    let crossed = run(&[format!("I1y={}", 0.0598 * 1.04)]);
    let index = |r: &pendkit::StageResult, label: &str| {
        r.modes.modes.iter().position(|m| m.label == label).unwrap()
    };
    let (pitch_old, y_old) = (index(&nominal, "pitch1"), index(&nominal, "y1"));
    let (pitch_new, y_new) = (index(&crossed, "pitch1"), index(&crossed, "y1"));
    assert!(pitch_old > y_old && pitch_new < y_new, "no crossing");

    let continued = crossed.match_modes(&nominal).unwrap();
    assert_eq!(continued.len(), nominal.modes.modes.len());
    assert_eq!(continued[pitch_old].unwrap().0, pitch_new);
    assert_eq!(continued[y_old].unwrap().0, y_new);
    // every mode keeps its label: a 4 % inertia change does not turn one mode into another
    for (old, pair) in continued.iter().enumerate() {
        let (new, overlap) = pair.expect("as many modes");
        assert_eq!(
            crossed.modes.modes[new].label, nominal.modes.modes[old].label,
            "mode {old}"
        );
        assert!(
            overlap > 0.5 && overlap <= 1.0 + 1e-12,
            "mode {old}: {overlap}"
        );
    }
    // against itself: each mode is itself, with overlap 1 to rounding (mass-normalised
    // shapes, so u'Mu = 1 to about n·ε)
    for (k, pair) in nominal.match_modes(&nominal).unwrap().iter().enumerate() {
        let (same, overlap) = pair.unwrap();
        assert_eq!(same, k);
        assert!((overlap - 1.0).abs() < 1e-12, "mode {k}: {overlap}");
    }
    // a run over other coordinates is refused, naming the argument
    let triple = run_stage(Case::model("triple").unwrap().build().unwrap().0, Stage::S2).unwrap();
    let e = triple.match_modes(&nominal).unwrap_err().to_string();
    assert!(e.contains("reference"), "{e}");
}

/// Old failure: a fit that could not explain its data (χ²/dof 1.6·10⁷ with a duplicated
/// measurement, 2.4·10⁵ in a wrong minimum) returned its values like any other, and the
/// command printed "every parameter is determined" and exited 0. The result now carries
/// the verdict.
#[test]
fn a_fit_that_cannot_explain_its_data_says_so_in_its_result() {
    let mut measured = synthetic(&[], 2e-4, 21);
    // z2 measured 10 % high: no UIM mass puts it there and keeps the other modes
    let z2 = measured.modes.iter_mut().find(|m| m.label == "z2").unwrap();
    z2.hz *= 1.1;
    let case = Case::model("quad").unwrap();
    let free = names(&["m1"]);
    let result = fit(&case, &measured, None, &free, &FitOptions::default()).unwrap();
    let reduced = result.reduced_chi_squared.unwrap();
    assert!(reduced > 100.0, "χ²/dof = {reduced}");
    assert!(!result.explains_data);
    // no start explains the data: the four more starts were all tried
    assert_eq!(result.starts, 5);
    // what would help, best first: a first-order estimate that a refit with the named
    // parameter freed as well (a second, nonlinear route) confirms to 1 % (the estimate
    // is linear in the new parameter's step; the refit's step here is small)
    assert!(!result.would_help.is_empty() && result.would_help.len() <= 3);
    assert!(
        result
            .would_help
            .windows(2)
            .all(|w| w[0].reduced_chi_squared <= w[1].reduced_chi_squared)
    );
    let best = &result.would_help[0];
    assert!(best.reduced_chi_squared < reduced);
    let refit = fit(
        &case,
        &measured,
        None,
        &names(&["m1", &best.parameter]),
        &FitOptions {
            more_starts: 0,
            ..FitOptions::default()
        },
    )
    .unwrap();
    let refit_reduced = refit.reduced_chi_squared.unwrap();
    assert!(
        (refit_reduced / best.reduced_chi_squared - 1.0).abs() < 0.01,
        "{} predicted {}, refit {refit_reduced}",
        best.parameter,
        best.reduced_chi_squared
    );
    // the worst residual is z2's, and it names its line
    let worst = result
        .modes
        .iter()
        .max_by(|a, b| a.normalized.abs().total_cmp(&b.normalized.abs()))
        .unwrap();
    assert_eq!((worst.label.as_str(), worst.line), ("z2", worst.mode + 1));
    // judged by a threshold above its χ²/dof, the same fit explains its data
    let lenient = FitOptions {
        max_reduced_chi_squared: 2.0 * reduced,
        ..FitOptions::default()
    };
    let again = fit(&case, &measured, None, &free, &lenient).unwrap();
    assert!(again.explains_data && again.starts == 1);
    let strict_once = FitOptions {
        more_starts: 0,
        ..FitOptions::default()
    };
    let once = fit(&case, &measured, None, &free, &strict_once).unwrap();
    assert!(!once.explains_data);
    assert_eq!(again.parameters, once.parameters);
    // a threshold that is not positive cannot judge anything
    for bad in [0.0, -1.0, f64::NAN] {
        let options = FitOptions {
            max_reduced_chi_squared: bad,
            ..FitOptions::default()
        };
        let e = fit(&case, &measured, None, &free, &options).unwrap_err();
        assert!(e.to_string().contains("max_reduced_chi_squared"), "{e}");
    }
}

/// Old failures: the shape column's order changed which mode a measurement matched
/// (`columns.dedup()` removed only adjacent duplicates, so the label's own coordinate
/// named again in the shape counted twice or once by where it stood); and measurements
/// were matched one at a time, best first, so that one could take the mode another
/// needed. Now the coordinates are a set and all measurements are assigned at once.
#[test]
fn matching_ignores_the_order_of_the_shape_column() {
    let case = Case::model("quad").unwrap();
    let solution = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let measured = synthetic(&[], 1e-4, 3);
    let reference = MatchedModes::by_label(&solution, &measured).unwrap();
    // every measured mode is its own model mode
    assert_eq!(reference.indices, (0..24).collect::<Vec<_>>());
    // the shape reversed, and with the label's coordinate named again at each place
    for place in 0..=3 {
        let mut shuffled = measured.clone();
        for m in &mut shuffled.modes {
            m.shape.reverse();
            m.shape.insert(place.min(m.shape.len()), m.label.clone());
        }
        let matched = MatchedModes::by_label(&solution, &shuffled).unwrap();
        assert_eq!(matched.indices, reference.indices, "label at {place}");
    }
}

/// Old failure: no frequency check paired a 50 Hz measurement with the 8.76 Hz mode
/// that moves z2 (and a 0.67 Hz one with a 2.5 Hz mode). A mode more than a factor 2
/// (`FitOptions::frequency_window`) away cannot match: the error names the line and the
/// mode that moves the coordinate most.
#[test]
fn a_measurement_far_from_every_mode_that_moves_it_is_refused_by_line() {
    let message = fit_error("x3,0.4328,0.001\ny3,0.4681,0.001\nz2,50,0.1\n", &["m1"]);
    assert!(
        message.starts_with(
            "measured.csv:3: no model mode within a factor 2 of 50 Hz moves z2 (at least 10 % \
             of its kinetic energy); the one that moves it most is mode 23 (z2 V, 8.7621 Hz)"
        ),
        "{message}"
    );
    // a wider window, asked for, lets it match (and the fit then fails its verdict)
    let measured = MeasuredModes::parse(
        Path::new("measured.csv"),
        "x3,0.4328,0.001\ny3,0.4681,0.001\nz2,50,0.1\n",
    )
    .unwrap();
    let options = FitOptions {
        frequency_window: 10.0,
        ..FitOptions::default()
    };
    let case = Case::model("quad").unwrap();
    let result = fit(&case, &measured, None, &names(&["m1"]), &options).unwrap();
    assert!(!result.explains_data);
}

/// Old failure: a duplicated measurement under a family label matched a second mode with
/// under 10 % share, or both copies went for one mode. Now the two copies go to two
/// different modes, each with its share, or the second is refused naming the mode the
/// first took.
#[test]
fn duplicated_measurements_never_share_a_mode() {
    let case = Case::model("quad").unwrap();
    let solution = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    for duplicate in ["pitch2", "yaw1", "x3"] {
        // half the modes (all 24 and a copy are more measurements than modes: refused)
        let mut measured = synthetic(&[], 1e-4, 3);
        measured.modes.retain(|m| m.hz < 3.1);
        let copy = measured
            .modes
            .iter()
            .find(|m| m.label == duplicate)
            .unwrap()
            .clone();
        measured.modes.push(MeasuredMode { line: 99, ..copy });
        match MatchedModes::by_label(&solution, &measured) {
            Ok(matched) => {
                let mut indices = matched.indices.clone();
                indices.sort_unstable();
                indices.dedup();
                assert_eq!(indices.len(), measured.modes.len(), "{duplicate}");
            }
            Err(e) => {
                let message = e.to_string();
                assert!(
                    message.starts_with("synthetic.csv:")
                        && message.contains("a mode is measured once"),
                    "{message}"
                );
            }
        }
    }
    // a family label twice: the yaw mode that moves yaw1 most, then no other
    let message = fit_error(
        "x3,0.4328,0.001\nY,3.05,0.001,yaw1\nY,3.05,0.001,yaw1\n",
        &["m1"],
    );
    assert!(
        message.starts_with("measured.csv:3: no model mode"),
        "{message}"
    );
}

/// Old failure: a UTF-8 byte-order mark (which spreadsheet programs write) broke line 1
/// of the measurement file. It, CRLF line ends and spaces around the fields are accepted.
#[test]
fn a_byte_order_mark_crlf_and_spaces_are_accepted() {
    let clean = MeasuredModes::parse(
        Path::new("m.csv"),
        "label,hz,sigma_hz,shape\nx3,0.4328,0.001,x3+x2\ny3,0.4681,0.001\n",
    )
    .unwrap();
    let windows = MeasuredModes::parse(
        Path::new("m.csv"),
        "\u{feff}label , hz , sigma_hz , shape\r\n x3 , 0.4328 ,0.001 , x3 + x2 \r\n\ty3,\t0.4681, 0.001\r\n",
    )
    .unwrap();
    assert_eq!(windows, clean);
    // without a header the mark sat in front of the first label
    let first = MeasuredModes::parse(Path::new("m.csv"), "\u{feff}x3,0.4328,0.001\r\n").unwrap();
    assert_eq!(first.modes[0].label, "x3");
    let tf = pendkit::fit::MeasuredTf::parse(
        Path::new("tf.csv"),
        "\u{feff}# input = x00\r\n# output = x3\r\n 1 , 2 , 0.1 \r\n",
    )
    .unwrap();
    assert_eq!((tf.input.as_str(), tf.points[0].abs), ("x00", 2.0));
}

/// Old failure: `--free n_beads` (a count) or a switch failed with the exact Jacobian's
/// error about a step of −2e-6; it is refused by name before the fit starts.
#[test]
fn counts_and_switches_are_refused_by_name() {
    let modes = "x3,0.4328,0.001\ny3,0.4681,0.001\npitch3,0.4919,0.001\n";
    for free in [["m1", "n_beads"], ["wire_terms_early", "m1"]] {
        let message = fit_error(modes, &free);
        let name = free.iter().find(|n| **n != "m1").unwrap();
        let expected =
            format!("free parameter '{name}': {name} is a count or a switch (the model refuses");
        assert!(message.starts_with(&expected), "{message}");
        assert!(
            message.contains("counts and switches cannot be fitted"),
            "{message}"
        );
    }
}

/// Old failure: fitting 20 quad parameters (stage lengths, blade frequencies, break-offs,
/// masses, two pitch inertias) from 20 % away to its 24 noise-free modes stalled for some
/// sign patterns of the offsets ("did not converge in 50 iterations", χ² 10⁷): modes
/// followed by overlap across large steps had been taken for others. This pattern now
/// converges to the truth after restarting from where the descent stalled, its
/// measurements matched again by label.
#[test]
fn a_stalled_twenty_parameter_fit_restarts_and_converges() {
    let free = names(&[
        "ln", "l1", "l2", "l3", "ufcn", "ufc1", "ufc2", "dm", "dn", "d0", "d1", "d2", "d3", "d4",
        "mn", "m1", "m2", "m3", "Iny", "I1y",
    ]);
    let signs = "+---+-+-+++-----+---";
    let case = Case::model("quad").unwrap();
    let (_, resolved) = case.build().unwrap();
    let truth: Vec<f64> = free
        .iter()
        .zip(signs.chars())
        .map(|(n, sign)| resolved.get(n).unwrap() * if sign == '+' { 1.2 } else { 0.8 })
        .collect();
    let sets: Vec<String> = free
        .iter()
        .zip(&truth)
        .map(|(n, v)| format!("{n}={v}"))
        .collect();
    let measured = synthetic_modes(&sets, 1e-4, None);
    let result = fit(&case, &measured, None, &free, &FitOptions::default()).unwrap();
    assert!(
        result.restarts >= 1,
        "converged without a restart: {}",
        result.iterations
    );
    assert!(result.explains_data);
    for (p, t) in result.parameters.iter().zip(&truth) {
        assert!((p.value - t).abs() <= 1e-5 * t.abs(), "{p:?} against {t}");
    }
}

/// The sign patterns of `benches/benches/fit_starts.rs` (SplitMix64 from seed 2026, one
/// sign per free parameter, patterns in order): pattern `k` of `n` parameters.
fn bench_pattern(k: usize, n: usize) -> Vec<bool> {
    let mut state: u64 = 2026;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) & 1 == 1
    };
    let mut signs = Vec::new();
    for _ in 0..=k {
        signs = (0..n).map(|_| next()).collect();
    }
    signs
}

/// Issue 35: a 24-mode fit of 20 quad parameters (18 modes, 15 parameters of the triple)
/// from a start 20 % away, for sign patterns of the offsets where one descent from the
/// start stalls (the quad's pattern 5 of the bench `fit_starts`, also from four more
/// starts; the triple's 19) or ends in a wrong minimum that passes for a fit (χ²/dof 3.8
/// and 14 on noise-free data: the quad's 18 and 44, also from four starts). The bench
/// measures all 80 patterns of each model (80 of 80 to the truth, docs/fitting.md); the
/// test keeps the hardest, since each costs seconds in a test build. From eight starts (the case's values and seven moved by up to ±20 %, the best kept)
/// each converges to the truth: every parameter within 1e-4 of it, the truth being a
/// solve of the model at the offset values (noise-free, σ = 1e-4 f; a converged fit is
/// within 1e-6 of it, the tolerance leaves room for the weakest-determined direction).
#[test]
fn fits_from_twenty_percent_away_converge_to_the_truth_from_eight_starts() {
    let quad = names(&[
        "ln", "l1", "l2", "l3", "ufcn", "ufc1", "ufc2", "dm", "dn", "d0", "d1", "d2", "d3", "d4",
        "mn", "m1", "m2", "m3", "Iny", "I1y",
    ]);
    let triple = names(&[
        "l1", "l2", "l3", "ufc1", "ufc2", "d0", "d1", "d2", "d3", "d4", "m1", "m2", "m3", "I1y",
        "I2y",
    ]);
    let options = FitOptions {
        starts: 8,
        ..FitOptions::default()
    };
    for (model, free, patterns) in [
        ("quad", &quad, &[5, 18, 44][..]),
        ("triple", &triple, &[19][..]),
    ] {
        let case = Case::model(model).unwrap();
        let (_, resolved) = case.build().unwrap();
        for &k in patterns {
            let truth: Vec<f64> = free
                .iter()
                .zip(bench_pattern(k, free.len()))
                .map(|(n, up)| resolved.get(n).unwrap() * if up { 1.2 } else { 0.8 })
                .collect();
            let sets: Vec<String> = free
                .iter()
                .zip(&truth)
                .map(|(n, v)| format!("{n}={v}"))
                .collect();
            let measured = synthetic_modes_of(model, &sets, 1e-4, None);
            let result = fit(&case, &measured, None, free, &options).unwrap();
            for (p, t) in result.parameters.iter().zip(&truth) {
                assert!(
                    (p.value - t).abs() <= 1e-4 * t.abs(),
                    "{model} pattern {k}: {} = {} against {t}",
                    p.name,
                    p.value
                );
            }
            assert!(result.explains_data && result.starts == 8, "{model} {k}");
        }
    }
}

/// A fit whose first start explains its data tries no more starts; one that does not
/// explain it tries `more_starts` more, one at a time, and says how many it tried.
#[test]
fn more_starts_only_when_the_fit_does_not_explain_its_data() {
    let quad = names(&[
        "ln", "l1", "l2", "l3", "ufcn", "ufc1", "ufc2", "dm", "dn", "d0", "d1", "d2", "d3", "d4",
        "mn", "m1", "m2", "m3", "Iny", "I1y",
    ]);
    let case = Case::model("quad").unwrap();
    let (_, resolved) = case.build().unwrap();
    // pattern 0 converges from the start; pattern 6 ends at chi^2/dof 3.5e4 from it
    for (k, tried_at_least) in [(0, 1), (6, 2)] {
        let sets: Vec<String> = quad
            .iter()
            .zip(bench_pattern(k, quad.len()))
            .map(|(n, up)| {
                format!(
                    "{n}={}",
                    resolved.get(n).unwrap() * if up { 1.2 } else { 0.8 }
                )
            })
            .collect();
        let measured = synthetic_modes_of("quad", &sets, 1e-4, None);
        let result = fit(&case, &measured, None, &quad, &FitOptions::default()).unwrap();
        if k == 0 {
            assert_eq!(result.starts, 1);
        } else {
            assert!(
                result.starts >= tried_at_least && result.starts <= 5,
                "{}",
                result.starts
            );
        }
        let none = FitOptions {
            more_starts: 0,
            ..FitOptions::default()
        };
        let single = fit(&case, &measured, None, &quad, &none).unwrap();
        assert_eq!(single.starts, 1);
        assert_eq!(single.explains_data, k == 0, "pattern {k}");
    }
}

/// Issue 38: a measured-data file is read only if it is a regular file (a device such as
/// /dev/zero was read until memory ran out), and its rows are counted before one is
/// parsed: past `PENDKIT_MAX_MEASURED_ROWS` (10 000 by default) the file is refused at the
/// first row beyond (a 100 000-row |TF| file made `fit` take 334 s).
#[test]
fn measured_files_are_bounded_before_they_are_read_or_parsed() {
    let e = MeasuredModes::read(Path::new("/dev/zero")).unwrap_err();
    assert!(e.to_string().contains("not a regular file"), "{e}");
    let limit = pendkit_limits::MEASURED_ROWS.value().unwrap();
    let mut modes = String::from("label,hz,sigma_hz\n");
    let mut tf = String::from("# input = x00\n# output = x3\n");
    for k in 0..=limit {
        modes.push_str(&format!("x3,{},0.001\n", 0.4 + 1e-6 * k as f64));
        tf.push_str(&format!("{},1,0.1\n", 1.0 + 1e-3 * k as f64));
    }
    let e = MeasuredModes::parse(Path::new("m.csv"), &modes).unwrap_err();
    // the header is line 1, row k (from 0) line k + 2
    let expected = format!("m.csv:{}: ", limit + 2);
    assert!(
        e.to_string().starts_with(&expected) && e.to_string().contains("PENDKIT_MAX_MEASURED_ROWS"),
        "{e}"
    );
    let e = pendkit::fit::MeasuredTf::parse(Path::new("tf.csv"), &tf).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("tf.csv:{}: ", limit + 3)),
        "{e}"
    );
    // at the limit, the rows are read (and then judged as measurements)
    let at_limit: String = modes
        .lines()
        .take(limit + 1)
        .map(|l| format!("{l}\n"))
        .collect();
    let e = MeasuredModes::parse(Path::new("m.csv"), &at_limit).map(|m| m.modes.len());
    assert_eq!(e.unwrap(), limit);
}
