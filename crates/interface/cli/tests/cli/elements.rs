//! `pendkit elements KIND` and `[[element]]` instances on the command line: the schema with
//! its units and a snippet that, pasted into a suspension file, loads; and `extends`
//! carrying a base file's instances along (same name replaces, new names add).
//!
//! The reference is the model itself without the spring: a point mass m on hinged fibres
//! with an isotropic spring k between the bob's centre of mass and the support adds k/m to
//! each swing's ω² (the spring's points coincide at the start, so it adds no static force),
//! so f(k) = sqrt(f₀² + k/(4π² m)) with f₀ the same file's swing without the spring.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use crate::common;
use common::pendkit;

/// The bundled pendulum's mass `m1` (kg).
const M: f64 = 40.0;

/// The bundled `pendulum` (a 40 kg point mass, `mass1`, hinged on four 0.6 m silica fibres
/// from a driven support), with the parameter `k_magnet` (100 N/m) and `extra` appended.
fn pendulum_with(extra: &str) -> String {
    format!(
        r#"extends = "pendulum"
[parameters]
k_magnet = {{ value = 100, unit = "N/m", description = "the magnet's stiffness" }}
{extra}"#
    )
}

/// The instance `name` of a point spring of stiffness `k` (an expression) between the bob's
/// centre of mass (`mass1`) and the same point on the support.
fn coil(name: &str, k: &str) -> String {
    format!(
        r#"
[[element]]
kind = "point-spring"
name = "{name}"
between = ["mass1", "support"]
points = [[0, 0, 0], [0, 0, 0]]
values = {{ k = "{k}" }}
"#
    )
}

/// A scratch folder of this test binary's own.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pendkit-elements-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `path` written with `text`, as a command-line argument.
fn write(path: &Path, text: &str) -> String {
    std::fs::write(path, text).unwrap();
    path.display().to_string()
}

/// The two lowest stage-0A mode frequencies (Hz) of `file` with `args` after it.
fn swings(file: &str, args: &[&str]) -> [f64; 2] {
    let mut all = vec!["modes", file, "--stage", "0a", "--json"];
    all.extend_from_slice(args);
    let (ok, stdout, stderr) = pendkit(&all);
    assert!(ok, "{all:?}: {stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
    let hz: Vec<f64> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["hz"].as_f64().unwrap())
        .collect();
    [hz[0], hz[1]]
}

/// Whether both swings of `file` are the spring-free swings `f0` stiffened by `k` (N/m).
fn assert_stiffened(got: [f64; 2], f0: [f64; 2], k: f64) {
    for (f, f0) in got.into_iter().zip(f0) {
        let expected = (f0 * f0 + k / (4.0 * PI * PI * M)).sqrt();
        // the model is exactly the closed form here; 1e-9 covers the eigenvalues' rounding
        assert!(
            (f - expected).abs() < 1e-9 * expected,
            "{f} vs {expected} (k = {k})"
        );
    }
}

#[test]
fn elements_kind_prints_the_schema_and_a_snippet_that_loads() {
    let (ok, stdout, stderr) = pendkit(&["elements", "point-spring"]);
    assert!(ok, "{stderr}");
    let k = stdout
        .lines()
        .find(|l| l.split_whitespace().next() == Some("k"))
        .unwrap_or_else(|| panic!("no row for k: {stdout}"));
    assert!(k.contains("N/m") && k.contains("required"), "{k}");
    // the snippet, with the bodies named as this file names them
    let snippet = stdout
        .split_once("[[element]]")
        .map(|(_, s)| format!("[[element]]{s}"))
        .unwrap_or_else(|| panic!("no snippet: {stdout}"));
    let snippet = snippet
        .replace("\"body1\"", "\"mass1\"")
        .replace("\"body2\"", "\"support\"");
    let value = snippet
        .lines()
        .find_map(|l| l.strip_prefix("values = { k = \""))
        .and_then(|l| l.split('"').next())
        .unwrap_or_else(|| panic!("k given by a parameter: {snippet}"));
    let dir = scratch("snippet");
    let bare = write(&dir.join("bare.toml"), &pendulum_with(""));
    let with = pendulum_with(&format!(
        "\n[parameters.{value}]\nvalue = 250\nunit = \"N/m\"\ndescription = \"pasted\"\n\n{snippet}"
    ));
    let pasted = write(&dir.join("pasted.toml"), &with);
    assert_stiffened(swings(&pasted, &[]), swings(&bare, &[]), 250.0);
}

#[test]
fn elements_unknown_kind_is_a_usage_error_listing_kinds() {
    let (ok, stdout, stderr) = pendkit(&["elements", "point-sprung"]);
    assert!(!ok && stdout.is_empty());
    assert!(
        stderr.contains("point-sprung") && stderr.contains("point-spring"),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}

#[test]
fn extends_carries_instances_along() {
    let dir = scratch("extends");
    let bare = write(&dir.join("bare.toml"), &pendulum_with(""));
    let f0 = swings(&bare, &[]);
    write(
        &dir.join("base.toml"),
        &pendulum_with(&coil("coil", "k_magnet")),
    );
    // extending without touching [[element]]: the base's instance, its value a parameter
    // that --set reaches
    let plain = write(&dir.join("plain.toml"), "extends = \"base.toml\"\n");
    assert_stiffened(swings(&plain, &[]), f0, 100.0);
    assert_stiffened(swings(&plain, &["--set", "k_magnet=300"]), f0, 300.0);
    // a new name adds a spring in parallel (at the same points: stiffnesses add)
    let added = write(
        &dir.join("added.toml"),
        &format!("extends = \"base.toml\"\n{}", coil("coil2", "3 * k_magnet")),
    );
    assert_stiffened(swings(&added, &[]), f0, 400.0);
    // the base's name replaces the base's instance
    let replaced = write(
        &dir.join("replaced.toml"),
        &format!("extends = \"base.toml\"\n{}", coil("coil", "2 * k_magnet")),
    );
    assert_stiffened(swings(&replaced, &[]), f0, 200.0);
}
