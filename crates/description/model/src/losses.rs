//! Loss angles of wires, fibres and blades from their material and geometry, written as
//! damping expressions over a model's parameters (so that a case can change any input and
//! the loss follows). The formulas are those of LIGO's noise budget (pygwinc 0.6.2,
//! `suspension.py`), split by deformation because pendkit tags stretch, bending and
//! torsion separately:
//!
//! - bulk loss φ of the material (`<m>_phi`);
//! - surface loss (Gretarsson & Harry, Rev. Sci. Instrum. 70, 4081 (1999)):
//!   φ = φ_bulk (1 + μ d_s / r) with d_s the material's dissipation depth
//!   (`<m>_dissdepth`, m) and μ the surface-to-volume strain-energy factor of the
//!   deformation: μ = 2 for uniform stretch, μ = 4 for bending and torsion of a round
//!   section (the strain energy density grows as the distance from the axis squared, so
//!   the surface holds twice the volume's mean);
//! - thermoelastic loss of bending (Cagnoli & Willems, PRB 65, 174111 (2002)), at the
//!   clamp's radius r where the bending happens: Δ = (Y T_K/ρC)(α − σ β)², σ = tension/πr²
//!   the static stress, β = d ln Y/dT, τ = ρ C (2r)²/(2.16 · 2π K) (pygwinc's
//!   0.0737 · 4 ρ C A/(π K), the same number), φ = Δ ωτ/(1 + ω²τ²);
//! - blades: structural φ of the blade material plus the thermoelastic loss of a plate of
//!   thickness t bent across it, Δ = Y α² T_K/(ρC), τ = ρ C t²/(π² K) (pygwinc's
//!   `bladeTELoss`, which neglects the stress term).
//!
//! Every expression takes the temperature it uses from a parameter (or expression) that
//! the caller names, and the spec carries it as the tag's noise temperature, so that an
//! element can sit at its own temperature.

use crate::DampingSpec;

/// A material's constants as the loss formulas read them: each an expression over the
/// model's parameters (a parameter's name, a number, or any expression).
#[derive(Clone, Debug, PartialEq)]
pub struct LossMaterial {
    /// Structural (bulk) loss angle φ (rad).
    pub phi: String,
    /// Density ρ (kg/m³).
    pub rho: String,
    /// Specific heat C (J/(kg K)).
    pub specific_heat: String,
    /// Thermal conductivity K (W/(m K)).
    pub conductivity: String,
    /// Linear thermal expansion α (1/K).
    pub alpha: String,
    /// β = d ln Y / dT (1/K): the stress term of the thermoelastic loss.
    pub dlne_dt: String,
    /// Surface-loss dissipation depth d_s (m).
    pub dissipation_depth: String,
    /// Young's modulus Y (Pa).
    pub youngs: String,
}

/// The deformations of a wire and the inputs of their loss angles; each field is an
/// expression over the model's parameters.
#[derive(Clone, Debug)]
pub struct WireLoss<'a> {
    /// Prefix of the wire set's tags: `<set>_stretch`, `<set>_bending`, `<set>_torsion`.
    pub set: &'a str,
    /// The material's constants (its `youngs` is not read: the set's own is `youngs`).
    pub material: LossMaterial,
    /// Static tension per wire (N).
    pub tension: &'a str,
    /// Young's modulus (Pa).
    pub youngs: &'a str,
    /// Radius at the clamps (m): bending and its thermoelastic loss.
    pub clamp_radius: &'a str,
    /// Surface loss: `None` leaves it out (the material's bulk φ only); otherwise the
    /// strain-energy-weighted 1/r (1/m) of stretch and of torsion, e.g. `1/r` for a
    /// uniform wire (see [`crate::FibreProfile::stretch_inverse_radius`]).
    pub surface: Option<(String, String)>,
    /// Temperature (K): a parameter name or expression; `temperature` is the model's.
    pub temperature: &'a str,
    /// A factor on the whole bending loss (bulk, surface and thermoelastic), e.g.
    /// (computed dilution)/(given dilution) to impose a measured dilution; `None` is 1.
    pub dilution_scale: Option<String>,
}

impl WireLoss<'_> {
    /// The tags and damping of the set: stretch, bending (with the thermoelastic peak) and
    /// torsion.
    pub fn damping(&self) -> Vec<(String, DampingSpec)> {
        let m = &self.material;
        let phi = format!("({})", m.phi);
        let (rho, c, k) = (&m.rho, &m.specific_heat, &m.conductivity);
        let (alpha, beta) = (&m.alpha, &m.dlne_dt);
        let surface = |mu: f64, inverse_radius: &str| {
            format!(
                "{phi}*(1 + {mu}*({})*({inverse_radius}))",
                m.dissipation_depth
            )
        };
        let (stretch, bending, torsion) = match &self.surface {
            None => (phi.clone(), phi.clone(), phi.clone()),
            Some((stretch_ir, torsion_ir)) => (
                surface(2.0, stretch_ir),
                surface(4.0, &format!("1/({})", self.clamp_radius)),
                surface(4.0, torsion_ir),
            ),
        };
        let (t, r, y) = (self.tension, self.clamp_radius, self.youngs);
        let stress = format!("({t})/(pi*({r})^2)");
        let delta = format!(
            "({y})*({temp})/(({rho})*({c}))*(({alpha}) - {stress}*({beta})/({y}))^2",
            temp = self.temperature
        );
        let tau = format!("({rho})*({c})*(2*({r}))^2/(2.16*2*pi*({k}))");
        let (bending, delta) = match &self.dilution_scale {
            None => (bending, delta),
            Some(scale) => (
                format!("({bending})*({scale})"),
                format!("({delta})*({scale})"),
            ),
        };
        let at_temperature = |mut spec: DampingSpec| {
            if self.temperature != "temperature" {
                spec.temperature = Some(self.temperature.to_string());
            }
            spec
        };
        vec![
            (
                format!("{}_stretch", self.set),
                at_temperature(DampingSpec::structural(&stretch)),
            ),
            (
                format!("{}_bending", self.set),
                at_temperature(DampingSpec {
                    structural: Some(bending),
                    thermoelastic_delta: Some(delta),
                    thermoelastic_tau: Some(tau),
                    ..Default::default()
                }),
            ),
            (
                format!("{}_torsion", self.set),
                at_temperature(DampingSpec::structural(&torsion)),
            ),
        ]
    }
}

/// Damping of a blade of `material` and thickness `thickness` (m, an expression) at
/// `temperature` (K, an expression): structural φ plus the plate's thermoelastic loss.
pub fn blade_loss(material: &LossMaterial, thickness: &str, temperature: &str) -> DampingSpec {
    let m = material;
    let (y, alpha, rho, c, k) = (
        &m.youngs,
        &m.alpha,
        &m.rho,
        &m.specific_heat,
        &m.conductivity,
    );
    DampingSpec {
        structural: Some(m.phi.clone()),
        thermoelastic_delta: Some(format!("({y})*({alpha})^2*({temperature})/(({rho})*({c}))")),
        thermoelastic_tau: Some(format!("({rho})*({c})*({thickness})^2/(pi^2*({k}))")),
        temperature: (temperature != "temperature").then(|| temperature.to_string()),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pendkit_params::ParamSet;

    /// The material whose constants are the parameters `<prefix>_phi`, `<prefix>_rho`, ...
    /// (as `params` names them).
    fn material(prefix: &str) -> LossMaterial {
        let p = |column: &str| format!("{prefix}_{column}");
        LossMaterial {
            phi: p("phi"),
            rho: p("rho"),
            specific_heat: p("C"),
            conductivity: p("K"),
            alpha: p("alpha"),
            dlne_dt: p("dlnE_dT"),
            dissipation_depth: p("dissdepth"),
            youngs: p("Y"),
        }
    }

    /// pygwinc's aLIGO materials (ifo.yaml `Suspension.Silica`, `MaragingSteel`).
    fn params() -> pendkit_params::Resolved {
        let mut p = ParamSet::new();
        for (n, v) in [
            ("silica_phi", 4.1e-10),
            ("silica_rho", 2200.0),
            ("silica_C", 772.0),
            ("silica_K", 1.38),
            ("silica_alpha", 3.9e-7),
            ("silica_dlnE_dT", 1.52e-4),
            ("silica_Y", 7.2e10),
            ("silica_dissdepth", 1.5e-2),
            ("maraging_phi", 1e-4),
            ("maraging_rho", 7800.0),
            ("maraging_C", 460.0),
            ("maraging_K", 20.0),
            ("maraging_alpha", 11e-6),
            ("maraging_Y", 187e9),
            ("temperature", 290.0),
            ("cold", 123.0),
            ("T3", 39.6 * 9.81 / 4.0),
            ("r_neck", 400e-6),
            ("r_mid", 205e-6),
        ] {
            p.define_value(n, v).unwrap();
        }
        p.resolve().unwrap()
    }

    #[test]
    fn fibre_losses_match_pygwinc_formulas() {
        // pygwinc 0.6.2 suspension.py, written out here for a tapered fibre: horizontal
        // φ_h = φ(1 + (4/r_end) d_s) + φ_TE(r_end), vertical φ_v = φ(1 + (2/r) d_s)
        let p = params();
        let loss = WireLoss {
            set: "fibre",
            material: material("silica"),
            tension: "T3",
            youngs: "silica_Y",
            clamp_radius: "r_neck",
            surface: Some(("1/r_mid".into(), "1/r_neck".into())),
            temperature: "temperature",
            dilution_scale: None,
        };
        let d = loss.damping();
        let (phi, ds, t) = (4.1e-10, 1.5e-2, 39.6 * 9.81 / 4.0);
        let (rho, c, k, alpha, beta, y) = (2200.0, 772.0, 1.38, 3.9e-7, 1.52e-4, 7.2e10);
        let a_end = std::f64::consts::PI * 400e-6 * 400e-6;
        for f in [20.0, 100.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let tau = 7.37e-2 * 4.0 * (rho * c * a_end) / (std::f64::consts::PI * k);
            let delta = (alpha - t * beta / (a_end * y)).powi(2) * y * 290.0 / (rho * c);
            let te = delta * tau * w / (1.0 + w * w * tau * tau);
            let bending = phi * (1.0 + 4.0 / 400e-6 * ds) + te;
            let stretch = phi * (1.0 + 2.0 / 205e-6 * ds);
            let at = |tag: &str| {
                let spec = &d.iter().find(|(n, _)| n == tag).unwrap().1;
                spec.resolve(tag, &p).unwrap().at(f).1
            };
            // τ: pygwinc's 0.0737·4/π against 4/(2.16·2π): 1e-4 apart
            assert!((at("fibre_bending") / bending - 1.0).abs() < 2e-4, "{f} Hz");
            assert!((at("fibre_stretch") / stretch - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn blade_loss_matches_pygwinc_formula_and_carries_its_temperature() {
        // pygwinc bladeTELoss: τ = ρ C t²/(K π²), Δ = Y α² T/(ρ C)
        let p = params();
        let spec = blade_loss(&material("maraging"), "4200e-6", "cold");
        assert_eq!(spec.temperature.as_deref(), Some("cold"));
        let (rho, c, k, alpha, y, t) = (7800.0, 460.0, 20.0, 11e-6, 187e9, 4200e-6);
        let tau = rho * c * t * t / (k * std::f64::consts::PI.powi(2));
        let delta = y * alpha * alpha * 123.0 / (rho * c);
        let w = 2.0 * std::f64::consts::PI * 30.0;
        let expected = 1e-4 + delta * tau * w / (1.0 + w * w * tau * tau);
        let (_, im) = spec.resolve("b", &p).unwrap().at(30.0);
        assert!((im / expected - 1.0).abs() < 1e-12);
        assert!(
            blade_loss(&material("maraging"), "t", "temperature")
                .temperature
                .is_none()
        );
    }
}
