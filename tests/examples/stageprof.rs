//! Profiling driver: runs one model's stage `reps` times (for callgrind or timing), and
//! prints the decoupled blocks of K_eff and M.
use pendkit::system::Stage;
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map(String::as_str).unwrap_or("quad");
    let sets: Vec<String> = args
        .get(2)
        .filter(|s| !s.is_empty())
        .map(|s| s.split(',').map(String::from).collect())
        .unwrap_or_default();
    let reps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let stage = match args.get(4).map(String::as_str) {
        Some("0a") => Stage::S0A,
        _ => Stage::S2,
    };
    let case = pendkit::Case::model(model).unwrap();
    let case = case.with_sets(&sets).unwrap();
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = Instant::now();
        let (system, _) = case.build().unwrap();
        let r = pendkit::run_stage(system, stage).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(&r);
        if reps == 1 {
            let k = pendkit_dynamics::eliminate_floats(
                &r.model.real_stiffness(&r.system.damping),
                &r.assembled.layout,
                &r.system,
            )
            .unwrap()
            .k_eff;
            let n = k.nrows();
            let mut label: Vec<usize> = (0..n).collect();
            fn find(l: &[usize], i: usize) -> usize {
                let mut i = i;
                while l[i] != i {
                    i = l[i];
                }
                i
            }
            for i in 0..n {
                for j in 0..n {
                    if k[(i, j)] != 0.0 || r.assembled.mass[(i, j)] != 0.0 {
                        let (a, b) = (find(&label, i), find(&label, j));
                        label[a.max(b)] = a.min(b);
                    }
                }
            }
            let mut sizes = std::collections::BTreeMap::new();
            for i in 0..n {
                *sizes.entry(find(&label, i)).or_insert(0) += 1;
            }
            println!("blocks {:?}", sizes.values().collect::<Vec<_>>());
            println!("iterations {}", r.assembled.equilibrium.iterations);
        }
    }
    println!("best {:.3} ms", best * 1e3);
}
