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
