//! Frequency sweeps on precomputed stage-2 results: the support-to-mass transfer function
//! (`StageModel::transfer`, input `x00`) and the thermal noise with its per-term breakdown
//! (`pendkit_noise::thermal_noise`) over log grids from 0.1 to 100 Hz, plus the state-space
//! matrices of the quad. Building the model and `run_stage` happen outside the timed loop.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit::{Case, StageResult, log_grid, run_stage};
use pendkit_dynamics::{Input, Output};
use pendkit_energy::Stage;

/// Support input of every transfer function: longitudinal displacement of the suspension
/// point.
const INPUT: &str = "x00";

/// Stage-2 result of bundled model `name`.
fn stage2(name: &str) -> StageResult {
    Case::model(name)
        .and_then(|case| case.build())
        .and_then(|(system, _)| run_stage(system, Stage::S2))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The 0.1–100 Hz log grid with `n` points.
fn grid(n: usize) -> Vec<f64> {
    log_grid(0.1, 100.0, n).expect("valid grid")
}

/// Input `x00` and output `output` of `r`, parsed as the command line does.
fn input_output(name: &str, r: &StageResult, output: &str) -> (Input, Output) {
    let input = r.input(INPUT).unwrap_or_else(|e| panic!("{name}: {e}"));
    let output = r.output(output).unwrap_or_else(|e| panic!("{name}: {e}"));
    (input, output)
}

/// `tf/<name>/<n>`: transfer function x00 → `output` at `n` frequencies.
fn bench_tf(c: &mut Criterion, name: &str, r: &StageResult, output: &str, n: usize) {
    let (input, output) = input_output(name, r, output);
    let freqs = grid(n);
    c.bench_function(&format!("tf/{name}/{n}"), |b| {
        b.iter(|| {
            r.model.transfer(
                &r.system.damping,
                black_box(&input),
                black_box(&output),
                black_box(&freqs),
            )
        })
    });
}

/// `noise/<name>/<n>`: thermal noise of displacement `output`, total and per term, at `n`
/// frequencies and the model's temperature.
fn bench_noise(c: &mut Criterion, name: &str, r: &StageResult, output: &str, n: usize) {
    let Output::Displacement(v) = input_output(name, r, output).1 else {
        panic!("{name}: {output} is not a displacement output");
    };
    let freqs = grid(n);
    c.bench_function(&format!("noise/{name}/{n}"), |b| {
        b.iter(|| {
            pendkit_noise::thermal_noise(
                &r.model,
                &r.system.damping,
                black_box(&v),
                r.system.temperature,
                black_box(&freqs),
            )
        })
    });
}

/// Small models: both sweeps at 1000 and 10 000 points, output the first (or lowest) mass.
fn small(c: &mut Criterion) {
    for (name, output) in [
        ("pendulum", "x1"),
        ("double-pendulum", "x2"),
        ("rigid-body", "x1"),
    ] {
        let r = stage2(name);
        for n in [1000, 10_000] {
            bench_tf(c, name, &r, output, n);
            bench_noise(c, name, &r, output, n);
        }
    }
}

/// Multi-stage families (every model named `quad*` or `triple*` in `pendkit::models()`),
/// output `x3`: the noise of every variant at 1000 points; for the family's base model
/// (named exactly `quad`, `triple`) also the transfer function and the noise at 10 000
/// points, and for the quad the state-space matrices at 1 Hz.
fn chains(c: &mut Criterion) {
    const OUTPUT: &str = "x3";
    for family in ["quad", "triple"] {
        for model in pendkit::models()
            .into_iter()
            .filter(|m| m.name().starts_with(family))
        {
            let name = model.name();
            let r = stage2(name);
            bench_noise(c, name, &r, OUTPUT, 1000);
            if name == family {
                bench_tf(c, name, &r, OUTPUT, 10_000);
                bench_noise(c, name, &r, OUTPUT, 10_000);
            }
            if name == "quad" {
                c.bench_function("ss/quad", |b| {
                    b.iter(|| {
                        r.model
                            .state_space(&r.system.damping, black_box(1.0))
                            .unwrap()
                    })
                });
            }
        }
    }
}

criterion_group! {
    name = small_models;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = small
}
// 10 samples: an iteration takes 50 ms to 0.6 s, so criterion runs one per sample.
criterion_group! {
    name = chain_models;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = chains
}
criterion_main!(small_models, chain_models);
