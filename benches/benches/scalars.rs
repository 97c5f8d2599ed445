//! The second scalar types of the derivative passes against the path that would replace
//! each (issue 33: a second scalar type stays only where it pays ≥ 1.3×), on the quad at
//! stage 2 with the PUM mass `m2` seeded (every term of every kind up to stage 2, built
//! around the equilibrium):
//!
//! - `modes-along/*`: Σ over the terms of uᵀ(∂K/∂p)u along 24 directions (the quad has 24
//!   modes), every body's frame evaluated beforehand as the projection does once per
//!   stage: six directions per evaluation (`SecondLanes`, four passes) against one at a
//!   time by the hyper-dual number with u = v (`HyperTangent`, 24 passes; until issue 33
//!   also by `Dual2<Dual64>`, which no request used). `modes-along-with-frames/*`: the
//!   same with the frames' evaluation timed too (what the projection's motion re-evaluates
//!   per coordinate).
//! - `projection/*`: one parameter's Wᵀ(dK/dp)W on the 24 directions, diagonal pairs, by
//!   `stage_tangent` projected (the lanes, the equilibrium's motion through the
//!   projection's coefficients) against the full dK/dp (`HyperTangent`, one evaluation per
//!   entry of each term's upper triangle) contracted with the directions.
//! - `gradient/*`: each term's gradient with its parameter derivative (∂g/∂p) by
//!   `Dual<Dual64>` (`DualTangent`, one evaluation per coordinate; per term, and from every
//!   body's frames shared by all the terms as the sensitivities take it) against what the
//!   hyper-dual pass also gives (`TangentTerm::derivatives`: value, gradient and Hessian).
//! - `hessian-f64/*`: the `f64` model's terms' value, gradient and Hessian by their fast
//!   path (`Term::derivatives`) against the hyper-dual reference every kind has
//!   (`Term::reference_derivatives`).
//!
//! The directions are fixed dense vectors (every coordinate moving), not the modes
//! themselves: the cost of the dual arithmetic does not depend on the values.

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use num_dual::Dual64;
use pendkit::assembly::{
    Along, AssemblyOptions, Balance, Projection, assemble_with, stage_tangent,
};
use pendkit::energy::{
    GradientFrames, Reference, SharedBodies, TangentSum, TangentTerm, Term, registry,
    tangent_frames, tangent_frames_along_lanes,
};
use pendkit::nalgebra::DMatrix;
use pendkit::{Case, Stage};
use pendkit_rotations::LANES;

/// The directions: 24, one per mode of the quad.
const DIRECTIONS: usize = 24;

/// What the benches share: the quad's `f64` model, its equilibrium and assembly at stage 2,
/// the model built with `m2` seeded and its terms around the equilibrium, the directions.
struct Quad {
    system: pendkit::system::System,
    dual: pendkit::system::System<Dual64>,
    equilibrium: Vec<f64>,
    at_rest: Vec<Dual64>,
    layout: pendkit::assembly::Layout,
    tangent_terms: Vec<TangentTerm>,
    terms: Vec<Term>,
    directions: Vec<Vec<f64>>,
}

fn quad() -> Quad {
    let case = Case::model("quad").expect("quad");
    let (system, _) = case.build().expect("build");
    let a = assemble_with(&system, Stage::S2, &AssemblyOptions::default(), None).expect("assemble");
    let equilibrium = a.equilibrium.coords.clone();
    let at_rest: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
    let dual = pendkit::model::build_tangent(&*case.model, &case.overrides, "m2")
        .expect("exact build of m2");
    let to_stage_2 = |kind: &&'static dyn pendkit::energy::Element| {
        system
            .element_stage(kind.kind(), kind.stage())
            .is_some_and(|s| s <= Stage::S2)
    };
    let (tangent_shared, shared) = (SharedBodies::new(), SharedBodies::new());
    let reference = Reference::new(&dual, &at_rest);
    let f64_reference = Reference::new(&system, &equilibrium);
    let (mut tangent_terms, mut terms) = (Vec::new(), Vec::new());
    for kind in registry().iter().copied().filter(to_stage_2) {
        tangent_terms.extend(
            kind.tangent_terms(&reference, &tangent_shared)
                .expect("tangent terms")
                .expect("every bundled kind has tangent terms"),
        );
        terms.extend(kind.terms_shared(&f64_reference, &shared).expect("terms"));
    }
    let n = system.coords.len();
    let directions = (0..DIRECTIONS)
        .map(|k| {
            (0..n)
                .map(|i| (((i + 3) * (k + 5)) % 7) as f64 * 0.3 - 0.8)
                .collect()
        })
        .collect();
    Quad {
        layout: a.layout,
        system,
        dual,
        equilibrium,
        at_rest,
        tangent_terms,
        terms,
        directions,
    }
}

type Group<'c> = BenchmarkGroup<'c, WallTime>;

fn scalars(c: &mut Criterion) {
    let q = quad();
    let mut group = c.benchmark_group("scalars");
    modes_along(&mut group, &q);
    projection(&mut group, &q);
    gradient_and_hessian(&mut group, &q);
    group.finish();
}

/// `modes-along/*` and `modes-along-with-frames/*`.
fn modes_along(group: &mut Group, q: &Quad) {
    let sum = TangentSum::new(&q.tangent_terms);
    let refs: Vec<&[f64]> = q.directions.iter().map(|d| d.as_slice()).collect();
    // uᵀ(∂K/∂p)u along each direction: lanes, and hyper-dual one at a time
    let lanes: Vec<_> = refs
        .chunks(LANES)
        .map(|chunk| tangent_frames_along_lanes(&q.dual, &q.at_rest, chunk).expect("lanes"))
        .collect();
    let hyper: Vec<_> = refs
        .iter()
        .map(|u| tangent_frames(&q.dual, &q.at_rest, u, u).expect("frames"))
        .collect();
    group.bench_function("modes-along/lanes", |b| {
        b.iter(|| {
            for frames in &lanes {
                black_box(sum.second_along_frames_lanes(frames).unwrap());
            }
        })
    });
    group.bench_function("modes-along/hyper-tangent", |b| {
        b.iter(|| {
            for frames in &hyper {
                black_box(sum.second_along_frames(frames).unwrap());
            }
        })
    });
    group.bench_function("modes-along-with-frames/lanes", |b| {
        b.iter(|| {
            for chunk in refs.chunks(LANES) {
                let frames = tangent_frames_along_lanes(&q.dual, &q.at_rest, chunk).unwrap();
                black_box(sum.second_along_frames_lanes(&frames).unwrap());
            }
        })
    });
    group.bench_function("modes-along-with-frames/hyper-tangent", |b| {
        b.iter(|| {
            for u in &refs {
                let frames = tangent_frames(&q.dual, &q.at_rest, u, u).unwrap();
                black_box(sum.second_along_frames(&frames).unwrap());
            }
        })
    });
}

/// `projection/*`: one parameter's Wᵀ(dK/dp)W on the diagonal pairs, projected against
/// full and contracted.
fn projection(group: &mut Group, q: &Quad) {
    let balance = Balance::new(&q.system, &q.equilibrium)
        .expect("balance")
        .expect("the exact route is open");
    let n = q.system.coords.len();
    let w = DMatrix::from_fn(n, DIRECTIONS, |i, k| q.directions[k][i]);
    let pairs: Vec<(usize, usize)> = (0..DIRECTIONS).map(|k| (k, k)).collect();
    let projection = Projection::new(
        &q.system,
        Stage::S2,
        &q.equilibrium,
        &balance,
        (&w, &pairs),
        1,
    )
    .expect("projection")
    .expect("the exact route is open");
    let tangent = |along| {
        stage_tangent(
            &q.dual,
            Stage::S2,
            &q.equilibrium,
            &q.layout,
            &balance,
            along,
        )
        .unwrap()
        .unwrap()
    };
    group.bench_function("projection/projected", |b| {
        b.iter(|| black_box(tangent(Along::Projected(&projection)).stiffness))
    });
    group.bench_function("projection/full-contracted", |b| {
        b.iter(|| {
            let full = tangent(Along::Full).stiffness;
            black_box(w.tr_mul(&(full * &w)))
        })
    });
}

/// `gradient/*` (∂g/∂p: the dual gradient against the hyper-dual derivatives) and
/// `hessian-f64/*`.
fn gradient_and_hessian(group: &mut Group, q: &Quad) {
    let frames = GradientFrames::new(&q.system, &q.at_rest).expect("frames");
    group.bench_function("gradient/dual-tangent", |b| {
        b.iter(|| {
            for t in &q.tangent_terms {
                black_box(t.gradient(&q.at_rest).unwrap());
            }
        })
    });
    group.bench_function("gradient/dual-tangent-shared-frames", |b| {
        b.iter(|| {
            for t in &q.tangent_terms {
                black_box(t.gradient_from(&frames).unwrap());
            }
        })
    });
    group.bench_function("gradient/hyper-tangent", |b| {
        b.iter(|| {
            for t in &q.tangent_terms {
                black_box(t.derivatives(&q.at_rest).unwrap());
            }
        })
    });

    // the f64 model's Hessians: fast path against the hyper-dual reference
    group.bench_function("hessian-f64/fast", |b| {
        b.iter(|| {
            for t in &q.terms {
                black_box(t.derivatives(&q.equilibrium).unwrap());
            }
        })
    });
    group.bench_function("hessian-f64/hyper-dual", |b| {
        b.iter(|| {
            for t in &q.terms {
                black_box(t.reference_derivatives(&q.equilibrium).unwrap());
            }
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = scalars
}
criterion_main!(benches);
