//! Damping specifications as a model or case writes them, resolved against the model's
//! parameters into compiled multipliers of frequency.

use pendkit_energy::TagDamping;
use pendkit_expr::{Slot, parse};
use pendkit_params::Resolved;

use crate::BuildError;

/// The damping of one tag: each field an expression over the model's parameters; `real`
/// and `imag` may also use `f` (Hz). The imaginary multiplier is the sum of the parts given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DampingSpec {
    /// ε'(f); 1 when absent.
    pub real: Option<String>,
    /// Structural loss angle φ (frequency independent).
    pub structural: Option<String>,
    /// Viscous loss: ε'' = viscous · f, i.e. the loss angle at 1 Hz (for a spring k with
    /// dashpot c, viscous = 2π c / k).
    pub viscous: Option<String>,
    /// Thermoelastic (Δ, τ in s): ε'' = Δ ωτ / (1 + (ωτ)²), ω = 2π f.
    pub thermoelastic: Option<(String, String)>,
    /// Any further ε''(f).
    pub imag: Option<String>,
}

impl DampingSpec {
    /// Structural damping with loss angle `phi` (an expression).
    pub fn structural(phi: &str) -> Self {
        DampingSpec {
            structural: Some(phi.to_string()),
            ..Default::default()
        }
    }

    /// Replaces the fields that `other` sets.
    pub fn merge(&mut self, other: &DampingSpec) {
        let pick = |a: &mut Option<String>, b: &Option<String>| {
            if b.is_some() {
                a.clone_from(b);
            }
        };
        pick(&mut self.real, &other.real);
        pick(&mut self.structural, &other.structural);
        pick(&mut self.viscous, &other.viscous);
        pick(&mut self.imag, &other.imag);
        if other.thermoelastic.is_some() {
            self.thermoelastic.clone_from(&other.thermoelastic);
        }
    }

    /// Sets one field by name (`real`, `structural`, `viscous`, `imag`,
    /// `thermoelastic.delta`, `thermoelastic.tau`), as `--set damping.<tag>.<field>=...` does.
    pub fn set_field(&mut self, field: &str, text: &str) -> Result<(), String> {
        let t = Some(text.to_string());
        match field {
            "real" => self.real = t,
            "structural" => self.structural = t,
            "viscous" => self.viscous = t,
            "imag" => self.imag = t,
            "thermoelastic.delta" | "thermoelastic.tau" => {
                let (mut d, mut tau) = self
                    .thermoelastic
                    .clone()
                    .unwrap_or(("0".into(), "0".into()));
                if field.ends_with("delta") {
                    d = text.to_string();
                } else {
                    tau = text.to_string();
                }
                self.thermoelastic = Some((d, tau));
            }
            _ => {
                return Err(format!(
                    "unknown damping field '{field}' (real, structural, viscous, imag, thermoelastic.delta, thermoelastic.tau)"
                ));
            }
        }
        Ok(())
    }

    /// Compiles the multipliers of tag `tag` against resolved parameters.
    pub fn resolve(&self, tag: &str, params: &Resolved) -> Result<TagDamping, BuildError> {
        let mut imag_parts = Vec::new();
        if let Some(phi) = &self.structural {
            imag_parts.push(format!("({phi})"));
        }
        if let Some(v) = &self.viscous {
            imag_parts.push(format!("({v})*f"));
        }
        if let Some((delta, tau)) = &self.thermoelastic {
            imag_parts.push(format!("({delta})*(2*pi*f*({tau}))/(1+(2*pi*f*({tau}))^2)"));
        }
        if let Some(e) = &self.imag {
            imag_parts.push(format!("({e})"));
        }
        let imag = if imag_parts.is_empty() {
            "0".to_string()
        } else {
            imag_parts.join("+")
        };
        let real = self.real.clone().unwrap_or_else(|| "1".to_string());
        let compile = |text: &str, which: &str| {
            let context = format!("damping of tag '{tag}' ({which})");
            let expr = parse(text).map_err(|e| BuildError::Expression {
                context: context.clone(),
                message: e.to_string(),
            })?;
            let slot = |s: &str| {
                if s == "f" {
                    Some(Slot::Var(0))
                } else {
                    params.get(s).ok().map(Slot::Const)
                }
            };
            expr.compile(&slot).map_err(|e| BuildError::Expression {
                context,
                message: e.to_string(),
            })
        };
        Ok(TagDamping {
            real: compile(&real, "real")?,
            imag: compile(&imag, "imag")?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pendkit_params::ParamSet;

    fn params() -> Resolved {
        let mut p = ParamSet::new();
        p.define("delta", "1.945745e-5").unwrap();
        p.define("tau", "1.450933e-2").unwrap();
        p.define("phi", "1e-7").unwrap();
        p.resolve().unwrap()
    }

    #[test]
    fn thermoelastic_peak_matches_the_oracle_table() {
        // physics_oracles.md §7, silica fibre with the stress term: Δ = 1.945745e-5,
        // τ = 1.450933e-2 s; φ_TE(1, 10, 100, 500 Hz) printed to 7 digits.
        let spec = DampingSpec {
            thermoelastic: Some(("delta".into(), "tau".into())),
            ..Default::default()
        };
        let d = spec.resolve("t", &params()).unwrap();
        for (f, printed) in [
            (1.0, 1.759213e-6),
            (10.0, 9.687251e-6),
            (100.0, 2.108941e-6),
            (500.0, 4.266579e-7),
        ] {
            let (re, im) = d.at(f);
            assert_eq!(re, 1.0);
            assert!((im - printed).abs() <= 0.5e-6 * printed, "{f} Hz: {im}");
        }
    }

    #[test]
    fn parts_add_and_fields_merge() {
        // §6: φ_w(ω) = φ + Δ ωτ/(1 + ω²τ²) = 9.787251e-6 at 10 Hz with φ = 1e-7.
        let mut spec = DampingSpec::structural("phi");
        spec.merge(&DampingSpec {
            thermoelastic: Some(("delta".into(), "tau".into())),
            ..Default::default()
        });
        let (_, im) = spec.resolve("t", &params()).unwrap().at(10.0);
        assert!((im - 9.787251e-6).abs() <= 0.5e-12);
        spec.set_field("viscous", "2e-3").unwrap();
        spec.set_field("real", "1 + 0*f").unwrap();
        let (re, im2) = spec.resolve("t", &params()).unwrap().at(10.0);
        assert_eq!(re, 1.0);
        assert!((im2 - im - 2e-2).abs() < 1e-15);
        assert!(spec.set_field("loss", "1").is_err());
        let bad = DampingSpec::structural("nosuch");
        assert!(
            bad.resolve("t", &params())
                .unwrap_err()
                .to_string()
                .contains("nosuch")
        );
    }
}
