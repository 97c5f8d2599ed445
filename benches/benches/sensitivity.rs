//! The issue-15 target in one run: the mode sensitivities of the quad at stage 2 (all 24
//! modes × all its parameters, `pendkit::sensitivity::sensitivities`) against one stage run of the same
//! model (build to modes: `Case::build` and `run_stage`), so that the ratio is read off
//! numbers measured side by side. The sensitivities are timed on one thread and on the
//! machine's threads, by the exact route and by the difference route. Beside them, the
//! response sensitivities (the difference route of the stage's matrices): |H| from the
//! support to the test mass and its thermal noise at 100 frequencies, on the quad and on
//! quad-aligo (whose damping tags have their own temperatures).

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit::sensitivity::SensitivityRequest;
use pendkit::sensitivity::sensitivities;
use pendkit::{Case, run_stage};
use pendkit_system::Stage;

fn sensitivity(c: &mut Criterion) {
    let mut group = c.benchmark_group("sensitivity");
    for name in ["quad", "triple"] {
        let case = Case::model(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let stage = Stage::S2;
        group.bench_function(format!("{name}/stage-run"), |b| {
            b.iter(|| {
                let (system, _) = case.build().unwrap();
                run_stage(system, stage).unwrap()
            })
        });
        for (label, threads, differences) in [
            ("exact/1-thread", 1, false),
            ("exact/all-threads", 0, false),
            ("differences/1-thread", 1, true),
            ("differences/all-threads", 0, true),
        ] {
            let request = SensitivityRequest {
                threads,
                differences,
                ..SensitivityRequest::modes(stage)
            };
            // fail here, with the model, rather than inside the timed loop
            sensitivities(&case, &request).unwrap_or_else(|e| panic!("{name}: {e}"));
            group.bench_function(format!("{name}/{label}"), |b| {
                b.iter(|| sensitivities(&case, &request).unwrap())
            });
        }
    }
    // |H| and noise ASD sensitivities, every parameter, 100 log-spaced frequencies
    let freqs: Vec<f64> = (0..100)
        .map(|k| 0.1 * 1000f64.powf(k as f64 / 99.0))
        .collect();
    for name in ["quad", "quad-aligo"] {
        let case = Case::model(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let request = SensitivityRequest {
            modes: false,
            tf: Some(("x00".into(), "x3".into())),
            noise: Some("x3".into()),
            freqs: freqs.clone(),
            ..SensitivityRequest::modes(Stage::S2)
        };
        sensitivities(&case, &request).unwrap_or_else(|e| panic!("{name}: {e}"));
        group.bench_function(format!("{name}/responses-100-freqs/all-threads"), |b| {
            b.iter(|| sensitivities(&case, &request).unwrap())
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = sensitivity
}
criterion_main!(benches);
