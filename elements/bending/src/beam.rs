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

use num_dual::Dual3_64;
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
///
/// A scalar that carries derivatives of total order at most three (every dual number the
/// derivative passes use: `Dual64`, `Dual2<Dual64>`, `HyperDual<Dual64>`, `Dual2SVec64`, …)
/// gets them by Taylor's formula around its real part u₀: f(u) = Σₖ f⁽ᵏ⁾(u₀) δᵏ / k! with
/// δ = u − u₀, whose powers past the scalar's order vanish exactly, and the f⁽ᵏ⁾(u₀)
/// from one evaluation on `f64` third-order duals. The same derivatives as the closed
/// form carried through the nested scalar (to rounding), for a few products instead of
/// its divisions and exponentials, which dominated the beam's cost in those passes.
pub fn stability<D: Real>(u: D) -> Stability<D> {
    let order = D::NDERIV;
    if order == 0 || order > 3 {
        return stability_direct(u);
    }
    let u0 = u.re();
    let at = derivatives_at(u0);
    let delta = u - u0;
    let zero = c::<D>(0.0);
    let delta2 = if order >= 2 { delta * delta } else { zero };
    let delta3 = if order >= 3 { delta2 * delta } else { zero };
    let lift = |f: Dual3_64| delta3 * (f.v3 / 6.0) + delta2 * (f.v2 * 0.5) + delta * f.v1 + f.re;
    Stability {
        s_ii: lift(at.s_ii),
        s_ij: lift(at.s_ij),
        ds_ii: lift(at.ds_ii),
        ds_ij: lift(at.ds_ij),
    }
}

/// The stability functions and their first three derivatives at `u0`, remembered per
/// thread for the last few `u0`: a pass along many directions meets the same wire at the
/// same u₀ once per direction (a pure function of `u0`, so a remembered value is the
/// value).
fn derivatives_at(u0: f64) -> Stability<Dual3_64> {
    const SLOTS: usize = 64;
    type Slots = [Option<(u64, Stability<Dual3_64>)>; SLOTS];
    thread_local! {
        static REMEMBERED: std::cell::RefCell<Slots> = const { std::cell::RefCell::new([None; SLOTS]) };
    }
    let bits = u0.to_bits();
    // the mantissa's middle bits spread nearby tensions over the slots
    let slot = ((bits >> 20) ^ (bits >> 36)) as usize % SLOTS;
    REMEMBERED.with(|cell| {
        let mut slots = cell.borrow_mut();
        match slots[slot] {
            Some((key, value)) if key == bits => value,
            _ => {
                let value = stability_direct(Dual3_64::new(u0, 1.0, 0.0, 0.0));
                slots[slot] = Some((bits, value));
                value
            }
        }
    })
}

/// The stability functions at `u` ≥ 0 by the closed form (or its series), carried through
/// whatever scalar `u` is.
fn stability_direct<D: Real>(u: D) -> Stability<D> {
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

    /// Every part of a nested scalar, for comparing two evaluations of it.
    trait Parts {
        fn parts(&self) -> Vec<f64>;
    }
    impl Parts for f64 {
        fn parts(&self) -> Vec<f64> {
            vec![*self]
        }
    }
    impl<T: Parts> Parts for num_dual::Dual<T> {
        fn parts(&self) -> Vec<f64> {
            [self.re.parts(), self.eps.parts()].concat()
        }
    }
    impl<T: Parts> Parts for num_dual::Dual2<T> {
        fn parts(&self) -> Vec<f64> {
            [self.re.parts(), self.v1.parts(), self.v2.parts()].concat()
        }
    }
    impl<T: Parts> Parts for num_dual::HyperDual<T> {
        fn parts(&self) -> Vec<f64> {
            let (a, b, c, d) = (&self.re, &self.eps1, &self.eps2, &self.eps1eps2);
            [a.parts(), b.parts(), c.parts(), d.parts()].concat()
        }
    }

    /// Taylor's formula around the real part against the closed form carried through the
    /// same nested scalar: both are the exact derivatives, so they agree to rounding,
    /// relative to the largest part of each function: 1e-13 from u = 4 on; below, just
    /// above the series switch, the closed form's denominator u − 2 tanh(u/2) ≈ u³/12
    /// cancels and each derivative divides by it once more, so the two orders of
    /// operations round apart by more (3.8e-11 at u = 0.51, 1.2e-12 at u = 1 measured:
    /// 1e-10 allowed there). In the series range they agree to 1e-16.
    fn lifted_matches_direct<D: Real + Parts>(seed: impl Fn(f64) -> D) {
        for u in [0.05f64, 0.3, 0.49, 0.51, 1.0, 4.0, 30.0, 700.0] {
            let tolerance = match u {
                u if u < SERIES_BELOW => 1e-15,
                u if u < 4.0 => 1e-10,
                _ => 1e-13,
            };
            let (lifted, direct) = (stability(seed(u)), stability_direct(seed(u)));
            let pairs = [
                (lifted.s_ii, direct.s_ii),
                (lifted.s_ij, direct.s_ij),
                (lifted.ds_ii, direct.ds_ii),
                (lifted.ds_ij, direct.ds_ij),
            ];
            for (k, (a, b)) in pairs.iter().enumerate() {
                let (a, b) = (a.parts(), b.parts());
                let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
                for (x, y) in a.iter().zip(&b) {
                    assert!(
                        (x - y).abs() <= tolerance * scale,
                        "u = {u}, function {k}: {a:?} vs {b:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn taylor_lift_matches_the_closed_form_in_every_nested_scalar() {
        use num_dual::{Dual, Dual2, Dual64, HyperDual};
        let d = |re: f64, eps: f64| Dual64::new(re, eps);
        lifted_matches_direct(|u| Dual64::new(u, 0.8));
        lifted_matches_direct(|u| Dual::new(d(u, 0.7), d(1.3, -0.4)));
        lifted_matches_direct(|u| Dual2::new(d(u, 0.7), d(1.3, -0.4), d(0.2, 0.9)));
        lifted_matches_direct(|u| {
            HyperDual::new(d(u, 0.7), d(1.3, -0.4), d(-0.6, 0.5), d(0.2, 0.9))
        });
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
