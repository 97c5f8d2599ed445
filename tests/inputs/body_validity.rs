//! Bodies that no rigid body can be, and names that no signal can address, are refused
//! where they are written (issue 38, part 4): principal moments of inertia that break the
//! triangle inequality (I₃ > I₁ + I₂, beyond `INERTIA_TRIANGLE_TOLERANCE` for the rounding of
//! a thin plate's written moments), and body names, aliases and coordinate names a point
//! signal `<body>@x,y,z/dx,dy,dz` or an expression cannot hold. Names that can be addressed,
//! however unusual, are accepted and addressed.

use std::path::Path;

use nalgebra::{Matrix3, Rotation3, Vector3};
use pendkit::Case;
use pendkit::model::{BodySpec, INERTIA_TRIANGLE_TOLERANCE, SystemBuilder, check_inertia};

const EXAMPLE: &str = include_str!("../../examples/three-stage.toml");

/// The example with `from` replaced by `to` (which must occur).
fn edited(pairs: &[(&str, &str)]) -> String {
    let mut text = EXAMPLE.to_string();
    for (from, to) in pairs {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    text
}

/// The line (from 1) of `text` holding `needle` first.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// The one-line error of reading and building `text` (called `s.toml`).
fn error(text: &str) -> String {
    let e = match Case::from_text(Path::new("s.toml"), text) {
        Err(e) => e.to_string(),
        Ok(case) => match case.build() {
            Err(e) => e.to_string(),
            Ok(_) => panic!("built"),
        },
    };
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

/// The example with its middle body called `name` everywhere it is named.
fn renamed(name: &str) -> String {
    edited(&[
        ("[bodies.middle]", &format!("[bodies.\"{name}\"]")),
        ("[stages.middle]", &format!("[stages.\"{name}\"]")),
        (
            "[stages.middle.wires]",
            &format!("[stages.\"{name}\".wires]"),
        ),
        ("from = \"middle\"", &format!("from = \"{name}\"")),
        ("middle = \"M2\"", &format!("\"{name}\" = \"M2\"")),
    ])
}

/// Whether `text` reads and builds.
fn builds(text: &str) -> bool {
    Case::from_text(Path::new("s.toml"), text).is_ok_and(|c| c.build().is_ok())
}

#[test]
fn moments_no_rigid_body_has_are_refused_at_the_field_naming_the_body() {
    let text = edited(&[(
        "mass = \"m_top\"\ninertia = [0.1, 0.1, 0.1]",
        "mass = \"m_top\"\ninertia = [0.1, 0.3, 0.1]",
    )]);
    let line = line_of(&text, "inertia = [0.1, 0.3, 0.1]");
    assert_eq!(
        error(&text),
        format!(
            "s.toml:{line}: bodies.top.inertia: body 'top': principal moments of inertia 0.1, 0.1, 0.3 kg m^2 break the triangle inequality: 0.3 > 0.1 + 0.1 (no rigid body has one moment larger than the other two together; a thin plate has them equal)"
        )
    );
    // a full tensor: the principal moments are its eigenvalues, whatever the axes
    let turn = Rotation3::from_euler_angles(0.3, -0.2, 0.7).into_inner();
    let tensor = turn * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 2.5)) * turn.transpose();
    let rows: Vec<String> = (0..3)
        .map(|i| {
            let row: Vec<String> = (0..3).map(|j| format!("{:e}", tensor[(i, j)])).collect();
            format!("[{}]", row.join(", "))
        })
        .collect();
    let text = edited(&[(
        "mass = \"m_mid\"\ninertia = [0.1, 0.1, 0.1]",
        &format!("mass = \"m_mid\"\ninertia = [{}]", rows.join(", ")),
    )]);
    let e = error(&text);
    assert!(
        e.contains("bodies.middle.inertia: body 'middle': principal moments of inertia")
            && e.contains("break the triangle inequality"),
        "{e}"
    );
}

#[test]
fn a_thin_plate_is_accepted_as_computed_and_as_rounded_but_no_thinner() {
    // a plate 0.4 m x 0.3 m: I_x = m b^2/12, I_y = m a^2/12, I_z = m (a^2 + b^2)/12 exactly
    // at the triangle's edge, computed two ways by the expressions
    let plate = "inertia = [\"m_top*0.3^2/12\", \"m_top*0.4^2/12\", \"m_top*(0.4^2 + 0.3^2)/12\"]";
    assert!(builds(&edited(&[(
        "mass = \"m_top\"\ninertia = [0.1, 0.1, 0.1]",
        &format!("mass = \"m_top\"\n{plate}")
    )])));
    // the same plate written to six significant digits with the last digit of I_z off by
    // one (0.208334 for 0.2083333: 4.8e-6 of I_z over the others' sum)
    assert!(builds(&edited(&[(
        "mass = \"m_top\"\ninertia = [0.1, 0.1, 0.1]",
        "mass = \"m_top\"\ninertia = [0.075, 0.133333, 0.208334]"
    )])));
    // thinner than flat by more than the tolerance: refused
    let over = 0.208333333 * (1.0 + 3.0 * INERTIA_TRIANGLE_TOLERANCE);
    let e = error(&edited(&[(
        "mass = \"m_top\"\ninertia = [0.1, 0.1, 0.1]",
        &format!("mass = \"m_top\"\ninertia = [0.075, 0.1333333333, {over}]"),
    )]));
    assert!(e.contains("break the triangle inequality"), "{e}");
}

#[test]
fn an_override_that_makes_a_body_impossible_is_refused_at_the_inertia() {
    // the optic's axial moment with a parameter added to it: 0 is the cylinder, 1 kg m^2
    // makes it 1.16 kg m^2 beside two of 0.095 kg m^2, which no body has
    let text = edited(&[(
        "inertia = [\"m_optic*r_optic^2/2\",",
        "inertia = [\"m_optic*r_optic^2/2 + extra\",",
    )])
    .replace(
        "[parameters]\n",
        "[parameters]\nextra = { value = 0, unit = \"kg m^2\", description = \"added axial moment\" }\n",
    );
    let case = Case::from_text(Path::new("s.toml"), &text).unwrap();
    assert!(case.build().is_ok());
    let e = case
        .with_sets(&["extra=1".to_string()])
        .unwrap()
        .build()
        .expect_err("refused")
        .to_string();
    let line = line_of(&text, "inertia = [\"m_optic*r_optic^2/2 + extra\"");
    assert!(
        e.contains(&format!(
            "s.toml:{line}: bodies.optic.inertia: body 'optic': principal moments of inertia"
        )) && e.contains("kg m^2 break the triangle inequality"),
        "{e}"
    );
}

#[test]
fn check_inertia_takes_zero_plates_and_bodies_and_refuses_the_impossible() {
    let diag = |a: f64, b: f64, c: f64| Matrix3::from_diagonal(&Vector3::new(a, b, c));
    assert!(check_inertia("body 'p'", &Matrix3::zeros()).is_ok());
    assert!(check_inertia("body 'p'", &diag(1.0, 2.0, 3.0)).is_ok());
    assert!(check_inertia("body 'p'", &diag(0.5, 0.5, 0.5)).is_ok());
    assert!(check_inertia("body 'p'", &diag(1.0, 2.0, 3.0 * (1.0 + 2e-5))).is_err());
    // the same through the builder, which every model goes through
    let mut b = SystemBuilder::new(9.81);
    let e = b
        .body(BodySpec::new("rod").mass(1.0).inertia(diag(1.0, 1.0, 3.0)))
        .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("body 'rod': principal moments of inertia 1, 1, 3 kg m^2"),
        "{e}"
    );
}

#[test]
fn names_no_signal_can_address_are_refused_where_they_are_written() {
    // a body whose name holds '@', ':' or surrounding spaces
    for (name, why) in [
        ("mid@dle", "'@' ends a body's name in a point signal"),
        ("mid:dle", "':' separates `force:`"),
        (" middle", "spaces around it are trimmed"),
    ] {
        let text = renamed(name);
        let line = line_of(&text, &format!("[bodies.\"{name}\"]"));
        let e = error(&text);
        assert!(
            e.starts_with(&format!(
                "s.toml:{line}: bodies.{name}: body name \"{name}\": {why}"
            )),
            "{e}"
        );
    }
    // an alias of a naming scheme, addressed as a body is
    let text = edited(&[("optic = \"M3\"", "optic = \"M@3\"")]);
    let e = error(&text);
    assert!(
        e.contains("names.ligo.bodies.optic: body name \"M@3\"") && e.contains("'@'"),
        "{e}"
    );
    // coordinates an expression cannot hold: a suffix, and beads named after a wire
    let e = error(&edited(&[("coordinates = \"3\"", "coordinates = \"3-a\"")]));
    assert!(
        e.contains("bodies.optic.coordinates: '3-a' does not make usable coordinate names"),
        "{e}"
    );
    let e = error(&edited(&[("name = \"f\"\n", "name = \"f-\"\nbeads = 1\n")]));
    assert!(
        e.contains("stages.optic.fibres: coordinate name \"xf-1b1\""),
        "{e}"
    );
}

#[test]
fn unusual_names_a_signal_can_address_are_accepted_and_addressed() {
    // a space inside, a dash, a slash: a point signal reads the body up to its '@'
    let name = "mid dle-2/b";
    let text = renamed(name);
    let case = Case::from_text(Path::new("s.toml"), &text).unwrap();
    let (system, _) = case.build().unwrap();
    let r = pendkit::run_stage(system, pendkit::Stage::S2).unwrap();
    // the body's x through a point at its centre: the coordinate x2 itself
    let through_point = r
        .transfer("x0", &format!("{name}@0,0,0/1,0,0"), &[1.0])
        .unwrap()[0];
    let direct = r.transfer("x0", "x2", &[1.0]).unwrap()[0];
    assert!(
        (through_point - direct).norm() <= 1e-12 * direct.norm(),
        "{through_point} vs {direct}"
    );
}
