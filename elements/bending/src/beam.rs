//! The tensioned beam in closed form (docs/physics.md §1, docs/reference-values.md §9).
//!
//! A wire of length l under tension T with bending stiffness EI, whose end slopes relative
//! to the chord are θ1 and θ2, stores (bending plus work against tension)
//!
//!   U = (EI / 2l) [ s_ii (θ1² + θ2²) + 2 s_ij θ1 θ2 ],  u = l sqrt(T / EI),
//!
//! with the tension "stability functions" of the beam-column
//!
//!   s_ii = u (u coth u − 1) / (u − 2 tanh(u/2)),  s_ij = u (1 − u / sinh u) / (u − 2 tanh(u/2)).
//!
//! A hinged end carries no moment, so its slope is condensed out (U minimised over it).
//! The part of U that is bending strain energy is EI ∂U/∂EI at fixed T, l and angles;
//! since u ∝ EI^(-1/2), that is (EI/2l) Θ [c − (u/2) dc/du] for every coefficient c.
//!
//! Evaluation is overflow-free for any u ≥ 0: the hyperbolic functions are written in
//! e^(−u), and below u = 0.5, where u − 2 tanh(u/2) ≈ u³/12 cancels, the Taylor series to
//! u¹⁰ is used (both are accurate to about 1e-14 at the switch).

use pendkit_rotations::{Real, c};

/// Below this tension parameter the series is used.
pub const SERIES_BELOW: f64 = 0.5;

/// s_ii, s_ij and their derivatives with respect to u.
#[derive(Clone, Copy, Debug)]
pub struct Stability<D> {
    /// Diagonal stability function s_ii(u) (4 at u = 0).
    pub s_ii: D,
    /// Off-diagonal stability function s_ij(u) (2 at u = 0).
    pub s_ij: D,
    /// ds_ii/du.
    pub ds_ii: D,
    /// ds_ij/du.
    pub ds_ij: D,
}

/// Taylor coefficients in u² of s_ii and s_ij (from sympy's series of the closed forms).
const SERIES_II: [f64; 6] = [
    4.0,
    2.0 / 15.0,
    -11.0 / 6300.0,
    1.0 / 27000.0,
    -509.0 / 582120000.0,
    14617.0 / 681080400000.0,
];
const SERIES_IJ: [f64; 6] = [
    2.0,
    -1.0 / 30.0,
    13.0 / 12600.0,
    -11.0 / 378000.0,
    907.0 / 1164240000.0,
    -27641.0 / 1362160800000.0,
];

/// Value and derivative of Σ a_k u^(2k).
fn even_series<D: Real>(a: &[f64; 6], u: D) -> (D, D) {
    let u2 = u * u;
    let mut value = c::<D>(0.0);
    let mut slope = c::<D>(0.0);
    for k in (0..6).rev() {
        value = value * u2 + a[k];
        if k > 0 {
            slope = slope * u2 + a[k] * (2 * k) as f64;
        }
    }
    // Σ 2k a_k u^(2k−1) = u · Σ 2k a_k u^(2k−2)
    (value, slope * u)
}

/// The stability functions at tension parameter `u` ≥ 0.
pub fn stability<D: Real>(u: D) -> Stability<D> {
    if u.re() < SERIES_BELOW {
        let (s_ii, ds_ii) = even_series(&SERIES_II, u);
        let (s_ij, ds_ij) = even_series(&SERIES_IJ, u);
        return Stability {
            s_ii,
            s_ij,
            ds_ii,
            ds_ij,
        };
    }
    let one = c::<D>(1.0);
    let e = (-u).exp();
    let e2 = e * e;
    let t = (one - e) / (one + e); // tanh(u/2)
    let coth = (one + e2) / (one - e2);
    let csch = e * 2.0 / (one - e2);
    let den = u - t * 2.0;
    let dden = t * t;
    let num_ii = u * u * coth - u;
    let dnum_ii = u * coth * 2.0 - u * u * csch * csch - one;
    let num_ij = u - u * u * csch;
    let dnum_ij = one - u * csch * 2.0 + u * u * csch * coth;
    let den2 = den * den;
    Stability {
        s_ii: num_ii / den,
        s_ij: num_ij / den,
        ds_ii: (dnum_ii * den - num_ii * dden) / den2,
        ds_ij: (dnum_ij * den - num_ij * dden) / den2,
    }
}

/// Coefficients of U = (EI/2l) (c11 θ1² + c22 θ2² + 2 c12 θ1 θ2).
#[derive(Clone, Copy, Debug)]
pub struct Coefficients<D> {
    /// Coefficient of θ1².
    pub c11: D,
    /// Coefficient of θ2².
    pub c22: D,
    /// Coefficient of 2 θ1 θ2.
    pub c12: D,
}

/// The total and the bending-only coefficients at tension parameter `u`, for ends that are
/// clamped (`true`) or hinged (`false`). A hinged end's slope is condensed out.
pub fn coefficients<D: Real>(u: D, clamped: [bool; 2]) -> (Coefficients<D>, Coefficients<D>) {
    let s = stability(u);
    let zero = c::<D>(0.0);
    let half_u = u * 0.5;
    // (value, d/du) of each coefficient
    let (c11, c22, c12) = match clamped {
        [true, true] => ((s.s_ii, s.ds_ii), (s.s_ii, s.ds_ii), (s.s_ij, s.ds_ij)),
        [true, false] | [false, true] => {
            // min over the hinged slope: s_ii − s_ij²/s_ii
            let f = s.s_ii - s.s_ij * s.s_ij / s.s_ii;
            let df = s.ds_ii
                - (s.s_ij * s.ds_ij * 2.0 * s.s_ii - s.s_ij * s.s_ij * s.ds_ii) / (s.s_ii * s.s_ii);
            if clamped[0] {
                ((f, df), (zero, zero), (zero, zero))
            } else {
                ((zero, zero), (f, df), (zero, zero))
            }
        }
        [false, false] => ((zero, zero), (zero, zero), (zero, zero)),
    };
    let total = Coefficients {
        c11: c11.0,
        c22: c22.0,
        c12: c12.0,
    };
    let bending = Coefficients {
        c11: c11.0 - half_u * c11.1,
        c22: c22.0 - half_u * c22.1,
        c12: c12.0 - half_u * c12.1,
    };
    (total, bending)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed forms evaluated directly with sinh/cosh (fine for moderate u).
    fn direct(u: f64) -> (f64, f64) {
        let den = 2.0 - 2.0 * u.cosh() + u * u.sinh();
        (
            (u * u * u.cosh() - u * u.sinh()) / den,
            (u * u.sinh() - u * u) / den,
        )
    }

    #[test]
    fn oracle_table_values() {
        // docs/reference-values.md §9, printed to 7 significant digits.
        let s = stability(1.0f64);
        assert!((s.s_ii - 4.131623).abs() < 5e-7 && (s.s_ij - 1.967670).abs() < 5e-7);
        let s = stability(10.0f64);
        assert!((s.s_ii - 11.24974).abs() < 5e-6 && (s.s_ij - 1.248837).abs() < 5e-7);
        let s = stability(624.76195f64);
        assert!((s.s_ii - 625.7652).abs() < 5e-5 && (s.s_ij - 1.003211).abs() < 5e-7);
        // bending parts of (EI/l) s_ii and (EI/l) s_ij at u = 10 (EI = 1, l = 1)
        let (_, b) = coefficients(10.0f64, [true, true]);
        assert!((b.c11 - 6.404669).abs() < 5e-7 && (b.c12 - 1.399674).abs() < 5e-7);
    }

    #[test]
    fn matches_the_textbook_cosh_sinh_form() {
        // Chen & Lui's cosh/sinh form, independent of our e^(−u) rewriting
        for u in [0.6f64, 1.0, 3.0, 10.0, 50.0, 300.0] {
            let s = stability(u);
            let (ii, ij) = direct(u);
            assert!((s.s_ii - ii).abs() < 1e-12 * ii, "{u}");
            assert!((s.s_ij - ij).abs() < 1e-12 * ii, "{u}");
        }
    }

    #[test]
    fn derivatives_match_finite_differences_and_duals() {
        for u in [0.1f64, 0.49, 0.51, 2.0, 30.0, 700.0] {
            let h = 1e-6 * u;
            let (p, m) = (stability(u + h), stability(u - h));
            let s = stability(u);
            assert!(
                (s.ds_ii - (p.s_ii - m.s_ii) / (2.0 * h)).abs() < 1e-7 * s.s_ii.abs().max(1.0),
                "{u}"
            );
            assert!(
                (s.ds_ij - (p.s_ij - m.s_ij) / (2.0 * h)).abs() < 1e-7,
                "{u}"
            );
            let d = stability(num_dual::Dual64::new(u, 1.0));
            assert!((d.s_ii.eps - s.ds_ii).abs() < 1e-10 * s.ds_ii.abs().max(1.0));
        }
    }

    #[test]
    fn continuous_across_the_series_switch() {
        let below = stability(SERIES_BELOW * (1.0f64 - 1e-12));
        let above = stability(SERIES_BELOW * (1.0f64 + 1e-12));
        assert!((below.s_ii - above.s_ii).abs() < 1e-13);
        assert!((below.s_ij - above.s_ij).abs() < 1e-13);
        assert!((below.ds_ii - above.ds_ii).abs() < 1e-11);
        assert!((below.ds_ij - above.ds_ij).abs() < 1e-11);
    }

    #[test]
    fn finite_and_asymptotic_at_huge_u() {
        // u → ∞: s_ii ≈ u − 1 + ..., s_ij → 1 (overflow-free up to 1e5 and beyond)
        for u in [1e3f64, 1e4, 1e5, 1e7] {
            let s = stability(u);
            assert!(s.s_ii.is_finite() && s.s_ij.is_finite() && s.ds_ii.is_finite());
            assert!((s.s_ii - (u * u - u) / (u - 2.0)).abs() < 1e-9 * u);
            assert!((s.s_ij - u / (u - 2.0)).abs() < 1e-12);
            let (t, b) = coefficients(num_dual::HyperDual64::from_re(u), [true, false]);
            assert!(t.c11.re.is_finite() && b.c11.eps1eps2.is_finite());
        }
    }

    #[test]
    fn hinged_end_reproduces_one_bending_point_stiffness() {
        // §9: pinned bottom K1 = T/l + (EI/l³)(s_ii² − s_ij²)/s_ii = T/(l − λ tanh u)
        let (ei, t, l) = (1.0f64, 100.0f64, 1.0f64);
        let u: f64 = l * (t / ei).sqrt();
        let (c, _) = coefficients(u, [true, false]);
        let k1 = t / l + ei / l.powi(3) * c.c11;
        let lambda = (ei / t).sqrt();
        assert!((k1 - t / (l - lambda * u.tanh())).abs() < 1e-12 * k1);
        assert!((k1 - 111.1111).abs() < 5e-5);
        // clamped, non-rotating bottom: K2 = T/l + 2 (EI/l³)(s_ii + s_ij) = T/(l − 2λ tanh(u/2))
        let (c, _) = coefficients(u, [true, true]);
        let k2 = t / l + 2.0 * ei / l.powi(3) * (c.c11 + c.c12);
        assert!((k2 - t / (l - 2.0 * lambda * (u / 2.0).tanh())).abs() < 1e-12 * k2);
        assert!((k2 - 124.9972).abs() < 5e-5);
    }
}
