//! The size limits from the command line (docs/checks-and-refusals.md, "Limits"): each is
//! one line naming the option or file, the count, the limit and the variable that raises it,
//! and the variable moves the limit for the run (lowered here, so that every test is a few
//! steps: raising it is the same code). A variable that is not a count is refused naming it.

use crate::common::{pendkit, pendkit_env};

/// Runs `args` with `env`, which must fail with one line holding every one of `words`.
#[track_caller]
fn refused_with(args: &[&str], env: &[(&str, &str)], words: &[&str]) {
    let (ok, stdout, stderr) = pendkit_env(args, env);
    assert!(!ok && stdout.is_empty(), "{args:?}: {stdout}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    for w in words {
        assert!(stderr.contains(w), "'{w}' not in {stderr}");
    }
}

#[test]
fn a_sweep_limit_set_by_its_variable_moves_and_says_who_set_it() {
    let sweep = ["sweep", "pendulum", "--vary", "m1=30:50:4", "--modes"];
    refused_with(
        &sweep,
        &[("PENDKIT_MAX_SWEEP_STEPS", "3")],
        &[
            "--vary 'm1=30:50:4': 4 sweep steps: more than the limit of 3",
            "PENDKIT_MAX_SWEEP_STEPS sets it",
        ],
    );
    let (ok, stdout, stderr) = pendkit_env(&sweep, &[("PENDKIT_MAX_SWEEP_STEPS", "4")]);
    assert!(ok, "{stderr}");
    // the header and the pendulum's three modes at each of the four steps
    assert_eq!(stdout.lines().count(), 1 + 4 * 3, "{stdout}");
    // the table's rows: four steps of three modes
    refused_with(
        &sweep,
        &[("PENDKIT_MAX_SWEEP_ROWS", "11")],
        &["sweep: 12 rows in one sweep table: more than the limit of 11"],
    );
    refused_with(
        &sweep,
        &[("PENDKIT_MAX_SWEEP_STEPS", "1e4")],
        &["PENDKIT_MAX_SWEEP_STEPS='1e4' is not a whole number from 1 up"],
    );
}

#[test]
fn frequency_lists_are_counted_whether_given_as_a_grid_a_list_or_a_file() {
    let tf = ["tf", "pendulum", "--input", "x00", "--output", "x1"];
    let env = [("PENDKIT_MAX_FREQUENCY_POINTS", "3")];
    refused_with(
        &[&tf[..], &["--points", "4"]].concat(),
        &env,
        &["--points: 4 frequencies in one grid: more than the limit of 3"],
    );
    refused_with(
        &[&tf[..], &["--freqs", "1,2,3,4"]].concat(),
        &env,
        &["--freqs: 4 frequencies in one grid"],
    );
    let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("limits-freqs.txt");
    std::fs::write(&path, "1 2\n3\n4 5\n").unwrap();
    let file = path.to_string_lossy().into_owned();
    refused_with(
        &[&tf[..], &["--freqs-file", &file]].concat(),
        &env,
        &[&format!("--freqs-file {file}: 5 frequencies in one grid")],
    );
    let (ok, _, stderr) = pendkit_env(&[&tf[..], &["--points", "3"]].concat(), &env);
    assert!(ok, "{stderr}");
}

#[test]
fn input_files_past_the_size_limit_or_not_regular_are_not_read() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("limits-small.toml");
    std::fs::write(&path, "model = \"pendulum\"\n").unwrap();
    let file = path.to_string_lossy().into_owned();
    refused_with(
        &["modes", &file],
        &[("PENDKIT_MAX_FILE_BYTES", "10")],
        &[&format!(
            "case file {file}: 19 bytes in one input file: more than the limit of 10"
        )],
    );
    let (ok, _, stderr) = pendkit(&["modes", &file]);
    assert!(ok, "{stderr}");
    // a frequency file that is a directory
    let (ok, _, stderr) = pendkit(&[
        "tf",
        "pendulum",
        "--input",
        "x00",
        "--output",
        "x1",
        "--freqs-file",
        &dir.to_string_lossy(),
    ]);
    assert!(
        !ok && stderr.contains("not a regular file (a directory)"),
        "{stderr}"
    );
}
