//! `pendkit tradeoff`: the CSV and chart it writes, its errors recomputed through the
//! library by a second route, the bead ladder converging, and the cheapest variant it names
//! checked against its own CSV.

use std::path::{Path, PathBuf};

use pendkit::system::Stage;
use pendkit::{Case, NoiseOptions, Solver, StageResult, log_grid, run_stage};

use crate::common;
use common::pendkit;

/// A fresh directory for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pendkit-tradeoff-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

const HEADER: &str = "variant,seconds,modes_max_rel_err,noise_max_rel_err,tf_max_rel_err";

/// One CSV row: name, seconds, modes, noise and transfer-function errors (None if empty).
#[derive(Debug)]
struct Row {
    variant: String,
    seconds: f64,
    modes: f64,
    noise: f64,
    tf: Option<f64>,
}

impl Row {
    fn max(&self) -> f64 {
        self.modes.max(self.noise).max(self.tf.unwrap_or(0.0))
    }
}

fn read_csv(dir: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(dir.join("tradeoff.csv")).expect("tradeoff.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(HEADER));
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 5, "{line}");
            let num = |s: &str| s.parse::<f64>().unwrap_or_else(|_| panic!("{line}"));
            Row {
                variant: f[0].to_string(),
                seconds: num(f[1]),
                modes: num(f[2]),
                noise: num(f[3]),
                tf: (!f[4].is_empty()).then(|| num(f[4])),
            }
        })
        .collect()
}

fn row<'a>(rows: &'a [Row], name: &str) -> &'a Row {
    rows.iter()
        .find(|r| r.variant == name)
        .unwrap_or_else(|| panic!("no row {name} in {rows:?}"))
}

/// max |v / r − 1|, equal values counting as no error.
fn max_rel(reference: &[f64], variant: &[f64]) -> f64 {
    reference
        .iter()
        .zip(variant)
        .map(|(r, v)| if r == v { 0.0 } else { (v / r - 1.0).abs() })
        .fold(0.0, f64::max)
}

fn stage_of(model: &str, stage: Stage) -> StageResult {
    let (system, _) = Case::model(model).unwrap().build().unwrap();
    run_stage(system, stage).unwrap()
}

/// The second route of a row's noise and |TF| errors: the library's answers of the
/// reference (full solve) and of the variant (restricted) on `grid`, compared here, for the
/// noise of `output` and the transfer function `input` → `output`. Both routes run the same
/// deterministic arithmetic, and the CSV prints every digit ({:e}), so the row must carry
/// these values to rounding (1e-12 relative); each is also checked to be a real, visible
/// difference.
fn assert_row_is_the_second_route(
    row: &Row,
    reference: &StageResult,
    variant: &StageResult,
    (input, output): (&str, &str),
    grid: &[f64],
) {
    let full = NoiseOptions {
        solver: Solver::Full,
        per_term: false,
    };
    let expected_noise = max_rel(
        &reference.noise_with(output, grid, &full).unwrap().asd(),
        &variant.noise(output, grid).unwrap().asd(),
    );
    let tf = |run: &StageResult, solver| -> Vec<f64> {
        run.transfer_with(input, output, grid, solver)
            .unwrap()
            .iter()
            .map(|h| h.norm())
            .collect()
    };
    let expected_tf = max_rel(
        &tf(reference, Solver::Full),
        &tf(variant, Solver::Restricted),
    );
    assert!(expected_noise > 1e-6 && expected_tf > 1e-9);
    assert!(
        (row.noise - expected_noise).abs() <= 1e-12 * expected_noise,
        "{} vs {expected_noise}",
        row.noise
    );
    let row_tf = row.tf.unwrap();
    assert!(
        (row_tf - expected_tf).abs() <= 1e-12 * expected_tf,
        "{row_tf} vs {expected_tf}"
    );
}

#[test]
fn pendulum_ladder_matches_the_library_and_names_the_cheapest_within_tolerance() {
    let dir = scratch("pendulum");
    let tolerance = 1e-3;
    let (ok, stdout, stderr) = pendkit(&[
        "tradeoff",
        "pendulum",
        "--output",
        "x1",
        "--input",
        "x00",
        "--band",
        "1:100",
        "--tolerance",
        "1e-3",
        "--budget",
        "0.02",
        "--no-continuum",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let rows = read_csv(&dir);

    // The pendulum has no beads and no blade-tip family: the stages 0B..2 restricted, the
    // full solve at stage 2 as the reference (continuum fibres left out here; see
    // `continuum_fibres_are_the_reference_the_beads_converge_to`); 0A cannot answer a
    // noise question.
    let names: Vec<&str> = rows.iter().map(|r| r.variant.as_str()).collect();
    assert_eq!(
        names,
        [
            "pendulum s2 full-solve",
            "pendulum s0B",
            "pendulum s1A",
            "pendulum s1B",
            "pendulum s2"
        ]
    );
    assert!(stdout.contains("skipped pendulum s0A: "), "{stdout}");
    let reference = &rows[0];
    assert_eq!(
        (reference.modes, reference.noise, reference.tf),
        (0.0, 0.0, Some(0.0))
    );
    assert!(rows.iter().all(|r| r.seconds > 0.0));

    // Second route: the library's noise and transfer function of stage 1B (restricted) and
    // of the reference (stage 2, full solve); stage 1B lacks only the extra stretch.
    let grid = log_grid(1.0, 100.0, 200).unwrap();
    let reference_run = stage_of("pendulum", Stage::S2);
    let variant_run = stage_of("pendulum", Stage::S1B);
    let s1b = row(&rows, "pendulum s1B");
    assert_row_is_the_second_route(s1b, &reference_run, &variant_run, ("x00", "x1"), &grid);
    // Modes by label (the pendulum's three modes are each on one coordinate): the largest
    // relative difference of x1, y1, z1 between stage 1B and stage 2 (all below 100 Hz).
    let by_label = |run: &StageResult, label: &str| {
        run.modes
            .modes
            .iter()
            .find(|m| m.label == label)
            .unwrap()
            .hz
    };
    let expected_modes = ["x1", "y1", "z1"]
        .iter()
        .map(|l| (by_label(&variant_run, l) / by_label(&reference_run, l) - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(
        (s1b.modes - expected_modes).abs() <= 1e-12 * expected_modes,
        "{} vs {expected_modes}",
        s1b.modes
    );

    // The last line names the fastest row whose largest error is within the tolerance.
    let last = stdout.lines().last().unwrap();
    let rest = last
        .strip_prefix("cheapest within 0.001: ")
        .unwrap_or_else(|| panic!("{last}"));
    let (name, _) = rest.rsplit_once(" (").unwrap();
    let named = row(&rows, name);
    assert!(named.max() <= tolerance, "{named:?}");
    assert!(
        rows.iter()
            .all(|r| r.max() > tolerance || r.seconds >= named.seconds),
        "{rows:?}"
    );

    // The chart: well-formed XML with both axes named with their units.
    let svg = std::fs::read_to_string(dir.join("tradeoff.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).expect("tradeoff.svg is XML");
    let texts: Vec<&str> = doc
        .descendants()
        .filter_map(|n| n.text())
        .map(str::trim)
        .collect();
    assert!(texts.contains(&"time (s)"), "{texts:?}");
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("max relative error") && t.contains("dimensionless")),
        "{texts:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn quad_bead_ladder_converges_to_the_reference() {
    // The fibres as N point beads: a lumped-mass discretisation of a continuous fibre,
    // which converges as N grows. Against the reference (5 beads, full solve) the errors of
    // 1, 2 and 5 beads must fall, and 5 beads solved over the restricted blocks must equal
    // the full solve to rounding (the restriction drops exact zeros only; 1e-10 leaves room
    // for the different order of the sums). 0 beads is a different model (massless
    // fibres), not a step of the discretisation, so it is left out of the ladder here.
    let dir = scratch("quad");
    let (rows, stdout) = quad_x3_ladder("quad-full", &["--no-continuum"], &dir);
    assert_eq!(rows[0].variant, "quad-full s2 b5 full-solve", "{stdout}");
    let ladder = quad_full_beads(&rows);
    for pair in ladder.windows(2) {
        let (coarse, fine) = (pair[0], pair[1]);
        assert!(coarse.modes > fine.modes, "{coarse:?} {fine:?}");
        assert!(coarse.tf.unwrap() > fine.tf.unwrap(), "{coarse:?} {fine:?}");
    }
    assert!(ladder[2].max() <= 1e-10, "{:?}", ladder[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `tradeoff MODEL --output x3 --input x00 --band 10:100 --beads 1,2,5` (30 points, no
/// repeats) with `extra` arguments, into `dir`: its rows and what it printed.
fn quad_x3_ladder(model: &str, extra: &[&str], dir: &Path) -> (Vec<Row>, String) {
    let mut args = vec![
        "tradeoff", model, "--output", "x3", "--input", "x00", "--band", "10:100", "--points",
        "30", "--beads", "1,2,5", "--budget", "0",
    ];
    args.extend_from_slice(extra);
    let out = dir.to_str().unwrap().to_string();
    args.extend_from_slice(&["--out", &out]);
    let (ok, stdout, stderr) = pendkit(&args);
    assert!(ok, "{stderr}");
    (read_csv(dir), stdout)
}

/// `quad-full`'s rows with 1, 2 and 5 beads, whose noise errors must fall in that order:
/// the beads converge (to the continuum, tests/physics), whichever is the reference.
fn quad_full_beads(rows: &[Row]) -> Vec<&Row> {
    let ladder: Vec<&Row> = ["quad-full s2 b1", "quad-full s2 b2", "quad-full s2 b5"]
        .iter()
        .map(|n| row(rows, n))
        .collect();
    for pair in ladder.windows(2) {
        assert!(pair[0].noise > pair[1].noise, "{:?} {:?}", pair[0], pair[1]);
    }
    ladder
}

#[test]
fn continuum_fibres_are_the_reference_the_beads_converge_to() {
    // With continuum fibres in the ladder (the default) the reference of the noise and the
    // transfer function is the richest family member with continuum fibres, full solve;
    // the modes are measured against the richest finite variant (5 beads), whose name the
    // table gives. Second route, as in the pendulum's test: the library's continuum noise
    // and |TF| (quad-full, stage 2, full solve) against its 2-bead ones, compared here, must
    // equal the 2-bead row's errors to rounding; and the beads' noise errors must fall
    // from 1 to 2 to 5 beads, towards the continuum (their limit: tests/physics).
    let dir = scratch("continuum");
    let (rows, stdout) = quad_x3_ladder("quad", &[], &dir);
    assert_eq!(
        rows[0].variant, "quad-full s2 continuum full-solve",
        "{stdout}"
    );
    assert_eq!((rows[0].noise, rows[0].tf), (0.0, Some(0.0)));
    assert!(
        stdout.contains(
            "errors against quad-full s2 continuum full-solve (modes: quad-full s2 b5 full-solve)"
        ),
        "{stdout}"
    );
    for member in ["quad", "quad-lite", "quad-lateral", "quad-full"] {
        row(&rows, &format!("{member} s2 continuum"));
    }
    quad_full_beads(&rows);
    let grid = log_grid(10.0, 100.0, 30).unwrap();
    let continuum = stage_of("quad-full", Stage::S2)
        .with_fibres(&pendkit::stage::Fibres::Continuum)
        .unwrap();
    let case = Case::open("quad-full")
        .unwrap()
        .with_sets(&["n_beads=2".to_string()])
        .unwrap();
    let two = run_stage(case.build().unwrap().0, Stage::S2).unwrap();
    let b2 = row(&rows, "quad-full s2 b2");
    assert_row_is_the_second_route(b2, &continuum, &two, ("x00", "x3"), &grid);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_band_is_one_line_naming_it() {
    let dir = scratch("bad");
    let (ok, _, stderr) = pendkit(&[
        "tradeoff",
        "pendulum",
        "--output",
        "x1",
        "--band",
        "100:10",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: --band '100:10'"), "{stderr}");
}
