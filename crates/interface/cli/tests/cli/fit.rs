//! `pendkit fit` end to end: measured modes made by `pendkit modes` of the quad at known
//! parameter values (no noise), fitted from the nominal model; the written case file loads
//! and reproduces the fitted modes.

use crate::common;

use common::pendkit;
use serde_json::Value;

/// A fresh scratch folder for this test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("pendkit-fit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn modes_json(args: &[&str]) -> Value {
    let (ok, stdout, stderr) = pendkit(args);
    assert!(ok, "{stderr}");
    serde_json::from_str(&stdout).unwrap()
}

#[test]
fn fit_writes_a_case_file_that_reproduces_the_fitted_modes() {
    let dir = scratch("case");
    // the truth: a heavier UIM on longer wires
    let truth = modes_json(&[
        "modes", "quad", "--set", "m1=23", "--set", "l1=0.31", "--json",
    ]);
    let coordinates: Vec<&str> = truth["coordinates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    let mut csv =
        String::from("# synthetic: the quad with m1=23, l1=0.31\nlabel,hz,sigma_hz,shape\n");
    for m in truth["modes"].as_array().unwrap() {
        let hz = m["hz"].as_f64().unwrap();
        let shares: Vec<f64> = m["energy_fractions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let mut order: Vec<usize> = (0..shares.len()).collect();
        order.sort_by(|&a, &b| shares[b].total_cmp(&shares[a]));
        // the shape: the three coordinates `pendkit modes` lists for the mode
        csv += &format!(
            "{},{hz},{},{}+{}+{}\n",
            m["label"].as_str().unwrap(),
            1e-4 * hz,
            coordinates[order[0]],
            coordinates[order[1]],
            coordinates[order[2]]
        );
    }
    let measured = dir.join("measured.csv");
    std::fs::write(&measured, csv).unwrap();
    let fitted = dir.join("fitted.toml");
    let (ok, stdout, stderr) = pendkit(&[
        "fit",
        "quad",
        "--modes",
        measured.to_str().unwrap(),
        "--free",
        "m1,l1,silica_phi",
        "--out",
        fitted.to_str().unwrap(),
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let result: Value = serde_json::from_str(&stdout).unwrap();
    let parameters = result["fit"]["parameters"].as_array().unwrap();
    // noise-free data: the fit lands on the truth far inside its uncertainty
    for (p, truth) in parameters.iter().zip([23.0, 0.31]) {
        let sigma = p["uncertainty"].as_f64().unwrap();
        let value = p["value"].as_f64().unwrap();
        assert!((value - truth).abs() < 0.01 * sigma, "{p}");
    }
    assert!(
        parameters[2]["uncertainty"].is_null(),
        "silica_phi: {}",
        parameters[2]
    );
    assert_eq!(result["fit"]["undetermined"].as_array().unwrap().len(), 1);
    assert_eq!(result["fit"]["jacobian"], "exact");

    // the case file loads and gives the fitted model's frequencies, mode by mode
    let again = modes_json(&["modes", fitted.to_str().unwrap(), "--json"]);
    let modes = again["modes"].as_array().unwrap();
    for r in result["fit"]["modes"].as_array().unwrap() {
        let k = r["mode"].as_u64().unwrap() as usize - 1;
        let hz = modes[k]["hz"].as_f64().unwrap();
        let fitted_hz = r["model_hz"].as_f64().unwrap();
        // the file holds every digit of the fitted values: the same model, the same numbers
        assert!((hz - fitted_hz).abs() <= 1e-12 * hz, "{hz} vs {fitted_hz}");
    }

    // `pendkit fit quad --modes measured.csv --free <free>` and more arguments
    let fit_quad = |free: &str, more: &[&str]| {
        let base = [
            "fit",
            "quad",
            "--modes",
            measured.to_str().unwrap(),
            "--free",
            free,
        ];
        pendkit(&[&base[..], more].concat())
    };
    // the table says the same in words
    let (ok, table, stderr) = fit_quad("m1,l1,silica_phi", &[]);
    assert!(ok, "{stderr}");
    for expected in [
        "exact Jacobian",
        "chi^2/dof",
        "correlation",
        "undetermined combinations",
        "1.000 silica_phi",
    ] {
        assert!(table.contains(expected), "no '{expected}' in\n{table}");
    }

    // central differences for the Jacobian on request: the same fit, said so; a method
    // that is neither is a one-line usage error naming it
    let (ok, table, stderr) = fit_quad("m1,l1", &["--jacobian", "differences"]);
    assert!(ok, "{stderr}");
    assert!(table.contains("central-difference Jacobian"), "{table}");
    let (ok, _, stderr) = fit_quad("m1", &["--jacobian", "adjoint"]);
    assert!(!ok);
    assert!(
        stderr.contains("'adjoint' is not a Jacobian method (exact or differences)"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fit_refuses_bad_files_naming_the_line() {
    let dir = scratch("bad");
    let measured = dir.join("measured.csv");
    std::fs::write(&measured, "label,hz,sigma_hz\nx3,0.43,0.001\nz3,0.67,-2\n").unwrap();
    let (ok, _, stderr) = pendkit(&[
        "fit",
        "quad",
        "--modes",
        measured.to_str().unwrap(),
        "--free",
        "m1",
    ]);
    assert!(!ok);
    let expected = format!("error: {}:3: sigma_hz must be positive", measured.display());
    assert!(stderr.starts_with(&expected), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
