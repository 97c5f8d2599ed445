//! A Monte Carlo tolerance study of the bundled `quad` model, written as a downstream tool
//! would write it: on the public API of the `pendkit` crate alone.
//!
//! Each sample builds the quad with Gaussian manufacturing errors on its masses, wire and
//! fibre lengths and break-off distances, runs stage 2 (the complete model), and records
//! the frequency of every pitch and every yaw mode and the cross-coupling from a
//! longitudinal force on the test mass to its pitch at 1 Hz. [`run_study`] returns each
//! quantity's nominal value and spread.
//!
//! `src/main.rs` is the command line around it; the tests at the end of this file check it
//! (one test program, to keep `cargo test` to one link of pendkit).

use std::time::{Duration, Instant};

use pendkit::describe::DOF_FAMILIES;
use pendkit::{Case, Override, Stage, StageResult, run_stage};
use rayon::prelude::*;

/// The bundled model studied.
pub const MODEL: &str = "quad";

/// The masses perturbed (kg): top mass, UIM, PUM, test mass (`models/ligo/quad.toml`).
pub const MASSES: [&str; 4] = ["mn", "m1", "m2", "m3"];

/// The wire and fibre lengths perturbed (m): top wires, UIM wires, PUM wires, fibres.
pub const LENGTHS: [&str; 4] = ["ln", "l1", "l2", "l3"];

/// The vertical break-off distances perturbed (m): of the wires from each mass's centre of
/// mass, above (`dm`, `d0`, `d2`, `d4`) and below (`dn`, `d1`, `d3`).
pub const BREAK_OFFS: [&str; 7] = ["dm", "dn", "d0", "d1", "d2", "d3", "d4"];

/// The input of the cross-coupling: a force (N) along x (longitudinal) on the test mass.
pub const COUPLING_INPUT: &str = "force:x3";

/// The output of the cross-coupling: the test mass's pitch (rad).
pub const COUPLING_OUTPUT: &str = "pitch3";

/// Where the cross-coupling is evaluated (Hz).
pub const COUPLING_HZ: f64 = 1.0;

/// The mode families reported, as indices into [`pendkit::describe::DOF_FAMILIES`] (whose order is
/// the pose entries x, y, z, yaw, pitch, roll): pitch `P`, then yaw `Y`.
const FAMILIES: [usize; 2] = [4, 3];

/// Gaussian manufacturing tolerances: the standard deviation of every error in a group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Of each mass in [`MASSES`] (kg).
    pub mass_kg: f64,
    /// Of each length in [`LENGTHS`] (m).
    pub length_m: f64,
    /// Of each break-off distance in [`BREAK_OFFS`] (m).
    pub break_off_m: f64,
}

impl Tolerances {
    /// The study's tolerances (the README says why): 10 g on masses, 1 mm on lengths,
    /// 0.5 mm on break-offs.
    pub const DEFAULT: Tolerances = Tolerances {
        mass_kg: 0.010,
        length_m: 0.001,
        break_off_m: 0.000_5,
    };

    /// No errors at all: every sample is the nominal model.
    pub const ZERO: Tolerances = Tolerances {
        mass_kg: 0.0,
        length_m: 0.0,
        break_off_m: 0.0,
    };

    /// Every standard deviation multiplied by `factor`.
    pub fn scaled(self, factor: f64) -> Tolerances {
        Tolerances {
            mass_kg: self.mass_kg * factor,
            length_m: self.length_m * factor,
            break_off_m: self.break_off_m * factor,
        }
    }

    /// Every perturbed parameter with its standard deviation (SI units), in the fixed
    /// order in which a sample draws its errors.
    pub fn per_parameter(&self) -> Vec<(&'static str, f64)> {
        let group =
            |names: &'static [&'static str], sigma: f64| names.iter().map(move |&n| (n, sigma));
        group(&MASSES, self.mass_kg)
            .chain(group(&LENGTHS, self.length_m))
            .chain(group(&BREAK_OFFS, self.break_off_m))
            .collect()
    }
}

/// Summary statistics of one quantity over the samples that succeeded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (with n − 1; 0 for a single value).
    pub std: f64,
    /// 1st percentile (linear interpolation between order statistics).
    pub p01: f64,
    /// 99th percentile.
    pub p99: f64,
}

impl Stats {
    /// The statistics of `values` (at least one value; NaN for an empty slice).
    pub fn of(values: &[f64]) -> Stats {
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n as f64;
        // n − 1 (Bessel's correction); a single value has no spread, 0 rather than 0/0
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n.max(2) - 1) as f64;
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Stats {
            mean,
            std: var.sqrt(),
            p01: percentile(&sorted, 0.01),
            p99: percentile(&sorted, 0.99),
        }
    }
}

/// The `q`-quantile of sorted values, interpolating linearly between the order statistics
/// at ranks ⌊q (n − 1)⌋ and ⌈q (n − 1)⌉ (the "type 7" definition of R and NumPy).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = q * (sorted.len() - 1) as f64;
    let (lo, hi) = (rank.floor() as usize, rank.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (rank - lo as f64)
}

/// One quantity recorded per sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantity {
    /// Short name: `P1` ... for the pitch modes by ascending frequency, `Y1` ... for yaw,
    /// `|pitch3/force:x3|` for the cross-coupling.
    pub name: String,
    /// For a mode, the coordinate with the largest share of its kinetic energy in the
    /// nominal model (e.g. `pitch0`); empty for the cross-coupling.
    pub nominal_label: String,
    /// Unit: `Hz` for a mode, the transfer function's (`rad/N`) for the cross-coupling.
    pub unit: String,
    /// Value of the nominal model.
    pub nominal: f64,
    /// Value of every sample that succeeded, in sample order.
    pub values: Vec<f64>,
    /// Statistics of `values`.
    pub stats: Stats,
}

/// The result of [`run_study`].
#[derive(Clone, Debug)]
pub struct Study {
    /// The quantities: pitch modes, yaw modes, then the cross-coupling.
    pub quantities: Vec<Quantity>,
    /// Samples drawn.
    pub samples: usize,
    /// Samples whose build or stage run failed, or whose equilibrium is unstable.
    pub failed: usize,
    /// Samples in which a tracked mode, followed from the nominal model by the overlap of
    /// its shape ([`StageResult::match_modes`]), kept less than half of it (overlap < 0.5):
    /// no mode of the sample is that mode any more, so the sample is left out of the
    /// statistics. A mode that keeps its shape is tracked even where its family letter
    /// changes (a mixed mode whose larger energy share moved to another family).
    pub mismatched: usize,
    /// The first such sample, as (sample index, what became of the tracked modes).
    pub first_mismatch: Option<(usize, String)>,
    /// The first failure, as (sample index, message), if any.
    pub first_failure: Option<(usize, String)>,
    /// Wall-clock time of the samples (the nominal run excluded).
    pub elapsed: Duration,
    /// Worker threads the samples ran on (rayon's pool).
    pub threads: usize,
}

impl Study {
    /// Samples per second of wall-clock time.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64()
    }
}

/// Runs `samples` builds of the quad, each with errors drawn with standard deviations
/// `tolerances` from a generator seeded by `seed` and the sample's index (so the result
/// does not depend on how rayon schedules the samples), in parallel on rayon's pool.
///
/// An error is returned only when the nominal model cannot be built or run, or is unstable;
/// a sample that fails is counted in [`Study::failed`].
pub fn run_study(
    tolerances: &Tolerances,
    samples: usize,
    seed: u64,
) -> Result<Study, pendkit::Error> {
    let case = Case::model(MODEL)?;
    let (system, _parameters) = case.build()?;
    let nominal = run_stage(system, Stage::S2)?;
    nominal.check_stable()?;
    let (mut quantities, tracked) = describe(&nominal)?;

    let sigmas = tolerances.per_parameter();
    let start = Instant::now();
    // collected in index order whatever thread ran each sample
    let outcomes: Vec<Outcome> = (0..samples)
        .into_par_iter()
        .map(|index| run_sample(&case, &sigmas, seed, index, &nominal, &tracked))
        .collect();
    let elapsed = start.elapsed();

    let (mut failed, mut mismatched) = (0, 0);
    let (mut first_failure, mut first_mismatch) = (None, None);
    for (index, outcome) in outcomes.into_iter().enumerate() {
        match outcome {
            Outcome::Values(values) => {
                for (q, v) in quantities.iter_mut().zip(values) {
                    q.values.push(v);
                }
            }
            Outcome::Mismatched(families) => {
                mismatched += 1;
                first_mismatch.get_or_insert((index, families));
            }
            Outcome::Failed(message) => {
                failed += 1;
                first_failure.get_or_insert((index, message));
            }
        }
    }
    for q in &mut quantities {
        q.stats = Stats::of(&q.values);
    }
    Ok(Study {
        quantities,
        samples,
        failed,
        mismatched,
        first_mismatch,
        first_failure,
        elapsed,
        threads: rayon::current_num_threads(),
    })
}

/// What became of one sample.
enum Outcome {
    /// The quantities, in the order of [`Study::quantities`].
    Values(Vec<f64>),
    /// A tracked mode lost its shape: what became of each, for the report.
    Mismatched(String),
    /// The build, the stage run or the stability check failed: why.
    Failed(String),
}

/// The quantities of the nominal model (values, no samples yet), and the index of each
/// tracked mode (every pitch mode, then every yaw mode) in its mode list.
fn describe(nominal: &StageResult) -> Result<(Vec<Quantity>, Vec<usize>), pendkit::Error> {
    let mut quantities = Vec::new();
    let mut tracked = Vec::new();
    for family in FAMILIES {
        let modes = family_modes(nominal, family);
        tracked.extend(modes.iter().map(|&(index, _)| index));
        for (k, (_, mode)) in modes.iter().enumerate() {
            quantities.push(Quantity {
                name: format!("{}{}", DOF_FAMILIES[family], k + 1),
                nominal_label: mode.label.clone(),
                unit: "Hz".into(),
                nominal: mode.hz,
                values: Vec::new(),
                stats: Stats::of(&[]),
            });
        }
    }
    quantities.push(Quantity {
        name: format!("|{COUPLING_OUTPUT}/{COUPLING_INPUT}|"),
        nominal_label: String::new(),
        // the library knows the unit of every input and output; `None` would be a name it
        // does not know, which `coupling` below reports as an error first
        unit: nominal
            .transfer_unit(COUPLING_INPUT, COUPLING_OUTPUT)
            .unwrap_or_default(),
        nominal: coupling(nominal)?,
        values: Vec::new(),
        stats: Stats::of(&[]),
    });
    Ok((quantities, tracked))
}

/// The modes of one family (an index into [`DOF_FAMILIES`]) with their indices in the mode
/// list, by ascending frequency.
fn family_modes(result: &StageResult, family: usize) -> Vec<(usize, &pendkit::dynamics::Mode)> {
    let mut modes: Vec<_> = result
        .modes
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| result.mode_family(m) == DOF_FAMILIES[family])
        .collect();
    modes.sort_by(|a, b| a.1.hz.total_cmp(&b.1.hz));
    modes
}

/// |H| of the cross-coupling at [`COUPLING_HZ`] (rad/N).
fn coupling(result: &StageResult) -> Result<f64, pendkit::Error> {
    let h = result.transfer(COUPLING_INPUT, COUPLING_OUTPUT, &[COUPLING_HZ])?;
    Ok(h[0].norm())
}

/// One sample: the quad with the errors drawn for `index`, at stage 2.
fn run_sample(
    case: &Case,
    tolerances: &[(&'static str, f64)],
    seed: u64,
    index: usize,
    nominal: &StageResult,
    tracked: &[usize],
) -> Outcome {
    evaluate(
        case,
        &draw_errors(tolerances, seed, index),
        nominal,
        tracked,
    )
    .unwrap_or_else(|e| Outcome::Failed(e.to_string()))
}

/// The errors of sample `index`: each parameter of `tolerances` with its standard deviation
/// times a standard normal deviate, in the order given. Every error is drawn, even with a
/// zero tolerance, so that the k-th parameter's deviate is the same whatever the
/// tolerances are.
fn draw_errors(
    tolerances: &[(&'static str, f64)],
    seed: u64,
    index: usize,
) -> Vec<(&'static str, f64)> {
    let mut rng = SplitMix64::for_sample(seed, index as u64);
    tolerances
        .iter()
        .map(|&(name, sigma)| (name, sigma * rng.gaussian()))
        .collect()
}

/// The quantities of `case` with each parameter of `errors` incremented by its error (SI
/// units), at stage 2: the frequencies of the nominal modes `tracked`, each followed into
/// the sample by the overlap of its shape, then the cross-coupling; [`Outcome::Mismatched`]
/// when a tracked mode kept less than half its shape.
fn evaluate(
    case: &Case,
    errors: &[(&str, f64)],
    nominal: &StageResult,
    tracked: &[usize],
) -> Result<Outcome, pendkit::Error> {
    // `increment(x)` adds to the model's definition (whatever it is); `{:e}` prints the
    // shortest text that reads back as the same f64
    let overrides = errors
        .iter()
        .map(|(name, error)| Override::expression(*name, format!("increment({error:e})")));
    let (system, _parameters) = case.clone().with(overrides)?.build()?;
    let result = run_stage(system, Stage::S2)?;
    result.check_stable()?;
    let continued = result.match_modes(nominal)?;
    let mut values = Vec::new();
    for &old in tracked {
        match continued[old] {
            Some((new, overlap)) if overlap >= 0.5 => values.push(result.modes.modes[new].hz),
            _ => {
                let became: Vec<String> = tracked
                    .iter()
                    .map(|&k| match continued[k] {
                        Some((new, overlap)) => {
                            let m = &result.modes.modes[new];
                            format!(
                                "{} -> {:.3} Hz {} (overlap {overlap:.2})",
                                nominal.modes.modes[k].label,
                                m.hz,
                                result.mode_family(m)
                            )
                        }
                        None => format!("{} -> none", nominal.modes.modes[k].label),
                    })
                    .collect();
                return Ok(Outcome::Mismatched(became.join(", ")));
            }
        }
    }
    values.push(coupling(&result)?);
    Ok(Outcome::Values(values))
}

/// The splitmix64 generator (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): 64 bits of state, statistically sound for a Monte Carlo of
/// this size, and a few lines, so the example needs no random-number crate.
struct SplitMix64(u64);

impl SplitMix64 {
    /// The generator of sample `index` under `seed`: its state is the seed and the index
    /// each passed through the output mix, so neighbouring indices start far apart.
    fn for_sample(seed: u64, index: u64) -> SplitMix64 {
        SplitMix64(mix(seed) ^ mix(index.wrapping_add(0x5851_F42D_4C95_7F2D)))
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    /// Uniform on (0, 1]: 53 random bits, never 0, so that its logarithm is finite.
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A standard normal deviate by the Box–Muller transform (its cosine half only: a
    /// model build costs ~10⁵ times what the second deviate would save).
    fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// splitmix64's output function (a bijection of 64-bit words).
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generator's deviates have mean 0 and variance 1 (4σ bounds for 100 000 draws),
    /// and the percentiles are those of R's and NumPy's default.
    #[test]
    fn generator_and_percentiles() {
        let mut rng = SplitMix64::for_sample(7, 3);
        let z: Vec<f64> = (0..100_000).map(|_| rng.gaussian()).collect();
        let s = Stats::of(&z);
        assert!(s.mean.abs() < 4.0 / (z.len() as f64).sqrt(), "{s:?}");
        assert!(
            (s.std - 1.0).abs() < 4.0 * (0.5 / z.len() as f64).sqrt(),
            "{s:?}"
        );
        // numpy.percentile([1, 2, 3, 4, 5], [1, 99]) = [1.04, 4.96]
        let s = Stats::of(&[5.0, 1.0, 4.0, 2.0, 3.0]);
        assert!(
            (s.p01 - 1.04).abs() < 1e-12 && (s.p99 - 4.96).abs() < 1e-12,
            "{s:?}"
        );
    }

    /// With every tolerance zero, every sample is the nominal model: the same value to
    /// 1e-12 (relative) in every sample, so no spread.
    #[test]
    fn zero_tolerances_give_the_nominal_model() -> Result<(), pendkit::Error> {
        let study = run_study(&Tolerances::ZERO, 40, 1)?;
        assert_eq!((study.failed, study.mismatched), (0, 0));
        // the quad has four pitch and four yaw modes, and the cross-coupling
        assert_eq!(study.quantities.len(), 9);
        for q in &study.quantities {
            assert!(q.nominal.is_finite() && q.nominal > 0.0, "{}", q.name);
            assert_eq!(q.values.len(), 40);
            let close = |v: f64| (v - q.nominal).abs() <= 1e-12 * q.nominal;
            assert!(
                q.values.iter().all(|&v| close(v)),
                "{}: {:?}",
                q.name,
                q.values
            );
            assert!(close(q.stats.mean) && close(q.stats.p01) && close(q.stats.p99));
            assert!(
                q.stats.std <= 1e-12 * q.nominal,
                "{}: {:?}",
                q.name,
                q.stats
            );
        }
        Ok(())
    }

    /// With the same seed the deviates are the same, so halving every tolerance halves
    /// every error: for errors this small the response is linear, and every spread halves
    /// (to 3 %). The same seed gives the same study, whatever the thread schedule.
    #[test]
    fn spread_scales_with_the_tolerances() -> Result<(), pendkit::Error> {
        let full = run_study(&Tolerances::DEFAULT.scaled(0.2), 200, 11)?;
        let half = run_study(&Tolerances::DEFAULT.scaled(0.1), 200, 11)?;
        let again = run_study(&Tolerances::DEFAULT.scaled(0.1), 200, 11)?;
        for ((f, h), a) in full
            .quantities
            .iter()
            .zip(&half.quantities)
            .zip(&again.quantities)
        {
            let ratio = h.stats.std / f.stats.std;
            assert!(
                (ratio - 0.5).abs() < 0.015,
                "{}: spread ratio {ratio}",
                f.name
            );
            assert_eq!(h.values, a.values, "{}", f.name);
        }
        Ok(())
    }

    /// Second method: each sample's quantities against their first-order prediction,
    /// nominal + Σ_k (∂q/∂p_k) δp_k, with the derivatives from central differences of
    /// single-parameter builds and the δp_k the sample's own errors. The residual (the
    /// second-order terms) must be a small part of the spread.
    #[test]
    fn samples_follow_the_linear_prediction() -> Result<(), pendkit::Error> {
        let (n, seed) = (100, 5);
        let tolerances = Tolerances::DEFAULT.scaled(0.1);
        let study = run_study(&tolerances, n, seed)?;
        assert_eq!((study.failed, study.mismatched), (0, 0));

        let case = Case::model(MODEL)?;
        let (system, _) = case.build()?;
        let nominal = run_stage(system, Stage::S2)?;
        let (_, tracked) = describe(&nominal)?;
        let values = |errors: &[(&str, f64)]| match evaluate(&case, errors, &nominal, &tracked) {
            Ok(Outcome::Values(v)) => v,
            _ => panic!("the build with {errors:?} failed"),
        };
        let sigmas = tolerances.per_parameter();
        // ∂q/∂p for every parameter (rows) and quantity (columns), stepping by one sigma
        let jacobian: Vec<Vec<f64>> = sigmas
            .iter()
            .map(|&(name, sigma)| {
                let (plus, minus) = (values(&[(name, sigma)]), values(&[(name, -sigma)]));
                plus.iter()
                    .zip(&minus)
                    .map(|(p, m)| (p - m) / (2.0 * sigma))
                    .collect()
            })
            .collect();
        for (j, q) in study.quantities.iter().enumerate() {
            let mut residual2 = 0.0;
            for (index, value) in q.values.iter().enumerate() {
                let errors = draw_errors(&sigmas, seed, index);
                let linear = q.nominal
                    + errors
                        .iter()
                        .zip(&jacobian)
                        .map(|((_, e), row)| e * row[j])
                        .sum::<f64>();
                residual2 += (value - linear).powi(2);
            }
            let rms = (residual2 / n as f64).sqrt();
            assert!(
                rms < 0.02 * q.stats.std,
                "{}: residual {rms:e}, spread {:e}",
                q.name,
                q.stats.std
            );
        }
        Ok(())
    }
}
