//! The fast derivative path: what an element's optional fast routine receives (the frame
//! jets of the bodies its term touches, see [`pendkit_geometry::FrameJet`]) and where it
//! writes (value, gradient, force scale and Hessians with the tension on and off), plus the
//! pieces several kinds share: chain-rule helpers for body-fixed points and directions, and
//! the general fallback that differentiates an energy written over frames by hyper-dual
//! numbers whose frames are taken from the jets instead of re-evaluating pose expressions.

use crate::EnergyError;
use nalgebra::{Matrix3, Vector3};
use num_dual::HyperDual64;
use pendkit_geometry::{Frame, FrameJet, JetError};

/// One frame a term reads, at the evaluation point: the body's jet and, for each of the
/// jet's coordinates, its index in the term's local coordinate vector.
#[derive(Clone, Copy, Debug)]
pub struct FrameAt<'a> {
    /// The body's frame and its derivatives.
    pub jet: &'a FrameJet,
    /// `local[i]` is the term-local index of the jet's coordinate `i`.
    pub local: &'a [usize],
}

impl FrameAt<'_> {
    /// `local` names one term-local index per coordinate of the jet (and, with `second`,
    /// the jet has second derivatives): then every position among `local` is a valid index
    /// of the jet, which `function` checks once here instead of per derivative.
    pub(crate) fn check_jet(
        &self,
        function: &'static str,
        second: bool,
    ) -> Result<(), EnergyError> {
        let k = self.jet.vars().len();
        if self.local.len() != k {
            return Err(EnergyError::Length {
                function,
                argument: "frame.local (one entry per jet coordinate)",
                expected: k,
                given: self.local.len(),
            });
        }
        if second && !self.jet.has_second() && k > 0 {
            return Err(pendkit_geometry::JetError::NoSecond { function }.into());
        }
        Ok(())
    }

    /// The position of term-local coordinate `l` among the jet's coordinates, if the frame
    /// depends on it.
    pub fn position(&self, l: usize) -> Option<usize> {
        self.local.iter().position(|&m| m == l)
    }
}

/// Where a fast routine is evaluated: the term's local coordinates and its frames (in the
/// order of the [`crate::LocalFrames`] the term was built with).
#[derive(Clone, Copy, Debug)]
pub struct JetPoint<'a> {
    /// Local coordinates (m, rad).
    pub x: &'a [f64],
    /// One entry per frame of the term.
    pub frames: &'a [FrameAt<'a>],
}

/// What became of the tension-off Hessian in a fast evaluation (it must agree with what
/// the term's `tension_off`, built at the evaluation point, says).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OffForm {
    /// Equal to the tension-on Hessian (all of the stiffness is lossy).
    Same,
    /// Zero (all of the stiffness is lossless).
    Zero,
    /// Written into [`Derivatives::off`].
    Written,
}

/// The outputs of one fast evaluation of a term's energy body over its `n` local
/// coordinates. Every buffer is zeroed by the caller. A body with several energy parts
/// (see [`crate::SharedPotential`]) writes part `p` at offset `p n` of the gradients and
/// force scales, `p n²` of the Hessians, and `p` of the values.
#[derive(Debug)]
pub struct Derivatives<'a> {
    /// Number of local coordinates.
    pub n: usize,
    /// Whether Hessians are wanted; otherwise only values, gradients and force scales.
    pub hessian: bool,
    /// Energy of each part (J).
    pub values: &'a mut [f64],
    /// Gradient of each part (N or N m per local coordinate).
    pub gradients: &'a mut [f64],
    /// Rounding scale of each gradient entry beyond its own size (N or N m): the size of
    /// the large forces whose difference it is, e.g. k (l + l0) for a stretched wire, whose
    /// force is k times a small difference of lengths. Leave zero when the gradient is not
    /// such a difference. The equilibrium search uses it to know when residual forces are
    /// rounding.
    pub force_scales: &'a mut [f64],
    /// Hessian of each part with the tension on (row-major n × n).
    pub on: &'a mut [f64],
    /// Hessian of the tension-off term built at the evaluation point (single-part bodies),
    /// when [`Derivatives::off_form`] is set to [`OffForm::Written`].
    pub off: &'a mut [f64],
    /// What the routine did with the tension-off Hessian (preset to `Same`).
    pub off_form: OffForm,
    /// Scratch space the routine may use as it likes.
    pub scratch: &'a mut Scratch,
}

/// Reusable scratch buffers for fast routines, so that evaluating a term does not allocate
/// once the buffers have grown.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// 3-vectors (e.g. a Jacobian's columns).
    pub vectors: Vec<Vector3<f64>>,
    /// 3 × 3 matrices (e.g. derivatives of a relative rotation).
    pub matrices: Vec<Matrix3<f64>>,
    /// Numbers.
    pub numbers: Vec<f64>,
}

impl Scratch {
    /// `len` zero vectors, reusing the buffer.
    pub fn zero_vectors(&mut self, len: usize) -> &mut [Vector3<f64>] {
        self.vectors.clear();
        self.vectors.resize(len, Vector3::zeros());
        &mut self.vectors
    }
}

/// A body-fixed vector whose derivatives a term needs.
#[derive(Clone, Copy, Debug)]
pub enum Attached<'v> {
    /// A point (m, body coordinates): X + R a.
    Point(&'v Vector3<f64>),
    /// A direction (body coordinates): R v.
    Direction(&'v Vector3<f64>),
}

impl Attached<'_> {
    fn first(&self, jet: &FrameJet, i: usize) -> Result<Vector3<f64>, JetError> {
        match self {
            Attached::Point(a) => jet.d_point(i, a),
            Attached::Direction(v) => Ok(jet.d_rotation(i)? * *v),
        }
    }

    fn second(&self, jet: &FrameJet, i: usize, j: usize) -> Result<Vector3<f64>, JetError> {
        match self {
            Attached::Point(a) => jet.dd_point(i, j, a),
            Attached::Direction(v) => Ok(jet.dd_rotation(i, j)? * *v),
        }
    }

    /// Its value (m or unit vector, lab axes).
    pub fn value(&self, jet: &FrameJet) -> Vector3<f64> {
        match self {
            Attached::Point(a) => jet.point(a),
            Attached::Direction(v) => jet.rotation() * *v,
        }
    }
}

/// One more than the highest local coordinate `frame` maps to, checked against the
/// length `given` of `function`'s argument `argument` (one check per call, so the loops
/// below read without checks of their own).
fn check_local(
    frame: &FrameAt,
    function: &'static str,
    argument: &'static str,
    given: usize,
) -> Result<(), EnergyError> {
    let expected = frame.local.iter().max().map_or(0, |&l| l.saturating_add(1));
    if given < expected {
        return Err(EnergyError::Length {
            function,
            argument,
            expected,
            given,
        });
    }
    Ok(())
}

/// Adds `sign` times the Jacobian of an attached vector over the local coordinates into
/// `columns` (one 3-vector per local coordinate); `columns` shorter than the frame's local
/// coordinates, or a frame whose `local` does not name one index per jet coordinate, is an
/// error (and nothing is added).
pub fn add_jacobian(
    frame: &FrameAt,
    what: Attached,
    sign: f64,
    columns: &mut [Vector3<f64>],
) -> Result<(), EnergyError> {
    check_local(frame, "add_jacobian", "columns", columns.len())?;
    frame.check_jet("add_jacobian", false)?;
    for (i, &l) in frame.local.iter().enumerate() {
        columns[l] += what.first(frame.jet, i)? * sign;
    }
    Ok(())
}

/// Adds Σ_k w_k ∂²v_k/∂q_a∂q_b of an attached vector v into the n × n matrix `h`
/// (row-major): the "gradient times second derivative of the input" half of the chain
/// rule H = Jᵀ H_in J + Σ_k g_k ∇²in_k, with `w` the energy's gradient with respect to v.
/// An `n` that leaves out a local coordinate of the frame, an `h` shorter than n × n, a
/// frame whose `local` does not name one index per jet coordinate, or a first-order jet, is
/// an error (and nothing is added).
pub fn add_curvature(
    frame: &FrameAt,
    what: Attached,
    w: &Vector3<f64>,
    h: &mut [f64],
    n: usize,
) -> Result<(), EnergyError> {
    check_local(frame, "add_curvature", "n", n)?;
    if h.len() < n * n {
        return Err(EnergyError::Length {
            function: "add_curvature",
            argument: "h (n x n, row-major)",
            expected: n * n,
            given: h.len(),
        });
    }
    frame.check_jet("add_curvature", true)?;
    let local = frame.local;
    for (i, &a) in local.iter().enumerate() {
        for (j, &b) in local.iter().enumerate().skip(i) {
            let v = what.second(frame.jet, i, j)?.dot(w);
            h[a * n + b] += v;
            if i != j {
                h[b * n + a] += v;
            }
        }
    }
    Ok(())
}

/// Most energy parts a hyper-dual fallback evaluation handles at once.
pub const MAX_PARTS: usize = 4;

/// The general fallback for energies written over frames: value, gradient and Hessian of
/// every part by one hyper-dual evaluation per pair (i ≤ j) of local coordinates, each with
/// the frames rebuilt from the jets ([`FrameJet::hyper_dual`]) rather than re-evaluated
/// from their pose expressions. `energy` writes the energy of each part. Exact to rounding
/// at any configuration; costs n(n+1)/2 evaluations, so kinds use it where no structure
/// is exact. Needs second-order jets when Hessians are wanted. Returns false (nothing
/// written) for more than [`MAX_PARTS`] parts, frames whose `local` does not name one
/// index per jet coordinate (or first-order jets when Hessians are wanted), or buffers of
/// `out` too short for `parts` parts over `out.n` coordinates.
pub fn hyper_dual_over_frames<const F: usize>(
    at: &JetPoint,
    parts: usize,
    out: &mut Derivatives,
    mut energy: impl FnMut(&[Frame<HyperDual64>; F], &mut [HyperDual64]),
) -> bool {
    if parts > MAX_PARTS || at.frames.len() != F {
        return false;
    }
    // checked once: then every write below is inside its buffer
    let n = out.n;
    let fits = |len: usize, per_part: Option<usize>| {
        per_part
            .and_then(|k| k.checked_mul(parts))
            .is_some_and(|need| len >= need)
    };
    if !fits(out.values.len(), Some(1))
        || !fits(out.gradients.len(), Some(n))
        || (out.hessian && !fits(out.on.len(), n.checked_mul(n)))
    {
        return false;
    }
    // checked once: then every position below is an index the jets have
    let jets_fit = at
        .frames
        .iter()
        .all(|f| f.check_jet("hyper_dual_over_frames", out.hessian).is_ok());
    if !jets_fit {
        return false;
    }
    let mut e = [HyperDual64::from_re(0.0); MAX_PARTS];
    let frames_at = |i: Option<usize>, j: Option<usize>| {
        let mut frames: [Frame<HyperDual64>; F] = std::array::from_fn(|_| Frame::identity());
        for (frame, f) in frames.iter_mut().zip(at.frames) {
            *frame = f
                .jet
                .hyper_dual(i.and_then(|i| f.position(i)), j.and_then(|j| f.position(j)))
                .ok()?;
        }
        Some(frames)
    };
    let Some(frames) = frames_at(None, None) else {
        return false;
    };
    energy(&frames, &mut e[..parts]);
    for (p, v) in e[..parts].iter().enumerate() {
        out.values[p] = v.re;
    }
    for i in 0..n {
        let last = if out.hessian { n } else { i + 1 };
        for j in i..last {
            let Some(frames) = frames_at(Some(i), Some(j)) else {
                return false;
            };
            energy(&frames, &mut e[..parts]);
            for (p, v) in e[..parts].iter().enumerate() {
                if j == i {
                    out.gradients[p * n + i] = v.eps1;
                }
                if out.hessian {
                    let h = &mut out.on[p * n * n..(p + 1) * n * n];
                    h[i * n + j] = v.eps1eps2;
                    h[j * n + i] = v.eps1eps2;
                }
            }
        }
    }
    true
}

/// Most frames a term on the fast path reads (a term with more takes the reference path).
pub const MAX_FRAMES: usize = 4;

/// Calls `f` with the `count` frames `view(0..count)` as a slice on the stack, so that
/// evaluating a term does not allocate; None for more than [`MAX_FRAMES`] frames.
pub fn on_stack<'a, R>(
    count: usize,
    view: impl Fn(usize) -> FrameAt<'a>,
    f: impl FnOnce(&[FrameAt<'a>]) -> R,
) -> Option<R> {
    Some(match count {
        0 => f(&[]),
        1 => f(&[view(0)]),
        2 => f(&[view(0), view(1)]),
        3 => f(&[view(0), view(1), view(2)]),
        4 => f(&[view(0), view(1), view(2), view(3)]),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hyper_dual_fallback_declines_buffers_too_short_for_its_parts() {
        // no frames, so every jet "fits": only the buffers' lengths stand between the
        // routine and writing past them
        let at = JetPoint {
            x: &[0.0, 0.0],
            frames: &[],
        };
        let mut scratch = Scratch::default();
        let (mut values, mut gradients, mut scales, mut on, mut off) = (
            vec![0.0; 1],
            vec![0.0; 3],
            vec![0.0; 4],
            vec![0.0; 7],
            vec![],
        );
        let mut out = Derivatives {
            n: 2,
            hessian: true,
            values: &mut values,
            gradients: &mut gradients,
            force_scales: &mut scales,
            on: &mut on,
            off: &mut off,
            off_form: OffForm::Same,
            scratch: &mut scratch,
        };
        // two parts need 2 values, 4 gradient and 8 Hessian entries
        assert!(!hyper_dual_over_frames::<0>(&at, 2, &mut out, |_, e| {
            e.iter_mut().for_each(|v| *v = HyperDual64::from_re(1.0));
        }));
        assert!(out.values.iter().all(|&v| v == 0.0));
        // one part fits, and is written
        assert!(hyper_dual_over_frames::<0>(&at, 1, &mut out, |_, e| {
            e[0] = HyperDual64::from_re(1.0);
        }));
        assert_eq!(out.values[0], 1.0);
    }
}
