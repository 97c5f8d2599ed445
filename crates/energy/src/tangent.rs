//! Terms whose constants carry their derivative with respect to one parameter: the energy
//! bodies of a model built with that parameter seeded (`System<Dual64>`), differentiated
//! over their coordinates by nested dual numbers, so that every gradient and Hessian entry
//! comes with its exact derivative with respect to the parameter (steps 3 and 4 of
//! docs/exact-sensitivities.md).
//!
//! The coordinates may carry a derivative too (a configuration moving with the parameter,
//! q* + ε δq): then the Hessian's derivative is the total one, the third derivatives of
//! the energy along δq included. The energy bodies are the kinds' own, written once over
//! the scalar and over their constants' type ([`Lift`]), as functions of their bodies'
//! frames, so that a pass along given directions evaluates each body's frame once for all
//! the terms on it ([`tangent_frames`]).

use std::sync::Arc;

use num_dual::{Dual, Dual2, Dual64, HyperDual};
use pendkit_geometry::Frame;
use pendkit_rotations::{Lift, Real};

use crate::{BodyId, EnergyError, LocalFrames, MAX_FRAMES, MAX_PARTS};

/// The scalar of the parameter-derivative Hessian pass: second derivatives over two
/// coordinates, each part carrying its derivative with respect to the parameter.
pub type HyperTangent = HyperDual<Dual64>;

/// The scalar of the parameter-derivative gradient pass.
pub type DualTangent = Dual<Dual64>;

/// The scalar of the parameter-derivative pass along one direction (a mode): the second
/// derivative along it, with its derivative with respect to the parameter.
pub type SecondTangent = Dual2<Dual64>;

/// An energy body whose constants are `Dual64` (a value and its derivative with respect to
/// one parameter), written once over every scalar that can take such constants, as a
/// function of its bodies' frames: so that one evaluation of each body's frame serves
/// every term on it ([`TangentTerm::second_along_frames`]).
pub trait TangentPotential: Send + Sync + 'static {
    /// Potential energy (J) with the term's bodies at `frames` (in the order of its
    /// [`LocalFrames::bodies`]).
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D;
}

/// A [`TangentPotential`] that yields several energies in one evaluation, each that of its
/// own term (see [`crate::SharedPotential`]).
pub trait TangentSharedPotential: Send + Sync + 'static {
    /// Number of energy parts.
    fn parts(&self) -> usize;
    /// The energy (J) of every part with the bodies at `frames`, written into `out`.
    fn energies_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>], out: &mut [D]);
}

/// Object-safe view of the three scalars the passes use.
trait DynTangent: Send + Sync {
    fn value_d(&self, frames: &[&Frame<DualTangent>]) -> DualTangent;
    fn value_d2(&self, frames: &[&Frame<SecondTangent>]) -> SecondTangent;
    fn value_hd(&self, frames: &[&Frame<HyperTangent>]) -> HyperTangent;
}

impl<P: TangentPotential> DynTangent for P {
    fn value_d(&self, frames: &[&Frame<DualTangent>]) -> DualTangent {
        self.energy_on_frames(frames)
    }
    fn value_d2(&self, frames: &[&Frame<SecondTangent>]) -> SecondTangent {
        self.energy_on_frames(frames)
    }
    fn value_hd(&self, frames: &[&Frame<HyperTangent>]) -> HyperTangent {
        self.energy_on_frames(frames)
    }
}

/// One part of a shared body, evaluated whole for each part asked for: a wire's beam is
/// evaluated once for its bending term and once for its extra-stretch term (the beam is
/// about a fifth of the exact sensitivities' time; sharing it would save half of that).
struct PartOf<S> {
    shared: Arc<S>,
    part: usize,
}

impl<S: TangentSharedPotential> PartOf<S> {
    /// This part's energy, all parts evaluated.
    fn value<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        let parts = self.shared.parts();
        if parts <= MAX_PARTS {
            // on the stack: this runs once per term and direction
            let mut out = [D::from(0.0); MAX_PARTS];
            self.shared.energies_on_frames(frames, &mut out[..parts]);
            return out[self.part];
        }
        let mut out = vec![D::from(0.0); parts];
        self.shared.energies_on_frames(frames, &mut out);
        out[self.part]
    }
}

impl<S: TangentSharedPotential> DynTangent for PartOf<S> {
    fn value_d(&self, frames: &[&Frame<DualTangent>]) -> DualTangent {
        self.value(frames)
    }
    fn value_d2(&self, frames: &[&Frame<SecondTangent>]) -> SecondTangent {
        self.value(frames)
    }
    fn value_hd(&self, frames: &[&Frame<HyperTangent>]) -> HyperTangent {
        self.value(frames)
    }
}

/// Value, gradient and Hessian of one term over its own coordinates, each with its
/// derivative with respect to the parameter (the dual part).
#[derive(Clone, Debug, PartialEq)]
pub struct TangentDerivatives {
    /// Energy (J).
    pub value: Dual64,
    /// Gradient, one entry per local coordinate (N or N m).
    pub gradient: Vec<Dual64>,
    /// Hessian, row-major n × n (N/m, N, N m/rad); empty from [`TangentTerm::gradient`].
    pub hessian: Vec<Dual64>,
}

/// One potential-energy term of a model built with one parameter seeded.
#[derive(Clone)]
pub struct TangentTerm {
    /// Human-readable name, e.g. `wire-stretch fibre1`.
    pub label: String,
    /// Kind of element that produced it.
    pub kind: &'static str,
    /// Damping tag (docs/physics.md §2).
    pub tag: String,
    /// Global coordinate indices, in the order of the body's local vector.
    pub coords: Vec<usize>,
    frames: LocalFrames,
    body: Arc<dyn DynTangent>,
}

impl std::fmt::Debug for TangentTerm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TangentTerm")
            .field("label", &self.label)
            .field("kind", &self.kind)
            .field("coords", &self.coords)
            .finish()
    }
}

impl TangentTerm {
    /// Wraps an energy body that reads the frames `frames` (its coordinates are theirs).
    pub fn on_frames<P: TangentPotential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        frames: &LocalFrames,
        body: P,
    ) -> Self {
        TangentTerm {
            label: label.into(),
            kind,
            tag: tag.into(),
            coords: frames.coords.clone(),
            frames: frames.clone(),
            body: Arc::new(body),
        }
    }

    /// A term whose energy is part `part` of a shared body that reads the frames `frames`.
    pub fn part<S: TangentSharedPotential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        frames: &LocalFrames,
        shared: Arc<S>,
        part: usize,
    ) -> Self {
        TangentTerm {
            label: label.into(),
            kind,
            tag: tag.into(),
            coords: frames.coords.clone(),
            frames: frames.clone(),
            body: Arc::new(PartOf { shared, part }),
        }
    }

    /// The bodies the term reads, in the order its energy takes their frames.
    pub fn bodies(&self) -> &[BodyId] {
        &self.frames.bodies
    }

    /// The term's frames at local coordinates `x`, and `f` of them.
    fn on_local_frames<D: Real, R>(&self, x: &[D], f: impl FnOnce(&[&Frame<D>]) -> R) -> R {
        let frames: Vec<Frame<D>> = self.frames.frames.iter().map(|m| m.eval(x)).collect();
        let refs: Vec<&Frame<D>> = frames.iter().collect();
        f(&refs)
    }

    /// `x_global` covers every coordinate of the term.
    fn check_length(&self, function: &'static str, x_global: &[Dual64]) -> Result<(), EnergyError> {
        let expected = self.coords.iter().max().map_or(0, |&i| i + 1);
        if x_global.len() < expected {
            return Err(EnergyError::Length {
                function,
                argument: "x_global (coordinates)",
                expected,
                given: x_global.len(),
            });
        }
        Ok(())
    }

    /// Value and gradient over the term's own coordinates at `x_global`, by one dual
    /// evaluation per coordinate: the gradient's dual parts are its derivatives with respect
    /// to the parameter (at fixed coordinates when `x_global` carries no derivative).
    pub fn gradient(&self, x_global: &[Dual64]) -> Result<TangentDerivatives, EnergyError> {
        self.check_length("TangentTerm::gradient", x_global)?;
        let mut x: Vec<DualTangent> = self
            .coords
            .iter()
            .map(|&i| DualTangent::from_re(x_global[i]))
            .collect();
        let zero = Dual64::from_re(0.0);
        let mut out = TangentDerivatives {
            value: zero,
            gradient: vec![zero; x.len()],
            hessian: Vec::new(),
        };
        for i in 0..x.len() {
            x[i].eps = Dual64::from_re(1.0);
            let r = self.on_local_frames(&x, |f| self.body.value_d(f));
            x[i].eps = zero;
            out.value = r.re;
            out.gradient[i] = r.eps;
        }
        if x.is_empty() {
            out.value = self.on_local_frames(&x, |f| self.body.value_d(f)).re;
        }
        Ok(out)
    }

    /// The second derivative uᵀ H v of the energy along two directions u, v, given every
    /// body's frame at x + ε₁u + ε₂v (`frames`, indexed by body, as [`tangent_frames`]
    /// gives them): its value part, with its derivative with respect to the parameter
    /// along the coordinates' own derivative in the dual part. One evaluation of each
    /// body's frame serves every term on it.
    pub fn second_along_frames(
        &self,
        frames: &[Frame<HyperTangent>],
    ) -> Result<Dual64, EnergyError> {
        self.with_frames(frames, |mine| self.body.value_hd(mine).eps1eps2)
    }

    /// [`TangentTerm::second_along_frames`] with u = v, given every body's frame at x + εu
    /// ([`tangent_frames_along`]): uᵀ H u by the cheaper second-order dual number.
    pub fn second_along_frames_once(
        &self,
        frames: &[Frame<SecondTangent>],
    ) -> Result<Dual64, EnergyError> {
        self.with_frames(frames, |mine| self.body.value_d2(mine).v2)
    }

    /// `f` of the frames of the term's bodies picked out of every body's `frames`, without
    /// copying or allocating (this runs once per term and direction).
    fn with_frames<T, R>(
        &self,
        frames: &[Frame<T>],
        f: impl FnOnce(&[&Frame<T>]) -> R,
    ) -> Result<R, EnergyError> {
        let bodies = &self.frames.bodies;
        let missing = |index: usize| EnergyError::Index {
            item: format!("term '{}'", self.label),
            what: "body (frames given)",
            index,
            len: frames.len(),
        };
        let Some(&first) = bodies.first() else {
            return Ok(f(&[]));
        };
        if bodies.len() > MAX_FRAMES {
            return Err(missing(bodies[MAX_FRAMES]));
        }
        let mut mine = [frames.get(first).ok_or_else(|| missing(first))?; MAX_FRAMES];
        for (slot, &b) in mine.iter_mut().zip(bodies) {
            *slot = frames.get(b).ok_or_else(|| missing(b))?;
        }
        Ok(f(&mine[..bodies.len()]))
    }

    /// Value, gradient and Hessian over the term's own coordinates at `x_global`, by one
    /// nested hyper-dual evaluation per entry of the upper triangle; each entry's dual part
    /// is its derivative with respect to the parameter along the coordinates' own
    /// derivative.
    pub fn derivatives(&self, x_global: &[Dual64]) -> Result<TangentDerivatives, EnergyError> {
        self.check_length("TangentTerm::derivatives", x_global)?;
        let n = self.coords.len();
        let mut x: Vec<HyperTangent> = self
            .coords
            .iter()
            .map(|&i| HyperTangent::from_re(x_global[i]))
            .collect();
        let (zero, one) = (Dual64::from_re(0.0), Dual64::from_re(1.0));
        let mut out = TangentDerivatives {
            value: self.on_local_frames(&x, |f| self.body.value_hd(f)).re,
            gradient: vec![zero; n],
            hessian: vec![zero; n * n],
        };
        for i in 0..n {
            x[i].eps1 = one;
            for j in i..n {
                x[j].eps2 = one;
                let r = self.on_local_frames(&x, |f| self.body.value_hd(f));
                x[j].eps2 = zero;
                if j == i {
                    out.gradient[i] = r.eps1;
                }
                out.hessian[i * n + j] = r.eps1eps2;
                out.hessian[j * n + i] = r.eps1eps2;
            }
            x[i].eps1 = zero;
        }
        Ok(out)
    }
}

/// Every body's frame of `system` at x + ε₁u + ε₂v, `x` carrying its own parameter
/// derivative and `u`, `v` full coordinate vectors: the frames
/// [`TangentTerm::second_along_frames`] reads. A vector shorter than the coordinates is an
/// error naming it.
pub fn tangent_frames<S: Real>(
    system: &crate::System<S>,
    x: &[Dual64],
    u: &[f64],
    v: &[f64],
) -> Result<Vec<Frame<HyperTangent>>, EnergyError> {
    let zero = Dual64::from_re(0.0);
    frames_at(
        system,
        [("x", x.len()), ("u", u.len()), ("v", v.len())],
        |i| HyperTangent::new(x[i], Dual64::from_re(u[i]), Dual64::from_re(v[i]), zero),
    )
}

/// Every body's frame of `system` at x + εu: the frames
/// [`TangentTerm::second_along_frames_once`] reads.
pub fn tangent_frames_along<S: Real>(
    system: &crate::System<S>,
    x: &[Dual64],
    u: &[f64],
) -> Result<Vec<Frame<SecondTangent>>, EnergyError> {
    let zero = Dual64::from_re(0.0);
    frames_at(system, [("x", x.len()), ("u", u.len())], |i| {
        SecondTangent::new(x[i], Dual64::from_re(u[i]), zero)
    })
}

/// Every body's frame at the coordinates `seed(i)`, after checking that each named vector
/// covers the coordinates.
fn frames_at<S: Real, T: Real, const K: usize>(
    system: &crate::System<S>,
    lengths: [(&'static str, usize); K],
    seed: impl Fn(usize) -> T,
) -> Result<Vec<Frame<T>>, EnergyError> {
    let n = system.coords.len();
    if let Some(&(argument, given)) = lengths.iter().find(|(_, given)| *given < n) {
        return Err(EnergyError::Length {
            function: "tangent_frames",
            argument,
            expected: n,
            given,
        });
    }
    let at: Vec<T> = (0..n).map(seed).collect();
    Ok(system.bodies.iter().map(|b| b.frame.eval(&at)).collect())
}
