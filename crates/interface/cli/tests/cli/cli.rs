//! The command line as docs/cli.md specifies it.

use crate::common;
use common::pendkit;

fn modes_json(args: &[&str]) -> serde_json::Value {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(ok, "{stderr}");
    serde_json::from_str(&stdout).expect("valid JSON")
}

fn frequencies(v: &serde_json::Value) -> Vec<f64> {
    v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["hz"].as_f64().unwrap())
        .collect()
}

#[test]
fn toy_json_has_the_contract_fields_and_the_oracle_frequency() {
    let v = modes_json(&["modes", "toy", "--stage", "0a", "--json"]);
    assert_eq!(v["model"], "toy");
    assert_eq!(v["stage"], "0A");
    assert_eq!(v["coordinates"], serde_json::json!(["x"]));
    let m = &v["modes"][0];
    assert_eq!(m["label"], "x");
    assert_eq!(m["vector"].as_array().unwrap().len(), 1);
    // docs/reference-values.md §8: f0 = 4.358638 Hz (7 significant digits)
    assert!((m["hz"].as_f64().unwrap() - 4.358638).abs() < 5e-7);
}

#[test]
fn pendulum_json_prints_the_pendulum_and_bounce_modes() {
    let v = modes_json(&["modes", "pendulum", "--stage", "0a", "--json"]);
    let hz = frequencies(&v);
    // sqrt(g/l)/2π = 0.6435451 Hz twice, bounce 6.180387 Hz (oracles §1, §3)
    assert_eq!(hz.len(), 3);
    assert!((hz[0] - 0.6435451).abs() < 5e-8 && (hz[1] - 0.6435451).abs() < 5e-8);
    assert!((hz[2] - 6.180387).abs() < 5e-7);
    assert!(hz.windows(2).all(|w| w[0] <= w[1]));
}

#[test]
fn set_overrides_and_case_files_agree() {
    let case = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../models/basic/cases/rigid-body/d2mm.toml"
    );
    let from_file = frequencies(&modes_json(&["modes", case, "--stage", "0a", "--json"]));
    let from_set = frequencies(&modes_json(&[
        "modes",
        "rigid-body",
        "--stage",
        "0a",
        "--set",
        "d_fibre=0.002",
        "--json",
    ]));
    assert_eq!(from_file, from_set);
    // oracles §2, d = 2 mm, s = ±5 mm: x-pitch pair 0.3717501 and 0.6437291 Hz
    assert!(from_file.iter().any(|f| (f - 0.3717501).abs() < 5e-8));
    let scaled = frequencies(&modes_json(&[
        "modes",
        "rigid-body",
        "--stage",
        "0a",
        "--set",
        "d_fibre=scale(0.2)",
        "--json",
    ]));
    assert_eq!(scaled, from_set);
}

#[test]
fn elements_lists_kinds_with_stages_and_crates() {
    let (ok, stdout, _) = pendkit(&["elements"]);
    assert!(ok);
    // the registered set and where each kind comes from: the core kinds from the energy
    // crate, the plug-ins from their own crates (recorded at registration)
    for (kind, stage, krate) in [
        ("gravity", "0A", "pendkit-energy"),
        ("spring", "0A", "pendkit-energy"),
        ("wire-stretch", "0A", "pendkit-energy"),
        ("wire-torsion", "1A", "pendkit-element-torsion"),
        ("wire-bending", "1B", "pendkit-element-bending"),
        ("wire-extra-stretch", "2", "pendkit-element-extra-stretch"),
    ] {
        let line = stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(kind))
            .unwrap_or_else(|| panic!("{kind} missing"));
        let columns: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(columns[1..3], [stage, krate], "{line}");
    }
}

#[test]
fn bad_input_is_one_line_and_non_zero() {
    let dir = std::env::temp_dir().join(format!("pendkit-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let broken = dir.join("broken.toml");
    std::fs::write(&broken, "model = \"pendulum\"\n[parameters\nm1 = 3\n").unwrap();
    let broken = broken.to_string_lossy().into_owned();
    let cases: [(&[&str], &str); 6] = [
        (&["modes", "nosuch"], "unknown model 'nosuch'"),
        (&["modes", "pendulum", "--set", "m1=-40"], "negative mass"),
        (
            &[
                "modes",
                "pendulum",
                "--set",
                "m1=2*l_fibre",
                "--set",
                "l_fibre=m1",
            ],
            "cycle",
        ),
        (&["modes", "pendulum", "--set", "m1"], "expected NAME=EXPR"),
        (&["modes", "pendulum", "--stage", "3"], "unknown stage"),
        (&["modes", broken.as_str()], "broken.toml"),
    ];
    for (args, expected) in cases {
        let (ok, stdout, stderr) = pendkit(args);
        assert!(!ok, "{args:?} succeeded");
        assert!(stdout.is_empty(), "{args:?} printed {stdout}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        if expected != "unknown stage" {
            // clap formats its own usage errors; ours are exactly one line
            assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        }
    }
}

#[test]
fn quad_modes_and_transfer_functions() {
    let v = modes_json(&["modes", "quad", "--stage", "0a", "--json"]);
    assert_eq!(frequencies(&v).len(), 24);
    assert_eq!(v["coordinates"].as_array().unwrap().len(), 24);
    // headers name their units: x3/x00 in m/m, x3 per newton on x3 in m/N
    for (input, header) in [
        ("x00", "f_hz,re_m_per_m,im_m_per_m"),
        ("force:x3", "f_hz,re_m_per_N,im_m_per_N"),
    ] {
        let (ok, stdout, stderr) = pendkit(&[
            "tf", "quad", "--input", input, "--output", "x3", "--points", "5", "--csv",
        ]);
        assert!(ok, "{stderr}");
        let rows: Vec<&str> = stdout.lines().collect();
        assert_eq!(rows[0], header);
        assert_eq!(rows.len(), 6);
        let first: Vec<f64> = rows[1].split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(first[0], 0.1);
        assert!(first[1].is_finite() && first[2].is_finite());
    }
    let (ok, stdout, _) = pendkit(&[
        "noise",
        "quad",
        "--output",
        "x3",
        "--points",
        "3",
        "--csv",
        "--breakdown",
    ]);
    assert!(ok);
    assert!(
        stdout
            .lines()
            .next()
            .unwrap()
            .starts_with("f_hz,asd_m_per_rthz,asd_")
    );
}

#[test]
fn every_bundled_case_file_runs() {
    // the case files under models/ are examples users copy: each must parse, build and run
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../models");
    let mut stack = vec![std::path::PathBuf::from(root)];
    let mut count = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "toml")
                && path.to_string_lossy().contains("/cases/")
            {
                let (ok, _, stderr) = pendkit(&["modes", path.to_str().unwrap()]);
                assert!(ok, "{}: {stderr}", path.display());
                count += 1;
            }
        }
    }
    assert!(count >= 5, "found {count} case files");
}

#[test]
fn bench_json_has_the_contract_shape() {
    // `pendkit bench` reports times, which are not asserted; its shape is (issue 9):
    // {"model", "stage", "phases": [{"name", "median_s", "min_s", "calls"}], "total_median_s"}
    let (ok, stdout, stderr) = pendkit(&[
        "bench", "pendulum", "--repeat", "3", "--json", "--noise", "x1", "--points", "4",
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(keys.len(), 4, "{keys:?}");
    assert_eq!(v["model"], "pendulum");
    assert_eq!(v["stage"], "2", "stage 2 is the default");
    let phases = v["phases"].as_array().unwrap();
    let names: Vec<&str> = phases.iter().map(|p| p["name"].as_str().unwrap()).collect();
    for expected in ["build", "equilibrium", "mass", "modes", "noise"] {
        assert!(
            names.contains(&expected),
            "{expected} missing from {names:?}"
        );
    }
    // one phase per element kind whose Hessians were evaluated (the pendulum's fibres
    // bend: their beam is shared by the bending and extra-stretch kinds)
    assert!(names.contains(&"hessian:wire-torsion"), "{names:?}");
    assert!(
        names.contains(&"hessian:wire-bending+wire-extra-stretch"),
        "{names:?}"
    );
    let mut least_total = 0.0;
    for p in phases {
        assert_eq!(p.as_object().unwrap().len(), 4, "{p}");
        let (median, min) = (
            p["median_s"].as_f64().unwrap(),
            p["min_s"].as_f64().unwrap(),
        );
        assert!(min >= 0.0 && min <= median, "{p}");
        assert!(p["calls"].as_u64().unwrap() >= 1, "{p}");
        if p["name"] != "noise" {
            least_total += min;
        }
    }
    let noise = phases.iter().find(|p| p["name"] == "noise").unwrap();
    assert_eq!(noise["calls"], 4, "one call per frequency");
    // every repetition's total is at least the sum of the phases' minima (noise excluded)
    assert!(v["total_median_s"].as_f64().unwrap() >= least_total);
    // and bad input is an error like everywhere else
    let (ok, _, stderr) = pendkit(&["bench", "pendulum", "--stage", "0a", "--noise", "x1"]);
    assert!(!ok && stderr.contains("stage 0b or later"), "{stderr}");
    let (ok, _, stderr) = pendkit(&["bench", "pendulum", "--repeat", "0"]);
    assert!(!ok && stderr.contains("--repeat"), "{stderr}");
}

/// Rows of a CSV output as numbers (header skipped).
fn csv_rows(stdout: &str) -> Vec<Vec<f64>> {
    stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

#[test]
fn full_solves_print_what_the_restricted_ones_print() {
    // --full solves every unknown instead of the coupled blocks: the same numbers up to
    // rounding (checked at 1e-12 relative against the dense reference in
    // tests/sensitivities/fast_responses.rs; here the command line wiring, at 1e-10 on printed digits)
    for args in [
        &[
            "tf", "quad", "--input", "x00", "--output", "x3", "--points", "7", "--csv",
        ][..],
        &["noise", "quad", "--output", "x3", "--points", "7", "--csv"][..],
    ] {
        let (ok, restricted, stderr) = pendkit(args);
        assert!(ok, "{stderr}");
        let (ok, full, stderr) = pendkit(&[args, &["--full"]].concat());
        assert!(ok, "{stderr}");
        for (a, b) in csv_rows(&restricted).iter().zip(&csv_rows(&full)) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= 1e-10 * y.abs(), "{args:?}: {x} vs {y}");
            }
        }
    }
}

#[test]
fn noise_names_the_dominant_tag_or_with_breakdown_the_dominant_term() {
    let table = |extra: &[&str]| {
        let (ok, out, stderr) = pendkit(
            &[
                &["noise", "quad", "--output", "x3", "--points", "2"][..],
                extra,
            ]
            .concat(),
        );
        assert!(ok, "{stderr}");
        out.lines().nth(2).unwrap().to_string()
    };
    // at 0.1 Hz the top-stage wire bending dominates: the tag, then one of its terms
    assert!(
        table(&[]).ends_with('%') && table(&[]).contains("wn_bending"),
        "{}",
        table(&[])
    );
    let by_term = table(&["--breakdown"]);
    assert!(by_term.contains("wire-bending wn"), "{by_term}");
    // the double pendulum's lossy terms leave x1 still (hinged wires: bending stores
    // nothing; horizontal motion stretches no wire to first order): a zero PSD, no share
    // dominates, and stderr says why the column is zero
    let (ok, out, stderr) =
        pendkit(&["noise", "double-pendulum", "--output", "x1", "--freqs", "1"]);
    assert!(ok, "{stderr}");
    let row = out.lines().nth(2).unwrap();
    assert!(row.ends_with("0.000000e0  -"), "{row}");
    assert!(
        stderr.contains("exactly 0 at every frequency: no lossy term moves it"),
        "{stderr}"
    );
    // a model with no loss at all has no thermal noise: an error naming the lossless tags
    let (ok, _, stderr) = pendkit(&[
        "noise",
        "pendulum",
        "--output",
        "x1",
        "--freqs",
        "1",
        "--set",
        "phi_fibre=0",
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("no loss on the tags fibre_bending, fibre_stretch, fibre_torsion"),
        "{stderr}"
    );
}

#[test]
fn modes_below_a_frequency_are_the_lowest_modes() {
    // small model: the dense solver, filtered; large model (30 beads per fibre, 384
    // variables): shift-invert; both must be the lowest modes of the full list
    for (sets, below) in [(&[][..], "2"), (&["--set", "n_beads=30"][..], "5")] {
        let all = modes_json(&[&["modes", "quad", "--stage", "2", "--json"][..], sets].concat());
        let some = modes_json(
            &[
                &["modes", "quad", "--stage", "2", "--json", "--below", below][..],
                sets,
            ]
            .concat(),
        );
        let (all, some) = (frequencies(&all), frequencies(&some));
        let limit: f64 = below.parse().unwrap();
        let expected: Vec<f64> = all.into_iter().filter(|&f| f < limit).collect();
        assert!(!expected.is_empty());
        assert_eq!(some.len(), expected.len(), "{sets:?}");
        for (a, b) in some.iter().zip(&expected) {
            assert!((a - b).abs() <= 1e-9 * b, "{sets:?}: {a} vs {b}");
        }
    }
    let (ok, _, stderr) = pendkit(&["modes", "quad", "--below=0"]);
    assert!(!ok && stderr.contains("must be positive"), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1);
}

/// `modes --violin N` prints the rigid-body table as before and then the violin table (the
/// library's roots, tested against closed forms and beads in tests/physics/violin_modes.rs),
/// `--json` carries them, and N out of range, static fibres, a model with beads or without
/// wires are each refused with one line.
#[test]
fn modes_violin_lists_the_violin_modes_after_the_rigid_body_ones() {
    let (ok, plain, err) = pendkit(&["modes", "quad"]);
    assert!(ok, "{err}");
    let (ok, out, err) = pendkit(&["modes", "quad", "--violin", "2"]);
    assert!(ok, "{err}");
    assert!(
        out.starts_with(&plain),
        "the rigid-body table changed:\n{out}"
    );
    let violin: Vec<&str> = out[plain.len()..].lines().collect();
    assert!(violin[0].contains("violin modes of fibres"), "{out}");
    // two harmonics of 4 fibres × 2 planes, after the heading and column lines
    assert_eq!(violin.len(), 2 + 16, "{out}");
    assert_eq!(
        violin.iter().filter(|l| l.contains("bodies still")).count(),
        10,
        "{out}"
    );
    let (ok, json, err) = pendkit(&["modes", "quad", "--violin", "1", "--json"]);
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
    let roots = doc["violin"].as_array().unwrap();
    assert_eq!(roots.len(), 8);
    let first = &roots[0];
    let hz = first["frequency_hz"].as_f64().unwrap();
    assert!((hz - 495.4957).abs() < 1e-3, "{first}");
    assert!(first["q"].as_f64().unwrap() > 1e8, "{first}");
    assert_eq!(first["harmonic"], 1);
    // without --violin the document has no such key
    let (_, json, _) = pendkit(&["modes", "quad", "--json"]);
    assert!(!json.contains("\"violin\""));
    for (args, expected) in [
        (&["modes", "quad", "--violin", "0"][..], "must be 1 to 50"),
        (&["modes", "quad", "--violin", "51"][..], "must be 1 to 50"),
        (
            &["modes", "quad", "--violin", "1", "--fibres", "static"][..],
            "needs continuum fibres",
        ),
        (
            &["modes", "quad", "--violin", "1", "--set", "n_beads=2"][..],
            "continuum fibres replace violin beads",
        ),
        (&["modes", "toy", "--violin", "1"][..], "no wires"),
    ] {
        let (ok, _, err) = pendkit(args);
        assert!(!ok && err.contains(expected), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}

/// `--fibres continuum` reaches `noise` (its answer at 100 Hz is the library's continuum
/// one, tested against beads in tests/physics/continuum_fibre.rs, and differs from the
/// static model's by the fibres' mass: several per cent), and `ss` keeps the static model
/// and says so.
#[test]
fn fibres_continuum_changes_the_noise_and_ss_says_it_keeps_beads() {
    let noise = |extra: &[&str]| {
        let mut args = vec!["noise", "quad", "--output", "x3", "--freqs", "100", "--csv"];
        args.extend_from_slice(extra);
        let (ok, out, err) = pendkit(&args);
        assert!(ok, "{err}");
        let value: f64 = out
            .lines()
            .nth(1)
            .unwrap()
            .split(',')
            .nth(1)
            .unwrap()
            .parse()
            .unwrap();
        value
    };
    let (plain, continuum) = (noise(&[]), noise(&["--fibres", "continuum"]));
    assert!(
        continuum < 0.99 * plain && continuum > 0.9 * plain,
        "{plain} {continuum}"
    );
    let dir = std::env::temp_dir().join(format!("pendkit-fibres-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("ss.mat");
    let (ok, _, err) = pendkit(&[
        "ss",
        "quad",
        "--fibres",
        "continuum",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok && err.contains("keeps the static wires"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    let (ok, _, err) = pendkit(&["noise", "quad", "--fibres", "beads", "--output", "x3"]);
    assert!(!ok && err.contains("continuum"), "{err}");
}

#[test]
fn each_subcommand_help_opens_with_its_description() {
    // Subcommands are built lazily (clap's `defer`), and a deferred subcommand takes the
    // description of its arguments struct over its own: each `--help` must open with the
    // line `pendkit --help` lists for it (the variant's doc comment), not with an
    // arguments struct's or a flattened struct's doc comment.
    let (ok, top, stderr) = pendkit(&["--help"]);
    assert!(ok, "{stderr}");
    let listed: Vec<(String, String)> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| {
            let (name, about) = l.trim().split_once(' ')?;
            Some((name.to_string(), about.trim().to_string()))
        })
        .filter(|(name, _)| name != "help")
        .collect();
    assert_eq!(listed.len(), 15, "{top}");
    for (name, about) in &listed {
        for flag in ["--help", "-h"] {
            let (ok, help, stderr) = pendkit(&[name, flag]);
            assert!(ok, "{name} {flag}: {stderr}");
            let first = help.lines().next().unwrap_or_default();
            assert_eq!(first, about, "pendkit {name} {flag} opens with {first:?}");
        }
    }
}
