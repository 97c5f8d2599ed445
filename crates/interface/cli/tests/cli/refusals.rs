//! What the command line refuses (issue 11), one test per defect, named by what it guards:
//! each bad input gives exit status 1 and one line on stderr naming what and where, and
//! never a table, a file or a non-finite number.

use crate::common;
use common::pendkit;

/// Runs and expects a refusal: failure, nothing on stdout, one line on stderr containing
/// every one of `words`.
#[track_caller]
fn refused(args: &[&str], words: &[&str]) -> String {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(!ok, "{args:?} succeeded: {stdout}");
    assert!(stdout.is_empty(), "{args:?} printed: {stdout}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    for w in words {
        assert!(stderr.contains(w), "{args:?}: '{w}' not in {stderr}");
    }
    stderr
}

/// Every number in a CSV table's data rows, which must parse and be finite.
#[track_caller]
fn finite_csv(stdout: &str) {
    for line in stdout.lines().skip(1) {
        for cell in line.split(',') {
            let x: f64 = cell
                .parse()
                .unwrap_or_else(|_| panic!("'{cell}' in {line}"));
            assert!(x.is_finite(), "{line}");
        }
    }
}

#[test]
fn tf_noise_and_ss_refuse_an_unstable_quad_naming_the_growing_mode() {
    let sets = ["--set", "d4=-0.02"];
    let tf = [
        &["tf", "quad", "--input", "x00", "--output", "pitch3"][..],
        &sets,
    ]
    .concat();
    refused(&tf, &["unstable", "grows at", "Hz", "pitch3"]);
    let noise = [&["noise", "quad", "--output", "pitch3"][..], &sets].concat();
    refused(&noise, &["unstable", "pitch3"]);
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let out = dir.join("unstable-quad.mat");
    let _ = std::fs::remove_file(&out);
    let path = out.to_string_lossy().into_owned();
    let ss = [&["ss", "quad", "--out", &path][..], &sets].concat();
    refused(&ss, &["unstable", "pitch3"]);
    assert!(!out.exists(), "no file for a refused state space");
    let modes = [&["modes", "quad"][..], &sets].concat();
    refused(&modes, &["unstable", "pitch3"]);
}

#[test]
fn allow_unstable_goes_on_with_a_warning_on_stderr() {
    let (ok, stdout, stderr) = pendkit(&[
        "tf",
        "quad",
        "--set",
        "d4=-0.02",
        "--input",
        "x00",
        "--output",
        "pitch3",
        "--points",
        "5",
        "--csv",
        "--allow-unstable",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.starts_with("warning: unstable") && stderr.contains("pitch3"),
        "{stderr}"
    );
    assert_eq!(stdout.lines().count(), 6);
    finite_csv(&stdout);
}

#[test]
fn massless_float_on_a_negative_spring_is_not_reported_stable() {
    refused(
        &["modes", "toy", "--set", "k1=-4000"],
        &["float 'q'", "no stable position"],
    );
}

#[test]
fn stiff_wires_reach_equilibrium_within_rounding() {
    // r_wire = 30 × nominal: wire stiffness 900 times nominal (stiffness ratio ~1e8 to the
    // pendulum's own); the force tolerance scales with the rounding of k |x| ε
    let (ok, stdout, stderr) = pendkit(&["modes", "double-pendulum", "--set", "r_wire=scale(30)"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("6 modes"), "{stdout}");
}

#[test]
fn negative_loss_and_non_finite_damping_are_refused_naming_the_tag() {
    refused(
        &[
            "noise",
            "quad",
            "--output",
            "x3",
            "--set",
            "damping.fibre_stretch.structural=-1e-7",
        ],
        &[
            "fibre_stretch",
            "structural = -1e-7 rad is outside its domain",
            ">= 0",
        ],
    );
    refused(
        &[
            "tf",
            "quad",
            "--input",
            "x00",
            "--output",
            "x3",
            "--set",
            "damping.fibre_stretch.structural=1/0",
        ],
        &["fibre_stretch"],
    );
    // the sensitivities of the same responses refuse them too (they were differentiated,
    // a noise ASD from a negative loss given as an answer)
    for response in [&["--noise", "x3"][..], &["--tf", "x00:x3"][..]] {
        let mut args = vec!["sensitivity", "quad", "--freqs", "1", "--parameters", "m3"];
        args.extend_from_slice(response);
        args.extend_from_slice(&["--set", "damping.fibre_stretch.structural=-1e-7"]);
        refused(
            &args,
            &[
                "fibre_stretch",
                "structural = -1e-7 rad is outside its domain",
            ],
        );
    }
}

/// A temperature so high that the fibres' thermoelastic loss overflows would make the
/// damping multiplier 1 + inf i at every frequency of the sweep: its Δ is not finite, which
/// the damping's domain check refuses when the model is built, naming the tag and the field,
/// instead of a singular solve being reported.
#[test]
fn damping_that_overflows_at_a_sweep_frequency_is_named_not_called_singular() {
    for command in [
        &["noise", "quad", "--output", "x3", "--points", "10"][..],
        &[
            "tf", "quad", "--input", "x00", "--output", "x3", "--points", "5",
        ][..],
    ] {
        let mut args = command.to_vec();
        args.extend(["--set", "temperature=1e300"]);
        // refused where the damping is built, before any sweep: the tag and the field
        let message = refused(
            &args,
            &[
                "fibre_bending",
                "thermoelastic.delta = inf",
                "not a finite number",
            ],
        );
        assert!(!message.contains("singular"), "{message}");
    }
}

#[test]
fn frequency_grids_outside_the_documented_limits_are_refused() {
    let tf = ["tf", "quad", "--input", "x00", "--output", "x3"];
    // refused by the options' number parser (a clap error: exit status 2 with a usage hint)
    refused_option(
        &[&tf[..], &["--to", "inf"]].concat(),
        "--to",
        &["not a finite number"],
    );
    refused_option(
        &[&tf[..], &["--from", "1e-320"]].concat(),
        "--from",
        &["too small"],
    );
    refused(&[&tf[..], &["--from", "1e-12"]].concat(), &["1e-9"]);
    refused(
        &[&tf[..], &["--points", "100000000000000"]].concat(),
        &["--points", "1000000", "PENDKIT_MAX_FREQUENCY_POINTS"],
    );
    refused(
        &[&tf[..], &["--freqs", "1,nan"]].concat(),
        &["nan", "not a finite number"],
    );
    refused(
        &[&tf[..], &["--freqs", "1,1e300"]].concat(),
        &["1e300", "1e9"],
    );
    // a list that starts with a minus sign reaches the frequency check (not clap's
    // "unexpected argument")
    refused(
        &[&tf[..], &["--freqs", "-2,1"]].concat(),
        &["--freqs", "-2", "must be positive"],
    );
    refused_option(
        &[
            "ss",
            "quad",
            "--out",
            "never-written.mat",
            "--damping-frequency",
            "1e-320",
        ],
        "--damping-frequency",
        &["too small"],
    );
    refused(
        &[
            "ss",
            "quad",
            "--out",
            "never-written.mat",
            "--damping-frequency",
            "1e-12",
        ],
        &["damping frequency", "1e-9"],
    );
    assert!(!std::path::Path::new("never-written.mat").exists());
}

#[test]
fn negative_wire_radius_is_refused_not_read_as_its_absolute_value() {
    refused(
        &["modes", "double-pendulum", "--set", "r_wire=-0.0005"],
        &["wire1", "positive"],
    );
    // the quad declares its radii positive: refused by the domain, before anything is
    // built; a file that widens the domain meets the wire's own check
    refused(
        &["modes", "quad", "--set", "r1=0"],
        &["parameter 'r1' = 0 m", "domain", "> 0"],
    );
    refused(
        &["modes", &quad_with_finite(&["r1"]), "--set", "r1=0"],
        &["w1_1", "positive"],
    );
}

/// A suspension file extending the quad whose parameters `names` may take any finite
/// value (their declared domains widened), so that what reads them is what checks them.
fn quad_with_finite(names: &[&str]) -> String {
    let mut text = "name = \"quad-unchecked\"\nextends = \"quad\"\n[parameters]\n".to_string();
    for name in names {
        text.push_str(&format!("{name} = {{ domain = \"finite\" }}\n"));
    }
    scratch_file(&format!("quad-finite-{}.toml", names.join("-")), &text)
}

#[test]
fn set_on_a_parameter_nothing_reads_is_refused() {
    refused(
        &["modes", "quad", "--set", "maraging_Y=2e11"],
        &["maraging_Y", "read by nothing"],
    );
}

#[test]
fn existing_export_is_replaced_with_or_without_force() {
    // Was: refused without --force (`ss` alone among the outputs; issue 35 made every
    // command replace its outputs, docs/cli.md "Output files"). --force is still accepted.
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let out = dir.join("refusals-existing.json");
    let path = out.to_string_lossy().into_owned();
    for force in [&[][..], &["--force"][..]] {
        std::fs::write(&out, "kept").unwrap();
        let mut args = vec!["ss", "double-pendulum", "--out", &path];
        args.extend_from_slice(force);
        let (ok, _, stderr) = pendkit(&args);
        assert!(ok, "{stderr}");
        let written: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert!(written["A"].is_array());
    }
}

#[test]
fn support_point_as_input_moves_a_point_on_the_support_one_for_one() {
    // a point on the support driven along x by the support's own x: the point's motion
    // over the input is exactly 1 at every frequency (it is the input), and the pendulum
    // mass follows as a pendulum does (→ 1 at low frequency)
    let (ok, stdout, stderr) = pendkit(&[
        "tf",
        "pendulum",
        "--input",
        "x00",
        "--output",
        "support@0,0,0/1,0,0",
        "--freqs",
        "0.1,1,10",
        "--csv",
    ]);
    assert!(ok, "{stderr}");
    for line in stdout.lines().skip(1) {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert_eq!((cells[1], cells[2]), (1.0, 0.0), "{line}");
    }
    let (ok, stdout, stderr) = pendkit(&[
        "tf",
        "pendulum",
        "--input",
        "support@0,0,0/1,0,0",
        "--output",
        "x1",
        "--freqs",
        "0.01",
        "--csv",
    ]);
    assert!(ok, "{stderr}");
    let row: Vec<f64> = stdout
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    // pendulum: x1/x00 = ω0² / (ω0² − ω²) ≈ 1 + (f/f0)² with f0 ≈ 0.64 Hz, f = 0.01 Hz
    assert!((row[1] - 1.0).abs() < 1e-3, "{row:?}");
}

#[test]
fn tradeoff_refuses_an_unstable_suspension_naming_the_growing_mode() {
    // the trade-off answers with the linearised model of every variant: the reference
    // variant of an unstable rigid body (fibres below the centre of mass) is refused
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tradeoff-unstable");
    let out = dir.to_string_lossy().into_owned();
    refused(
        &[
            "tradeoff",
            "rigid-body",
            "--set",
            "d_fibre=-0.01",
            "--output",
            "x1",
            "--budget",
            "0",
            "--points",
            "5",
            "--out",
            &out,
        ],
        &["unstable", "pitch1"],
    );
    assert!(!dir.join("tradeoff.csv").exists());
}

#[test]
fn negative_or_zero_frequency_parameter_is_refused_not_squared_away() {
    // the quad's blade stiffness is ½ (2π ufc1)² m: a negative ufc1 would act as its
    // absolute value, a zero one leave a blade without stiffness
    // (the quad declares both positive: a file that widens the domains meets the checks of
    // what reads them)
    let unchecked = quad_with_finite(&["ufc1", "m3"]);
    for v in ["-2.48", "0"] {
        refused(
            &["modes", &unchecked, "--set", &format!("ufc1={v}")],
            &["ufc1", "frequency must be positive"],
        );
        refused(
            &["modes", "quad", "--set", &format!("ufc1={v}")],
            &["parameter 'ufc1'", "Hz", "must be positive"],
        );
    }
    refused(
        &["modes", &unchecked, "--set", "m3=-40"],
        &["negative mass"],
    );
}

#[test]
fn subnormal_parameter_is_refused_not_turned_into_infinite_frequencies() {
    // m1 = 1e-320 kg gave "inf" mode frequencies with exit status 0
    refused(
        &["modes", "pendulum", "--set", "m1=1e-320"],
        &["m1", "subnormal"],
    );
}

#[test]
fn sweep_with_more_steps_than_the_limit_is_refused_at_once() {
    // 1e9 steps ran (and allocated) for hours; two --vary multiply
    refused(
        &[
            "sweep",
            "pendulum",
            "--vary",
            "m1=1:2:1000000000",
            "--modes",
        ],
        &["--vary", "10000", "PENDKIT_MAX_SWEEP_STEPS"],
    );
    refused(
        &[
            "sweep",
            "pendulum",
            "--vary",
            "m1=1:2:1000",
            "--vary",
            "l_fibre=1:2:1000",
            "--modes",
        ],
        &["1000 x 1000", "10000", "PENDKIT_MAX_SWEEP_STEPS"],
    );
}

/// Writes `text` to `name` in the tests' scratch folder and returns its path.
fn scratch_file(name: &str, text: &str) -> String {
    let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn empty_suspension_file_is_refused_not_a_model_with_no_modes() {
    // an empty .toml read as a suspension file with nothing in it gave "0 modes", exit 0
    let path = scratch_file("empty-suspension.toml", "");
    refused(&["modes", &path], &["no bodies", "model = \"quad\""]);
}

#[test]
fn named_output_with_every_coefficient_zero_is_refused() {
    // `0*x1` is an output that reads nothing: a table of zeros with exit status 0 before
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../models/basic/pendulum.toml"
    ))
    .unwrap();
    let path = scratch_file(
        "zero-output.toml",
        &format!("{base}\n[outputs]\nnothing = \"0*x1\"\n"),
    );
    refused(
        &[
            "tf", &path, "--input", "x00", "--output", "nothing", "--points", "3",
        ],
        &["nothing", "every coefficient zero"],
    );
}

#[test]
fn switch_parameter_other_than_0_or_1_is_refused() {
    // hinged_bottom = -1 was read as "hinged" (anything non-zero); the bundled model is its
    // suspension file, so the error names the file's line and field
    refused(
        &["modes", "pendulum", "--set", "hinged_bottom=-1"],
        &[
            "pendulum.toml",
            "hinged",
            "-1",
            "must be 0 (clamped) or 1 (hinged)",
        ],
    );
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../models/basic/pendulum.toml"
    );
    refused(
        &["modes", file, "--set", "hinged_bottom=2"],
        &["hinged", "must be 0 (clamped) or 1 (hinged)"],
    );
}

#[test]
fn poisson_ratio_outside_its_physical_range_is_refused() {
    // G = E / (2 (1 + ν)): ν = 1e300 gave a shear modulus of ~0 and torsion-free fibres
    refused(
        &["modes", "pendulum", "--set", "nu_fibre=1e300"],
        &[
            "pendulum.toml",
            "poisson_ratio",
            "poisson_ratio = 1e300 is outside its domain",
            "(-1, 0.5)",
        ],
    );
    refused(
        &["modes", "quad", "--set", "nu_silica=0.6"],
        &["ligo-materials.toml", "poisson_ratio", "0.6", "(-1, 0.5)"],
    );
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../models/basic/pendulum.toml"
    );
    refused(
        &["modes", file, "--set", "nu_fibre=-1"],
        &["poisson_ratio", "(-1, 0.5)"],
    );
}

#[test]
fn mass_and_inertia_ratios_past_1e12_are_refused_not_read_as_neutral_modes() {
    // m3 = 1e-300 kg next to the 39.6 kg PUM reported the pendulum modes "neutral" with
    // exit status 0: the mass matrix spans 4e301, far past what doubles resolve
    for set in ["m3=1e-300", "m3=1e-20"] {
        refused(
            &["modes", "quad", "--set", set],
            &["testmass", "mass", "1e12"],
        );
    }
    refused(
        &["modes", "quad", "--set", "I3x=1e-30"],
        &["testmass", "moment of inertia", "1e12"],
    );
    // m3 = 1e-9 kg passes the mass check (ratio 4e10) but its fibres then hold 1e-8 N,
    // stretched by 2.8e-13 of their length: k l / T = 3.6e12, past the wire limit
    refused(
        &["modes", "quad", "--set", "m3=1e-9"],
        &["wire 'f1'", "pendulum stiffness"],
    );
    // within both limits (mass ratio 4e7; the fibres, holding 1e-5 N, at k l / T ≈ 4e9)
    // the modes answer, with their accuracy where it is worse than 1e-6
    let (ok, stdout, stderr) = pendkit(&["modes", "quad", "--set", "m3=1e-6"]);
    assert!(ok, "{stderr}");
    assert!(
        !stdout.contains("neutral") && !stdout.contains("NaN"),
        "{stdout}"
    );
}

#[test]
fn wires_whose_stretch_is_lost_in_rounding_are_refused_not_read_as_neutral_modes() {
    // E_wire × 1e16 left the wires' static stretch (T/k ≈ 1e-19 m) below the rounding of
    // their lengths (1e-16 m), and the pendulum modes came out "neutral" with exit status
    // 0; the check refuses past k l / T = 1e12
    for (model, set) in [
        ("double-pendulum", "E_wire=scale(1e16)"),
        ("double-pendulum", "r_wire=scale(1e5)"),
        ("quad", "Y3=scale(1e16)"),
    ] {
        refused(
            &["modes", model, "--set", set],
            &["wire '", "pendulum stiffness", "1e12"],
        );
    }
    // a massless test mass leaves its fibres without tension: refused for the missing
    // inertia (what the user changed), not for the fibres' stiffness ratio
    refused(
        &["modes", &quad_with_finite(&["m3"]), "--set", "m3=0"],
        &["x3", "no inertia"],
    );
    // r_wire × 1e4 (k l / T ≈ 4e10) still answers, stating its accuracy
    let (ok, stdout, stderr) = pendkit(&["modes", "double-pendulum", "--set", "r_wire=scale(1e4)"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("accuracy") && !stdout.contains("neutral"),
        "{stdout}"
    );
}

#[test]
fn point_directions_of_tiny_or_huge_size_are_normalised_not_called_zero() {
    // 1e-300 along x underflowed in the norm and was refused as "the direction is zero";
    // the same direction scaled gives the same transfer function
    let tf = |dir: &str| {
        let (ok, stdout, stderr) = pendkit(&[
            "tf",
            "quad",
            "--input",
            "x00",
            "--output",
            &format!("testmass@0,0,0/{dir}"),
            "--freqs",
            "1",
            "--csv",
        ]);
        assert!(ok, "{dir}: {stderr}");
        finite_csv(&stdout);
        stdout.lines().nth(1).unwrap().to_string()
    };
    let unit = tf("1,0,0");
    assert_eq!(tf("1e-300,0,0"), unit);
    assert_eq!(tf("1e300,0,0"), unit);
    refused(
        &[
            "tf",
            "quad",
            "--input",
            "x00",
            "--output",
            "testmass@0,0,0/0,0,0",
        ],
        &["direction is zero"],
    );
}

#[test]
fn huge_lengths_in_errors_are_printed_in_exponent_form() {
    // g = 1e300 gave an unstretched length printed as 300 digits
    let e = refused(
        &["modes", "quad", "--set", "g=1e300"],
        &["unstretched length", "e"],
    );
    assert!(e.len() < 300, "{e}");
}

/// Runs and expects clap to refuse an option's value: failure, nothing on stdout, and the
/// first line of stderr naming the option and containing every one of `words`.
#[track_caller]
fn refused_option(args: &[&str], option: &str, words: &[&str]) {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(!ok, "{args:?} succeeded: {stdout}");
    assert!(stdout.is_empty(), "{args:?} printed: {stdout}");
    let first = stderr.lines().next().unwrap_or_default();
    assert!(
        first.contains(option),
        "{args:?}: '{option}' not in {first}"
    );
    for w in words {
        assert!(first.contains(w), "{args:?}: '{w}' not in {first}");
    }
}

#[test]
fn number_literals_an_f64_cannot_hold_are_refused_in_every_option() {
    // 1e-400 read as 0 and 1e400 as inf without a word: each is now named where typed
    let tf = ["tf", "pendulum", "--input", "x00", "--output", "x1"];
    for (value, problem) in [
        ("1e-400", "too small"),
        ("-4.9e-324", "too small"),
        ("1e400", "too large"),
        ("nan", "not a finite number"),
    ] {
        // in an expression, `nan` is a name nothing defines; the others are literals
        for set in [format!("m1={value}"), format!("m1=2*{value}")] {
            let words = if value == "nan" {
                vec!["'m1'", "undefined symbol 'nan'"]
            } else {
                vec!["parameter 'm1'", value, problem]
            };
            refused(&["modes", "pendulum", "--set", &set], &words);
        }
        for option in ["--from", "--to"] {
            refused_option(&[&tf[..], &[option, value]].concat(), option, &[problem]);
        }
        refused(
            &[&tf[..], &["--freqs", &format!("1,{value}")]].concat(),
            &["--freqs", problem],
        );
        refused_option(
            &[
                "ss",
                "pendulum",
                "--out",
                "x.json",
                "--damping-frequency",
                value,
            ],
            "--damping-frequency",
            &[problem],
        );
        refused_option(
            &["modes", "pendulum", "--below", value],
            "--below",
            &[problem],
        );
        refused(
            &[
                "sweep",
                "toy",
                "--vary",
                &format!("k1=1000:{value}:3"),
                "--modes",
            ],
            &["--vary", "STOP", problem],
        );
        refused(
            &[
                "tf",
                "pendulum",
                "--input",
                "x00",
                "--output",
                &format!("mass1@0,0,{value}/1,0,0"),
            ],
            &["the point is not three numbers", problem],
        );
        let measured = scratch_file(
            "literal-modes.csv",
            &format!("label,hz,sigma_hz\nx1,0.64,0.01\nz1,{value},0.1\n"),
        );
        refused(
            &["fit", "pendulum", "--modes", &measured, "--free", "m1"],
            &["literal-modes.csv:3: hz", value],
        );
    }
}

#[test]
fn case_file_numbers_an_f64_cannot_hold_are_refused_with_file_line_and_field() {
    // `m1 = 1e-400` reached the model as 0 (and failed later on a massless body)
    let case = scratch_file(
        "literal-case.toml",
        "model = \"pendulum\"\n[parameters]\nl_fibre = 0.5\nm1 = 1e-400\n",
    );
    refused(
        &["modes", &case],
        &[
            "literal-case.toml",
            "line 4: parameters.m1",
            "'1e-400' is too small",
        ],
    );
    // and an overflowing one, which the TOML reader refused without naming the field (and
    // the file was then read as a suspension file)
    let case = scratch_file(
        "literal-case-big.toml",
        "model = \"pendulum\"\n[parameters]\nm1 = 1e400\n",
    );
    refused(
        &["modes", &case],
        &[
            "case file",
            "literal-case-big.toml",
            "line 3: parameters.m1",
            "'1e400' is too large",
        ],
    );
}

#[test]
fn set_of_the_same_parameter_twice_is_refused_not_last_one_wins() {
    // `--set m3=1 --set m3=2` silently used 2
    refused(
        &["modes", "quad", "--set", "m3=1", "--set", "m3 = 2"],
        &["--set 'm3' is given twice"],
    );
    refused(
        &[
            "noise",
            "pendulum",
            "--output",
            "x1",
            "--set",
            "damping.fibre_bending.structural=1",
            "--set",
            "damping.fibre_bending.structural=2",
        ],
        &["damping.fibre_bending.structural", "twice"],
    );
}

#[test]
fn sweep_of_a_parameter_twice_or_also_set_is_refused() {
    // two --vary of k1 gave a table whose first k1 column changed nothing
    refused(
        &[
            "sweep", "toy", "--vary", "k1=1:2:3", "--vary", "k1=1:2:3", "--modes",
        ],
        &["'k1' is swept twice"],
    );
    refused(
        &[
            "sweep", "toy", "--set", "k1=5", "--vary", "k1=1:2:3", "--modes",
        ],
        &["'k1' is swept and also given by --set"],
    );
}

#[test]
fn case_file_whose_model_is_a_case_file_is_refused_naming_it() {
    // a case naming itself (or another case) was read as a suspension file: "model: unknown
    // field"
    let path = scratch_file("self-case.toml", "model = \"self-case.toml\"\n");
    refused(&["modes", &path], &["self-case.toml", "is a case file"]);
}

#[test]
fn negative_stiffness_near_the_bottom_of_f64_is_unstable_not_a_hang() {
    // `modes toy --set k2=-1e-305` ran for ever: the shift bisection started from a floor
    // that underflowed to 0 and formed low·high, which underflowed to 0 too. The toy's
    // springs in series give k = k1 k2 / (k1 + k2) ≈ k2 for |k2| ≪ k1 = 1000 N/m, so with
    // m = 1 kg the mode grows with e-folding time 1/sqrt(|k2|/m) = 1/sqrt(1e-305) s
    // = 3.162e152 s (closed form; printed to 4 digits).
    refused(
        &["modes", "toy", "--set", "k2=-1e-305"],
        &["unstable", "e-folding time 3.162e152 s"],
    );
}

/// A physically impossible value is refused by every command, whether or not the command
/// reads it (`modes` reads no heat capacity), naming the field, its value with its unit and
/// its domain: the material constants and damping fields of the schema
/// (`pendkit_model::schema`), and a parameter's own declared domain.
#[test]
fn impossible_values_are_refused_by_every_command_whether_or_not_it_reads_them() {
    let report = std::env::temp_dir().join(format!("pendkit-impossible-{}", std::process::id()));
    let report = report.to_str().unwrap();
    let commands: [&[&str]; 9] = [
        &["modes", "quad"],
        &[
            "tf", "quad", "--input", "x00", "--output", "x3", "--points", "3",
        ],
        &["noise", "quad", "--output", "x3", "--points", "3"],
        &["params", "quad"],
        &["sweep", "quad", "--vary", "m3=39:40:2", "--modes"],
        &["sensitivity", "quad", "--parameters", "m3"],
        &["bench", "quad", "--repeat", "1"],
        &["report", "quad", "--out", report, "--points", "3"],
        &["ss", "quad", "--out", "never-written.json"],
    ];
    let impossible = [
        (
            "steel_C=-486",
            "specific_heat = -486 J/(kg K) is outside its domain",
        ),
        ("steel_rho=0", "density = 0 kg/m^3 is outside its domain"),
        (
            "steel_phi=-2e-4",
            "loss_angle = -0.0002 rad is outside its domain",
        ),
        (
            "silica_K=-1",
            "conductivity = -1 W/(m K) is outside its domain",
        ),
        ("nu_steel=0.5", "poisson_ratio = 0.5 is outside its domain"),
        (
            "maraging_Y=0",
            "youngs_modulus = 0 Pa is outside its domain",
        ),
        (
            "damping.fibre_bending.temperature=0",
            "temperature = 0 K is outside its domain",
        ),
        (
            "damping.w1_bending.viscous=-1",
            "viscous = -1 rad is outside its domain",
        ),
    ];
    for command in commands {
        for (set, words) in impossible {
            let args = [command, &["--set", set]].concat();
            refused(&args, &[words, "must be"]);
        }
    }
    assert!(!std::path::Path::new("never-written.json").exists());
}
