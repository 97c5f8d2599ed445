//! Helpers shared by the workspace tests: running a bundled model, finding a mode,
//! and tolerance assertions that say what they compared.

use pendkit::{Case, StageResult, run_stage};
use pendkit_energy::Stage;

/// Runs a bundled model (with `NAME=EXPR` overrides) at `stage`.
pub fn run(model: &str, sets: &[&str], stage: Stage) -> StageResult {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = Case::model(model)
        .and_then(|c| c.with_sets(&sets))
        .expect("case");
    let (system, _) = case.build().expect("model builds");
    run_stage(system, stage).expect("stage runs")
}

/// Frequency (Hz) of the mode labelled `label`, `nth` of them (0-based) in ascending order.
pub fn hz(result: &StageResult, label: &str, nth: usize) -> f64 {
    result
        .modes
        .modes
        .iter()
        .filter(|m| m.label == label)
        .nth(nth)
        .unwrap_or_else(|| panic!("no mode #{nth} labelled {label}"))
        .hz
}

/// Asserts |a - b| <= rel * |b|.
#[track_caller]
pub fn assert_rel(a: f64, b: f64, rel: f64) {
    assert!(
        (a - b).abs() <= rel * b.abs(),
        "{a} vs {b}: relative difference {:.3e} > {rel:.1e}",
        ((a - b) / b).abs()
    );
}

/// Asserts that `a` rounds to the printed reference `printed` given with `digits`
/// significant digits (i.e. is within half a unit of its last digit).
#[track_caller]
pub fn assert_printed(a: f64, printed: f64, digits: i32) {
    let unit = 10f64.powi(printed.abs().log10().floor() as i32 - (digits - 1));
    assert!(
        (a - printed).abs() <= 0.5 * unit,
        "{a} does not round to the reference {printed} ({digits} significant digits)"
    );
}

pub const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
