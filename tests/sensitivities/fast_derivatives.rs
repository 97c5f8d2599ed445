//! The fast derivative path against the reference: every term's fast Hessians (tension on
//! and off) equal the hyper-dual reference (`Term::reference_derivatives`, one evaluation
//! per entry of the whole generic energy body) on every bundled model at every stage and at
//! randomised configurations away from the equilibrium; the mass matrix from shared frame
//! jets equals the one from forward-mode dual numbers; and mode frequencies are the ones
//! the reference path gives.
//!
//! Tolerances: both paths compute the same functions in a different order of floating-point
//! operations, so they agree to a few ulps of the largest entry of a term's Hessian; 1e-12
//! of the largest entry (the requirement) leaves room for the ~1e3 cancellation of
//! stiff wires (k l / T) without admitting any structural error, which would be of the
//! size of the entries themselves. Mode frequencies are required to agree to 1e-9, except
//! that a mode far above the lowest is only determined to about ε ω²/ω²_min relative by the
//! eigen solve itself (the pencil is reduced with K_eff's factor and solved for 1/ω², whose
//! absolute rounding is ε/ω²_min): a violin bead's 9 kHz mode moves by 2e-9 when the
//! Hessians change by one ulp, whichever path computes them, so that much is added.

use nalgebra::Vector3;
use pendkit::energy::{Element, OffHessian, Reference, SharedBodies, Term, registry};
use pendkit::system::{EndDirection, Stage, System, Wire, WireEnd, WireSection, WireTags};
use pendkit_assembly::{
    AssemblyOptions, DerivativePath, EquilibriumOptions, assemble_at_with, assemble_with,
    mass_matrix,
};
use pendkit_model::{BodySpec, SystemBuilder};

/// Largest |fast − reference| relative to the reference's largest entry (0 when both vanish).
fn mismatch(fast: &[f64], reference: &[f64]) -> f64 {
    assert_eq!(fast.len(), reference.len());
    let scale = reference.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = fast
        .iter()
        .zip(reference)
        .fold(0.0f64, |a, (f, r)| a.max((f - r).abs()));
    if diff == 0.0 { 0.0 } else { diff / scale }
}

const TOLERANCE: f64 = 1e-12;

/// Asserts that two tension-off forms agree (same kind; matrices within tolerance).
fn assert_off_matches(fast: &OffHessian, reference: &OffHessian, what: &str) {
    match (fast, reference) {
        (OffHessian::Matrix(f), OffHessian::Matrix(r)) => {
            let m = mismatch(f, r);
            assert!(m <= TOLERANCE, "{what} off: mismatch {m:.2e}");
        }
        (f, r) => assert_eq!(f, r, "{what}: tension-off forms differ"),
    }
}

fn build(model: &str, sets: &[&str]) -> System {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    pendkit::Case::model(model)
        .and_then(|c| c.with_sets(&sets))
        .and_then(|c| c.build())
        .unwrap_or_else(|e| panic!("{model}: {e}"))
        .0
}

/// Every bundled model at its defaults, and the equilibrium-early variants of the wire
/// models (plug-in terms built at the start and evaluated away from it, or rebuilt).
fn cases() -> Vec<(String, System)> {
    let mut cases: Vec<(String, System)> = pendkit::catalogue::models()
        .iter()
        .map(|m| (m.name().to_string(), build(m.name(), &[])))
        .collect();
    for (model, early) in [
        ("pendulum", "1"),
        ("pendulum", "2"),
        ("rigid-body", "1"),
        ("rigid-body", "2"),
        ("quad", "1"),
    ] {
        cases.push((
            format!("{model} wire_terms_early={early}"),
            build(model, &[&format!("wire_terms_early={early}")]),
        ));
    }
    // started away from the equilibrium, so that the plug-in terms built at the start are
    // evaluated elsewhere (early = 1) and Newton takes steps
    for early in ["0", "1", "2"] {
        let mut system = build("rigid-body", &[&format!("wire_terms_early={early}")]);
        for (name, offset) in [("x1", 2e-3), ("pitch1", 1e-3), ("yaw1", -2e-3)] {
            let i = system.coord(name).unwrap();
            system.coords[i].start += offset;
        }
        cases.push((
            format!("rigid-body displaced start, wire_terms_early={early}"),
            system,
        ));
    }
    cases
}

#[test]
fn every_bundled_model_at_every_stage_matches_the_reference() {
    for (name, system) in cases() {
        for stage in Stage::ALL {
            let fast = assemble_with(&system, stage, &AssemblyOptions::default(), None)
                .unwrap_or_else(|e| panic!("{name} {stage}: {e}"));
            // the reference at the same equilibrium, so that only the derivatives differ
            let reference = assemble_at_with(
                &system,
                stage,
                fast.equilibrium.clone(),
                DerivativePath::Reference,
            )
            .unwrap();
            assert_eq!(fast.terms.len(), reference.terms.len(), "{name} {stage}");
            for (f, r) in fast.terms.iter().zip(&reference.terms) {
                let what = format!("{name} stage {stage} {}", r.label);
                assert_eq!(f.label, r.label, "{what}");
                assert_eq!(f.coords, r.coords, "{what}");
                let m = mismatch(&f.on, &r.on);
                assert!(m <= TOLERANCE, "{what}: mismatch {m:.2e}");
                assert_off_matches(&f.off, &r.off, &what);
            }
            // mass from the shared jets against forward-mode duals
            let m = mismatch(
                fast.mass.to_dense().as_slice(),
                reference.mass.to_dense().as_slice(),
            );
            assert!(m <= 1e-14, "{name} {stage} mass: mismatch {m:.2e}");
            let direct = mass_matrix(&system, &fast.layout, &fast.equilibrium.coords).unwrap();
            assert!(
                mismatch(
                    direct.to_dense().as_slice(),
                    reference.mass.to_dense().as_slice()
                ) <= 1e-14
            );
        }
    }
}

#[test]
fn mode_frequencies_are_those_of_the_reference_path() {
    // Each path finds its own equilibrium (Newton with its own derivatives) and modes.
    let reference = pendkit::stage::RunOptions {
        assembly: AssemblyOptions {
            equilibrium: EquilibriumOptions::default(),
            derivatives: DerivativePath::Reference,
        },
        ..Default::default()
    };
    for (name, system) in cases() {
        for stage in Stage::ALL {
            let fast = pendkit::run_stage(system.clone(), stage).unwrap();
            let slow =
                pendkit::stage::run_stage_with(system.clone(), stage, &reference, None).unwrap();
            assert_eq!(fast.modes.modes.len(), slow.modes.modes.len());
            let lowest = slow
                .modes
                .modes
                .iter()
                .map(|m| m.omega_squared.abs())
                .fold(f64::INFINITY, f64::min);
            for (f, r) in fast.modes.modes.iter().zip(&slow.modes.modes) {
                let solve = f64::EPSILON * r.omega_squared.abs() / lowest;
                assert!(
                    (f.hz - r.hz).abs() <= (1e-9 + solve) * r.hz.abs(),
                    "{name} stage {stage}: {} Hz vs {} Hz",
                    f.hz,
                    r.hz
                );
            }
        }
    }
}

/// Deterministic pseudo-random numbers in [-1, 1) (xorshift64*).
struct Random(u64);

impl Random {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        bits as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Every kind's terms built around `x`, sharing bodies as the assembly does.
fn all_terms(system: &System, x: &[f64]) -> Vec<Term> {
    let reference = Reference::new(system, x);
    let shared = SharedBodies::new();
    registry()
        .iter()
        .flat_map(|k: &&dyn Element| k.terms_shared(&reference, &shared).unwrap())
        .collect()
}

/// Fast against reference for every term at `x` (value, gradient, Hessians on and off).
fn compare_terms_at(terms: &[Term], x: &[f64], what: &str) {
    for term in terms {
        let what = format!("{what} {}", term.label);
        let (fast, reference) = (
            term.derivatives(x).unwrap(),
            term.reference_derivatives(x).unwrap(),
        );
        // Where the true gradient vanishes (torsion and bending at their reference) the
        // structured path gives exact zeros and the reference the rounding of its Hessian
        // times the coordinates; so gradients are compared on the scale of the larger of
        // the gradient and the Hessian times a unit displacement (1 m or 1 rad), and
        // energies on the scale of that times 1 m (they vanish there too).
        let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let scale = largest(&reference.gradient).max(largest(&reference.hessian));
        assert!(
            (fast.value - reference.value).abs() <= TOLERANCE * reference.value.abs().max(scale),
            "{what}: value {} vs {}",
            fast.value,
            reference.value
        );
        let diff = fast
            .gradient
            .iter()
            .zip(&reference.gradient)
            .fold(0.0f64, |a, (f, r)| a.max((f - r).abs()));
        assert!(
            diff <= TOLERANCE * scale,
            "{what}: gradient mismatch {diff:.2e} of {scale:.2e}"
        );
        let (on_fast, off_fast) = term.hessians(x, true).unwrap();
        let (on_ref, off_ref) = term.hessians(x, false).unwrap();
        let m = mismatch(&on_fast, &on_ref);
        assert!(m <= TOLERANCE, "{what}: mismatch {m:.2e}");
        assert_off_matches(&off_fast, &off_ref, &what);
    }
}

/// Perturbs every variable and float of `system` by up to `length` (m) or `angle` (rad).
fn perturbed(system: &System, x: &[f64], rng: &mut Random, length: f64, angle: f64) -> Vec<f64> {
    x.iter()
        .zip(&system.coords)
        .map(|(&v, c)| {
            if c.kind == pendkit::system::CoordKind::Parameter {
                return v;
            }
            let angular = ["yaw", "pitch", "roll"]
                .iter()
                .any(|a| c.name.starts_with(a));
            v + rng.next() * if angular { angle } else { length }
        })
        .collect()
}

#[test]
fn random_states_away_from_equilibrium_match_the_reference() {
    let mut rng = Random(0x9e37_79b9_7f4a_7c15);
    let models = [
        "toy",
        "pendulum",
        "double-pendulum",
        "rigid-body",
        "quad",
        "quad-lite",
        "quad-full",
        "quad-lateral",
        "quad-v5",
        "triple-full",
    ];
    for model in models {
        let system = build(model, &[]);
        let eq = pendkit_assembly::solve_equilibrium(&system, &EquilibriumOptions::default())
            .unwrap()
            .coords;
        let terms = all_terms(&system, &eq);
        // at the reference itself (the structured paths), then a few mm / mrad away, then
        // several cm / 0.2 rad away (the general paths)
        compare_terms_at(&terms, &eq, &format!("{model} at equilibrium"));
        for (length, angle) in [(3e-3, 3e-3), (5e-2, 0.2)] {
            for k in 0..3 {
                let x = perturbed(&system, &eq, &mut rng, length, angle);
                compare_terms_at(&terms, &x, &format!("{model} ±{length} m #{k}"));
            }
        }
    }
}

/// A 20 kg rigid body under a support on four wires with every kind of end (explicit
/// clamps off the chord, hinges, auto), round and oblong sections, and a blade-tip-like
/// child frame riding on the body (a float in an affine pose entry) holding one wire.
fn mixed_ends() -> System {
    let mut b = SystemBuilder::new(9.81);
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    let l = 0.5;
    for (n, v) in [
        ("x1", 0.0),
        ("y1", 0.0),
        ("z1", -l),
        ("yaw1", 0.0),
        ("pitch1", 0.0),
        ("roll1", 0.0),
    ] {
        b.variable(n, v).unwrap();
    }
    b.float("q1", 0.0).unwrap();
    let body = b
        .body(
            BodySpec::new("body")
                .pose(["x1", "y1", "z1", "yaw1", "pitch1", "roll1"])
                .mass(20.0)
                .inertia_diag(0.2, 0.3, 0.25),
        )
        .unwrap();
    let tip = b
        .body(
            BodySpec::new("tip")
                .on(body)
                .pose(["0.05", "-0.1", "0.02 + q1", "0", "0", "0"]),
        )
        .unwrap();
    let round = WireSection::round(2e-4, 7.2e10, 3e10, 2200.0);
    let mut oblong = round.clone();
    oblong.moment_1 *= 3.0;
    oblong.moment_2 /= 2.0;
    oblong.principal_axis = Vector3::new(1.0, 0.3, 0.0);
    let tags = WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    };
    let tilt = |a: f64, c: f64| EndDirection::Explicit(Vector3::new(a, c, -1.0));
    let wires = [
        // (support point, body or tip, body point, top end, bottom end, section)
        (
            Vector3::new(0.1, 0.1, 0.0),
            body,
            Vector3::new(0.1, 0.1, 0.0),
            tilt(0.02, -0.01),
            EndDirection::Hinged,
            &round,
        ),
        (
            Vector3::new(-0.1, 0.1, 0.0),
            body,
            Vector3::new(-0.1, 0.1, 0.0),
            EndDirection::Auto,
            EndDirection::Auto,
            &oblong,
        ),
        (
            Vector3::new(0.1, -0.1, 0.0),
            body,
            Vector3::new(0.1, -0.1, 0.0),
            tilt(-0.01, 0.03),
            EndDirection::Explicit(Vector3::new(0.01, 0.0, 1.0)),
            &oblong,
        ),
        (
            Vector3::new(0.05, -0.1, 0.02),
            tip,
            Vector3::zeros(),
            EndDirection::Hinged,
            EndDirection::Explicit(Vector3::new(-0.02, 0.01, 1.0)),
            &round,
        ),
    ];
    for (k, (top, lower, point, d0, d1, section)) in wires.into_iter().enumerate() {
        b.wire(Wire::from_tension(
            format!("w{k}"),
            [
                WireEnd {
                    body: support,
                    point: top,
                    direction: d0,
                },
                WireEnd {
                    body: lower,
                    point,
                    direction: d1,
                },
            ],
            section.clone(),
            l,
            20.0 * 9.81 / 4.0,
            tags.clone(),
        ))
        .unwrap();
    }
    b.build().unwrap()
}

#[test]
fn explicit_clamps_hinges_oblong_sections_and_riding_frames_match_the_reference() {
    let system = mixed_ends();
    let start = system.start();
    let terms = all_terms(&system, &start);
    assert!(terms.iter().any(|t| t.kind == "wire-bending"));
    compare_terms_at(&terms, &start, "mixed ends at the reference");
    let mut rng = Random(12345);
    for (length, angle) in [(2e-3, 2e-3), (3e-2, 0.1)] {
        for k in 0..4 {
            let x = perturbed(&system, &start, &mut rng, length, angle);
            compare_terms_at(&terms, &x, &format!("mixed ends ±{length} m #{k}"));
        }
    }
}

#[test]
fn very_stiff_wires_converge_to_the_rounding_floor() {
    // r_wire × 30: k = E π r² / l = 2.5e8 N/m per wire, 4e5 times the pendulum stiffness
    // m g / l; a length's rounding (1e-16 m) is a force of 3e-8 N, above the old absolute
    // floor, so the search used to hunt below rounding and fail. The equilibrium is the
    // nominal geometry (l0 derived from the tensions), and the modes are the closed forms:
    // horizontally the double pendulum of T1 = (m1 + m2) g, T2 = m2 g over l (oracles §2,
    // independent of k), vertically two masses on two springs k (K = [[2k, −k], [−k, k]]).
    let system = build("double-pendulum", &["r_wire=scale(30)"]);
    let r = pendkit::run_stage(system, Stage::S0A).unwrap();
    let x = &r.assembled.equilibrium.coords;
    for (name, value) in [("z1", -0.6), ("z2", -1.2), ("x1", 0.0), ("x2", 0.0)] {
        let i = r.system.coord(name).unwrap();
        // a residual of 3e-8 N on a 2.5e8 N/m wire is 1e-16 m
        assert!((x[i] - value).abs() < 1e-12, "{name} = {}", x[i]);
    }
    let (m, g, l) = (40.0f64, 9.81, 0.6);
    let k = 212e9 * std::f64::consts::PI * (30.0 * 0.5e-3f64).powi(2) / l;
    let two_by_two = |a: f64, b: f64, c: f64| {
        // eigenvalues of [[a, b], [b, c]] / m, ascending
        let (mean, half) = (0.5 * (a + c), (0.25 * (a - c).powi(2) + b * b).sqrt());
        [(mean - half) / m, (mean + half) / m]
    };
    let (t1, t2) = (2.0 * m * g, m * g);
    let horizontal = two_by_two(t1 / l + t2 / l, -t2 / l, t2 / l);
    let vertical = two_by_two(2.0 * k, -k, k);
    let hz = |w2: f64| w2.sqrt() / (2.0 * std::f64::consts::PI);
    let mut expected: Vec<f64> = horizontal
        .iter()
        .flat_map(|&w2| [hz(w2), hz(w2)])
        .chain(vertical.iter().map(|&w2| hz(w2)))
        .collect();
    expected.sort_by(f64::total_cmp);
    assert_eq!(r.modes.modes.len(), 6);
    for (mode, f) in r.modes.modes.iter().zip(expected) {
        assert!((mode.hz - f).abs() < 1e-9 * f, "{} Hz vs {f} Hz", mode.hz);
    }
}

#[test]
fn a_model_at_its_equilibrium_costs_one_gradient_check() {
    // The quad starts at its nominal geometry, which is its equilibrium to rounding (the
    // model derives wire lengths and blade preloads from the static loads): Newton accepts
    // it on forces alone, so no Hessian is evaluated there and the assembly evaluates each
    // stage-0A term's Hessians once (each kind's phase counts every one of its terms).
    let system = build("quad", &[]);
    let mut times = pendkit_assembly::PhaseTimes::new();
    let a = assemble_with(
        &system,
        Stage::S0A,
        &AssemblyOptions::default(),
        Some(&mut times),
    )
    .unwrap();
    assert_eq!(a.equilibrium.iterations, 0);
    let calls = |name: &str| {
        times
            .phases()
            .iter()
            .find(|p| p.name == name)
            .map_or(0, |p| p.calls)
    };
    assert_eq!(calls("hessian:wire-stretch"), system.wires.len());
    assert_eq!(calls("hessian:spring"), system.springs.len());
    let massive = system.bodies.iter().filter(|b| b.mass != 0.0).count();
    assert_eq!(calls("hessian:gravity"), massive);
}

#[test]
fn very_stiff_wires_converge_on_the_reference_path_too() {
    // the reference path takes its rounding floor from the Hessian (ε |H| |x|), the fast
    // path from each term's own cancellation scale (k (|p0| + |p1| + l0) for a wire): both
    // find the nominal geometry of the stiff double pendulum
    let system = build("double-pendulum", &["r_wire=scale(30)"]);
    let options = pendkit::stage::RunOptions {
        assembly: AssemblyOptions {
            derivatives: DerivativePath::Reference,
            ..AssemblyOptions::default()
        },
        ..Default::default()
    };
    let r = pendkit::stage::run_stage_with(system, Stage::S0A, &options, None).unwrap();
    let i = r.system.coord("z2").unwrap();
    assert!((r.assembled.equilibrium.coords[i] + 1.2).abs() < 1e-12);
}
