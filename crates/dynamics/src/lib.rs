//! Dynamics from the assembled matrices: elimination of floats by Schur complement, and
//! normal modes (generalised symmetric eigenproblem K_eff v = ω² M v) with labels and a
//! lab-frame table of body motions; and, with dissipation dilution, transfer functions
//! and state-space matrices.

mod response;

pub use response::{Input, Output, ReducedComplex, StageModel, StateSpace, TermLoss};

use faer::{Mat, Side};
use nalgebra::{DMatrix, Vector3};
use pendkit_assembly::Layout;
use pendkit_energy::{CoordKind, System};
use pendkit_rotations::lab_yaw_pitch_roll;

/// Errors of the dynamics calculations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// The float block Q cannot be inverted: some float is held by nothing.
    #[error("float '{float}' has no stiffness holding it (the float block Q is singular)")]
    SingularFloats {
        /// The float with the smallest pivot.
        float: String,
    },
    /// The mass matrix is not positive definite.
    #[error(
        "variable '{variable}' carries no inertia (the mass matrix is singular): give its body mass or inertia, or make it a float"
    )]
    SingularMass {
        /// The variable with the smallest diagonal mass.
        variable: String,
    },
    /// Damping represented at a frequency that is not positive.
    #[error("damping frequency must be positive (got {0} Hz)")]
    DampingFrequency(f64),
    /// The eigen solver failed.
    #[error("eigen solver failed: {0}")]
    Eigen(String),
    /// A negative eigenvalue: the equilibrium is unstable.
    #[error(
        "unstable equilibrium: mode {index} has negative stiffness (growth rate {rate_hz:.6} Hz), mostly {label} ({fraction:.0} % of its kinetic energy)"
    )]
    Unstable {
        /// 1-based mode number in ascending order.
        index: usize,
        /// sqrt(-ω²)/2π (Hz).
        rate_hz: f64,
        /// Dominant coordinate.
        label: String,
        /// Its kinetic-energy share (%).
        fraction: f64,
    },
}

/// Real stiffness with floats eliminated: K_eff, C_XS,eff and S_eff (DESIGN.md §5).
#[derive(Clone, Debug)]
pub struct Reduced {
    /// K_eff over the variables (N/m, N/rad, N m/rad).
    pub k_eff: DMatrix<f64>,
    /// C_XS,eff: variables × parameters.
    pub c_xs_eff: DMatrix<f64>,
    /// S_eff over the parameters.
    pub s_eff: DMatrix<f64>,
}

/// Eliminates the floats from a master matrix `p` (layout order) by Schur complement:
/// K_eff = K − C_XQ Q⁻¹ C_QX, C_XS,eff = C_XS − C_XQ Q⁻¹ C_QS, S_eff = S − C_SQ Q⁻¹ C_QS.
pub fn eliminate_floats(
    p: &DMatrix<f64>,
    layout: &Layout,
    system: &System,
) -> Result<Reduced, DynamicsError> {
    let (nx, nq, ns) = layout.sizes();
    let kept = |r0: usize, c0: usize, nr: usize, nc: usize| p.view((r0, c0), (nr, nc)).into_owned();
    let (xq, sq) = (nx, nx + nq);
    // rows/cols of the kept coordinates (x then s) and of the floats
    let mut a = DMatrix::zeros(nx + ns, nx + ns);
    a.view_mut((0, 0), (nx, nx)).copy_from(&kept(0, 0, nx, nx));
    a.view_mut((0, nx), (nx, ns))
        .copy_from(&kept(0, sq, nx, ns));
    a.view_mut((nx, 0), (ns, nx))
        .copy_from(&kept(sq, 0, ns, nx));
    a.view_mut((nx, nx), (ns, ns))
        .copy_from(&kept(sq, sq, ns, ns));
    if nq > 0 {
        let q = kept(xq, xq, nq, nq);
        let mut c = DMatrix::zeros(nx + ns, nq);
        c.view_mut((0, 0), (nx, nq)).copy_from(&kept(0, xq, nx, nq));
        c.view_mut((nx, 0), (ns, nq))
            .copy_from(&kept(sq, xq, ns, nq));
        let lu = q.clone().full_piv_lu();
        let scale = q.abs().max();
        let singular =
            !lu.is_invertible() || lu.u().diagonal().iter().any(|d| d.abs() <= 1e-13 * scale);
        if singular {
            let weakest = (0..nq)
                .min_by(|&i, &j| q[(i, i)].abs().total_cmp(&q[(j, j)].abs()))
                .unwrap_or(0);
            return Err(DynamicsError::SingularFloats {
                float: system.coords[layout.floats[weakest]].name.clone(),
            });
        }
        let q_inv_ct = lu
            .solve(&c.transpose())
            .ok_or_else(|| DynamicsError::SingularFloats {
                float: system.coords[layout.floats[0]].name.clone(),
            })?;
        a -= &c * q_inv_ct;
    }
    Ok(Reduced {
        k_eff: a.view((0, 0), (nx, nx)).into_owned(),
        c_xs_eff: a.view((0, nx), (nx, ns)).into_owned(),
        s_eff: a.view((nx, nx), (ns, ns)).into_owned(),
    })
}

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
}

/// All normal modes of a stage, ascending in frequency.
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

fn to_faer(m: &DMatrix<f64>) -> Mat<f64> {
    Mat::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// Eigenpairs (ω², vectors) of the pencil (A, B) by Cholesky reduction of B:
/// C = L⁻¹ A L⁻ᵀ, eigenvalues ascending, vectors L⁻ᵀ u (B-orthonormal).
fn reduced_eigen(
    a: &DMatrix<f64>,
    b_llt: &faer::linalg::solvers::Llt<f64>,
) -> Result<(Vec<f64>, Mat<f64>), DynamicsError> {
    let n = a.nrows();
    let l = b_llt.L();
    let mut x = to_faer(a);
    l.solve_lower_triangular_in_place(x.as_mut());
    let mut c = x.transpose().to_owned();
    l.solve_lower_triangular_in_place(c.as_mut());
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| DynamicsError::Eigen(format!("{e:?}")))?;
    let mut v = evd.U().to_owned();
    l.transpose().solve_upper_triangular_in_place(v.as_mut());
    Ok(((0..n).map(|i| evd.S().column_vector()[i]).collect(), v))
}

/// Solves K_eff v = ω² M v. When K_eff is positive definite the pencil is reduced with
/// K_eff's Cholesky factor and solved for 1/ω²: the low modes, the ones suspensions are
/// about, then keep full relative accuracy even when very stiff, very light parts (blade
/// tips, beads) put other modes many decades higher; otherwise (neutral or unstable modes)
/// it is reduced with M's factor, and eigenvalues within rounding of zero (100 ε of the
/// largest) are reported as exactly zero: neutral. Modes stiffer than the lowest by more
/// than 1/(100 ε) ≈ 4.5e13 in ω² cannot be resolved in double precision and are reported
/// at that bound. `names` are the variable names.
pub fn normal_modes(
    k_eff: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    names: &[String],
) -> Result<Modes, DynamicsError> {
    let n = mass.nrows();
    let m_llt = to_faer(mass).llt(Side::Lower).map_err(|_| {
        let weakest = (0..n)
            .min_by(|&i, &j| mass[(i, i)].total_cmp(&mass[(j, j)]))
            .unwrap_or(0);
        DynamicsError::SingularMass {
            variable: names.get(weakest).cloned().unwrap_or_default(),
        }
    })?;
    let (lambdas, v, zero) = match to_faer(k_eff).llt(Side::Lower) {
        Ok(k_llt) => {
            // M u = μ K u with μ = 1/ω², μ descending ⇔ ω² ascending
            let (mus, u) = reduced_eigen(mass, &k_llt)?;
            // every μ is positive in exact arithmetic; the smallest (the stiffest modes) are
            // resolved only down to rounding of the largest, and are reported at that bound
            let floor = 100.0 * f64::EPSILON * mus.last().copied().unwrap_or(0.0);
            let order: Vec<usize> = (0..n).rev().collect();
            let mut v = Mat::zeros(n, n);
            let mut lambdas = Vec::with_capacity(n);
            for (k, &j) in order.iter().enumerate() {
                let col: Vec<f64> = (0..n).map(|i| u[(i, j)]).collect();
                let vn = nalgebra::DVector::from_column_slice(&col);
                let norm = vn.dot(&(mass * &vn)).sqrt();
                for i in 0..n {
                    v[(i, k)] = col[i] / norm;
                }
                lambdas.push(1.0 / mus[j].max(floor));
            }
            (lambdas, v, 0.0)
        }
        Err(_) => {
            let (lambdas, v) = reduced_eigen(k_eff, &m_llt)?;
            // neutral modes come out as ± rounding of the largest eigenvalue
            let largest = lambdas.iter().fold(0.0f64, |a, l| a.max(l.abs()));
            (lambdas, v, 100.0 * f64::EPSILON * largest)
        }
    };
    let modes = (0..n)
        .map(|k| {
            let lambda = if lambdas[k].abs() <= zero {
                0.0
            } else {
                lambdas[k]
            };
            let vector: Vec<f64> = (0..n).map(|i| v[(i, k)]).collect();
            let vec_na = nalgebra::DVector::from_column_slice(&vector);
            let mv = mass * &vec_na;
            let energy_fractions: Vec<f64> = (0..n).map(|i| vector[i] * mv[i]).collect();
            let dominant = (0..n)
                .max_by(|&i, &j| energy_fractions[i].total_cmp(&energy_fractions[j]))
                .unwrap_or(0);
            let hz = lambda.signum() * lambda.abs().sqrt() / (2.0 * std::f64::consts::PI);
            Mode {
                omega_squared: lambda,
                hz,
                label: names.get(dominant).cloned().unwrap_or_default(),
                vector,
                energy_fractions,
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
