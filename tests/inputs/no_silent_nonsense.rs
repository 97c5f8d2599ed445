//! Property tests (issue 11): over generated parameter values, expressions, case files and
//! suspension files (with named signals),
//! pendkit never panics, and whatever it answers with success is finite. Errors are
//! fine; a panic or a NaN with `Ok` is a failure. Each property runs a few dozen cases
//! (each case builds and solves a model); proptest's shrinking names the smallest input
//! that breaks one.

use pendkit::{Case, Error, StageResult, log_grid, run_stage};
use pendkit_system::Stage;
use proptest::prelude::*;

/// Builds and runs `case`, then checks every number a successful run gives: modes, and
/// where the equilibrium is stable, a transfer function and the thermal noise.
fn run_and_check(case: Result<Case, Error>, stage: Stage) -> Result<(), TestCaseError> {
    let Ok(case) = case else { return Ok(()) };
    let Ok((system, _)) = case.build() else {
        return Ok(());
    };
    let Ok(r) = run_stage(system, stage) else {
        return Ok(());
    };
    check_finite(&r, stage)
}

fn check_finite(r: &StageResult, stage: Stage) -> Result<(), TestCaseError> {
    for m in &r.modes.modes {
        prop_assert!(
            m.omega_squared.is_finite() && m.hz.is_finite(),
            "mode {m:?}"
        );
        prop_assert!(m.vector.iter().all(|x| x.is_finite()), "mode vector {m:?}");
        prop_assert!(m.omega_squared_error.is_finite() && m.omega_squared_error >= 0.0);
    }
    for x in &r.assembled.equilibrium.coords {
        prop_assert!(x.is_finite());
    }
    if stage == Stage::S0A || r.check_stable().is_err() {
        return Ok(());
    }
    let freqs = log_grid(0.1, 10.0, 4).unwrap();
    let input = r.model.parameters[0].clone();
    let output = r.model.variables[0].clone();
    if let Ok(h) = r.transfer(&input, &output, &freqs) {
        prop_assert!(
            h.iter().all(|z| z.re.is_finite() && z.im.is_finite()),
            "{h:?}"
        );
    }
    if let Ok(noise) = r.noise(&output, &freqs) {
        prop_assert!(
            noise.total.iter().all(|x| x.is_finite() && *x >= 0.0),
            "{noise:?}"
        );
    }
    Ok(())
}

/// Values a user might type, sensible or not.
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        (-1e3f64..1e3).prop_map(|x| format!("{x:e}")),
        (-30i32..30).prop_map(|e| format!("1e{e}")),
        (-30i32..30).prop_map(|e| format!("-1e{e}")),
        (0.0f64..40.0).prop_map(|x| format!("scale({x})")),
        (-1.0f64..1.0).prop_map(|x| format!("increment({x})")),
        Just("0".to_string()),
        Just("-0".to_string()),
        Just("1/0".to_string()),
        Just("0/0".to_string()),
        Just("1e308*10".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
    ]
}

/// Expressions from a small grammar over numbers, the model's own parameter names and
/// functions, nested a few levels.
fn expression(names: &'static [&'static str]) -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        (-1e3f64..1e3).prop_map(|x| format!("{x}")),
        (0..names.len()).prop_map(move |i| names[i].to_string()),
        Just("pi".to_string()),
    ];
    leaf.prop_recursive(3, 12, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone(), 0..5usize).prop_map(|(a, b, op)| {
                let op = ["+", "-", "*", "/", "^"][op];
                format!("({a}){op}({b})")
            }),
            (inner.clone(), 0..6usize).prop_map(|(a, f)| {
                let f = ["sqrt", "sin", "cos", "exp", "ln", "abs"][f];
                format!("{f}({a})")
            }),
            inner.prop_map(|a| format!("-({a})")),
        ]
    })
}

const TOY: &[&str] = &["m", "k1", "k2"];
const DOUBLE: &[&str] = &["m1", "m2", "r_wire", "l_wire"];
const QUAD: &[&str] = &["d0", "d1", "d2", "d3", "d4", "m1", "m3", "r1", "r2", "Y1"];

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn any_parameter_value_on_small_models_gives_an_error_or_finite_numbers(
        model in 0..2usize,
        which in 0..4usize,
        v in value(),
    ) {
        let (name, params) = [("toy", TOY), ("double-pendulum", DOUBLE)][model];
        let p = params[which % params.len()];
        let case = Case::model(name).and_then(|c| c.with_sets(&[format!("{p}={v}")]));
        run_and_check(case, Stage::S2)?;
    }

    #[test]
    fn any_expression_as_a_parameter_gives_an_error_or_finite_numbers(
        which in 0..3usize,
        e in expression(TOY),
    ) {
        let case = Case::model("toy").and_then(|c| c.with_sets(&[format!("{}={e}", TOY[which])]));
        run_and_check(case, Stage::S0A)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn any_value_on_quad_parameters_gives_an_error_or_finite_numbers(
        which in 0..QUAD.len(),
        v in value(),
    ) {
        let case = Case::model("quad").and_then(|c| c.with_sets(&[format!("{}={v}", QUAD[which])]));
        run_and_check(case, Stage::S2)?;
    }

    #[test]
    fn any_case_file_gives_an_error_or_finite_numbers(
        model in prop_oneof![Just("toy"), Just("double-pendulum"), Just("nope"), Just("")],
        p in 0..4usize,
        v in value(),
        tag in prop_oneof![Just("k1"), Just("wire_stretch"), Just("gravity"), Just("x")],
        field in prop_oneof![Just("structural"), Just("viscous"), Just("loss"), Just("")],
        loss in value(),
        junk in "[ -~\n]{0,40}",
    ) {
        let param = [TOY, DOUBLE][usize::from(model == "double-pendulum")][p % 3];
        let text = format!(
            "model = \"{model}\"\n[parameters]\n{param} = \"{v}\"\n[damping.{tag}]\n{field} = \"{loss}\"\n{junk}\n"
        );
        let dir = std::env::temp_dir().join(format!("pendkit-prop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("case.toml");
        std::fs::write(&path, &text).unwrap();
        run_and_check(Case::from_file(&path), Stage::S2)?;
    }
}

/// Signal texts for a suspension file's `[outputs]`/`[inputs]`: points on its bodies (also
/// the support, an unknown body, degenerate directions), combinations of coordinates and
/// malformed text.
fn signal() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        3 => (-2.0f64..2.0).prop_map(|x| format!("{x}")),
        1 => Just("0".to_string()),
        1 => Just("1e300".to_string()),
        1 => Just("a_fibre".to_string()),
    ];
    let body = prop_oneof![3 => Just("mass1"), 2 => Just("support"), 1 => Just("nobody")];
    let coordinate = prop_oneof![Just("x1"), Just("y1"), Just("z1"), Just("x00"), Just("m1")];
    let point = (
        body,
        proptest::collection::vec(number.clone(), 3),
        proptest::collection::vec(number.clone(), 3),
    )
        .prop_map(|(b, p, d)| format!("{b}@{}/{}", p.join(","), d.join(",")));
    let combination = proptest::collection::vec((number, coordinate), 1..3).prop_map(|terms| {
        terms
            .iter()
            .map(|(c, x)| format!("({c})*{x}"))
            .collect::<Vec<_>>()
            .join(" + ")
    });
    let text = prop_oneof![3 => point, 2 => combination, 1 => "[ -~]{0,20}"];
    let generated =
        (text, any::<bool>()).prop_map(|(s, force)| if force { format!("force:{s}") } else { s });
    // and, as often, well-formed signals, so that many files get as far as a response
    let valid = prop_oneof![
        Just("x00".to_string()),
        Just("support@0,0,0/1,0,0".to_string()),
        Just("force:mass1@0,0,0/0,0,1".to_string()),
        Just("mass1@0.1,0,0/1,0,0".to_string()),
        Just("2*x1 - z1".to_string()),
    ];
    prop_oneof![generated, valid]
}

/// A fresh file name for each generated suspension file: they are cached by path.
fn fresh_path(stem: &str) -> std::path::PathBuf {
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("pendkit-prop-files-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(format!("{stem}-{k}.toml"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// The bundled pendulum's suspension file with one parameter's value replaced, a named
    /// output and input added, and a line of junk: an error, or finite numbers (modes,
    /// and where stable, the named signals' transfer function and noise).
    #[test]
    fn any_suspension_file_gives_an_error_or_finite_numbers(
        p in 0..18usize,
        v in value(),
        output in signal(),
        input in signal(),
        // mostly nothing (junk breaks the TOML, and the rest would go untried)
        junk in prop_oneof![3 => Just(String::new()), 1 => "[ -~]{0,30}"],
    ) {
        let source = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/basic/pendulum.toml");
        let base = std::fs::read_to_string(source).unwrap();
        // two cases in three keep every parameter (p ≥ 6), so the signals get tried
        let param = ["m1", "a_fibre", "r_fibre", "E_fibre", "l_fibre", "phi_fibre"]
            .get(p)
            .copied()
            .unwrap_or("none");
        // replace the value of `param`'s definition line
        let text: String = base
            .lines()
            .map(|line| match line.strip_prefix(&format!("{param} = {{ value = ")) {
                Some(rest) => {
                    let tail = rest.split_once(',').map_or("", |(_, t)| t);
                    format!("{param} = {{ value = \"{v}\",{tail}")
                }
                None => line.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n");
        let text = format!(
            "{text}\n[outputs]\nprobe = {output:?}\n[inputs]\ndrive = {input:?}\n{junk}\n"
        );
        let path = fresh_path("pendulum");
        std::fs::write(&path, &text).unwrap();
        let Ok(case) = Case::from_file(&path) else { return Ok(()) };
        let Ok((system, _)) = case.build() else { return Ok(()) };
        let Ok(r) = run_stage(system, Stage::S2) else { return Ok(()) };
        check_finite(&r, Stage::S2)?;
        if r.check_stable().is_err() {
            return Ok(());
        }
        let freqs = log_grid(0.1, 10.0, 4).unwrap();
        for (i, o) in [("drive", "x1"), ("x00", "probe"), ("drive", "probe")] {
            if let Ok(h) = r.transfer(i, o, &freqs) {
                prop_assert!(
                    h.iter().all(|z| z.re.is_finite() && z.im.is_finite()),
                    "{i} -> {o}: {h:?}"
                );
            }
        }
        if let Ok(noise) = r.noise("probe", &freqs) {
            prop_assert!(noise.total.iter().all(|x| x.is_finite() && *x >= 0.0), "{noise:?}");
        }
    }
}

/// A decimal literal at the edges of `f64` (`d.ddde±3xx`, either sign) or zero with a huge
/// exponent, and whether an `f64` holds it as a normal number: decided from the digits
/// against the limits f64::MIN_POSITIVE = 2.2250738585072014e-308 and f64::MAX =
/// 1.7976931348623157e308 (IEEE 754), without parsing the literal. Three digits of mantissa
/// never fall between a limit and the rounding threshold next to it, so the comparison of
/// mantissas is exact.
fn limit_literal() -> impl Strategy<Value = (String, bool)> {
    let edge = (
        any::<bool>(),
        1000u32..10000,
        prop_oneof![-330i32..=-300, 300i32..=330],
    )
        .prop_map(|(negative, digits, exponent)| {
            let mantissa = f64::from(digits) / 1000.0;
            let sign = if negative { "-" } else { "" };
            let text = format!("{sign}{}.{:03}e{exponent}", digits / 1000, digits % 1000);
            let representable = if exponent < 0 {
                exponent > -308 || (exponent == -308 && mantissa > 2.2250738585072014)
            } else {
                exponent < 308 || (exponent == 308 && mantissa < 1.7976931348623157)
            };
            (text, representable)
        });
    let zero = (-999i32..999).prop_map(|e| (format!("0e{e}"), true));
    prop_oneof![4 => edge, 1 => zero]
}

/// Whether an error is the literal's own refusal (its text quoted, too small or too large).
fn refuses_literal(error: &str, literal: &str) -> bool {
    error.contains(literal)
        && (error.contains("too small")
            || error.contains("too large")
            || error.contains("overflow"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// A number literal an `f64` cannot hold (1e-400 read as 0, 1e400 as inf) is refused
    /// where it is written — in `--set`, in an expression, in a case file (bare or quoted),
    /// in a suspension file's parameter or field — quoting the literal; a literal it can hold
    /// is never refused as one; and success is finite.
    #[test]
    fn number_literals_at_the_limits_of_f64_are_refused_exactly_when_not_representable(
        (literal, representable) in limit_literal(),
        where_ in 0..6usize,
        field in 0..5usize,
    ) {
        let dir = std::env::temp_dir().join(format!("pendkit-prop-literals-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let case = match where_ {
            0 => Case::model("toy").and_then(|c| c.with_sets(&[format!("k2={literal}")])),
            1 => Case::model("toy").and_then(|c| c.with_sets(&[format!("k2=3000+{literal}")])),
            2 | 3 => {
                let value = if where_ == 2 { literal.clone() } else { format!("\"{literal}\"") };
                let path = dir.join("literal-case.toml");
                std::fs::write(&path, format!("model = \"toy\"\n[parameters]\nk2 = {value}\n")).unwrap();
                Case::from_file(&path)
            }
            _ => {
                // a field of the pendulum's file: a parameter's value or a part's own field
                let source = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/basic/pendulum.toml");
                let base = std::fs::read_to_string(source).unwrap();
                let (from, to) = [
                    ("value = 40,", format!("value = {literal},")),
                    ("length = \"l_fibre\"", format!("length = {literal}")),
                    ("radius = \"r_fibre\"", format!("radius = \"{literal}\"")),
                    ("density = \"rho_fibre\"", format!("density = {literal}")),
                    ("mass = \"m1\"", format!("mass = \"2*{literal}\"")),
                ][field].clone();
                let path = fresh_path("literal");
                std::fs::write(&path, base.replacen(from, &to, 1)).unwrap();
                Case::from_file(&path)
            }
        };
        let outcome = case.and_then(|c| c.build().map(|(system, _)| system));
        match outcome {
            Err(e) => {
                let e = e.to_string();
                prop_assert_eq!(refuses_literal(&e, &literal), !representable, "{}", e);
            }
            Ok(system) => {
                prop_assert!(representable, "{literal} accepted");
                if let Ok(r) = run_stage(system, Stage::S2) {
                    check_finite(&r, Stage::S2)?;
                }
            }
        }
    }
}
