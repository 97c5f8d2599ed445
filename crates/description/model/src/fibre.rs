//! Fibres whose radius changes along their length (aLIGO's tapered silica fibres: thick
//! necks at both clamps, a thin middle), as one effective wire.
//!
//! A profile is a list of round pieces (length, radius) from the upper clamp down. One
//! wire between the two clamps stands for the whole profile; its constants follow it:
//!
//! - stretch: the pieces are springs in series, k = 1 / Σ lᵢ/(Y Aᵢ) (exact for the static
//!   stretch; the fibre's own mass is not in the spring, as for every massless wire);
//! - bending: the bending energy of a fibre under tension T sits within a bending length
//!   λ = √(Y I / T) of each clamp (λ ≈ 4 mm for aLIGO's 400 µm necks under 97 N) and decays
//!   as e^(−s/λ) away from it, so the clamps see only their own piece: the section's
//!   moment of area is the clamp piece's. Exact up to e^(−l_neck/λ) (1e-5 for a 45 mm neck)
//!   when the clamp pieces are many bending lengths long, which [`FibreProfile::check`]
//!   does not require but [`FibreProfile::clamp_length_in_bending_lengths`] reports; the
//!   middle's own bending stiffness only matters for violin overtones (not modelled by one
//!   wire);
//! - torsion: the pieces twist in series, κ = 1 / Σ lᵢ/(G Jᵢ + T Jᵢ/Aᵢ); the effective
//!   section reproduces κ and dκ/dT at the nominal tension (the torsion term evaluates
//!   (G J_e + T J/A)/l at the equilibrium tension, which differs from the nominal by ~1e-6);
//! - mass: Σ ρ Aᵢ lᵢ (the linear density of the effective section is the mean).
//!
//! The loss weights ([`FibreProfile::stretch_inverse_radius`],
//! [`FibreProfile::torsion_inverse_radius`]) give each piece its share of the strain
//! energy, for surface loss (see [`crate::losses`]).

use std::f64::consts::PI;

use pendkit_expr::number_text;
use pendkit_system::{Real, WireEnd, WireSection, WireTags};

use crate::BuildError;

/// A round fibre made of pieces of different radii, with its material; its numbers are
/// generic over the scalar like the model's (`f64` by default).
#[derive(Clone, Debug, PartialEq)]
pub struct FibreProfile<S: Real = f64> {
    /// (length m, radius m) of each piece, from the upper clamp down.
    pub pieces: Vec<(S, S)>,
    /// Young's modulus Y (Pa).
    pub youngs_modulus: S,
    /// Shear modulus G (Pa).
    pub shear_modulus: S,
    /// Density ρ (kg/m³).
    pub density: S,
}

impl<S: Real> FibreProfile<S> {
    /// A uniform round fibre of `length` and `radius` (m).
    pub fn uniform(length: S, radius: S, youngs: S, shear: S, density: S) -> Self {
        FibreProfile {
            pieces: vec![(length, radius)],
            youngs_modulus: youngs,
            shear_modulus: shear,
            density,
        }
    }

    /// A tapered fibre of total `length` (m): necks of `neck_length` and `neck_radius` at
    /// both ends, `middle_radius` between them (pygwinc's `Fiber.EndLength`,
    /// `Fiber.EndRadius`, `Fiber.Radius`).
    pub fn tapered(
        length: S,
        (neck_length, neck_radius): (S, S),
        middle_radius: S,
        (youngs, shear, density): (S, S, S),
    ) -> Self {
        FibreProfile {
            pieces: vec![
                (neck_length, neck_radius),
                (length - neck_length * 2.0, middle_radius),
                (neck_length, neck_radius),
            ],
            youngs_modulus: youngs,
            shear_modulus: shear,
            density,
        }
    }

    /// Checks that every piece has a positive length and radius and the moduli and density
    /// are positive; `item` names the fibre in the error.
    pub fn check(&self, item: &str) -> Result<(), BuildError> {
        let bad = |message: String| BuildError::Invalid {
            item: item.to_string(),
            message,
        };
        if self.pieces.is_empty() {
            return Err(bad("a fibre profile needs at least one piece".into()));
        }
        for (k, &(l, r)) in self.pieces.iter().enumerate() {
            let (l, r) = (l.re(), r.re());
            if !(l.is_finite() && l > 0.0 && r.is_finite() && r > 0.0) {
                return Err(bad(format!(
                    "piece {} has length {l} m and radius {r} m; both must be positive \
                     (are the necks longer than half the fibre?)",
                    k + 1
                )));
            }
        }
        for (what, v) in [
            ("Young's modulus (Pa)", self.youngs_modulus),
            ("shear modulus (Pa)", self.shear_modulus),
            ("density (kg/m^3)", self.density),
        ] {
            let v = v.re();
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(format!(
                    "{what} must be positive (got {})",
                    number_text(v)
                )));
            }
        }
        Ok(())
    }

    /// Total length (m).
    pub fn length(&self) -> S {
        self.pieces.iter().map(|p| p.0).sum()
    }

    /// Mass (kg), Σ ρ π rᵢ² lᵢ.
    pub fn mass(&self) -> S {
        self.pieces
            .iter()
            .map(|&(l, r)| self.density * PI * r * r * l)
            .sum()
    }

    /// Stretch stiffness (N/m) of the pieces in series, 1 / Σ lᵢ/(Y π rᵢ²).
    pub fn stretch_stiffness(&self) -> S {
        self.pieces
            .iter()
            .map(|&(l, r)| l / (self.youngs_modulus * PI * r * r))
            .sum::<S>()
            .recip()
    }

    /// The part of the profile between `from` and `to` (m from the upper end, clamped to
    /// the profile), e.g. one segment between violin beads.
    pub fn slice(&self, from: S, to: S) -> FibreProfile<S> {
        // which piece ends bound the slice is decided on the values; the bounds carry their
        // derivatives
        let larger = |a: S, b: S| if a.re() >= b.re() { a } else { b };
        let smaller = |a: S, b: S| if a.re() <= b.re() { a } else { b };
        let mut pieces = Vec::new();
        let mut start = S::from(0.0);
        for &(l, r) in &self.pieces {
            let (a, b) = (larger(from, start), smaller(to, start + l));
            if b.re() > a.re() {
                pieces.push((b - a, r));
            }
            start += l;
        }
        FibreProfile {
            pieces,
            ..self.clone()
        }
    }

    /// Radius at the upper and lower clamps (m).
    pub fn clamp_radii(&self) -> (S, S) {
        let zero = S::from(0.0);
        let first = self.pieces.first().map_or(zero, |p| p.1);
        let last = self.pieces.last().map_or(zero, |p| p.1);
        (first, last)
    }

    /// The radius (m) of the uniform fibre with the same bending compliance as the pieces in
    /// series, r with 1/r⁴ = Σ (lᵢ/l)/rᵢ⁴: the bending constant of a segment clamped at both
    /// ends and short beside the bending length, which bends along its whole length.
    pub fn series_bending_radius(&self) -> S {
        let compliance: S = self.pieces.iter().map(|&(l, r)| l / r.powi(4)).sum();
        (self.length() / compliance).powf(0.25)
    }

    /// The shorter clamp piece's length in bending lengths λ = √(Y I/T) at tension `tension`
    /// (N): the effective bending constant is exact up to e^(−this).
    pub fn clamp_length_in_bending_lengths(&self, tension: f64) -> f64 {
        let youngs = self.youngs_modulus.re();
        [self.pieces.first(), self.pieces.last()]
            .into_iter()
            .flatten()
            .map(|&(l, r)| l.re() / (youngs * PI * r.re().powi(4) / 4.0 / tension).sqrt())
            .fold(f64::INFINITY, f64::min)
    }

    /// Σ wᵢ/rᵢ (1/m) with wᵢ each piece's share of the stretch energy (∝ lᵢ/rᵢ², the
    /// compliance share of springs in series): the 1/r of the surface loss of stretching.
    pub fn stretch_inverse_radius(&self) -> S {
        self.weighted_inverse_radius(2)
    }

    /// Σ wᵢ/rᵢ (1/m) with wᵢ each piece's share of the torsion energy (∝ lᵢ/rᵢ⁴, the
    /// compliance share of the unloaded twist G J).
    pub fn torsion_inverse_radius(&self) -> S {
        self.weighted_inverse_radius(4)
    }

    fn weighted_inverse_radius(&self, power: i32) -> S {
        let zero = S::from(0.0);
        let (num, den) = self.pieces.iter().fold((zero, zero), |(n, d), &(l, r)| {
            let w = l / r.powi(power);
            (n + w / r, d + w)
        });
        num / den
    }

    /// The effective section at nominal tension `tension` (N): area and moments of area of
    /// the upper clamp's piece (both clamps are alike in a symmetric profile; the bending
    /// term takes one section), torsion constants that give the series twist stiffness and
    /// its tension slope, and the mean linear density.
    pub fn section(&self, tension: S) -> WireSection<S> {
        self.section_bent_at(tension, self.clamp_radii().0)
    }

    /// [`FibreProfile::section`] with the moments of area of radius `r_clamp` (m): the
    /// radius at the end that is clamped, when only one is (a segment between a clamp and
    /// a hinged bead).
    pub fn section_bent_at(&self, tension: S, r_clamp: S) -> WireSection<S> {
        let g = self.shear_modulus;
        // per piece: c = G J + T J/A with J = π r⁴/2, J/A = r²/2
        let c = |r: S| g * PI * r.powi(4) / 2.0 + tension * r * r / 2.0;
        let compliance: S = self.pieces.iter().map(|&(l, r)| l / c(r)).sum();
        let length = self.length();
        let kappa_l = length / compliance; // κ l = G J_e + T J/A (N m²)
        // dκ/dT = κ² Σ lᵢ (Jᵢ/Aᵢ)/cᵢ²
        let slope: S = self
            .pieces
            .iter()
            .map(|&(l, r)| l * (r * r / 2.0) / (c(r) * c(r)))
            .sum::<S>()
            / (compliance * compliance)
            * length;
        let area = S::from(PI) * r_clamp * r_clamp;
        let moment = S::from(PI) * r_clamp.powi(4) / 4.0;
        let (zero, one) = (S::from(0.0), S::from(1.0));
        WireSection {
            youngs_modulus: self.youngs_modulus,
            shear_modulus: g,
            area,
            moment_1: moment,
            moment_2: moment,
            principal_axis: nalgebra::Vector3::new(one, zero, zero),
            // G J_e + T (J/A) = κ l with J/A = slope
            torsion_constant: (kappa_l - tension * slope) / g,
            polar_moment: slope * area,
            linear_density: self.mass() / length,
        }
    }

    /// One wire `name` for the whole profile between `ends`, carrying `tension` (N) at its
    /// nominal length (the profile's length): the effective section, the series stretch
    /// stiffness, and the unstretched length l − T/k.
    pub fn wire(
        &self,
        name: impl Into<String>,
        ends: [WireEnd<S>; 2],
        tension: S,
        tags: WireTags,
    ) -> pendkit_system::Wire<S> {
        self.wire_with_section(name, ends, tension, self.section(tension), tags)
    }

    /// [`FibreProfile::wire`] with a given effective section (see
    /// [`FibreProfile::section_bent_at`]).
    pub fn wire_with_section(
        &self,
        name: impl Into<String>,
        ends: [WireEnd<S>; 2],
        tension: S,
        section: WireSection<S>,
        tags: WireTags,
    ) -> pendkit_system::Wire<S> {
        let length = self.length();
        let stiffness = self.stretch_stiffness();
        pendkit_system::Wire {
            name: name.into(),
            ends,
            stiffness,
            unstretched_length: length - tension / stiffness,
            section,
            profile: self.pieces.clone(),
            tags,
            continuum: false,
        }
    }
}

/// The expression of a tapered fibre's strain-energy-weighted 1/r (see
/// [`FibreProfile::stretch_inverse_radius`]: `power` 2 for stretch, 4 for torsion) over
/// the parameters named by `(length, neck_length, neck_radius, middle_radius)`.
pub fn fibre_inverse_radius(
    (length, neck_length, neck_radius, middle_radius): (&str, &str, &str, &str),
    power: u32,
) -> String {
    let (ends, middle) = (
        format!("2*{neck_length}"),
        format!("({length}-2*{neck_length})"),
    );
    format!(
        "({ends}/{neck_radius}^{p1} + {middle}/{middle_radius}^{p1})/({ends}/{neck_radius}^{power} + {middle}/{middle_radius}^{power})",
        // a u64, so that no `power` overflows (2 and 4 are the ones used)
        p1 = u64::from(power) + 1
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn silica(length: f64) -> FibreProfile {
        FibreProfile::tapered(
            length,
            (0.045, 400e-6),
            205e-6,
            (7.2e10, 7.2e10 / 2.34, 2200.0),
        )
    }

    #[test]
    fn a_uniform_profile_is_a_round_wire() {
        // one piece: the effective section must be WireSection::round exactly (to rounding)
        let p: FibreProfile = FibreProfile::uniform(0.6, 2e-4, 7e10, 3e10, 2200.0);
        let s = p.section(97.0);
        let round = WireSection::round(2e-4, 7e10, 3e10, 2200.0);
        for (a, b) in [
            (s.area, round.area),
            (s.moment_1, round.moment_1),
            (s.torsion_constant, round.torsion_constant),
            (s.polar_moment, round.polar_moment),
            (s.linear_density, round.linear_density),
            (p.stretch_stiffness(), 7e10 * round.area / 0.6),
        ] {
            assert!((a - b).abs() <= 1e-12 * b.abs(), "{a} vs {b}");
        }
        assert!((p.stretch_inverse_radius() - 5e3).abs() < 1e-9);
    }

    #[test]
    fn tapered_constants_follow_the_profile() {
        // hand values for pygwinc's aLIGO fibre: 0.59 m, necks 45 mm of 400 µm, middle
        // 205 µm; stretch: 2 l_e/(Y π r_e²) + l_m/(Y π r_m²) in series (pygwinc's kv at
        // low frequency), mass ρ π (2 l_e r_e² + l_m r_m²)
        let p = silica(0.59);
        let y = 7.2e10;
        let k = 1.0 / (2.0 * 0.045 / (y * PI * 16e-8) + 0.5 / (y * PI * 205e-6 * 205e-6));
        assert!((p.stretch_stiffness() / k - 1.0).abs() < 1e-12);
        let m = 2200.0 * PI * (0.09 * 16e-8 + 0.5 * 205e-6 * 205e-6);
        assert!((p.mass() / m - 1.0).abs() < 1e-12);
        // bending at the clamps from the neck: I = π r_e⁴/4
        let s = p.section(97.1);
        assert!((s.moment_1 / (PI * 400e-6f64.powi(4) / 4.0) - 1.0).abs() < 1e-12);
        // the neck is ~11.6 bending lengths long at 97.1 N
        let n = p.clamp_length_in_bending_lengths(97.1);
        assert!((n - 0.045 / (y * PI * 400e-6f64.powi(4) / 4.0 / 97.1).sqrt()).abs() < 1e-9);
        assert!(n > 11.0 && n < 12.0);
        // torsion: the effective (G J_e + T J/A)/l at 97.1 N and at 98 N against the series
        // sum computed here piece by piece
        let kappa = |t: f64| {
            let c = |r: f64| y / 2.34 * PI * r.powi(4) / 2.0 + t * r * r / 2.0;
            1.0 / (2.0 * 0.045 / c(400e-6) + 0.5 / c(205e-6))
        };
        let eff =
            |t: f64| (s.shear_modulus * s.torsion_constant + t * s.polar_moment / s.area) / 0.59;
        assert!((eff(97.1) / kappa(97.1) - 1.0).abs() < 1e-12);
        // linear in T around the nominal: second-order error only
        assert!((eff(98.0) / kappa(98.0) - 1.0).abs() < 1e-6);
        // surface-loss weights lie between the two radii's 1/r
        let w = p.stretch_inverse_radius();
        assert!(w > 1.0 / 400e-6 && w < 1.0 / 205e-6);
    }

    #[test]
    fn slices_cover_the_profile() {
        // 7 equal segments of the 0.59 m fibre: their lengths and masses add up to the
        // whole; the first and last end in a neck, one segment straddles each junction
        let p = silica(0.59);
        let s = 0.59 / 7.0;
        let slices: Vec<FibreProfile> = (0..7)
            .map(|k| p.slice(k as f64 * s, (k + 1) as f64 * s))
            .collect();
        let (l, m): (f64, f64) = slices
            .iter()
            .fold((0.0, 0.0), |(l, m), x| (l + x.length(), m + x.mass()));
        assert!((l - 0.59).abs() < 1e-12 && (m / p.mass() - 1.0).abs() < 1e-12);
        assert_eq!(slices[0].clamp_radii(), (400e-6, 205e-6));
        assert_eq!(slices[6].clamp_radii(), (205e-6, 400e-6));
        // one middle piece of the segment's length (to rounding of the end positions)
        assert_eq!(slices[3].pieces.len(), 1);
        let (len, r) = slices[3].pieces[0];
        assert!((len - s).abs() < 1e-15 && r == 205e-6, "{len} {r}");
    }

    #[test]
    fn impossible_profiles_are_named() {
        let e = silica(0.08).check("fibre 'f1'").unwrap_err().to_string();
        assert!(e.contains("fibre 'f1'") && e.contains("piece 2"), "{e}");
    }
}
