//! The library's public functions that take indices or sizes answer an argument out of
//! range with their crate's error (docs/checks-and-refusals.md: no public function of the
//! library crates panics on the sizes, indices or names it is given). Each of issue 38's
//! five that indexed without a check is called here with what it cannot have: a body, a
//! coordinate or a wire past the model's lists, a coordinate vector too short, a count past
//! its range. Each would have panicked (index out of bounds) before.

use std::path::Path;

use nalgebra::Vector3;
use pendkit::Case;
use pendkit::energy::{
    EnergyError, LocalFrames, Reference, SharedBodies, constraint_terms, extra_terms,
};
use pendkit::system::{EndDirection, ExtraPhase, ExtraTerm, System, WireEnd};

/// The bundled pendulum's model (a support, a point mass, four fibres) and its start.
fn pendulum() -> (System, Vec<f64>) {
    let (system, _) = Case::model("pendulum").unwrap().build().unwrap();
    let start = system.coords.iter().map(|c| c.start).collect();
    (system, start)
}

#[test]
fn a_reference_frame_and_the_wire_helpers_refuse_a_body_the_model_lacks() {
    let (mut system, start) = pendulum();
    let bodies = system.bodies.len();
    let e = Reference::new(&system, &start).frame(bodies).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("Reference::frame: body index {bodies} is out of range (the system has {bodies})")
    );
    // a wire whose lower end is on a body past the list, as a hand-built model may have
    system.wires[0].ends[1] = WireEnd {
        body: bodies + 3,
        point: Vector3::zeros(),
        direction: EndDirection::Hinged,
    };
    let reference = Reference::new(&system, &start);
    let wire = &system.wires[0];
    let named = |e: EnergyError| {
        assert_eq!(
            e.to_string(),
            format!(
                "wire '{}': body index {} is out of range (the system has {bodies})",
                wire.name,
                bodies + 3
            )
        );
    };
    named(reference.wire_points(wire).unwrap_err());
    named(reference.wire_length(wire).unwrap_err());
    named(reference.wire_tension(wire).unwrap_err());
    named(reference.wire_end_directions(wire).unwrap_err());
    // the other wires are as they were: 0.6 m long (the model's nominal geometry)
    let length = reference.wire_length(&system.wires[1]).unwrap();
    assert!((length - 0.6).abs() < 1e-12, "{length}");
}

#[test]
fn local_frames_refuse_a_body_the_model_lacks_made_anew_or_shared() {
    let (system, _) = pendulum();
    let n = system.bodies.len();
    let e = LocalFrames::new(&system, &[0, n]).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("LocalFrames::new: body index {n} is out of range (the system has {n})")
    );
    let shared = SharedBodies::new();
    assert!(shared.frames(&system, &[n + 1]).is_err());
    // and the bodies it has are collected: the point mass reads its three coordinates
    let frames = shared.frames(&system, &[1]).unwrap();
    assert_eq!(frames.coords.len(), 3);
}

#[test]
fn constraint_and_extra_terms_refuse_short_vectors_and_foreign_coordinates() {
    let (mut system, start) = pendulum();
    let n = system.coords.len();
    let short = &start[..n - 1];
    system.constraint_stiffness.insert(0, 10.0);
    let e = constraint_terms(&system, short).unwrap_err();
    assert!(
        matches!(e, EnergyError::Length { function: "constraint_terms", expected, given, .. } if expected == n && given == n - 1),
        "{e}"
    );
    assert_eq!(constraint_terms(&system, &start).unwrap().len(), 1);
    // a constraint on a coordinate the model does not have
    system.constraint_stiffness.insert(n + 5, 10.0);
    let e = constraint_terms(&system, &start).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "constraint: coordinate index {} is out of range (the system has {n})",
            n + 5
        )
    );
    // an extra term after the equilibrium reads `<coordinate>.eq` from the vector
    system.extra_terms.push(ExtraTerm {
        name: "tie".into(),
        energy: pendkit::expr::parse("(x1 - x1.eq)^2").unwrap(),
        tag: "tie".into(),
        phase: ExtraPhase::AfterEquilibrium,
    });
    let e = extra_terms(&system, ExtraPhase::AfterEquilibrium, Some(short)).unwrap_err();
    assert!(
        matches!(
            e,
            EnergyError::Length {
                function: "extra_terms",
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(
        extra_terms(&system, ExtraPhase::AfterEquilibrium, Some(&start))
            .unwrap()
            .len(),
        1
    );
}

#[test]
fn a_chunk_direction_past_the_chunk_cannot_be_made() {
    let k = pendkit::params::TANGENT_CHUNK;
    assert!(pendkit::params::Direction::new(k - 1).is_ok());
    for bad in [k, usize::MAX] {
        let e = pendkit::params::Direction::new(bad).unwrap_err();
        assert!(e.to_string().contains("is out of range"), "{e}");
    }
}

#[test]
fn a_generated_chain_is_refused_outside_its_stage_count() {
    use pendkit::suspension::generate::{MAX_GENERATED_STAGES, chain};
    for n in [0, MAX_GENERATED_STAGES + 1, usize::MAX] {
        let e = chain(n).expect_err("refused").to_string();
        assert!(
            e.contains(&format!(
                "{n} stages: a chain has 1 to {MAX_GENERATED_STAGES}"
            )),
            "{e}"
        );
    }
    // and a chain within it reads as a suspension
    let written = chain(2).unwrap();
    let case = Case::from_text(Path::new("chain-2.toml"), &written.source.text).unwrap();
    assert_eq!(case.build().unwrap().0.bodies.len(), 3);
}

#[test]
fn a_tapered_fibres_inverse_radius_takes_any_power() {
    // the power's successor is written too: u32::MAX + 1 overflowed
    let text = pendkit::model::fibre_inverse_radius(("l", "n", "rn", "r"), u32::MAX);
    assert!(text.contains("^4294967296"), "{text}");
}
