//! `pendkit ss` in each format carries units and provenance: the quad in LIGO names, to
//! JSON (read here) and to `.npz` (read by numpy). Expected values come from outside the
//! code under test: the quad's 2005 parameter table (m3 = 39.6 kg), the state-space form of
//! docs/physics.md §3 (A's upper right block is the identity), and the LIGO names of
//! docs/conventions.md.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn export(file: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(file);
    // a previous run's file would be replaced; removed so that this run surely wrote it
    let _ = std::fs::remove_file(&path);
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .args(["ss", "quad", "--naming", "ligo", "--out"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

fn strings(v: &Value) -> Vec<&str> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect()
}

#[test]
fn json_export_carries_names_units_and_provenance() {
    let path = export("quad-ss.json");
    let d: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(strings(&d["model"]), ["quad"]);
    assert_eq!(strings(&d["case_name"]), ["quad"]);
    assert_eq!(strings(&d["stage"]), ["2"]);
    assert_eq!(strings(&d["naming"]), ["ligo"]);
    assert_eq!(strings(&d["pendkit_version"]), [env!("CARGO_PKG_VERSION")]);
    // 24 variables: positions then velocities
    let states = strings(&d["states"]);
    assert_eq!(states.len(), 48);
    assert_eq!(
        &states[18..24],
        ["L3_L", "L3_T", "L3_V", "L3_Y", "L3_P", "L3_R"]
    );
    let state_units = strings(&d["state_units"]);
    assert_eq!(state_units[18], "m");
    assert_eq!(state_units[22], "rad");
    assert_eq!(state_units[24 + 18], "m/s");
    let inputs = strings(&d["inputs"]);
    assert_eq!(&inputs[..3], ["GND_L", "GND_T", "GND_V"]);
    assert!(inputs.contains(&"force:L3_P"));
    let input_units = strings(&d["input_units"]);
    let k = inputs.iter().position(|&i| i == "force:L3_P").unwrap();
    assert_eq!(input_units[k], "N m");
    // A = [[0, I], ...]
    let a = d["A"].as_array().unwrap();
    for (i, row) in a.iter().take(24).enumerate() {
        for (j, value) in row.as_array().unwrap().iter().enumerate() {
            let want = if j == 24 + i { 1.0 } else { 0.0 };
            assert_eq!(value.as_f64(), Some(want), "A[{i}][{j}]");
        }
    }
    let names = strings(&d["parameter_names"]);
    let m3 = names.iter().position(|&n| n == "m3").unwrap();
    assert_eq!(d["parameter_values"][m3][0].as_f64(), Some(39.6));
    assert_eq!(strings(&d["parameter_units"])[m3], "kg");
    assert_eq!(d["damping_frequency_hz"][0][0].as_f64(), Some(1.0));
}

#[test]
fn npz_export_reads_in_numpy_with_the_same_fields() {
    if !crate::opted_in(
        "PENDKIT_TEST_PYTHON",
        "exports::ss_exports::npz_export_reads_in_numpy_with_the_same_fields",
        "python3 with numpy",
    ) {
        return;
    }
    let path = export("quad-ss.npz");
    let script = r#"
import sys
import numpy as np
d = np.load(sys.argv[1])
assert str(d["case_name"][0]) == "quad", d["case_name"]
assert str(d["naming"][0]) == "ligo"
assert d["A"].shape == (48, 48), d["A"].shape
names = list(d["parameter_names"])
assert float(d["parameter_values"][names.index("m3"), 0]) == 39.6
assert str(d["parameter_units"][names.index("m3")]) == "kg"
assert list(d["inputs"][:3]) == ["GND_L", "GND_T", "GND_V"]
print("ok")
"#;
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(&path)
        .output()
        .expect("python3 runs (python3 -m pip install numpy)");
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "ok",
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
