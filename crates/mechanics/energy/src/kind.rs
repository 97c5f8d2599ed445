//! One contract per element kind that owns instances: the kind writes its schema and one
//! energy function over its bodies' frames, generic over the scalar ([`InstanceKind`]);
//! [`KindElement`] turns that into an [`Element`] with every derivative path the assembly
//! and the sensitivities use (the reference path by hyper-dual numbers, the fast path from
//! frame jets, the tangent forms with parameter derivatives, the tension-off form), and
//! [`check_fast_path`] checks a kind's optional hand-written fast path against the generic
//! form. The minimal kind is `elements/point-spring`; docs/elements.md is the tutorial.

use std::fmt::Debug;
use std::marker::PhantomData;

use nalgebra::Vector3;
use num_dual::{Dual64, HyperDual64};
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Constant, Lift, Real};

use crate::{
    Derivatives, Element, EnergyError, InstanceSchema, JetPoint, LocalFrames, OffForm, OffHessian,
    PartOff, PluginElement, Potential, Reference, SharedBodies, Stage, TangentPotential,
    TangentTerm, TensionOff, Term, hyper_dual_over_frames,
};

/// An element kind whose terms come from instances (`[[element]]` in a suspension file):
/// what it is, what an instance needs, and its energy. Register it with
/// [`register_kind!`](crate::register_kind).
pub trait InstanceKind: Send + Sync + 'static {
    /// The kind's name, as files write it (`point-spring`).
    const KIND: &'static str;
    /// The stage at which its terms join the calculation: [`Stage::S0A`] to take part in
    /// the equilibrium (its reference is then the model's start), a later one to be built
    /// around the equilibrium.
    const STAGE: Stage;
    /// One line saying what the kind models.
    const SUMMARY: &'static str;
    /// What an instance needs; every instance is checked against it before any term is
    /// built, so [`InstanceKind::instance`] reads the values unchecked.
    const SCHEMA: InstanceSchema;
    /// What becomes of the kind's stiffness with static tensions off (stage 0B,
    /// docs/physics.md §2): `Unchanged`, all of it is lossy and carries the instance tag's
    /// loss (a spring); `Vanishes`, all of it is lossless (radiation pressure).
    const TENSION_OFF: PartOff = PartOff::Unchanged;

    /// What one instance keeps between evaluations: its values and whatever it computes
    /// once from the reference configuration, with the model's numbers as `C` (`f64`, or
    /// `Dual64` carrying their derivatives with respect to one parameter).
    type Instance<C: Constant>: Clone + Debug + Send + Sync + 'static;

    /// The instance `at.element`, built around the reference configuration. It may read
    /// only what `at` offers (the instance and its bodies' reference frames): that is how
    /// the sensitivities know when it moves with a parameter.
    fn instance<C: Constant>(at: &InstanceAt<'_, C>) -> Self::Instance<C>;

    /// Potential energy (J) of `instance` with its bodies at `frames` (in `between` order).
    fn energy<C: Constant, D: Lift<C>>(instance: &Self::Instance<C>, frames: &[&Frame<D>]) -> D;

    /// Checks of an instance beyond its fields' domains (fields that must agree with each
    /// other), given its values by name: see [`Element::check_instance`]. The default
    /// accepts every instance.
    fn check(_value: &dyn Fn(&str) -> f64) -> Result<(), String> {
        Ok(())
    }

    /// Optional fast path: value, gradient and Hessian of [`InstanceKind::energy`] from the
    /// frame jets (see [`crate::Potential::fast_derivatives`]); return false to use the
    /// general one (hyper-dual numbers over the jets). A kind that writes one checks it
    /// against the generic form with [`check_fast_path`].
    fn fast_derivatives(
        _instance: &Self::Instance<f64>,
        _at: &JetPoint,
        _out: &mut Derivatives,
    ) -> bool {
        false
    }
}

/// One instance and its place in the reference configuration, as
/// [`InstanceKind::instance`] sees it.
#[derive(Debug)]
pub struct InstanceAt<'r, C: Constant> {
    /// The instance (checked against the kind's schema).
    pub element: &'r PluginElement<C>,
    schema: &'r InstanceSchema,
    frames: Vec<&'r Frame<C>>,
}

impl<C: Constant> InstanceAt<'_, C> {
    /// Value `name` (in the field's SI unit), or the field's default.
    pub fn value(&self, name: &str) -> C {
        self.schema.value(self.element, name)
    }
    /// Point `k` (m) in its body's coordinates: `k` below the schema's `points`, which the
    /// instance was checked to have before it was offered (an index past the kind's own
    /// schema is a mistake in the kind's code, not in its input).
    pub fn point(&self, k: usize) -> Vector3<C> {
        self.element.points[k]
    }
    /// Body `k`'s frame at the reference configuration: `k` below the schema's `bodies`
    /// (see [`InstanceAt::point`]).
    pub fn frame(&self, k: usize) -> &Frame<C> {
        self.frames[k]
    }
    /// Point `k` (m) in lab coordinates at the reference configuration (see
    /// [`InstanceAt::point`]).
    pub fn lab_point(&self, k: usize) -> Vector3<C> {
        self.frames[k].point(&self.element.points[k])
    }
    /// Whether anything `instance` may read moves with the parameter.
    fn moves(&self) -> bool {
        let frame_moves =
            |f: &&Frame<C>| f.origin.iter().chain(f.rotation.iter()).any(|v| v.moves());
        self.element.values.values().any(|v| v.moves())
            || self.element.points.iter().flatten().any(|v| v.moves())
            || self.frames.iter().any(frame_moves)
    }
}

/// A term of kind `K`: the instance and its bodies' frames over the term's coordinates.
#[derive(Clone, Debug)]
struct KindTerm<K: InstanceKind, C: Constant> {
    frames: Vec<FrameMap>,
    instance: K::Instance<C>,
    /// Whether anything the instance was built from moves with the parameter.
    moves: bool,
}

/// Calls `f` with `frames` evaluated at `x`, on the stack for up to four bodies.
fn with_frames<D: Real, R>(frames: &[FrameMap], x: &[D], f: impl FnOnce(&[&Frame<D>]) -> R) -> R {
    let e = |k: usize| frames[k].eval(x);
    match frames.len() {
        1 => f(&[&e(0)]),
        2 => f(&[&e(0), &e(1)]),
        3 => f(&[&e(0), &e(1), &e(2)]),
        _ => {
            let all: Vec<Frame<D>> = frames.iter().map(|m| m.eval(x)).collect();
            f(&all.iter().collect::<Vec<_>>())
        }
    }
}

impl<K: InstanceKind> Potential for KindTerm<K, f64> {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        with_frames(&self.frames, x, |frames| K::energy(&self.instance, frames))
    }

    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        match K::TENSION_OFF {
            PartOff::Unchanged => TensionOff::Unchanged,
            PartOff::Vanishes => TensionOff::Vanishes,
        }
    }

    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let done = K::fast_derivatives(&self.instance, at, out) || {
            let energy = |f: &[&Frame<HyperDual64>], e: &mut [HyperDual64]| {
                e[0] = K::energy(&self.instance, f);
            };
            match at.frames.len() {
                1 => hyper_dual_over_frames::<1>(at, 1, out, |f, e| energy(&[&f[0]], e)),
                2 => hyper_dual_over_frames::<2>(at, 1, out, |f, e| energy(&[&f[0], &f[1]], e)),
                3 => hyper_dual_over_frames::<3>(at, 1, out, |f, e| {
                    energy(&[&f[0], &f[1], &f[2]], e)
                }),
                _ => false,
            }
        };
        // the tension-off Hessian is the kind's declared form, whoever computed the rest
        if done && K::TENSION_OFF == PartOff::Vanishes {
            out.off_form = OffForm::Zero;
        }
        done
    }
}

impl<K: InstanceKind> TangentPotential for KindTerm<K, Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        K::energy(&self.instance, frames)
    }
    fn moves(&self) -> bool {
        self.moves
    }
}

/// An instance as [`KindElement::instances`] makes it: the element, its local frames and
/// its term.
type InstanceParts<'r, K, C, F> = (&'r PluginElement<C>, F, KindTerm<K, C>);

/// The [`Element`] of an [`InstanceKind`]: register it with
/// [`register_kind!`](crate::register_kind).
pub struct KindElement<K>(PhantomData<fn() -> K>);

impl<K: InstanceKind> KindElement<K> {
    /// The element of kind `K`.
    pub const NEW: Self = KindElement(PhantomData);

    /// Each instance of `K` in `reference`'s model, with the frames it reads and the
    /// instance `K` builds from it; `frames` gives the local frames of a list of bodies.
    /// Each instance is checked against the kind's schema first (the assembly has checked
    /// it already; a caller of [`Element::terms`] may not have), so that the point and
    /// frame indices [`InstanceAt`] offers the kind are those its schema declares.
    fn instances<'r, C: Constant, F>(
        reference: &'r Reference<'r, C>,
        frames: impl Fn(&[usize]) -> Result<F, EnergyError> + 'r,
    ) -> impl Iterator<Item = Result<InstanceParts<'r, K, C, F>, EnergyError>> + 'r
    where
        F: AsRef<LocalFrames>,
    {
        reference
            .system
            .plugin_elements
            .iter()
            .filter(|e| e.kind == K::KIND)
            .map(move |e| {
                K::SCHEMA.check(e).map_err(|m| EnergyError::Element {
                    kind: K::KIND,
                    element: e.name.clone(),
                    message: m.message,
                })?;
                let at = InstanceAt {
                    element: e,
                    schema: &K::SCHEMA,
                    frames: e
                        .bodies
                        .iter()
                        .map(|&b| reference.frame(b))
                        .collect::<Result<_, _>>()?,
                };
                let local = frames(&e.bodies)?;
                let term = KindTerm {
                    frames: local.as_ref().frames.clone(),
                    instance: K::instance(&at),
                    moves: at.moves(),
                };
                Ok((e, local, term))
            })
    }
}

impl<K: InstanceKind> Element for KindElement<K> {
    fn kind(&self) -> &'static str {
        K::KIND
    }
    fn stage(&self) -> Stage {
        K::STAGE
    }
    fn summary(&self) -> &'static str {
        K::SUMMARY
    }
    fn instance_schema(&self) -> Option<InstanceSchema> {
        Some(K::SCHEMA)
    }
    fn check_instance(&self, value: &dyn Fn(&str) -> f64) -> Result<(), String> {
        K::check(value)
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        let system = reference.system;
        Self::instances(reference, |b| LocalFrames::new(system, b).map(Box::new))
            .map(|instance| {
                let (e, local, term) = instance?;
                let label = crate::term_label(K::KIND, &e.name);
                Ok(Term::on_frames(label, K::KIND, e.tag.clone(), *local, term))
            })
            .collect()
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        let system = reference.system;
        Self::instances(reference, |b| shared.frames(system, b))
            .map(|instance| {
                let (e, local, term) = instance?;
                let label = crate::term_label(K::KIND, &e.name);
                Ok(TangentTerm::on_frames(
                    label,
                    K::KIND,
                    e.tag.clone(),
                    local,
                    term,
                ))
            })
            .collect::<Result<_, _>>()
            .map(Some)
    }
}

/// Registers an [`InstanceKind`] in the link-time registry:
/// `pendkit_energy::register_kind!(MyKind);`.
#[macro_export]
macro_rules! register_kind {
    ($kind:ty) => {
        $crate::register_element!($crate::KindElement::<$kind>::NEW);
    };
}

/// Checks every term of `terms` (the terms of one kind, as its `Element` built them) at
/// `x` (global coordinates, m and rad): the fast path's value, gradient, Hessian and
/// tension-off form against the reference path's (hyper-dual numbers on the generic
/// energy), each entry within `tolerance` relative to the largest entry of its array.
/// The shared test of a kind's hand-written fast path; `Err` names the term and entry.
pub fn check_fast_path(terms: &[Term], x: &[f64], tolerance: f64) -> Result<(), String> {
    for term in terms {
        let close = |what: &str, fast: &[f64], generic: &[f64]| -> Result<(), String> {
            if fast.len() != generic.len() {
                return Err(format!("{}: {what} lengths differ", term.label));
            }
            let scale = fast
                .iter()
                .chain(generic)
                .fold(0.0f64, |m, v| m.max(v.abs()));
            // a NaN on either path is a misfit too
            let off =
                |(a, b): (&f64, &f64)| (a - b).abs().is_nan() || (a - b).abs() > tolerance * scale;
            match fast.iter().zip(generic).position(off) {
                Some(i) => Err(format!(
                    "{}: {what}[{i}] = {:e} on the fast path, {:e} on the generic one",
                    term.label, fast[i], generic[i]
                )),
                None => Ok(()),
            }
        };
        let fast = term.derivatives(x).map_err(|e| e.to_string())?;
        let generic = term.reference_derivatives(x).map_err(|e| e.to_string())?;
        close("value", &[fast.value], &[generic.value])?;
        close("gradient", &fast.gradient, &generic.gradient)?;
        close("hessian", &fast.hessian, &generic.hessian)?;
        let (_, off_fast) = term.hessians(x, true).map_err(|e| e.to_string())?;
        let (_, off_generic) = term.hessians(x, false).map_err(|e| e.to_string())?;
        match (&off_fast, &off_generic) {
            (OffHessian::Same, OffHessian::Same) | (OffHessian::Zero, OffHessian::Zero) => {}
            (OffHessian::Matrix(a), OffHessian::Matrix(b)) => close("tension-off hessian", a, b)?,
            _ => {
                return Err(format!(
                    "{}: tension-off form {off_fast:?} on the fast path, {off_generic:?} on the generic one",
                    term.label
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    //! The contract on a small kind written here (a spring along the lab's z between two
    //! points, E = ½ k (Δz)²): the generated terms' fast path, tension-off form and tangent
    //! terms, and [`check_fast_path`] catching a wrong hand-written fast path.

    use super::*;
    use crate::{Domain, ValueField};
    use pendkit_system::System;

    /// ½ k (Δz)², Δz the change of the points' height difference; lossless or lossy, and
    /// with a hand-written fast path that is right or (`WRONG_FAST`) off by 1e-9.
    struct VerticalSpring<const LOSSLESS: bool, const WRONG_FAST: bool>;

    #[derive(Clone, Debug)]
    struct Instance<C> {
        points: [Vector3<C>; 2],
        rest: C,
        k: C,
    }

    impl<const LOSSLESS: bool, const WRONG_FAST: bool> InstanceKind
        for VerticalSpring<LOSSLESS, WRONG_FAST>
    {
        const KIND: &'static str = "test-vertical-spring";
        const STAGE: Stage = Stage::S0A;
        const SUMMARY: &'static str = "test";
        const SCHEMA: InstanceSchema = InstanceSchema {
            bodies: 2,
            points: 2,
            values: &[ValueField {
                name: "k",
                unit: "N/m",
                domain: Domain::Finite,
                default: Some(3.0),
                description: "stiffness",
            }],
        };
        const TENSION_OFF: PartOff = if LOSSLESS {
            PartOff::Vanishes
        } else {
            PartOff::Unchanged
        };
        type Instance<C: Constant> = Instance<C>;

        fn instance<C: Constant>(at: &InstanceAt<'_, C>) -> Instance<C> {
            Instance {
                points: [at.point(0), at.point(1)],
                rest: at.lab_point(1)[2] - at.lab_point(0)[2],
                k: at.value("k"),
            }
        }
        fn energy<C: Constant, D: Lift<C>>(s: &Instance<C>, frames: &[&Frame<D>]) -> D {
            let dz = frames[1].point(&s.points[1])[2]
                - frames[0].point(&s.points[0])[2]
                - D::lift(s.rest);
            (dz * dz).times(s.k * 0.5)
        }
        fn fast_derivatives(s: &Instance<f64>, at: &JetPoint, out: &mut Derivatives) -> bool {
            // the generic fast path, then (for the wrong variant) a slip in the Hessian
            let done = hyper_dual_over_frames::<2>(at, 1, out, |f, e| {
                e[0] = Self::energy(s, &[&f[0], &f[1]]);
            });
            if WRONG_FAST {
                out.on.iter_mut().for_each(|h| *h *= 1.0 + 1e-9);
            }
            done
        }
    }

    /// A support and a 10 kg body joined by one instance of kind `K`, the body displaced
    /// and turned a little (so every coordinate takes part), and the terms of `K` there.
    fn terms_of<K: InstanceKind>() -> (Vec<Term>, Vec<f64>) {
        let mut system = System::free_bodies(&[("support", 0.0), ("mass", 10.0)]).unwrap();
        system.plugin_elements.push(PluginElement {
            kind: K::KIND.into(),
            name: "s".into(),
            bodies: vec![0, 1],
            points: vec![Vector3::new(0.1, 0.2, 0.3), Vector3::new(-0.2, 0.1, 0.05)],
            values: Default::default(),
            tag: "s".into(),
        });
        let start = vec![0.0; 12];
        let reference = Reference::new(&system, &start);
        let terms = KindElement::<K>::NEW.terms(&reference).unwrap();
        let x = [
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01, -0.02, 0.03, 0.1, -0.05, 0.2,
        ];
        (terms, x.to_vec())
    }

    #[test]
    fn an_instance_that_misfits_its_schema_or_the_model_is_an_error_not_a_panic() {
        type K = VerticalSpring<false, false>;
        let mut system = System::free_bodies(&[("support", 0.0), ("mass", 10.0)]).unwrap();
        let instance = PluginElement {
            kind: K::KIND.into(),
            name: "s".into(),
            bodies: vec![0, 1],
            // one point where the schema has two: `at.point(1)` would read past it
            points: vec![Vector3::zeros()],
            values: Default::default(),
            tag: "s".into(),
        };
        system.plugin_elements.push(instance.clone());
        let start = vec![0.0; 12];
        let e = KindElement::<K>::NEW
            .terms(&Reference::new(&system, &start))
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("test-vertical-spring 's': needs 2 points, got 1"),
            "{e}"
        );
        // a body the model does not have
        system.plugin_elements[0] = PluginElement {
            bodies: vec![0, 7],
            points: vec![Vector3::zeros(); 2],
            ..instance
        };
        let e = KindElement::<K>::NEW
            .terms(&Reference::new(&system, &start))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "Reference::frame: body index 7 is out of range (the system has 2)"
        );
    }

    #[test]
    fn the_generated_fast_path_is_the_generic_energys() {
        let (terms, x) = terms_of::<VerticalSpring<false, false>>();
        check_fast_path(&terms, &x, 1e-12).unwrap();
        // the value against the closed form where the body only moves: Δz = z1 = 0.03 m,
        // and k its default, 3 N/m
        let mut moved = vec![0.0; 12];
        moved[6..9].copy_from_slice(&[0.01, -0.02, 0.03]);
        let value = terms[0].energy(&moved).unwrap();
        let expected = 0.5 * 3.0 * 0.03f64.powi(2);
        assert!((value - expected).abs() <= 1e-15, "{value} vs {expected}");
    }

    #[test]
    fn a_lossless_kind_has_no_tension_off_stiffness() {
        let (terms, x) = terms_of::<VerticalSpring<true, false>>();
        check_fast_path(&terms, &x, 1e-12).unwrap();
        assert_eq!(terms[0].hessians(&x, true).unwrap().1, OffHessian::Zero);
        let (lossy, x) = terms_of::<VerticalSpring<false, false>>();
        assert_eq!(lossy[0].hessians(&x, true).unwrap().1, OffHessian::Same);
    }

    #[test]
    fn a_wrong_hand_written_fast_path_is_caught() {
        let (terms, x) = terms_of::<VerticalSpring<false, true>>();
        let error = check_fast_path(&terms, &x, 1e-12).unwrap_err();
        assert!(
            error.contains("test-vertical-spring s: hessian["),
            "{error}"
        );
    }
}
