//! Profiling driver: times the quad's noise sweep in a loop (for callgrind / perf), `cargo run --release -p pendkit-tests --example noiseprof -- [MODEL]`.
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map(String::as_str).unwrap_or("quad");
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    let case = pendkit::Case::model(model).unwrap();
    let (system, _) = case.build().unwrap();
    let r = pendkit::run_stage(system, pendkit::system::Stage::S2).unwrap();
    let freqs = pendkit::log_grid(0.1, 100.0, 1000).unwrap();
    let mut best = [f64::INFINITY; 3];
    for _ in 0..reps {
        let t = Instant::now();
        let n = r.noise("x3", &freqs).unwrap();
        best[0] = best[0].min(t.elapsed().as_secs_f64());
        std::hint::black_box(n);
        let t = Instant::now();
        let h = r.transfer("x00", "x3", &freqs).unwrap();
        best[1] = best[1].min(t.elapsed().as_secs_f64());
        std::hint::black_box(h);
        let t = Instant::now();
        let h = r.transfer("force:x3", "x3", &freqs).unwrap();
        best[2] = best[2].min(t.elapsed().as_secs_f64());
        std::hint::black_box(h);
    }
    println!(
        "noise {:.3} us/pt  tf x00 {:.3} us/pt  tf force {:.3} us/pt",
        best[0] * 1e3,
        best[1] * 1e3,
        best[2] * 1e3
    );
}
