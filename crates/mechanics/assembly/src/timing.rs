//! Wall-clock time of the named phases of a calculation (equilibrium, Hessians per element
//! kind, mass matrix, ...), recorded on request so that `pendkit bench` can show where the
//! time goes without a copy of the pipeline.

use std::time::{Duration, Instant};

/// One named phase: total time and how many items it processed (terms for a Hessian
/// phase, frequencies for noise, 1 otherwise).
#[derive(Clone, Debug, PartialEq)]
pub struct Phase {
    /// Name, e.g. `equilibrium` or `hessian:wire-stretch`.
    pub name: String,
    /// Total wall-clock time (s).
    pub seconds: f64,
    /// Items processed.
    pub calls: usize,
}

/// The phases of one run, in the order they first occurred; a phase recorded again adds
/// to its time and count.
#[derive(Clone, Debug, Default)]
pub struct PhaseTimes {
    phases: Vec<Phase>,
}

impl PhaseTimes {
    /// No phases yet.
    pub fn new() -> Self {
        PhaseTimes::default()
    }

    /// Adds `elapsed` and `calls` to phase `name`.
    pub fn add(&mut self, name: &str, elapsed: Duration, calls: usize) {
        let seconds = elapsed.as_secs_f64();
        match self.phases.iter_mut().find(|p| p.name == name) {
            Some(p) => {
                p.seconds += seconds;
                p.calls += calls;
            }
            None => self.phases.push(Phase {
                name: name.to_string(),
                seconds,
                calls,
            }),
        }
    }

    /// Runs `f`, recording its time as phase `name` with `calls` items.
    pub fn time<T>(&mut self, name: &str, calls: usize, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.add(name, start.elapsed(), calls);
        out
    }

    /// The phases recorded.
    pub fn phases(&self) -> &[Phase] {
        &self.phases
    }
}

/// Times `f` as phase `name` when `times` is given; runs it untimed otherwise.
pub fn timed<T>(
    times: &mut Option<&mut PhaseTimes>,
    name: &str,
    calls: usize,
    f: impl FnOnce() -> T,
) -> T {
    match times {
        Some(t) => t.time(name, calls, f),
        None => f(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_accumulate_by_name_in_first_seen_order() {
        let mut t = PhaseTimes::new();
        t.add("b", Duration::from_millis(2), 1);
        t.add("a", Duration::from_millis(1), 3);
        t.add("b", Duration::from_millis(3), 1);
        let names: Vec<&str> = t.phases().iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["b", "a"]);
        assert!((t.phases()[0].seconds - 0.005).abs() < 1e-12);
        assert_eq!(t.phases()[0].calls, 2);
        assert_eq!(t.time("c", 1, || 7), 7);
        assert_eq!(t.phases().len(), 3);
    }
}
