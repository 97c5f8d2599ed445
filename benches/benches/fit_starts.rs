//! Fits from far starts: how often a many-parameter fit to noise-free synthetic modes
//! converges to the truth, over random sign patterns of the start's offsets.
//!
//!     cargo bench -p pendkit-benches --bench fit_starts [-- PATTERNS [STARTS [MORE [OFFSET [MODEL]]]]]
//!
//! For the quad (24 modes, 20 free parameters) and the triple (18 modes, 15 free
//! parameters; MODEL names one of them): the truth is the model's values scaled by 1 ± OFFSET (default 0.2) with a
//! sign per parameter from a fixed seed (PATTERNS patterns, default 30); the measured modes are the truth's frequencies
//! (σ = 10⁻⁴ f, no noise), labelled by their dominant coordinate with their three largest
//! coordinates as the shape. The fit starts from the model's values, with STARTS starts
//! (default 1) and up to MORE more when none explains the data (default 4): the
//! `FitOptions::starts` and `more_starts` of the fit. Printed per pattern: the outcome,
//! χ²/dof, the largest relative error of a parameter against the truth and the largest
//! error in units of the stated uncertainty, the iterations, starts and solutions, and the
//! time; then a summary. A pattern whose truth the model refuses (a body that breaks the
//! triangle inequality) is counted apart and not fitted. Not a criterion bench: it counts
//! outcomes.

use std::path::Path;
use std::time::Instant;

use pendkit::fit::{FitOptions, MeasuredModes, fit};
use pendkit::{Case, Stage, run_stage};

/// SplitMix64: reproducible signs.
struct Signs(u64);

impl Signs {
    fn next(&mut self) -> bool {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) & 1 == 1
    }
}

/// The stage-2 modes of `model` with `sets`, σ = 10⁻⁴ f, noise-free; or why the model
/// refuses that truth (a body whose moments break the triangle inequality: the triple's
/// intermediate mass with its mass 20 % up and its pitch inertia 20 % down).
fn synthetic(model: &str, sets: &[String]) -> Result<MeasuredModes, pendkit::Error> {
    let case = Case::model(model)?.with_sets(sets)?;
    let r = run_stage(case.build()?.0, Stage::S2)?;
    Ok(MeasuredModes::of_modes(
        Path::new("synthetic.csv"),
        &r.modes,
        1e-4,
    ))
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let patterns: usize = args.first().map_or(30, |a| a.parse().unwrap());
    let starts: usize = args.get(1).map_or(1, |a| a.parse().unwrap());
    let more_starts: usize = args.get(2).map_or(4, |a| a.parse().unwrap());
    let offset: f64 = args.get(3).map_or(0.2, |a| a.parse().unwrap());
    let cases: [(&str, &[&str]); 2] = [
        (
            "quad",
            &[
                "ln", "l1", "l2", "l3", "ufcn", "ufc1", "ufc2", "dm", "dn", "d0", "d1", "d2", "d3",
                "d4", "mn", "m1", "m2", "m3", "Iny", "I1y",
            ],
        ),
        (
            "triple",
            &[
                "l1", "l2", "l3", "ufc1", "ufc2", "d0", "d1", "d2", "d3", "d4", "m1", "m2", "m3",
                "I1y", "I2y",
            ],
        ),
    ];
    let only: Option<&str> = args.get(4).map(String::as_str);
    for (model, free) in cases {
        if only.is_some_and(|m| m != model) {
            continue;
        }
        let free: Vec<String> = free.iter().map(|s| s.to_string()).collect();
        let case = Case::model(model).unwrap();
        let (_, resolved) = case.build().unwrap();
        let mut signs = Signs(2026);
        let (mut to_truth, mut explained, mut total_time, mut impossible) = (0, 0, 0.0, 0);
        println!("{model}: {} free parameters", free.len());
        for pattern in 0..patterns {
            let pattern_signs: Vec<bool> = free.iter().map(|_| signs.next()).collect();
            let truth: Vec<f64> = free
                .iter()
                .zip(&pattern_signs)
                .map(|(n, &up)| {
                    resolved.get(n).unwrap() * if up { 1.0 + offset } else { 1.0 - offset }
                })
                .collect();
            let sets: Vec<String> = free
                .iter()
                .zip(&truth)
                .map(|(n, v)| format!("{n}={v}"))
                .collect();
            let signs_text: String = pattern_signs
                .iter()
                .map(|&s| if s { '+' } else { '-' })
                .collect();
            let measured = match synthetic(model, &sets) {
                Ok(measured) => measured,
                Err(e) => {
                    println!("  {pattern:3} {signs_text} no such suspension: {e}");
                    impossible += 1;
                    continue;
                }
            };
            let start = Instant::now();
            let options = FitOptions {
                starts,
                more_starts,
                ..FitOptions::default()
            };
            let outcome = fit(&case, &measured, None, &free, &options);
            let seconds = start.elapsed().as_secs_f64();
            total_time += seconds;
            match outcome {
                Ok(r) => {
                    let (mut worst, mut worst_sigma) = (0.0f64, 0.0f64);
                    for (p, t) in r.parameters.iter().zip(&truth) {
                        worst = worst.max((p.value - t).abs() / t.abs());
                        if let Some(u) = p.uncertainty {
                            worst_sigma = worst_sigma.max((p.value - t).abs() / u);
                        }
                    }
                    explained += usize::from(r.explains_data);
                    to_truth += usize::from(worst <= 1e-4);
                    println!(
                        "  {pattern:3} {signs_text} chi2/dof {:9.3e} worst {worst:8.1e} ({worst_sigma:8.1e} sigma) it {:3} starts {:2} solves {:4} {seconds:6.2} s",
                        r.reduced_chi_squared.unwrap_or(f64::NAN),
                        r.iterations,
                        r.starts,
                        r.solves,
                    );
                }
                Err(e) => println!("  {pattern:3} {signs_text} error: {e} ({seconds:.2} s)"),
            }
        }
        let fitted = patterns - impossible;
        println!(
            "{model}: {to_truth}/{fitted} to the truth (1e-4), {explained}/{fitted} explain the data, {:.2} s per fit ({impossible} patterns make no rigid body)\n",
            total_time / fitted.max(1) as f64
        );
    }
}
