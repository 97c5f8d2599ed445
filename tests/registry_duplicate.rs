//! A second crate registering an existing kind name is an error naming both crates, not
//! a silent replacement (or a doubled energy). This program links such a registration, so
//! it is a test binary of its own.

use pendkit::Error;
use pendkit_energy::{
    Element, EnergyError, Reference, Term, check_registrations, register_element,
};
use pendkit_system::Stage;

/// An element that claims the core's "gravity" kind name.
struct ShadowGravity;

impl Element for ShadowGravity {
    fn kind(&self) -> &'static str {
        "gravity"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "a second element under the core's gravity name"
    }
    fn terms(&self, _: &Reference) -> Result<Vec<Term>, EnergyError> {
        Ok(Vec::new())
    }
}

register_element!(ShadowGravity);

#[test]
fn registering_a_kind_name_twice_is_an_error_naming_both_crates() {
    let e = check_registrations().unwrap_err();
    assert_eq!(e.kind, "gravity");
    let mut crates = [e.first, e.second];
    crates.sort_unstable();
    assert_eq!(crates, ["pendkit-energy", "pendkit-tests"]);
    let message = e.to_string();
    assert!(message.contains("pendkit-energy") && message.contains("pendkit-tests"));
    // and every run refuses to go on with it
    let (system, _) = pendkit::Case::model("toy").unwrap().build().unwrap();
    match pendkit::run_stage(system, Stage::S0A) {
        Err(Error::Registry(d)) => assert_eq!(d, e),
        Err(other) => panic!("wrong error: {other}"),
        Ok(_) => panic!("a run with a duplicate kind succeeded"),
    }
}
