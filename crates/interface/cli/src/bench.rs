//! `pendkit bench`: the time of each phase of a calculation, measured in this process.

use std::fmt::Write as _;

use pendkit::Error;
use pendkit::system::Stage;

// Arguments of `pendkit bench` (a plain comment: see `Command` on why clap must not read it).
#[derive(clap::Args)]
pub struct Args {
    /// Bundled model name or path to a case file (.toml).
    model: String,
    /// Calculation stage: 0a, 0b, 1a, 1b or 2.
    #[arg(long, default_value = "2")]
    stage: Stage,
    /// Number of repetitions.
    #[arg(long, default_value_t = 20)]
    repeat: usize,
    /// Override a parameter or damping field (as for `modes`; repeatable).
    #[arg(long = "set", value_name = "NAME=EXPR")]
    sets: Vec<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Also time the thermal noise of this output (a variable or <body>@x,y,z/dx,dy,dz).
    #[arg(long, value_name = "OUTPUT")]
    noise: Option<String>,
    /// Frequencies of the noise calculation (log-spaced, 0.1 to 100 Hz).
    #[arg(long, default_value_t = 200, requires = "noise")]
    points: usize,
}

/// Runs the command and returns what it prints.
pub fn run(a: Args) -> Result<String, Error> {
    let noise = a.noise.as_deref().map(|output| (output, a.points));
    let report = pendkit::stage::bench(&a.model, &a.sets, a.stage, a.repeat, noise)?;
    Ok(if a.json {
        serde_json::to_string_pretty(&report).unwrap_or_default() + "\n"
    } else {
        bench_table(&report, a.repeat)
    })
}

fn bench_table(r: &pendkit::stage::BenchReport, repeat: usize) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}, stage {}: time per repetition over {repeat} repetitions",
        r.model, r.stage
    );
    let _ = writeln!(
        out,
        "{:<44} {:>12} {:>12} {:>7}",
        "phase", "median", "min", "calls"
    );
    let ms = |s: f64| format!("{:.4} ms", 1e3 * s);
    for p in &r.phases {
        let _ = writeln!(
            out,
            "{:<44} {:>12} {:>12} {:>7}",
            p.name,
            ms(p.median_s),
            ms(p.min_s),
            p.calls
        );
    }
    let _ = writeln!(
        out,
        "{:<44} {:>12}",
        "total (build to modes, noise excluded)",
        ms(r.total_median_s)
    );
    out
}
