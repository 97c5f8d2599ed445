//! Rotation matrices and angular-velocity maps for (yaw, pitch, roll) angles, generic over
//! the dual-number scalar so that the same code gives values, gradients and Hessians; and
//! those scalars' traits, with the dual number that carries several modes at once
//! ([`SecondLanes`]).
//!
//! Convention (docs/conventions.md): R = Rz(yaw) · Ry(pitch) · Rx(roll); a point p given in body
//! coordinates sits at X + R p in space. Angles are in radians.

use nalgebra::{Matrix3, Vector3};
use num_dual::{Dual, Dual64, DualNum, HyperDual};

mod lanes;
pub use lanes::{
    LANES, Lanes, SecondLanes, TangentLanes, second_lanes_moving, second_lanes_parts,
    second_lanes_seed,
};

/// The scalar every generic energy body is written over: `f64` for values, a dual number
/// for derivatives (num-dual 0.15 writes the bound `DualNum<Primitive = f64> + Copy`).
pub trait Real: DualNum<Primitive = f64> + Copy {}
impl<T: DualNum<Primitive = f64> + Copy> Real for T {}

/// Lifts an `f64` constant into the scalar type.
#[inline]
pub fn c<D: Real>(x: f64) -> D {
    D::from(x)
}

/// An evaluation scalar that can take a model constant of type `C`: every [`Real`] takes an
/// `f64` constant (no derivative), and the scalars of the parameter-derivative passes take a
/// `Dual64` constant, whose dual part is the constant's derivative with respect to one
/// parameter (docs/exact-sensitivities.md). Energy bodies whose constants are generic write
/// `D::lift(k)` or `x.times(k)` where they would write `c(k)` or `x * k`.
pub trait Lift<C>: Real {
    /// The constant as a scalar of this type.
    fn lift(constant: C) -> Self;
    /// This scalar times the constant (for `f64` the cheap scalar product).
    fn times(self, constant: C) -> Self;
}

impl<D: Real> Lift<f64> for D {
    #[inline]
    fn lift(constant: f64) -> Self {
        D::from(constant)
    }
    #[inline]
    fn times(self, constant: f64) -> Self {
        self * constant
    }
}

impl Lift<Dual64> for Dual64 {
    #[inline]
    fn lift(constant: Dual64) -> Self {
        constant
    }
    #[inline]
    fn times(self, constant: Dual64) -> Self {
        self * constant
    }
}

/// The scalar of a model's constants: `f64`, or `Dual64` when the model was built with one
/// parameter seeded (each constant carrying its derivative with respect to it).
pub trait Constant: Real + Lift<Self> + Send + Sync + std::fmt::Debug + 'static {
    /// Whether the constant is zero and stays zero as the parameter moves (a term it
    /// multiplies can be skipped).
    fn is_exactly_zero(self) -> bool;
    /// Whether the constant moves with the parameter (a nonzero or NaN derivative): a term
    /// none of whose constants move has no derivative at fixed coordinates, so the exact
    /// sensitivities skip it there.
    fn moves(self) -> bool;
}
impl Constant for f64 {
    fn is_exactly_zero(self) -> bool {
        self == 0.0
    }
    fn moves(self) -> bool {
        false
    }
}
impl Constant for Dual64 {
    fn is_exactly_zero(self) -> bool {
        self.re == 0.0 && self.eps == 0.0
    }
    fn moves(self) -> bool {
        // NaN != 0: a broken derivative counts as moving, so it is never skipped
        self.eps != 0.0
    }
}

/// Whether any of `constants` moves with the parameter ([`Constant::moves`]).
pub fn any_moves<'a, C: Constant>(constants: impl IntoIterator<Item = &'a C>) -> bool {
    constants.into_iter().any(|c| c.moves())
}

/// First derivatives over the coordinates of a function whose constants carry a parameter
/// derivative (the ∂g/∂p pass).
impl Lift<Dual64> for Dual<Dual64> {
    #[inline]
    fn lift(constant: Dual64) -> Self {
        Dual::from_re(constant)
    }
    #[inline]
    fn times(self, constant: Dual64) -> Self {
        Dual::new(self.re * constant, self.eps * constant)
    }
}

/// Second derivatives over the coordinates of a function whose constants carry a parameter
/// derivative (the dK/dp pass).
impl Lift<Dual64> for HyperDual<Dual64> {
    #[inline]
    fn lift(constant: Dual64) -> Self {
        HyperDual::from_re(constant)
    }
    #[inline]
    fn times(self, constant: Dual64) -> Self {
        HyperDual::new(
            self.re * constant,
            self.eps1 * constant,
            self.eps2 * constant,
            self.eps1eps2 * constant,
        )
    }
}

/// Rotation matrix R = Rz(yaw) · Ry(pitch) · Rx(roll) (angles in rad).
pub fn rotation<D: Real>(yaw: D, pitch: D, roll: D) -> Matrix3<D> {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// Value and angle derivatives of R(yaw, pitch, roll) (f64): the first derivatives
/// ∂R/∂θ_m and the second derivatives ∂²R/∂θ_m∂θ_n for θ = (yaw, pitch, roll), the
/// pieces a frame's coordinate derivatives are assembled from by the chain rule.
#[derive(Clone, Copy, Debug)]
pub struct RotationDerivatives {
    /// R itself.
    pub value: Matrix3<f64>,
    /// ∂R/∂θ_m, m = yaw, pitch, roll (per rad).
    pub first: [Matrix3<f64>; 3],
    /// ∂²R/∂θ_m∂θ_n (per rad²), indexed `[m][n]` (symmetric).
    pub second: [[Matrix3<f64>; 3]; 3],
}

/// R as a multilinear form in (1, cos θ, sin θ) of each angle: every entry of
/// R = Rz(yaw) Ry(pitch) Rx(roll) is a sum of products of one of these per angle. Passing
/// (0, −sin θ, cos θ) for an angle (the derivatives of the three) differentiates R with
/// respect to it, and (0, −cos θ, −sin θ) twice.
fn multilinear(y: [f64; 3], p: [f64; 3], r: [f64; 3]) -> Matrix3<f64> {
    Matrix3::new(
        y[1] * p[1] * r[0],
        y[1] * p[2] * r[2] - y[2] * p[0] * r[1],
        y[1] * p[2] * r[1] + y[2] * p[0] * r[2],
        y[2] * p[1] * r[0],
        y[2] * p[2] * r[2] + y[1] * p[0] * r[1],
        y[2] * p[2] * r[1] - y[1] * p[0] * r[2],
        -y[0] * p[2] * r[0],
        y[0] * p[1] * r[2],
        y[0] * p[1] * r[1],
    )
}

/// R = Rz(yaw) Ry(pitch) Rx(roll) and its angle derivatives (first only unless `second`;
/// the second derivatives are zero then), angles in rad.
pub fn rotation_derivatives(yaw: f64, pitch: f64, roll: f64, second: bool) -> RotationDerivatives {
    // per angle: (1, c, s), its derivative and its second derivative
    let trig = |a: f64| {
        let (s, c) = a.sin_cos();
        [[1.0, c, s], [0.0, -s, c], [0.0, -c, -s]]
    };
    let t = [trig(yaw), trig(pitch), trig(roll)];
    // R differentiated `o[k]` times with respect to angle k
    let form = |o: [usize; 3]| multilinear(t[0][o[0]], t[1][o[1]], t[2][o[2]]);
    let unit = |m: usize| std::array::from_fn(|k| usize::from(k == m));
    let first = std::array::from_fn(|m| form(unit(m)));
    let mut out = RotationDerivatives {
        value: form([0, 0, 0]),
        first,
        second: [[Matrix3::zeros(); 3]; 3],
    };
    if second {
        for m in 0..3 {
            for n in m..3 {
                let mut o = unit(m);
                o[n] += 1;
                let d = form(o);
                out.second[m][n] = d;
                out.second[n][m] = d;
            }
        }
    }
    out
}

/// A · B for 3×3 matrices, written out: nalgebra's generic product is not inlined for dual
/// numbers, which made it the largest cost of Hessian evaluation.
#[inline]
pub fn mul<D: Real>(a: &Matrix3<D>, b: &Matrix3<D>) -> Matrix3<D> {
    Matrix3::from_fn(|i, j| a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)])
}

/// Aᵀ · B for 3×3 matrices, written out.
#[inline]
pub fn tr_mul<D: Real>(a: &Matrix3<D>, b: &Matrix3<D>) -> Matrix3<D> {
    Matrix3::from_fn(|i, j| a[(0, i)] * b[(0, j)] + a[(1, i)] * b[(1, j)] + a[(2, i)] * b[(2, j)])
}

/// A · Bᵀ for 3×3 matrices, with B a model constant (see [`Lift`]).
#[inline]
pub fn mul_tr_const<C: Copy, D: Lift<C>>(a: &Matrix3<D>, b: &Matrix3<C>) -> Matrix3<D> {
    Matrix3::from_fn(|i, j| {
        a[(i, 0)].times(b[(j, 0)]) + a[(i, 1)].times(b[(j, 1)]) + a[(i, 2)].times(b[(j, 2)])
    })
}

/// A · B for 3×3 matrices, with B a model constant (see [`Lift`]).
#[inline]
pub fn mul_const<C: Copy, D: Lift<C>>(a: &Matrix3<D>, b: &Matrix3<C>) -> Matrix3<D> {
    Matrix3::from_fn(|i, j| {
        a[(i, 0)].times(b[(0, j)]) + a[(i, 1)].times(b[(1, j)]) + a[(i, 2)].times(b[(2, j)])
    })
}

/// A · v, written out.
#[inline]
pub fn mul_vec<D: Real>(a: &Matrix3<D>, v: &Vector3<D>) -> Vector3<D> {
    Vector3::from_fn(|i, _| a[(i, 0)] * v[0] + a[(i, 1)] * v[1] + a[(i, 2)] * v[2])
}

/// Aᵀ · v, written out.
#[inline]
pub fn tr_mul_vec<D: Real>(a: &Matrix3<D>, v: &Vector3<D>) -> Vector3<D> {
    Vector3::from_fn(|i, _| a[(0, i)] * v[0] + a[(1, i)] * v[1] + a[(2, i)] * v[2])
}

/// A · v with v a model constant (see [`Lift`]): an `f64` vector is not lifted to the
/// scalar type.
#[inline]
pub fn mul_const_vec<C: Copy, D: Lift<C>>(a: &Matrix3<D>, v: &Vector3<C>) -> Vector3<D> {
    Vector3::from_fn(|i, _| a[(i, 0)].times(v[0]) + a[(i, 1)].times(v[1]) + a[(i, 2)].times(v[2]))
}

/// |v|, written out (nalgebra's norm asks for a field trait not every dual number has).
#[inline]
pub fn norm<D: Real>(v: &Vector3<D>) -> D {
    dot(v, v).sqrt()
}

/// u · v, written out.
#[inline]
pub fn dot<D: Real>(u: &Vector3<D>, v: &Vector3<D>) -> D {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

/// Body-frame angular velocity map Ω_B: ω_B = Ω_B · (d yaw, d pitch, d roll)/dt, in rad/s per
/// rad/s. Derived from ω̂_B = Rᵀ Ṙ (tests check it against a numerical derivative of R).
pub fn body_rate_matrix<D: Real>(_yaw: D, pitch: D, roll: D) -> Matrix3<D> {
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let zero = c::<D>(0.0);
    let one = c::<D>(1.0);
    Matrix3::new(-sp, zero, one, cp * sr, cr, zero, cp * cr, -sr, zero)
}

/// Space-frame angular velocity map Ω_S = R · Ω_B: ω_S = Ω_S · (d yaw, d pitch, d roll)/dt
/// (the source's `omegaIS`).
pub fn space_rate_matrix<D: Real>(yaw: D, pitch: D, _roll: D) -> Matrix3<D> {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let zero = c::<D>(0.0);
    let one = c::<D>(1.0);
    Matrix3::new(zero, -sy, cy * cp, zero, cy, sy * cp, one, zero, -sp)
}

/// (yaw, pitch, roll) of a rotation matrix, the inverse of [`rotation`] for
/// |pitch| < π/2 (rad).
pub fn angles<D: Real>(r: &Matrix3<D>) -> [D; 3] {
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    let pitch = (-r[(2, 0)]).atan2((r[(0, 0)] * r[(0, 0)] + r[(1, 0)] * r[(1, 0)]).sqrt());
    let roll = r[(2, 1)].atan2(r[(2, 2)]);
    [yaw, pitch, roll]
}

/// The entries of a rotation matrix that [`angles`] reads: (0,0), (1,0), (2,0), (2,1), (2,2).
pub const ANGLE_ENTRIES: [(usize, usize); 5] = [(0, 0), (1, 0), (2, 0), (2, 1), (2, 2)];

/// First and second derivatives of (yaw, pitch, roll) = [`angles`]`(M)` with respect to the
/// five entries of M it reads ([`ANGLE_ENTRIES`]), in closed form.
#[derive(Clone, Copy, Debug)]
pub struct AngleDerivatives {
    /// `gradient[k][e]` = ∂angle_k/∂M_e.
    pub gradient: [[f64; 5]; 3],
    /// `hessian[k][e][f]` = ∂²angle_k/∂M_e∂M_f.
    pub hessian: [[[f64; 5]; 5]; 3],
}

/// Gradient (∂/∂y, ∂/∂x) and Hessian (yy, xx, xy) of atan2(y, x).
fn atan2_derivatives(y: f64, x: f64) -> ([f64; 2], [f64; 3]) {
    let r2 = x * x + y * y;
    let r4 = r2 * r2;
    (
        [x / r2, -y / r2],
        [-2.0 * x * y / r4, 2.0 * x * y / r4, (y * y - x * x) / r4],
    )
}

/// The derivatives of [`angles`] at M (|pitch| < π/2): yaw = atan2(M10, M00),
/// pitch = atan2(−M20, b) with b = sqrt(M00² + M10²), roll = atan2(M21, M22).
pub fn angle_derivatives(m: &Matrix3<f64>) -> AngleDerivatives {
    let mut d = AngleDerivatives {
        gradient: [[0.0; 5]; 3],
        hessian: [[[0.0; 5]; 5]; 3],
    };
    let (m00, m10, m20, m21, m22) = (m[(0, 0)], m[(1, 0)], m[(2, 0)], m[(2, 1)], m[(2, 2)]);
    // yaw and roll: atan2 of two entries each (entry indices of y and x)
    for (k, (y, x), (ey, ex)) in [(0, (m10, m00), (1, 0)), (2, (m21, m22), (3, 4))] {
        let ([gy, gx], [hyy, hxx, hxy]) = atan2_derivatives(y, x);
        d.gradient[k][ey] = gy;
        d.gradient[k][ex] = gx;
        d.hessian[k][ey][ey] = hyy;
        d.hessian[k][ex][ex] = hxx;
        d.hessian[k][ey][ex] = hxy;
        d.hessian[k][ex][ey] = hxy;
    }
    // pitch = atan2(a, b), a = −M20, b = sqrt(M00² + M10²)
    let b = (m00 * m00 + m10 * m10).sqrt();
    let ([pa, pb], [paa, pbb, pab]) = atan2_derivatives(-m20, b);
    let db = [m00 / b, m10 / b];
    let b3 = b * b * b;
    let ddb = [
        [m10 * m10 / b3, -m00 * m10 / b3],
        [-m00 * m10 / b3, m00 * m00 / b3],
    ];
    for e in 0..2 {
        d.gradient[1][e] = pb * db[e];
        for f in 0..2 {
            d.hessian[1][e][f] = pbb * db[e] * db[f] + pb * ddb[e][f];
        }
        // a = −M20 (entry 2): ∂a/∂M20 = −1
        d.hessian[1][2][e] = -pab * db[e];
        d.hessian[1][e][2] = -pab * db[e];
    }
    d.gradient[1][2] = -pa;
    d.hessian[1][2][2] = paa;
    d
}

/// The vector of a skew-symmetric matrix: vee(\[ω\]×) = ω.
pub fn vee<D: Real>(m: &Matrix3<D>) -> Vector3<D> {
    let half = 0.5;
    Vector3::new(
        (m[(2, 1)] - m[(1, 2)]) * half,
        (m[(0, 2)] - m[(2, 0)]) * half,
        (m[(1, 0)] - m[(0, 1)]) * half,
    )
}

/// Small-rotation vector (rad) of a rotation that is close to the identity: the axis times
/// the sine of the angle, exact to first order (used for twists and lab-frame rotations).
pub fn small_rotation<D: Real>(r: &Matrix3<D>) -> Vector3<D> {
    vee(r)
}

/// Reorders a space-frame rotation vector (about x, y, z) into the lab "yaw, pitch, roll"
/// order (about z, y, x), the source's `omegaSNI` permutation.
pub fn lab_yaw_pitch_roll<D: Real>(omega_space: &Vector3<D>) -> [D; 3] {
    [omega_space[2], omega_space[1], omega_space[0]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn max_abs(m: &Matrix3<f64>) -> f64 {
        m.iter().fold(0.0, |a, &b| a.max(b.abs()))
    }

    #[test]
    fn single_axis_rotations_follow_the_right_hand_rule() {
        // yaw turns x towards y; pitch turns z towards x; roll turns y towards z.
        let q = std::f64::consts::FRAC_PI_2;
        let x = Vector3::x();
        let z = Vector3::z();
        let y = Vector3::y();
        assert!((rotation(q, 0.0, 0.0) * x - y).norm() < 1e-15);
        assert!((rotation(0.0, q, 0.0) * z - x).norm() < 1e-15);
        assert!((rotation(0.0, 0.0, q) * y - z).norm() < 1e-15);
    }

    proptest! {
        #[test]
        fn rotation_is_orthogonal(y in -3.1..3.1f64, p in -1.5..1.5f64, r in -3.1..3.1f64) {
            let m = rotation(y, p, r);
            prop_assert!(max_abs(&(m.transpose() * m - Matrix3::identity())) < 1e-14);
            prop_assert!((m.determinant() - 1.0).abs() < 1e-14);
        }

        #[test]
        fn angles_round_trip(y in -3.1..3.1f64, p in -1.5..1.5f64, r in -3.1..3.1f64) {
            let [y2, p2, r2] = angles(&rotation(y, p, r));
            prop_assert!((y - y2).abs() < 1e-12);
            prop_assert!((p - p2).abs() < 1e-12);
            prop_assert!((r - r2).abs() < 1e-12);
        }

        #[test]
        fn body_rate_matches_numerical_derivative(
            y in -3.0..3.0f64, p in -1.4..1.4f64, r in -3.0..3.0f64,
            dy in -1.0..1.0f64, dp in -1.0..1.0f64, dr in -1.0..1.0f64,
        ) {
            // ω̂_B = Rᵀ Ṙ with Ṙ from a central difference along (dy, dp, dr).
            let h = 1e-6;
            let rp = rotation(y + h * dy, p + h * dp, r + h * dr);
            let rm = rotation(y - h * dy, p - h * dp, r - h * dr);
            let rdot = (rp - rm) / (2.0 * h);
            let rot = rotation(y, p, r);
            let omega_hat = rot.transpose() * rdot;
            let rate = Vector3::new(dy, dp, dr);
            let omega_b = body_rate_matrix(y, p, r) * rate;
            prop_assert!((vee(&omega_hat) - omega_b).norm() < 1e-8);
            // skew-symmetry of Rᵀ Ṙ (consistency of the numerical derivative itself)
            prop_assert!(max_abs(&(omega_hat + omega_hat.transpose())) < 1e-8);
            let omega_s = space_rate_matrix(y, p, r) * rate;
            prop_assert!((vee(&(rdot * rot.transpose())) - omega_s).norm() < 1e-8);
        }

        #[test]
        fn small_rotation_is_first_order_exact(a in -1.0..1.0f64, b in -1.0..1.0f64, cc in -1.0..1.0f64) {
            let eps = 1e-7;
            let m = rotation(eps * a, eps * b, eps * cc);
            let v = small_rotation(&m);
            let [yaw, pitch, roll] = lab_yaw_pitch_roll(&v);
            prop_assert!((yaw - eps * a).abs() < 1e-13);
            prop_assert!((pitch - eps * b).abs() < 1e-13);
            prop_assert!((roll - eps * cc).abs() < 1e-13);
        }
    }

    #[test]
    fn rotation_derivatives_match_hyper_duals() {
        // every first and second angle derivative against a hyper-dual evaluation of R
        use num_dual::HyperDual64;
        let angles = [0.3, -0.4, 0.7];
        let d = rotation_derivatives(angles[0], angles[1], angles[2], true);
        let f = rotation_derivatives(angles[0], angles[1], angles[2], false);
        assert_eq!(d.first, f.first);
        assert!(max_abs(&(d.value - rotation(angles[0], angles[1], angles[2]))) < 1e-15);
        for m in 0..3 {
            for n in 0..3 {
                let a: [HyperDual64; 3] = std::array::from_fn(|k| {
                    let e1 = if k == m { 1.0 } else { 0.0 };
                    let e2 = if k == n { 1.0 } else { 0.0 };
                    HyperDual64::new(angles[k], e1, e2, 0.0)
                });
                let r = rotation(a[0], a[1], a[2]);
                assert!(max_abs(&(r.map(|e| e.eps1) - d.first[m])) < 1e-15);
                assert!(max_abs(&(r.map(|e| e.eps1eps2) - d.second[m][n])) < 1e-15);
            }
        }
    }

    #[test]
    fn angle_derivatives_match_hyper_duals() {
        // the closed form against hyper-dual evaluation of `angles` itself, on a rotation
        // times a general matrix (off the rotation group, as the chain rule needs)
        use num_dual::HyperDual64;
        let m =
            rotation(0.4, -0.3, 0.9) * Matrix3::new(1.1, 0.1, -0.2, 0.05, 0.9, 0.3, -0.1, 0.2, 1.2);
        let d = angle_derivatives(&m);
        for e in 0..5 {
            for f in 0..5 {
                let mut md = m.map(HyperDual64::from_re);
                md[ANGLE_ENTRIES[e]].eps1 = 1.0;
                md[ANGLE_ENTRIES[f]].eps2 = 1.0;
                for (k, a) in angles(&md).iter().enumerate() {
                    assert!((a.eps1 - d.gradient[k][e]).abs() < 1e-14, "{k} {e}");
                    assert!(
                        (a.eps1eps2 - d.hessian[k][e][f]).abs() < 1e-13,
                        "{k} {e} {f}"
                    );
                }
            }
        }
    }

    #[test]
    fn written_out_products_match_nalgebra() {
        let a = rotation(0.1, 0.2, 0.3) * 1.5;
        let b = rotation(-0.7, 0.4, 1.1) + Matrix3::identity();
        let v = Vector3::new(0.3, -1.0, 2.0);
        assert!(max_abs(&(mul(&a, &b) - a * b)) < 1e-15);
        assert!(max_abs(&(tr_mul(&a, &b) - a.transpose() * b)) < 1e-15);
        assert!(max_abs(&(mul_tr_const(&a, &b) - a * b.transpose())) < 1e-15);
        assert!(max_abs(&(mul_const(&a, &b) - a * b)) < 1e-15);
        assert!((mul_vec(&a, &v) - a * v).norm() < 1e-15);
        assert!((mul_const_vec(&a, &v) - a * v).norm() < 1e-15);
        assert!((tr_mul_vec(&a, &v) - a.transpose() * v).norm() < 1e-15);
        assert!((dot(&v, &v) - v.norm_squared()).abs() < 1e-15);
    }

    #[test]
    fn generic_over_dual_numbers() {
        use num_dual::Dual64;
        // d/dyaw of R(yaw, 0, 0) at 0 is the generator of rotations about z.
        let m = rotation(Dual64::new(0.0, 1.0), Dual64::from(0.0), Dual64::from(0.0));
        let d = m.map(|e| e.eps);
        let expected = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(max_abs(&(d - expected)) < 1e-15);
    }
}
