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
            .filter(|c| c.kind == pendkit_system::CoordKind::Float)
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

/// `GOOD` with a material that has every constant of the loss physics and a wire set that
/// uses them, with `set` (fields of the wire set) and `blades` (a blade set on the support
/// whose tips carry the wires).
fn lossy(set: &str, blades: &str) -> String {
    let text = broken(
        "density = 7800",
        "density = 7800\nloss_angle = 1e-4\nspecific_heat = 486\nconductivity = 49\nthermal_expansion = 12e-6\ndissipation_depth = 1e-3",
    );
    let text = text.replace(
        "upper = { at = [0, 0.1, 0], mirror = \"y\" }",
        "upper = { at = [0, 0, 0] }",
    );
    let text = text.replace(
        "[stages.bob.wires]",
        &format!(
            "[stages.bob.blades]\ntips = {{ at = [0, 0.1, 0], mirror = \"y\" }}\nstiffness = 1e4\nmaterial = \"steel\"\n{blades}\n[stages.bob.wires]"
        ),
    );
    format!("{text}{set}\n")
}

/// Line (from 1) of the first line of `text` that starts with `key`.
fn line_of(text: &str, key: &str) -> usize {
    text.lines().position(|l| l.starts_with(key)).unwrap() + 1
}

#[test]
#[expect(
    clippy::too_many_lines,
    reason = "a table: each loss-physics field made impossible in turn, with the file line, \
              field path and reason its error must name, checked by the one loop below it"
)]
fn loss_physics_fields_build_and_bad_values_name_file_line_and_field() {
    let good = lossy(
        "profile = { neck_length = 0.02, neck_radius = 0.5e-3 }\nsurface_loss = true\ntemperature = 120\ndilution = 50",
        "thickness = 4e-3\ntemperature = 80",
    );
    let s = Suspension::from_text("good.toml", &good, &NoLibrary).unwrap_or_else(|e| panic!("{e}"));
    let (system, _) = build_with(&s, &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(system.wires.len(), 2);
    // each new field, made impossible in turn: zero, negative, not a number, too long
    for (set, blades, key, field, why) in [
        (
            "profile = { neck_length = 0.02, neck_radius = -1e-4 }",
            "",
            "profile",
            "stages.bob.wires.profile.neck_radius",
            "must be positive",
        ),
        (
            "profile = { neck_length = 0.3, neck_radius = 1e-4 }",
            "",
            "profile",
            "stages.bob.wires.profile",
            "half the fibre",
        ),
        (
            "profile = { neck_length = 0.02 }",
            "",
            "profile",
            "stages.bob.wires.profile",
            "needs `neck_radius`",
        ),
        (
            "temperature = 0",
            "",
            "temperature",
            "stages.bob.wires.temperature",
            "must be positive",
        ),
        (
            "dilution = \"0/0\"",
            "",
            "dilution",
            "stages.bob.wires.dilution",
            "not a finite number",
        ),
        (
            "dilution = -3",
            "",
            "dilution",
            "stages.bob.wires.dilution",
            "must be positive",
        ),
        (
            "",
            "thickness = -4e-3",
            "thickness",
            "stages.bob.blades.thickness",
            "must be positive",
        ),
        (
            "",
            "temperature = \"0/0\"",
            "temperature",
            "stages.bob.blades.temperature",
            "not a finite number",
        ),
    ] {
        let text = lossy(set, blades);
        let line = if set.is_empty() {
            // the blades' field: after the `[stages.bob.blades]` line
            let from = line_of(&text, "[stages.bob.blades]");
            from + 1
                + text
                    .lines()
                    .skip(from)
                    .position(|l| l.starts_with(key))
                    .unwrap()
        } else {
            line_of(&text, key)
        };
        starts(&text, &format!("bad.toml:{line}: {field}: "), why);
    }
    // violin beads on a tapered fibre: each wire is 3 segments (slices of the profile)
    let beaded = lossy(
        "profile = { neck_length = 0.02, neck_radius = 0.5e-3 }\nbeads = 2",
        "",
    );
    let s =
        Suspension::from_text("beaded.toml", &beaded, &NoLibrary).unwrap_or_else(|e| panic!("{e}"));
    let (system, _) = build_with(&s, &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(system.wires.len(), 2 * 3);
    // surface loss needs the material's dissipation depth
    let text = lossy("surface_loss = true", "").replace("\ndissipation_depth = 1e-3", "");
    starts(&text, "bad.toml:", "dissipation_depth");
    // a given dilution at the stage, not its wires, is pointed to them
    let text = lossy("", "").replace(
        "[stages.bob]\nfrom = \"support\"",
        "[stages.bob]\nfrom = \"support\"\ndilution = 50",
    );
    starts(
        &text,
        &format!(
            "bad.toml:{}: stages.bob.dilution: ",
            line_of(&text, "dilution")
        ),
        "wires or fibres",
    );
}

#[test]
fn number_literals_an_f64_cannot_hold_are_refused_at_reading() {
    // a nonzero literal below 2.2e-308 would read as 0 (or a subnormal): named where written
    starts(
        &broken("radius = 0.3e-3", "radius = 0.3e-400"),
        "bad.toml:20: stages.bob.wires.radius: ",
        "number '0.3e-400' is too small",
    );
    starts(
        &broken("density = 7800", "density = \"2*1e-320\""),
        "bad.toml:6: materials.steel.density: ",
        "number '1e-320' is too small",
    );
    starts(
        &broken("{ value = 40,", "{ value = 40, allowed = [40, 1e-400],"),
        "bad.toml:2: parameters.m.allowed: ",
        "too small",
    );
    starts(
        &broken("{ value = 40,", "{ value = \"4e999\","),
        "bad.toml:2: parameters.m.value: ",
        "too large",
    );
    starts(
        &broken("youngs_modulus = 200e9", "youngs_modulus = 200e999"),
        "bad.toml:4: materials.steel.youngs_modulus: ",
        "number '200e999' is too large",
    );
    // zero written with a huge exponent is zero: the file reads (and fails later, for the
    // zero radius it is)
    starts(
        &broken("radius = 0.3e-3", "radius = 0e-400"),
        "bad.toml:16: stages.bob.wires: ",
        "stiffness 0 N/m must be positive (check the wire's radius",
    );
}
