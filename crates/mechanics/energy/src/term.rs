//! Potential-energy terms: one generic energy body per term, wrapped so that a list of
//! terms of different kinds can be differentiated over each term's own coordinates.
//!
//! Two derivative paths exist. The reference path differentiates the generic energy body
//! by hyper-dual numbers, one evaluation per entry of the Hessian's upper triangle; every
//! element gets it from its energy alone. The fast path is optional: an element that knows
//! the structure of its energy differentiates it with respect to its few geometric inputs
//! (attachment points, directions, frames) and assembles the Hessian by the chain rule from
//! frame jets computed once per body ([`crate::JetPoint`]). Both paths must agree to
//! rounding; the workspace tests check every bundled kind.

use std::sync::Arc;

use num_dual::HyperDual64;
use pendkit_geometry::{FrameJet, JetOrder};
use pendkit_rotations::Real;

use crate::fast::{Derivatives, FrameAt, JetPoint, OffForm, Scratch, on_stack};
use crate::{EnergyError, LocalFrames};

/// The energy of one term as a function of its own (local) coordinate vector, written once
/// for every scalar type.
pub trait Potential: Send + Sync + 'static {
    /// Potential energy (J) at local coordinates `x` (m or rad).
    fn energy<D: Real>(&self, x: &[D]) -> D;

    /// The term with static tensions and preloads switched off (stage 0B, docs/physics.md §2),
    /// given the equilibrium local coordinates. The default keeps the term as it is: all of
    /// its stiffness comes from first-order deformation and so carries its loss.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self>
    where
        Self: Sized,
    {
        TensionOff::Unchanged
    }

    /// Optional fast path: value, gradient (and, if asked, the Hessians with the tension on
    /// and off) at `at`, from the frame jets of the term's bodies (see [`Derivatives`] for
    /// the outputs). The tension-off Hessian is that of `tension_off` built at the
    /// evaluation point. Returns false when it cannot (the reference path is then used);
    /// the default always does. Only terms built with [`Term::on_frames`] get jets.
    fn fast_derivatives(&self, _at: &JetPoint, _out: &mut Derivatives) -> bool {
        false
    }
}

/// An energy body that yields several energies in one evaluation, each the energy of its
/// own term (possibly of different element kinds): the beam of a wire gives its bending
/// strain energy (one kind, stage 1B) and its work against tension (another kind, stage 2).
/// Terms share it through [`crate::SharedBodies`], and the assembly evaluates each shared
/// body once for all of its terms.
pub trait SharedPotential: Send + Sync + 'static {
    /// Number of energy parts.
    fn parts(&self) -> usize;

    /// The energy (J) of every part at local coordinates `x`, written into `out`
    /// (`out.len() == parts()`).
    fn energies<D: Real>(&self, x: &[D], out: &mut [D]);

    /// Optional fast path for every part at once (see [`Potential::fast_derivatives`];
    /// tension-off forms are fixed per part by [`Term::part`] and not written here).
    fn fast_derivatives(&self, _at: &JetPoint, _out: &mut Derivatives) -> bool {
        false
    }
}

/// What a term becomes when static tensions are switched off.
#[derive(Clone, Debug)]
pub enum TensionOff<P> {
    /// Nothing depends on tension: the whole stiffness is lossy (bending, springs without
    /// preload, user terms).
    Unchanged,
    /// The term is pure work against a static load: the whole stiffness is lossless
    /// (gravity, wire extra stretch).
    Vanishes,
    /// A different term (a wire with l0 set to its equilibrium length, a spring without
    /// preload).
    Replaced(P),
}

/// The tension-off form of one part of a shared body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartOff {
    /// All of the part's stiffness is lossy.
    Unchanged,
    /// All of the part's stiffness is lossless.
    Vanishes,
}

/// Object-safe view of a [`Potential`]: the two scalar types the reference path uses
/// (values and hyper-dual second derivatives), so the set behind the trait object stays
/// short, and the fast path. The hyper-dual path is the one every kind has; where a kind
/// has a fast path it pays: `cargo bench -p pendkit-benches --bench scalars -- hessian-f64`,
/// the quad's stage-2 terms 9.8× faster (median of three runs, 8.8–17×) than by
/// hyper-dual numbers.
trait DynPotential: Send + Sync {
    fn value(&self, x: &[f64]) -> f64;
    fn value_hd(&self, x: &[HyperDual64]) -> HyperDual64;
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Arc<dyn DynPotential>>;
    fn fast(&self, at: &JetPoint, out: &mut Derivatives) -> bool;
}

impl<P: Potential> DynPotential for P {
    fn value(&self, x: &[f64]) -> f64 {
        self.energy(x)
    }
    fn value_hd(&self, x: &[HyperDual64]) -> HyperDual64 {
        self.energy(x)
    }
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Arc<dyn DynPotential>> {
        match Potential::tension_off(self, x_eq) {
            TensionOff::Unchanged => TensionOff::Unchanged,
            TensionOff::Vanishes => TensionOff::Vanishes,
            TensionOff::Replaced(p) => TensionOff::Replaced(Arc::new(p)),
        }
    }
    fn fast(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        self.fast_derivatives(at, out)
    }
}

/// Object-safe view of a [`SharedPotential`].
trait DynShared: Send + Sync {
    fn parts(&self) -> usize;
    fn values(&self, x: &[f64], out: &mut [f64]);
    fn values_hd(&self, x: &[HyperDual64], out: &mut [HyperDual64]);
    fn fast(&self, at: &JetPoint, out: &mut Derivatives) -> bool;
}

impl<S: SharedPotential> DynShared for S {
    fn parts(&self) -> usize {
        SharedPotential::parts(self)
    }
    fn values(&self, x: &[f64], out: &mut [f64]) {
        self.energies(x, out)
    }
    fn values_hd(&self, x: &[HyperDual64], out: &mut [HyperDual64]) {
        self.energies(x, out)
    }
    fn fast(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        self.fast_derivatives(at, out)
    }
}

/// A term's energy body: its own, or one part of a shared one.
#[derive(Clone)]
enum Body {
    Own(Arc<dyn DynPotential>),
    Part {
        shared: Arc<dyn DynShared>,
        part: usize,
        off: PartOff,
    },
}

impl Body {
    fn value(&self, x: &[f64]) -> f64 {
        match self {
            Body::Own(p) => p.value(x),
            Body::Part { shared, part, .. } => {
                let mut e = vec![0.0; shared.parts()];
                shared.values(x, &mut e);
                e[*part]
            }
        }
    }

    fn value_hd(&self, x: &[HyperDual64], parts: &mut Vec<HyperDual64>) -> HyperDual64 {
        match self {
            Body::Own(p) => p.value_hd(x),
            Body::Part { shared, part, .. } => {
                parts.clear();
                parts.resize(shared.parts(), HyperDual64::from_re(0.0));
                shared.values_hd(x, parts);
                parts[*part]
            }
        }
    }
}

/// Value, gradient and Hessian of one term over its own coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalDerivatives {
    /// Energy (J).
    pub value: f64,
    /// Gradient, one entry per local coordinate (N or N m).
    pub gradient: Vec<f64>,
    /// Hessian, row-major n × n (N/m, N, N m/rad).
    pub hessian: Vec<f64>,
}

/// The tension-off part of one term's Hessian (docs/physics.md §2).
#[derive(Clone, Debug, PartialEq)]
pub enum OffHessian {
    /// Equal to the tension-on Hessian: all of the term's stiffness is lossy.
    Same,
    /// Zero: all of the term's stiffness is lossless.
    Zero,
    /// A different matrix (row-major, over the term's coordinates).
    Matrix(Vec<f64>),
}

/// Buffers for evaluating single terms outside an assembly (layout of [`Derivatives`]),
/// kept per thread so that repeated calls do not allocate for their workings.
#[derive(Default)]
struct Buffers {
    x: Vec<f64>,
    jets: Vec<FrameJet>,
    values: Vec<f64>,
    gradients: Vec<f64>,
    scales: Vec<f64>,
    on: Vec<f64>,
    off: Vec<f64>,
    scratch: Scratch,
}

thread_local! {
    static STANDALONE: std::cell::RefCell<Buffers> = std::cell::RefCell::new(Buffers::default());
}

/// One potential-energy term: an energy body, the global coordinates it reads, a damping
/// tag and a name for reports.
#[derive(Clone)]
pub struct Term {
    /// Human-readable name, e.g. `wire-stretch fibre1`.
    pub label: String,
    /// Kind of element that produced it, e.g. `wire-stretch`.
    pub kind: &'static str,
    /// Damping tag (docs/physics.md §2).
    pub tag: String,
    /// Global coordinate indices, in the order of the body's local vector.
    pub coords: Vec<usize>,
    body: Body,
    frames: Option<Arc<LocalFrames>>,
}

impl std::fmt::Debug for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Term")
            .field("label", &self.label)
            .field("kind", &self.kind)
            .field("tag", &self.tag)
            .field("coords", &self.coords)
            .finish()
    }
}

impl Term {
    /// Wraps an energy body that reads the global coordinates `coords` (in order).
    pub fn new<P: Potential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        coords: Vec<usize>,
        body: P,
    ) -> Self {
        Term {
            label: label.into(),
            kind,
            tag: tag.into(),
            coords,
            body: Body::Own(Arc::new(body)),
            frames: None,
        }
    }

    /// Wraps an energy body that reads the frames `frames` (its coordinates are theirs):
    /// the fast path then gets the frames' jets, in this order.
    pub fn on_frames<P: Potential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        frames: impl Into<Arc<LocalFrames>>,
        body: P,
    ) -> Self {
        let frames = frames.into();
        Term {
            coords: frames.coords.clone(),
            frames: Some(frames),
            ..Term::new(label, kind, tag, Vec::new(), body)
        }
    }

    /// A term whose energy is part `part` of a shared body that reads the frames `frames`,
    /// with the tension-off form `off`; a part the body does not have is an error.
    pub fn part<S: SharedPotential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        frames: Arc<LocalFrames>,
        shared: Arc<S>,
        part: usize,
        off: PartOff,
    ) -> Result<Self, EnergyError> {
        let label = label.into();
        crate::check_part(&label, part, shared.parts())?;
        Ok(Term {
            label,
            kind,
            tag: tag.into(),
            coords: frames.coords.clone(),
            body: Body::Part { shared, part, off },
            frames: Some(frames),
        })
    }

    /// The frames the term reads, when it was built on them.
    pub fn frames(&self) -> Option<&LocalFrames> {
        self.frames.as_deref()
    }

    /// Identity of the term's energy body (equal for terms that share one), the number of
    /// energy parts it yields, and this term's part.
    pub fn body_parts(&self) -> (usize, usize, usize) {
        match &self.body {
            Body::Own(p) => (Arc::as_ptr(p) as *const () as usize, 1, 0),
            Body::Part { shared, part, .. } => (
                Arc::as_ptr(shared) as *const () as usize,
                shared.parts(),
                *part,
            ),
        }
    }

    /// The shortest full coordinate vector the term can read: one more than its highest
    /// global coordinate index.
    pub fn needs(&self) -> usize {
        self.coords.iter().max().map_or(0, |&i| i.saturating_add(1))
    }

    /// `x_global`, the argument of `function`, covers every coordinate of the term: checked
    /// once at each public entry so that the reads below need no checks.
    fn check_length(&self, function: &'static str, x_global: &[f64]) -> Result<(), EnergyError> {
        let expected = self.needs();
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

    /// The term's coordinates picked out of `x_global`, which covers them.
    fn gather(&self, x_global: &[f64]) -> Vec<f64> {
        self.coords.iter().map(|&i| x_global[i]).collect()
    }

    /// This term's coordinates picked out of a full coordinate vector.
    pub fn local(&self, x_global: &[f64]) -> Result<Vec<f64>, EnergyError> {
        self.check_length("Term::local", x_global)?;
        Ok(self.gather(x_global))
    }

    /// Energy (J) at the full coordinate vector `x_global`.
    pub fn energy(&self, x_global: &[f64]) -> Result<f64, EnergyError> {
        self.check_length("Term::energy", x_global)?;
        Ok(self.body.value(&self.gather(x_global)))
    }

    /// Value, gradient and Hessian over the term's own coordinates, at the full coordinate
    /// vector `x_global`, by one hyper-dual evaluation per entry of the upper triangle: the
    /// reference every fast path is checked against.
    pub fn reference_derivatives(&self, x_global: &[f64]) -> Result<LocalDerivatives, EnergyError> {
        self.check_length("Term::reference_derivatives", x_global)?;
        Ok(self.reference_at(x_global))
    }

    /// [`Term::reference_derivatives`] at an `x_global` that covers the term.
    fn reference_at(&self, x_global: &[f64]) -> LocalDerivatives {
        let n = self.coords.len();
        let mut x: Vec<HyperDual64> = self
            .coords
            .iter()
            .map(|&i| HyperDual64::from_re(x_global[i]))
            .collect();
        let mut parts = Vec::new();
        let mut out = LocalDerivatives {
            value: self.body.value(&self.gather(x_global)),
            gradient: vec![0.0; n],
            hessian: vec![0.0; n * n],
        };
        for i in 0..n {
            x[i].eps1 = 1.0;
            for j in i..n {
                x[j].eps2 = 1.0;
                let r = self.body.value_hd(&x, &mut parts);
                x[j].eps2 = 0.0;
                if j == i {
                    out.gradient[i] = r.eps1;
                }
                out.hessian[i * n + j] = r.eps1eps2;
                out.hessian[j * n + i] = r.eps1eps2;
            }
            x[i].eps1 = 0.0;
        }
        out
    }

    /// Value, gradient and Hessian over the term's own coordinates at `x_global`: by the
    /// term's fast path when it has one (computing its frames' jets here), otherwise by
    /// [`Term::reference_derivatives`].
    pub fn derivatives(&self, x_global: &[f64]) -> Result<LocalDerivatives, EnergyError> {
        self.check_length("Term::derivatives", x_global)?;
        let (n, part) = (self.coords.len(), self.body_parts().2);
        Ok(self
            .standalone_fast(x_global, |b, _| LocalDerivatives {
                value: b.values[part],
                gradient: b.gradients[part * n..(part + 1) * n].to_vec(),
                hessian: b.on[part * n * n..(part + 1) * n * n].to_vec(),
            })
            .unwrap_or_else(|| self.reference_at(x_global)))
    }

    /// Hessians with the tension on and off at `x_global`, the off term built there, by
    /// the fast path (`fast`) when the term has one, or by the reference path.
    pub fn hessians(
        &self,
        x_global: &[f64],
        fast: bool,
    ) -> Result<(Vec<f64>, OffHessian), EnergyError> {
        self.check_length("Term::hessians", x_global)?;
        let (n, part) = (self.coords.len(), self.body_parts().2);
        let read = |b: &Buffers, form: OffForm| {
            let on = b.on[part * n * n..(part + 1) * n * n].to_vec();
            let off = match self.part_off().map_or(form, |p| match p {
                PartOff::Unchanged => OffForm::Same,
                PartOff::Vanishes => OffForm::Zero,
            }) {
                OffForm::Same => OffHessian::Same,
                OffForm::Zero => OffHessian::Zero,
                OffForm::Written => OffHessian::Matrix(b.off.clone()),
            };
            (on, off)
        };
        if fast && let Some(result) = self.standalone_fast(x_global, read) {
            return Ok(result);
        }
        let off = match self.off_at(x_global) {
            TensionOff::Unchanged => OffHessian::Same,
            TensionOff::Vanishes => OffHessian::Zero,
            TensionOff::Replaced(t) => OffHessian::Matrix(t.reference_at(x_global).hessian),
        };
        Ok((self.reference_at(x_global).hessian, off))
    }

    /// The tension-off form of a shared body's part (None for a term with its own body).
    pub fn part_off(&self) -> Option<PartOff> {
        match &self.body {
            Body::Own(_) => None,
            Body::Part { off, .. } => Some(*off),
        }
    }

    /// The fast path at `at` for the term's whole body (every part of a shared body);
    /// false when the body has none.
    pub fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        match &self.body {
            Body::Own(p) => p.fast(at, out),
            Body::Part { shared, .. } => shared.fast(at, out),
        }
    }

    /// The fast path outside an assembly: the term's frames' jets over its local
    /// coordinates, then [`Term::fast_derivatives`] with both Hessians, into this thread's
    /// reusable buffers, from which `read` takes what it needs (layout of [`Derivatives`]).
    /// None when the term has no fast path.
    fn standalone_fast<R>(
        &self,
        x_global: &[f64],
        read: impl FnOnce(&Buffers, OffForm) -> R,
    ) -> Option<R> {
        let frames = self.frames.as_deref()?;
        STANDALONE.with(|cell| {
            let mut fresh = Buffers::default();
            let mut borrowed = cell.try_borrow_mut();
            let b: &mut Buffers = match borrowed.as_deref_mut() {
                Ok(b) => b,
                Err(_) => &mut fresh,
            };
            let (n, parts) = (self.coords.len(), self.body_parts().1);
            b.x.clear();
            b.x.extend(self.coords.iter().map(|&i| x_global[i]));
            b.jets.resize_with(frames.frames.len(), FrameJet::new);
            for (f, jet) in frames.frames.iter().zip(b.jets.iter_mut()) {
                // the local frames read the local vector, which covers them by construction
                f.jet(&b.x, JetOrder::Second, jet).ok()?;
            }
            for (v, len) in [
                (&mut b.values, parts),
                (&mut b.gradients, parts * n),
                (&mut b.scales, parts * n),
                (&mut b.on, parts * n * n),
                (&mut b.off, n * n),
            ] {
                v.clear();
                v.resize(len, 0.0);
            }
            let mut out = Derivatives {
                n,
                hessian: true,
                values: &mut b.values,
                gradients: &mut b.gradients,
                force_scales: &mut b.scales,
                on: &mut b.on,
                off: &mut b.off,
                off_form: OffForm::Same,
                scratch: &mut b.scratch,
            };
            // the jets of the local frames read the local vector directly
            let jets = &b.jets;
            let view = |k: usize| FrameAt {
                jet: &jets[k],
                local: jets[k].vars(),
            };
            let done = on_stack(jets.len(), view, |frames| {
                self.fast_derivatives(&JetPoint { x: &b.x, frames }, &mut out)
            });
            let off_form = out.off_form;
            (done == Some(true)).then(|| read(b, off_form))
        })
    }

    /// The term with static tensions switched off, at the equilibrium `x_eq_global`.
    pub fn tension_off(&self, x_eq_global: &[f64]) -> Result<TensionOff<Term>, EnergyError> {
        self.check_length("Term::tension_off", x_eq_global)?;
        Ok(self.off_at(x_eq_global))
    }

    /// [`Term::tension_off`] at an `x_eq_global` that covers the term.
    fn off_at(&self, x_eq_global: &[f64]) -> TensionOff<Term> {
        let replaced = match &self.body {
            Body::Part { off, .. } => {
                return match off {
                    PartOff::Unchanged => TensionOff::Unchanged,
                    PartOff::Vanishes => TensionOff::Vanishes,
                };
            }
            Body::Own(p) => match p.tension_off(&self.gather(x_eq_global)) {
                TensionOff::Unchanged => return TensionOff::Unchanged,
                TensionOff::Vanishes => return TensionOff::Vanishes,
                TensionOff::Replaced(body) => body,
            },
        };
        TensionOff::Replaced(Term {
            label: self.label.clone(),
            kind: self.kind,
            tag: self.tag.clone(),
            coords: self.coords.clone(),
            body: Body::Own(replaced),
            frames: self.frames.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = a x² y + sin(x) y³, with a known gradient and Hessian.
    struct Cubic {
        a: f64,
    }

    impl Potential for Cubic {
        fn energy<D: Real>(&self, x: &[D]) -> D {
            x[0] * x[0] * x[1] * self.a + x[0].sin() * x[1].powi(3)
        }
    }

    #[test]
    fn derivatives_match_closed_form() {
        let t = Term::new("cubic", "test", "none", vec![2, 0], Cubic { a: 1.5 });
        // local (x, y) = (global[2], global[0])
        let (x, y) = (0.3, -0.7);
        let d = t.derivatives(&[y, 99.0, x]).unwrap();
        assert_eq!(d, t.reference_derivatives(&[y, 99.0, x]).unwrap());
        let a = 1.5;
        let g = [
            2.0 * a * x * y + x.cos() * y.powi(3),
            a * x * x + 3.0 * x.sin() * y * y,
        ];
        let h = [
            2.0 * a * y - x.sin() * y.powi(3),
            2.0 * a * x + 3.0 * x.cos() * y * y,
            2.0 * a * x + 3.0 * x.cos() * y * y,
            6.0 * x.sin() * y,
        ];
        assert!((d.value - (a * x * x * y + x.sin() * y.powi(3))).abs() < 1e-15);
        for (got, want) in d.gradient.iter().zip(g).chain(d.hessian.iter().zip(h)) {
            assert!((got - want).abs() < 1e-14);
        }
    }

    /// Two parts of one body: x² and x y.
    struct TwoParts;

    impl SharedPotential for TwoParts {
        fn parts(&self) -> usize {
            2
        }
        fn energies<D: Real>(&self, x: &[D], out: &mut [D]) {
            out[0] = x[0] * x[0];
            out[1] = x[0] * x[1];
        }
    }

    #[test]
    fn parts_of_a_shared_body_are_their_own_terms() {
        let frames = Arc::new(LocalFrames {
            coords: vec![0, 1],
            ..LocalFrames::default()
        });
        let body = Arc::new(TwoParts);
        let square = Term::part(
            "sq",
            "a",
            "t",
            frames.clone(),
            body.clone(),
            0,
            PartOff::Unchanged,
        )
        .unwrap();
        let product = Term::part(
            "xy",
            "b",
            "t",
            frames.clone(),
            body.clone(),
            1,
            PartOff::Vanishes,
        )
        .unwrap();
        // a part the body does not have is refused when the term is made
        let e = Term::part("z", "c", "t", frames, body, 2, PartOff::Vanishes).unwrap_err();
        assert_eq!(
            e.to_string(),
            "term 'z': energy part index 2 is out of range (the system has 2)"
        );
        let x = [2.0, 3.0];
        assert_eq!(square.energy(&x), Ok(4.0));
        assert_eq!(product.energy(&x), Ok(6.0));
        assert_eq!(
            product.reference_derivatives(&x).unwrap().hessian,
            vec![0.0, 1.0, 1.0, 0.0]
        );
        assert_eq!(square.body_parts().0, product.body_parts().0);
        assert!(matches!(product.tension_off(&x), Ok(TensionOff::Vanishes)));
        assert!(matches!(
            square.hessians(&x, true).unwrap().1,
            OffHessian::Same
        ));
    }
}
