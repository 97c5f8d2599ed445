//! `quad-aligo` against pygwinc 0.6.2, LIGO's noise-budget code, an independent
//! implementation of the suspension thermal noise of the same suspension (a 1-D chain of
//! four masses per direction with complex springs, a continuum fibre, and the loss formulas
//! of `suspension.py`). The test installs gwinc 0.6.2 in a virtual environment at
//! `target/venv-gwinc` if it is not there (`python3 -m venv`, `pip install gwinc==0.6.2`;
//! needs network access to PyPI once), then runs `tests/python/pygwinc_quad_aligo.py`,
//! which prints pygwinc's total suspension thermal noise (ASD, m/√Hz, of the test mass
//! along the beam: the horizontal joints plus θ² times the vertical ones) and the peaks of
//! its horizontal and vertical transfer functions.
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

use pendkit_energy::Stage;
use pendkit_tests::run;

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
