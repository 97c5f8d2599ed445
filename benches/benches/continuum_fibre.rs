//! The dynamic stiffness D(f) (12×12) of one continuum fibre per frequency point
//! (`pendkit-element-continuum-fibre`): quad-aligo's tapered fibre (three pieces) and a
//! uniform one, at 10 Hz and at 1 kHz (near the first violin mode); and the thermal noise
//! of `quad-aligo` at `tm_beam` over 1000 log-spaced points from 0.1 Hz to 2 kHz, bead-free
//! static fibres against continuum fibres (issue 37's targets: ≤ 3× per point, ≤ 5 ms).
//!
//!     cargo bench -p pendkit-benches --bench continuum_fibre

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix3, Vector3};
use pendkit_element_continuum_fibre::{ContinuumFibre, Moduli};
use pendkit_model::FibreProfile;
use pendkit_system::{EndDirection, WireEnd, WireTags};
use std::hint::black_box;

fn fibre(profile: &FibreProfile) -> ContinuumFibre {
    let end = |body| WireEnd {
        body,
        point: Vector3::zeros(),
        direction: EndDirection::Auto,
    };
    let tags = WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    };
    let tension = 97.1;
    let wire = profile.wire("fibre", [end(0), end(1)], tension, tags);
    let ends = [Vector3::zeros(), Vector3::new(0.0, 0.0, -profile.length())];
    ContinuumFibre::new(&wire, ends, &Matrix3::identity(), [false; 2], tension).unwrap()
}

fn bench(c: &mut Criterion) {
    let silica = (7.2e10, 7.2e10 / 2.34, 2200.0);
    let tapered = FibreProfile::tapered(0.59, (0.045, 400e-6), 205e-6, silica);
    let uniform = FibreProfile::uniform(0.59, 205e-6, silica.0, silica.1, silica.2);
    let moduli = Moduli {
        stretch: Moduli::LOSSLESS.stretch,
        bending: nalgebra::Complex::new(1.0, 4e-10),
        torsion: Moduli::LOSSLESS.torsion,
    };
    for (name, profile) in [("tapered", &tapered), ("uniform", &uniform)] {
        let f = fibre(profile);
        for hz in [10.0, 1000.0] {
            c.bench_function(&format!("continuum_fibre/{name}/{hz}Hz"), |b| {
                b.iter(|| black_box(f.dynamic_stiffness(black_box(hz), &moduli)))
            });
        }
    }
}

fn noise(c: &mut Criterion) {
    let (system, _) = pendkit::Case::model("quad-aligo").unwrap().build().unwrap();
    let result = pendkit::run_stage(system, pendkit::Stage::S2).unwrap();
    let freqs = pendkit::log_grid(0.1, 2000.0, 1000).unwrap();
    let mut group = c.benchmark_group("continuum_fibre/quad-aligo noise 1000 points");
    group.sample_size(20);
    group.bench_function("static", |b| {
        b.iter(|| black_box(result.noise("tm_beam", &freqs).unwrap()))
    });
    let continuum = result
        .with_fibres(&pendkit::stage::Fibres::Continuum)
        .unwrap();
    group.bench_function("continuum", |b| {
        b.iter(|| black_box(continuum.noise("tm_beam", &freqs).unwrap()))
    });
    group.finish();
}

criterion_group!(benches, bench, noise);
criterion_main!(benches);
