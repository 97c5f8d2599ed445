//! Dynamics from the assembled matrices: the stage's stiffness parts on one fixed sparsity
//! pattern, elimination of the floats (one Schur complement for modes and responses alike),
//! normal modes block by block (all of them, or those below a frequency by shift-invert on
//! a sparse factorisation), transfer-function sweeps solved only over the blocks an input
//! and output couple to, and state-space matrices.

mod lanczos;
mod lu;
mod modes;
mod pattern;
mod schur;
mod sparse_lu;
mod stage;
mod sweep;

pub use modes::{BodyMotion, Mode, Modes, lab_motion, normal_modes};
pub use pattern::Pattern;
pub use stage::{Input, Output, ReducedComplex, StageModel, StateSpace, TermLoss};
pub use sweep::{DENSE_LIMIT, Solver, Sweep, coupled_unknowns};

use faer::c64;
use nalgebra::DMatrix;
use pendkit_assembly::Layout;
use pendkit_energy::{Damping, System};

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
    /// An input, output or matrix with the wrong number of entries.
    #[error("{what} has {got} entries, expected {expected}")]
    Length {
        /// What was given.
        what: &'static str,
        /// Entries expected.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// The dynamic stiffness is singular at a frequency (an undamped resonance hit exactly).
    #[error(
        "the dynamic stiffness is singular at {f_hz} Hz (an undamped resonance exactly on the grid): add damping or move the frequency"
    )]
    Singular {
        /// The frequency (Hz).
        f_hz: f64,
    },
    /// A frequency bound for the modes that is not positive and finite.
    #[error("modes below {0} Hz: the frequency must be positive and finite")]
    BelowFrequency(f64),
    /// The sparse solver could not analyse or factorise a matrix.
    #[error("sparse solver: {0}")]
    Solver(String),
}

/// Real stiffness with floats eliminated: K_eff, C_XS,eff and S_eff (docs/physics.md §3).
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
    let n = nx + nq + ns;
    if p.nrows() != n || p.ncols() != n {
        return Err(DynamicsError::Length {
            what: "master matrix",
            expected: n,
            got: p.nrows(),
        });
    }
    let kept: Vec<usize> = (0..nx).chain(nx + nq..n).collect();
    let floats: Vec<usize> = (nx..nx + nq).collect();
    let e = schur::eliminate(|i, j| p[(i, j)], &kept, &floats);
    if let Some(k) = e.singular {
        return Err(DynamicsError::SingularFloats {
            float: system.coords[layout.floats[k]].name.clone(),
        });
    }
    let a = e.matrix;
    let block = |r0: usize, c0: usize, nr: usize, nc: usize| {
        DMatrix::from_fn(nr, nc, |i, j| a[(r0 + i, c0 + j)])
    };
    Ok(Reduced {
        k_eff: block(0, 0, nx, nx),
        c_xs_eff: block(0, nx, nx, ns),
        s_eff: block(nx, nx, ns, ns),
    })
}

impl StageModel {
    /// Transfer function from `input` to `output` at each frequency (Hz): output per unit
    /// input, complex (m/m, m/N, N/m, N/N ...), solved as `solver` says. Sign conventions
    /// of docs/physics.md §3: a pendulum's displacement transfer function tends to +1 at DC.
    pub fn transfer_with(
        &self,
        damping: &Damping,
        input: &Input,
        output: &Output,
        freqs: &[f64],
        solver: Solver,
    ) -> Result<Vec<c64>, DynamicsError> {
        let mut sweep = Sweep::new(self, damping, input, output, solver)?;
        let mut values = Vec::with_capacity(freqs.len());
        sweep.for_each(freqs, |_, y, _| values.push(y))?;
        Ok(values)
    }

    /// [`StageModel::transfer_with`] over the restricted blocks. An input or output of the
    /// wrong length, or a frequency where the dynamic stiffness is exactly singular, gives
    /// NaN values; [`StageModel::transfer_with`] says which it was.
    pub fn transfer(
        &self,
        damping: &Damping,
        input: &Input,
        output: &Output,
        freqs: &[f64],
    ) -> Vec<c64> {
        let nan = c64::new(f64::NAN, f64::NAN);
        match Sweep::new(self, damping, input, output, Solver::Restricted) {
            Ok(mut sweep) => {
                let mut values = Vec::with_capacity(freqs.len());
                match sweep.for_each(freqs, |_, y, _| values.push(y)) {
                    Ok(()) => values,
                    // a singular point: NaN there, the others solved one by one
                    Err(_) => freqs.iter().map(|&f| sweep.at(f).unwrap_or(nan)).collect(),
                }
            }
            Err(_) => vec![nan; freqs.len()],
        }
    }

    /// Response z over every variable and float (master order) to the generalised force
    /// `force` on the variables at `f_hz`, with the support held: E(f) z = [force; 0].
    pub fn respond_to_force(
        &self,
        damping: &Damping,
        force: &nalgebra::DVector<f64>,
        f_hz: f64,
    ) -> Result<Vec<c64>, DynamicsError> {
        let mut sweep = Sweep::new(
            self,
            damping,
            &Input::Force(force.clone()),
            &Output::Displacement(force.clone()),
            Solver::Full,
        )?;
        sweep.at(f_hz)?;
        Ok(sweep.response().to_vec())
    }
}
