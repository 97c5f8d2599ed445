//! Frequency sweeps on precomputed stage-2 results: the support-to-mass transfer function
//! (`StageModel::transfer`, input `x00`) and the thermal noise with its per-tag breakdown
//! (`pendkit_noise::thermal_noise_with`, default options: only the blocks the output
//! couples to) over log grids from 0.1 to 100 Hz, the state-space matrices of the quad, and
//! the normal modes of a large (bead) model, dense and below a frequency. Building the
//! model and `run_stage` happen outside the timed loop, except in `pipeline-noise`, which
//! times the whole way from a model name to a noise curve.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit::{Case, StageResult, log_grid, run_stage};
use pendkit_dynamics::{Input, Output, eliminate_floats, normal_modes};
use pendkit_noise::NoiseOptions;
use pendkit_system::Stage;

/// Support input of every transfer function: longitudinal displacement of the suspension
/// point.
const INPUT: &str = "x00";

/// Stage-2 result of bundled model `name` with overrides `sets`.
fn stage2(name: &str, sets: &[&str]) -> StageResult {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Case::model(name)
        .and_then(|case| case.with_sets(&sets))
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

/// `<prefix>/<name>/<n>`: thermal noise of displacement `output` at `n` frequencies and the
/// model's temperature, total and per tag (and per term with `options.per_term`).
fn bench_noise_with(
    c: &mut Criterion,
    prefix: &str,
    name: &str,
    r: &StageResult,
    output: &str,
    n: usize,
    options: NoiseOptions,
) {
    let Output::Displacement(v) = input_output(name, r, output).1 else {
        panic!("{name}: {output} is not a displacement output");
    };
    let freqs = grid(n);
    c.bench_function(&format!("{prefix}/{name}/{n}"), |b| {
        b.iter(|| {
            pendkit_noise::thermal_noise_with(
                &r.model,
                &r.system.damping,
                black_box(&v),
                r.system.temperature,
                black_box(&freqs),
                &options,
            )
            .expect("noise")
        })
    });
}

/// `noise/<name>/<n>`: the default noise (total and per tag, restricted solve).
fn bench_noise(c: &mut Criterion, name: &str, r: &StageResult, output: &str, n: usize) {
    bench_noise_with(c, "noise", name, r, output, n, NoiseOptions::default());
}

/// Small models: both sweeps at 1000 and 10 000 points, output the first (or lowest) mass.
fn small(c: &mut Criterion) {
    for (name, output) in [
        ("pendulum", "x1"),
        ("double-pendulum", "x2"),
        ("rigid-body", "x1"),
    ] {
        let r = stage2(name, &[]);
        for n in [1000, 10_000] {
            bench_tf(c, name, &r, output, n);
            bench_noise(c, name, &r, output, n);
        }
    }
}

/// Multi-stage families (every model named `quad*` or `triple*` in `pendkit::catalogue::models()`),
/// output `x3`: the noise of every variant at 1000 points; for the family's base model
/// (named exactly `quad`, `triple`) also the transfer function and the noise at 10 000
/// points (and for the quad at 1000 points, with the per-term breakdown, and over every
/// unknown), and for the quad the state-space matrices at 1 Hz.
fn chains(c: &mut Criterion) {
    const OUTPUT: &str = "x3";
    for family in ["quad", "triple"] {
        for model in pendkit::catalogue::models()
            .into_iter()
            .filter(|m| m.name().starts_with(family))
        {
            let name = model.name();
            let r = stage2(name, &[]);
            bench_noise(c, name, &r, OUTPUT, 1000);
            if name == family {
                bench_tf(c, name, &r, OUTPUT, 10_000);
                bench_noise(c, name, &r, OUTPUT, 10_000);
            }
            if name == "quad" {
                bench_tf(c, name, &r, OUTPUT, 1000);
                let per_term = NoiseOptions {
                    per_term: true,
                    ..Default::default()
                };
                bench_noise_with(c, "noise-per-term", name, &r, OUTPUT, 1000, per_term);
                let full = NoiseOptions {
                    solver: pendkit_dynamics::Solver::Full,
                    ..Default::default()
                };
                bench_noise_with(c, "noise-full", name, &r, OUTPUT, 1000, full);
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

/// Violin beads on the quad's fibres (`n_beads` per fibre; each bead three translations and,
/// with the default clamped joints, three joint angles): the noise at x3, which couples to
/// every bead through the test mass, solved by the scheduled sparse L D Lᵀ. 1000 points for
/// 5 and 20 beads, 200 for 50 (n = 1230; the per-point cost is the same).
fn beads(c: &mut Criterion) {
    for (beads, points) in [(5, 1000), (20, 1000), (50, 200)] {
        let name = format!("quad-beads{beads}");
        let r = stage2("quad", &[&format!("n_beads={beads}")]);
        bench_noise(c, &name, &r, "x3", points);
        bench_tf(c, &name, &r, "x3", points);
    }
}

/// The 100-stage `chain` (600 variables): noise and transfer function x00 → x100 at the
/// lowest body over 1000 points. Its x–pitch block (200 unknowns) is solved by the sparse
/// LU; the other blocks are decoupled from x100.
fn long_chain(c: &mut Criterion) {
    let name = "chain-100";
    let r = stage2("chain", &["n_stages=100"]);
    bench_noise(c, name, &r, "x100", 1000);
    bench_tf(c, name, &r, "x100", 1000);
}

/// `pipeline-noise/quad/1000`: the whole way from the model's name to its test-mass noise
/// curve, as a user calls it: build (defaults parsed once, during warm-up), equilibrium,
/// stage-2 assembly, modes, and the noise at x3 over 1000 points (the pipeline that
/// benches/vs_pygwinc.py compares with pygwinc's quad suspension thermal noise).
fn pipeline(c: &mut Criterion) {
    let freqs = grid(1000);
    c.bench_function("pipeline-noise/quad/1000", |b| {
        b.iter(|| {
            let r = stage2(black_box("quad"), &[]);
            r.noise("x3", black_box(&freqs)).expect("noise")
        })
    });
}

/// Normal modes of the quad with 48 beads per fibre (600 variables in one block): every
/// mode by the dense solver (`modes/quad-beads48`), the bare symmetric eigensolver on a
/// matrix of that size for comparison (`modes/bare-eigen/600`), and the modes below
/// 100 Hz by shift-invert (`modes-below/quad-beads48/100hz`).
fn modes(c: &mut Criterion) {
    let r = stage2("quad", &["n_beads=48"]);
    let k = eliminate_floats(
        &r.model.real_stiffness(&r.system.damping),
        &r.assembled.layout,
        &r.system,
    )
    .expect("floats eliminate")
    .k_eff;
    c.bench_function("modes/quad-beads48", |b| {
        b.iter(|| {
            normal_modes(
                black_box(&k),
                &r.assembled.mass.to_dense(),
                &r.model.variables,
            )
            .unwrap()
        })
    });
    let n = k.nrows();
    let kf = faer::Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)]);
    c.bench_function(&format!("modes/bare-eigen/{n}"), |b| {
        b.iter(|| {
            black_box(&kf)
                .self_adjoint_eigen(faer::Side::Lower)
                .unwrap()
        })
    });
    c.bench_function("modes-below/quad-beads48/100hz", |b| {
        b.iter(|| {
            r.model
                .modes_below(&r.system.damping, black_box(100.0))
                .unwrap()
        })
    });
}

criterion_group! {
    name = small_models;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = small
}
// 10 samples: the slowest iterations take tens to hundreds of ms.
criterion_group! {
    name = chain_models;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = chains, beads, long_chain, pipeline, modes
}
criterion_main!(small_models, chain_models);
