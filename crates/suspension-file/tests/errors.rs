//! Every error in a suspension file names the file, the line and the field: bad files, each
//! with one mistake, and the place the error must point at (read off the text here).

use pendkit_model::{Overrides, build_with};
use pendkit_suspension::{NoLibrary, Suspension};

/// A valid one-stage file; each test breaks one line of it. Line numbers below count from
/// the `[parameters]` line as line 1.
const GOOD: &str = r#"[parameters]
m = { value = 40, unit = "kg", description = "the bob" }
[materials.steel]
youngs_modulus = 200e9
poisson_ratio = 0.29
density = 7800
[bodies.support]
coordinates = "0"
driven = true
[bodies.bob]
coordinates = "1"
mass = "m"
inertia = [1, 1, 1]
[stages.bob]
from = "support"
[stages.bob.wires]
upper = { at = [0, 0.1, 0], mirror = "y" }
lower = { at = [0, 0.1, 0.01], mirror = "y" }
length = 0.5
radius = 0.3e-3
material = "steel"
"#;

/// The one-line error of reading and building `text` as `bad.toml`.
fn error_of(text: &str) -> String {
    let message = match Suspension::from_text("bad.toml", text, &NoLibrary) {
        Err(e) => e.to_string(),
        Ok(s) => match build_with(&s, &Overrides::default()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("the file built"),
        },
    };
    assert!(!message.contains('\n'), "{message}");
    message
}

/// `GOOD` with `from` replaced by `to` (which must occur once).
fn broken(from: &str, to: &str) -> String {
    assert_eq!(GOOD.matches(from).count(), 1, "{from}");
    GOOD.replace(from, to)
}

#[track_caller]
fn starts(text: &str, prefix: &str, also: &str) {
    let e = error_of(text);
    assert!(e.starts_with(prefix) && e.contains(also), "{e}");
}

#[test]
fn the_good_file_builds() {
    let s = Suspension::from_text("good.toml", GOOD, &NoLibrary).unwrap();
    let (system, _) = build_with(&s, &Overrides::default()).unwrap();
    assert_eq!(system.wires.len(), 2);
}

#[test]
fn reading_errors_name_file_line_and_field() {
    starts(
        &broken("coordinates = \"1\"\nmass", "coordinates = \"1\"\nmas"),
        "bad.toml:12: bodies.bob.mas: ",
        "did you mean `mass`",
    );
    starts(
        &broken("mass = \"m\"", "mass = \"m*\""),
        "bad.toml:12: bodies.bob.mass: ",
        "expected an expression",
    );
    starts(
        &broken("inertia = [1, 1, 1]", "inertia = [1, 1]"),
        "bad.toml:13: bodies.bob.inertia: ",
        "expected 3 entries",
    );
    starts(
        &broken("radius = 0.3e-3\n", ""),
        "bad.toml:16: stages.bob.wires: ",
        "needs `radius`",
    );
    starts(
        &broken("[stages.bob.wires]", "[stages.bob.wires"),
        "bad.toml:16: ",
        "",
    );
    starts(
        &broken("mirror = \"y\" }\nlength", "mirror = \"w\" }\nlength"),
        "bad.toml:18: stages.bob.wires.lower.mirror: ",
        "cannot mirror across 'w'",
    );
    starts(
        &broken("{ value = 40,", "{ value = \"2*n\","),
        "bad.toml:2: parameters.m: ",
        "n",
    );
    starts(
        &broken("material = \"steel\"", "material = \"stell\""),
        "bad.toml:21: stages.bob.wires.material: ",
        "unknown material 'stell' (materials: steel)",
    );
}

#[test]
fn building_errors_name_file_line_and_field() {
    starts(
        &broken("mass = \"m\"", "mass = \"mm\""),
        "bad.toml:12: bodies.bob.mass: ",
        "unknown parameter 'mm'",
    );
    starts(
        &broken("from = \"support\"", "from = \"suport\""),
        "bad.toml:15: stages.bob.from: ",
        "unknown body 'suport'",
    );
    starts(
        &broken("length = 0.5", "length = -0.5"),
        "bad.toml:19: stages.bob.wires.length: ",
        "must be positive",
    );
    starts(
        &broken("from = \"support\"", "from = \"bob\""),
        "bad.toml:15: stages.bob.from: ",
        "write the bodies from the top down",
    );
}

#[test]
fn extends_errors_name_the_file() {
    let e = Suspension::from_text("loop.toml", "extends = \"quad\"\n", &NoLibrary).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("loop.toml:1: extends: no file 'quad'"),
        "{e}"
    );
}

#[test]
fn bead_joints_are_clamped_or_hinged() {
    let with = |joints: &str| {
        broken(
            "material = \"steel\"\n",
            &format!("material = \"steel\"\nbeads = 2\nbead_joints = {joints}\n"),
        )
    };
    let floats = |text: &str| {
        let s = Suspension::from_text("beads.toml", text, &NoLibrary).unwrap();
        let (system, _) = build_with(&s, &Overrides::default()).unwrap();
        // 2 wires of 3 segments each
        assert_eq!(system.wires.len(), 6);
        system
            .coords
            .iter()
            .filter(|c| c.kind == pendkit_energy::CoordKind::Float)
            .count()
    };
    // clamped: each bead's joint has three orientation floats; hinged: none
    assert_eq!(floats(&with("\"clamped\"")), 2 * 2 * 3);
    assert_eq!(floats(&with("\"hinged\"")), 0);
    starts(
        &with("\"welded\""),
        "bad.toml:23: stages.bob.wires.bead_joints: ",
        "expected \"clamped\" or \"hinged\"",
    );
}
