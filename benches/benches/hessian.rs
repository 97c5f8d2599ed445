//! Time of `Term::derivatives` (value, gradient and Hessian by hyper-dual numbers) for one
//! term of each core element kind, at the model's start position.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit_energy::{Reference, Term, find_kind};

/// The first term of kind `kind` in bundled model `model` whose label ends with `label`
/// (any label if empty), with the start coordinates it is evaluated at.
fn term(model: &str, kind: &str, label: &str) -> (Term, Vec<f64>) {
    // `pendkit` links every element crate, so the registry is complete.
    let (system, _) = pendkit::Case::model(model)
        .and_then(|case| case.build())
        .unwrap_or_else(|e| panic!("{model}: {e}"));
    let x = system.start();
    let element = find_kind(kind).unwrap_or_else(|| panic!("no element kind '{kind}'"));
    let terms = element
        .terms(&Reference {
            system: &system,
            coords: &x,
        })
        .unwrap_or_else(|e| panic!("{model} {kind}: {e}"));
    let term = terms
        .into_iter()
        .find(|t| t.label.ends_with(label))
        .unwrap_or_else(|| panic!("{model}: no {kind} term '{label}'"));
    (term, x)
}

fn hessian(c: &mut Criterion) {
    let mut group = c.benchmark_group("hessian");
    for (model, kind, label) in [
        ("rigid-body", "wire-stretch", ""),
        ("rigid-body", "gravity", ""),
        ("toy", "spring", "k1"),
    ] {
        let (term, x) = term(model, kind, label);
        let id = format!("{kind} ({} coords)", term.coords.len());
        group.bench_function(id, |b| {
            b.iter(|| black_box(&term).derivatives(black_box(&x)))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = hessian
}
criterion_main!(benches);
