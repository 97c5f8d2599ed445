//! The size limits (docs/checks-and-refusals.md, "Limits"; `pendkit_limits`): every
//! expansion a file or a call asks for is counted before it is made and refused past its
//! limit with one line naming what, how many, the limit and the variable that raises it.
//! Each test here is a refusal before the work, so each takes milliseconds and little
//! memory however large the request: a test that took long would mean the count came after
//! the work.
//!
//! The variables themselves are not set here (a process reads each once): the command-line
//! tests run the program with them (`crates/interface/cli/tests/cli/limits.rs`).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use nalgebra::Vector3;
use pendkit::{Case, Error};
use pendkit_model::{BodySpec, SystemBuilder};
use pendkit_system::{EndDirection, Wire, WireEnd, WireSection, WireTags};

/// The three-stage example with its fibres' attachment points replaced by `upper` and
/// `lower` (point sets, as a file writes them).
fn three_stage(upper: &str, lower: &str) -> String {
    let text = include_str!("../../examples/three-stage.toml");
    let upper_was = r#"upper = { at = [0.01, 0.13, -0.05], mirror = ["x", "y"] }"#;
    let lower_was = r#"lower = { at = [0.01, 0.13, "breakoff"], mirror = ["x", "y"] }"#;
    assert!(text.contains(upper_was) && text.contains(lower_was));
    text.replace(upper_was, &format!("upper = {upper}"))
        .replace(lower_was, &format!("lower = {lower}"))
}

/// The line (from 1) of `text` that holds `needle` first.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// Reads and builds the suspension `text` (called `s.toml`), which must be refused within
/// half a second; the one-line error.
#[track_caller]
fn refused_quickly(text: &str) -> String {
    let start = Instant::now();
    let e = match Case::from_text(Path::new("s.toml"), text) {
        Err(e) => e.to_string(),
        Ok(case) => match case.build() {
            Err(e) => e.to_string(),
            Ok(_) => panic!("built"),
        },
    };
    assert!(
        start.elapsed() < Duration::from_millis(500),
        "took {:?}: {e}",
        start.elapsed()
    );
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

#[test]
fn a_mirror_across_an_axis_twice_is_refused_before_any_point_is_made() {
    // 30 mirrors across x asked for 2^30 wires: 3.2 GB before this check
    let thirty = format!("[{}]", vec!["\"x\""; 30].join(", "));
    let upper = format!("{{ at = [0.01, 0.13, -0.05], mirror = {thirty} }}");
    let lower = format!("{{ at = [0.01, 0.13, \"breakoff\"], mirror = {thirty} }}");
    let text = three_stage(&upper, &lower);
    let e = refused_quickly(&text);
    let line = line_of(
        &text,
        "upper = { at = [0.01, 0.13, -0.05], mirror = [\"x\", \"x\"",
    );
    assert_eq!(
        e,
        format!(
            "s.toml:{line}: stages.optic.fibres.upper.mirror: 'x' is given twice: mirroring across an axis again puts every point on one already there (mirror across each axis once)"
        )
    );
}

#[test]
fn more_points_in_a_set_than_the_limit_are_refused_naming_it_and_its_variable() {
    let limit = pendkit_limits::WIRES_PER_SET.default;
    // a list one past the limit, counted before any point is read
    let points = |z: &str| {
        let one = format!("[0.01, 0.13, {z}]");
        format!("{{ points = [{}] }}", vec![one; limit + 1].join(", "))
    };
    let text = three_stage(&points("-0.05"), &points("\"breakoff\""));
    let e = refused_quickly(&text);
    let line = line_of(&text, "upper = { points");
    assert_eq!(
        e,
        format!(
            "s.toml:{line}: stages.optic.fibres.upper.points: {} parts in one set (wires, blades or springs): more than the limit of {limit} (set PENDKIT_MAX_WIRES_PER_SET to raise it)",
            limit + 1
        )
    );
    // within the limit, mirrored past it: counted from the list and the mirrors
    let base = limit / 4 + 1;
    let mirrored = |z: &str| {
        let list: Vec<String> = (0..base)
            .map(|k| format!("[{}, 0.13, {z}]", 0.01 + 1e-4 * k as f64))
            .collect();
        format!("{{ points = [{}], mirror = \"xy\" }}", list.join(", "))
    };
    let e = refused_quickly(&three_stage(&mirrored("-0.05"), &mirrored("\"breakoff\"")));
    assert!(
        e.contains(&format!(
            "stages.optic.fibres.upper.mirror: {} parts in one set",
            4 * base
        )) && e.contains("PENDKIT_MAX_WIRES_PER_SET"),
        "{e}"
    );
}

/// A scratch folder for this test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("limits-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn files_are_read_only_if_regular_and_within_the_size_limit() {
    let dir = scratch("files");
    let case_error = |path: &Path| match Case::from_file(path) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("{} read", path.display()),
    };
    // a directory named like a suspension file
    let folder = dir.join("folder.toml");
    std::fs::create_dir_all(&folder).unwrap();
    let e = case_error(&folder);
    assert!(
        e.starts_with(&format!("case file {}: ", folder.display()))
            && e.contains("not a regular file (a directory)"),
        "{e}"
    );
    // a link to a device that never ends: read until memory ran out (2 GB in 2.7 s)
    #[cfg(unix)]
    {
        let link = dir.join("zero.toml");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let start = Instant::now();
        let e = case_error(&link);
        assert!(start.elapsed() < Duration::from_millis(100), "{e}");
        assert!(e.contains("not a regular file (a character device)"), "{e}");
    }
    // one byte past the limit (a sparse file: nothing is written, nothing is read)
    let big = dir.join("big.toml");
    let file = std::fs::File::create(&big).unwrap();
    let limit = pendkit_limits::FILE_BYTES.default;
    file.set_len(limit as u64 + 1).unwrap();
    let e = case_error(&big);
    assert!(
        e.contains(&format!(
            "{} bytes in one input file: more than the limit of {limit} (set PENDKIT_MAX_FILE_BYTES to raise it)",
            limit + 1
        )),
        "{e}"
    );
    // a file that extends one of them names the extends and the file
    let extends = dir.join("extends.toml");
    std::fs::write(&extends, "extends = \"folder.toml\"\n").unwrap();
    let e = case_error(&extends);
    assert!(
        e.contains("extends.toml:1: extends: cannot read") && e.contains("a directory"),
        "{e}"
    );
}

#[test]
fn includes_that_fan_out_are_counted_before_they_are_read() {
    // each level includes the next twice: 2^10 reads at level 10, refused at the limit
    let dir = scratch("fan-out");
    let levels = 10;
    for k in 0..levels {
        let next = if k + 1 == levels {
            "pendulum".to_string()
        } else {
            format!("level{}.toml", k + 1)
        };
        let text = format!(
            "[[include]]\nmodel = \"{next}\"\nprefix = \"a_\"\n\n[[include]]\nmodel = \"{next}\"\nprefix = \"b_\"\n"
        );
        std::fs::write(dir.join(format!("level{k}.toml")), text).unwrap();
    }
    let start = Instant::now();
    let e = Case::from_file(&dir.join("level0.toml"))
        .err()
        .expect("refused")
        .to_string();
    assert!(start.elapsed() < Duration::from_millis(500), "{e}");
    let limit = pendkit_limits::INCLUDED_FILES.default;
    assert!(
        e.contains(&format!(
            "].model: {} files extended or included by one suspension: more than the limit of {limit} (set PENDKIT_MAX_INCLUDED_FILES to raise it)",
            limit + 1
        )) && e.contains(": include["),
        "{e}"
    );
    // a chain of files each extending the next, deeper than any suspension needs
    let depth = pendkit::suspension::MAX_FILE_DEPTH + 5;
    for k in 0..depth {
        let text = if k + 1 == depth {
            "extends = \"pendulum\"\n".to_string()
        } else {
            format!("extends = \"chain{}.toml\"\n", k + 1)
        };
        std::fs::write(dir.join(format!("chain{k}.toml")), text).unwrap();
    }
    let e = Case::from_file(&dir.join("chain0.toml"))
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains(&format!(
            "extends: `extends` and includes nested {} deep: at most {}",
            pendkit::suspension::MAX_FILE_DEPTH + 1,
            pendkit::suspension::MAX_FILE_DEPTH
        )) && !e.contains('\n'),
        "{e}"
    );
}

/// A builder with a support and a 10 kg point mass.
fn point_mass() -> (SystemBuilder, [usize; 2]) {
    let mut b = SystemBuilder::new(9.81);
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    for (n, v) in [("x1", 0.0), ("y1", 0.0), ("z1", -1.0)] {
        b.variable(n, v).unwrap();
    }
    let bob = b
        .body(
            BodySpec::new("bob")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(10.0),
        )
        .unwrap();
    (b, [support, bob])
}

#[test]
fn a_builder_stops_at_the_wire_body_and_coordinate_limits() {
    let (mut b, [support, bob]) = point_mass();
    let hinge = |body| WireEnd {
        body,
        point: Vector3::zeros(),
        direction: EndDirection::Hinged,
    };
    let tags = WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    };
    let section = WireSection::round(0.5e-3, 200e9, 80e9, 7800.0);
    let limit = pendkit_limits::WIRES.default;
    let wire = |k: usize| {
        Wire::from_tension(
            format!("w{k}"),
            [hinge(support), hinge(bob)],
            section.clone(),
            1.0,
            10.0 * 9.81 / limit as f64,
            tags.clone(),
        )
    };
    for k in 0..limit {
        b.wire(wire(k)).unwrap();
    }
    let e = b.wire(wire(limit)).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "wire 'w{limit}': {} wires in one model: more than the limit of {limit} (set PENDKIT_MAX_WIRES to raise it)",
            limit + 1
        )
    );
    let (mut b, _) = point_mass();
    let limit = pendkit_limits::BODIES.default;
    // the support and the mass so far; massless frames at the origin cost least
    for k in 2..limit {
        b.body(BodySpec::new(format!("frame{k}"))).unwrap();
    }
    let e = b.body(BodySpec::new("one_more")).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "body 'one_more': {} bodies in one model: more than the limit of {limit} (set PENDKIT_MAX_BODIES to raise it)",
            limit + 1
        )
    );
    let (mut b, _) = point_mass();
    let limit = pendkit_limits::COORDINATES.default;
    // six support parameters and three variables so far
    for k in 9..limit {
        b.variable(&format!("q{k}"), 0.0).unwrap();
    }
    let e = b.float("one_more", 0.0).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "coordinate 'one_more': {} coordinates in one model: more than the limit of {limit} (set PENDKIT_MAX_COORDINATES to raise it)",
            limit + 1
        )
    );
}

#[test]
fn frequency_grids_past_the_limit_are_refused_before_they_are_made() {
    let limit = pendkit_limits::FREQUENCY_POINTS.default;
    assert_eq!(pendkit::log_grid(1.0, 10.0, limit).unwrap().len(), limit);
    let e = pendkit::log_grid(1.0, 10.0, usize::MAX).unwrap_err();
    assert!(matches!(e, Error::Dynamics(_)), "{e:?}");
    assert_eq!(
        e.to_string(),
        format!(
            "frequency grid: {} frequencies in one grid: more than the limit of {limit} (set PENDKIT_MAX_FREQUENCY_POINTS to raise it)",
            usize::MAX
        )
    );
    // a list given to a response: refused before the first solve
    let r = pendkit::run_stage(
        Case::model("pendulum").unwrap().build().unwrap().0,
        pendkit::Stage::S0B,
    )
    .unwrap();
    let freqs = vec![1.0; limit + 1];
    let e = r.transfer("x00", "x1", &freqs).unwrap_err().to_string();
    assert!(
        e.contains("frequencies in one grid: more than the limit"),
        "{e}"
    );
}

#[test]
fn a_search_that_stops_moving_ends_early_saying_so() {
    // the optic hung from one point 13 cm off its centre of mass, four fibres there: the
    // minimum is a body rolled by ~89 degrees, which the search approaches and then stops
    // moving at a residual 1e-9 of the weight; it ran the 200 iterations (57 s with
    // 10 000 such fibres), and now ends within a few iterations of standing still
    let point = |z: &str| {
        format!(
            "{{ points = [{}] }}",
            vec![format!("[0.01, 0.13, {z}]"); 4].join(", ")
        )
    };
    let text = three_stage(&point("-0.05"), &point("\"breakoff\""));
    let case = Case::from_text(Path::new("s.toml"), &text).unwrap();
    let (system, _) = case.build().unwrap();
    let e = pendkit::run_stage(system, pendkit::Stage::S2)
        .err()
        .expect("no equilibrium")
        .to_string();
    let stalled = "equilibrium search stalled: no progress in the last 10 of ";
    assert!(e.starts_with(stalled), "{e}");
    let iterations: usize = e[stalled.len()..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!(iterations < 100, "{e}");
}

/// The docs' "Limits" table has one row per limit, with its variable and its default: the
/// one place the limits are documented says what the code does.
#[test]
fn the_documented_limits_are_the_ones_checked() {
    let doc = include_str!("../../docs/checks-and-refusals.md");
    let section = &doc[doc.find("## Limits").expect("a Limits section")..];
    for limit in pendkit_limits::ALL {
        let row = section
            .lines()
            .find(|l| l.starts_with('|') && l.contains(&format!("`{}`", limit.variable)))
            .unwrap_or_else(|| panic!("no row for {}", limit.variable));
        let cells: Vec<&str> = row.split(" | ").collect();
        let written: String = cells[1].chars().filter(|c| !c.is_whitespace()).collect();
        let value = match written.strip_suffix("MiB") {
            Some(mib) => mib.parse::<usize>().map(|n| n << 20),
            None => written.parse::<usize>(),
        };
        assert_eq!(value, Ok(limit.default), "{row}");
    }
}
