//! `quad-aligo` against pygwinc 0.6.2, LIGO's noise-budget code, an independent
//! implementation of the suspension thermal noise of the same suspension (a 1-D chain of
//! four masses per direction with complex springs, a continuum fibre, and the loss formulas
//! of `suspension.py`). The test installs gwinc 0.6.2 in a virtual environment at
//! `target/venv-gwinc` if it is not there (`python3 -m venv`, `pip install gwinc==0.6.2`;
//! needs network access to PyPI once), then runs `tests/python/pygwinc_quad_aligo.py`,
//! which prints pygwinc's total suspension thermal noise (ASD, m/√Hz, of the test mass
//! along the beam: the horizontal joints plus θ² times the vertical ones) and the peaks of
//! its horizontal and vertical transfer functions, or (`--ifo`) the numbers of aLIGO's
//! `ifo.yaml` that `quad-aligo` takes as parameters. These tests are the independent
//! references of `quad-aligo` (a suspension file, `models/ligo/quad-aligo.toml`): its
//! parameters and stage separations, its noise, its resonances, and its beaded fibres
//! against pygwinc's continuum fibres.
//!
//! What pygwinc has and pendkit's `quad-aligo` does not, and the reverse, bounds each
//! tolerance (README, "quad-aligo against pygwinc", measures every effect by switching it):
//! - pygwinc's fibres have mass (continuum springs with violin modes): +0.2 % on pygwinc's
//!   ASD at 20 Hz, +0.9 % at 50 Hz, +3.1 % at 100 Hz; pendkit's effective fibre is massless;
//! - pendkit computes the steel stages' dilution (≈ 99, 97, 121) where pygwinc is given 87,
//!   80, 106: −0.4 % at 20 Hz, −0.1 % at 30 Hz;
//! - pendkit's wires stretch in series with the blades (pygwinc: blades only), its masses
//!   pitch and couple to x (3-D), and its geometry is the 2005 drawing's: a few 0.1 % at
//!   20 Hz, falling with frequency.

use std::path::{Path, PathBuf};
use std::process::Command;

use pendkit_system::Stage;
use pendkit_tests::{opted_in, run};

/// Whether the pygwinc comparisons run (`PENDKIT_TEST_NETWORK=1`; they install gwinc from
/// PyPI); says so when they do not.
fn network_opted_in(test: &str) -> bool {
    opted_in(
        "PENDKIT_TEST_NETWORK",
        &format!("external::pygwinc_quad_aligo::{test}"),
        "python3 and network access to PyPI (pip install gwinc==0.6.2)",
    )
}

const FREQS: [f64; 9] = [20.0, 25.0, 30.0, 40.0, 50.0, 60.0, 70.0, 85.0, 100.0];

/// The Python of a virtual environment with gwinc 0.6.2, created under `target/` if
/// missing (once, whichever test asks first).
fn gwinc_python() -> PathBuf {
    static PYTHON: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    PYTHON.get_or_init(make_gwinc_python).clone()
}

fn make_gwinc_python() -> PathBuf {
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/venv-gwinc");
    let python = venv.join("bin/python");
    let has_gwinc = |py: &Path| {
        Command::new(py)
            .args(["-c", "import gwinc; assert gwinc.__version__ == '0.6.2'"])
            .status()
            .is_ok_and(|s| s.success())
    };
    if !has_gwinc(&python) {
        let made = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .expect("python3 runs");
        assert!(made.success(), "python3 -m venv {} failed", venv.display());
        let pip = Command::new(&python)
            .args(["-m", "pip", "install", "--quiet", "gwinc==0.6.2"])
            .status()
            .expect("pip runs");
        assert!(pip.success(), "pip install gwinc==0.6.2 failed (network?)");
        assert!(has_gwinc(&python), "gwinc 0.6.2 does not import");
    }
    python
}

/// pygwinc's printout at `FREQS`, with `extra` arguments.
fn pygwinc(extra: &[&str]) -> serde_json::Value {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/python/pygwinc_quad_aligo.py");
    let freqs: Vec<String> = FREQS.iter().map(|f| f.to_string()).collect();
    let out = Command::new(gwinc_python())
        .arg(script)
        .arg(freqs.join(","))
        .args(extra)
        .output()
        .expect("the pygwinc script runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON from the pygwinc script")
}

fn numbers(v: &serde_json::Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no {key}"))
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

/// pendkit's ASD (m/√Hz) of `quad-aligo` at `tm_beam`, stage 2, with `sets`.
fn pendkit_asd(sets: &[&str]) -> Vec<f64> {
    run("quad-aligo", sets, Stage::S2)
        .noise("tm_beam", &FREQS)
        .expect("noise at tm_beam")
        .asd()
}

/// pygwinc's given dilution factors of the steel stages (ifo.yaml `Stage[*].Dilution`).
const GIVEN_DILUTION: [&str; 3] = ["dilution_wn=87", "dilution_w1=80", "dilution_w2=106"];

#[test]
fn thermal_noise_along_the_beam_matches_pygwinc() {
    if !network_opted_in("thermal_noise_along_the_beam_matches_pygwinc") {
        return;
    }
    let reference = pygwinc(&[]);
    assert_eq!(reference["version"], "0.6.2");
    // the coupling angle: pygwinc's Infrastructure.Length / R_earth, quad-aligo's vh_theta
    let theta = reference["theta"].as_f64().unwrap();
    assert!((theta - 3995.0 / 6.3781e6).abs() < 1e-15);
    let theirs = numbers(&reference, "asd");
    let ours = pendkit_asd(&[]);
    for ((f, a), b) in FREQS.iter().zip(&ours).zip(&theirs) {
        let ratio = a / b;
        eprintln!("{f:5} Hz  pendkit/pygwinc = {ratio:.4}");
        // the bounds: 5 % over 20–100 Hz, 1 % at 20–50 Hz; the measured ratios
        // (0.995 at 20 Hz, 1.008 at 50 Hz, 1.031 at 100 Hz) are the fibre-mass term above
        // and the dilution/3-D terms at the low end
        let tolerance = if *f <= 50.0 { 0.01 } else { 0.05 };
        assert!((ratio - 1.0).abs() <= tolerance, "{f} Hz: ratio {ratio}");
    }
}

#[test]
fn with_massless_fibres_and_given_dilution_the_two_codes_agree_closely() {
    if !network_opted_in("with_massless_fibres_and_given_dilution_the_two_codes_agree_closely") {
        return;
    }
    // pygwinc with its fibres' continuum mass taken out (the effect pendkit's massless
    // effective fibre leaves out) and pendkit with pygwinc's given dilutions: what remains
    // is the 3-D coupling, series stretch and geometry of the upper stages, measured at
    // −0.3 % at 20 Hz and below 0.1 % from 30 Hz; the tolerances are those with a margin
    // of about 1.5x, so that a change in any loss formula (the smallest, the fibre's
    // vertical surface loss, is ~0.3 % of the ASD) shows.
    let theirs = numbers(&pygwinc(&["--massless-fibres"]), "asd");
    let ours = pendkit_asd(&GIVEN_DILUTION);
    for ((f, a), b) in FREQS.iter().zip(&ours).zip(&theirs) {
        let ratio = a / b;
        eprintln!("{f:5} Hz  pendkit (given dilution) / pygwinc (massless fibres) = {ratio:.5}");
        let tolerance = if *f < 30.0 { 5e-3 } else { 1.5e-3 };
        assert!((ratio - 1.0).abs() <= tolerance, "{f} Hz: ratio {ratio}");
    }
}

#[test]
fn resonances_match_pygwinc() {
    if !network_opted_in("resonances_match_pygwinc") {
        return;
    }
    let reference = pygwinc(&[]);
    let modes = |sets: &[&str], family: &str| -> Vec<f64> {
        let r = run("quad-aligo", sets, Stage::S2);
        r.modes
            .modes
            .iter()
            .filter(|m| r.mode_family(m) == family)
            .map(|m| m.hz)
            .collect()
    };
    // vertical: pygwinc's chain has the blades only (the wires do not stretch); with the
    // steel wires' stretch made stiff (×1e4), pendkit's four vertical modes must match to
    // 1e-4 (measured 2e-6, and 2e-5 on the 9.7 Hz bounce mode, where pygwinc's fibres have
    // mass); as built (wires in series with the blades) the modes are lower by up to 0.3 %
    let theirs = numbers(&reference, "vertical");
    let stiff: Vec<String> = ["wn", "w1", "w2"]
        .iter()
        .map(|s| format!("damping.{s}_stretch.real=1e4"))
        .collect();
    let stiff: Vec<&str> = stiff.iter().map(String::as_str).collect();
    for (sets, tolerance) in [(&stiff[..], 1e-4), (&[][..], 4e-3)] {
        let ours = modes(sets, "V");
        assert_eq!(ours.len(), 4, "{ours:?}");
        for (a, b) in ours.iter().zip(&theirs) {
            assert!((a / b - 1.0).abs() <= tolerance, "vertical {a} vs {b} Hz");
        }
    }
    // longitudinal: pendkit's masses pitch and couple to x through the 1 mm break-offs, the
    // wires' bending adds to the real stiffness of the upper stages, and the stage lengths
    // come from the 2005 drawing; together they move the modes by up to 1.4 % (the top
    // stage's 3.38 Hz mode), hence 2 %
    let theirs = numbers(&reference, "horizontal");
    let ours = modes(&[], "L");
    assert_eq!(ours.len(), 4, "{ours:?}");
    for (a, b) in ours.iter().zip(&theirs) {
        assert!((a / b - 1.0).abs() <= 0.02, "longitudinal {a} vs {b} Hz");
    }
}

/// Resolved parameter `name` of `quad-aligo` (with `sets`).
fn parameter(sets: &[&str], name: &str) -> f64 {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = pendkit::Case::model("quad-aligo")
        .and_then(|c| c.with_sets(&sets))
        .expect("case");
    pendkit::describe::parameter_table(&case)
        .expect("parameters")
        .into_iter()
        .find(|row| row.name == name)
        .unwrap_or_else(|| panic!("quad-aligo has no parameter {name}"))
        .value
}

#[test]
fn parameters_are_pygwincs_ifo_yaml() {
    if !network_opted_in("parameters_are_pygwincs_ifo_yaml") {
        return;
    }
    // every number quad-aligo takes from aLIGO's ifo.yaml (masses, wire and fibre radii,
    // the fibres' profile, blade stiffnesses and thicknesses, materials, temperature, arm
    // length), read by pygwinc itself: the same decimal numbers, so equal to rounding
    let reference = pygwinc(&["--ifo"]);
    assert_eq!(reference["version"], "0.6.2");
    let fields = reference.as_object().expect("a JSON object");
    let mut compared = 0;
    for (name, value) in fields {
        let Some(theirs) = value.as_f64() else {
            continue;
        };
        let ours = parameter(&[], name);
        assert!(
            (ours - theirs).abs() <= 1e-15 * theirs.abs(),
            "{name}: quad-aligo {ours}, ifo.yaml {theirs}"
        );
        compared += 1;
    }
    assert_eq!(compared, 41, "numbers compared");
    // the wires of each stage (ifo.yaml's NWires, top to bottom), counted in the built model
    let (system, _) = pendkit::Case::model("quad-aligo")
        .expect("case")
        .build()
        .expect("builds");
    let counts: Vec<f64> = ["wn", "w1", "w2", "fibre"]
        .iter()
        .map(|set| {
            let tag = format!("{set}_stretch");
            system
                .wires
                .iter()
                .filter(|w| w.tags.stretch == tag)
                .count() as f64
        })
        .collect();
    assert_eq!(counts, numbers(&reference, "nw"));
    // the steel stages' centre-of-mass separations (ifo.yaml's stage Length, given to the
    // millimetre) against the equilibrium's body heights: the 2005 geometry with the as-built
    // masses and wires puts them within half a millimetre
    let r = run("quad-aligo", &[], Stage::S0A);
    let z = |n: &str| r.assembled.equilibrium.coords[r.system.coord(n).expect(n)];
    let ours = [-z("z0"), z("z0") - z("z1"), z("z1") - z("z2")];
    for (a, b) in ours.iter().zip(numbers(&reference, "separations")) {
        assert!((a - b).abs() <= 0.5e-3, "separation {a} vs {b} m");
    }
}

#[test]
fn beaded_fibres_converge_to_pygwincs_continuum_fibres() {
    if !network_opted_in("beaded_fibres_converge_to_pygwincs_continuum_fibres") {
        return;
    }
    // pygwinc's fibres are continuum springs with mass, of the middle's section along their
    // whole length; with uniform fibres (the necks' radius set to the middle's in both
    // codes) those are the fibres quad-aligo's beads discretise, each segment the slice of
    // the (here uniform) profile it spans. With pygwinc's given dilutions the two codes
    // agree to 1e-4 at 30–100 Hz once both fibres are massless (as measured by
    // `with_massless_fibres_and_given_dilution_the_two_codes_agree_closely`), so what is
    // left is the fibres' mass: without beads pendkit is high by the whole fibre-mass term
    // (measured +3.0 % at 100 Hz: asserted above 2 %, so that the comparison can tell), and
    // as beads are added it falls towards pygwinc's continuum at every frequency (measured
    // at 100 Hz: +0.91 %, +0.51 %, +0.29 % with 10, 20, 40 beads, about 1/N: each clamped
    // segment resolves the fibre's ~1 mm bending length at the clamps only in its effective
    // section). Asserted: each doubling of the beads gets closer, and 40 beads are within
    // 0.4 % over 20–100 Hz.
    let theirs = numbers(&pygwinc(&["--uniform-fibres"]), "asd");
    let error = |beads: usize| -> Vec<f64> {
        let beads = format!("n_beads={beads}");
        let mut sets = GIVEN_DILUTION.to_vec();
        sets.extend(["r3_neck=r3", beads.as_str()]);
        pendkit_asd(&sets)
            .iter()
            .zip(&theirs)
            .map(|(a, b)| a / b - 1.0)
            .collect()
    };
    let massless = error(0);
    assert!(massless[FREQS.len() - 1] > 0.02, "{massless:?}");
    let mut previous = massless;
    for beads in [10, 20, 40] {
        let e = error(beads);
        for ((f, now), before) in FREQS.iter().zip(&e).zip(&previous) {
            eprintln!("{beads:3} beads {f:5} Hz  pendkit/pygwinc − 1 = {now:+.5}");
            assert!(
                now.abs() < before.abs(),
                "{beads} beads, {f} Hz: {now} vs {before}"
            );
        }
        previous = e;
    }
    for (f, e) in FREQS.iter().zip(&previous) {
        assert!(e.abs() <= 4e-3, "40 beads, {f} Hz: {e}");
    }
}
