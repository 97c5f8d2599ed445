//! `Case::from_text` reads the suspension text it is given (a caller that keeps a file's text
//! — another process, an editor — gets that text's model, whatever is on disk at the path),
//! and two texts at the same path are two models.

use std::path::Path;

use pendkit::{Case, Stage, run_stage};

/// A bob on four hinged vertical fibres of length `length` m (the suspension-file crate's
/// documentation example).
fn pendulum(length: f64) -> String {
    format!(
        r#"
[parameters]
m = {{ value = 40, unit = "kg", description = "the bob" }}
[materials.silica]
youngs_modulus = 72e9
poisson_ratio = 0.17
density = 2200
loss_angle = 1e-7
[bodies.support]
coordinates = "00"
driven = true
[bodies.bob]
coordinates = "1"
dof = "xyz"
mass = "m"
[stages.bob]
from = "support"
[stages.bob.fibres]
upper = {{ at = [0.005, 0.17, 0], mirror = ["y", "x"] }}
lower = {{ at = [0.005, 0.17, 0], mirror = ["y", "x"], hinged = 1 }}
length = {length}
radius = 0.2e-3
material = "silica"
"#
    )
}

/// The lowest (pendulum) frequency of the case, Hz.
fn pendulum_hz(case: &Case) -> f64 {
    let (system, _) = case.build().unwrap();
    let r = run_stage(system, Stage::S0A).unwrap();
    r.modes
        .modes
        .iter()
        .map(|m| m.hz)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn case_text_is_the_model_not_the_file_at_its_path() {
    // no file at this path: the text alone is the suspension
    let path = Path::new("/nonexistent-folder/pendulum.toml");
    let long = Case::from_text(path, &pendulum(0.6)).unwrap();
    let short = Case::from_text(path, &pendulum(0.15)).unwrap();
    // A point mass on vertical hinged fibres swings at sqrt(g/L)/2π with L the fibres' length
    // under load; the same fibres, stretched by the same tension, a quarter as long have a
    // quarter of that length, so the frequencies are exactly 2 to 1. 1e-9: the stretch and
    // the modes' rounding cancel in the ratio far below it.
    let ratio = pendulum_hz(&short) / pendulum_hz(&long);
    assert!((ratio - 2.0).abs() < 1e-9, "ratio {ratio}");
}
