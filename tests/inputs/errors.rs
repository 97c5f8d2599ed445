//! Bad input gives a clear error naming what and where, never a panic or a wrong number.

use nalgebra::Vector3;
use pendkit::{Case, run_stage};
use pendkit_assembly::{AssemblyError, EquilibriumOptions, solve_equilibrium};
use pendkit_model::{BodySpec, SystemBuilder};
use pendkit_system::{EndDirection, Stage, Wire, WireEnd, WireSection, WireTags};

/// The one-line message of building `model` with `sets`.
fn build_error(model: &str, sets: &[&str]) -> String {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let result = Case::model(model)
        .and_then(|c| c.with_sets(&sets))
        .and_then(|c| c.build());
    match result {
        Ok(_) => panic!("{model} {sets:?} built without error"),
        Err(e) => {
            let text = e.to_string();
            assert!(!text.contains('\n'), "multi-line error: {text}");
            text
        }
    }
}

#[test]
fn parameter_cycle_names_the_chain() {
    let e = build_error("pendulum", &["m1=2*l_fibre", "l_fibre=m1/80"]);
    assert!(
        e.contains("m1 -> l_fibre -> m1") || e.contains("l_fibre -> m1 -> l_fibre"),
        "{e}"
    );
}

#[test]
fn undefined_symbol_is_named() {
    let e = build_error("pendulum", &["m1=mass_total/2"]);
    assert!(e.contains("'mass_total'") && e.contains("m1"), "{e}");
}

#[test]
fn unknown_parameter_is_named_with_a_suggestion() {
    let e = build_error("pendulum", &["m11=3"]);
    assert!(e.contains("'m11'") && e.contains("'m1'"), "{e}");
}

#[test]
fn unknown_model_lists_the_bundled_ones() {
    let e = Case::open("pendullum")
        .err()
        .expect("unknown model")
        .to_string();
    assert!(e.contains("'pendullum'") && e.contains("pendulum"), "{e}");
}

#[test]
fn negative_mass_is_rejected() {
    let e = build_error("pendulum", &["m1=-40"]);
    assert!(e.contains("mass1") && e.contains("negative mass"), "{e}");
}

#[test]
fn non_positive_definite_inertia_is_rejected() {
    let e = build_error("rigid-body", &["I1y=-0.1"]);
    assert!(
        e.contains("mass1") && e.contains("not positive definite"),
        "{e}"
    );
    // products of inertia larger than the moments break positive definiteness too
    let mut b = SystemBuilder::new(9.81);
    b.variable("yaw", 0.0).unwrap();
    let inertia = nalgebra::Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    let e = b
        .body(
            BodySpec::new("plate")
                .pose(["0", "0", "0", "yaw", "0", "0"])
                .mass(1.0)
                .inertia(inertia),
        )
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("plate") && e.contains("not positive definite"),
        "{e}"
    );
}

#[test]
fn zero_length_wire_is_rejected() {
    let e = build_error("pendulum", &["l_fibre=0"]);
    assert!(e.contains("fibre1") && e.contains("zero-length"), "{e}");
}

fn silica() -> WireSection {
    WireSection::round(0.2e-3, 72e9, 30e9, 2200.0)
}

fn tags() -> WireTags {
    WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    }
}

#[test]
fn coincident_attachment_points_are_a_zero_length_wire() {
    // a wire whose ends sit at the same point once the bodies are placed
    let mut b = SystemBuilder::new(9.81);
    b.support_parameters().unwrap();
    let top = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    b.variable("z1", 0.0).unwrap();
    let mass = b
        .body(
            BodySpec::new("bob")
                .pose(["0", "0", "z1", "0", "0", "0"])
                .mass(1.0),
        )
        .unwrap();
    let end = |body| WireEnd {
        body,
        point: Vector3::zeros(),
        direction: EndDirection::Hinged,
    };
    b.wire(Wire {
        name: "w".into(),
        ends: [end(top), end(mass)],
        stiffness: 1e4,
        unstretched_length: 0.5,
        section: silica(),
        profile: Vec::new(),
        tags: tags(),
        continuum: false,
    })
    .unwrap();
    let e = run_stage(b.build().unwrap(), Stage::S0A)
        .err()
        .expect("zero length")
        .to_string();
    assert!(e.contains("'w'") && e.contains("zero length"), "{e}");
}

#[test]
fn unsupported_body_runs_away() {
    // a mass with nothing holding it: the potential m g z has no minimum
    let mut b = SystemBuilder::new(9.81);
    b.variable("z1", 0.0).unwrap();
    b.body(
        BodySpec::new("bob")
            .pose(["0", "0", "z1", "0", "0", "0"])
            .mass(1.0),
    )
    .unwrap();
    let s = b.build().unwrap();
    let e = solve_equilibrium(&s, &EquilibriumOptions::default()).unwrap_err();
    assert!(
        matches!(e, AssemblyError::Runaway { ref coordinate, .. } if coordinate == "z1"),
        "{e}"
    );
}

#[test]
fn iteration_limit_is_a_clear_non_convergence() {
    let mut s = Case::model("rigid-body").unwrap().build().unwrap().0;
    let i = s.coord("pitch1").unwrap();
    s.coords[i].start = 0.3;
    let options = EquilibriumOptions {
        max_iterations: 1,
        ..Default::default()
    };
    let e = solve_equilibrium(&s, &options).unwrap_err();
    assert!(
        matches!(e, AssemblyError::NotConverged { iterations: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("did not converge"));
}

#[test]
fn inverted_pendulum_is_reported_unstable() {
    // a 1 kg bob balanced on a compressed strut 0.5 m above the support
    let mut b = SystemBuilder::new(9.81);
    b.support_parameters().unwrap();
    let top = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    for (n, v) in [("x1", 0.0), ("y1", 0.0), ("z1", 0.5)] {
        b.variable(n, v).unwrap();
    }
    let bob = b
        .body(
            BodySpec::new("bob")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(1.0),
        )
        .unwrap();
    let end = |body| WireEnd {
        body,
        point: Vector3::zeros(),
        direction: EndDirection::Hinged,
    };
    b.wire(Wire::from_tension(
        "strut",
        [end(top), end(bob)],
        silica(),
        0.5,
        -9.81,
        tags(),
    ))
    .unwrap();
    let result = run_stage(b.build().unwrap(), Stage::S0A).unwrap();
    let e = result.modes.check_stable().unwrap_err().to_string();
    assert!(
        e.contains("unstable equilibrium") && (e.contains("x1") || e.contains("y1")),
        "{e}"
    );
    // the unstable modes are reported with a growth rate, not NaN: sqrt(g/l)/2π
    let growth = (9.81f64 / 0.5).sqrt() / (2.0 * std::f64::consts::PI);
    let unstable: Vec<_> = result
        .modes
        .modes
        .iter()
        .filter(|m| !m.is_stable())
        .collect();
    assert_eq!(unstable.len(), 2);
    for m in unstable {
        assert!((m.hz + growth).abs() < 1e-9 * growth, "{}", m.hz);
    }
}

#[test]
fn other_impossible_parameters_are_named() {
    for (sets, expected) in [
        (&["r_fibre=0"][..], "stiffness 0 N/m must be positive"),
        (&["temperature=-1"][..], "'temperature': must be positive"),
        (&["m1=1e308*10"][..], "not a finite number"),
        (&["wire_terms_early=3"][..], "wire_terms_early"),
        (&["damping.nosuch.structural=1"][..], "unknown tag 'nosuch'"),
    ] {
        let e = build_error("pendulum", sets);
        assert!(e.contains(expected), "{sets:?}: {e}");
    }
    let e = build_error("quad", &["n_beads=2.5"]);
    assert!(e.contains("n_beads"), "{e}");
    // a float held by nothing is caught when its block is eliminated
    let sets = vec!["k1=0".to_string(), "k2=0".to_string()];
    let (system, _) = Case::model("toy")
        .unwrap()
        .with_sets(&sets)
        .unwrap()
        .build()
        .unwrap();
    let e = run_stage(system, Stage::S0A)
        .err()
        .expect("singular float")
        .to_string();
    assert!(e.contains("float 'q'"), "{e}");
}

/// Numbers far from 1 in messages are written in scientific notation (Rust's `{}` writes
/// 1e-300 as 301 decimals), and a wire its load would stretch past its own length says so
/// rather than calling itself zero-length.
#[test]
fn extreme_values_in_messages_are_short_and_say_what_is_wrong() {
    for (model, set, expected) in [
        (
            "quad",
            "l1=1e-300",
            "length 1e-300 m does not reach across 0.14 m",
        ),
        // a density the material's domain refuses, whether or not a part reads it
        (
            "quad",
            "silica_rho=-1e300",
            "density = -1e300 kg/m^3 is outside its domain",
        ),
        (
            "quad",
            "temperature=-1e300",
            "must be positive (got -1e300 K)",
        ),
        (
            "quad",
            "wire_terms_early=1e-300",
            "equilibrium only), got 1e-300",
        ),
        (
            "quad-v5",
            "n_beads=1e300",
            "`n_beads` = 1e300 must be a whole number",
        ),
        (
            "pendulum",
            "hinged_bottom=1e-300",
            "`hinged` = 1e-300: must be 0",
        ),
        (
            "triple",
            "fibre_silica=1e-300",
            "fibre_silica = 1e-300 must be one of 0, 1",
        ),
        (
            "triple",
            "kc1=-1e-300",
            "`kc1` = -1e-300 N/m must be positive",
        ),
        // l0 = l − T/k, T = 1e20 kg · g / 4 fibres ≈ 2.5e20 N, k = EA/l ≈ 1.5e4 N/m: −1.6e16 m
        (
            "pendulum",
            "m1=1e20",
            "e16 m is negative: its tension would stretch it by more than its length",
        ),
    ] {
        let e = build_error(model, &[set]);
        assert!(e.contains(expected), "{model} {set}: {e}");
        assert!(!e.contains("0000000000"), "{model} {set}: {e}");
        assert!(e.len() < 400, "{model} {set}: {e}");
    }
    let e = pendkit::log_grid(1e-10, 100.0, 200)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("frequency grid from 1e-10 Hz to 100 Hz"),
        "{e}"
    );
    let e = pendkit_dynamics::DynamicsError::DampingFrequency(-1e-300).to_string();
    assert_eq!(e, "damping frequency must be positive (got -1e-300 Hz)");
}

/// A damping field the tag refuses names the `--set` argument once, with the reason.
#[test]
fn a_bad_damping_field_names_the_argument_and_the_field() {
    let e = build_error("quad", &["damping.fibre_stretch.phi=1"]);
    assert!(
        e.starts_with("override 'damping.fibre_stretch.phi': unknown damping field 'phi'"),
        "{e}"
    );
    assert!(!e.contains("expected NAME=EXPR"), "{e}");
    // a missing name or expression is the argument's syntax, not an unknown parameter ''
    // or the expression "()"
    for set in ["=3", "m1=", "damping.fibre_stretch.structural=", " = "] {
        let e = build_error("quad", &[set]);
        assert_eq!(
            e,
            format!("override '{set}': expected NAME=EXPR or damping.<tag>.<field>=EXPR")
        );
    }
}

/// An empty file, or a case file's lines without its `model = ...`, reads as a suspension
/// file with nothing in it: the error says so at once instead of "no variables" from the
/// model builder.
#[test]
fn a_file_without_bodies_or_a_model_says_which_it_lacks() {
    for text in ["", "[parameters]\nm1 = 3\n", "# only a comment\n"] {
        let e = Case::from_text(std::path::Path::new("c.toml"), text)
            .err()
            .expect("no bodies")
            .to_string();
        assert!(
            e.starts_with("c.toml: no bodies: a suspension file describes its bodies")
                && e.contains("model = \"quad\""),
            "{text:?}: {e}"
        );
    }
}

/// Typed overrides: a value is the parameter's exact f64, a value that is not a finite number
/// is refused naming the parameter, a parameter or damping field given twice in one list is
/// refused, and a damping field outside the schema names the fields there are.
#[test]
fn typed_overrides_are_exact_and_refused_in_the_librarys_own_terms() {
    use pendkit::Override;
    // 0.1 + 0.2 is not 0.3 in binary: its text must read back as the same f64
    let value = 0.1 + 0.2;
    let case = Case::model("pendulum")
        .unwrap()
        .with([Override::value("m1", 40.0 * value)])
        .unwrap();
    let (_, resolved) = case.build().unwrap();
    assert_eq!(
        resolved.get("m1").unwrap().to_bits(),
        (40.0 * value).to_bits()
    );
    for bad in [f64::NAN, f64::INFINITY] {
        let e = Case::model("pendulum")
            .unwrap()
            .with([Override::value("m1", bad)])
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.starts_with("override 'm1': ") && e.contains("not a finite number"),
            "{e}"
        );
    }
    let twice = Case::model("pendulum").unwrap().with([
        Override::value("m1", 40.0),
        Override::expression("m1", "41"),
    ]);
    assert_eq!(
        twice.err().unwrap().to_string(),
        "'m1' is overridden twice: give each parameter or damping field once"
    );
    let e = Case::model("pendulum")
        .unwrap()
        .with([Override::damping("fibre_bending", "phi", "1e-7")])
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("unknown damping field 'phi'") && e.contains("thermoelastic.tau, temperature"),
        "{e}"
    );
}

/// A parameter's declared `domain` is checked for its default (at the file's line) and for
/// every override, whether or not the command reads it; `params` lists it.
#[test]
fn a_declared_parameter_domain_is_checked_for_the_default_and_every_override() {
    let file = |value: &str| {
        let parameters = format!(
            "m = {{ value = 40, unit = \"kg\", domain = \"> 0\", description = \"the bob\" }}\n\
             unused = {{ value = {value}, unit = \"K\", domain = \"> 0\", description = \"read by nothing\" }}"
        );
        pendkit_tests::hinged_bob(&parameters, 0.6)
    };
    let path = std::path::Path::new("bob.toml");
    // the default outside its own domain: the file's error, at the parameter's line
    let e = Case::from_text(path, &file("-3"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.starts_with("bob.toml:4: parameters.unused: ") && e.contains("must be > 0"),
        "{e}"
    );
    let case = Case::from_text(path, &file("3")).unwrap();
    let refused = |set: &str| {
        case.clone()
            .with_sets(&[set.to_string()])
            .and_then(|c| c.build())
            .err()
            .unwrap()
            .to_string()
    };
    assert_eq!(
        refused("m=0"),
        "parameter 'm' = 0 kg: outside its declared domain: must be > 0"
    );
    // a parameter nothing reads is checked all the same (its domain before its being unread)
    assert!(refused("unused=-1").contains("outside its declared domain"));
    let rows = pendkit::describe::parameter_table(&case).unwrap();
    let m = rows.iter().find(|r| r.name == "m").unwrap();
    assert_eq!((m.unit.as_str(), m.domain.as_str()), ("kg", "> 0"));
}
