//! `pendkit report` without a browser: what the page says for a stable model, an unstable
//! one, stage 0A and a model whose thermal noise is exactly zero, and that it fetches
//! nothing. (`report_browser.rs` opens the page in Chromium.)

use std::path::{Path, PathBuf};
use std::process::Command;

fn report(name: &str, args: &[&str]) -> (String, String) {
    let dir: PathBuf = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("report-{name}"));
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .arg("report")
        .args(args)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    (String::from_utf8_lossy(&out.stdout).into_owned(), html)
}

#[test]
fn the_quad_report_has_every_section_and_loads_nothing() {
    let (stdout, html) = report("quad", &["quad", "--naming", "ligo", "--points", "50"]);
    assert!(stdout.contains("12 figures"), "{stdout}");
    for id in [
        "model",
        "equilibrium",
        "stability",
        "modes",
        "transfer",
        "noise",
        "timing",
    ] {
        assert!(html.contains(&format!("<section id=\"{id}\">")), "{id}");
    }
    assert!(html.contains("verdict stable"));
    // 4 bodies x 6 degrees of freedom: modes numbered 1 to 24 in the table
    let modes = html
        .split("<section id=\"modes\">")
        .nth(1)
        .and_then(|rest| rest.split("</section>").next())
        .unwrap();
    assert_eq!(modes.matches("<tr><td>").count(), 24);
    // the LIGO names of the six test-mass degrees of freedom, from the support and a force
    for dof in ["L", "T", "V", "R", "P", "Y"] {
        assert!(
            html.contains(&format!("L3_{dof}/GND_{dof}")),
            "support to L3_{dof}"
        );
        assert!(
            html.contains(&format!("L3_{dof}/force:L3_{dof}")),
            "force to L3_{dof}"
        );
    }
    // self-contained: no script, no external resource of any kind (the SVG namespace is a
    // name, not a resource)
    let html = html.replace("xmlns=\"http://www.w3.org/2000/svg\"", "");
    for forbidden in [
        "<script", "src=", "http://", "https://", "<link", "@import", "url(",
    ] {
        assert!(!html.contains(forbidden), "the report contains {forbidden}");
    }
}

#[test]
fn an_unstable_model_gets_a_report_with_its_verdict() {
    // rigid-body with its fibres attached 10 mm below the centre of mass: the pitch
    // stiffness m g d + k_w Σs² + (bending, about N√(TEI)) is 40·9.81·(-0.01) + 1.51 + 0.38
    // = -2.0 N m/rad < 0 (docs/reference-values.md §2), so pitch is unstable
    let (stdout, html) = report("unstable", &["rigid-body", "--set", "d_fibre=-0.01"]);
    assert!(stdout.contains("unstable"), "{stdout}");
    assert!(html.contains("verdict unstable"));
    assert!(html.contains("pitch1"));
    assert_eq!(html.matches("Not computed").count(), 2);
}

#[test]
fn an_unstable_model_gets_its_linearised_responses_only_with_allow_unstable() {
    // the same unstable rigid body: with --allow-unstable the transfer functions and noise
    // of its linearisation are drawn, and the page and stderr say it is unstable
    let dir: PathBuf = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-allow-unstable");
    let out = Command::new(env!("CARGO_BIN_EXE_pendkit"))
        .args([
            "report",
            "rigid-body",
            "--set",
            "d_fibre=-0.01",
            "--points",
            "20",
        ])
        .arg("--allow-unstable")
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning:") && stderr.contains("pitch1"),
        "{stderr}"
    );
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(html.contains("verdict unstable"));
    assert!(html.contains("--allow-unstable"));
    assert_eq!(html.matches("Not computed").count(), 0);
}

#[test]
fn stage_0a_reports_modes_but_no_responses() {
    let (_, html) = report("0a", &["pendulum", "--stage", "0a"]);
    assert!(html.contains("verdict stable"));
    assert_eq!(html.matches("Not computed").count(), 2);
}

#[test]
fn a_noise_that_is_zero_everywhere_is_said_not_drawn() {
    // the double pendulum's point masses hang on hinged wires, so bending stores nothing and
    // horizontal motion stretches no wire to first order: no lossy term couples to x2
    let (_, html) = report("zero-noise", &["double-pendulum", "--points", "20"]);
    assert!(
        html.contains("is zero at every frequency"),
        "zero-noise paragraph"
    );
}
