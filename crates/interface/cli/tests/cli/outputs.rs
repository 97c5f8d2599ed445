//! Outputs that never lie (issue 35, item 4; docs/cli.md "Output files" and "Exit
//! statuses"): a failed write to stdout or to a file is an error exit with one line naming
//! it; a closed pipe is not an error; output files are written whole or not at all, no
//! temporary file stays behind, and an existing output is replaced by every command alike;
//! `modes --json`, now streamed, prints what the document built in memory printed.

use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::pendkit;

/// A fresh scratch folder for this test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pendkit-outputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The names in a folder, sorted (hidden temporary files included).
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Asserts that `args` fail with exactly one line on stderr, `error: ` and every word.
fn fails_with_one_line(args: &[&str], words: &[&str]) {
    let (ok, _, stderr) = pendkit(args);
    assert!(!ok, "{args:?} succeeded");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for w in words {
        assert!(stderr.contains(w), "{args:?}: '{w}' not in {stderr}");
    }
}

#[test]
fn a_full_stdout_is_an_error_naming_stdout() {
    // Was: exit 0 and nothing on stderr (main treated every stdout error as a closed pipe),
    // so a script's results were lost on a full disk without a word.
    for args in [
        &["modes", "quad"][..],
        &["modes", "quad", "--json"][..],
        &["tf", "quad", "--input", "x00", "--output", "x3", "--csv"][..],
        &["noise", "quad", "--output", "x3", "--csv"][..],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full (Linux)");
        let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
            .args(args)
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} exited 0");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error: cannot write the output to stdout: "),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn a_closed_pipe_is_a_quiet_success() {
    // `pendkit ... | head -1`: the reader has what it wanted. The JSON of quad-v5 (1 MB) is
    // far larger than a pipe's buffer, so the writes after the close surely fail (EPIPE).
    let mut child = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .args(["modes", "quad-v5", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert_eq!(first, "{\n");
    // the reader is dropped here: the pipe is closed
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{:?}", out.status);
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
}

/// The arguments of a run of the pendulum's fit that writes `--out path` (quick: one free
/// parameter, two measured modes).
fn fit_args(dir: &Path, out: &str) -> Vec<String> {
    let measured = dir.join("measured.csv");
    std::fs::write(
        &measured,
        "label,hz,sigma_hz\nx1,0.65,0.001\nz1,6.18,0.01\n",
    )
    .unwrap();
    ["fit", "pendulum", "--modes", measured.to_str().unwrap()]
        .into_iter()
        .chain(["--free", "l_fibre", "--out", out])
        .map(String::from)
        .collect()
}

/// One run of each kind of output file, writing `path` (a file, or `report`'s folder).
fn writers(dir: &Path, path: &str) -> Vec<Vec<String>> {
    let strings = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    vec![
        strings(&["modes", "pendulum", "--plot", &format!("{path}.svg")]),
        strings(&["modes", "pendulum", "--plot", &format!("{path}.png")]),
        strings(&["ss", "pendulum", "--out", &format!("{path}.json")]),
        strings(&["ss", "pendulum", "--out", &format!("{path}.npz")]),
        fit_args(dir, &format!("{path}.toml")),
        strings(&["report", "pendulum", "--points", "5", "--out", path]),
    ]
}

#[test]
fn an_output_in_a_missing_folder_fails_naming_it_and_leaves_nothing() {
    // A folder that does not exist, and one that cannot exist because a file stands where
    // it should be. `report` makes its output folder with its parents (as `mkdir -p`), so
    // only the second stops it. Read-only folders are not tried: the tests may run as
    // root, which writes anywhere.
    let dir = scratch("missing");
    std::fs::write(dir.join("a-file"), "").unwrap();
    for folder in ["no-such-folder", "a-file"] {
        let path = dir.join(folder).join("out");
        let path = path.to_str().unwrap();
        for args in writers(&dir, path) {
            if args[0] == "report" && folder == "no-such-folder" {
                continue;
            }
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            fails_with_one_line(&args, &["cannot write", path]);
        }
    }
    assert_eq!(entries(&dir), ["a-file", "measured.csv"]);
}

#[test]
fn an_existing_output_is_replaced_whole_by_every_command() {
    // Was: `ss` refused an existing file without --force while plots, reports, fit --out
    // and tradeoff replaced theirs; now every command replaces (docs/cli.md).
    let dir = scratch("replace");
    let path = dir.join("out");
    let path = path.to_str().unwrap();
    for args in writers(&dir, path) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let written = match args[0] {
            "report" => dir.join("out/index.html"),
            _ => PathBuf::from(args.last().unwrap()),
        };
        std::fs::create_dir_all(written.parent().unwrap()).unwrap();
        std::fs::write(&written, "an old output").unwrap();
        let (ok, _, stderr) = pendkit(&args);
        assert!(ok, "{args:?}: {stderr}");
        let new = std::fs::read(&written).unwrap();
        assert!(new.len() > 100, "{args:?}: {} bytes", new.len());
        assert!(!new.starts_with(b"an old output"), "{args:?}");
    }
    // no temporary file remains, in the folder or in the report's
    let left: Vec<String> = entries(&dir)
        .into_iter()
        .chain(entries(&dir.join("out")))
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_failed_rename_keeps_the_old_output_and_removes_the_temporary() {
    // The write itself succeeds but the output cannot take its name (a folder stands
    // there): the error names the output, the temporary file is removed, the folder stays.
    let dir = scratch("rename");
    let target = dir.join("chart.svg");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("kept"), "").unwrap();
    let target = target.to_str().unwrap();
    fails_with_one_line(
        &["modes", "pendulum", "--plot", target],
        &["cannot write", target],
    );
    assert_eq!(entries(&dir), ["chart.svg"]);
    assert_eq!(entries(Path::new(target)), ["kept"]);
}

/// `modes MODEL --json` as pendkit printed it before it was streamed: the document built
/// whole as one `serde_json::Value` (its `json!` form, copied from the earlier
/// crates/interface/cli/src/modes.rs) and printed with `to_string_pretty`. The reference of
/// the test below; it runs the stage as `pendkit modes` does (stage 2, the model's names).
fn modes_json_built_in_memory(model: &str) -> String {
    use pendkit::stage::{ModeSelection, RunOptions, run_stage_with};
    use serde_json::json;
    let case = pendkit::Case::open(model).unwrap().with_sets(&[]).unwrap();
    let (system, _) = case.build().unwrap();
    let options = RunOptions {
        modes: ModeSelection::All,
        ..Default::default()
    };
    let r = run_stage_with(system, pendkit::Stage::S2, &options, None).unwrap();
    let finite_or_null = |x: f64| {
        if x.is_finite() {
            json!(x)
        } else {
            serde_json::Value::Null
        }
    };
    let modes: Vec<serde_json::Value> = r
        .modes
        .modes
        .iter()
        .map(|m| {
            let lab: Vec<_> = pendkit::dynamics::lab_motion(
                &r.system,
                &r.assembled.layout,
                &r.assembled.equilibrium.coords,
                m,
            )
            .unwrap()
            .into_iter()
            .map(|b| json!({"body": b.body, "translation": b.translation, "rotation": b.rotation}))
            .collect();
            json!({
                "hz": m.hz,
                "omega_squared": m.omega_squared,
                "stable": m.is_stable(),
                "label": m.label,
                "family": r.mode_family(m),
                "accuracy": finite_or_null(m.accuracy()),
                "vector_accuracy": m.vector_error,
                "vector": m.vector,
                "energy_fractions": m.energy_fractions,
                "lab": lab,
            })
        })
        .collect();
    let equilibrium: serde_json::Map<String, serde_json::Value> = r
        .system
        .coords
        .iter()
        .zip(&r.assembled.equilibrium.coords)
        .map(|(c, v)| (c.name.clone(), json!(v)))
        .collect();
    let out = json!({
        "model": case.model.name(),
        "case": case.name,
        "stage": pendkit::Stage::S2.name(),
        "naming": "model",
        "coordinates": r.modes.coordinates,
        "coordinate_units": r.modes.coordinates.iter().map(|c| r.coordinate_unit(c).unwrap_or_default()).collect::<Vec<_>>(),
        "equilibrium": equilibrium,
        "modes": modes,
    });
    serde_json::to_string_pretty(&out).unwrap() + "\n"
}

#[test]
fn streamed_modes_json_is_what_the_document_in_memory_printed() {
    // Was: built as one serde_json::Value and then one String (5.6 GB of memory for the
    // 0.9 GB JSON of the quad with 200 beads per fibre). Streamed, it must be the same
    // document, byte for byte, as the reference above prints.
    for model in ["quad", "triple-v5", "pendulum"] {
        let (ok, streamed, stderr) = pendkit(&["modes", model, "--json"]);
        assert!(ok, "{model}: {stderr}");
        let built = modes_json_built_in_memory(model);
        let parsed: serde_json::Value = serde_json::from_str(&streamed).unwrap();
        let reference: serde_json::Value = serde_json::from_str(&built).unwrap();
        assert_eq!(parsed, reference, "{model}: a different document");
        // not assert_eq!: a failure would print megabytes
        assert!(
            streamed == built,
            "{model}: the same document in other bytes"
        );
    }
}
