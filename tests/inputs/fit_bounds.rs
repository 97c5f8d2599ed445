//! Fits bounded by the parameters' declared domains: the bundled quad declares each
//! break-off within its body, so a fit cannot carry an attachment point out of it.

use std::path::Path;

use pendkit::fit::{FitOptions, MeasuredModes, fit};
use pendkit::{Case, Stage, run_stage};

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Bounds from the parameters' domains: the quad declares each break-off within its body's
/// vertical extent (the test mass's: its radius, 0.17 m). Measurements made with the test
/// mass's wires breaking off 0.2 m above its centre (a model that extends the quad and
/// widens that domain, so the truth can be built) cannot be reached inside the quad's
/// domain: the fit stops at the edge, fails naming the parameter the bound holds, and never
/// gives a break-off outside the body. The same fit of the widened model recovers 0.2 m,
/// so it is the bound, not the data, that stops the first.
#[test]
fn break_offs_stay_within_their_bodies() {
    let widened = Case::from_text(
        Path::new("widened.toml"),
        r#"name = "widened"
extends = "quad"
[parameters]
d4 = { value = 0.001, domain = "in (-1, 1)" }
"#,
    )
    .unwrap();
    let truth = widened.clone().with_sets(&names(&["d4=0.2"])).unwrap();
    let solved = run_stage(truth.build().unwrap().0, Stage::S2).unwrap();
    let measured = MeasuredModes::of_modes(Path::new("truth.csv"), &solved.modes, 1e-4);
    let free = names(&["d4"]);
    let options = FitOptions {
        more_starts: 0,
        ..FitOptions::default()
    };
    // both fits start inside the quad's domain, 1 cm from its edge, where the modes are
    // close enough to the truth's for each measurement to find its mode
    let start = names(&["d4=0.16"]);
    let quad = Case::model("quad").unwrap().with_sets(&start).unwrap();
    // the data pull d4 out of the test mass: the fit steps nine tenths of the way to the
    // edge each time, stalls there, and says which parameter the bound holds and why
    let message = match fit(&quad, &measured, None, &free, &options) {
        Ok(result) => panic!("a fit pressed against its bound converged: {result:?}"),
        Err(e) => e.to_string(),
    };
    assert!(message.contains("the fit did not converge"), "{message}");
    assert!(
        message.contains(
            "d4 = 0.17 m is at the edge of its domain in (-0.17, 0.17): the data ask for a value outside it"
        ),
        "{message}"
    );
    let last = message
        .split("d4=")
        .nth(1)
        .and_then(|rest| rest.split(';').next())
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap();
    assert!(last > 0.16 && last < 0.17, "last d4 = {last} m");
    let widened = widened.with_sets(&start).unwrap();
    let free_to_move = fit(&widened, &measured, None, &free, &options).unwrap();
    assert!(free_to_move.explains_data);
    let recovered = free_to_move.parameters[0].value;
    // noise-free data: the fit converges to the truth far inside its 1e-4 relative σ
    assert!((recovered / 0.2 - 1.0).abs() < 1e-4, "d4 = {recovered} m");
}
