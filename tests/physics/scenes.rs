//! Scenes: several suspensions in one file (`[[include]]` under a prefix,
//! docs/suspension-files.md, "Scenes"). The references are the included models run alone
//! through the same library calls, and the closed form of two identical oscillators
//! coupled by a spring:
//!
//! - two uncoupled copies of a bundled model have exactly the single model's modes, each
//!   twice (the scene's equations are the two models' side by side): 1e-12 relative, the
//!   rounding of eigenvalues of a matrix of twice the size;
//! - an override of one copy's prefixed parameter (`--set a_m1=...`, or the scene's own
//!   `[parameters]`) changes that copy only: the scene's modes are the union of the
//!   changed model's and the unchanged model's;
//! - two pendulums whose masses are joined by a point spring k: along each axis the pair
//!   of modes of two identical oscillators of frequency ω0 and mass m coupled by k, ω² =
//!   ω0² (in phase, the spring idle) and ω² = ω0² + 2k/m (in antiphase), with ω0 each
//!   axis's frequency of the pendulum alone (the uncoupled run): 1e-9 relative.

use std::path::Path;

use pendkit::{Case, Override, Stage, run_stage};

/// The mode frequencies (Hz) of `case` at stage 2 (every element), ascending.
fn modes_hz(case: &Case) -> Vec<f64> {
    let (system, _) = case.build().expect("builds");
    let r = run_stage(system, Stage::S2).expect("runs");
    let mut hz: Vec<f64> = r.modes.modes.iter().map(|m| m.hz).collect();
    hz.sort_by(f64::total_cmp);
    hz
}

/// A bundled model's modes (Hz), with overrides.
fn model_hz(name: &str, overrides: &[(&str, f64)]) -> Vec<f64> {
    let case = Case::model(name)
        .unwrap()
        .with(overrides.iter().map(|(n, v)| Override::value(*n, *v)))
        .unwrap();
    modes_hz(&case)
}

/// The scene read from `text`.
fn scene(text: &str) -> Case {
    Case::from_text(Path::new("scene.toml"), text).unwrap()
}

/// A scene of `model` under the prefixes `a_` and `b_`, then `rest`.
fn two(model: &str, rest: &str) -> String {
    format!(
        "name = \"two\"\n\n[[include]]\nmodel = \"{model}\"\nprefix = \"a_\"\n\n\
         [[include]]\nmodel = \"{model}\"\nprefix = \"b_\"\n{rest}"
    )
}

/// `a` and `b` merged, ascending.
fn union(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut all: Vec<f64> = a.iter().chain(b).copied().collect();
    all.sort_by(f64::total_cmp);
    all
}

#[track_caller]
fn assert_same(scene: &[f64], reference: &[f64], rel: f64) {
    assert_eq!(scene.len(), reference.len(), "{scene:?} vs {reference:?}");
    for (s, r) in scene.iter().zip(reference) {
        assert!((s - r).abs() <= rel * r.abs(), "{s} vs {r} ({scene:?})");
    }
}

#[test]
fn two_uncoupled_copies_have_each_mode_of_the_model_twice() {
    // the pendulum (one stage), the quad (blades, four stages, a naming scheme) and
    // quad-aligo (which extends quad, which extends ligo-materials; its gravity 9.80665 and
    // its `temperature` are the scene's)
    for model in ["pendulum", "quad", "quad-aligo"] {
        let alone = model_hz(model, &[]);
        let both = modes_hz(&scene(&two(model, "")));
        assert_same(&both, &union(&alone, &alone), 1e-12);
    }
    // the bundled arm-cavity scene without light: its optical spring (power 0) adds
    // nothing, so the two quad-aligo suspensions are independent
    let alone = model_hz("quad-aligo", &[]);
    assert_same(&model_hz("arm-cavity", &[]), &union(&alone, &alone), 1e-12);
}

#[test]
fn an_override_of_one_copys_parameter_changes_that_copy_only() {
    let alone = model_hz("pendulum", &[]);
    let heavier = model_hz("pendulum", &[("m1", 55.0), ("l_fibre", 0.8)]);
    assert!((heavier[0] - alone[0]).abs() > 1e-3 * alone[0]);
    let expected = union(&alone, &heavier);
    // on the command line (`--set b_m1=55 --set b_l_fibre=0.8`) ...
    let set = scene(&two("pendulum", ""))
        .with([
            Override::value("b_m1", 55.0),
            Override::value("b_l_fibre", 0.8),
        ])
        .unwrap();
    assert_same(&modes_hz(&set), &expected, 1e-12);
    // ... and in the scene's own [parameters]
    let written = scene(&two(
        "pendulum",
        "\n[parameters]\nb_m1 = 55\nb_l_fibre = { value = 0.8, unit = \"m\" }\n",
    ));
    assert_same(&modes_hz(&written), &expected, 1e-12);
    // the override keeps the description the pendulum's file gives
    let (_, resolved) = written.build().unwrap();
    let info = written.model.parameter_info(&resolved).unwrap();
    let m = info.iter().find(|p| p.name == "b_m1").unwrap();
    assert_eq!(
        (m.unit.as_str(), m.description.as_str()),
        ("kg", "the point mass")
    );
}

/// Two pendulums side by side whose masses are joined by a point spring `k_c` (N/m),
/// between the masses' centres (which coincide: both hang from the origin).
fn coupled(k: f64) -> String {
    two(
        "pendulum",
        &format!(
            r#"
[parameters]
k_c = {{ value = {k}, unit = "N/m", description = "coupling stiffness" }}

[[element]]
kind = "point-spring"
name = "coupler"
between = ["a_mass1", "b_mass1"]
points = [["0", "0", "0"], ["0", "0", "0"]]
values = {{ k = "k_c" }}
"#
        ),
    )
}

#[test]
fn a_spring_between_the_two_masses_splits_each_pair_as_coupled_oscillators_do() {
    // m: the pendulum's documented point mass (models/basic/pendulum.toml, m1 = 40 kg)
    let m = 40.0;
    let k = 5.0;
    let alone = model_hz("pendulum", &[]);
    // the point mass has three modes, one per axis (x, y swings and the bounce)
    assert_eq!(alone.len(), 3);
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut expected: Vec<f64> = alone
        .iter()
        .flat_map(|f0| {
            let w0 = two_pi * f0;
            [*f0, (w0 * w0 + 2.0 * k / m).sqrt() / two_pi]
        })
        .collect();
    expected.sort_by(f64::total_cmp);
    let hz = modes_hz(&scene(&coupled(k)));
    assert_same(&hz, &expected, 1e-9);
}
