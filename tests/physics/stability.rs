//! Stability verdicts where methods fail (issue 11): growing modes with their growth rates
//! checked against closed forms and against a second eigen-solve, massless floats held by
//! a negative stiffness, bodies upside down, and the refusal of unstable equilibria by
//! every calculation that answers with a linearised model.

use std::f64::consts::PI;

use nalgebra::DMatrix;
use pendkit::dynamics::Verdict;
use pendkit::{Case, StageResult, run_stage};
use pendkit_system::Stage;

fn run(model: &str, sets: &[&str], stage: Stage) -> StageResult {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = Case::model(model)
        .and_then(|c| c.with_sets(&sets))
        .expect("case");
    let (system, _) = case.build().expect("model builds");
    run_stage(system, stage).expect("stage runs")
}

/// Growth rate (Hz) of the fastest growing mode; panics if nothing grows.
fn fastest_rate(r: &StageResult) -> (f64, f64) {
    let g = r.stability.growing.first().expect("a growing mode");
    (g.rate_hz, g.accuracy)
}

/// The lowest ω² (rad²/s²) and the largest |ω²| by a second method on the same matrices:
/// nalgebra's Cholesky of M and symmetric eigen-solve of L⁻¹ K_eff L⁻ᵀ (the library uses
/// faer, with K's or K + σM's factor). Its eigenvalues carry an absolute error of about
/// n ε max|ω²|, so it is a reference only where that is small next to |ω²_min|.
fn dense_extremes(r: &StageResult) -> (f64, f64) {
    let reduced = pendkit_dynamics::eliminate_floats(
        &r.model.real_stiffness(&r.system.damping),
        &r.assembled.layout,
        &r.system,
    )
    .expect("floats eliminated");
    let m: DMatrix<f64> = r.assembled.mass.to_dense();
    let li = m
        .cholesky()
        .expect("M positive definite")
        .l()
        .try_inverse()
        .unwrap();
    let a = &li * &reduced.k_eff * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let eig = a.symmetric_eigenvalues();
    let lowest = eig.iter().cloned().fold(f64::INFINITY, f64::min);
    let largest = eig.iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
    (lowest, largest)
}

/// The lowest ω² (rad²/s²) by a shifted solve in another library and formulation:
/// nalgebra's Cholesky L of K_eff + σM for a fixed σ (rad²/s²) that must make it positive
/// definite, then the largest eigenvalue μ of L⁻¹ M L⁻ᵀ: ω²_min = 1/μ_max − σ. μ_max is
/// resolved to a few n ε of itself, so ω²_min to n ε (ω²_min + σ), however stiff the rest.
fn shifted_lowest(r: &StageResult, sigma: f64) -> f64 {
    let reduced = pendkit_dynamics::eliminate_floats(
        &r.model.real_stiffness(&r.system.damping),
        &r.assembled.layout,
        &r.system,
    )
    .expect("floats eliminated");
    let m: DMatrix<f64> = r.assembled.mass.to_dense();
    let shifted = &reduced.k_eff + &m * sigma;
    let shifted = (&shifted + shifted.transpose()) * 0.5;
    let li = shifted
        .cholesky()
        .expect("K + σM positive definite")
        .l()
        .try_inverse()
        .unwrap();
    let b = &li * &m * li.transpose();
    let b = (&b + b.transpose()) * 0.5;
    let mu_max = b
        .symmetric_eigenvalues()
        .iter()
        .cloned()
        .fold(0.0f64, f64::max);
    1.0 / mu_max - sigma
}

#[test]
fn quad_with_the_pitch_break_off_passed_is_unstable_and_names_the_test_mass_pitch() {
    // d4 = −0.02 m puts the test mass's wire break-off above its centre of mass: the
    // pitch of the lowest stages becomes an inverted pendulum (issue 11's first example).
    let r = run("quad", &["d4=-0.02"], Stage::S2);
    assert_eq!(r.stability.verdict, Verdict::Unstable);
    let g = &r.stability.growing[0];
    assert_eq!(g.dominant[0].0, "pitch3", "{}", r.stability);
    assert!(g.rate_hz > 0.0 && g.rate_hz.is_finite());
    let message = r.check_stable().unwrap_err().to_string();
    assert!(!message.contains('\n'), "one line: {message}");
    assert!(
        message.contains("grows at") && message.contains("pitch3"),
        "{message}"
    );
    // every linearised answer refuses it; with allow_unstable it warns instead
    assert!(r.require_stable(false).is_err());
    let warning = r.require_stable(true).unwrap().expect("a warning");
    assert!(warning.contains("pitch3"), "{warning}");
    // the library's plain answers refuse it with the same line; the `_with` forms, for a
    // caller that goes on from an unstable plant on purpose, answer
    let freqs = [0.1, 1.0];
    let refused = r.transfer("x00", "pitch3", &freqs).unwrap_err().to_string();
    assert_eq!(refused, message);
    let refused = r.noise("pitch3", &freqs).unwrap_err().to_string();
    assert_eq!(refused, message);
    let h = r
        .transfer_with("x00", "pitch3", &freqs, pendkit::Solver::Restricted)
        .expect("answers when asked to go on");
    assert!(h.iter().all(|z| z.re.is_finite() && z.im.is_finite()));
    // nominal: stable
    let nominal = run("quad", &[], Stage::S2);
    assert_eq!(nominal.stability.verdict, Verdict::Stable);
    assert!(nominal.require_stable(false).unwrap().is_none());
}

#[test]
fn massless_float_on_a_negative_spring_is_unstable_not_a_stable_mode() {
    // toy: support –k1– float q –k2– mass. With k1 = −4000, k2 = 3000 the condensed
    // stiffness k1 k2 / (k1 + k2) = 12000 N/m is positive (a "stable 17.4 Hz mode"), but the
    // massless float sits on a maximum: k1 + k2 = −1000 N/m with the mass held.
    let r = run("toy", &["k1=-4000"], Stage::S0A);
    assert_eq!(r.stability.verdict, Verdict::Unstable, "{}", r.stability);
    let float = &r.stability.runaway_floats[0];
    assert_eq!(float.floats[0].0, "q");
    // closed form: Q = k1 + k2 = −1000 N/m; rounding of a few ulps of 4000 N/m
    assert!(
        (float.stiffness + 1000.0).abs() < 1e-9,
        "{}",
        float.stiffness
    );
    assert!(
        r.check_stable()
            .unwrap_err()
            .to_string()
            .contains("float 'q'")
    );
}

#[test]
fn growth_rate_of_a_condensed_spring_matches_the_closed_form_to_its_stated_accuracy() {
    // toy with k1 = −1000 N/m and k2 from 3e3 to 1e15 N/m (stiffness ratios to 1e12): the
    // float is held (k1 + k2 > 0) and the mass sees k1 k2 / (k1 + k2) < 0, so it grows at
    // sqrt(−k1 k2 / (k1 + k2) / m) / 2π. Forming that condensed stiffness in double
    // precision loses ε k2 / |k1| of it, so the tolerance is the accuracy the result
    // states, and that statement must stay honest (below 1 %) and useful (it shrinks as
    // k2 does).
    let mut previous_accuracy = f64::INFINITY;
    for k2 in [1e15f64, 1e12, 1e9, 3e3] {
        let r = run("toy", &["k1=-1000", &format!("k2={k2:e}")], Stage::S0A);
        let k1 = -1000.0;
        let exact = (-k1 * k2 / (k1 + k2)).sqrt() / (2.0 * PI);
        let (rate, accuracy) = fastest_rate(&r);
        assert!(
            (rate - exact).abs() <= accuracy * exact,
            "k2 {k2:e}: {rate} vs {exact} (stated accuracy {accuracy:e})"
        );
        assert!(
            accuracy < 1e-2 && accuracy <= previous_accuracy,
            "{accuracy:e}"
        );
        previous_accuracy = accuracy;
    }
    assert!(previous_accuracy < 1e-12);
}

#[test]
fn growth_rate_with_hundreds_of_bead_unknowns_matches_a_second_eigen_solve() {
    // quad with 40 violin beads per fibre (over 500 unknowns, light beads on stiff fibre
    // segments: a dense mass-factor solve is off by several % here) and the pitch
    // break-off passed: the growth rate from the library's solve against nalgebra's
    // Cholesky of K_eff + σM with a fixed σ = 10 rad²/s² (the growth rate is near
    // 0.33 Hz, ω² ≈ −4.2 rad²/s²). Tolerance: that solve's error, 4 n ε (ω² + σ)/|ω²| on
    // ω² (half on the rate), plus the library's stated accuracy.
    let r = run("quad-v5", &["d4=-0.02", "n_beads=40"], Stage::S2);
    assert!(r.modes.coordinates.len() > 500);
    let (rate, accuracy) = fastest_rate(&r);
    let sigma = 10.0;
    let lowest = shifted_lowest(&r, sigma);
    let reference = (-lowest).sqrt() / (2.0 * PI);
    let n = r.modes.coordinates.len() as f64;
    let reference_error = 4.0 * n * f64::EPSILON * (lowest + sigma) / lowest.abs();
    assert!(
        (rate - reference).abs() <= (0.5 * reference_error + accuracy) * reference,
        "{rate} vs {reference}: reference error {reference_error:e}, stated {accuracy:e}"
    );
    assert_eq!(r.stability.growing.len(), 1, "{}", r.stability);
}

#[test]
fn growth_rate_with_blades_stiff_to_1e12_follows_the_well_conditioned_limit() {
    // quad-full (blade tips as massless floats) with the pitch break-off passed, and the
    // blades' non-working translations stiffened from 1e9 to 1e12 N/m. The growth rate
    // approaches the rigid-blade limit as r(k) = r∞ + c/k. At 1e9 and 1e10 N/m the problem
    // is well conditioned and a second method (nalgebra's dense solve) confirms the
    // library's values; the two give r∞ and c, which predict r(1e12). At 1e12 the dense
    // mass-factor solve is off by about 1e-4 (rounding of the condensed stiffness
    // amplified by the stiffness ratio): the library must agree with the prediction within
    // its stated accuracy plus the extrapolation's own error (c/k² terms: 1e-3 of c/1e10).
    let rate_at = |k: f64| {
        let r = run(
            "quad-full",
            &["d4=-0.02", &format!("blade_stiff_translation={k:e}")],
            Stage::S2,
        );
        let (rate, accuracy) = fastest_rate(&r);
        (r, rate, accuracy)
    };
    let mut well_conditioned = Vec::new();
    for k in [1e9, 1e10] {
        let (r, rate, accuracy) = rate_at(k);
        let (lowest, largest) = dense_extremes(&r);
        let dense_rate = (-lowest).sqrt() / (2.0 * PI);
        let n = r.modes.coordinates.len() as f64;
        let dense_error = 4.0 * n * f64::EPSILON * largest / lowest.abs();
        assert!(
            (rate - dense_rate).abs() <= (0.5 * dense_error + accuracy + 1e-9) * rate,
            "k {k:e}: {rate} vs {dense_rate} (dense error {dense_error:e}, stated {accuracy:e})"
        );
        well_conditioned.push((k, rate));
    }
    let [(k_a, r_a), (k_b, r_b)] = [well_conditioned[0], well_conditioned[1]];
    let c = (r_a - r_b) / (1.0 / k_a - 1.0 / k_b);
    let limit = r_b - c / k_b;
    let (_, rate, accuracy) = rate_at(1e12);
    let predicted = limit + c / 1e12;
    let extrapolation = 1e-3 * (c / k_b).abs() + 1e-9 * limit;
    assert!(
        (rate - predicted).abs() <= accuracy * predicted + extrapolation,
        "{rate} vs predicted {predicted} (stated {accuracy:e}, extrapolation {extrapolation:e})"
    );
    assert!(accuracy < 1e-4, "{accuracy:e}");
}

#[test]
fn upside_down_minimum_from_a_tilted_start_is_named_and_not_stable() {
    // quad with the top mass started at 3 rad of pitch: Newton lands on a minimum with the
    // top and UIM turned over (nothing grows there: the wires' clamps hold them). It is not
    // the hanging suspension and must not be reported stable.
    let case = Case::model("quad").unwrap();
    let (mut system, _) = case.build().unwrap();
    let pitch = system
        .coords
        .iter_mut()
        .find(|c| c.name == "pitch1")
        .expect("pitch1");
    pitch.start = 3.0;
    let r = run_stage(system, Stage::S0A).expect("stage runs");
    assert_eq!(r.stability.verdict, Verdict::Inverted, "{}", r.stability);
    assert!(!r.stability.is_stable());
    let bodies: Vec<&str> = r
        .stability
        .inverted
        .iter()
        .map(|b| b.body.as_str())
        .collect();
    assert!(bodies.contains(&"top"), "{bodies:?}");
    let message = r.check_stable().unwrap_err().to_string();
    assert!(
        message.contains("upside down") && message.contains("'top'"),
        "{message}"
    );
}

/// The modes take a mode's stiffness rounding from a cheap bound (each term's geometric
/// part |zᵀ G z| replaced by |z|ᵀ |G| |z|, summed once over the stage) where that bound
/// already puts the mode far below the accuracy anything reports, and from the
/// term-by-term estimate otherwise (issue 9: the term-by-term pass for every mode made the
/// modes 2–10× slower). Guards both halves: the bound is never below the estimate it
/// stands for, on every mode of models with wires (amplified geometric parts), blades and
/// floats; and the stated error always covers the term-by-term estimate. (That the coarse
/// figure is kept only below REFINE_ABOVE is checked where the two can be told apart, in
/// the dynamics crate's unit tests.)
#[test]
fn the_rounding_bound_covers_the_term_by_term_estimate_on_every_mode() {
    use pendkit_dynamics::{StiffnessRounding, TermRounding};
    // nominal models (every mode far below reporting: the bound is kept) and ill-conditioned
    // ones (growth rates known to 1e-4 or worse: the finer estimate is used)
    for (model, sets, stage) in [
        ("quad", vec![], Stage::S2),
        ("quad-full", vec![], Stage::S2),
        ("quad", vec!["d4=-0.02"], Stage::S0A),
        ("toy", vec![], Stage::S0A),
        ("toy", vec!["k1=-1000", "k2=1e12"], Stage::S0A),
        (
            "quad-full",
            vec!["d4=-0.02", "blade_stiff_translation=1e12"],
            Stage::S2,
        ),
        ("chain", vec!["n_stages=6"], Stage::S2),
    ] {
        let r = run(model, &sets, stage);
        let rounding = TermRounding::new(&r.model, &r.assembled, &r.system.damping);
        for mode in &r.modes.modes {
            let (fine, coarse) = (rounding.error(&mode.vector), rounding.bound(&mode.vector));
            // the bound differs only by replacing |Σ| by Σ|·| per term: never smaller, up
            // to the rounding of the sums themselves
            assert!(
                coarse >= fine * (1.0 - 1e-12),
                "{model} {}: bound {coarse:e} below estimate {fine:e}",
                mode.label
            );
            // whichever figure a mode keeps, it covers the term-by-term estimate
            assert!(
                mode.omega_squared_error >= fine * (1.0 - 1e-12),
                "{model} {}: stated {:e} below the estimate {fine:e}",
                mode.label,
                mode.omega_squared_error
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// An independent check of the verdict (issue 11, brief C): the stiffness over the
// variables and floats, its float block's eigenvalues, the float elimination and the
// generalised eigenvalues of (K_eff, M), all by nalgebra's dense LU, Cholesky and
// symmetric eigen-solve (the library uses faer, a pattern-ordered sparse assembly, a
// block split and shifted factorisations), from the per-term Hessians summed afresh and,
// for small models, from central differences of the energy gradient.
// ---------------------------------------------------------------------------------------

/// The stiffness over the unknowns (variables then floats, layout order) as the plain
/// sum of the terms' tension-on Hessians (N/m, N/rad, N m/rad): every model swept here
/// has ε'(0) = 1 for every tag, so this is the stage's real stiffness at f = 0.
fn summed_stiffness(r: &StageResult) -> DMatrix<f64> {
    let (nx, nq, _) = r.assembled.layout.sizes();
    r.assembled
        .stiffness()
        .view((0, 0), (nx + nq, nx + nq))
        .into_owned()
}

/// The stiffness over the unknowns by central differences of the net generalised force
/// of the stage's terms, rebuilt here around the equilibrium (all registered kinds that
/// join at or before the stage, the case's extra terms and constraints). Step h = 1e-6
/// (m or rad): truncation h² times third derivatives, rounding ε |force| / h.
fn finite_difference_stiffness(r: &StageResult) -> DMatrix<f64> {
    use pendkit_energy::{Reference, constraint_terms, extra_terms, registry};
    use pendkit_system::ExtraPhase;
    let system = &r.system;
    let x0 = r.assembled.equilibrium.coords.clone();
    let stage = r.assembled.stage;
    let reference = Reference::new(system, &x0);
    let mut terms = Vec::new();
    for kind in registry() {
        if system
            .element_stage(kind.kind(), kind.stage())
            .is_some_and(|s| s <= stage)
        {
            terms.extend(kind.terms(&reference).expect("terms"));
        }
    }
    terms.extend(extra_terms(system, ExtraPhase::BeforeEquilibrium, None).expect("extra"));
    terms.extend(extra_terms(system, ExtraPhase::AfterEquilibrium, Some(&x0)).expect("extra"));
    terms.extend(constraint_terms(system, &x0).expect("constraints"));
    let layout = &r.assembled.layout;
    let unknowns: Vec<usize> = layout
        .variables
        .iter()
        .chain(&layout.floats)
        .copied()
        .collect();
    let force = |x: &[f64]| -> Vec<f64> {
        let mut g = vec![0.0; x.len()];
        for term in &terms {
            let d = term.derivatives(x).expect("derivatives");
            for (a, &i) in term.coords.iter().enumerate() {
                g[i] += d.gradient[a];
            }
        }
        unknowns.iter().map(|&i| g[i]).collect()
    };
    let n = unknowns.len();
    let h = 1e-6;
    let mut k = DMatrix::zeros(n, n);
    for (j, &gj) in unknowns.iter().enumerate() {
        let (mut plus, mut minus) = (x0.clone(), x0.clone());
        plus[gj] += h;
        minus[gj] -= h;
        let (fp, fm) = (force(&plus), force(&minus));
        for i in 0..n {
            k[(i, j)] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    (&k + k.transpose()) * 0.5
}

/// The independent verdict's evidence.
#[derive(Debug)]
struct Independent {
    /// Eigenvalues of the float block Q (N/m or N m/rad), ascending, and their absolute
    /// error (a few n ε ‖Q‖).
    float_eigenvalues: Vec<f64>,
    float_error: f64,
    /// Generalised eigenvalues ω² of (K_eff, M) (rad²/s²), ascending, and their common
    /// absolute error: the dense solve's n ε ‖L⁻¹ K_eff L⁻ᵀ‖ plus the rounding of
    /// forming K_eff, ε ‖L⁻¹‖² ‖|K| + |C| |Q⁻¹| |Cᵀ|‖ (the float elimination's
    /// amplification by the float block's conditioning).
    omega_squared: Vec<f64>,
    omega_squared_error: f64,
}

/// Σ over the terms of |H_on| over the unknowns: what the summed stiffness's entries are
/// rounded relative to (each term's entries to a few ulps of themselves).
fn summed_abs_stiffness(r: &StageResult) -> DMatrix<f64> {
    let (nx, nq, _) = r.assembled.layout.sizes();
    let n = nx + nq;
    let mut a = DMatrix::zeros(n, n);
    for t in &r.assembled.terms {
        let m = t.coords.len();
        for (i, &gi) in t.coords.iter().enumerate() {
            for (j, &gj) in t.coords.iter().enumerate() {
                let (pi, pj) = (
                    r.assembled.layout.position[gi],
                    r.assembled.layout.position[gj],
                );
                if pi < n && pj < n {
                    a[(pi, pj)] += t.on[i * m + j].abs();
                }
            }
        }
    }
    a
}

impl Independent {
    fn new(k: &DMatrix<f64>, abs_k: &DMatrix<f64>, mass: &DMatrix<f64>, nx: usize) -> Independent {
        let n = k.nrows();
        let nq = n - nx;
        let eps = f64::EPSILON;
        let kxx = k.view((0, 0), (nx, nx)).into_owned();
        let (k_eff, entries) = if nq > 0 {
            let q = k.view((nx, nx), (nq, nq)).into_owned();
            let c = k.view((nx, 0), (nq, nx)).into_owned();
            let q_inv = q.clone().try_inverse().expect("float block invertible");
            let k_eff = &kxx - c.transpose() * &q_inv * &c;
            let entries = abs_k.view((0, 0), (nx, nx)).into_owned()
                + c.abs().transpose() * q_inv.abs() * c.abs();
            (k_eff, entries)
        } else {
            (kxx.clone(), abs_k.view((0, 0), (nx, nx)).into_owned())
        };
        let (float_eigenvalues, float_error) = if nq > 0 {
            let q = k.view((nx, nx), (nq, nq)).into_owned();
            // ‖ Σ|H_t| ‖ over the float block bounds the rounding of Q's entries (the sum
            // of the terms cancels; their sizes do not)
            let norm = abs_k.view((nx, nx), (nq, nq)).into_owned().norm();
            let mut e: Vec<f64> = q.symmetric_eigenvalues().iter().copied().collect();
            e.sort_by(f64::total_cmp);
            (e, 16.0 * nq as f64 * eps * norm)
        } else {
            (Vec::new(), 0.0)
        };
        let li = mass
            .clone()
            .cholesky()
            .expect("M positive definite")
            .l()
            .try_inverse()
            .expect("L invertible");
        let a = &li * &k_eff * li.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let mut omega_squared: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
        omega_squared.sort_by(f64::total_cmp);
        let top = omega_squared.iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
        let li_norm = li.norm(); // Frobenius ≥ 2-norm
        let entries_norm = entries.norm();
        let omega_squared_error =
            16.0 * nx as f64 * eps * top + 16.0 * eps * li_norm * li_norm * entries_norm;
        Independent {
            float_eigenvalues,
            float_error,
            omega_squared,
            omega_squared_error,
        }
    }

    /// Negative eigenvalues beyond the errors: (floats, modes).
    fn clearly_negative(&self) -> (usize, usize) {
        (
            self.float_eigenvalues
                .iter()
                .filter(|&&k| k < -self.float_error)
                .count(),
            self.omega_squared
                .iter()
                .filter(|&&w| w < -self.omega_squared_error)
                .count(),
        )
    }
}

/// What is wrong with the library's verdict for `r`, judged against `reference`: a
/// confident verdict contradicted beyond both sides' stated errors, or a growth rate
/// outside them. Empty when the two agree.
fn verdict_disagreements(
    r: &StageResult,
    k: &DMatrix<f64>,
    reference: &Independent,
) -> Vec<String> {
    let s = &r.stability;
    let (nx, _, _) = r.assembled.layout.sizes();
    let mut wrong = Vec::new();
    let (float_neg, mode_neg) = reference.clearly_negative();
    // every clearly negative float direction is reported
    if s.runaway_floats.len() < float_neg {
        wrong.push(format!(
            "{float_neg} float direction(s) negative ({:?} ± {:e}), {} reported",
            &reference.float_eigenvalues[..float_neg],
            reference.float_error,
            s.runaway_floats.len()
        ));
    }
    // a reported runaway float is negative in the reference beyond its error, or (zero
    // within its stated error) the whole stiffness stays indefinite with the float block
    // made as stiff as that error allows: + δ I on it
    let lowest_float = reference.float_eigenvalues.first().copied().unwrap_or(0.0);
    let undetermined = s.runaway_floats.iter().any(|f| f.stiffness >= -f.error);
    for f in &s.runaway_floats {
        if f.stiffness < -f.error && lowest_float > reference.float_error {
            wrong.push(format!(
                "float {:?} reported at {:e} N/m, the reference's lowest is {lowest_float:e} ± {:e}",
                f.floats, f.stiffness, reference.float_error
            ));
        }
        if f.stiffness >= -f.error {
            let mut stiffer = k.clone();
            for i in nx..k.nrows() {
                stiffer[(i, i)] += f.error + f.stiffness.abs();
            }
            let lowest = stiffer.symmetric_eigenvalues().min();
            if lowest >= 0.0 {
                wrong.push(format!(
                    "float {:?} reported as runaway within rounding ({:e} ± {:e}), but the stiffness with the floats held that much more is positive definite",
                    f.floats, f.stiffness, f.error
                ));
            }
        }
    }
    // the growing modes: each clearly negative reference ω² is reported, and each
    // reported one is negative in the reference, with matching growth rates
    if float_neg == 0 && !undetermined {
        for (i, &w2) in reference.omega_squared.iter().enumerate() {
            let lib = r.modes.modes.get(i);
            let lib_w2 = lib.map_or(f64::NAN, |m| m.omega_squared);
            let lib_err = lib.map_or(0.0, |m| m.omega_squared_error);
            let tolerance = reference.omega_squared_error + lib_err;
            if (w2 - lib_w2).abs() > tolerance && (w2 < 0.0 || lib_w2 < 0.0) {
                wrong.push(format!(
                    "mode {}: ω² {lib_w2:e} ± {lib_err:e}, reference {w2:e} ± {:e}",
                    i + 1,
                    reference.omega_squared_error
                ));
            }
        }
        if mode_neg > s.growing.len() {
            wrong.push(format!(
                "{mode_neg} mode(s) clearly growing, {} reported",
                s.growing.len()
            ));
        }
    }
    let clearly_unstable = float_neg + mode_neg > 0;
    let clearly_stable = reference
        .float_eigenvalues
        .iter()
        .all(|&k| k > reference.float_error)
        && reference
            .omega_squared
            .iter()
            .all(|&w| w > reference.omega_squared_error);
    // a stable verdict never rests on a float stiffness within rounding of zero
    let float_undetermined = reference
        .float_eigenvalues
        .iter()
        .any(|k| k.abs() <= reference.float_error);
    if s.verdict == Verdict::Stable && float_undetermined {
        wrong.push(format!(
            "stable, but a float stiffness is zero within rounding ({:?} ± {:e})",
            reference.float_eigenvalues, reference.float_error
        ));
    }
    match s.verdict {
        Verdict::Stable | Verdict::Neutral if clearly_unstable => wrong.push(format!(
            "{:?} but the reference has negative directions",
            s.verdict
        )),
        Verdict::Unstable if clearly_stable => {
            wrong.push("unstable but the reference is positive definite".into())
        }
        _ => {}
    }
    wrong
}

/// One point of the sweep: the library's verdict against the reference from the summed
/// Hessians, and for small models the summed Hessians against finite differences.
fn check_point(model: &str, sets: &[&str], stage: Stage, fd: bool) -> Result<String, String> {
    let sets_owned: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = Case::model(model)
        .and_then(|c| c.with_sets(&sets_owned))
        .map_err(|e| format!("case: {e}"))?;
    let (system, _) = case
        .build()
        .map_err(|e| format!("{model} {sets:?}: build: {e}"))?;
    let r = match run_stage(system, stage) {
        Ok(r) => r,
        // refusing is allowed (a stated limit); a wrong verdict is not
        Err(e) => return Ok(format!("{model} {sets:?}: refused: {e}")),
    };
    let (nx, _, _) = r.assembled.layout.sizes();
    let k = summed_stiffness(&r);
    let abs_k = summed_abs_stiffness(&r);
    let reference = Independent::new(&k, &abs_k, &r.assembled.mass.to_dense(), nx);
    let mut wrong = verdict_disagreements(&r, &k, &reference);
    if fd {
        let k_fd = finite_difference_stiffness(&r);
        let scale = k.abs().max().max(1e-300);
        let diff = (&k_fd - &k).abs().max();
        if diff > 1e-5 * scale {
            wrong.push(format!(
                "finite differences differ by {diff:e} (scale {scale:e})"
            ));
        }
        // and the verdict from the differenced stiffness (a second Hessian path) agrees
        // with the library's as well, at the differences' own accuracy (1e-5 of the
        // largest entry, in place of the summed Hessians' rounding)
        let fd_abs = abs_k.map(|x| x + 1e-5 * scale / (16.0 * f64::EPSILON));
        let fd_reference = Independent::new(&k_fd, &fd_abs, &r.assembled.mass.to_dense(), nx);
        for w in verdict_disagreements(&r, &k_fd, &fd_reference) {
            wrong.push(format!("by finite differences: {w}"));
        }
    }
    let line = format!(
        "{model} {sets:?}: {} Qmin {:?}",
        verdict_line(&r, &reference),
        reference.float_eigenvalues.first(),
    );
    with_disagreements(line, &wrong)
}

/// The library's verdict (growth rates, runaway floats, inverted bodies) beside the
/// independent check's lowest ω², for the sweep's log.
fn verdict_line(r: &StageResult, reference: &Independent) -> String {
    format!(
        "{:?} growing {:?} floats {:?} inverted {:?} | ref ω²min {:e} ± {:e}",
        r.stability.verdict,
        r.stability
            .growing
            .iter()
            .map(|g| (g.rate_hz, g.accuracy))
            .collect::<Vec<_>>(),
        r.stability
            .runaway_floats
            .iter()
            .map(|f| f.stiffness)
            .collect::<Vec<_>>(),
        r.stability.inverted,
        reference.omega_squared.first().copied().unwrap_or(f64::NAN),
        reference.omega_squared_error,
    )
}

/// `line` when nothing disagreed, else an error listing what did.
fn with_disagreements(line: String, wrong: &[String]) -> Result<String, String> {
    if wrong.is_empty() {
        Ok(line)
    } else {
        Err(format!("{line}\n    WRONG: {}", wrong.join("; ")))
    }
}

/// Issue 11's target, zero wrong verdicts, over a representative sweep of every bundled
/// model family toward and past instability: negative and tiny break-off distances,
/// negative springs on the toy's float (to within an ulp of the float's balance), stiffness
/// ratios to 1e12, heavy masses, g = 0 and negative, blade springs at zero and negative,
/// 40 violin beads per fibre, long chains. Each point's verdict, growing modes and runaway
/// floats are judged against the independent dense solve above ([`verdict_disagreements`]:
/// a disagreement counts only beyond both sides' stated errors, so marginal points may be
/// neutral but never confidently wrong), and for the small models the summed Hessians
/// against central differences of the energy gradient (to 1e-5 of the largest entry: the
/// differences' truncation and rounding at h = 1e-6). Refusals (a stated limit of the
/// method, e.g. a wire stretched below what double precision resolves) are allowed.
#[test]
fn verdicts_agree_with_an_independent_dense_solve_across_the_bundled_models() {
    let mut bad = Vec::new();
    for (model, sets, stage, fd) in &sweep_points() {
        let sets: Vec<&str> = sets.iter().map(|s| s.as_str()).collect();
        if let Err(line) = check_point(model, &sets, *stage, *fd) {
            bad.push(line);
        }
    }
    assert!(bad.is_empty(), "{} wrong:\n{}", bad.len(), bad.join("\n"));
}

#[expect(
    clippy::too_many_lines,
    reason = "a table of the sweep's points, one loop per model and parameter region with its \
              finite-difference flag; a point is added or found by reading down the one list"
)]
fn sweep_points() -> Vec<(&'static str, Vec<String>, Stage, bool)> {
    let mut p = Vec::new();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    for k1 in [
        "-4000",
        "-3000.0001",
        "-2999.9999",
        "-1000",
        "-1e-9",
        "0.0",
        "1e-12",
        "1000",
    ] {
        p.push(("toy", s(&[&format!("k1={k1}")]), Stage::S0A, true));
    }
    for k1 in [
        "-2999.999999999999",
        "-2999.99999999999",
        "-2999.9999999999",
        "-2999.999999999",
        "-3000.000000000001",
        "-3000.00000000001",
        "-3000.0000000001",
    ] {
        p.push(("toy", s(&[&format!("k1={k1}")]), Stage::S0A, false));
    }
    for k2 in ["1e15", "1e12", "-1e12", "-999.99", "-1000.01"] {
        p.push((
            "toy",
            s(&["k1=-1000", &format!("k2={k2}")]),
            Stage::S0A,
            true,
        ));
    }
    for model in ["pendulum", "double-pendulum", "rigid-body"] {
        for g in ["9.81", "0", "1e-12", "-9.81"] {
            p.push((model, s(&[&format!("g={g}")]), Stage::S2, true));
        }
    }
    for sets in [
        vec![],
        vec!["d4=-0.02"],
        vec!["d4=-1e-3"],
        vec!["d4=-1e-4"],
        vec!["d4=-1e-5"],
        vec!["d4=-1e-6"],
        vec!["d4=0"],
        vec!["d4=1e-6"],
        vec!["d2=-0.01"],
        vec!["d0=-0.01"],
        vec!["d1=-0.01"],
        vec!["d3=-0.01"],
        vec!["dn=-0.01"],
        vec![
            "d0=-0.003",
            "d1=-0.003",
            "d2=-0.003",
            "d3=-0.003",
            "d4=-0.003",
        ],
        vec!["ufc1=1e-6"],
        vec!["mn=1000"],
        vec!["m1=500"],
        vec!["m3=1000"],
        vec!["g=0"],
        vec!["Yn=2.2e17"],
        vec!["Y3=7e16", "d4=-0.02"],
        vec!["rn=scale(30)"],
        vec!["m3=1e-3"],
        vec!["m3=1e-3", "d4=-0.02"],
        // a tiny pitch inertia: the test mass as a rod along y (I3x = I3z), so that it is
        // a body (each moment at most the other two together)
        vec!["I3x=0.41811", "I3y=1e-9"],
        vec!["I3x=0.41811", "I3y=1e-9", "d4=-0.02"],
        vec!["mn=1e4"],
        vec!["mn=1e4", "d0=-0.02"],
        vec!["d1=-0.05", "d3=-0.05"],
    ] {
        p.push(("quad", s(&sets), Stage::S2, false));
    }
    p.push(("quad", s(&[]), Stage::S0A, true));
    p.push(("quad", s(&["d4=-0.02"]), Stage::S0A, true));
    for sets in [vec!["kv_2=1e-9"], vec!["d4=-0.02"]] {
        p.push(("quad-aligo", s(&sets), Stage::S2, false));
    }
    for sets in [
        vec!["d4=-0.02", "n_beads=40"],
        vec!["d4=-1e-4", "n_beads=20"],
        vec!["n_beads=20"],
    ] {
        p.push(("quad-v5", s(&sets), Stage::S2, false));
    }
    for sets in [
        vec!["d4=-0.02", "blade_stiff_translation=1e12"],
        vec!["blade_stiff_translation=0"],
        vec!["blade_stiff_translation=-1e3"],
        vec!["blade_stiff_rotation=-1"],
        vec!["blade_stiff_rotation=0"],
    ] {
        p.push(("quad-full", s(&sets), Stage::S2, false));
    }
    for sets in [
        vec![],
        vec!["d4=-0.01"],
        vec!["d2=-0.005"],
        vec!["ufc1=1e-3"],
    ] {
        p.push(("triple", s(&sets), Stage::S2, false));
    }
    for sets in [
        vec!["n_stages=10"],
        vec!["n_stages=10", "d_bottom=-0.02"],
        vec!["d_top=-0.02"],
        vec!["E_wire=2.12e17"],
        vec!["g=0"],
        vec!["n_stages=3", "d_bottom=-1e-5"],
    ] {
        p.push(("chain", s(&sets), Stage::S2, false));
    }
    // every stage, and the other quad and triple variants, past the break-off
    for stage in [Stage::S0A, Stage::S0B, Stage::S1A, Stage::S1B] {
        p.push(("quad", s(&["d4=-0.02"]), stage, false));
        p.push(("quad-full", s(&["d4=-0.02"]), stage, false));
    }
    for model in [
        "quad-lite",
        "quad-lateral",
        "triple-lite",
        "triple-full",
        "triple-lateral",
    ] {
        p.push((model, s(&["d4=-0.02"]), Stage::S2, false));
        p.push((model, s(&[]), Stage::S1B, false));
    }
    p.push((
        "triple-v5",
        s(&["d4=-0.01", "n_beads=10"]),
        Stage::S2,
        false,
    ));
    p
}

/// [`check_point`] for a system built by the caller: the line and the result (none when
/// refused), or the disagreements.
fn check_system(
    label: &str,
    system: pendkit_system::System,
    stage: Stage,
) -> Result<(String, Option<StageResult>), String> {
    let r = match run_stage(system, stage) {
        Ok(r) => r,
        Err(e) => return Ok((format!("{label}: refused: {e}"), None)),
    };
    let (nx, _, _) = r.assembled.layout.sizes();
    let k = summed_stiffness(&r);
    let reference = Independent::new(
        &k,
        &summed_abs_stiffness(&r),
        &r.assembled.mass.to_dense(),
        nx,
    );
    let wrong = verdict_disagreements(&r, &k, &reference);
    let line = format!(
        "{label}: {} | {}",
        verdict_line(&r, &reference),
        r.stability
    );
    with_disagreements(line, &wrong).map(|line| (line, Some(r)))
}

/// Equilibria reached from tilted starts (Newton lands on the hanging one, on an
/// upside-down minimum, or on a saddle): the verdict agrees with the independent dense
/// solve, and a body found upside down is named (never a stable verdict).
#[test]
fn equilibria_from_tilted_starts_agree_with_the_independent_solve() {
    let mut bad = Vec::new();
    for (model, coord, start) in [
        ("quad", "pitch1", 3.0),
        ("quad", "pitch1", 1.6),
        ("quad", "pitch1", 1.2),
        ("quad", "yaw1", 3.0),
        ("quad", "yaw1", 1.6),
        ("quad", "roll1", 1.6),
        ("quad", "roll3", 3.0),
        ("quad", "pitch3", 3.0),
        ("quad", "pitch3", 1.5),
        ("quad", "yaw3", 3.1),
        ("quad", "x3", 0.5),
        ("quad", "z3", 0.5),
        ("double-pendulum", "x2", 0.5),
        ("double-pendulum", "z2", 1.0),
        ("double-pendulum", "z1", 0.5),
        ("pendulum", "z1", 1.0),
        ("rigid-body", "pitch1", 3.1),
        ("rigid-body", "roll1", 3.1),
        ("rigid-body", "yaw1", 3.1),
        ("rigid-body", "yaw1", 1.6),
        ("rigid-body", "z1", 0.6),
        ("triple", "pitch1", 3.0),
        ("triple", "yaw2", 3.0),
        ("chain", "yaw2", 3.1),
        ("chain", "pitch4", 3.0),
    ] {
        let (mut system, _) = Case::model(model).unwrap().build().unwrap();
        let c = system
            .coords
            .iter_mut()
            .find(|c| c.name == coord)
            .expect("coordinate");
        c.start = start;
        match check_system(&format!("{model} {coord}={start}"), system, Stage::S2) {
            Ok((line, Some(r))) => {
                let upside_down = !r.stability.inverted.is_empty();
                if upside_down && r.stability.is_stable() {
                    bad.push(format!("{line}: upside down but stable"));
                }
            }
            Ok((_, None)) => {}
            Err(line) => bad.push(line),
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Guards the float whose stiffness is zero within its rounding: toy with k1 within an
/// ulp or ten of −k2 = −3000 N/m. The float block Q = k1 + k2 (exact in double precision,
/// Sterbenz) is ±1e-12 N/m, below the rounding of its 3000 N/m terms (a few ulps of them,
/// 2.7e-12), so its sign cannot be told; the first-order error of the condensed mode
/// (−k1 k2/Q ≈ ∓1e19 N/m) is then as large as the mode, which read as "neutral". But either
/// sign is unstable: Q < 0, the float runs away; Q > 0, the mass sees k1 k2/(k1 + k2) < 0.
/// Reference: the closed form of the 2 × 2 stiffness [[k2, −k2], [−k2, k1 + k2]], whose
/// determinant k1 k2 is negative (−9e6) for every Q up to its rounding.
#[test]
fn a_float_zero_within_rounding_but_strongly_coupled_is_unstable_whatever_its_sign() {
    for k1 in [
        "-2999.999999999999",
        "-3000.000000000001",
        "-2999.99999999999",
    ] {
        let r = run("toy", &[&format!("k1={k1}")], Stage::S0A);
        assert_eq!(
            r.stability.verdict,
            Verdict::Unstable,
            "k1 {k1}: {}",
            r.stability
        );
        let float = &r.stability.runaway_floats[0];
        assert_eq!(float.floats[0].0, "q");
        let q = k1.parse::<f64>().unwrap() + 3000.0;
        assert_eq!(float.stiffness, q, "Q = k1 + k2 exactly");
        // its stated error covers it: zero within rounding, not a confident sign
        assert!(float.error >= float.stiffness.abs(), "{float:?}");
        let message = r.check_stable().unwrap_err().to_string();
        assert!(
            message.contains("within rounding") && message.contains("'q'"),
            "{message}"
        );
    }
    // a float clearly held (Q = 1e-9 N/m, 400 times its rounding) stays a fast growing mode
    let r = run("toy", &["k1=-2999.999999999"], Stage::S0A);
    assert!(r.stability.runaway_floats.is_empty(), "{}", r.stability);
    assert_eq!(r.stability.growing.len(), 1);
}

/// Guards the shift-invert modes (more than 200 variables, modes below a frequency) near
/// a marginal pitch: quad-v5 with 40 beads per fibre at d4 = −1.3787476e-2 m, where the
/// lowest mode lies at ω² ≈ 2e-5 rad²/s², next to the iteration's shift (−1e-6 of the
/// bound's ω²). The operator's largest |θ| = 1/(ω² − σ) is then ~1e5, and Rayleigh–Ritz
/// values of rounding size (ulps of it) read as λ = σ + 1/θ ≈ −5e11 rad²/s²: 132 "growing
/// modes" at 51 kHz were reported. Reference: the dense eigen-solve of all modes on the
/// same stage (the library's other method: faer's Cholesky of K or M and a symmetric
/// eigen-solve, no shift); the verdicts must match and the lowest ω² agree within both
/// stated errors.
#[test]
fn shift_invert_modes_near_their_shift_report_no_spurious_growing_modes() {
    use pendkit::stage::ModeSelection;
    use pendkit::stage::RunOptions;
    use pendkit::stage::run_stage_with;
    let sets = vec!["d4=-1.3787476e-2".to_string(), "n_beads=40".to_string()];
    let (system, _) = Case::model("quad-v5")
        .unwrap()
        .with_sets(&sets)
        .unwrap()
        .build()
        .unwrap();
    let options = RunOptions {
        modes: ModeSelection::Below(1.0),
        ..Default::default()
    };
    let below = run_stage_with(system.clone(), Stage::S2, &options, None).expect("runs");
    assert!(below.modes.coordinates.len() > pendkit::stage::DENSE_MODES_LIMIT);
    let all = run_stage(system, Stage::S2).expect("runs");
    assert_eq!(
        below.stability.verdict, all.stability.verdict,
        "{}",
        below.stability
    );
    assert!(below.stability.growing.is_empty(), "{}", below.stability);
    let (a, b) = (&below.modes.modes[0], &all.modes.modes[0]);
    assert!(
        (a.omega_squared - b.omega_squared).abs() <= a.omega_squared_error + b.omega_squared_error,
        "{a:?} vs {b:?}"
    );
}

/// The stated errors are honest: each point's three lowest modes from the two derivative
/// paths (the fast, hand-differentiated one and the hyper-dual reference: the same
/// Hessians rounded differently) agree within the sum of their stated errors, at the pitch
/// break-off within 1e-12 of its bisected value, with wires and blades 1e6–1e12 times
/// stiffer than nominal, near g = 0 and with a blade near zero stiffness. The verdicts
/// agree too.
#[test]
fn stated_errors_cover_the_difference_between_the_two_derivative_paths() {
    use pendkit::stage::RunOptions;
    use pendkit::stage::run_stage_with;
    use pendkit_assembly::{AssemblyOptions, DerivativePath};
    let points: Vec<(&str, Vec<&str>, Stage)> = vec![
        ("quad", vec!["d4=-1.3787475950811184e-2"], Stage::S2),
        ("quad", vec!["d4=-1.378747595081132e-2"], Stage::S2),
        ("quad", vec!["d4=-1.3787475950824973e-2"], Stage::S2),
        ("quad", vec!["d4=-1.3787475950797396e-2"], Stage::S2),
        ("quad", vec!["Yn=2.2e17", "d4=-0.02"], Stage::S2),
        ("quad", vec!["rn=scale(30)", "d4=-0.02"], Stage::S2),
        ("double-pendulum", vec!["r_wire=scale(100)"], Stage::S2),
        ("chain", vec!["E_wire=2.12e19", "d_bottom=-0.05"], Stage::S2),
        (
            "quad-full",
            vec!["d4=-0.02", "blade_stiff_translation=1e12"],
            Stage::S2,
        ),
        ("toy", vec!["k1=-1000", "k2=1e15"], Stage::S0A),
        ("quad", vec!["g=1e-3"], Stage::S2),
        ("quad", vec!["ufc1=1e-4", "d4=-0.02"], Stage::S2),
    ];
    let mut bad = Vec::new();
    for (model, sets, stage) in points {
        let sets_owned: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let (system, _) = Case::model(model)
            .unwrap()
            .with_sets(&sets_owned)
            .unwrap()
            .build()
            .unwrap();
        let [fast, reference] = [DerivativePath::Fast, DerivativePath::Reference].map(|path| {
            let options = RunOptions {
                assembly: AssemblyOptions {
                    derivatives: path,
                    ..Default::default()
                },
                ..Default::default()
            };
            run_stage_with(system.clone(), stage, &options, None).expect("runs")
        });
        if fast.stability.verdict != reference.stability.verdict {
            bad.push(format!(
                "{model} {sets:?}: {} vs {}",
                fast.stability, reference.stability
            ));
        }
        for (a, b) in fast.modes.modes.iter().zip(&reference.modes.modes).take(3) {
            if (a.omega_squared - b.omega_squared).abs()
                > a.omega_squared_error + b.omega_squared_error
            {
                bad.push(format!(
                    "{model} {sets:?} {}: ω² {:e} ± {:e} vs {:e} ± {:e}",
                    a.label,
                    a.omega_squared,
                    a.omega_squared_error,
                    b.omega_squared,
                    b.omega_squared_error
                ));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// A float whose own stiffness cancels to rounding, weakly coupled to a mass held by its
/// own spring: springs k1 = −1000 and k0 ≈ 1000 − k2 N/m from the ground to the float q,
/// k2 = 1e-6 N/m from q to the mass x, k3 = 1000 N/m from the ground to x (a massless
/// "holder" body posed by x).
const WEAK_FLOAT: &str = r#"
name = "weak-float"
summary = "a float whose own stiffness cancels to rounding, weakly coupled to a held mass"
gravity = 0

[parameters]
m = { value = 1, unit = "kg", description = "the mass" }
k1 = { value = -1000, unit = "N/m", description = "negative spring, ground to float" }
k0 = { value = 999.999999, unit = "N/m", description = "positive spring, ground to float" }
k2 = { value = 1e-6, unit = "N/m", description = "weak spring, float to mass" }
k3 = { value = 1000, unit = "N/m", description = "spring, ground to mass" }

[coordinates]
x = "variable"
q = "float"
s = "parameter"

[bodies.ground]
pose = ["s", 0, 0, 0, 0, 0]

[bodies.junction]
pose = ["q", 0, 0, 0, 0, 0]

[bodies.junction2]
pose = ["q", 0, 0, 0, 0, 0]

[bodies.mass]
pose = ["x", 0, 0, 0, 0, 0]
mass = "m"

[bodies.holder]
pose = ["x", 0, 0, 0, 0, 0]

[stages.junction]
from = "ground"
springs = { name = "k1", stiffness = ["k1", 0, 0, 0, 0, 0], tag = "k1" }

[stages.junction2]
from = "ground"
springs = { name = "k0", stiffness = ["k0", 0, 0, 0, 0, 0], tag = "k0" }

[stages.mass]
from = "junction"
springs = { name = "k2", stiffness = ["k2", 0, 0, 0, 0, 0], tag = "k2" }

[stages.holder]
from = "ground"
springs = { name = "k3", stiffness = ["k3", 0, 0, 0, 0, 0], tag = "k3" }
"#;

/// Guards the weakly coupled float whose stiffness is zero within rounding. With k0 an ulp
/// either side of 1000 − k1 − k2 the float block Q = k1 + k0 + k2 is ±1e-13 N/m, below the
/// rounding of its 1000 N/m terms (a few ulps of them), so its sign cannot be told: if
/// negative the float runs away. The mass, held by k3, shows a healthy 5 Hz mode either way
/// (k3 − k2²/Q ≈ 1000 ± 10 N/m), which read as "stable" with either sign of Q. Reference:
/// the closed form of the 2 × 2 stiffness [[k2 + k3, −k2], [−k2, Q]], whose float
/// direction decides; with Q clearly positive (k0 = 1000 N/m, Q = k2 = 1e-6 N/m, ten
/// million times its rounding) it is stable.
#[test]
fn a_weakly_coupled_float_zero_within_rounding_is_neutral_never_stable() {
    let run_with = |k0: &str| {
        let case = Case::from_text(std::path::Path::new("weak-float.toml"), WEAK_FLOAT)
            .and_then(|c| c.with_sets(&[format!("k0={k0}")]))
            .expect("case");
        let (system, _) = case.build().expect("builds");
        run_stage(system, Stage::S0A).expect("runs")
    };
    for k0 in ["999.9999990000001", "999.9999989999999"] {
        let r = run_with(k0);
        let q: f64 = -1000.0 + k0.parse::<f64>().unwrap() + 1e-6;
        assert!(q.abs() < 1e-12, "Q = {q:e}");
        assert_eq!(
            r.stability.verdict,
            Verdict::Neutral,
            "k0 {k0}: {}",
            r.stability
        );
        let float = &r.stability.neutral_floats[0];
        assert_eq!(float.floats[0].0, "q");
        assert!(float.error >= float.stiffness.abs(), "{float:?}");
        // nothing is refused (nothing is shown to grow), but the verdict is said
        let note = r.require_stable(false).unwrap().expect("a note");
        assert!(note.contains("'q'") || note.contains(" q "), "{note}");
    }
    let r = run_with("1000");
    assert_eq!(r.stability.verdict, Verdict::Stable, "{}", r.stability);
    assert!(r.require_stable(false).unwrap().is_none());
}
