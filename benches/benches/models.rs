//! Per bundled model: building the numeric model, finding its equilibrium, and the whole
//! stage-0A pipeline (build, equilibrium, assembly, normal modes); and the build of the
//! `chain` model at 10, 30 and 100 stages, to show how it scales.

mod scaling;

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit::{Case, run_stage};
use pendkit_assembly::solve_equilibrium;
use pendkit_system::Stage;

fn models(c: &mut Criterion) {
    for model in pendkit::catalogue::models() {
        let name = model.name();
        let case = Case::model(name).expect("bundled model");
        let (system, _) = case.build().unwrap_or_else(|e| panic!("{name}: {e}"));

        c.bench_function(&format!("build/{name}"), |b| {
            b.iter(|| black_box(&case).build().unwrap())
        });
        c.bench_function(&format!("equilibrium/{name}"), |b| {
            b.iter(|| solve_equilibrium(black_box(&system), &Default::default()).unwrap())
        });
        c.bench_function(&format!("pipeline/{name}"), |b| {
            b.iter(|| {
                let (system, _) = black_box(&case).build().unwrap();
                run_stage(system, Stage::S0A).unwrap()
            })
        });
    }
    // the rest of the pipeline at these sizes is `stage/chain-<n>/0A` in stages.rs
    for n in scaling::CHAIN_STAGES {
        let (name, case) = scaling::chain(n);
        c.bench_function(&format!("build/{name}"), |b| {
            b.iter(|| black_box(&case).build().unwrap())
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = models
}
criterion_main!(benches);
