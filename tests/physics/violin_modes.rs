//! Violin modes as roots of the whole model's frequency-dependent problem.

use nalgebra::Vector3;
use pendkit::stage::Fibres;
use pendkit_model::DampingSpec;
use pendkit_params::ParamSet;
use pendkit_system::Stage;

use crate::continuum_fibre::{LENGTH, RADIUS, TENSION, fibre_between};

/// The REF fibre hanging a body of mass `mass` (kg, inertia `mass` kg m² about each axis)
/// from a fixed support, gravity scaled so that the tension stays 98.1 N, bending loss φ.
fn hanging(mass: f64, phi: f64) -> pendkit::StageResult {
    let (mut system, _) = fibre_between(Vector3::new(0.0, 0.0, -LENGTH), RADIUS, TENSION);
    system.bodies[1].mass = mass;
    system.bodies[1].inertia *= mass;
    system.gravity = TENSION / mass;
    let params = ParamSet::new().resolve().unwrap();
    system.damping.set(
        "b",
        DampingSpec::structural(&phi.to_string())
            .resolve("b", &params)
            .unwrap(),
    );
    pendkit::run_stage(system, Stage::S2)
        .unwrap()
        .with_fibres(&Fibres::ContinuumNamed(vec!["fibre".into()]))
        .unwrap()
}

#[test]
fn explore() {
    for m in [10.0, 1e3, 1e6, 1e9] {
        let t = std::time::Instant::now();
        let v = hanging(m, 1e-6).violin_modes(3).unwrap();
        eprintln!("M = {m}: {:?}", t.elapsed());
        for r in v {
            eprintln!("  {r:?}");
        }
    }
}

#[test]
fn explore_aligo() {
    let t = std::time::Instant::now();
    let r = pendkit_tests::run("quad-aligo", &[], Stage::S2)
        .with_fibres(&Fibres::Continuum)
        .unwrap();
    eprintln!("run {:?}", t.elapsed());
    let t = std::time::Instant::now();
    let v = r.violin_modes(2).unwrap();
    eprintln!("violin {:?}", t.elapsed());
    for m in v {
        eprintln!(
            "  {} {:.9} Q {:.4e} acc {:.2e} {:?} {:?}",
            m.harmonic, m.frequency_hz, m.q, m.accuracy_hz, m.held, m.wires
        );
    }
}
