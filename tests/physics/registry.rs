//! The link-time registry holds exactly the expected element kinds, each at its stage.
//! A missing kind here means a crate was dropped by the linker (inventory issue #50).

use pendkit_energy::registry;

use pendkit_system::Stage;

// Link through the facade, as the command line does.
use pendkit as _;

#[test]
fn registered_kinds_are_exactly_the_bundled_set() {
    let kinds: Vec<(&str, Stage)> = registry().iter().map(|k| (k.kind(), k.stage())).collect();
    assert_eq!(
        kinds,
        vec![
            ("gravity", Stage::S0A),
            ("point-spring", Stage::S0A),
            ("spring", Stage::S0A),
            ("wire-stretch", Stage::S0A),
            ("optical-spring", Stage::S0B),
            ("wire-torsion", Stage::S1A),
            ("wire-bending", Stage::S1B),
            ("wire-extra-stretch", Stage::S2),
        ]
    );
}
