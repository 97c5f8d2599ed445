//! Suspension files on the command line: a file runs like a bundled model, a case file can
//! name one, `pendkit chain-file` writes one, `pendkit model-file` prints a bundled one,
//! `pendkit params` lists every parameter, and a
//! bad file's error is one line naming the file, the line and the field.

use std::path::PathBuf;

use crate::common;
use common::pendkit;

fn json(args: &[&str]) -> serde_json::Value {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(ok, "{args:?}: {stderr}");
    serde_json::from_str(&stdout).expect("valid JSON")
}

fn frequencies(args: &[&str]) -> Vec<f64> {
    json(args)["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["hz"].as_f64().unwrap())
        .collect()
}

fn example() -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../examples/three-stage.toml");
    path.display().to_string()
}

/// A scratch folder of this test binary's own.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "pendkit-suspension-files-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Magnitudes of `pendkit tf ... --csv` (columns f_hz, re, im).
fn tf_magnitudes(args: &[&str]) -> Vec<f64> {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(ok, "{args:?}: {stderr}");
    stdout
        .lines()
        .skip(1)
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            v[1].hypot(v[2])
        })
        .collect()
}

/// The worked example runs from the reference page's format. Its named output `optic_beam`
/// (the optic's face centre along x) equals the same point written on the command line,
/// and at 1 mHz, far below the lowest mode (0.45 Hz), the optic follows the support:
/// |H| = 1 + O((f/f0)²) ≈ 1 + 5e-6.
#[test]
fn the_worked_example_runs() {
    let file = example();
    let hz = frequencies(&["modes", &file, "--json"]);
    assert_eq!(hz.len(), 18, "3 bodies x 6 degrees of freedom");
    assert!(hz.iter().all(|f| *f > 0.0));
    let common = [
        "tf",
        &file,
        "--input",
        "x0",
        "--freqs",
        "0.001,0.3,1,10",
        "--csv",
    ];
    let named = tf_magnitudes(&[&common[..], &["--output", "optic_beam"]].concat());
    let point = tf_magnitudes(&[&common[..], &["--output", "optic@-0.05,0,0/1,0,0"]].concat());
    for (a, b) in named.iter().zip(&point) {
        assert!((a - b).abs() <= 1e-12 * a.abs(), "{a} vs {b}");
    }
    assert!((named[0] - 1.0).abs() < 1e-4, "{}", named[0]);
}

/// `pendkit chain-file N` writes a file that is the bundled chain with n_stages = N through
/// the command line: equal mode frequencies (the bundled chain is the same generator's text,
/// so they agree exactly; 1e-9 relative is the bound this test had when the bundled chain
/// was an independent Rust model). The chain's physics is pinned by tests/physics/chain.rs.
#[test]
fn chain_file_is_the_bundled_chain() {
    let (ok, text, stderr) = pendkit(&["chain-file", "3"]);
    assert!(ok, "{stderr}");
    let path = scratch("chain").join("chain-3.toml");
    std::fs::write(&path, text).unwrap();
    let file = frequencies(&["modes", path.to_str().unwrap(), "--json"]);
    let rust = frequencies(&["modes", "chain", "--set", "n_stages=3", "--json"]);
    assert_eq!(file.len(), 18);
    for (a, b) in file.iter().zip(&rust) {
        assert!((a - b).abs() <= 1e-9 * b, "{a} vs {b}");
    }
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
    let (ok, _, stderr) = pendkit(&["chain-file", "0"]);
    assert!(!ok && stderr.contains("1 to 10000"), "{stderr}");
}

/// A case file names a suspension file (relative to its own folder) and overrides it: the
/// same as the suspension file with `--set`.
#[test]
fn a_case_file_can_name_a_suspension_file() {
    let dir = scratch("case");
    std::fs::copy(example(), dir.join("three.toml")).unwrap();
    let case = dir.join("heavy.toml");
    std::fs::write(
        &case,
        "model = \"three.toml\"\n[parameters]\nm_optic = 40\n",
    )
    .unwrap();
    let v = json(&["modes", case.to_str().unwrap(), "--json"]);
    assert_eq!(v["model"], "three-stage");
    let by_case = frequencies(&["modes", case.to_str().unwrap(), "--json"]);
    let file = dir.join("three.toml");
    let by_set = frequencies(&[
        "modes",
        file.to_str().unwrap(),
        "--set",
        "m_optic=40",
        "--json",
    ]);
    let original = frequencies(&["modes", file.to_str().unwrap(), "--json"]);
    assert_eq!(by_case, by_set);
    assert_ne!(by_case, original);
    let _ = std::fs::remove_dir_all(dir);
}

/// `pendkit params` lists every parameter with value, unit, description and readers: the
/// example file's own entries as written there, the built-in temperature, a `--set`.
#[test]
fn params_lists_every_parameter() {
    let file = example();
    let rows = json(&["params", &file, "--set", "m_top=12", "--json"]);
    let rows = rows.as_array().unwrap();
    let row = |name: &str| {
        rows.iter()
            .find(|r| r["name"] == name)
            .unwrap_or_else(|| panic!("{name}"))
    };
    // the file defines 12 parameters; temperature and wire_terms_early are every model's
    assert_eq!(rows.len(), 14);
    let m = row("m_optic");
    assert_eq!(m["value"], 20.0);
    assert_eq!(m["unit"], "kg");
    assert_eq!(m["description"], "optic");
    let readers: Vec<&str> = m["read_by"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    for expected in [
        "bodies.optic.mass",
        "bodies.optic.inertia[0]",
        "bodies.optic.inertia[1]",
    ] {
        assert!(readers.contains(&expected), "{readers:?}");
    }
    assert_eq!(row("m_top")["value"], 12.0);
    assert_eq!(row("temperature")["unit"], "K");
    let breakoff: Vec<&str> = row("breakoff")["read_by"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    assert_eq!(breakoff.len(), 3, "{breakoff:?}");
    // a bundled model: units from the model, descriptions and readers from its file
    let (ok, table, stderr) = pendkit(&["params", "quad"]);
    assert!(ok, "{stderr}");
    let m3 = table.lines().find(|l| l.starts_with("m3 ")).unwrap();
    assert!(m3.contains(" kg ") && m3.contains("test mass"), "{m3}");
    assert!(table.contains("read by: bodies.testmass.mass"), "{table}");
    // quad-aligo: a tapered fibre's profile names its parameters too
    let (ok, table, stderr) = pendkit(&["params", "quad-aligo"]);
    assert!(ok, "{stderr}");
    let neck = table.lines().find(|l| l.starts_with("r3_neck ")).unwrap();
    assert!(neck.contains(" m ") && neck.contains("necks"), "{neck}");
    assert!(
        table.contains("read by: stages.testmass.fibres.profile.neck_radius"),
        "{table}"
    );
}

/// A bad file fails with one line: `error: <file>:<line>: <field>: <what>`.
#[test]
fn a_bad_file_names_file_line_and_field() {
    let text = std::fs::read_to_string(example()).unwrap();
    let bad = text.replace("mass = \"m_mid\"", "mass = \"m_middle\"");
    let line = bad.lines().position(|l| l.contains("m_middle")).unwrap() + 1;
    let path = scratch("bad").join("bad.toml");
    std::fs::write(&path, bad).unwrap();
    let (ok, _, stderr) = pendkit(&["modes", path.to_str().unwrap()]);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
    assert!(!ok);
    let expected = format!("error: {}:{line}: bodies.middle.mass: ", path.display());
    assert!(
        stderr.starts_with(&expected) && stderr.contains("m_mid"),
        "{stderr}"
    );
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
}

/// `pendkit model-file NAME` prints a bundled model's file; saved in a scratch folder and
/// run from there (its `extends` names bundled files, found wherever the copy is), it is the
/// bundled model: the same file read twice, so the same mode frequencies exactly. An unknown
/// name is refused with the names there are.
#[test]
fn model_file_prints_a_bundled_model_to_copy() {
    let (ok, text, stderr) = pendkit(&["model-file", "quad-lite"]);
    assert!(ok, "{stderr}");
    assert!(text.contains("name = \"quad-lite\""), "{text}");
    let path = scratch("model-file").join("my-quad.toml");
    std::fs::write(&path, text).unwrap();
    let copy = frequencies(&["modes", path.to_str().unwrap(), "--json"]);
    let bundled = frequencies(&["modes", "quad-lite", "--json"]);
    assert_eq!(copy.len(), 30);
    assert_eq!(copy, bundled);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
    let (ok, _, stderr) = pendkit(&["model-file", "quadd"]);
    assert!(!ok && stderr.contains("triple-v5"), "{stderr}");
}
