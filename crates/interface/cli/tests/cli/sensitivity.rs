//! `pendkit sensitivity`: the JSON shape and its numbers against closed forms, the table's
//! order, and one-line errors.

use crate::common;

use common::pendkit;

#[test]
fn json_has_one_row_per_mode_and_one_column_per_parameter() {
    // the toy (a mass on springs k1, k2 in series): f = √(k/m)/2π, k = k1 k2/(k1 + k2), so
    // df/dm = −f/(2m) and df/dk1 = f/(2k)·(k/k1)² (closed forms; 1e-9 relative: the
    // derivatives are exact, dual numbers through the build, the springs and the
    // equilibrium, so only rounding remains)
    let (ok, out, err) = pendkit(&["sensitivity", "toy", "--stage", "0a", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let object = v.as_object().expect("an object");
    let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        ["dfdp", "exact", "exact_build", "modes_hz", "parameters"]
    );
    let parameters: Vec<&str> = v["parameters"]
        .as_array()
        .expect("parameters")
        .iter()
        .map(|p| p.as_str().expect("a name"))
        .collect();
    assert_eq!(parameters[..3], ["m", "k1", "k2"]);
    // the toy's masses and springs have exact derivatives
    assert_eq!(v["exact"][0], true);
    assert_eq!(v["exact"][1], true);
    let f = v["modes_hz"][0].as_f64().expect("f");
    let row = v["dfdp"][0].as_array().expect("a row");
    assert_eq!(row.len(), parameters.len());
    let (m, k1, k2) = (1.0, 1e3, 3e3); // the toy's defaults (`pendkit params toy`)
    let k = k1 * k2 / (k1 + k2);
    let expected = [-f / (2.0 * m), f / (2.0 * k) * (k / k1).powi(2)];
    for (j, e) in expected.iter().enumerate() {
        let got = row[j].as_f64().expect("a number");
        assert!(
            (got - e).abs() <= 1e-9 * e.abs(),
            "{}: {got} vs {e}",
            parameters[j]
        );
    }
}

#[test]
fn table_puts_the_largest_relative_sensitivity_first() {
    let (ok, out, err) = pendkit(&["sensitivity", "pendulum", "--top", "0"]);
    assert!(ok, "{err}");
    let relative: Vec<f64> = out
        .lines()
        .skip(2)
        .take_while(|l| !l.starts_with("not differentiable"))
        .map(|l| {
            l.split_whitespace()
                .last()
                .and_then(|x| x.parse::<f64>().ok())
                .expect("a relative sensitivity")
        })
        .collect();
    assert!(relative.len() > 5, "{out}");
    assert!(
        relative.windows(2).all(|w| w[0].abs() >= w[1].abs()),
        "{out}"
    );
    // the swing modes' largest sensitivities include the fibre length
    assert!(
        out.lines()
            .any(|l| l.contains("l_fibre") && l.contains("x1"))
    );
}

#[test]
fn tf_and_noise_json_keys() {
    let (ok, out, err) = pendkit(&[
        "sensitivity",
        "pendulum",
        "--tf",
        "x00:x1",
        "--noise",
        "x1",
        "--freqs",
        "0.1,2",
        "--parameters",
        "l_fibre,m1",
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(v["freqs_hz"].as_array().map(Vec::len), Some(2));
    assert_eq!(v["dtf_abs_dp"][1].as_array().map(Vec::len), Some(2));
    assert_eq!(v["dnoise_asd_dp"][0].as_array().map(Vec::len), Some(2));
    // only the responses were asked for: no mode rows
    assert_eq!(v["dfdp"].as_array().map(Vec::len), Some(0));
    // a force input (`force:` is a prefix, not the separator), as `pendkit sweep --tf`
    // takes it: the same |H| as `pendkit tf` prints for it
    let (ok, out, err) = pendkit(&[
        "sensitivity",
        "pendulum",
        "--tf",
        "force:x1:x1",
        "--freqs",
        "2",
        "--parameters",
        "l_fibre",
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let (ok, tf, err) = pendkit(&[
        "tf", "pendulum", "--input", "force:x1", "--output", "x1", "--freqs", "2", "--csv",
    ]);
    assert!(ok, "{err}");
    // the CSV's re and im columns
    let row: Vec<f64> = tf
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let magnitude = row[1].hypot(row[2]);
    let abs = v["tf_abs"][0].as_f64().unwrap();
    assert!(
        (abs - magnitude).abs() <= 1e-9 * magnitude,
        "{abs} vs {magnitude}"
    );
}

#[test]
fn bad_requests_fail_with_one_line() {
    for (args, says) in [
        (
            &["sensitivity", "pendulum", "--tf", "x00"][..],
            "INPUT:OUTPUT",
        ),
        (
            &["sensitivity", "pendulum", "--parameters", "nope"][..],
            "nope",
        ),
        (
            &["sensitivity", "pendulum", "--noise", "x1", "--freqs", "0"][..],
            "--freqs",
        ),
        (
            &["sensitivity", "pendulum", "--tf", "x00:zz", "--freqs", "1"][..],
            "zz",
        ),
        (
            &["sensitivity", "pendulum", "--stage", "0a", "--noise", "x1"][..],
            "stage 0b",
        ),
        (
            &["sensitivity", "pendulum", "--parameters", "m,,l"][..],
            "empty name",
        ),
        (
            &["sensitivity", "pendulum", "--parameters", ""][..],
            "empty list",
        ),
        (&["sensitivity", "pendulum", "--freqs", "1,2"][..], "--tf"),
        (&["sensitivity", "pendulum", "--points", "3"][..], "--tf"),
    ] {
        let (ok, out, err) = pendkit(args);
        assert!(!ok, "{args:?} should fail: {out}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}

#[test]
fn threads_change_nothing_printed() {
    // the columns are computed by the same code on any thread: the JSON on one thread and
    // on three is the same text
    let (ok1, one, err1) = pendkit(&["sensitivity", "pendulum", "--json", "--threads", "1"]);
    let (ok3, three, err3) = pendkit(&["sensitivity", "pendulum", "--json", "--threads", "3"]);
    assert!(ok1 && ok3, "{err1} {err3}");
    assert_eq!(one, three);
}
