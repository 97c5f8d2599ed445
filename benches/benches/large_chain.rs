//! How the sparse paths scale: a chain of light bodies (`pendkit chain-file N` with 10 g
//! bodies, so that its top wires stay elastic at 10 000 stages) from 100 to 10 000 stages,
//! 600 to 60 000 variables: the stage run at stage 2 with the lowest 20 modes
//! (`large-chain/modes20/<n>`: equilibrium, assembly, stage model, the modes below a
//! frequency that holds 20 of them at every size by shift-invert, stability;
//! docs/performance.md, "Large models"). The model is built once, outside the timed part.
//! Sizes past the coordinate, wire and body limits are skipped with a note: run with
//! `PENDKIT_MAX_COORDINATES=60006 PENDKIT_MAX_WIRES=40000 PENDKIT_MAX_BODIES=10001` for all
//! of them. Ten samples each (criterion's least): the largest take seconds per run.

use std::path::Path;
use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use pendkit::Case;
use pendkit::stage::{ModeSelection, RunOptions, run_stage_with};
use pendkit_system::Stage;

/// The chain sizes (stages).
const STAGES: [usize; 4] = [100, 1000, 3000, 10_000];

/// The light bodies: 10 g, the chain's moments of inertia scaled with the mass.
const LIGHT: [&str; 4] = ["m=0.01", "Ix=1.425e-4", "Iy=1.05e-4", "Iz=1.05e-4"];

/// A frequency (Hz) with 20 modes of the light chain of `n` stages below it: the lowest
/// pendulum modes fall as 1/√(length), and 0.08 Hz holds 20 at 10 000 stages (measured
/// with `pendkit modes`).
fn below_20(n: usize) -> f64 {
    0.08 * (10_000.0 / n as f64).sqrt()
}

fn light_chain(n: usize) -> Result<Case, String> {
    let text = pendkit::suspension::generate::chain(n)
        .map_err(|e| e.to_string())?
        .source
        .text
        .clone();
    let sets: Vec<String> = LIGHT.iter().map(|s| s.to_string()).collect();
    Case::from_text(Path::new(&format!("chain-{n}.toml")), &text)
        .and_then(|case| case.with_sets(&sets))
        .map_err(|e| e.to_string())
}

fn large_chain(c: &mut Criterion) {
    let mut group = c.benchmark_group("large-chain");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_secs(1));
    for n in STAGES {
        let built = light_chain(n).and_then(|case| case.build().map_err(|e| e.to_string()));
        let system = match built {
            Ok((system, _)) => system,
            Err(e) => {
                eprintln!("large-chain/{n}: skipped ({e})");
                continue;
            }
        };
        let options = RunOptions {
            modes: ModeSelection::Below(below_20(n)),
            ..Default::default()
        };
        group.bench_function(format!("modes20/{n}"), |b| {
            b.iter_batched(
                || system.clone(),
                |system| run_stage_with(system, Stage::S2, &options, None).unwrap(),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, large_chain);
criterion_main!(benches);
