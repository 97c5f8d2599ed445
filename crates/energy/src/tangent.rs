//! Terms whose constants carry their derivative with respect to one parameter: the energy
//! bodies of a model built with that parameter seeded (`System<Dual64>`), differentiated
//! over their coordinates by nested dual numbers, so that every gradient and Hessian entry
//! comes with its exact derivative with respect to the parameter (steps 3 and 4 of
//! docs/exact-sensitivities.md).
//!
//! The coordinates may carry a derivative too (a configuration moving with the parameter,
//! q* + ε δq): then the Hessian's derivative is the total one, the third derivatives of
//! the energy along δq included. The energy bodies are the kinds' own, written once over
//! the scalar and over their constants' type ([`Lift`]); a term whose constants do not
//! depend on the parameter (a user's expression, a constraint spring) is evaluated as it
//! is ([`TangentTerm::fixed`]).

use std::sync::Arc;

use num_dual::{Dual, Dual64, HyperDual};
use pendkit_rotations::Lift;

use crate::{EnergyError, LocalFrames, Term};

/// The scalar of the parameter-derivative Hessian pass: second derivatives over two
/// coordinates, each part carrying its derivative with respect to the parameter.
pub type HyperTangent = HyperDual<Dual64>;

/// The scalar of the parameter-derivative gradient pass.
pub type DualTangent = Dual<Dual64>;

/// An energy body whose constants are `Dual64` (a value and its derivative with respect to
/// one parameter), written once over every scalar that can take such constants.
pub trait TangentPotential: Send + Sync + 'static {
    /// Potential energy (J) at local coordinates `x` (m or rad).
    fn energy<D: Lift<Dual64>>(&self, x: &[D]) -> D;
}

/// A [`TangentPotential`] that yields several energies in one evaluation, each that of its
/// own term (see [`crate::SharedPotential`]).
pub trait TangentSharedPotential: Send + Sync + 'static {
    /// Number of energy parts.
    fn parts(&self) -> usize;
    /// The energy (J) of every part at local coordinates `x`, written into `out`.
    fn energies<D: Lift<Dual64>>(&self, x: &[D], out: &mut [D]);
}

/// Object-safe view of the two scalars the passes use.
trait DynTangent: Send + Sync {
    fn value_d(&self, x: &[DualTangent]) -> DualTangent;
    fn value_hd(&self, x: &[HyperTangent]) -> HyperTangent;
}

impl<P: TangentPotential> DynTangent for P {
    fn value_d(&self, x: &[DualTangent]) -> DualTangent {
        self.energy(x)
    }
    fn value_hd(&self, x: &[HyperTangent]) -> HyperTangent {
        self.energy(x)
    }
}

/// One part of a shared body, evaluated whole for each entry (the passes are for
/// sensitivities, where a second evaluation of a wire's beam costs little).
struct PartOf<S> {
    shared: Arc<S>,
    part: usize,
}

impl<S: TangentSharedPotential> DynTangent for PartOf<S> {
    fn value_d(&self, x: &[DualTangent]) -> DualTangent {
        let mut out = vec![DualTangent::from_re(Dual64::from_re(0.0)); self.shared.parts()];
        self.shared.energies(x, &mut out);
        out[self.part]
    }
    fn value_hd(&self, x: &[HyperTangent]) -> HyperTangent {
        let mut out = vec![HyperTangent::from_re(Dual64::from_re(0.0)); self.shared.parts()];
        self.shared.energies(x, &mut out);
        out[self.part]
    }
}

/// A term of constants that do not depend on the parameter, evaluated with them as they are.
struct Fixed(Term);

impl DynTangent for Fixed {
    fn value_d(&self, x: &[DualTangent]) -> DualTangent {
        self.0.value_dual_tangent(x)
    }
    fn value_hd(&self, x: &[HyperTangent]) -> HyperTangent {
        self.0.value_hyper_tangent(x)
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
            body: Arc::new(PartOf { shared, part }),
        }
    }

    /// A term whose constants do not depend on the parameter (a user's expression, a
    /// constraint spring), evaluated as it is.
    pub fn fixed(term: Term) -> Self {
        TangentTerm {
            label: term.label.clone(),
            kind: term.kind,
            tag: term.tag.clone(),
            coords: term.coords.clone(),
            body: Arc::new(Fixed(term)),
        }
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
            let r = self.body.value_d(&x);
            x[i].eps = zero;
            out.value = r.re;
            out.gradient[i] = r.eps;
        }
        if x.is_empty() {
            out.value = self.body.value_d(&x).re;
        }
        Ok(out)
    }

    /// The second derivative uᵀ H v of the energy along two directions `u`, `v` (full
    /// coordinate vectors, read on the term's coordinates) at `x_global`, by one nested
    /// hyper-dual evaluation, with its derivative with respect to the parameter along the
    /// coordinates' own derivative.
    pub fn second_along(
        &self,
        x_global: &[Dual64],
        u: &[f64],
        v: &[f64],
    ) -> Result<Dual64, EnergyError> {
        self.check_length("TangentTerm::second_along", x_global)?;
        let short = u.len().min(v.len());
        if let Some(&needed) = self.coords.iter().find(|&&i| i >= short) {
            return Err(EnergyError::Length {
                function: "TangentTerm::second_along",
                argument: "u, v (directions)",
                expected: needed + 1,
                given: short,
            });
        }
        let x: Vec<HyperTangent> = self
            .coords
            .iter()
            .map(|&i| {
                let (du, dv) = (Dual64::from_re(u[i]), Dual64::from_re(v[i]));
                HyperTangent::new(x_global[i], du, dv, Dual64::from_re(0.0))
            })
            .collect();
        Ok(self.body.value_hd(&x).eps1eps2)
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
            value: self.body.value_hd(&x).re,
            gradient: vec![zero; n],
            hessian: vec![zero; n * n],
        };
        for i in 0..n {
            x[i].eps1 = one;
            for j in i..n {
                x[j].eps2 = one;
                let r = self.body.value_hd(&x);
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
