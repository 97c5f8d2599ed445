//! `pendkit-downstream [--samples N] [--seed S]`: a Monte Carlo tolerance study of the
//! bundled quad (see the library, `src/lib.rs`, and the README).

use std::error::Error;
use std::process::ExitCode;
use std::str::FromStr;

use pendkit_downstream::{COUPLING_HZ, MODEL, Tolerances, run_study};

const USAGE: &str = "usage: pendkit-downstream [--samples N] [--seed S]
  --samples N   samples to draw (default 10000)
  --seed S      seed of the random errors (default 1; the same seed gives the same result)";

// `main` prints the error with Display (one line, the library's message) rather than the
// Debug form a `main` returning `Result` would print
fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn Error>> {
    let (mut samples, mut seed) = (10_000_usize, 1_u64);
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--samples" => samples = option(&arg, args.next())?,
            "--seed" => seed = option(&arg, args.next())?,
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            other => return Err(format!("unknown argument '{other}'\n{USAGE}").into()),
        }
    }
    if samples < 2 {
        return Err("--samples must be at least 2 (a spread needs two samples)".into());
    }

    let tolerances = Tolerances::DEFAULT;
    let study = run_study(&tolerances, samples, seed)?;

    println!(
        "{MODEL} at stage 2: {samples} samples, seed {seed}, {} threads",
        study.threads
    );
    println!(
        "errors (1 sigma, Gaussian): masses {} g, lengths {} mm, break-offs {} mm",
        tolerances.mass_kg * 1e3,
        tolerances.length_m * 1e3,
        tolerances.break_off_m * 1e3
    );
    println!(
        "\n{:<26} {:>11} {:>11} {:>10} {:>11} {:>11}  unit",
        "quantity", "nominal", "mean", "std", "p1", "p99"
    );
    for q in &study.quantities {
        let name = if q.nominal_label.is_empty() {
            format!("{} at {COUPLING_HZ} Hz", q.name)
        } else {
            format!("{} ({})", q.name, q.nominal_label)
        };
        // frequencies in fixed point (µHz resolution), the coupling in scientific notation
        let num = |x: f64| {
            if q.unit == "Hz" {
                format!("{x:.6}")
            } else {
                format!("{x:.5e}")
            }
        };
        let s = &q.stats;
        println!(
            "{name:<26} {:>11} {:>11} {:>10.3e} {:>11} {:>11}  {}",
            num(q.nominal),
            num(s.mean),
            s.std,
            num(s.p01),
            num(s.p99),
            q.unit
        );
    }
    println!(
        "\nfailed: {} (build, run or stability); tracked modes changed: {} (left out)",
        study.failed, study.mismatched
    );
    if let Some((index, modes)) = &study.first_mismatch {
        println!("first with a changed mode: sample {index}: {modes}");
    }
    if let Some((index, message)) = &study.first_failure {
        println!("first failure: sample {index}: {message}");
    }
    println!(
        "time: {:.2} s for {samples} samples, {:.0} samples/s",
        study.elapsed.as_secs_f64(),
        study.samples_per_second()
    );
    Ok(())
}

/// The value of option `name`, parsed.
fn option<T: FromStr>(name: &str, value: Option<String>) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    let value = value.ok_or(format!("{name} needs a value\n{USAGE}"))?;
    value.parse().map_err(|e| format!("{name} '{value}': {e}"))
}
