//! Checks of what a calculation is given before it runs: frequencies within documented
//! limits, damping multipliers that are finite with a non-negative loss at every frequency
//! used, and wires whose static stretch double precision resolves.

use pendkit_system::{Damping, System};

use crate::DynamicsError;

/// Lowest frequency (Hz) any calculation accepts: below it 1/ω and 1/ω² approach the
/// limits of double precision in the noise and the state space.
pub const MIN_FREQUENCY: f64 = 1e-9;

/// Highest frequency (Hz) any calculation accepts (ω² stays far from overflow, and no
/// suspension has dynamics there).
pub const MAX_FREQUENCY: f64 = 1e9;

/// Largest ratio of a wire's axial stiffness k to its pendulum stiffness T/l (T its
/// tension, l its length) that a calculation accepts: l0 / |l − l0| at the equilibrium.
///
/// The tension is k (l − l0), a difference of two lengths each rounded to ε l (ε = 2.2e-16),
/// so it carries a relative error of about ε l / |l − l0| = ε × ratio: 2e-4 at 1e12 (the
/// range issue 11 states for stiffness ratios); past 1/ε ≈ 4.5e15 the tension, and with it
/// the pendulum stiffness of every stage below, is rounding noise, and modes read from it
/// come out "neutral" or at any frequency.
pub const MAX_WIRE_STIFFNESS_RATIO: f64 = 1e12;

/// Every wire of `system` is stretched at the equilibrium `x_eq` by more than
/// 1/[`MAX_WIRE_STIFFNESS_RATIO`] of its unstretched length, or a one-line error naming the
/// first that is not, its strain and its ratio (not checked without gravity, g = 0).
pub fn check_wire_stretch(system: &System, x_eq: &[f64]) -> Result<(), DynamicsError> {
    // Without gravity nothing loads the wires: a zero stretch is then exact (a fibre is a
    // plain cantilever), not a tension lost in rounding.
    if system.gravity == 0.0 {
        return Ok(());
    }
    for wire in &system.wires {
        let end = |k: usize| {
            let e = &wire.ends[k];
            let body = system.bodies.get(e.body)?;
            Some(body.frame.try_eval(x_eq).ok()?.point(&e.point))
        };
        // ends that cannot be placed were refused by the assembly already
        let (Some(p0), Some(p1)) = (end(0), end(1)) else {
            continue;
        };
        let l0 = wire.unstretched_length;
        let stretch = (p1 - p0).norm() - l0;
        let ratio = l0 / stretch.abs();
        if ratio.is_nan() || ratio > MAX_WIRE_STIFFNESS_RATIO {
            return Err(DynamicsError::StiffWire {
                wire: wire.name.clone(),
                strain: stretch / l0,
                ratio,
            });
        }
    }
    Ok(())
}

/// `f_hz` is finite and within [`MIN_FREQUENCY`], [`MAX_FREQUENCY`]; `what` names it in
/// the error (e.g. "damping frequency").
pub fn check_frequency(what: &'static str, f_hz: f64) -> Result<(), DynamicsError> {
    if f_hz.is_finite() && (MIN_FREQUENCY..=MAX_FREQUENCY).contains(&f_hz) {
        Ok(())
    } else {
        Err(DynamicsError::Frequency { what, f_hz })
    }
}

/// Every frequency of `freqs` passes [`check_frequency`], and there are at most
/// [`pendkit_limits::FREQUENCY_POINTS`] of them.
pub fn check_frequencies(freqs: &[f64]) -> Result<(), DynamicsError> {
    pendkit_limits::FREQUENCY_POINTS
        .check(freqs.len())
        .map_err(DynamicsError::TooManyPoints)?;
    freqs
        .iter()
        .try_for_each(|&f| check_frequency("frequency", f))
}

/// Checks one tag's multiplier ε' + i ε'' at `f_hz`: both finite, the loss ε'' not
/// negative (a negative loss makes the suspension gain energy and its "noise" negative),
/// the storage ε' not negative (it would turn the tag's stiffness inside out).
pub fn check_multiplier(tag: &str, f_hz: f64, real: f64, imag: f64) -> Result<(), DynamicsError> {
    let problem = if !real.is_finite() || !imag.is_finite() {
        "is not finite"
    } else if imag < 0.0 {
        "has a negative loss (imaginary part): losses must be zero or positive"
    } else if real < 0.0 {
        "has a negative real part: it would turn the tag's stiffness inside out"
    } else {
        return Ok(());
    };
    Err(DynamicsError::Damping {
        tag: tag.to_string(),
        f_hz,
        real,
        imag,
        problem,
    })
}

/// Checks the multipliers of `tags` (those of a stage's lossy terms; tags without explicit
/// damping have 1 + 0i) at every frequency of `freqs`.
pub fn check_damping<'a>(
    damping: &Damping,
    tags: impl IntoIterator<Item = &'a str>,
    freqs: &[f64],
) -> Result<(), DynamicsError> {
    for tag in tags {
        if let Some(d) = damping.get(tag) {
            for &f in freqs {
                let (re, im) = d.at(f);
                check_multiplier(tag, f, re, im)?;
            }
        }
    }
    Ok(())
}
