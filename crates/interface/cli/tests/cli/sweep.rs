//! `pendkit sweep`: modes tracked through a crossing keep their labels and follow their
//! closed forms; noise and transfer-function sweeps print what the single commands print.

use crate::common;
use common::pendkit;

/// CSV rows as fields.
fn rows(stdout: &str) -> Vec<Vec<String>> {
    stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn tracked_modes_keep_their_labels_through_a_crossing() {
    // The rigid body's yaw mode depends on the yaw inertia I1z alone (its block is exactly
    // decoupled from x-pitch, y-roll and bounce), so sweeping I1z from 0.72 to 1.28 kg m^2
    // (with I1x = 1 and I1y = 0.3 kg m^2: every step a body, each moment at most the other
    // two together) moves it from above the x-pitch and y-roll pendulum modes to below all
    // of them: sorted by frequency, mode 4 at the start is mode 1 at the end. Tracked by
    // shape, the yaw mode keeps its number and label at every step.
    let (ok, stdout, stderr) = pendkit(&[
        "sweep",
        "rigid-body",
        "--stage",
        "0a",
        "--set",
        "I1x=1",
        "--set",
        "I1y=0.3",
        "--vary",
        "I1z=0.72:1.28:9",
        "--modes",
    ]);
    assert!(ok, "{stderr}");
    // no progress bar when stderr is not a terminal: only the sweep's stability summary
    assert_eq!(
        stderr,
        "sweep: stable at every step: no instability for I1z from 0.72 to 1.28 kg m^2\n"
    );
    assert_eq!(
        stdout.lines().next().unwrap(),
        "I1z_kg_m2,mode,label,family,frequency_hz,dominant,overlap"
    );
    let rows = rows(&stdout);
    assert_eq!(rows.len(), 9 * 6);
    let yaw: Vec<&Vec<String>> = rows.iter().filter(|r| r[2] == "yaw1").collect();
    assert_eq!(yaw.len(), 9);
    // Reference (docs/physics.md, yaw with vertical wires at stage 0A): K_yaw = (T/l) Σ r_i²
    // with T = m g / 4 and r_i² = a² + b² for the four fibres at (±a, ±b): 40 kg, a = 5 mm,
    // b = 0.17 m, l = 0.6 m, g = 9.81. Tolerance 1e-10 as in the stage-0A closed-form
    // tests: rounding in assembly and eigen-solve (~1e-14) and the equilibrium residual.
    let k_yaw = 40.0 * 9.81 / 4.0 / 0.6 * 4.0 * (0.005f64.powi(2) + 0.17f64.powi(2));
    let mut others_first: Vec<(String, f64)> = Vec::new();
    for (step, row) in yaw.iter().enumerate() {
        let izz: f64 = row[0].parse().unwrap();
        let expected = (k_yaw / izz).sqrt() / (2.0 * std::f64::consts::PI);
        let hz: f64 = row[4].parse().unwrap();
        assert!(
            (hz - expected).abs() <= 1e-10 * expected,
            "step {step}: {hz} vs {expected}"
        );
        assert_eq!(row[1], "4", "the yaw mode keeps its number");
        assert_eq!(row[3], "Y");
        assert_eq!(row[5], "yaw1", "the shape stays a yaw shape");
        assert!((row[6].parse::<f64>().unwrap() - 1.0).abs() < 1e-6);
    }
    // the other modes do not depend on I1z: the same at every step, each labelled by its
    // own shape
    for row in rows.iter().filter(|r| r[2] != "yaw1") {
        assert_eq!(row[2], row[5], "{row:?}");
        let hz: f64 = row[4].parse().unwrap();
        match others_first.iter().find(|(label, _)| *label == row[2]) {
            Some((_, first)) => assert!((hz - first).abs() <= 1e-10 * first, "{row:?}"),
            None => others_first.push((row[2].clone(), hz)),
        }
    }
    // it did cross: above three modes at the first step, below all at the last
    let frequencies_at = |izz: &str| -> Vec<(String, f64)> {
        rows.iter()
            .filter(|r| r[0] == izz)
            .map(|r| (r[2].clone(), r[4].parse().unwrap()))
            .collect()
    };
    let rank = |modes: &[(String, f64)]| {
        let yaw = modes.iter().find(|m| m.0 == "yaw1").unwrap().1;
        modes.iter().filter(|m| m.1 < yaw).count()
    };
    assert_eq!(rank(&frequencies_at(&yaw[0][0])), 3);
    assert_eq!(rank(&frequencies_at(&yaw[8][0])), 0);
}

#[test]
fn noise_and_transfer_sweeps_print_what_the_single_commands_print() {
    for (sweep, single, header) in [
        (
            vec!["--noise", "x1"],
            vec!["noise", "pendulum", "--output", "x1"],
            "m1_kg,f_hz,asd_m_per_rthz",
        ),
        (
            vec!["--tf", "x00:x1"],
            vec!["tf", "pendulum", "--input", "x00", "--output", "x1"],
            "m1_kg,f_hz,re_m_per_m,im_m_per_m",
        ),
    ] {
        let args = [
            &[
                "sweep",
                "pendulum",
                "--vary",
                "m1=20:40:3",
                "--freqs",
                "0.5,3,30",
            ][..],
            &sweep,
        ]
        .concat();
        let (ok, stdout, stderr) = pendkit(&args);
        assert!(ok, "{stderr}");
        assert_eq!(stdout.lines().next().unwrap(), header);
        let rows = rows(&stdout);
        assert_eq!(rows.len(), 9);
        for (k, m1) in ["20", "30", "40"].iter().enumerate() {
            let set = format!("m1={m1}");
            let args = [
                &single[..],
                &["--set", &set, "--freqs", "0.5,3,30", "--csv"],
            ]
            .concat();
            let (ok, expected, stderr) = pendkit(&args);
            assert!(ok, "{stderr}");
            for (i, line) in expected.lines().skip(1).enumerate() {
                assert_eq!(rows[3 * k + i][1..].join(","), line, "{args:?}");
                assert_eq!(
                    rows[3 * k + i][0].parse::<f64>().unwrap(),
                    m1.parse::<f64>().unwrap()
                );
            }
        }
    }
}

#[test]
fn sweep_errors_are_one_line() {
    for (args, expected) in [
        (
            &["sweep", "pendulum", "--vary", "m1=1:2", "--modes"][..],
            "--vary 'm1=1:2'",
        ),
        (
            &["sweep", "pendulum", "--vary", "nosuch=1:2:2", "--modes"][..],
            "nosuch",
        ),
        (
            &["sweep", "pendulum", "--vary", "m1=1:2:2", "--tf", "x00"][..],
            "--tf 'x00'",
        ),
        (
            &[
                "sweep", "pendulum", "--vary", "m1=1:2:2", "--noise", "x1", "--freqs", "1,-2",
            ][..],
            "--freqs",
        ),
        (
            &[
                "sweep",
                "pendulum",
                "--vary",
                "m1=1:2:2",
                "--vary",
                "l_fibre=0.5:0.6:2",
                "--modes",
                "--plot",
                "a.svg",
            ][..],
            "one --vary",
        ),
    ] {
        let (ok, stdout, stderr) = pendkit(args);
        assert!(!ok && stdout.is_empty(), "{args:?}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
}
