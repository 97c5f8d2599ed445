//! `run_stage` (equilibrium, assembly of the stage's terms, elimination of floats and normal
//! modes) at every stage, for every bundled model. The numeric model is built once; each
//! iteration runs on a fresh clone of it, made outside the timed section.

use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use pendkit::{Case, run_stage};
use pendkit_energy::Stage;

fn stages(c: &mut Criterion) {
    let mut group = c.benchmark_group("stage");
    for name in pendkit::models().iter().map(|m| m.name()) {
        let (system, _) = Case::model(name)
            .and_then(|case| case.build())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        for stage in Stage::ALL {
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
