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

/// The groups of `n` items that `coupled(i, j)` (symmetric) joins, directly or through
/// others: the connected components, each ascending, in order of their first item. The
/// float block of a suspension falls apart into such groups (each fibre's bead joints, each
/// blade's tip), and each group is eliminated on its own: exact zeros skipped, the same
/// Schur complement at a fraction of the dense cost.
pub(crate) fn components(n: usize, coupled: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..n {
        for j in i + 1..n {
            if coupled(i, j) {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of_root = vec![usize::MAX; n];
    for i in 0..n {
        let r = root(&mut parent, i);
        if group_of_root[r] == usize::MAX {
            group_of_root[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of_root[r]].push(i);
    }
    groups
}

/// Eliminates `floats` from the symmetric matrix whose entry at master rows/columns (i, j)
/// is `entry(i, j)`, keeping `kept` (in that order): group by group over the float block's
/// connected components ([`components`]), each group with a fully pivoted LU of its block
/// and only the kept rows it couples to.
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
    let zero = T::zero();
    let scale = floats.iter().fold(0.0f64, |m, &i| {
        floats.iter().fold(m, |m, &j| m.max(entry(i, j).modulus()))
    });
    // each group: its floats, the kept rows it couples to, and Q_g⁻¹ C_g,kept
    let mut updates = Vec::new();
    for group in components(floats.len(), |i, j| entry(floats[i], floats[j]) != zero) {
        let q = DMatrix::from_fn(group.len(), group.len(), |i, j| {
            entry(floats[group[i]], floats[group[j]])
        });
        let rows: Vec<usize> = (0..kept.len())
            .filter(|&k| group.iter().any(|&f| entry(kept[k], floats[f]) != zero))
            .collect();
        let lu = q.clone().full_piv_lu();
        let degenerate = !lu.is_invertible()
            || lu
                .u()
                .diagonal()
                .iter()
                .any(|d| d.modulus().is_nan() || d.modulus() <= 1e-13 * scale);
        // Q⁻¹ C_QK with C_QK = C_KQᵀ (the matrix is symmetric)
        let c = DMatrix::from_fn(rows.len(), group.len(), |i, j| {
            entry(kept[rows[i]], floats[group[j]])
        });
        match lu.solve(&c.transpose()) {
            Some(q_inv_ct) if !degenerate => updates.push((rows, &c * q_inv_ct)),
            _ => {
                // the float with the smallest diagonal stiffness, the one most likely held
                // by nothing
                let weakest = (0..group.len())
                    .min_by(|&i, &j| q[(i, i)].modulus().total_cmp(&q[(j, j)].modulus()))
                    .map_or(0, |k| group[k]);
                return Eliminated {
                    matrix,
                    singular: Some(weakest),
                };
            }
        }
    }
    for (rows, update) in updates {
        for (a, &ra) in rows.iter().enumerate() {
            for (b, &rb) in rows.iter().enumerate() {
                matrix[(ra, rb)] -= update[(a, b)];
            }
        }
    }
    Eliminated {
        matrix,
        singular: None,
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
    fn groups_are_eliminated_as_the_whole_block_would_be() {
        // kept 0, 1; floats 2, 3 coupled to each other and to 0, float 4 alone coupled to
        // 1: the grouped elimination equals the dense Schur complement A − C Q⁻¹ Cᵀ
        let p = [
            [5.0, 0.5, -1.0, 0.0, 0.0],
            [0.5, 6.0, 0.0, 0.0, -2.0],
            [-1.0, 0.0, 4.0, -1.0, 0.0],
            [0.0, 0.0, -1.0, 3.0, 0.0],
            [0.0, -2.0, 0.0, 0.0, 7.0],
        ];
        assert_eq!(
            components(3, |i, j| p[2 + i][2 + j] != 0.0),
            vec![vec![0, 1], vec![2]]
        );
        let e = eliminate(|i, j| p[i][j], &[0, 1], &[2, 3, 4]);
        assert!(e.singular.is_none());
        // by hand: Q₁ = [[4, −1], [−1, 3]], Q₁⁻¹ = [[3, 1], [1, 4]]/11, couples row 0 by −1
        // on float 2: 5 − 3/11; float 4 on row 1: 6 − 4/7
        assert!((e.matrix[(0, 0)] - (5.0 - 3.0 / 11.0)).abs() < 1e-14);
        assert!((e.matrix[(1, 1)] - (6.0 - 4.0 / 7.0)).abs() < 1e-14);
        assert_eq!(e.matrix[(0, 1)], 0.5);
    }

    #[test]
    fn a_float_held_by_nothing_is_reported() {
        // float 2 has no stiffness at all; float 1 is held
        let p = [[1.0, -1.0, 0.0], [-1.0, 2.0, 0.0], [0.0, 0.0, 0.0]];
        let e = eliminate(|i, j| p[i][j], &[0], &[1, 2]);
        assert_eq!(e.singular, Some(1));
    }
}
