//! The one elimination of the massless floats (docs/physics.md §3), for real matrices (K_eff at
//! f = 0, the modes) and complex ones (K_eff(f), C_XS,eff(f), S_eff(f), the state space)
//! alike: the Schur complement A_kk − A_kq Q⁻¹ A_qk of the float block Q.

use nalgebra::{ComplexField, DMatrix};

/// The Schur complement of the floats over the kept coordinates.
pub(crate) struct Eliminated<T: ComplexField> {
    /// A_kk − A_kq Q⁻¹ A_qk, in the order of `kept` (A_kk alone when Q is singular).
    pub matrix: DMatrix<T>,
    /// When Q is numerically singular (a pivot of its fully pivoted LU at or below 1e-13 of
    /// its largest entry): the position in `floats` of the float with the smallest diagonal
    /// stiffness, the one most likely held by nothing.
    pub singular: Option<usize>,
}

/// Eliminates `floats` from the symmetric matrix whose entry at master rows/columns (i, j)
/// is `entry(i, j)`, keeping `kept` (in that order).
pub(crate) fn eliminate<T: ComplexField<RealField = f64> + Copy>(
    entry: impl Fn(usize, usize) -> T,
    kept: &[usize],
    floats: &[usize],
) -> Eliminated<T> {
    let mut matrix = DMatrix::from_fn(kept.len(), kept.len(), |i, j| entry(kept[i], kept[j]));
    if floats.is_empty() {
        return Eliminated {
            matrix,
            singular: None,
        };
    }
    let q = DMatrix::from_fn(floats.len(), floats.len(), |i, j| {
        entry(floats[i], floats[j])
    });
    let c = DMatrix::from_fn(kept.len(), floats.len(), |i, j| entry(kept[i], floats[j]));
    let lu = q.clone().full_piv_lu();
    let scale = q.iter().fold(0.0f64, |m, x| m.max(x.modulus()));
    let degenerate = !lu.is_invertible()
        || lu
            .u()
            .diagonal()
            .iter()
            .any(|d| d.modulus().is_nan() || d.modulus() <= 1e-13 * scale);
    let weakest = || {
        (0..floats.len())
            .min_by(|&i, &j| q[(i, i)].modulus().total_cmp(&q[(j, j)].modulus()))
            .unwrap_or(0)
    };
    // Q⁻¹ C_QK with C_QK = C_KQᵀ (the matrix is symmetric)
    match lu.solve(&c.transpose()) {
        Some(q_inv_ct) if !degenerate => {
            matrix -= &c * q_inv_ct;
            Eliminated {
                matrix,
                singular: None,
            }
        }
        _ => Eliminated {
            matrix,
            singular: Some(weakest()),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Complex;

    #[test]
    fn toy_float_elimination_real_and_complex() {
        // two springs in series through a float: k1 k2/(k1 + k2) (docs/reference-values.md §8),
        // ordering x, q: [[k2, −k2], [−k2, k1 + k2]]
        let (k1, k2) = (1000.0, 3000.0);
        let p = [[k2, -k2], [-k2, k1 + k2]];
        let real = eliminate(|i, j| p[i][j], &[0], &[1]);
        assert!(real.singular.is_none());
        assert!((real.matrix[(0, 0)] - k1 * k2 / (k1 + k2)).abs() < 1e-12 * k2);
        // loss on k1 only, eliminated on the complex values: k1 (1 + iφ) k2 / (k1 (1 + iφ) + k2)
        let k1c = Complex::new(k1, 1.0);
        let pc = [
            [Complex::new(k2, 0.0), Complex::new(-k2, 0.0)],
            [Complex::new(-k2, 0.0), k1c + k2],
        ];
        let complex = eliminate(|i, j| pc[i][j], &[0], &[1]);
        let expected = k1c * k2 / (k1c + k2);
        assert!((complex.matrix[(0, 0)] - expected).norm() < 1e-12 * k2);
    }

    #[test]
    fn a_float_held_by_nothing_is_reported() {
        // float 2 has no stiffness at all; float 1 is held
        let p = [[1.0, -1.0, 0.0], [-1.0, 2.0, 0.0], [0.0, 0.0, 0.0]];
        let e = eliminate(|i, j| p[i][j], &[0], &[1, 2]);
        assert_eq!(e.singular, Some(1));
    }
}
