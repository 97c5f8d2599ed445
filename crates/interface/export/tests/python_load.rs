//! Cross-check with the Python tools that load our files: writes a .mat and a .npz and runs
//! `tests/load_check.py`, which reads them with `scipy.io.loadmat` and `numpy.load` and
//! compares values exactly. Needs `python3 -m pip install scipy numpy`; without them the
//! script, and so this test, fails with that hint.

use std::path::Path;
use std::process::Command;

use pendkit_export::{Matrix, Names, write};

#[test]
fn scipy_and_numpy_load_what_we_write() {
    if !opted_in(
        "PENDKIT_TEST_PYTHON",
        "python_load::scipy_and_numpy_load_what_we_write",
        "python3 with scipy and numpy",
    ) {
        return;
    }
    // Keep in step with the expected values in load_check.py.
    let a = [0.1, -2.5, 1e-300, 1.0 / 3.0, 6.02214076e23, -0.0];
    let b = [1.0, 2.0, 3.0];
    let states: Vec<String> = ["x1", "theta_dot", "φ_pitch", ""]
        .map(String::from)
        .to_vec();
    let inputs: Vec<String> = Vec::new();
    let matrices = [
        Matrix {
            name: "A",
            rows: 2,
            cols: 3,
            data: &a,
        },
        Matrix {
            name: "B",
            rows: 3,
            cols: 1,
            data: &b,
        },
        Matrix {
            name: "E",
            rows: 0,
            cols: 0,
            data: &[],
        },
    ];
    let names = [
        Names {
            name: "states",
            items: &states,
        },
        Names {
            name: "inputs",
            items: &inputs,
        },
    ];

    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pendkit-export-python");
    std::fs::create_dir_all(&dir).unwrap();
    let mat = dir.join("ss.mat");
    let npz = dir.join("ss.npz");
    // files of an earlier run: write refuses to replace them
    let _ = std::fs::remove_file(&mat);
    let _ = std::fs::remove_file(&npz);
    write(&mat, &matrices, &names).unwrap();
    write(&npz, &matrices, &names).unwrap();

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/load_check.py");
    let output = Command::new("python3")
        .arg(&script)
        .arg(&mat)
        .arg(&npz)
        .output()
        .unwrap_or_else(|e| panic!("cannot run python3 {}: {e}", script.display()));
    assert!(
        output.status.success(),
        "{} failed ({}):\n{}{}",
        script.display(),
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
}

/// Whether the opt-in tests gated by the environment variable `var` run: they do when it is
/// `1`. Otherwise this prints one line naming `test`, what it needs and how to enable it, and
/// the caller returns (Rust has no run-time skip: the test passes). The line is written to
/// the process's stderr directly, past the test harness's capture, so `cargo test` shows it.
/// With the variable set, the test runs and a missing tool fails it with its own message.
fn opted_in(var: &str, test: &str, needs: &str) -> bool {
    if std::env::var(var).is_ok_and(|v| v == "1") {
        return true;
    }
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED {test}: needs {needs}; run it with {var}=1"
    );
    false
}
