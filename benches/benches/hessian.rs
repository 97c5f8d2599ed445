//! Time of `Term::derivatives` (value, gradient and Hessian by hyper-dual numbers) for one
//! term of each core element kind at the model's start position, and for one wire term of
//! each plug-in kind (and wire stretch) at the equilibrium of `rigid-body` and `quad`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use pendkit_assembly::solve_equilibrium;
use pendkit_energy::{Reference, Term, find_kind};

/// Where the terms are built and their derivatives evaluated.
#[derive(Clone, Copy)]
enum At {
    /// `system.start()`, the start of the equilibrium search.
    Start,
    /// The equilibrium from `solve_equilibrium`, as the assembly uses it.
    Equilibrium,
}

/// The first term of kind `kind` in bundled model `model` whose label ends with `label`
/// (any label if empty), with the coordinates it is built around and evaluated at.
fn term(model: &str, kind: &str, label: &str, at: At) -> (Term, Vec<f64>) {
    // `pendkit` links every element crate, so the registry is complete.
    let (system, _) = pendkit::Case::model(model)
        .and_then(|case| case.build())
        .unwrap_or_else(|e| panic!("{model}: {e}"));
    let x = match at {
        At::Start => system.start(),
        At::Equilibrium => {
            solve_equilibrium(&system, &Default::default())
                .unwrap_or_else(|e| panic!("{model}: {e}"))
                .coords
        }
    };
    let element = find_kind(kind).unwrap_or_else(|| panic!("no element kind '{kind}'"));
    let terms = element
        .terms(&Reference::new(&system, &x))
        .unwrap_or_else(|e| panic!("{model} {kind}: {e}"));
    let term = terms
        .into_iter()
        .find(|t| t.label.ends_with(label))
        .unwrap_or_else(|| panic!("{model}: no {kind} term '{label}'"));
    (term, x)
}

fn hessian(c: &mut Criterion) {
    let mut group = c.benchmark_group("hessian");
    // Core kinds at the start position; ids without the model name (as before).
    for (model, kind, label) in [
        ("rigid-body", "wire-stretch", ""),
        ("rigid-body", "gravity", ""),
        ("toy", "spring", "k1"),
    ] {
        let (term, x) = term(model, kind, label, At::Start);
        let id = format!("{kind} ({} coords)", term.coords.len());
        group.bench_function(id, |b| {
            b.iter(|| black_box(&term).derivatives(black_box(&x)))
        });
    }
    // Wire terms at equilibrium: the first fibre of `rigid-body`, and fibre `f1` of `quad`
    // (penultimate mass to test mass, 6 + 6 body coordinates).
    for (model, label, kinds) in [
        (
            "rigid-body",
            "",
            &["wire-torsion", "wire-bending", "wire-extra-stretch"][..],
        ),
        (
            "quad",
            " f1",
            &[
                "wire-stretch",
                "wire-torsion",
                "wire-bending",
                "wire-extra-stretch",
            ][..],
        ),
    ] {
        for kind in kinds {
            let (term, x) = term(model, kind, label, At::Equilibrium);
            let id = format!("{kind} {model} ({} coords)", term.coords.len());
            group.bench_function(id, |b| {
                b.iter(|| black_box(&term).derivatives(black_box(&x)))
            });
        }
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
