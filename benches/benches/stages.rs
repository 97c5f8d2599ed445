//! `run_stage` (equilibrium, assembly of the stage's terms, elimination of floats and normal
//! modes) at every stage, for every bundled model; and at stages 0A and 2 for the `chain`
//! model at 10, 30 and 100 stages, to show how the cost scales with the size. The numeric
//! model is built once; each iteration runs on a fresh clone of it, made outside the timed
//! section.

mod scaling;

use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BatchSize, BenchmarkGroup, Criterion, criterion_group, criterion_main};
use pendkit::{Case, run_stage};
use pendkit_system::Stage;

/// `stage/<name>/<stage>` for each of `stages`.
fn bench_stages(group: &mut BenchmarkGroup<WallTime>, name: &str, case: &Case, stages: &[Stage]) {
    let (system, _) = case.build().unwrap_or_else(|e| panic!("{name}: {e}"));
    for &stage in stages {
        // fail here, with the model and stage, rather than inside the timed loop
        run_stage(system.clone(), stage)
            .unwrap_or_else(|e| panic!("{name} stage {}: {e}", stage.name()));
        group.bench_function(format!("{name}/{}", stage.name()), |b| {
            b.iter_batched(
                || system.clone(),
                |system| run_stage(system, stage).unwrap(),
                BatchSize::SmallInput,
            )
        });
    }
}

fn stages(c: &mut Criterion) {
    let mut group = c.benchmark_group("stage");
    for name in pendkit::catalogue::models().iter().map(|m| m.name()) {
        let case = Case::model(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        bench_stages(&mut group, name, &case, &Stage::ALL);
    }
    for n in scaling::CHAIN_STAGES {
        let (name, case) = scaling::chain(n);
        bench_stages(&mut group, &name, &case, &[Stage::S0A, Stage::S2]);
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(1));
    targets = stages
}
criterion_main!(benches);
