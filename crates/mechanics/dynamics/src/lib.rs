//! Dynamics from the assembled matrices: the stage's stiffness parts on one fixed sparsity
//! pattern, elimination of the floats (one Schur complement for modes and responses alike),
//! normal modes block by block (all of them, or those below a frequency by shift-invert on
//! a sparse factorisation), transfer-function sweeps solved only over the blocks an input
//! and output couple to, state-space matrices, and the derivative of the stage's matrices
//! with respect to a parameter by central differences over stepped models ([`difference`]);
//! [`StageRun`] runs a stage on a system in the order every command uses.

pub mod difference;
mod lanczos;
mod lu;
mod modes;
mod pattern;
mod run;
mod schur;
mod sparse_lu;
mod stability;
mod stage;
mod sweep;
pub mod validate;
mod violin;

pub use modes::{
    BodyMotion, EntryRounding, Mode, Modes, REFINE_ABOVE, StiffnessRounding, lab_motion,
    normal_modes, normal_modes_with_rounding,
};
pub use pattern::{CommonPattern, Pattern};
pub use run::{DENSE_MODES_LIMIT, ModeSelection, RunError, RunOptions, StageRun};
pub use stability::{
    FloatDirections, FloatMap, GrowingMode, InvertedBody, RunawayFloat, Stability, TermRounding,
    Verdict, float_directions, inverted_bodies, runaway_floats,
};
pub use stage::{
    FrequencyTerm, Group, HeldResonance, Input, Multiplier, Output, ReducedComplex, StageModel,
    StateSpace, TermLoss, block_len,
};
pub use sweep::{DENSE_LIMIT, Solver, Sweep, coupled_unknowns};
pub use violin::{MAX_VIOLIN_HARMONICS, ViolinRoot};

use faer::c64;
use nalgebra::DMatrix;
use pendkit_assembly::Layout;
use pendkit_system::{Damping, System};

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
    #[error("damping frequency must be positive (got {} Hz)", pendkit_expr::number_text(*.0))]
    DampingFrequency(f64),
    /// The eigen solver failed.
    #[error("eigen solver failed: {0}")]
    Eigen(String),
    /// The equilibrium is unstable: the report says what grows (one line).
    #[error("{0}")]
    Unstable(Box<Stability>),
    /// A matrix given to a calculation holds NaN or infinity.
    #[error("{what} has a non-finite entry at row {row}, column {column}")]
    NotFinite {
        /// Which matrix.
        what: &'static str,
        /// Row (from 0).
        row: usize,
        /// Column (from 0).
        column: usize,
    },
    /// A frequency outside the documented limits.
    #[error(
        "{what} {f_hz:e} Hz is out of range: frequencies must be finite, from 1e-9 Hz to 1e9 Hz"
    )]
    Frequency {
        /// What the frequency is for.
        what: &'static str,
        /// The value given (Hz).
        f_hz: f64,
    },
    /// A wire so stiff that its static stretch is lost in the rounding of its length.
    #[error(
        "wire '{wire}': stretched by {strain:.1e} of its length, its stiffness is {ratio:.1e} times its pendulum stiffness T/l: beyond the ratio 1e12 that double precision resolves (its tension would carry a relative error of about 2.2e-16 x ratio)"
    )]
    StiffWire {
        /// The wire.
        wire: String,
        /// Its static strain (l − l0) / l0 at the equilibrium.
        strain: f64,
        /// k l0 / |T| = l0 / |l − l0|.
        ratio: f64,
    },
    /// A violin-mode search that cannot run (one line: why).
    #[error("violin modes: {0}")]
    Violin(String),
    /// A frequency grid with more points than [`pendkit_limits::FREQUENCY_POINTS`] allows
    /// (or that limit's variable set wrongly).
    #[error("frequency grid: {0}")]
    TooManyPoints(pendkit_limits::LimitError),
    /// A damping multiplier that is not finite or has the wrong sign somewhere.
    #[error(
        "damping tag '{tag}' at {} Hz: multiplier {} {} {}i {problem}",
        pendkit_expr::number_text(*f_hz),
        pendkit_expr::number_text(*real),
        if imag.is_sign_negative() { "-" } else { "+" },
        imaginary_text(*imag)
    )]
    Damping {
        /// The tag.
        tag: String,
        /// Where (Hz).
        f_hz: f64,
        /// ε' there.
        real: f64,
        /// ε'' there.
        imag: f64,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// A temperature that is not positive and finite.
    #[error("temperature must be positive and finite (got {0} K)")]
    Temperature(f64),
    /// Thermal noise of a model whose every tag is lossless: it would be exactly zero at
    /// every frequency, which would look like an answer.
    #[error(
        "thermal noise of {output} is exactly 0 at every frequency: no loss on the tags {}; give a loss in [damping.<tag>] (structural, viscous, thermoelastic, imag) or a material's loss_angle",
        if lossless.is_empty() { "(the model has none)".to_string() } else { lossless.join(", ") }
    )]
    NoLoss {
        /// The output, as the caller names it (or `the output`).
        output: String,
        /// The model's tags, none of which carries a loss.
        lossless: Vec<String>,
    },
    /// An index (of a variable, float or parameter) beyond the model's.
    #[error("{what} index {index} is out of range (the model has {len})")]
    Index {
        /// What the index is of.
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many there are.
        len: usize,
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
    #[error(
        "modes below {} Hz: the frequency must be positive and finite",
        pendkit_expr::number_text(*.0)
    )]
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
            what: "eliminate_floats: p (master matrix, per side)",
            expected: n,
            got: if p.nrows() != n { p.nrows() } else { p.ncols() },
        });
    }
    let kept: Vec<usize> = (0..nx).chain(nx + nq..n).collect();
    let floats: Vec<usize> = (nx..nx + nq).collect();
    let e = schur::eliminate(|i, j| p[(i, j)], &kept, &floats);
    if let Some(k) = e.singular {
        return Err(DynamicsError::SingularFloats {
            float: layout
                .floats
                .get(k)
                .and_then(|&c| system.coords.get(c))
                .map(|c| c.name.clone())
                .unwrap_or_default(),
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
        validate::check_frequencies(freqs)?;
        let mut sweep = Sweep::new(self, damping, input, output, solver)?;
        let mut values = Vec::with_capacity(freqs.len());
        sweep.for_each(freqs, |_, y, _| values.push(y))?;
        Ok(values)
    }

    /// [`StageModel::transfer_with`] over the restricted blocks.
    pub fn transfer(
        &self,
        damping: &Damping,
        input: &Input,
        output: &Output,
        freqs: &[f64],
    ) -> Result<Vec<c64>, DynamicsError> {
        self.transfer_with(damping, input, output, freqs, Solver::Restricted)
    }

    /// Response z over every variable and float (master order) to the generalised force
    /// `force` on the variables at `f_hz`, with the support held: E(f) z = [force; 0].
    pub fn respond_to_force(
        &self,
        damping: &Damping,
        force: &nalgebra::DVector<f64>,
        f_hz: f64,
    ) -> Result<Vec<c64>, DynamicsError> {
        validate::check_frequency("frequency", f_hz)?;
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

/// |x| for the imaginary part of a message's complex number: bracketed when it is not a
/// finite number, so that it does not run into the `i` ("1 + (inf)i").
fn imaginary_text(x: f64) -> String {
    let text = pendkit_expr::number_text(x.abs());
    if x.is_finite() {
        text
    } else {
        format!("({text})")
    }
}
