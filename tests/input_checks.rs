//! Library entry points given sizes, indices, names and frequencies they cannot use return
//! errors (never a panic, never NaN with success), and points on float-posed bodies carry
//! the floats' motion (issue 11).

use nalgebra::{DMatrix, DVector};
use pendkit::dynamics::{DynamicsError, Input, Output, normal_modes};
use pendkit::{Case, StageResult, run_stage};
use pendkit_energy::Stage;

fn quad() -> StageResult {
    let (system, _) = Case::model("quad").unwrap().build().unwrap();
    run_stage(system, Stage::S2).unwrap()
}

#[test]
fn mis_sized_inputs_to_public_functions_are_errors_not_panics_or_nan() {
    let r = quad();
    let d = &r.system.damping;
    let (nx, _, ns) = r.model.sizes;
    let good_in = Input::Displacement(DVector::from_element(ns, 1.0));
    let good_out = Output::Displacement(DVector::from_element(nx, 1.0));
    let short_in = Input::Displacement(DVector::zeros(ns + 1));
    let short_out = Output::Displacement(DVector::zeros(1));
    assert!(matches!(
        r.model.transfer(d, &short_in, &good_out, &[1.0]),
        Err(DynamicsError::Length { .. })
    ));
    assert!(matches!(
        r.model.transfer(d, &good_in, &short_out, &[1.0]),
        Err(DynamicsError::Length { .. })
    ));
    assert!(r.model.transfer(d, &good_in, &good_out, &[1.0]).is_ok());
    let nan_in = Input::Displacement(DVector::from_element(ns, f64::NAN));
    assert!(r.model.transfer(d, &nan_in, &good_out, &[1.0]).is_err());
    // frequencies outside the documented limits
    for f in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-320, 1e300] {
        assert!(
            r.model.transfer(d, &good_in, &good_out, &[f]).is_err(),
            "{f}"
        );
    }
    // thermal noise: output of the wrong length, temperature not positive
    let v = DVector::zeros(3);
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, 290.0, &[1.0]).is_err());
    let v = DVector::from_element(nx, 1.0);
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, -1.0, &[1.0]).is_err());
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, 290.0, &[1.0]).is_ok());
    // modes of matrices that do not fit, or hold NaN
    let names: Vec<String> = vec!["a".into(), "b".into()];
    let k = DMatrix::identity(2, 2);
    assert!(normal_modes(&k, &DMatrix::identity(3, 3), &names).is_err());
    assert!(normal_modes(&k, &DMatrix::identity(2, 2), &names[..1]).is_err());
    let mut bad = k.clone();
    bad[(0, 1)] = f64::NAN;
    assert!(normal_modes(&bad, &DMatrix::identity(2, 2), &names).is_err());
    // modes below a frequency that is not one
    assert!(r.model.modes_below(d, f64::NAN).is_err());
    // names that are not the model's
    assert!(r.input("nope").is_err() && r.output("nope").is_err());
    assert!(r.output("testmass@0,0/1,0,0").is_err());
    assert!(r.output("testmass@0,0,0/0,0,0").is_err());
}

#[test]
fn point_on_a_blade_tip_carries_the_tip_float_motion() {
    // Maxwell–Betti reciprocity: the displacement of coordinate z2 per unit vertical force
    // at a blade tip equals the tip's vertical displacement per unit generalised force on
    // z2. The tip is posed by a massless float, so the second one holds only if the output
    // point carries the float's motion (dropping it gives the UIM's own motion there, a
    // different number). Tolerance: rounding of two solves of the same matrices.
    let r = quad();
    let tip = "blade1l@0,0,0/0,0,1";
    let freqs = [0.01, 1.0, 10.0];
    let push_tip = r.transfer(&format!("force:{tip}"), "z2", &freqs).unwrap();
    let read_tip = r.transfer("force:z2", tip, &freqs).unwrap();
    for ((a, b), f) in push_tip.iter().zip(&read_tip).zip(freqs) {
        assert!((a - b).norm() <= 1e-9 * a.norm(), "{f} Hz: {a} vs {b}");
        assert!(a.norm() > 0.0);
    }
    // and the tip moves relative to the UIM: its own compliance exceeds the UIM point's
    let tip_self = r.transfer(&format!("force:{tip}"), tip, &[0.01]).unwrap()[0];
    let uim = "uim@0,0,0/0,0,1";
    let uim_self = r.transfer(&format!("force:{uim}"), uim, &[0.01]).unwrap()[0];
    assert!(tip_self.re > uim_self.re, "{tip_self} vs {uim_self}");
}
