//! Scenes (`[[include]]`, docs/suspension-files.md "Scenes") that are wrong are refused with
//! one line naming the file, the line and the field: a prefix that is empty or does not
//! start a name, a name defined twice once prefixed, an include that goes round in a
//! circle, a model that does not exist, included suspensions whose gravities differ. And
//! what a scene names is prefixed: coordinates, parameters, tags, signals, name schemes.

use std::path::Path;

use pendkit::Case;

/// The error of reading (or else building) the scene `text`, called `scene.toml`.
fn error(text: &str) -> String {
    let e = match Case::from_text(Path::new("scene.toml"), text) {
        Err(e) => e.to_string(),
        Ok(case) => match case.build() {
            Err(e) => e.to_string(),
            Ok(_) => panic!("built: {text}"),
        },
    };
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

/// A scene including the pendulum under `a` and `b`, then `rest`.
fn two(a: &str, b: &str, rest: &str) -> String {
    format!(
        "[[include]]\nmodel = \"pendulum\"\nprefix = \"{a}\"\n\n\
         [[include]]\nmodel = \"pendulum\"\nprefix = \"{b}\"\n{rest}"
    )
}

#[test]
fn bad_prefixes_are_refused_at_their_line() {
    for (prefix, what) in [
        ("", "'' is not a valid prefix"),
        ("1a_", "'1a_' is not a valid prefix"),
        ("a.b", "'a.b' is not a valid prefix"),
    ] {
        let e = error(&two("a_", prefix, ""));
        assert!(
            e.contains(&format!("scene.toml:7: include[1].prefix: {what}")),
            "{e}"
        );
    }
    let e = error(&two("a_", "a_", ""));
    assert!(
        e.contains(
            "scene.toml:7: include[1].prefix: prefix 'a_' is already used by the include at line 1"
        ),
        "{e}"
    );
    let e = error("[[include]]\nmodel = \"pendulum\"\n");
    assert!(
        e.contains("scene.toml:1: include[0]: needs `prefix`"),
        "{e}"
    );
    let e = error("[[include]]\nmodel = \"pendulum\"\nprefix = \"a_\"\npefix = 1\n");
    assert!(
        e.contains("scene.toml:4: include[0].pefix: unknown field; did you mean `prefix`?"),
        "{e}"
    );
}

#[test]
fn a_name_defined_twice_after_prefixing_is_refused() {
    // the scene's own body with an included body's prefixed name
    let e = error(&two(
        "a_",
        "b_",
        "\n[bodies.a_mass1]\ncoordinates = \"9\"\nmass = 1\n",
    ));
    assert!(
        e.contains("scene.toml:9: bodies.a_mass1: name collision: body 'a_mass1' is defined twice"),
        "{e}"
    );
    // the scene's own material named as an included one
    let e = error(&two(
        "a_",
        "b_",
        "\n[materials.b_silica]\nyoungs_modulus = 1e9\n",
    ));
    assert!(
        e.contains("scene.toml:9: materials.b_silica: name collision: material 'b_silica'"),
        "{e}"
    );
}

#[test]
fn an_unknown_model_is_refused_at_its_line() {
    let e = error("[[include]]\nmodel = \"pendulm\"\nprefix = \"a_\"\n");
    assert!(
        e.contains("scene.toml:2: include[0].model: no file 'pendulm' (a bundled model name, or a path ending in .toml)"),
        "{e}"
    );
}

/// The error of reading `files[0]` of `files` (name, text), written to a folder of their
/// own (includes name files beside the scene).
fn error_on_disk(test: &str, files: &[(&str, &str)]) -> String {
    let dir = std::env::temp_dir().join(format!("pendkit-scenes-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let e = match Case::from_file(&dir.join(files[0].0)) {
        Err(e) => e.to_string(),
        Ok(case) => match case.build() {
            Err(e) => e.to_string(),
            Ok(_) => panic!("built {files:?}"),
        },
    };
    std::fs::remove_dir_all(&dir).ok();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn two_includes_that_make_one_name_are_refused_at_the_second() {
    // `x_m1` included as `a_` is the pendulum's `m1` included as `a_x_`
    let e = error_on_disk(
        "collision",
        &[
            (
                "scene.toml",
                "[[include]]\nmodel = \"other.toml\"\nprefix = \"a_\"\n\
                 [[include]]\nmodel = \"pendulum\"\nprefix = \"a_x_\"\n",
            ),
            ("other.toml", "[parameters]\nx_m1 = 3\n"),
        ],
    );
    assert!(
        e.contains("scene.toml:6: include[1].prefix: name collision: parameter 'a_x_m1' is defined twice in the scene ("),
        "{e}"
    );
    assert!(
        e.contains("other.toml:2 and models/basic/pendulum.toml:"),
        "{e}"
    );
}

#[test]
fn an_include_that_goes_round_in_a_circle_is_refused() {
    let include = |other: &str| format!("[[include]]\nmodel = \"{other}\"\nprefix = \"x_\"\n");
    let e = error_on_disk(
        "circle",
        &[
            ("one.toml", &include("two.toml")),
            ("two.toml", &include("one.toml")),
        ],
    );
    assert!(
        e.contains("two.toml:2: include[0].model: include goes round in a circle: "),
        "{e}"
    );
    assert!(e.contains("one.toml -> "), "{e}");
}

#[test]
fn included_suspensions_under_different_gravities_are_refused() {
    // quad-aligo's gravity is 9.80665 m/s^2, the pendulum's 9.81: one scene, one gravity
    let e = error(
        "[[include]]\nmodel = \"quad-aligo\"\nprefix = \"a_\"\n\
         [[include]]\nmodel = \"pendulum\"\nprefix = \"b_\"\n",
    );
    assert!(
        e.contains("pendulum.toml:5: gravity: the suspension included as 'b_' has gravity 9.81 m/s^2, the scene 9.80665 m/s^2"),
        "{e}"
    );
    // the scene's own gravity holds for both
    let text = "gravity = 9.81\n[[include]]\nmodel = \"quad-aligo\"\nprefix = \"a_\"\n\
         [[include]]\nmodel = \"pendulum\"\nprefix = \"b_\"\n";
    Case::from_text(Path::new("scene.toml"), text)
        .unwrap()
        .build()
        .unwrap();
}

#[test]
fn every_name_an_included_suspension_makes_carries_its_prefix() {
    let text = "gravity = 9.81\n[[include]]\nmodel = \"quad\"\nprefix = \"itm_\"\n\
                [[include]]\nmodel = \"quad-aligo\"\nprefix = \"etm_\"\n";
    let case = Case::from_text(Path::new("scene.toml"), text).unwrap();
    let (system, params) = case.build().unwrap();
    let coords: Vec<&str> = system.coords.iter().map(|c| c.name.as_str()).collect();
    for name in ["itm_x0", "itm_pitch3", "etm_pitch3", "itm_zb0l", "etm_zb0l"] {
        assert!(coords.contains(&name), "{name} in {coords:?}");
    }
    assert!(
        coords
            .iter()
            .all(|c| c.starts_with("itm_") || c.starts_with("etm_")),
        "{coords:?}"
    );
    // parameters: prefixed, but for the built-in ones every model shares
    assert_eq!(params.get("itm_m3").unwrap(), 39.6);
    assert!(params.get("m3").is_err());
    assert!(params.get("temperature").is_ok());
    assert!(params.get("etm_temperature").is_err());
    // damping tags, signals and the LIGO names
    let tags = system.tags();
    assert!(tags.contains("etm_fibre_bending"), "{tags:?}");
    // all but the system's own tags of gravity and of the constraints
    assert!(
        tags.iter()
            .filter(|t| !["gravity", "constraint"].contains(&t.as_str()))
            .all(|t| t.starts_with("itm_") || t.starts_with("etm_")),
        "{tags:?}"
    );
    let outputs: Vec<&str> = system.outputs.iter().map(|s| s.name.as_str()).collect();
    assert!(outputs.contains(&"etm_tm_beam"), "{outputs:?}");
    let ligo = &system.name_schemes["ligo"];
    assert_eq!(ligo.coords["itm_pitch3"], "itm_L3_P");
    assert_eq!(ligo.coords["etm_pitch3"], "etm_L3_P");
}
