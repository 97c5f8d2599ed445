//! Frames given coordinate vectors (or Jacobian widths) too short for them answer with an
//! error naming the function and both lengths, never a panic (issue 11, item 5).

use nalgebra::Vector3;
use pendkit_expr::{Slot, parse};
use pendkit_geometry::{FrameJet, FrameMap, GeometryError, JetOrder, PoseMap};

/// A free body posed by coordinates 2..8 of the model (x, y, z, yaw, pitch, roll), with
/// a blade tip riding on it that slides along the body's z by coordinate 9 times 2.
fn body_and_tip() -> (FrameMap, FrameMap) {
    let names = ["a", "b", "x", "y", "z", "yaw", "pitch", "roll", "c", "q"];
    let slot = |s: &str| names.iter().position(|n| *n == s).map(Slot::Var);
    let pose = |texts: [&str; 6]| PoseMap {
        entries: texts.map(|t| parse(t).unwrap().compile(&slot).unwrap()),
    };
    let body = FrameMap::root(pose(["x", "y", "z", "yaw", "pitch", "roll"]));
    let tip = body.child(pose(["0", "0.2", "2*q", "0", "0", "0"]));
    (body, tip)
}

#[test]
fn short_coordinate_vectors_are_errors_naming_both_lengths() {
    let (body, tip) = body_and_tip();
    assert_eq!((body.needs(), tip.needs()), (8, 10));
    let full = [0.0, 0.0, 0.1, 0.2, 0.3, 0.01, 0.02, 0.03, 0.0, 0.004];
    let short = &full[..9];
    let p = Vector3::new(0.1, 0.0, 0.0);
    // every entry point, on the tip that reads coordinate 9
    assert_eq!(
        tip.try_eval(short).unwrap_err(),
        GeometryError {
            function: "FrameMap::eval",
            argument: "x (coordinates)",
            expected: 10,
            given: 9
        }
    );
    let mut jet = FrameJet::new();
    let e = tip.jet(short, JetOrder::Second, &mut jet).unwrap_err();
    assert_eq!((e.function, e.expected, e.given), ("FrameMap::jet", 10, 9));
    assert!(tip.try_jacobian(short, &p).is_err());
    assert!(tip.reference_jacobian(short, &p).is_err());
    assert!(tip.try_eval::<f64>(&[]).is_err());
    // the infallible forms answer NaN, never a panic and never a plausible number
    let frame = tip.eval(short);
    assert!(
        frame
            .origin
            .iter()
            .chain(frame.rotation.iter())
            .all(|v| v.is_nan())
    );
    let jac = tip.jacobian(short, &p);
    assert_eq!(jac.position.ncols(), 9);
    assert!(jac.position.iter().all(|v| v.is_nan()));
    // the body alone reads only up to coordinate 7, so 9 entries are enough for it
    assert!(body.try_eval(short).is_ok());
    assert!(body.jet(short, JetOrder::First, &mut jet).is_ok());
    // the right length works, and the error message is one line naming everything
    assert!(tip.try_eval(&full).is_ok());
    assert!(tip.try_jacobian(&full, &p).is_ok());
    assert_eq!(
        tip.try_eval(short).unwrap_err().to_string(),
        "FrameMap::eval: x (coordinates) has 9 entries, the frame needs 10"
    );
}

#[test]
fn a_jet_asked_for_fewer_jacobian_columns_than_it_reads_is_an_error() {
    let (_, tip) = body_and_tip();
    let x = [0.0, 0.0, 0.1, 0.2, 0.3, 0.01, 0.02, 0.03, 0.0, 0.004];
    let mut jet = FrameJet::new();
    tip.jet(&x, JetOrder::First, &mut jet).unwrap();
    let p = Vector3::zeros();
    let e = jet.jacobian(9, &p).unwrap_err();
    assert_eq!(
        (e.function, e.expected, e.given),
        ("FrameJet::jacobian", 10, 9)
    );
    assert!(jet.jacobian(0, &p).is_err());
    // exactly wide enough, or wider (the model's other coordinates get zero columns)
    assert_eq!(jet.jacobian(10, &p).unwrap().position.ncols(), 10);
    let wide = jet.jacobian(12, &p).unwrap();
    assert!(wide.position.column(11).iter().all(|&v| v == 0.0));
}

#[test]
fn jet_derivatives_at_out_of_range_indices_are_errors_naming_the_index() {
    use pendkit_geometry::JetError;
    let (_, tip) = body_and_tip();
    let x = [0.0, 0.0, 0.1, 0.2, 0.3, 0.01, 0.02, 0.03, 0.0, 0.004];
    let a = Vector3::new(0.1, 0.0, 0.0);
    let mut jet = FrameJet::new();
    tip.jet(&x, JetOrder::Second, &mut jet).unwrap();
    // the tip depends on the body's six coordinates and its own q: seven, indices 0..7
    let k = jet.vars().len();
    assert_eq!(k, 7);
    assert!(jet.d_point(k - 1, &a).is_ok() && jet.dd_point(k - 1, k - 1, &a).is_ok());
    assert_eq!(
        jet.d_point(k, &a).unwrap_err(),
        JetError::Index {
            function: "FrameJet::d_point",
            argument: "i",
            index: 7,
            len: 7
        }
    );
    assert!(jet.d_rotation(k).is_err());
    assert!(jet.velocity(usize::MAX, &a).is_err());
    // j = k would alias the pair (i + 1, 0) in the k × k storage: refused, not aliased
    let e = jet.dd_point(0, k, &a).unwrap_err();
    assert_eq!(
        e.to_string(),
        "FrameJet::dd_point: j = 7 is out of range, the jet has 7 coordinates"
    );
    assert!(jet.dd_rotation(k, 0).is_err());
    assert!(jet.hyper_dual(Some(k), None).is_err());
    assert!(jet.hyper_dual(None, Some(k)).is_err());
    assert!(jet.hyper_dual(Some(0), Some(1)).is_ok());
    // the loop forms have exactly one entry per coordinate
    assert_eq!(jet.d_points(&a).len(), k);
    assert_eq!(jet.d_rotations().len(), k);
    assert_eq!(jet.velocities(&a).len(), k);
    // a first-order jet has no second derivatives: an error, not a panic
    tip.jet(&x, JetOrder::First, &mut jet).unwrap();
    assert_eq!(
        jet.dd_point(0, 0, &a).unwrap_err(),
        JetError::NoSecond {
            function: "FrameJet::dd_point"
        }
    );
    assert!(jet.dd_rotation(0, 0).is_err());
    assert!(jet.hyper_dual(Some(0), Some(0)).is_err());
    assert!(jet.hyper_dual(Some(0), None).is_ok());
    // an empty jet (never computed) has no coordinates at all
    let empty = FrameJet::new();
    assert!(empty.d_point(0, &a).is_err() && empty.d_rotation(0).is_err());
    assert_eq!(empty.d_points(&a).len(), 0);
}

#[test]
fn a_frame_remapped_to_the_largest_index_needs_more_than_any_vector_not_nothing() {
    let (_, tip) = body_and_tip();
    let far = tip.remap(&|_| usize::MAX);
    // one more than usize::MAX saturates: were it to wrap to 0, every vector would pass
    // the length check and the reads would run past its end
    assert_eq!(far.needs(), usize::MAX);
    let x = [0.0_f64; 10];
    assert!(far.try_eval(&x).is_err());
    assert!(far.eval(&x).origin.iter().all(|v| v.is_nan()));
    let mut jet = FrameJet::new();
    assert!(far.jet(&x, JetOrder::First, &mut jet).is_err());
}
