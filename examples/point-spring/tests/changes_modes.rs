//! The example kind, linked only here, joins the registry and changes the modes of a
//! bundled model as its physics says: a spring k between the support and a pendulum's mass
//! adds k to the horizontal and vertical stiffness.

use nalgebra::Vector3;
use pendkit::energy::registry;
use pendkit::system::{PluginElement, Stage};
use pendkit_example_point_spring as _;

#[test]
fn registered_next_to_the_bundled_kinds() {
    assert!(
        registry()
            .iter()
            .any(|k| k.kind() == "example-point-spring" && k.stage() == Stage::S0A)
    );
}

#[test]
fn spring_to_the_support_stiffens_the_pendulum() {
    let (mut system, _) = pendkit::Case::model("pendulum").unwrap().build().unwrap();
    let (support, mass) = (
        system.body("support").unwrap(),
        system.body("mass1").unwrap(),
    );
    let k = 100.0;
    system.plugin_elements.push(PluginElement {
        kind: "example-point-spring".into(),
        name: "coil".into(),
        bodies: vec![support, mass],
        points: vec![Vector3::new(0.0, 0.0, -0.6), Vector3::zeros()],
        values: [("k".to_string(), k)].into_iter().collect(),
        tag: "coil".into(),
    });
    let r = pendkit::run_stage(system, Stage::S0A).unwrap();
    let two_pi = 2.0 * std::f64::consts::PI;
    let m = 40.0;
    let kw = 4.0 * 72e9 * std::f64::consts::PI * 0.2e-3f64.powi(2) / 0.6;
    let expected = [
        ((m * 9.81 / 0.6 + k) / m).sqrt() / two_pi,
        ((m * 9.81 / 0.6 + k) / m).sqrt() / two_pi,
        ((kw + k) / m).sqrt() / two_pi,
    ];
    for (mode, f) in r.modes.modes.iter().zip(expected) {
        assert!((mode.hz - f).abs() < 1e-10 * f, "{} vs {f}", mode.hz);
    }
}
