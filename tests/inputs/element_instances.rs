//! `[[element]]` instances that do not fit their kind are refused before anything is built,
//! with one line naming the file, the line, the instance's field, the kind and what the
//! kind accepts; `extends` carries instances along.

use std::path::Path;

use pendkit::Case;

/// The hinged bob with one `[[element]]` whose body lines are `instance`.
fn file(instance: &str) -> String {
    let mut text = pendkit_tests::hinged_bob(
        r#"m = { value = 40, unit = "kg", description = "the bob" }
k_magnet = { value = 100, unit = "N/m", description = "the magnet's stiffness" }"#,
        0.6,
    );
    text.push_str("\n[[element]]\n");
    text.push_str(instance);
    text
}

/// The one-line error of building `instance`.
fn error(instance: &str) -> String {
    let text = file(instance);
    let e = match Case::from_text(Path::new("magnet.toml"), &text) {
        Err(e) => e.to_string(),
        Ok(case) => match case.build() {
            Err(e) => e.to_string(),
            Ok(_) => panic!("built: {instance}"),
        },
    };
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

const GOOD: &str = r#"kind = "point-spring"
name = "coil"
between = ["bob", "support"]
points = [[0, 0, 0], [0, 0, 0]]
values = { k = "k_magnet" }
"#;

#[test]
fn a_fitting_instance_builds_with_its_tag() {
    let case = Case::from_text(Path::new("magnet.toml"), &file(GOOD)).unwrap();
    let (system, _) = case.build().unwrap();
    let e = &system.plugin_elements[0];
    assert_eq!((e.kind.as_str(), e.name.as_str()), ("point-spring", "coil"));
    assert_eq!(e.values["k"], 100.0);
    // no tag given: the instance's name
    assert_eq!(e.tag, "coil");
}

#[test]
fn each_misfit_is_one_line_naming_file_line_kind_and_field() {
    // (the instance, the field the error names, what it says)
    let cases = [
        (
            GOOD.replace("\"point-spring\"", "\"point-sprung\""),
            "element.coil.kind",
            "element kind 'point-sprung' is not registered; kinds with instances: ",
        ),
        (
            GOOD.replace("\"point-spring\"", "\"wire-bending\""),
            "element.coil.kind",
            "element kind 'wire-bending' owns no instances",
        ),
        (
            GOOD.replace(
                "values = { k = \"k_magnet\" }",
                "values = { k = \"k_magnet\", c = 1 }",
            ),
            "element.coil.values.c",
            "point-spring 'coil': unknown value 'c' (it takes 2 bodies, 2 points, values k (N/m, ",
        ),
        (
            GOOD.replace("values = { k = \"k_magnet\" }", "values = { }"),
            "element.coil.values",
            "point-spring 'coil': needs the value 'k' (N/m",
        ),
        (
            GOOD.replace("\"support\"]", "\"suport\"]"),
            "element.coil.between",
            "point-spring 'coil': unknown body 'suport' (bodies: support, bob)",
        ),
        (
            GOOD.replace("[\"bob\", \"support\"]", "[\"bob\"]"),
            "element.coil.between",
            "point-spring 'coil': needs 2 bodies, got 1 (it takes 2 bodies, 2 points",
        ),
        (
            GOOD.replace("[[0, 0, 0], [0, 0, 0]]", "[[0, 0, 0]]"),
            "element.coil.points",
            "point-spring 'coil': needs 2 points, got 1",
        ),
        (
            GOOD.replace("\"k_magnet\"", "\"k_magnet/0\""),
            "element.coil.values.k",
            // the expression itself is refused (k's domain, finite, is never reached)
            "`k_magnet/0` = inf is not a finite number",
        ),
        (
            GOOD.replace("name = \"coil\"\n", "name = \"coil\"\ncolour = 1\n"),
            "element.coil.colour",
            "unknown field",
        ),
    ];
    for (instance, field, expected) in cases {
        let e = error(&instance);
        assert!(e.starts_with("magnet.toml:"), "{e}");
        let line = e.split(':').nth(1).unwrap_or_default();
        assert!(line.parse::<usize>().is_ok(), "names the line: {e}");
        assert!(e.contains(&format!(": {field}: ")), "names {field}: {e}");
        assert!(e.contains(expected), "{expected:?} in {e}");
    }
}
