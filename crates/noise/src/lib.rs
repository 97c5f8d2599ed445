//! Thermal noise by the fluctuation–dissipation theorem (DESIGN.md §5) at any output
//! combination of the coordinates, with the share of every lossy term and damping tag.
//!
//! S(f) = (4 k_B T / ω) |Im(vᵀ E(f)⁻¹ v)| as a one-sided PSD (m²/Hz for a displacement
//! output, rad²/Hz for an angle). With z = E⁻¹ v (floats included), Im(vᵀ z) = −z̄ᵀ Im(P) z
//! and Im(P) = Σ_terms ε''_tag(f) P_off,term, so the noise splits exactly into one
//! non-negative share per lossy term: which wire or blade dominates at which frequency.

use std::collections::BTreeMap;

use nalgebra::DVector;
use pendkit_dynamics::StageModel;
use pendkit_energy::Damping;

/// Boltzmann constant k_B (J/K).
pub const BOLTZMANN: f64 = 1.380649e-23;

/// Thermal noise at one output over a frequency grid.
#[derive(Clone, Debug)]
pub struct ThermalNoise {
    /// One-sided PSD (m²/Hz or rad²/Hz) per frequency.
    pub total: Vec<f64>,
    /// Share of each lossy term: (term name, tag, PSD per frequency); they add up to
    /// `total`.
    pub by_term: Vec<(String, String, Vec<f64>)>,
}

impl ThermalNoise {
    /// The breakdown summed per damping tag, in tag order.
    pub fn by_tag(&self) -> Vec<(String, Vec<f64>)> {
        let mut tags: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        for (_, tag, series) in &self.by_term {
            let sum = tags
                .entry(tag.clone())
                .or_insert_with(|| vec![0.0; series.len()]);
            for (s, v) in sum.iter_mut().zip(series) {
                *s += v;
            }
        }
        tags.into_iter().collect()
    }
}

/// Thermal-noise PSD of the output combination `v` of the variables (m²/Hz or rad²/Hz) at
/// temperature `temperature` (K) and frequencies `freqs` (Hz), with the share of every
/// lossy term, for the stage `model` with damping `damping`.
pub fn thermal_noise(
    model: &StageModel,
    damping: &Damping,
    v: &DVector<f64>,
    temperature: f64,
    freqs: &[f64],
) -> ThermalNoise {
    let (nx, nq, _) = model.sizes;
    let n = nx + nq;
    let mut out = ThermalNoise {
        total: Vec::with_capacity(freqs.len()),
        by_term: model
            .terms
            .iter()
            .map(|t| {
                (
                    t.label.clone(),
                    t.tag.clone(),
                    Vec::with_capacity(freqs.len()),
                )
            })
            .collect(),
    };
    for &f in freqs {
        let z = model.respond_to_force(damping, v, f);
        let scale = 4.0 * BOLTZMANN * temperature / (2.0 * std::f64::consts::PI * f);
        let response: faer::c64 = (0..nx).map(|i| z[i] * v[i]).sum();
        out.total.push(scale * response.im.abs());
        for (t, (_, _, series)) in model.terms.iter().zip(out.by_term.iter_mut()) {
            let (_, loss) = damping.at(&t.tag, f);
            // dissipation of this term: ε''(f) Re(z̄ᵀ P_off z) over its coordinates (the
            // support's entries of z are zero: it is held)
            let zl = |a: usize| {
                t.positions
                    .get(a)
                    .filter(|&&p| p < n)
                    .map_or(faer::c64::new(0.0, 0.0), |&p| z[p])
            };
            let m = t.positions.len();
            let mut energy = 0.0;
            if loss != 0.0 {
                for a in 0..m {
                    for b in 0..m {
                        energy += (zl(a).conj() * zl(b)).re * t.off[a * m + b];
                    }
                }
            }
            series.push(scale * loss * energy);
        }
    }
    out
}
