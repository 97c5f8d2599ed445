//! Second-order dual numbers along several directions at once, one lane per direction.
//!
//! The exact mode sensitivities evaluate every energy term along each mode w: the second
//! derivative wᵀHw, with its derivative with respect to a parameter or a coordinate
//! (docs/exact-sensitivities.md). `Dual2<Dual64>` does that one mode at a time. A
//! [`TangentLanes`] ([`SecondLanes`]) carries [`LANES`] modes in one evaluation: the value
//! and its derivative are shared, and each lane holds the first and second derivative along
//! its own direction with their derivatives (no cross derivatives between lanes, which
//! nothing needs): lane k alone is `Dual2<Dual64>`. Sharing the value and every elementary
//! function's derivatives (sin, cos, sqrt, exp once for all lanes), with every part of the
//! lanes a plain array that the compiler vectorises, makes one evaluation of eight lanes
//! cost about 0.6 of the eight one-direction evaluations it replaces (measured on a
//! wire-like energy). Six lanes: in the library's sensitivities as fast as eight on the quad
//! (24 modes, four groups) and faster on the triple (18 modes: three full groups, where
//! eight lanes leave six of a third group idle). The numbers are those of one-direction
//! `Dual2<Dual64>` evaluations up to rounding (the same products, some summed in another
//! order).
//!
//! The arithmetic and every function come from num-dual's own macros (`impl_dual!`,
//! `impl_third_derivatives!`) over a chain rule and a product rule written here once, lane
//! by lane as num-dual's `Dual2<Dual64>` has them.

use std::fmt;
use std::iter::{Product, Sum};
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

use num_dual::{
    Dual64, DualNum, DualNumFloat, DualStruct, chain_rule, first, forward_binop, impl_add_sub_rem,
    impl_assign_ops, impl_comparisons, impl_derivatives, impl_dual, impl_dual_struct,
    impl_float_const, impl_from_f, impl_from_primitive, impl_inv, impl_iterator, impl_neg,
    impl_num, impl_scalar_op, impl_signed, impl_third_derivatives, impl_zero_one, second, third,
    zeroth,
};
use num_traits::{FloatConst, FromPrimitive, Inv, Num, One, Signed, Zero};

use crate::Lift;

/// How many directions a [`TangentLanes`] carries.
pub const LANES: usize = 6;

/// One number per lane, added, subtracted and scaled lane by lane: a lane part of a
/// [`TangentLanes`], with the operations num-dual's macros apply to each part of a dual
/// number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<T>(pub [T; LANES]);

impl<T: Clone> Lanes<T> {
    /// `f` of each lane's number.
    #[inline]
    fn map(&self, f: impl Fn(T) -> T) -> Self {
        Lanes(std::array::from_fn(|k| f(self.0[k].clone())))
    }

    /// `f` of each lane's numbers in `self` and `other`.
    #[inline]
    fn zip(&self, other: &Self, f: impl Fn(T, T) -> T) -> Self {
        Lanes(std::array::from_fn(|k| {
            f(self.0[k].clone(), other.0[k].clone())
        }))
    }
}

impl<T: Zero> Lanes<T> {
    /// Every lane 0.
    #[inline]
    pub fn zero() -> Self {
        Lanes(std::array::from_fn(|_| T::zero()))
    }
}

impl<T: DualNum> Add<&Lanes<T>> for Lanes<T> {
    type Output = Lanes<T>;
    #[inline]
    fn add(self, other: &Lanes<T>) -> Lanes<T> {
        self.zip(other, |a, b| a + b)
    }
}

impl<T: DualNum> Sub<&Lanes<T>> for Lanes<T> {
    type Output = Lanes<T>;
    #[inline]
    fn sub(self, other: &Lanes<T>) -> Lanes<T> {
        self.zip(other, |a, b| a - b)
    }
}

impl<T: DualNum> Neg for Lanes<T> {
    type Output = Lanes<T>;
    #[inline]
    fn neg(self) -> Lanes<T> {
        self.map(|a| -a)
    }
}

impl<T: DualNum> AddAssign for Lanes<T> {
    #[inline]
    fn add_assign(&mut self, other: Lanes<T>) {
        *self = self.zip(&other, |a, b| a + b);
    }
}

impl<T: DualNum> SubAssign for Lanes<T> {
    #[inline]
    fn sub_assign(&mut self, other: Lanes<T>) {
        *self = self.zip(&other, |a, b| a - b);
    }
}

impl<T: DualNum> Mul<&T> for Lanes<T> {
    type Output = Lanes<T>;
    #[inline]
    fn mul(self, factor: &T) -> Lanes<T> {
        self.map(|a| a * factor.clone())
    }
}

impl<T: DualNum> MulAssign<T> for Lanes<T> {
    #[inline]
    fn mul_assign(&mut self, factor: T) {
        *self = self.map(|a| a * factor.clone());
    }
}

impl<T: DualNum> DivAssign<T> for Lanes<T> {
    #[inline]
    fn div_assign(&mut self, divisor: T) {
        *self = self.map(|a| a / divisor.clone());
    }
}

/// A second-order dual number along [`LANES`] directions at once, every part carrying its
/// derivative with respect to one parameter (or coordinate) ε: the value `re` (and `eps`,
/// its derivative), and per lane k the first (`v1[k]`, `v1e[k]`) and second (`v2[k]`,
/// `v2e[k]`) derivative along direction k. Lane k alone is num-dual's `Dual2<Dual64>` with
/// parts (re, eps), (v1, v1e), (v2, v2e); every part a plain number, so that the lanes
/// vectorise and one product is one function. The remainder `%` has no derivative and is
/// not defined (num-dual's macros leave it unimplemented, as for num-dual's own numbers):
/// no energy body uses it.
#[derive(Clone, Copy, Debug)]
pub struct TangentLanes<T> {
    /// The value.
    pub re: T,
    /// The value's derivative with respect to ε.
    pub eps: T,
    /// First derivative along each lane's direction.
    pub v1: Lanes<T>,
    /// Its derivative with respect to ε.
    pub v1e: Lanes<T>,
    /// Second derivative along each lane's direction.
    pub v2: Lanes<T>,
    /// Its derivative with respect to ε.
    pub v2e: Lanes<T>,
}

impl<T> TangentLanes<T> {
    /// The number with these parts.
    #[inline]
    pub fn new(re: T, eps: T, v1: Lanes<T>, v1e: Lanes<T>, v2: Lanes<T>, v2e: Lanes<T>) -> Self {
        TangentLanes {
            re,
            eps,
            v1,
            v1e,
            v2,
            v2e,
        }
    }
}

impl<T: Zero> TangentLanes<T> {
    /// A number without derivatives.
    #[inline]
    pub fn from_re(re: T) -> Self {
        TangentLanes::new(
            re,
            T::zero(),
            Lanes::zero(),
            Lanes::zero(),
            Lanes::zero(),
            Lanes::zero(),
        )
    }
}

// chain rule, lane by lane as num-dual's Dual2<Dual64>, whose f, f', f'' at re + eps·ε are
// (f0, f1·eps), (f1, f2·eps), (f2, f3·eps)
impl<T: DualNum> TangentLanes<T> {
    #[inline]
    fn chain_rule(&self, f0: T, f1: T, f2: T, f3: T) -> Self {
        let e = self.eps.clone();
        let (g1, g2, g3) = (f2.clone() * e.clone(), f3 * e.clone(), f2.clone());
        TangentLanes::new(
            f0,
            f1.clone() * e,
            self.v1.map(|v1| v1 * f1.clone()),
            Lanes(std::array::from_fn(|k| {
                self.v1e.0[k].clone() * f1.clone() + self.v1.0[k].clone() * g1.clone()
            })),
            Lanes(std::array::from_fn(|k| {
                let v1 = self.v1.0[k].clone();
                self.v2.0[k].clone() * f1.clone() + v1.clone() * v1 * g3.clone()
            })),
            Lanes(std::array::from_fn(|k| {
                let (v1, v1e) = (self.v1.0[k].clone(), self.v1e.0[k].clone());
                (self.v2e.0[k].clone() * f1.clone() + self.v2.0[k].clone() * g1.clone())
                    + (v1.clone() * v1e.clone() + v1e * v1.clone()) * g3.clone()
                    + v1.clone() * v1 * g2.clone()
            })),
        )
    }
}

// product rule, lane by lane as num-dual's Dual2<Dual64> (a product's derivatives are sums)
#[allow(clippy::suspicious_arithmetic_impl)]
impl<T: DualNum> Mul<&TangentLanes<T>> for &TangentLanes<T> {
    type Output = TangentLanes<T>;
    #[inline]
    fn mul(self, other: &TangentLanes<T>) -> TangentLanes<T> {
        let (a, b) = (self, other);
        let (ar, ae, br, be) = (a.re.clone(), a.eps.clone(), b.re.clone(), b.eps.clone());
        TangentLanes::new(
            ar.clone() * br.clone(),
            ae.clone() * br.clone() + ar.clone() * be.clone(),
            Lanes(std::array::from_fn(|k| {
                b.v1.0[k].clone() * ar.clone() + a.v1.0[k].clone() * br.clone()
            })),
            Lanes(std::array::from_fn(|k| {
                (b.v1e.0[k].clone() * ar.clone() + b.v1.0[k].clone() * ae.clone())
                    + (a.v1e.0[k].clone() * br.clone() + a.v1.0[k].clone() * be.clone())
            })),
            Lanes(std::array::from_fn(|k| {
                let p = a.v1.0[k].clone() * b.v1.0[k].clone();
                b.v2.0[k].clone() * ar.clone() + p.clone() + p + a.v2.0[k].clone() * br.clone()
            })),
            Lanes(std::array::from_fn(|k| {
                let pe =
                    a.v1e.0[k].clone() * b.v1.0[k].clone() + a.v1.0[k].clone() * b.v1e.0[k].clone();
                (b.v2e.0[k].clone() * ar.clone() + b.v2.0[k].clone() * ae.clone())
                    + pe.clone()
                    + pe
                    + (a.v2e.0[k].clone() * br.clone() + a.v2.0[k].clone() * be.clone())
            })),
        )
    }
}

// quotient rule: the product with the reciprocal (from the chain rule)
#[allow(clippy::suspicious_arithmetic_impl)]
impl<T: DualNum> Div<&TangentLanes<T>> for &TangentLanes<T> {
    type Output = TangentLanes<T>;
    #[inline]
    fn div(self, other: &TangentLanes<T>) -> TangentLanes<T> {
        self * &other.recip()
    }
}

impl<T: DualNum> fmt::Display for TangentLanes<T> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{} + {}ε + {LANES} lanes", self.re, self.eps)
    }
}

impl_third_derivatives!(TangentLanes, [eps, v1, v1e, v2, v2e]);
impl_dual!(TangentLanes, [eps, v1, v1e, v2, v2e]);

/// The scalar of the passes along [`LANES`] modes at once: each lane's second derivative,
/// every part carrying its derivative with respect to one parameter (or coordinate).
/// `cargo bench -p pendkit-benches --bench scalars -- modes-along`: the quad's terms along
/// 24 modes 2.2× faster (median of six runs, 1.8–2.7×) than one mode at a time by the
/// hyper-dual number, and 1.5× (1.2–3.4×) than by `Dual2<Dual64>`, measured before that
/// one-mode path was removed (issue 33).
pub type SecondLanes = TangentLanes<f64>;

/// A coordinate of a pass along [`LANES`] directions: its value `x` (with its derivative),
/// each lane's direction entry `along[k]` and no second-order part.
pub fn second_lanes_seed(x: Dual64, along: [f64; LANES]) -> SecondLanes {
    TangentLanes::new(
        x.re,
        x.eps,
        Lanes(along),
        Lanes::zero(),
        Lanes::zero(),
        Lanes::zero(),
    )
}

/// The seed `x` moved along its own coordinate: its value's derivative set to 1 (the
/// directions' entries do not move with it).
pub fn second_lanes_moving(x: SecondLanes) -> SecondLanes {
    TangentLanes { eps: 1.0, ..x }
}

/// Each lane's second derivative with its derivative: (v2, d v2) per lane.
pub fn second_lanes_parts(value: &SecondLanes) -> [Dual64; LANES] {
    std::array::from_fn(|k| Dual64::new(value.v2.0[k], value.v2e.0[k]))
}

/// The passes along several modes take constants that carry a parameter derivative.
impl Lift<Dual64> for SecondLanes {
    #[inline]
    fn lift(constant: Dual64) -> Self {
        TangentLanes {
            eps: constant.eps,
            ..TangentLanes::from_re(constant.re)
        }
    }
    #[inline]
    fn times(self, constant: Dual64) -> Self {
        // (a + b ε)(c + d ε) = a c + (a d + b c) ε, part by part
        let (c, d) = (constant.re, constant.eps);
        TangentLanes::new(
            self.re * c,
            self.eps * c + self.re * d,
            self.v1.map(|v| v * c),
            self.v1e.zip(&self.v1, |ve, v| ve * c + v * d),
            self.v2.map(|v| v * c),
            self.v2e.zip(&self.v2, |ve, v| ve * c + v * d),
        )
    }
}

#[cfg(test)]
mod tests {
    use num_dual::Dual2;

    use super::*;

    /// A function that uses every kind of operation the energies use.
    fn f<D: DualNum<Primitive = f64> + Copy>(x: D, y: D) -> D {
        let (s, c) = x.sin_cos();
        let r = (x * x + y * y + D::from(0.3)).sqrt();
        (s * y - c / r) * (r * 0.7).exp() + x.powi(3) - y / (x + D::from(2.0)) + r.ln()
            - (-x).tanh()
            + y.atan2(x + D::from(1.5))
    }

    /// Each lane of one lanes evaluation is the `Dual2<Dual64>` evaluation along its own
    /// direction, to rounding (the same products summed in another order).
    #[test]
    fn each_lane_is_the_one_direction_second_derivative_with_its_derivative() {
        let (x, y) = (Dual64::new(0.4, 1.0), Dual64::new(-0.7, 0.25));
        let dirs: [(f64, f64); LANES] = std::array::from_fn(|k| {
            let k = k as f64;
            (0.3 * k - 1.0, 0.5 - 0.2 * k)
        });
        let lanes = f(
            second_lanes_seed(x, dirs.map(|d| d.0)),
            second_lanes_seed(y, dirs.map(|d| d.1)),
        );
        let parts = second_lanes_parts(&lanes);
        for (k, &(u, v)) in dirs.iter().enumerate() {
            let zero = Dual64::from_re(0.0);
            let one = f(
                Dual2::new(x, Dual64::from_re(u), zero),
                Dual2::new(y, Dual64::from_re(v), zero),
            );
            for (got, want) in [(parts[k].re, one.v2.re), (parts[k].eps, one.v2.eps)] {
                assert!(
                    (got - want).abs() <= 1e-14 * want.abs().max(1.0),
                    "lane {k}: {got} against {want}"
                );
            }
            assert!((lanes.re - one.re.re).abs() <= 1e-15 * one.re.re.abs());
            assert!((lanes.v1.0[k] - one.v1.re).abs() <= 1e-14 * one.v1.re.abs().max(1.0));
            assert!((lanes.v1e.0[k] - one.v1.eps).abs() <= 1e-14 * one.v1.eps.abs().max(1.0));
        }
        // a constant with a derivative, lifted and multiplied in, moves the derivative part
        let k = Dual64::new(2.0, 3.0);
        let scaled = parts_of(lanes.times(k));
        let lifted = parts_of(lanes * SecondLanes::lift(k));
        for (a, b) in scaled.iter().zip(&lifted) {
            assert!((a.re - b.re).abs() <= 1e-14 * b.re.abs().max(1.0));
            assert!((a.eps - b.eps).abs() <= 1e-14 * b.eps.abs().max(1.0));
        }
    }

    fn parts_of(value: SecondLanes) -> [Dual64; LANES] {
        second_lanes_parts(&value)
    }
}
