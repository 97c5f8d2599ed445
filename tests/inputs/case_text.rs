//! `Case::from_text` reads the suspension text it is given (a caller that keeps a file's text
//! — another process, an editor — gets that text's model, whatever is on disk at the path),
//! and two texts at the same path are two models.

use std::path::Path;

use pendkit::{Case, Stage, run_stage};

/// A bob on four hinged vertical fibres of length `length` m.
fn pendulum(length: f64) -> String {
    pendkit_tests::hinged_bob(
        r#"m = { value = 40, unit = "kg", description = "the bob" }"#,
        length,
    )
}

/// The lowest (pendulum) frequency of the case, Hz.
fn pendulum_hz(case: &Case) -> f64 {
    let (system, _) = case.build().unwrap();
    let r = run_stage(system, Stage::S0A).unwrap();
    r.modes
        .modes
        .iter()
        .map(|m| m.hz)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn case_text_is_the_model_not_the_file_at_its_path() {
    // no file at this path: the text alone is the suspension
    let path = Path::new("/nonexistent-folder/pendulum.toml");
    let long = Case::from_text(path, &pendulum(0.6)).unwrap();
    let short = Case::from_text(path, &pendulum(0.15)).unwrap();
    // A point mass on vertical hinged fibres swings at sqrt(g/L)/2π with L the fibres' length
    // under load; the same fibres, stretched by the same tension, a quarter as long have a
    // quarter of that length, so the frequencies are exactly 2 to 1. 1e-9: the stretch and
    // the modes' rounding cancel in the ratio far below it.
    let ratio = pendulum_hz(&short) / pendulum_hz(&long);
    assert!((ratio - 2.0).abs() < 1e-9, "ratio {ratio}");
}

/// Every settable field of a case, written by the case-file writer that `pendkit fit --out`
/// uses and read back, gives the same overrides and the same model: every parameter of the
/// quad overridden (each scaled, so that a dropped override would change the model), and
/// every damping field of the schema on one tag, with a second tag that sets only one half
/// of the thermoelastic pair (the model's other half must stay).
#[test]
fn every_settable_field_survives_the_case_file_writer() {
    use pendkit::model::schema::DAMPING_FIELDS;
    use pendkit::model::{DampingSpec, Overrides, build_with};

    let quad = Case::model("quad").unwrap();
    let (_, resolved) = quad.build().unwrap();
    let mut overrides = Overrides::default();
    for (name, _) in resolved.iter() {
        overrides
            .parameters
            .push((name.to_string(), "scale(1.0001)".to_string()));
    }
    let texts = [
        ("real", "1 + 1e-6*f"),
        ("structural", "2*silica_phi"),
        ("viscous", "1e-9"),
        ("imag", "1e-10*f/(1 + f)"),
        ("thermoelastic.delta", "1e-5"),
        ("thermoelastic.tau", "0.01"),
        ("temperature", "100"),
    ];
    // the test names every field of the schema, so a field added later is not left out
    assert_eq!(
        texts.map(|(name, _)| name).to_vec(),
        DAMPING_FIELDS.iter().map(|f| f.name).collect::<Vec<_>>()
    );
    let mut every = DampingSpec::default();
    for (field, text) in texts {
        every.set_field(field, text).unwrap();
    }
    overrides.damping.insert("fibre_bending".into(), every);
    let mut half = DampingSpec::default();
    half.set_field("thermoelastic.tau", "0.02").unwrap();
    overrides.damping.insert("w1_bending".into(), half);

    let text = overrides.case_file("quad", "every field", &|name| {
        (name == "m1").then(|| "a note".to_string())
    });
    let read = Case::from_text(Path::new("written.toml"), &text).unwrap();
    assert_eq!(read.overrides, overrides, "{text}");
    // the same model, to the last bit: every number and every damping multiplier
    let (written_system, written_values) = build_with(&*quad.model, &overrides).unwrap();
    let (read_system, read_values) = build_with(&*read.model, &read.overrides).unwrap();
    assert_eq!(format!("{written_system:?}"), format!("{read_system:?}"));
    let values = |r: &pendkit::params::Resolved| format!("{:?}", r.iter().collect::<Vec<_>>());
    assert_eq!(values(&written_values), values(&read_values));
    // and the overrides took: the model is not the default quad
    let (default_system, _) = quad.build().unwrap();
    assert_ne!(format!("{default_system:?}"), format!("{read_system:?}"));
    // the half pair keeps the model's Δ: the same loss as the model's own w1_bending fields
    // with τ alone replaced, written out in full
    let defaults = pendkit::model::Defaults::of(&*quad.model).unwrap();
    let mut in_full = defaults.damping["w1_bending"].spec().clone();
    assert!(in_full.thermoelastic_delta.is_some());
    in_full.thermoelastic_tau = Some("0.02".into());
    let mut explicit = overrides.clone();
    explicit.damping.insert("w1_bending".into(), in_full);
    let (explicit_system, _) = build_with(&*quad.model, &explicit).unwrap();
    let loss =
        |system: &pendkit::system::System| system.damping.get("w1_bending").unwrap().at(10.0);
    assert_eq!(loss(&read_system), loss(&explicit_system));
}
