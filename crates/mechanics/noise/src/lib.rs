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
    tag_temperature(damping, tag, temperature) * damping.at(tag, f_hz).1
}

/// The noise temperature (K) of the terms tagged `tag`: their own where `damping` gives
/// one, else `temperature` (K).
fn tag_temperature(damping: &Damping, tag: &str, temperature: f64) -> f64 {
    damping.temperature(tag).unwrap_or(temperature)
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
/// gives one. With [`TagSum::change`], its first-order change with a parameter. The one
/// implementation of the per-tag sum: [`thermal_noise_with`] splits the noise by tag with
/// it, and the sensitivities differentiate it.
#[derive(Clone, Debug, PartialEq)]
pub struct TagSum {
    /// 4 k_B / ω ([`fd_scale`]).
    pub scale: f64,
    /// Per tag (the model's `by_tag` order): T_tag ε''_tag(f) (K, [`tag_weight`]).
    pub weights: Vec<f64>,
    /// Per tag: z̄ᵀ P_tag z (N m per unit response², as [`dissipation_form`]).
    pub energies: Vec<f64>,
}

impl TagSum {
    /// The sum for `model` with `damping` at `f_hz` (Hz) and the model's `temperature`
    /// (K), at the response `z` over the unknowns. An error when `z` has another length.
    pub fn new(
        model: &StageModel,
        damping: &Damping,
        temperature: f64,
        f_hz: f64,
        z: &[c64],
    ) -> Result<TagSum, DynamicsError> {
        let u = model.unknowns();
        if z.len() != u {
            return Err(DynamicsError::Length {
                what: "TagSum: response",
                expected: u,
                got: z.len(),
            });
        }
        // every tag's energy, lossless ones too: a parameter that makes a tag lossy (a
        // loss angle at 0) changes the sum by its weight's change times that energy
        let mut sums = TagSums::new(
            model,
            damping,
            temperature,
            |r| (r < u).then_some(r),
            |_| true,
        );
        let loss = |t: usize| {
            model
                .by_tag
                .get(t)
                .map_or(0.0, |(tag, _)| damping.at(tag, f_hz).1)
        };
        Ok(sums.at(f_hz, z, loss).clone())
    }

    /// The PSD S (m²/Hz or rad²/Hz): the tags' shares ([`TagSum::share`]) added in tag
    /// order.
    pub fn psd(&self) -> f64 {
        (0..self.weights.len()).map(|t| self.share(t)).sum()
    }

    /// The share of tag `t` (index into the model's `by_tag`) in the PSD, 4 k_B/ω T_tag
    /// ε''_tag z̄ᵀ P_tag z (m²/Hz or rad²/Hz); 0 for an index past the tags.
    pub fn share(&self, t: usize) -> f64 {
        self.share_of(t, self.energies.get(t).copied().unwrap_or(0.0))
    }

    /// The share of a part of tag `t` whose form z̄ᵀ P z is `energy` (one lossy term of
    /// the tag, or the whole tag): 4 k_B/ω T_tag ε''_tag `energy`. Exactly 0 where the tag
    /// does not dissipate at this frequency, whatever the energy.
    fn share_of(&self, t: usize, energy: f64) -> f64 {
        match self.weights.get(t) {
            Some(&w) if w != 0.0 => self.scale * w * energy,
            _ => 0.0,
        }
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

/// The per-tag sum over one fixed set of solved unknowns, prepared once for responses at
/// many frequencies: each tag's form z̄ᵀ P_tag z (sharing their products) and temperature.
/// [`TagSum::new`] makes one for a single response; [`thermal_noise_with`] one per sweep.
struct TagSums {
    /// One form per tag, in `by_tag` order.
    forms: Forms,
    /// Per tag: its own temperature, or the model's (K).
    temperatures: Vec<f64>,
    /// The sum at the last [`TagSums::at`], its vectors reused from one frequency to the
    /// next.
    sum: TagSum,
}

impl TagSums {
    /// The tags' forms of `model` over the unknowns `local` places in the response (master
    /// index → index in z), each tag at its own temperature in `damping` or at
    /// `temperature` (K); a tag `keep` refuses (by index) gets an empty form, energy 0.
    fn new(
        model: &StageModel,
        damping: &Damping,
        temperature: f64,
        local: impl Fn(usize) -> Option<usize>,
        keep: impl Fn(usize) -> bool,
    ) -> TagSums {
        let n = model.by_tag.len();
        TagSums {
            forms: Forms::of_tags(model, local, keep),
            temperatures: model
                .by_tag
                .iter()
                .map(|(tag, _)| tag_temperature(damping, tag, temperature))
                .collect(),
            sum: TagSum {
                scale: 0.0,
                weights: vec![0.0; n],
                energies: vec![0.0; n],
            },
        }
    }

    /// The sum at `f_hz` (Hz) for the response `z` (over the unknowns given to
    /// [`TagSums::new`]) and each tag's loss ε''_tag(f) by index, `loss(t)`.
    fn at(&mut self, f_hz: f64, z: &[c64], loss: impl Fn(usize) -> f64) -> &TagSum {
        self.forms.update(z);
        self.sum.scale = fd_scale(f_hz);
        for (t, (w, e)) in self
            .sum
            .weights
            .iter_mut()
            .zip(self.sum.energies.iter_mut())
            .enumerate()
        {
            *w = self.temperatures[t] * loss(t);
            *e = self.forms.energy(t);
        }
        &self.sum
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
    /// One form per damping tag of `model` (`by_tag` order), z̄ᵀ P_tag z from the tag's
    /// values on the pattern, over the unknowns `local` places (master index → index in
    /// z); a tag `keep` refuses (by index) gets an empty form.
    fn of_tags(
        model: &StageModel,
        local: impl Fn(usize) -> Option<usize>,
        keep: impl Fn(usize) -> bool,
    ) -> Forms {
        let mut forms = Forms::default();
        for (t, (_, values)) in model.by_tag.iter().enumerate() {
            forms.begin();
            if !keep(t) {
                continue;
            }
            for (&p, (r, c)) in values.iter().zip(model.pattern.positions()) {
                if let (Some(i), Some(j), true) = (local(r), local(c), p != 0.0) {
                    forms.push(i, j, p);
                }
            }
        }
        forms
    }

    /// One form per lossy term of `model` (its `terms` order), z̄ᵀ P_off z from the term's
    /// full local matrix, over the unknowns `local` places, with each term's tag index; a
    /// term whose tag `keep` refuses gets an empty form. A pair (i, j) and its transpose
    /// each contribute once, so the upper entry carries w_ij + w_ji (pushed halved, since
    /// [`Forms::push`] doubles off-diagonal weights).
    fn of_terms(
        model: &StageModel,
        local: impl Fn(usize) -> Option<usize>,
        keep: impl Fn(usize) -> bool,
    ) -> (Forms, Vec<usize>) {
        let mut forms = Forms::default();
        let mut tags = Vec::with_capacity(model.terms.len());
        for t in &model.terms {
            let tag = model
                .by_tag
                .iter()
                .position(|(name, _)| *name == t.tag)
                .unwrap_or(0);
            tags.push(tag);
            forms.begin();
            if !keep(tag) {
                continue;
            }
            let m = t.positions.len();
            for (a, &pa) in t.positions.iter().enumerate() {
                for (b, &pb) in t.positions.iter().enumerate() {
                    if let (Some(i), Some(j)) = (local(pa), local(pb)) {
                        let w = t.off[a * m + b];
                        match i.cmp(&j) {
                            std::cmp::Ordering::Equal => forms.push(i, j, w),
                            std::cmp::Ordering::Less => forms.push(i, j, 0.5 * w),
                            std::cmp::Ordering::Greater => forms.push(j, i, 0.5 * w),
                        }
                    }
                }
            }
        }
        (forms, tags)
    }

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

/// Which of `model`'s tags (by index) can dissipate: a tag without damping, or whose loss
/// is the constant zero, never does, so its form stays empty and its products are neither
/// computed nor summed per frequency. A model that dissipates nothing has no thermal noise:
/// an ASD of exactly 0 everywhere would look like an answer, so it is refused, naming the
/// tags (an output that only lossless parts move is a result: its zeros are reported as
/// such by the callers).
fn lossy_tags(model: &StageModel, damping: &Damping) -> Result<Vec<bool>, DynamicsError> {
    let lossy: Vec<bool> = model
        .by_tag
        .iter()
        .map(|(name, _)| {
            damping
                .get(name)
                .is_some_and(|d| d.imag.as_const() != Some(0.0))
        })
        .collect();
    if lossy.contains(&true) {
        Ok(lossy)
    } else {
        Err(DynamicsError::NoLoss {
            output: "the output".to_string(),
            lossless: model.by_tag.iter().map(|(name, _)| name.clone()).collect(),
        })
    }
}

/// The curves of [`ThermalNoise`] as they are filled, one frequency at a time.
struct Curves {
    /// The PSD per frequency.
    total: Vec<f64>,
    /// Each tag's share per frequency, `by_tag` order.
    tags: Vec<Vec<f64>>,
    /// Each lossy term's share per frequency, `terms` order (empty without the per-term
    /// split).
    terms: Vec<Vec<f64>>,
}

impl Curves {
    fn new(n_freqs: usize, n_tags: usize, n_terms: usize) -> Curves {
        Curves {
            total: Vec::with_capacity(n_freqs),
            tags: vec![Vec::with_capacity(n_freqs); n_tags],
            terms: vec![Vec::with_capacity(n_freqs); n_terms],
        }
    }

    /// Each tag's share at this frequency as the sum of its terms' (the reference path's
    /// breakdown, from the per-term shares just pushed).
    fn push_tags_from_terms(&mut self, term_tags: &[usize]) {
        for series in &mut self.tags {
            series.push(0.0);
        }
        for (&tag, series) in term_tags.iter().zip(&self.terms) {
            if let (Some(sum), Some(last)) = (
                self.tags.get_mut(tag).and_then(|s| s.last_mut()),
                series.last(),
            ) {
                *sum += last;
            }
        }
    }

    /// The total at this frequency replaced by the sum of the tags' shares (where tags
    /// have their own temperatures, the noise is the sum of each tag's, not 4 k_B T/ω
    /// |Im R| at one T).
    fn total_from_tags(&mut self) {
        if let Some(last) = self.total.last_mut() {
            *last = self.tags.iter().filter_map(|s| s.last()).sum();
        }
    }

    /// The breakdown named after `model`'s tags and terms (the terms only if asked).
    fn finish(self, model: &StageModel, per_term: bool) -> ThermalNoise {
        ThermalNoise {
            total: self.total,
            tags: model
                .by_tag
                .iter()
                .map(|(name, _)| name.clone())
                .zip(self.tags)
                .collect(),
            by_term: if per_term {
                model
                    .terms
                    .iter()
                    .zip(self.terms)
                    .map(|(t, series)| (t.label.clone(), t.tag.clone(), series))
                    .collect()
            } else {
                Vec::new()
            },
        }
    }
}

/// Thermal noise as [`thermal_noise`], solved and broken down as `options` says. `v` may
/// also be a displacement output over the variables, floats and parameters (a point's
/// whole motion): the parameters' part is left out, the support does not fluctuate.
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
    let lossy = lossy_tags(model, damping)?;
    let keep = |t: usize| lossy.get(t).copied().unwrap_or(true);
    let mut sweep = Sweep::new(model, damping, &input, &output, options.solver)?;
    let mut tag_sums = TagSums::new(model, damping, temperature, |u| sweep.local(u), keep);
    // the reference path adds its per-tag shares up from the per-term ones
    let reference = options.solver == Solver::DenseReference;
    let (mut term_forms, term_tags) = if options.per_term || reference {
        Forms::of_terms(model, |u| sweep.local(u), keep)
    } else {
        (Forms::default(), Vec::new())
    };
    // with one temperature the PSD is 4 k_B T/ω |Im R|, R = vᵀ E⁻¹ v: no sum of shares
    let uniform = tag_sums.temperatures.iter().all(|&t| t == temperature);
    let mut curves = Curves::new(freqs.len(), model.by_tag.len(), term_tags.len());
    // the frequency terms' dissipation per tag (continuum fibres: docs/continuum-fibres.md)
    let frequency = !model.frequency_terms.is_empty();
    let mut dissipation = vec![0.0; model.by_tag.len()];
    sweep.for_each(freqs, |k, response, sweep| {
        let f = freqs[k];
        let scale = 4.0 * BOLTZMANN * temperature / (2.0 * std::f64::consts::PI * f);
        curves.total.push(scale * response.im.abs());
        let z = sweep.response();
        let sum = tag_sums.at(f, z, |t| sweep.multiplier(t).map_or(0.0, |m| m.im));
        if !term_tags.is_empty() {
            term_forms.update(z);
            for (j, (&tag, series)) in term_tags.iter().zip(&mut curves.terms).enumerate() {
                series.push(sum.share_of(tag, term_forms.energy(j)));
            }
        }
        if reference {
            curves.push_tags_from_terms(&term_tags);
        } else {
            for (t, series) in curves.tags.iter_mut().enumerate() {
                series.push(sum.share(t));
            }
        }
        if frequency {
            // each tag's share gains 4 k_B T_tag/ω z̄ᵀ Im(C_tag) z, so that the shares
            // still add up to 4 k_B T/ω |Im R| (Im E = Σ ε″ P_tag + Σ Im C_tag)
            dissipation.fill(0.0);
            sweep.add_frequency_dissipation(&mut dissipation);
            for (t, series) in curves.tags.iter_mut().enumerate() {
                if let Some(last) = series.last_mut() {
                    *last += fd_scale(f) * tag_sums.temperatures[t] * dissipation[t];
                }
            }
        }
        if !uniform {
            curves.total_from_tags();
        }
    })?;
    Ok(curves.finish(model, options.per_term))
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
    //! evaluated here from the inputs. The models go through the same builder, equilibrium
    //! and stage matrices as any other (`pendkit_assembly::assemble`, `StageModel::new`).
    //! Beyond the one oscillator: a float between two springs and three decoupled blocks,
    //! against a dense solve written here ([`Dense`]) or the closed form per block.
    //!
    //! Tolerance 1e-10 relative unless a test says otherwise: the stage's matrices are
    //! exact (linear springs), the responses are small complex solves whose condition is
    //! at most about 1/φ = 10³ at a resonance, so rounding (~1e-13 at worst) is all that
    //! separates the two sides; 1e-10 is the same bound the workspace's oracle tests use.

    use super::*;
    use nalgebra::{Complex, DMatrix, Matrix6, Vector3, Vector6};
    use pendkit_assembly::{EquilibriumOptions, assemble};
    use pendkit_model::{BodySpec, DampingSpec, SystemBuilder};
    use pendkit_params::ParamSet;
    use pendkit_system::{SpringEnd, Stage};

    const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
    const TEMPERATURE: f64 = 300.0;

    /// A spring of a fixture along x: end 0's body (an index into the fixture's bodies, or
    /// `None` for the ground, the parameter `s`), end 1's body, stiffness k (N/m), tag.
    type LineSpring<'a> = (Option<usize>, usize, f64, &'a str);

    /// A tag's loss of a fixture: tag, structural loss angle φ (rad), and its own noise
    /// temperature (K) if it has one.
    type Loss<'a> = (&'a str, f64, Option<f64>);

    /// Bodies moving along x only, each `(coordinate, mass)`: a variable with its mass
    /// (kg), or a float (a massless body) for `None`, joined to each other and to the
    /// ground by `springs`; assembled at stage 0B.
    fn line(bodies: &[(&str, Option<f64>)], springs: &[LineSpring]) -> StageModel {
        let mut b = SystemBuilder::new(9.81);
        b.parameter("s", 0.0).unwrap();
        let ground = b
            .body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))
            .unwrap();
        let mut ids = Vec::new();
        for &(name, mass) in bodies {
            let spec = BodySpec::new(format!("body {name}")).pose([name, "0", "0", "0", "0", "0"]);
            let spec = match mass {
                Some(m) => {
                    b.variable(name, 0.0).unwrap();
                    spec.mass(m)
                }
                None => {
                    b.float(name, 0.0).unwrap();
                    spec
                }
            };
            ids.push(b.body(spec).unwrap());
        }
        let end = |body| SpringEnd {
            body,
            point: Vector3::zeros(),
            angles: [0.0; 3],
        };
        for (n, &(from, to, k, tag)) in springs.iter().enumerate() {
            let from = from.map_or(ground, |i| ids[i]);
            let stiffness = Matrix6::from_diagonal(&Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
            b.spring(
                &format!("k{n}"),
                [end(from), end(ids[to])],
                stiffness,
                Vector6::zeros(),
                tag,
            )
            .unwrap();
        }
        let system = b.build().unwrap();
        let assembled = assemble(&system, Stage::S0B, &EquilibriumOptions::default()).unwrap();
        StageModel::new(&system, &assembled)
    }

    /// Structural damping, each tag's loss φ given by `losses` (and its own temperature
    /// where given).
    fn structural(losses: &[Loss]) -> Damping {
        let mut damping = Damping::default();
        let params = ParamSet::new().resolve().unwrap();
        for &(tag, phi, temperature) in losses {
            // Display of an f64 is the shortest text that reads back as the same number
            let spec = DampingSpec::structural(&phi.to_string());
            damping.set(tag, spec.resolve(tag, &params).unwrap());
            if let Some(t) = temperature {
                damping.set_temperature(tag, t);
            }
        }
        damping
    }

    /// A mass of 1 kg on a spring `k` (N/m) along x to ground, with `spec` on tag "spring".
    fn oscillator(k: f64, spec: DampingSpec) -> (StageModel, Damping) {
        let model = line(&[("x", Some(1.0))], &[(None, 0, k, "spring")]);
        let mut damping = Damping::default();
        damping.set(
            "spring",
            spec.resolve("spring", &ParamSet::new().resolve().unwrap())
                .unwrap(),
        );
        (model, damping)
    }

    /// S_x(f) of a structurally damped oscillator, mass m (kg) on k(1 + iφ) (N/m), at
    /// [`TEMPERATURE`] (docs/reference-values.md §6).
    fn closed_form(k: f64, m: f64, phi: f64, f: f64) -> f64 {
        let w = TWO_PI * f;
        let d = (k - m * w * w).powi(2) + (k * phi).powi(2);
        4.0 * BOLTZMANN * TEMPERATURE * k * phi / (w * d)
    }

    /// dS_x/dk of [`closed_form`] (m²/Hz per N/m), by hand: S = C k/D with C = 4 k_B T φ/ω
    /// and D = (k − m ω²)² + k² φ², so dS/dk = C (D − k D')/D², D' = 2(k − m ω²) + 2 k φ².
    fn closed_form_dk(k: f64, m: f64, phi: f64, f: f64) -> f64 {
        let w = TWO_PI * f;
        let c = 4.0 * BOLTZMANN * TEMPERATURE * phi / w;
        let d = (k - m * w * w).powi(2) + (k * phi).powi(2);
        let d_prime = 2.0 * (k - m * w * w) + 2.0 * k * phi * phi;
        c * (d - k * d_prime) / (d * d)
    }

    /// The relative difference |a − b|/|b|, or |a| where b is 0.
    fn rel(a: f64, b: f64) -> f64 {
        if b == 0.0 {
            a.abs()
        } else {
            (a - b).abs() / b.abs()
        }
    }

    /// A fixture's matrices written out densely from its description (bodies, springs,
    /// losses), without the assembly, the pattern or the sweeps: over the master rows in
    /// the model's order (variables, floats, parameters, found by name), each tag's
    /// stiffness K_tag (N/m) with its loss and temperature, and the mass M (kg).
    struct Dense {
        /// Unknowns (variables and floats), then the parameter `s`: n = u + 1 rows.
        u: usize,
        /// (tag, φ, noise temperature (K), K_tag).
        tags: Vec<(String, f64, f64, DMatrix<f64>)>,
        mass: DMatrix<f64>,
    }

    impl Dense {
        fn new(
            model: &StageModel,
            bodies: &[(&str, Option<f64>)],
            springs: &[LineSpring],
            losses: &[Loss],
        ) -> Dense {
            let names: Vec<&String> = model
                .variables
                .iter()
                .chain(&model.floats)
                .chain(&model.parameters)
                .collect();
            let row = |name: &str| names.iter().position(|n| *n == name).unwrap();
            let n = names.len();
            let mut mass = DMatrix::zeros(n, n);
            for &(name, m) in bodies {
                mass[(row(name), row(name))] = m.unwrap_or(0.0);
            }
            let tags = losses
                .iter()
                .map(|&(tag, phi, temperature)| {
                    let mut k_tag = DMatrix::zeros(n, n);
                    for &(from, to, k, _) in springs.iter().filter(|s| s.3 == tag) {
                        let a = row(from.map_or("s", |i| bodies[i].0));
                        let b = row(bodies[to].0);
                        // ½ k (x_b − x_a)²
                        k_tag[(a, a)] += k;
                        k_tag[(b, b)] += k;
                        k_tag[(a, b)] -= k;
                        k_tag[(b, a)] -= k;
                    }
                    (
                        tag.to_string(),
                        phi,
                        temperature.unwrap_or(TEMPERATURE),
                        k_tag,
                    )
                })
                .collect();
            Dense {
                u: model.unknowns(),
                tags,
                mass,
            }
        }

        /// E(f) = Σ_tag (1 + iφ_tag) K_tag − ω² M over every master row.
        fn e(&self, f: f64) -> DMatrix<Complex<f64>> {
            let w2 = (TWO_PI * f).powi(2);
            let mut e = self.mass.map(|m| Complex::new(-w2 * m, 0.0));
            for (_, phi, _, k) in &self.tags {
                e += k.map(|k| Complex::new(k, k * phi));
            }
            e
        }

        /// E_uu⁻¹ rhs over the unknowns, by nalgebra's dense complex LU.
        fn solve(&self, f: f64, rhs: &[Complex<f64>]) -> Vec<Complex<f64>> {
            let e = self.e(f).view((0, 0), (self.u, self.u)).into_owned();
            let x = e
                .lu()
                .solve(&nalgebra::DVector::from_column_slice(rhs))
                .unwrap();
            x.iter().copied().collect()
        }

        /// Tag `tag`'s share of the PSD at `f` for the response `z` over the unknowns:
        /// 4 k_B T_tag φ_tag z̄ᵀ K_tag z / ω (the fluctuation–dissipation theorem per tag).
        fn share(&self, tag: &str, f: f64, z: &[Complex<f64>]) -> f64 {
            let (_, phi, temperature, k) = self.tags.iter().find(|t| t.0 == tag).unwrap();
            4.0 * BOLTZMANN * temperature * phi * self.form(k, z) / (TWO_PI * f)
        }

        /// z̄ᵀ A z over the unknowns, A real symmetric.
        fn form(&self, a: &DMatrix<f64>, z: &[Complex<f64>]) -> f64 {
            let mut sum = Complex::new(0.0, 0.0);
            for i in 0..self.u {
                for j in 0..self.u {
                    sum += z[i].conj() * a[(i, j)] * z[j];
                }
            }
            sum.re
        }
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
            let expected = closed_form(k, 1.0, phi, *f);
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
            let expected = closed_form(k, 1.0, phi, f);
            assert!(
                (sum.psd() - expected).abs() <= 1e-10 * expected,
                "{f} Hz: {} vs {expected}",
                sum.psd()
            );
        }
        // a right-hand side of another length is an error, not a panic
        assert!(sweep.solve_again(&mut [c64::new(1.0, 0.0); 2]).is_err());
    }

    /// The float fixture: ground —(k2, tag "outer")— float q —(k1, tag "inner")— mass m on
    /// x, so the mass hangs on k1 k2/(k1 + k2) = 40 N/m (f0 ≈ 0.71 Hz) and the float, with
    /// no mass, is where the two springs' forces balance. The losses differ (10⁻³, 10⁻²)
    /// so that each tag's share is its own.
    const FLOAT_BODIES: [(&str, Option<f64>); 2] = [("x", Some(2.0)), ("q", None)];
    const FLOAT_SPRINGS: [LineSpring<'static>; 2] =
        [(None, 1, 200.0, "outer"), (Some(1), 0, 50.0, "inner")];

    /// A float between two springs, the outer at its own temperature of 77 K: the noise at
    /// the mass (total, per tag, per term), the response and a second solve from the same
    /// factors (`Sweep::solve_again`), E(f) put together on the pattern and applied
    /// (`sum_parts`, `multiply`, parameter row included) and `TagSum`'s PSD, each against
    /// the dense matrices written out here and solved by nalgebra's complex LU over x and q.
    #[test]
    fn a_float_between_two_springs_is_the_dense_solution() {
        let losses = [("inner", 1e-3, None), ("outer", 1e-2, Some(77.0))];
        let model = line(&FLOAT_BODIES, &FLOAT_SPRINGS);
        let damping = structural(&losses);
        let dense = Dense::new(&model, &FLOAT_BODIES, &FLOAT_SPRINGS, &losses);
        assert_eq!((model.sizes, dense.u), ((1, 1, 1), 2));
        let one = Complex::new(1.0, 0.0);
        let zero = Complex::new(0.0, 0.0);
        // the output is the mass's x: unit force on x, unknowns (x, q)
        let v = DVector::from_vec(vec![1.0, 0.0]);
        // below, near and above the resonance (the closest point is 0.7 Hz)
        let freqs = [0.1, 0.7, 5.0];
        let noise = thermal_noise(&model, &damping, &v, TEMPERATURE, &freqs).unwrap();
        let mut sweep = Sweep::new(
            &model,
            &damping,
            &Input::Force(v.clone()),
            &Output::Displacement(v.clone()),
            Solver::Restricted,
        )
        .unwrap();
        // x and q are one block: both are solved
        assert_eq!(sweep.unknowns(), &[0, 1]);
        for (i, &f) in freqs.iter().enumerate() {
            let z = dense.solve(f, &[one, zero]);
            // tags at their own temperatures: the noise is the sum of the tags' shares
            let inner = dense.share("inner", f, &z);
            let outer = dense.share("outer", f, &z);
            assert!(rel(noise.total[i], inner + outer) <= 1e-10, "{f} Hz total");
            for (tag, expected) in [("inner", inner), ("outer", outer)] {
                let tag_curve = &noise.tags.iter().find(|t| t.0 == tag).unwrap().1;
                assert!(rel(tag_curve[i], expected) <= 1e-10, "{f} Hz {tag}");
                // one spring per tag: its term carries the tag's share
                let term = &noise.by_term.iter().find(|t| t.1 == tag).unwrap().2;
                assert!(rel(term[i], expected) <= 1e-10, "{f} Hz term of {tag}");
            }
            sweep.at(f).unwrap();
            for (a, b) in sweep.response().iter().zip(&z) {
                assert!((a - b).norm() <= 1e-10 * b.norm(), "{f} Hz response");
            }
            // a force on the float alone, from the same factors
            let mut on_float = vec![zero, one];
            sweep.solve_again(&mut on_float).unwrap();
            for (a, b) in on_float.iter().zip(dense.solve(f, &[zero, one])) {
                assert!((a - b).norm() <= 1e-10 * b.norm(), "{f} Hz solve_again");
            }
            // E w over every master row, the support's too, for a w that moves all three
            let w = [z[0], z[1], Complex::new(0.3, -0.2)];
            let mut e = vec![zero; model.pattern.len()];
            model
                .sum_parts(&model.dynamic_parts(&damping, f), &mut e)
                .unwrap();
            let mut ew = vec![zero; 3];
            model.multiply(&e, &w, &mut ew).unwrap();
            let expected = dense.e(f) * nalgebra::DVector::from_column_slice(&w);
            let scale = expected.norm();
            for (a, b) in ew.iter().zip(expected.iter()) {
                assert!((a - b).norm() <= 1e-12 * scale, "{f} Hz E w");
            }
            let sum = TagSum::new(&model, &damping, TEMPERATURE, f, &z).unwrap();
            assert!(rel(sum.psd(), inner + outer) <= 1e-10, "{f} Hz TagSum");
        }
    }

    /// `TagSum::change` on the float fixture at one temperature, for the inner loss angle
    /// φ1 as the parameter: the weight T φ1 moves by T, and every tag's energy through the
    /// response, dz = −E⁻¹ (dE/dφ1) z with dE/dφ1 = i K_inner (the dense solve here), so
    /// dE_tag = 2 Re z̄ᵀ K_tag dz. The expected dS comes the other way, from the total
    /// alone: S = 4 k_B T/ω |Im R|, R = vᵀz, dR = vᵀ dz, which the per-tag split must give
    /// by the fluctuation–dissipation theorem. Tolerance 1e-9 relative: the same solves as
    /// above, but dS sums terms of both signs (the weight's and the energies' changes),
    /// which can cancel a digit.
    #[test]
    fn a_float_tag_sums_change_is_the_change_of_the_total() {
        let losses = [("inner", 1e-3, None), ("outer", 1e-2, None)];
        let model = line(&FLOAT_BODIES, &FLOAT_SPRINGS);
        let damping = structural(&losses);
        let dense = Dense::new(&model, &FLOAT_BODIES, &FLOAT_SPRINGS, &losses);
        let one = Complex::new(1.0, 0.0);
        let zero = Complex::new(0.0, 0.0);
        let k_inner = dense
            .tags
            .iter()
            .find(|t| t.0 == "inner")
            .unwrap()
            .3
            .clone();
        for f in [0.1, 0.7, 5.0] {
            let z = dense.solve(f, &[one, zero]);
            let de_z: Vec<Complex<f64>> = (0..dense.u)
                .map(|i| {
                    (0..dense.u)
                        .map(|j| Complex::new(0.0, k_inner[(i, j)]) * z[j])
                        .sum()
                })
                .collect();
            let dz: Vec<Complex<f64>> = dense.solve(f, &de_z).iter().map(|x| -x).collect();
            let r = z[0];
            let expected = 4.0 * BOLTZMANN * TEMPERATURE / (TWO_PI * f) * r.im.signum() * dz[0].im;
            let sum = TagSum::new(&model, &damping, TEMPERATURE, f, &z).unwrap();
            let (mut d_weights, mut d_energies) = (Vec::new(), Vec::new());
            for (tag, _) in &model.by_tag {
                d_weights.push(if tag == "inner" { TEMPERATURE } else { 0.0 });
                let k_tag = &dense.tags.iter().find(|t| t.0 == *tag).unwrap().3;
                let mut along = Complex::new(0.0, 0.0);
                for i in 0..dense.u {
                    for j in 0..dense.u {
                        along += z[i].conj() * k_tag[(i, j)] * dz[j];
                    }
                }
                d_energies.push(2.0 * along.re);
            }
            let change = sum.change(&d_weights, &d_energies);
            assert!(
                rel(change, expected) <= 1e-9,
                "{f} Hz: {change} vs {expected}"
            );
        }
    }

    /// The blocks fixture: three masses, each on its own spring to the ground, so each is
    /// its own block: a (1 kg, 4π² N/m, tag "a"), b (1.5 kg, 5 N/m, tag "b"), c (0.5 kg,
    /// 20 N/m, tag "a" too). The output is x_a + 2 x_c, which block b never meets.
    const BLOCK_BODIES: [(&str, Option<f64>); 3] =
        [("xa", Some(1.0)), ("xb", Some(1.5)), ("xc", Some(0.5))];
    const BLOCK_SPRINGS: [LineSpring<'static>; 3] = [
        (None, 0, TWO_PI * TWO_PI, "a"),
        (None, 1, 5.0, "b"),
        (None, 2, 20.0, "a"),
    ];
    const BLOCK_LOSSES: [Loss<'static>; 2] = [("a", 1e-3, None), ("b", 1e-2, None)];
    const BLOCK_OUTPUT: [f64; 3] = [1.0, 0.0, 2.0];

    /// Block `i`'s (k (N/m), m (kg), φ) from the fixture.
    fn block(i: usize) -> (f64, f64, f64) {
        let (_, _, k, tag) = BLOCK_SPRINGS[i];
        let phi = BLOCK_LOSSES.iter().find(|l| l.0 == tag).unwrap().1;
        (k, BLOCK_BODIES[i].1.unwrap(), phi)
    }

    /// Block `i`'s receptance 1/(k(1 + iφ) − m ω²) (m/N) at `f` (Hz).
    fn receptance(i: usize, f: f64) -> Complex<f64> {
        let (k, m, phi) = block(i);
        Complex::new(1.0, 0.0) / (Complex::new(k, k * phi) - m * (TWO_PI * f).powi(2))
    }

    /// The noise at x_a + 2 x_c: S_a + 4 S_c of the two oscillators' closed forms.
    fn blocks_psd(f: f64) -> f64 {
        let ((k_a, m_a, phi_a), (k_c, m_c, phi_c)) = (block(0), block(2));
        closed_form(k_a, m_a, phi_a, f) + 4.0 * closed_form(k_c, m_c, phi_c, f)
    }

    /// Three decoupled blocks: the noise at x_a + 2 x_c is the closed forms' S_a + 4 S_c,
    /// all of it tag a's and tag b's exactly 0 (its block is not even solved); the
    /// restricted sweep solves a and c only, with the receptances as responses, and
    /// `solve_again` gives a force on c alone c's receptance and a exactly no motion.
    #[test]
    fn three_blocks_noise_and_solves_are_the_oscillators() {
        let model = line(&BLOCK_BODIES, &BLOCK_SPRINGS);
        let damping = structural(&BLOCK_LOSSES);
        assert_eq!(model.sizes, (3, 0, 1));
        let v = DVector::from_column_slice(&BLOCK_OUTPUT);
        let freqs = [0.1, 1.0, 10.0];
        let noise = thermal_noise(&model, &damping, &v, TEMPERATURE, &freqs).unwrap();
        let (input, output) = (Input::Force(v.clone()), Output::Displacement(v.clone()));
        let mut sweep = Sweep::new(&model, &damping, &input, &output, Solver::Restricted).unwrap();
        assert_eq!(sweep.unknowns(), &[0, 2]);
        let tag = |name: &str| &noise.tags.iter().find(|t| t.0 == name).unwrap().1;
        for (n, &f) in freqs.iter().enumerate() {
            let expected = blocks_psd(f);
            assert!(rel(noise.total[n], expected) <= 1e-10, "{f} Hz total");
            assert!(rel(tag("a")[n], expected) <= 1e-10, "{f} Hz tag a");
            assert!(tag("b")[n] == 0.0, "{f} Hz tag b");
            sweep.at(f).unwrap();
            let z_ac = [receptance(0, f), receptance(2, f) * 2.0];
            for (a, b) in sweep.response().iter().zip(&z_ac) {
                assert!((a - b).norm() <= 1e-10 * b.norm(), "{f} Hz response");
            }
            let mut on_c = vec![Complex::new(0.0, 0.0), Complex::new(1.0, 0.0)];
            sweep.solve_again(&mut on_c).unwrap();
            assert!(on_c[0].norm() == 0.0, "{f} Hz: a force on c moves a");
            let z_c = receptance(2, f);
            assert!(
                (on_c[1] - z_c).norm() <= 1e-10 * z_c.norm(),
                "{f} Hz solve_again"
            );
        }
    }

    /// Three decoupled blocks: E(f) from `sum_parts` applied by `multiply` to a w over every
    /// master row (row i is (k(1 + iφ) − m ω²) w_i − k(1 + iφ) w_s, the support's
    /// Σ k(1 + iφ) (w_s − w_i), written out; tolerance 1e-12 relative, a few products and
    /// sums); `TagSum` over all
    /// three unknowns (the full sweep's response) gives S_a + 4 S_c, and its change with
    /// k_c, at fixed weights (a structural loss does not move with k), tag a's energy
    /// k_a |z_a|² + k_c |z_c|² moving by |z_c|² + 2 k_c Re(z̄_c dz_c), dz_c = −(1 + iφ)
    /// z_c²/2, gives 4 dS_c/dk by hand ([`closed_form_dk`]). Tolerance 1e-9 for the change:
    /// near the resonance both sides subtract terms of similar size (D − k D' by hand,
    /// |z_c|² against 2 k_c Re z̄_c dz_c here), which can cost a digit or two of the 1e-10.
    #[test]
    fn three_blocks_dynamic_stiffness_and_tag_sum_are_the_oscillators() {
        let model = line(&BLOCK_BODIES, &BLOCK_SPRINGS);
        let damping = structural(&BLOCK_LOSSES);
        let zero = Complex::new(0.0, 0.0);
        let v = DVector::from_column_slice(&BLOCK_OUTPUT);
        let (input, output) = (Input::Force(v.clone()), Output::Displacement(v));
        let mut full = Sweep::new(&model, &damping, &input, &output, Solver::Full).unwrap();
        let w = [
            Complex::new(1.0, 0.5),
            Complex::new(-2.0, 0.25),
            Complex::new(0.5, -1.0),
            Complex::new(0.125, 0.0),
        ];
        for f in [0.1, 1.0, 10.0] {
            let mut e = vec![zero; model.pattern.len()];
            model
                .sum_parts(&model.dynamic_parts(&damping, f), &mut e)
                .unwrap();
            let mut ew = vec![zero; 4];
            model.multiply(&e, &w, &mut ew).unwrap();
            let mut support = zero;
            for i in 0..3 {
                let (k, _, phi) = block(i);
                let k = Complex::new(k, k * phi);
                let row = w[i] / receptance(i, f) - w[3] * k;
                assert!(
                    (ew[i] - row).norm() <= 1e-12 * row.norm(),
                    "{f} Hz E w row {i}"
                );
                support += (w[3] - w[i]) * k;
            }
            assert!(
                (ew[3] - support).norm() <= 1e-12 * support.norm(),
                "{f} Hz E w support"
            );
            full.at(f).unwrap();
            let z = full.response().to_vec();
            let sum = TagSum::new(&model, &damping, TEMPERATURE, f, &z).unwrap();
            assert!(rel(sum.psd(), blocks_psd(f)) <= 1e-10, "{f} Hz TagSum");
            let (k_c, m_c, phi_c) = block(2);
            let dz_c = -Complex::new(1.0, phi_c) * z[2] * z[2] / 2.0;
            let d_energy_a = z[2].norm_sqr() + 2.0 * k_c * (z[2].conj() * dz_c).re;
            let change = sum.change(&[0.0, 0.0], &[d_energy_a, 0.0]);
            let expected = 4.0 * closed_form_dk(k_c, m_c, phi_c, f);
            assert!(
                rel(change, expected) <= 1e-9,
                "{f} Hz: dS/dk_c {change} vs {expected}"
            );
        }
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
