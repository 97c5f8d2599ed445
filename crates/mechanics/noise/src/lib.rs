//! Thermal noise by the fluctuation–dissipation theorem (docs/physics.md §3) at any output
//! combination of the coordinates, with the share of every damping tag (and, when asked,
//! of every lossy term).
//!
//! S(f) = (4 k_B T / ω) |Im(vᵀ E(f)⁻¹ v)| as a one-sided PSD (m²/Hz for a displacement
//! output, rad²/Hz for an angle). With z = E⁻¹ v (floats included), Im(vᵀ z) = −z̄ᵀ Im(P) z
//! and Im(P) = Σ_tags ε''_tag(f) P_tag = Σ_terms ε''_tag(f) P_off,term, so the noise splits
//! exactly into one non-negative share per tag, or per lossy term: which wire or blade
//! dominates at which frequency. Only the blocks of the stage that the output couples to
//! are solved (see [`pendkit_dynamics::Solver`]), and the per-tag shares cost one sparse
//! quadratic form per tag over them.

use std::collections::HashMap;

use faer::c64;
use nalgebra::DVector;
use pendkit_dynamics::{DynamicsError, Input, Output, Solver, StageModel, Sweep};
use pendkit_system::Damping;

/// Boltzmann constant k_B (J/K).
pub const BOLTZMANN: f64 = 1.380649e-23;

/// How a noise curve is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoiseOptions {
    /// Which unknowns are solved (default: only the blocks the output couples to).
    pub solver: Solver,
    /// Also give the share of every lossy term ([`ThermalNoise::by_term`]); the per-tag
    /// shares are always given.
    pub per_term: bool,
}

/// Thermal noise at one output over a frequency grid.
#[derive(Clone, Debug)]
pub struct ThermalNoise {
    /// One-sided PSD (m²/Hz or rad²/Hz) per frequency.
    pub total: Vec<f64>,
    /// Share of each damping tag with lossy terms, in tag-name order: (tag, PSD per
    /// frequency); they add up to `total`.
    pub tags: Vec<(String, Vec<f64>)>,
    /// Share of each lossy term: (term name, tag, PSD per frequency), adding up to `total`;
    /// empty unless asked for ([`NoiseOptions::per_term`]).
    pub by_term: Vec<(String, String, Vec<f64>)>,
}

impl ThermalNoise {
    /// The breakdown per damping tag, in tag order: PSD (m²/Hz or rad²/Hz), as
    /// [`ThermalNoise::psd_by_tag`].
    pub fn by_tag(&self) -> &[(String, Vec<f64>)] {
        &self.tags
    }

    /// One-sided power spectral density per frequency (m²/Hz for a displacement output,
    /// rad²/Hz for an angle): the `total` field.
    pub fn psd(&self) -> &[f64] {
        &self.total
    }

    /// Amplitude spectral density per frequency, √PSD (m/√Hz or rad/√Hz): what the
    /// command line prints.
    pub fn asd(&self) -> Vec<f64> {
        self.total.iter().map(|p| p.max(0.0).sqrt()).collect()
    }

    /// Each damping tag's share of the PSD (m²/Hz or rad²/Hz), in tag order; the shares add
    /// up to [`ThermalNoise::psd`].
    pub fn psd_by_tag(&self) -> &[(String, Vec<f64>)] {
        &self.tags
    }

    /// Each damping tag's noise as an ASD, √(its PSD share) (m/√Hz or rad/√Hz), in tag
    /// order: the curve that tag alone would give. ASDs add in quadrature, not linearly.
    pub fn asd_by_tag(&self) -> Vec<(String, Vec<f64>)> {
        self.tags
            .iter()
            .map(|(tag, psd)| (tag.clone(), psd.iter().map(|p| p.max(0.0).sqrt()).collect()))
            .collect()
    }
}

/// 4 k_B / ω at `f_hz` (Hz): the fluctuation–dissipation theorem's factor (J/K per rad/s)
/// between T Im(vᵀ E⁻¹ v) (K m/N) and the one-sided PSD (m²/Hz).
pub fn fd_scale(f_hz: f64) -> f64 {
    4.0 * BOLTZMANN / (2.0 * std::f64::consts::PI * f_hz)
}

/// A damping tag's weight T_tag ε''_tag(f) (K) in the fluctuation–dissipation sum at
/// `f_hz` (Hz): its loss times its own temperature, or `temperature` (K) without one.
pub fn tag_weight(damping: &Damping, tag: &str, temperature: f64, f_hz: f64) -> f64 {
    damping.temperature(tag).unwrap_or(temperature) * damping.at(tag, f_hz).1
}

/// z̄ᵀ P z (N m per unit response², real for a real symmetric P) over the unknowns, P given
/// as values on `model`'s pattern (a tag's tension-off stiffness, or its change with a
/// parameter) and `z` over the unknowns: the quadratic form that the loss ε''_tag weighs in
/// the fluctuation–dissipation sum. The parameters' rows and columns are left out (the
/// support does not move). An error when `values` or `z` has another length.
pub fn dissipation_form(
    model: &StageModel,
    values: &[f64],
    z: &[c64],
) -> Result<f64, DynamicsError> {
    let u = model.unknowns();
    if z.len() != u {
        return Err(DynamicsError::Length {
            what: "dissipation_form: response",
            expected: u,
            got: z.len(),
        });
    }
    if values.len() != model.pattern.len() {
        return Err(DynamicsError::Length {
            what: "values on the pattern",
            expected: model.pattern.len(),
            got: values.len(),
        });
    }
    Ok(values
        .iter()
        .zip(model.pattern.positions())
        .filter(|&(&v, (i, j))| v != 0.0 && i < u && j < u)
        .map(|(&v, (i, j))| v * (z[i].re * z[j].re + z[i].im * z[j].im))
        .sum())
}

/// The fluctuation–dissipation sum over the damping tags at one frequency, S = 4 k_B/ω
/// Σ_tag T_tag ε''_tag z̄ᵀ P_tag z (m²/Hz or rad²/Hz), for the response z over the unknowns
/// to a unit force along the output; each tag at its own temperature where the damping
/// gives one. With [`TagSum::change`], its first-order change with a parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct TagSum {
    /// 4 k_B / ω ([`fd_scale`]).
    pub scale: f64,
    /// Per tag (the model's `by_tag` order): T_tag ε''_tag(f) (K, [`tag_weight`]).
    pub weights: Vec<f64>,
    /// Per tag: z̄ᵀ P_tag z ([`dissipation_form`]).
    pub energies: Vec<f64>,
}

impl TagSum {
    /// The sum for `model` with `damping` at `f_hz` (Hz) and the model's `temperature`
    /// (K), at the response `z` over the unknowns.
    pub fn new(
        model: &StageModel,
        damping: &Damping,
        temperature: f64,
        f_hz: f64,
        z: &[c64],
    ) -> Result<TagSum, DynamicsError> {
        let mut weights = Vec::with_capacity(model.by_tag.len());
        let mut energies = Vec::with_capacity(model.by_tag.len());
        for (tag, values) in &model.by_tag {
            weights.push(tag_weight(damping, tag, temperature, f_hz));
            energies.push(dissipation_form(model, values, z)?);
        }
        Ok(TagSum {
            scale: fd_scale(f_hz),
            weights,
            energies,
        })
    }

    /// The PSD S (m²/Hz or rad²/Hz).
    pub fn psd(&self) -> f64 {
        self.scale
            * self
                .weights
                .iter()
                .zip(&self.energies)
                .map(|(w, e)| w * e)
                .sum::<f64>()
    }

    /// dS for the tags' changes of weight `d_weights` (K) and of energy `d_energies`
    /// (each in tag order; missing entries count as 0): 4 k_B/ω Σ (dw E + w dE).
    pub fn change(&self, d_weights: &[f64], d_energies: &[f64]) -> f64 {
        let at = |v: &[f64], t: usize| v.get(t).copied().unwrap_or(0.0);
        self.scale
            * (0..self.weights.len())
                .map(|t| at(d_weights, t) * self.energies[t] + self.weights[t] * at(d_energies, t))
                .sum::<f64>()
    }
}

/// Thermal-noise PSD of the output combination `v` of the variables (or of the variables
/// and the floats) (m²/Hz or rad²/Hz) at temperature `temperature` (K, positive) and
/// frequencies `freqs` (Hz), for the stage `model` with damping `damping`, with the share
/// of every tag and every lossy term. An output of the wrong length, a frequency out of
/// range, a damping multiplier that is not finite or has a negative loss, or a frequency
/// where the dynamic stiffness is exactly singular is an error.
pub fn thermal_noise(
    model: &StageModel,
    damping: &Damping,
    v: &DVector<f64>,
    temperature: f64,
    freqs: &[f64],
) -> Result<ThermalNoise, DynamicsError> {
    let options = NoiseOptions {
        per_term: true,
        ..Default::default()
    };
    thermal_noise_with(model, damping, v, temperature, freqs, &options)
}

/// Quadratic forms Σ w_ij Re(z̄_i z_j) over the solved unknowns, evaluated together: each
/// product Re(z̄_i z_j) (i ≤ j) that some form needs is computed once per frequency, and each
/// form is a list of (product, weight), the off-diagonal weights doubled. The per-tag forms
/// of the quad's x–pitch block share most of their products.
#[derive(Default)]
struct Forms {
    /// The (i, j) of each product, i ≤ j.
    pairs: Vec<(usize, usize)>,
    /// Index of each pair in `pairs`.
    index: HashMap<(usize, usize), usize>,
    /// Each form: (product index, weight).
    forms: Vec<Vec<(usize, f64)>>,
    /// The products at the current frequency.
    products: Vec<f64>,
}

impl Forms {
    /// Starts a new form.
    fn begin(&mut self) {
        self.forms.push(Vec::new());
    }

    /// Adds w Re(z̄_i z_j) to the form begun last (entries below the diagonal are skipped:
    /// give each unordered pair once through its upper entry, doubled by this call).
    fn push(&mut self, i: usize, j: usize, w: f64) {
        if i > j {
            return;
        }
        let next = self.pairs.len();
        let k = *self.index.entry((i, j)).or_insert(next);
        if k == next {
            self.pairs.push((i, j));
        }
        let weight = if i == j { w } else { 2.0 * w };
        if let Some(form) = self.forms.last_mut() {
            form.push((k, weight));
        }
    }

    /// Computes the products at the response `z`.
    fn update(&mut self, z: &[c64]) {
        self.products.clear();
        self.products.extend(
            self.pairs
                .iter()
                .map(|&(i, j)| z[i].re * z[j].re + z[i].im * z[j].im),
        );
    }

    /// The value of form `f` at the last [`Forms::update`].
    fn energy(&self, f: usize) -> f64 {
        self.forms[f]
            .iter()
            .map(|&(k, w)| w * self.products[k])
            .sum()
    }
}

/// Thermal noise as [`thermal_noise`], solved and broken down as `options` says. `v` may
/// also be a displacement output over the variables, floats and parameters (a point's
/// whole motion): the parameters' part is left out, the support does not fluctuate.
#[expect(
    clippy::too_many_lines,
    reason = "one frequency loop whose solve, per-tag split and per-term split share the factorisation and the solved vector of each frequency"
)]
pub fn thermal_noise_with(
    model: &StageModel,
    damping: &Damping,
    v: &DVector<f64>,
    temperature: f64,
    freqs: &[f64],
    options: &NoiseOptions,
) -> Result<ThermalNoise, DynamicsError> {
    if !(temperature.is_finite() && temperature > 0.0) {
        return Err(DynamicsError::Temperature(temperature));
    }
    pendkit_dynamics::validate::check_frequencies(freqs)?;
    let v = &v.rows(0, v.len().min(model.unknowns())).into_owned();
    let input = Input::Force(v.clone());
    let output = Output::Displacement(v.clone());
    // a tag without damping, or whose loss is the constant zero, never dissipates: its form
    // stays empty, so its products are neither computed nor summed per frequency
    let lossy: Vec<bool> = model
        .by_tag
        .iter()
        .map(|(name, _)| {
            damping
                .get(name)
                .is_some_and(|d| d.imag.as_const() != Some(0.0))
        })
        .collect();
    // a model that dissipates nothing has no thermal noise: an ASD of exactly 0 everywhere
    // would look like an answer, so it is refused, naming the tags (an output that only
    // lossless parts move is a result: its zeros are reported as such by the callers)
    if !lossy.contains(&true) {
        return Err(DynamicsError::NoLoss {
            output: "the output".to_string(),
            lossless: model.by_tag.iter().map(|(name, _)| name.clone()).collect(),
        });
    }
    let mut sweep = Sweep::new(model, damping, &input, &output, options.solver)?;
    // per-tag forms over the solved unknowns, from the tags' values on the pattern
    let mut tag_forms = Forms::default();
    for ((_, values), &lossy) in model.by_tag.iter().zip(&lossy) {
        tag_forms.begin();
        if !lossy {
            continue;
        }
        for (&p, (r, c)) in values.iter().zip(model.pattern.positions()) {
            if let (Some(i), Some(j), true) = (sweep.local(r), sweep.local(c), p != 0.0) {
                tag_forms.push(i, j, p);
            }
        }
    }
    // per-term forms (each with its tag's index), from the terms' full local matrices: a
    // pair (i, j) and its transpose each contribute once, so the upper entry carries
    // w_ij + w_ji (pushed halved, since push doubles off-diagonal weights)
    let per_term = options.per_term || options.solver == Solver::DenseReference;
    let mut term_forms = Forms::default();
    let mut term_tags = Vec::new();
    if per_term {
        for t in &model.terms {
            let tag = model
                .by_tag
                .iter()
                .position(|(name, _)| *name == t.tag)
                .unwrap_or(0);
            term_tags.push(tag);
            term_forms.begin();
            if !lossy.get(tag).copied().unwrap_or(true) {
                continue;
            }
            let m = t.positions.len();
            for (a, &pa) in t.positions.iter().enumerate() {
                for (b, &pb) in t.positions.iter().enumerate() {
                    if let (Some(i), Some(j)) = (sweep.local(pa), sweep.local(pb)) {
                        let w = t.off[a * m + b];
                        match i.cmp(&j) {
                            std::cmp::Ordering::Equal => term_forms.push(i, j, w),
                            std::cmp::Ordering::Less => term_forms.push(i, j, 0.5 * w),
                            std::cmp::Ordering::Greater => term_forms.push(j, i, 0.5 * w),
                        }
                    }
                }
            }
        }
    }
    let n_tags = model.by_tag.len();
    // each tag's terms at their own temperature (K) when the damping gives one: the
    // fluctuation–dissipation theorem per dissipating term, S = Σ 4 k_B T_tag ε''_tag
    // z̄ᵀ P_tag z / ω; with one temperature this is the total below
    let tag_ratio: Vec<f64> = model
        .by_tag
        .iter()
        .map(|(name, _)| damping.temperature(name).unwrap_or(temperature) / temperature)
        .collect();
    let uniform = tag_ratio.iter().all(|&r| r == 1.0);
    let mut total = Vec::with_capacity(freqs.len());
    let mut tags: Vec<Vec<f64>> = vec![Vec::with_capacity(freqs.len()); n_tags];
    let mut terms: Vec<Vec<f64>> = vec![Vec::with_capacity(freqs.len()); term_tags.len()];
    sweep.for_each(freqs, |_, response, sweep| {
        let f = freqs[total.len()];
        let scale = 4.0 * BOLTZMANN * temperature / (2.0 * std::f64::consts::PI * f);
        total.push(scale * response.im.abs());
        let z = sweep.response();
        let share = |forms: &Forms, form: usize, tag: usize| {
            let loss = sweep.multiplier(tag).map_or(0.0, |m| m.im);
            if loss != 0.0 {
                scale * tag_ratio[tag] * loss * forms.energy(form)
            } else {
                0.0
            }
        };
        if per_term {
            term_forms.update(z);
            for (k, (&tag, series)) in term_tags.iter().zip(terms.iter_mut()).enumerate() {
                series.push(share(&term_forms, k, tag));
            }
        }
        if options.solver == Solver::DenseReference {
            // the reference adds the per-term shares up per tag
            for series in tags.iter_mut() {
                series.push(0.0);
            }
            for (&tag, series) in term_tags.iter().zip(&terms) {
                if let (Some(sum), Some(last)) = (tags[tag].last_mut(), series.last()) {
                    *sum += last;
                }
            }
        } else {
            tag_forms.update(z);
            for (t, series) in tags.iter_mut().enumerate() {
                series.push(share(&tag_forms, t, t));
            }
        }
        if !uniform && let Some(last) = total.last_mut() {
            *last = tags.iter().filter_map(|s| s.last()).sum();
        }
    })?;
    Ok(ThermalNoise {
        total,
        tags: model
            .by_tag
            .iter()
            .map(|(name, _)| name.clone())
            .zip(tags)
            .collect(),
        by_term: if options.per_term {
            model
                .terms
                .iter()
                .zip(terms)
                .map(|(t, series)| (t.label.clone(), t.tag.clone(), series))
                .collect()
        } else {
            Vec::new()
        },
    })
}

#[cfg(test)]
mod tests {
    //! The noise of one lossy oscillator (a mass m = 1 kg on a spring k to ground, f0 = 1 Hz,
    //! at T = 300 K) against the closed-form fluctuation–dissipation result
    //! (docs/reference-values.md §6, docs/physics.md §3). With structural loss φ the
    //! spring is k(1 + iφ) and
    //!
    //!   S_x(f) = 4 k_B T k φ / (ω [(k − m ω²)² + k² φ²]),  ω = 2π f,
    //!
    //! evaluated here from the inputs. The model goes through the same builder, equilibrium
    //! and stage matrices as any other (`pendkit_assembly::assemble`, `StageModel::new`).
    //!
    //! Tolerance 1e-10 relative: the stage's matrices are exact (a linear spring), the
    //! response is one 1×1 complex solve per frequency, so rounding (~1e-15) is all that
    //! separates the two; 1e-10 is the same bound the workspace's oracle tests use.

    use super::*;
    use nalgebra::{Matrix6, Vector3, Vector6};
    use pendkit_assembly::{EquilibriumOptions, assemble};
    use pendkit_model::{BodySpec, DampingSpec, SystemBuilder};
    use pendkit_params::ParamSet;
    use pendkit_system::{SpringEnd, Stage};

    const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
    const TEMPERATURE: f64 = 300.0;

    /// A mass of 1 kg on a spring `k` (N/m) along x to ground, with `spec` on tag "spring".
    fn oscillator(k: f64, spec: DampingSpec) -> (StageModel, Damping) {
        let mut b = SystemBuilder::new(9.81);
        b.parameter("s", 0.0).unwrap();
        b.variable("x", 0.0).unwrap();
        let ground = b
            .body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))
            .unwrap();
        let mass = b
            .body(
                BodySpec::new("mass")
                    .pose(["x", "0", "0", "0", "0", "0"])
                    .mass(1.0),
            )
            .unwrap();
        let end = |body| SpringEnd {
            body,
            point: Vector3::zeros(),
            angles: [0.0; 3],
        };
        let stiffness = Matrix6::from_diagonal(&Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
        b.spring(
            "spring",
            [end(ground), end(mass)],
            stiffness,
            Vector6::zeros(),
            "spring",
        )
        .unwrap();
        let system = b.build().unwrap();
        let assembled = assemble(&system, Stage::S0B, &EquilibriumOptions::default()).unwrap();
        let model = StageModel::new(&system, &assembled);
        let mut damping = Damping::default();
        damping.set(
            "spring",
            spec.resolve("spring", &ParamSet::new().resolve().unwrap())
                .unwrap(),
        );
        (model, damping)
    }

    /// S_x(f) of the structurally damped oscillator, m = 1 kg (docs/reference-values.md §6).
    fn closed_form(k: f64, phi: f64, f: f64) -> f64 {
        let w = TWO_PI * f;
        4.0 * BOLTZMANN * TEMPERATURE * k * phi / (w * ((k - w * w).powi(2) + (k * phi).powi(2)))
    }

    #[test]
    fn single_lossy_oscillator_is_the_fluctuation_dissipation_closed_form() {
        let (k, phi) = (TWO_PI * TWO_PI, 1e-3);
        let (model, damping) = oscillator(k, DampingSpec::structural("1e-3"));
        // below, at and above the resonance
        let freqs = [0.1, 1.0, 10.0];
        let v = DVector::from_element(1, 1.0);
        let noise = thermal_noise(&model, &damping, &v, TEMPERATURE, &freqs).unwrap();
        for (f, s) in freqs.iter().zip(&noise.total) {
            let expected = closed_form(k, phi, *f);
            assert!(
                (s - expected).abs() <= 1e-10 * expected,
                "{f} Hz: {s} vs {expected}"
            );
        }
        // one lossy tag and one lossy term: each carries the whole of it (to rounding)
        assert_eq!(noise.tags.len(), 1);
        assert_eq!(noise.by_term.len(), 1);
        for (s, total) in noise.tags[0].1.iter().zip(&noise.total) {
            assert!((s - total).abs() <= 1e-12 * total);
        }
    }

    /// The sensitivities' pieces on the same oscillator: the response z to a unit force
    /// solved by `Sweep` (and again by `Sweep::solve_again` from its factors), E(f) put
    /// together by `StageModel::sum_parts` and applied by `StageModel::multiply`, and
    /// `TagSum`'s PSD: each against the closed forms z = 1/(k(1 + iφ) − m ω²) and S_x above.
    /// Tolerance 1e-10 relative, as above: one 1×1 complex solve separates them.
    #[test]
    fn the_sensitivities_pieces_give_the_closed_form() {
        let (k, phi) = (TWO_PI * TWO_PI, 1e-3);
        let (model, damping) = oscillator(k, DampingSpec::structural("1e-3"));
        let v = DVector::from_element(1, 1.0);
        let input = Input::Force(v.clone());
        let output = Output::Displacement(v);
        let mut sweep = Sweep::new(&model, &damping, &input, &output, Solver::Full).unwrap();
        for f in [0.1, 1.0, 10.0] {
            let w2 = (TWO_PI * f).powi(2);
            let z_expected = c64::new(1.0, 0.0) / (c64::new(k, k * phi) - w2);
            sweep.at(f).unwrap();
            let z = sweep.response().to_vec();
            assert_eq!(z.len(), 1);
            assert!(
                (z[0] - z_expected).norm() <= 1e-10 * z_expected.norm(),
                "{f} Hz"
            );
            let mut again = vec![c64::new(2.0, 0.0)];
            sweep.solve_again(&mut again).unwrap();
            let twice = z_expected * 2.0;
            assert!((again[0] - twice).norm() <= 1e-10 * twice.norm(), "{f} Hz");
            // E z = 1 over the variable's row
            let mut e = vec![c64::new(0.0, 0.0); model.pattern.len()];
            model
                .sum_parts(&model.dynamic_parts(&damping, f), &mut e)
                .unwrap();
            let mut w = vec![c64::new(0.0, 0.0); model.pattern.dim()];
            w[0] = z[0];
            let mut ez = vec![c64::new(0.0, 0.0); model.pattern.dim()];
            model.multiply(&e, &w, &mut ez).unwrap();
            assert!((ez[0] - 1.0).norm() <= 1e-10, "{f} Hz: E z = {}", ez[0]);
            let sum = TagSum::new(&model, &damping, TEMPERATURE, f, &z).unwrap();
            let expected = closed_form(k, phi, f);
            assert!(
                (sum.psd() - expected).abs() <= 1e-10 * expected,
                "{f} Hz: {} vs {expected}",
                sum.psd()
            );
        }
        // a right-hand side of another length is an error, not a panic
        assert!(sweep.solve_again(&mut [c64::new(1.0, 0.0); 2]).is_err());
    }

    #[test]
    fn noise_is_refused_without_loss_and_at_a_bad_temperature() {
        // a model that dissipates nothing has no thermal noise: an error, not zeros; and the
        // temperature must be positive
        let (model, _) = oscillator(TWO_PI * TWO_PI, DampingSpec::structural("1e-3"));
        let v = DVector::from_element(1, 1.0);
        assert!(thermal_noise(&model, &Damping::default(), &v, TEMPERATURE, &[1.0]).is_err());
        let (model, damping) = oscillator(TWO_PI * TWO_PI, DampingSpec::structural("1e-3"));
        assert!(thermal_noise(&model, &damping, &v, 0.0, &[1.0]).is_err());
    }
}
