//! Where the time of a whole calculation goes, phase by phase (`pendkit bench`).

use pendkit_assembly::PhaseTimes;
use pendkit_system::Stage;

use crate::stage::{RunOptions, run_stage_with};
use crate::{Case, Error, log_grid};

/// Most repetitions `pendkit bench` makes.
pub const MAX_REPEAT: usize = 100_000;

/// One phase of a benchmark: its median and minimum time per repetition and how many
/// items it processes in one repetition (terms for `hessian:<kind>`, frequencies for
/// `noise`, 1 otherwise).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchPhase {
    /// Phase name.
    pub name: String,
    /// Median over repetitions (s).
    pub median_s: f64,
    /// Minimum over repetitions (s).
    pub min_s: f64,
    /// Items per repetition.
    pub calls: usize,
}

/// Where the time of a whole calculation goes, phase by phase (`pendkit bench`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchReport {
    /// Model name.
    pub model: String,
    /// Stage name (`0A` ... `2`).
    pub stage: String,
    /// Phases in the order they run.
    pub phases: Vec<BenchPhase>,
    /// Median over repetitions of the time from the build to the modes (s), noise excluded.
    pub total_median_s: f64,
}

/// Times every phase of building `spec` (a model or case file, with `sets` overrides) and
/// running `stage`, `repeat` times in this process: `build` (parameters and the numeric
/// model), the assembly's phases (`equilibrium`, `hessian:<kind>`, `mass`), `stage-model`,
/// `floats`, `modes`, and with `noise = Some((output, points))` the thermal noise of
/// `output` at `points` log-spaced frequencies from 0.1 to 100 Hz (`noise`).
pub fn bench(
    spec: &str,
    sets: &[String],
    stage: Stage,
    repeat: usize,
    noise: Option<(&str, usize)>,
) -> Result<BenchReport, Error> {
    if repeat == 0 || repeat > MAX_REPEAT {
        return Err(Error::ZeroRepeat);
    }
    if noise.is_some() && stage == Stage::S0A {
        return Err(Error::StageTooEarly);
    }
    let grid = match noise {
        Some((_, points)) => log_grid(0.1, 100.0, points)?,
        None => Vec::new(),
    };
    let mut runs: Vec<PhaseTimes> = Vec::with_capacity(repeat);
    let mut model = String::new();
    for _ in 0..repeat {
        let mut times = PhaseTimes::new();
        let (case, system) = times.time("build", 1, || -> Result<_, Error> {
            let case = Case::open(spec)?.with_sets(sets)?;
            let (system, _) = case.build()?;
            Ok((case, system))
        })?;
        model = case.model.name().to_string();
        let result = run_stage_with(system, stage, &RunOptions::default(), Some(&mut times))?;
        if let Some((output, points)) = noise {
            times.time("noise", points, || result.noise(output, &grid))?;
        }
        runs.push(times);
    }
    let median = |mut v: Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        let m = v.len() / 2;
        if v.len() % 2 == 1 {
            v[m]
        } else {
            0.5 * (v[m - 1] + v[m])
        }
    };
    let mut phases: Vec<BenchPhase> = Vec::new();
    for name in runs.iter().flat_map(|r| r.phases().iter().map(|p| &p.name)) {
        if phases.iter().any(|p| &p.name == name) {
            continue;
        }
        // a phase absent from a repetition took no time there
        let samples: Vec<(f64, usize)> = runs
            .iter()
            .map(|r| {
                r.phases()
                    .iter()
                    .find(|p| &p.name == name)
                    .map_or((0.0, 0), |p| (p.seconds, p.calls))
            })
            .collect();
        phases.push(BenchPhase {
            name: name.clone(),
            median_s: median(samples.iter().map(|s| s.0).collect()),
            min_s: samples.iter().map(|s| s.0).fold(f64::INFINITY, f64::min),
            calls: samples.iter().map(|s| s.1).max().unwrap_or(0),
        });
    }
    let totals = runs
        .iter()
        .map(|r| {
            r.phases()
                .iter()
                .filter(|p| p.name != "noise")
                .map(|p| p.seconds)
                .sum()
        })
        .collect();
    Ok(BenchReport {
        model,
        stage: stage.name().to_string(),
        phases,
        total_median_s: median(totals),
    })
}
