//! One calculation stage of a [`System`], run: its equilibrium and matrices (by the
//! assembly), its stage model, its normal modes with their accuracy, and the stability
//! verdict; the order every command runs them in, in one place ([`StageRun::new`]).

use pendkit_assembly::{
    Assembled, AssemblyError, AssemblyOptions, PhaseTimes, assemble_with, timed,
};
use pendkit_system::{Stage, System};

use crate::{
    DynamicsError, Modes, Stability, StageModel, TermRounding, eliminate_floats, float_directions,
    inverted_bodies, normal_modes_with_rounding, validate,
};

/// Largest number of variables for which [`ModeSelection::Below`] uses the dense
/// eigensolver (a few ms at this size); larger models use shift-invert.
pub const DENSE_MODES_LIMIT: usize = 200;

/// Which normal modes a stage run computes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ModeSelection {
    /// Every mode, by the dense eigensolver block by block.
    #[default]
    All,
    /// The modes below this frequency (Hz): by the dense eigensolver up to
    /// [`DENSE_MODES_LIMIT`] variables, by shift-invert Lanczos on the sparse factorisation
    /// above ([`StageModel::modes_below`]).
    Below(f64),
}

/// How [`StageRun::new`] runs a stage: assembly options (equilibrium controls, derivative
/// path) and which modes to compute.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Equilibrium controls and derivative path.
    pub assembly: AssemblyOptions,
    /// All modes, or those below a frequency.
    pub modes: ModeSelection,
}

/// Why a stage could not be run: the layer that refused it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// The element registry, the terms, the equilibrium or the matrices.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    /// The stage model, the modes or the stability verdict.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
}

/// A system run at one stage: its equilibrium, matrices, modes and stability verdict.
pub struct StageRun {
    /// The numeric model.
    pub system: System,
    /// Equilibrium and per-term matrices.
    pub assembled: Assembled,
    /// The stage's frequency-independent matrices for responses and noise.
    pub model: StageModel,
    /// Normal modes (possibly with unstable ones: see `stability`). Each carries its
    /// estimated error ([`crate::Mode::omega_squared_error`]).
    pub modes: Modes,
    /// The stability verdict of the equilibrium: growing modes, floats without a stable
    /// position, bodies upside down. [`StageRun::check_stable`] turns it into an error.
    pub stability: Stability,
}

impl StageRun {
    /// Equilibrium, stiffness, mass, modes and stability of `system` at `stage`. The modes
    /// use the real stiffness at f = 0 (each tag's ε'(0); 1 unless a model says otherwise).
    /// When `times` is given, the time of each phase is recorded into it: the assembly's
    /// (`terms`, `equilibrium`, `hessian:<kind>`, `mass`), then `stage-model` (the stage's
    /// matrices by tag), `rounding` (each term's share of the stiffness rounding, for the
    /// modes' accuracy), `floats` (their elimination), `modes` and `stability` (the float
    /// block's and the bodies' checks for the verdict).
    pub fn new(
        system: System,
        stage: Stage,
        options: &RunOptions,
        mut times: Option<&mut PhaseTimes>,
    ) -> Result<StageRun, RunError> {
        if let ModeSelection::Below(hz) = options.modes
            && !(hz > 0.0 && hz.is_finite())
        {
            return Err(DynamicsError::BelowFrequency(hz).into());
        }
        let assembled = assemble_with(&system, stage, &options.assembly, times.as_deref_mut())?;
        let model = timed(&mut times, "stage-model", 1, || {
            StageModel::new(&system, &assembled)
        });
        model.check_damping_at_dc(&system.damping)?;
        let rounding = timed(&mut times, "rounding", 1, || {
            TermRounding::new(&model, &assembled, &system.damping)
        });
        let modes = match options.modes {
            ModeSelection::Below(hz) if model.sizes.0 > DENSE_MODES_LIMIT => {
                let below = timed(&mut times, "modes", 1, || {
                    model.modes_below_with_rounding(&system.damping, hz, &rounding)
                });
                match below {
                    Ok(modes) => modes,
                    // the shift-invert iteration could not resolve every mode below the
                    // bound (a growing mode beyond its shift's resolution, a shift on an
                    // eigenvalue): the dense solve, slower but complete, decides instead
                    Err(DynamicsError::Solver(_)) => {
                        dense_modes(&model, &assembled, &system, &rounding, Some(hz), &mut times)?
                    }
                    Err(e) => return Err(e.into()),
                }
            }
            ModeSelection::Below(hz) => {
                dense_modes(&model, &assembled, &system, &rounding, Some(hz), &mut times)?
            }
            ModeSelection::All => {
                dense_modes(&model, &assembled, &system, &rounding, None, &mut times)?
            }
        };
        // after the modes, so that a model the modes refuse outright (a massless body,
        // whose wires then carry no tension) is refused for that
        validate::check_wire_stretch(&system, &assembled.equilibrium.coords)?;
        let stability = timed(&mut times, "stability", 1, || {
            let floats = float_directions(&model, &system.damping, Some(&rounding))?;
            let inverted = inverted_bodies(&system, &assembled.equilibrium.coords);
            Ok::<_, DynamicsError>(Stability::assess(&modes, floats, model.sizes.1, inverted))
        })?;
        Ok(StageRun {
            system,
            assembled,
            model,
            modes,
            stability,
        })
    }

    /// One line saying what grows, as an error, unless the equilibrium is stable (or
    /// neutral). Every calculation that answers with a linearised model checks this first.
    pub fn check_stable(&self) -> Result<(), DynamicsError> {
        self.stability.check()
    }

    /// The check every command answering with a linearised model (transfer functions,
    /// noise, state space, ...) makes before it answers: `Ok(None)` when nothing grows;
    /// when something does, the error, or with `allow_unstable` `Ok(Some(warning))`, the
    /// one line to show the user before going on (control design needs unstable plants).
    /// A neutral verdict that rests on a float stiffness rounding cannot sign (nothing
    /// shown to grow) goes on, with the verdict as the line to show.
    pub fn require_stable(&self, allow_unstable: bool) -> Result<Option<String>, DynamicsError> {
        match (self.check_stable(), allow_unstable) {
            (Ok(()), _) if !self.stability.neutral_floats.is_empty() => {
                Ok(Some(self.stability.to_string()))
            }
            (Ok(()), _) => Ok(None),
            (Err(e), true) => Ok(Some(format!("{e} (going on: --allow-unstable)"))),
            (Err(e), false) => Err(e),
        }
    }
}

/// The stage's modes by the dense eigensolver block by block (those below `below` Hz when
/// given, every growing mode among them), recording the `floats` and `modes` phases.
fn dense_modes(
    model: &StageModel,
    assembled: &Assembled,
    system: &System,
    rounding: &TermRounding,
    below: Option<f64>,
    times: &mut Option<&mut PhaseTimes>,
) -> Result<Modes, DynamicsError> {
    // a large model without floats: the same block solves from the pattern, without the
    // dense n × n matrices
    if model.sizes.0 > DENSE_MODES_LIMIT
        && let Some(modes) = timed(times, "modes", 1, || {
            model.modes_by_blocks(&system.damping, rounding)
        })
    {
        let mut modes = modes?;
        if let Some(hz) = below {
            modes.modes.retain(|m| m.hz < hz);
        }
        return Ok(modes);
    }
    let reduced = timed(times, "floats", 1, || {
        eliminate_floats(
            &model.real_stiffness(&system.damping),
            &assembled.layout,
            system,
        )
    })?;
    let mut modes = timed(times, "modes", 1, || {
        normal_modes_with_rounding(
            &reduced.k_eff,
            &assembled.mass.to_dense(),
            &model.variables,
            rounding,
        )
    })?;
    if let Some(hz) = below {
        modes.modes.retain(|m| m.hz < hz);
    }
    Ok(modes)
}
