//! Normal modes: the generalised symmetric eigenproblem K_eff v = ω² M v, solved block by
//! block over the exactly decoupled blocks of K_eff and M (their exact zeros: the quad's
//! x–pitch, y–z–roll and yaw blocks, or the identical stages of a chain), with labels, the
//! kinetic-energy fractions, and a lab-frame table of body motions.

use faer::{Mat, Side};
use nalgebra::{DMatrix, Vector3};
use pendkit_assembly::Layout;
use pendkit_energy::{CoordKind, System};
use pendkit_rotations::lab_yaw_pitch_roll;

use crate::DynamicsError;
use crate::pattern::dense_components;

/// One normal mode.
#[derive(Clone, Debug)]
pub struct Mode {
    /// Eigenvalue ω² (rad²/s²); negative for an unstable mode.
    pub omega_squared: f64,
    /// Frequency (Hz); for an unstable mode, minus the growth rate sqrt(-ω²)/2π.
    pub hz: f64,
    /// Dominant coordinate by kinetic-energy fraction.
    pub label: String,
    /// Mass-normalised eigenvector over the variables (vᵀ M v = 1).
    pub vector: Vec<f64>,
    /// Kinetic-energy fraction per variable, v_i (M v)_i (sums to 1).
    pub energy_fractions: Vec<f64>,
}

impl Mode {
    /// Whether ω² ≥ 0 (zero-frequency neutral modes count as stable).
    pub fn is_stable(&self) -> bool {
        self.omega_squared >= 0.0
    }

    /// A mode from its eigenvalue ω² (rad²/s²) and an eigenvector `u` (any scale) over the
    /// variables: normalised to uᵀ M u = 1 with `mass_times` = M u, labelled by the largest
    /// kinetic-energy fraction.
    pub(crate) fn from_vector(
        omega_squared: f64,
        u: &[f64],
        mass_times: &[f64],
        names: &[String],
    ) -> Mode {
        let norm2: f64 = u.iter().zip(mass_times).map(|(a, b)| a * b).sum();
        let scale = 1.0 / norm2.sqrt();
        let vector: Vec<f64> = u.iter().map(|x| x * scale).collect();
        let energy_fractions: Vec<f64> = u
            .iter()
            .zip(mass_times)
            .map(|(a, b)| a * b / norm2)
            .collect();
        let dominant = (0..u.len())
            .max_by(|&i, &j| energy_fractions[i].total_cmp(&energy_fractions[j]))
            .unwrap_or(0);
        let hz = omega_squared.signum() * omega_squared.abs().sqrt() / (2.0 * std::f64::consts::PI);
        Mode {
            omega_squared,
            hz,
            label: names.get(dominant).cloned().unwrap_or_default(),
            vector,
            energy_fractions,
        }
    }
}

/// All normal modes of a stage (or those asked for), ascending in frequency.
#[derive(Clone, Debug)]
pub struct Modes {
    /// Variable names, the order of every mode vector.
    pub coordinates: Vec<String>,
    /// The modes, ascending in ω².
    pub modes: Vec<Mode>,
}

impl Modes {
    /// An error describing the first unstable mode, if any.
    pub fn check_stable(&self) -> Result<(), DynamicsError> {
        match self.modes.iter().position(|m| !m.is_stable()) {
            None => Ok(()),
            Some(i) => {
                let m = &self.modes[i];
                let k = self
                    .coordinates
                    .iter()
                    .position(|c| *c == m.label)
                    .unwrap_or(0);
                Err(DynamicsError::Unstable {
                    index: i + 1,
                    rate_hz: -m.hz,
                    label: m.label.clone(),
                    fraction: 100.0 * m.energy_fractions.get(k).copied().unwrap_or(0.0),
                })
            }
        }
    }
}

/// The non-zero entries of a matrix by column, to multiply it into many vectors at the
/// cost of its non-zeros (mass matrices are block diagonal: one 6 × 6 block per body).
pub(crate) struct SparseColumns {
    entries: Vec<Vec<(usize, f64)>>,
}

impl SparseColumns {
    pub(crate) fn new(n: usize, entry: impl Fn(usize, usize) -> f64) -> Self {
        SparseColumns {
            entries: (0..n)
                .map(|j| {
                    (0..n)
                        .filter_map(|i| {
                            let v = entry(i, j);
                            (v != 0.0).then_some((i, v))
                        })
                        .collect()
                })
                .collect(),
        }
    }

    /// A x.
    pub(crate) fn times(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.entries.len()];
        for (column, &xj) in self.entries.iter().zip(x) {
            if xj != 0.0 {
                for &(i, v) in column {
                    y[i] += v * xj;
                }
            }
        }
        y
    }
}

/// A lower-triangular Cholesky factor L stored by columns down to each column's last
/// non-zero (its envelope). The factor of a banded matrix is banded (a chain's blocks
/// couple each stage to its neighbours only), and triangular solves that stop each column
/// at its last non-zero skip only exact zeros: the same values up to the order of the sums,
/// at about n² b instead of n³ operations for n right-hand sides and bandwidth b.
struct Envelope {
    /// Column k of L from the diagonal down to its last non-zero.
    columns: Vec<Vec<f64>>,
}

impl Envelope {
    fn new(l: faer::MatRef<'_, f64>) -> Self {
        let n = l.nrows();
        let columns = (0..n)
            .map(|k| {
                let end = (k + 1..n)
                    .rev()
                    .find(|&i| l[(i, k)] != 0.0)
                    .map_or(k + 1, |i| i + 1);
                (k..end).map(|i| l[(i, k)]).collect()
            })
            .collect();
        Envelope { columns }
    }

    /// Whether the envelope holds so few entries that the skyline solves beat the blocked
    /// dense ones (an eighth of the lower triangle: dense blocks keep faer's kernels).
    fn is_narrow(&self) -> bool {
        let n = self.columns.len();
        let stored: usize = self.columns.iter().map(Vec::len).sum();
        8 * stored < n * n
    }

    /// x ← L⁻¹ x for every column of x, column-oriented (zeros of x skipped).
    fn solve_lower(&self, x: &mut Mat<f64>) {
        for c in 0..x.ncols() {
            let x = x.col_as_slice_mut(c);
            for (k, column) in self.columns.iter().enumerate() {
                if x[k] == 0.0 {
                    continue;
                }
                let xk = x[k] / column[0];
                x[k] = xk;
                for (xi, &lik) in x[k + 1..].iter_mut().zip(&column[1..]) {
                    *xi -= lik * xk;
                }
            }
        }
    }

    /// x ← L⁻ᵀ x for every column of x (back substitution by dot products over the columns
    /// of L).
    fn solve_upper_transposed(&self, x: &mut Mat<f64>) {
        for c in 0..x.ncols() {
            let x = x.col_as_slice_mut(c);
            for (k, column) in self.columns.iter().enumerate().rev() {
                let below: f64 = x[k + 1..]
                    .iter()
                    .zip(&column[1..])
                    .map(|(xi, lik)| lik * xi)
                    .sum();
                x[k] = (x[k] - below) / column[0];
            }
        }
    }
}

/// Eigenpairs of the pencil (A, B) by Cholesky reduction of B: C = L⁻¹ A L⁻ᵀ, eigenvalues
/// ascending, vectors L⁻ᵀ u (B-orthonormal). The triangular solves follow L's envelope
/// when it is narrow (banded blocks), faer's blocked kernels otherwise.
fn reduced_eigen(
    a: &Mat<f64>,
    b_llt: &faer::linalg::solvers::Llt<f64>,
) -> Result<(Vec<f64>, Mat<f64>), DynamicsError> {
    let n = a.nrows();
    let l = b_llt.L();
    let envelope = Envelope::new(l);
    let narrow = envelope.is_narrow();
    let solve_lower = |x: &mut Mat<f64>| {
        if narrow {
            envelope.solve_lower(x);
        } else {
            l.solve_lower_triangular_in_place(x.as_mut());
        }
    };
    let mut x = a.clone();
    solve_lower(&mut x);
    let mut c = x.transpose().to_owned();
    solve_lower(&mut c);
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| DynamicsError::Eigen(format!("{e:?}")))?;
    let mut v = evd.U().to_owned();
    if narrow {
        envelope.solve_upper_transposed(&mut v);
    } else {
        l.transpose().solve_upper_triangular_in_place(v.as_mut());
    }
    Ok(((0..n).map(|i| evd.S().column_vector()[i]).collect(), v))
}

/// Eigenvalues (ω², ascending) and eigenvectors (columns, any scale) of one block, and
/// whether they came from M's factor (so that rounding-level eigenvalues mean neutral).
struct BlockModes {
    omega_squared: Vec<f64>,
    vectors: Mat<f64>,
    by_mass_factor: bool,
}

/// Solves one block: with K_eff's Cholesky factor and for 1/ω² when K_eff is positive
/// definite there, so low modes keep full relative accuracy next to stiff, light parts;
/// with M's factor otherwise.
fn block_modes(
    k: &Mat<f64>,
    m: &Mat<f64>,
    weakest: impl Fn() -> String,
) -> Result<BlockModes, DynamicsError> {
    let n = m.nrows();
    let m_llt = m
        .llt(Side::Lower)
        .map_err(|_| DynamicsError::SingularMass {
            variable: weakest(),
        })?;
    match k.llt(Side::Lower) {
        Ok(k_llt) => {
            // M u = μ K u with μ = 1/ω², μ descending ⇔ ω² ascending. Every μ is positive in
            // exact arithmetic; the smallest (the stiffest modes) are resolved only down to
            // rounding of the largest, and are reported at that bound.
            let (mus, u) = reduced_eigen(m, &k_llt)?;
            let floor = 100.0 * f64::EPSILON * mus.last().copied().unwrap_or(0.0);
            let order: Vec<usize> = (0..n).rev().collect();
            Ok(BlockModes {
                omega_squared: order.iter().map(|&j| 1.0 / mus[j].max(floor)).collect(),
                vectors: Mat::from_fn(n, n, |i, k| u[(i, order[k])]),
                by_mass_factor: false,
            })
        }
        Err(_) => {
            let (lambdas, v) = reduced_eigen(k, &m_llt)?;
            Ok(BlockModes {
                omega_squared: lambdas,
                vectors: v,
                by_mass_factor: true,
            })
        }
    }
}

/// Solves K_eff v = ω² M v. The variables are split into the blocks that K_eff and M couple
/// (their exact zeros; found from the matrices, never assumed), and each block is solved on
/// its own: with K_eff's Cholesky factor and for 1/ω² when K_eff is positive definite on the
/// block (the low modes, the ones suspensions are about, then keep full relative accuracy
/// even when very stiff, very light parts put other modes many decades higher); otherwise
/// with M's factor, and eigenvalues within rounding of zero (100 ε of the largest |ω²| of
/// all blocks) are reported as exactly zero: neutral. Modes stiffer than the lowest of
/// their block by more than 1/(100 ε) ≈ 4.5e13 in ω² cannot be resolved in double
/// precision and are reported at that bound. Vectors are normalised and the energy
/// fractions formed with one product by the (block-sparse) mass matrix. `names` are the
/// variable names.
pub fn normal_modes(
    k_eff: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    names: &[String],
) -> Result<Modes, DynamicsError> {
    let n = mass.nrows();
    if k_eff.nrows() != n || k_eff.ncols() != n || mass.ncols() != n {
        return Err(DynamicsError::Length {
            what: "stiffness matrix for the modes",
            expected: n,
            got: k_eff.nrows(),
        });
    }
    let (label, count) = dense_components(n, &[k_eff.as_slice(), mass.as_slice()]);
    // (ω², from M's factor, block, vector over the block's variables); a block's modes are
    // exactly zero on the other variables
    let mut raw: Vec<(f64, bool, usize, Vec<f64>)> = Vec::with_capacity(n);
    let mut blocks = Vec::with_capacity(count);
    for b in 0..count {
        let idx: Vec<usize> = (0..n).filter(|&i| label[i] == b).collect();
        let kb = Mat::from_fn(idx.len(), idx.len(), |i, j| k_eff[(idx[i], idx[j])]);
        let mb = Mat::from_fn(idx.len(), idx.len(), |i, j| mass[(idx[i], idx[j])]);
        let weakest = || {
            let w = idx
                .iter()
                .copied()
                .min_by(|&i, &j| mass[(i, i)].total_cmp(&mass[(j, j)]))
                .unwrap_or(0);
            names.get(w).cloned().unwrap_or_default()
        };
        let block = block_modes(&kb, &mb, weakest)?;
        for (k, &w2) in block.omega_squared.iter().enumerate() {
            let vector = (0..idx.len()).map(|i| block.vectors[(i, k)]).collect();
            raw.push((w2, block.by_mass_factor, b, vector));
        }
        let mass_columns = SparseColumns::new(idx.len(), |i, j| mb[(i, j)]);
        let block_names: Vec<String> = idx
            .iter()
            .map(|&i| names.get(i).cloned().unwrap_or_default())
            .collect();
        blocks.push((idx, mass_columns, block_names));
    }
    let largest = raw.iter().fold(0.0f64, |a, (l, _, _, _)| a.max(l.abs()));
    let zero = 100.0 * f64::EPSILON * largest;
    raw.sort_by(|a, b| a.0.total_cmp(&b.0));
    let modes = raw
        .into_iter()
        .map(|(w2, by_mass, b, u)| {
            let w2 = if by_mass && w2.abs() <= zero { 0.0 } else { w2 };
            let (idx, mass_columns, block_names) = &blocks[b];
            let local = Mode::from_vector(w2, &u, &mass_columns.times(&u), block_names);
            let spread = |values: &[f64]| {
                let mut full = vec![0.0; n];
                for (&i, &v) in idx.iter().zip(values) {
                    full[i] = v;
                }
                full
            };
            Mode {
                vector: spread(&local.vector),
                energy_fractions: spread(&local.energy_fractions),
                ..local
            }
        })
        .collect();
    Ok(Modes {
        coordinates: names.to_vec(),
        modes,
    })
}

/// Motion of one body in a mode, in lab axes.
#[derive(Clone, Debug)]
pub struct BodyMotion {
    /// Body name.
    pub body: String,
    /// Displacement of the centre of mass (m per unit modal amplitude).
    pub translation: [f64; 3],
    /// Small rotation about lab z, y, x: lab yaw, pitch, roll (rad per unit modal amplitude).
    pub rotation: [f64; 3],
}

/// The lab-frame table of a mode (the source's `e2ni`): each massive body's centre-of-mass
/// displacement and small rotation, through the linearised geometry at `x_eq`. Float
/// motion is not included (it follows from the variables).
pub fn lab_motion(system: &System, layout: &Layout, x_eq: &[f64], mode: &Mode) -> Vec<BodyMotion> {
    system
        .bodies
        .iter()
        .filter(|b| b.mass > 0.0)
        .map(|body| {
            let jac = body.frame.jacobian(x_eq, &body.centre_of_mass);
            let mut translation = Vector3::zeros();
            let mut omega = Vector3::zeros();
            for (k, &g) in layout.variables.iter().enumerate() {
                debug_assert_eq!(system.coords[g].kind, CoordKind::Variable);
                translation += jac.position.column(g) * mode.vector[k];
                omega += jac.omega_space.column(g) * mode.vector[k];
            }
            BodyMotion {
                body: body.name.clone(),
                translation: [translation[0], translation[1], translation[2]],
                rotation: lab_yaw_pitch_roll(&omega),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_solves_equal_the_dense_triangular_solves() {
        // a banded symmetric positive definite matrix (bandwidth 3, diagonally dominant)
        // and a dense right-hand side with leading zeros: the envelope solves skip exact
        // zeros only, so they agree with faer's dense solves to rounding
        let n = 40;
        let a = Mat::from_fn(n, n, |i, j| {
            let d = i.abs_diff(j);
            match d {
                0 => 10.0 + (i % 7) as f64,
                1..=3 => 1.0 / (1.0 + (i + j) as f64 * 0.1 + d as f64),
                _ => 0.0,
            }
        });
        let llt = a.llt(Side::Lower).unwrap();
        let envelope = Envelope::new(llt.L());
        assert!(envelope.is_narrow());
        let b = Mat::from_fn(n, 5, |i, j| {
            if i < 3 * j {
                0.0
            } else {
                ((i * 7 + j * 3) % 11) as f64 - 5.0
            }
        });
        let (mut x, mut y) = (b.clone(), b.clone());
        envelope.solve_lower(&mut x);
        llt.L().solve_lower_triangular_in_place(y.as_mut());
        let (mut u, mut v) = (b.clone(), b.clone());
        envelope.solve_upper_transposed(&mut u);
        llt.L()
            .transpose()
            .solve_upper_triangular_in_place(v.as_mut());
        for j in 0..5 {
            for i in 0..n {
                assert!((x[(i, j)] - y[(i, j)]).abs() <= 1e-13 * (1.0 + y[(i, j)].abs()));
                assert!((u[(i, j)] - v[(i, j)]).abs() <= 1e-13 * (1.0 + v[(i, j)].abs()));
            }
        }
    }
}
