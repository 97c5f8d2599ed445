//! Accuracy against cost: how much model a result needs.
//!
//! Run with `cargo run --release -p pendkit-tests --example accuracy_vs_cost`. Prints three
//! tables (times are the median of several runs on this machine):
//! 1. stages of the `pendulum`: the x-mode frequency against the exact flexure result
//!    (docs/reference-values.md §1), and the time of build + equilibrium + modes;
//! 2. violin beads on the quad's fibres: the first violin mode against the clamped stiff
//!    string (continuum with bending, §5), and the time;
//! 3. quad variants: the largest deviation of the 24 suspension modes from the xtra-lite
//!    quad, and the time.

use std::time::Instant;

use pendkit::system::Stage;
use pendkit::{Case, StageResult, run_stage};
use pendkit_tests::stiff_string_f1;

/// Median wall time (s) of `runs` calls, and the last result.
fn timed(runs: usize, f: impl Fn() -> StageResult) -> (f64, StageResult) {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        last = Some(f());
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (times[runs / 2], last.expect("at least one run"))
}

fn run(model: &str, sets: &[String], stage: Stage) -> StageResult {
    let case = Case::model(model)
        .and_then(|c| c.with_sets(sets))
        .expect("bundled model");
    run_stage(case.build().expect("builds").0, stage).expect("runs")
}

fn main() {
    println!("1. pendulum x mode by stage (exact with flexure: T/(l - λ tanh(l/λ)))");
    let (t, l, ei, m) = (
        98.1f64,
        0.6,
        72e9 * std::f64::consts::PI * 0.2e-3f64.powi(4) / 4.0,
        40.0,
    );
    let lambda = (ei / t).sqrt();
    let exact =
        (4.0 * t / (l - lambda * (l / lambda).tanh()) / m).sqrt() / (2.0 * std::f64::consts::PI);
    println!(
        "{:>6} {:>14} {:>12} {:>10}",
        "stage", "f_x (Hz)", "rel. error", "time (ms)"
    );
    for stage in Stage::ALL {
        let (time, r) = timed(21, || run("pendulum", &[], stage));
        let f = r.modes.modes[0].hz;
        println!(
            "{:>6} {f:>14.9} {:>12.3e} {:>10.3}",
            stage.name(),
            (f / exact - 1.0).abs(),
            time * 1e3
        );
    }

    println!(
        "\n2. quad first violin mode vs beads per fibre, stage 2 (continuum: clamped stiff string)"
    );
    let (r3, y3) = (0.2e-3f64, 70e9);
    let area = std::f64::consts::PI * r3 * r3;
    let exact = stiff_string_f1(
        39.6 * 9.81 / 4.0,
        y3 * area * r3 * r3 / 4.0,
        2200.0 * area,
        0.6,
    );
    println!(
        "{:>6} {:>10} {:>14} {:>12} {:>10}",
        "beads", "DOF", "f1 (Hz)", "rel. error", "time (ms)"
    );
    for beads in [1, 2, 5, 10, 20, 40, 80] {
        let sets = vec![format!("n_beads={beads}")];
        let (time, r) = timed(5, || run("quad", &sets, Stage::S2));
        let f1 = r
            .modes
            .modes
            .iter()
            .find(|m| m.hz > 100.0)
            .map_or(f64::NAN, |m| m.hz);
        println!(
            "{beads:>6} {:>10} {f1:>14.6} {:>12.3e} {:>10.2}",
            r.modes.modes.len(),
            (f1 / exact - 1.0).abs(),
            time * 1e3
        );
    }

    println!(
        "\n3. quad variants at stage 0A: largest deviation of the 24 suspension modes from xtra-lite"
    );
    let (_, quad) = timed(1, || run("quad", &[], Stage::S0A));
    let reference: Vec<f64> = quad.modes.modes.iter().map(|m| m.hz).collect();
    println!(
        "{:>14} {:>6} {:>12} {:>10}",
        "variant", "DOF", "max dev.", "time (ms)"
    );
    for variant in ["quad", "quad-lateral", "quad-lite", "quad-full", "quad-v5"] {
        let (time, r) = timed(11, || run(variant, &[], Stage::S0A));
        let dev = r
            .modes
            .modes
            .iter()
            .take(24)
            .zip(&reference)
            .map(|(m, f)| (m.hz / f - 1.0).abs())
            .fold(0.0, f64::max);
        println!(
            "{variant:>14} {:>6} {dev:>12.3e} {:>10.2}",
            r.modes.modes.len(),
            time * 1e3
        );
    }
}
