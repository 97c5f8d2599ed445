//! One uniform piece of a fibre, and a chain of pieces, in one dimension: the exact
//! dynamic stiffness of a tensioned beam (4×4 over w, w′ at both ends) and of a wave
//! (2×2 over the axial or twist displacement at both ends).
//!
//! Each piece's matrix is D = F B⁻¹ over a basis of exact solutions written so that no
//! entry grows with the piece's length: cos kx and sin(kx)/k (analytic in k², so the
//! static limit k → 0 is the same formula), and the decaying exponentials e^(−κx) and
//! e^(−κ(L−x)) of the bending boundary layers at both ends. A product of transfer matrices
//! (the textbook route) multiplies e^(+κL) ≈ 1e270 for a silica fibre by numbers of order
//! one and keeps no digit; chaining dynamic stiffnesses by eliminating the joints between
//! pieces (one small Schur complement per joint) is the same algebra without that growth.

use nalgebra::{Complex, ComplexField, Const, DimMin, Matrix2, Matrix4, SMatrix, Vector4};

/// A complex number of f64.
pub type C64 = Complex<f64>;

/// A two-node stiffness in N × N blocks [[D₀₀, D₀₁], [D₁₀, D₁₁]] (N values per node: 1 for
/// a wave, 2 for a beam): fixed-size, so a piece and a chain allocate nothing per frequency.
pub(crate) type Blocks<const N: usize> = [[SMatrix<C64, N, N>; 2]; 2];

/// (cos(√z x), sin(√z x)/√z) for complex z: both are entire in z, so near z = 0 (the static
/// limit) they come from their series instead of dividing by √z.
pub(crate) fn cos_sinc(z: C64, x: f64) -> (C64, C64) {
    let k = z.sqrt();
    if (k * x).norm() < 1e-3 {
        // |z x²| < 1e-6: the first omitted terms are below 1e-27 relative
        let y = z * (x * x);
        let c = C64::from(1.0) - y / 2.0 + y * y / 24.0 - y * y * y / 720.0;
        let s = (C64::from(1.0) - y / 6.0 + y * y / 120.0 - y * y * y / 5040.0) * x;
        (c, s)
    } else {
        let kx = k * x;
        (kx.cos(), kx.sin() / k)
    }
}

/// Dynamic stiffness (N/m) of a uniform wave piece of length `len` (m), stiffness `c`
/// (N, or N m² for torsion; complex for loss) and inertia `m` per length (kg/m, or kg m),
/// at angular frequency `omega` (rad/s): u″ c + m ω² u = 0, over (u(0), u(L)), the
/// generalised forces on the piece being (−c u′(0), c u′(L)).
pub(crate) fn wave_piece(c: C64, m: f64, omega: f64, len: f64) -> Blocks<1> {
    // u = a cos βx + b sin(βx)/β with β² = m ω²/c: a = u0, b = (u1 − u0 cos βL)/S; then
    // D = (c/S) [[cos βL, −1], [−1, cos βL]] (cos² + β² S² = 1 gives the symmetry)
    let (co, s) = cos_sinc(c.powi(-1) * (m * omega * omega), len);
    let f = c / s;
    let (diagonal, cross) = (SMatrix::from_element(f * co), SMatrix::from_element(-f));
    [[diagonal, cross], [cross, diagonal]]
}

/// Dynamic stiffness of a uniform beam piece of length `len` (m), bending stiffness `ei`
/// (N m², complex for loss), static tension `tension` (N, positive) and linear density
/// `mu` (kg/m) at angular frequency `omega` (rad/s), over (w(0), w′(0), w(L), w′(L)):
/// EI w⁗ − T w″ − μ ω² w = 0, with the generalised forces (work-conjugate to those four)
/// (EI w‴ − T w′, −EI w″) at 0 and (−EI w‴ + T w′, EI w″) at L.
pub(crate) fn beam_piece(ei: C64, tension: f64, mu: f64, omega: f64, len: f64) -> Blocks<2> {
    // e^(λx) with EI λ⁴ − T λ² − μω² = 0: λ² = κ² = (T + s)/(2EI) (the boundary layers) or
    // λ² = −k² with k² = (s − T)/(2EI) = 2μω²/(s + T) (the waves; this form has no
    // cancellation at low frequency), s = √(T² + 4 EI μ ω²)
    let w2 = mu * omega * omega;
    let s = (C64::from(tension * tension) + ei * (4.0 * w2)).sqrt();
    let kappa2 = (s + tension) / (ei * 2.0);
    let k2 = (s + tension).powi(-1) * (2.0 * w2);
    let kappa = kappa2.sqrt();
    let (co, sn) = cos_sinc(k2, len);
    let e = (-kappa * len).exp();
    let one = C64::from(1.0);
    let zero = C64::from(0.0);
    // value and first three derivatives of each basis function at 0 and at L:
    // cos kx, sin(kx)/k, e^(−κx), e^(−κ(L−x))
    let layer = |sign: f64| Vector4::new(one, kappa * sign, kappa2, kappa2 * kappa * sign);
    let at0 = [
        Vector4::new(one, zero, -k2, zero),
        Vector4::new(zero, one, zero, -k2),
        layer(-1.0),
        layer(1.0) * e,
    ];
    let at_l = [
        Vector4::new(co, -k2 * sn, -k2 * co, k2 * k2 * sn),
        Vector4::new(sn, co, -k2 * sn, -k2 * co),
        layer(-1.0) * e,
        layer(1.0),
    ];
    let mut b = Matrix4::<C64>::zeros();
    let mut f = Matrix4::<C64>::zeros();
    for j in 0..4 {
        let (p, q) = (at0[j], at_l[j]);
        b[(0, j)] = p[0];
        b[(1, j)] = p[1];
        b[(2, j)] = q[0];
        b[(3, j)] = q[1];
        f[(0, j)] = ei * p[3] - p[1] * tension;
        f[(1, j)] = -ei * p[2];
        f[(2, j)] = -ei * q[3] + q[1] * tension;
        f[(3, j)] = ei * q[2];
    }
    // D = F B⁻¹, i.e. Bᵀ Dᵀ = Fᵀ; at a clamped–clamped resonance B is singular and the
    // entries are infinite, which is what the physics says
    let d = match b.transpose().lu().solve(&f.transpose()) {
        Some(dt) => dt.transpose(),
        None => Matrix4::from_element(C64::new(f64::INFINITY, 0.0)),
    };
    split(&d)
}

/// The 2 × 2 blocks of a 4 × 4 beam matrix.
pub(crate) fn split(d: &Matrix4<C64>) -> Blocks<2> {
    let b = |i: usize, j: usize| d.fixed_view::<2, 2>(2 * i, 2 * j).into_owned();
    [[b(0, 0), b(0, 1)], [b(1, 0), b(1, 1)]]
}

/// The 4 × 4 beam matrix of its 2 × 2 blocks.
pub(crate) fn join(b: &Blocks<2>) -> Matrix4<C64> {
    Matrix4::from_fn(|i, j| b[i / 2][j / 2][(i % 2, j % 2)])
}

/// The 2 × 2 wave matrix of its 1 × 1 blocks.
pub(crate) fn join_wave(b: &Blocks<1>) -> Matrix2<C64> {
    Matrix2::from_fn(|i, j| b[i][j][(0, 0)])
}

/// The dynamic stiffness between the two ends of a chain of pieces, each over
/// (node values at its start, node values at its end) with N values per node:
/// the joints between pieces carry no external force, so each is eliminated by a Schur
/// complement as the chain grows.
pub(crate) fn chain<const N: usize>(pieces: impl IntoIterator<Item = Blocks<N>>) -> Blocks<N>
where
    Const<N>: DimMin<Const<N>, Output = Const<N>>,
{
    let mut pieces = pieces.into_iter();
    let Some(mut run) = pieces.next() else {
        return [[SMatrix::zeros(); 2]; 2];
    };
    for [[p00, p01], [p10, p11]] in pieces {
        // nodes: 0 (kept), j (the joint), next (kept)
        let [[a00, a0j], [aj0, ajj]] = run;
        let lu = (ajj + p00).lu();
        let solve = |m: &SMatrix<C64, N, N>| {
            lu.solve(m)
                .unwrap_or_else(|| SMatrix::from_element(C64::new(f64::NAN, 0.0)))
        };
        let (x_a, x_p) = (solve(&aj0), solve(&p01));
        run = [
            [a00 - a0j * x_a, -(a0j * x_p)],
            [-(p10 * x_a), p11 - p10 * x_p],
        ];
    }
    run
}

/// `m` with its value `k` eliminated (no external force on it) and its row and column left
/// zero: a hinged end's slope.
pub(crate) fn condense(m: &Matrix4<C64>, k: usize) -> Matrix4<C64> {
    let pivot = m[(k, k)];
    Matrix4::from_fn(|a, b| {
        if a == k || b == k {
            C64::new(0.0, 0.0)
        } else {
            m[(a, b)] - m[(a, k)] * m[(k, b)] / pivot
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A piece cut in two and chained gives the piece: the joint elimination is exact.
    /// Tolerance 1e-10 relative: both sides are exact solutions, evaluated with a few
    /// hundred operations on numbers of condition ~κL ≈ 50.
    #[test]
    fn halves_chain_to_the_whole() {
        let (ei, t, mu, l) = (C64::new(1e-4, 1e-8), 100.0, 3e-4, 0.5);
        for omega in [0.0, 300.0, 3000.0, 20000.0] {
            let whole = join(&beam_piece(ei, t, mu, omega, l));
            let halves = join(&chain([
                beam_piece(ei, t, mu, omega, l / 2.0),
                beam_piece(ei, t, mu, omega, l / 2.0),
            ]));
            let scale = whole.iter().map(|z| z.norm()).fold(0.0, f64::max);
            assert!(
                (whole - halves).iter().all(|z| z.norm() < 1e-10 * scale),
                "{omega}: {whole} {halves}"
            );
            let c = C64::new(7e3, 1e-3);
            let whole = join_wave(&wave_piece(c, 0.3, omega, l));
            let halves = join_wave(&chain([
                wave_piece(c, 0.3, omega, 0.2),
                wave_piece(c, 0.3, omega, 0.3),
            ]));
            assert!(
                (whole - halves)
                    .iter()
                    .all(|z| z.norm() < 1e-10 * whole[(0, 0)].norm())
            );
        }
    }
}
