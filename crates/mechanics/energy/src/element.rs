//! The `Element` trait and the link-time registry of element kinds.
//!
//! An element kind turns part of a [`System`] into potential-energy terms. Gravity, springs
//! and wire stretch are registered here; plug-in crates under `elements/` register more with
//! `inventory::submit!`, and the core never names them. A crate that nothing names can be
//! dropped by the linker (inventory issue #50), so the `pendkit` facade names every bundled
//! element crate and a test asserts the registered set.

use std::any::{Any, TypeId};
use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

use nalgebra::Vector3;
use num_dual::Dual64;
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{Constant, norm, tr_mul_vec};

use crate::{BodyId, EndDirection, EnergyError, Spring, Stage, System, TangentTerm, Term, Wire};

/// The configuration an element builds its terms around: the equilibrium, or the start
/// position when plug-in terms join the equilibrium search early. With `S = Dual64` the
/// model's numbers and the coordinates carry their derivatives with respect to one
/// parameter (the exact sensitivities, docs/exact-sensitivities.md).
#[derive(Clone, Debug)]
pub struct Reference<'a, S: Constant = f64> {
    /// The model.
    pub system: &'a System<S>,
    /// Full coordinate vector (m, rad).
    pub coords: &'a [S],
    /// Every body's frame at `coords`, evaluated at the first request: the kinds built
    /// around one reference ask for the same few bodies' frames many times (each wire's
    /// ends, for its stretch, tension, clamp directions, torsion and beam).
    frames: OnceLock<Vec<Frame<S>>>,
    /// Whether the caller keeps only the terms whose constants move with the parameter
    /// ([`Reference::moving_only`]).
    moving_only: bool,
}

impl<'a, S: Constant> Reference<'a, S> {
    /// The configuration `coords` (full coordinate vector, m and rad) of `system`.
    pub fn new(system: &'a System<S>, coords: &'a [S]) -> Self {
        Reference {
            system,
            coords,
            frames: OnceLock::new(),
            moving_only: false,
        }
    }

    /// [`Reference::new`] for a caller that keeps only the terms whose constants move with
    /// the parameter and discards the rest ([`TangentTerm::moves`]: the exact sensitivities'
    /// passes at a fixed configuration). A kind may then leave out the terms of an element
    /// nothing of which moves ([`Reference::keeps_wire`], [`Reference::keeps_body`],
    /// [`Reference::keeps_spring`]), which saves building them; a kind that builds them all
    /// anyway is only slower.
    pub fn moving_only(system: &'a System<S>, coords: &'a [S]) -> Self {
        Reference {
            moving_only: true,
            ..Reference::new(system, coords)
        }
    }

    /// Whether body `body`'s frame here moves with the parameter: some coordinate it reads
    /// carries a derivative (the frames' expressions hold no model numbers). A body or
    /// coordinate the model does not have counts as moving: its terms are then built, and
    /// the build reports what is wrong with them.
    fn frame_moves(&self, body: BodyId) -> bool {
        self.system.bodies.get(body).is_none_or(|b| {
            b.frame
                .var_list()
                .iter()
                .any(|&i| self.coords.get(i).is_none_or(|c| c.moves()))
        })
    }

    /// Whether a kind must build its terms of `wire`: always, unless the caller keeps only
    /// moving terms ([`Reference::moving_only`]) and nothing a wire's terms are built from
    /// moves: the wire's numbers ([`Wire::moves`]) and its end bodies' frames here.
    pub fn keeps_wire(&self, wire: &Wire<S>) -> bool {
        !self.moving_only || wire.moves() || wire.ends.iter().any(|e| self.frame_moves(e.body))
    }

    /// Whether a kind must build its terms of body `body` alone (gravity): always, unless
    /// the caller keeps only moving terms and none of the body's numbers (mass, inertia,
    /// centre of mass), the gravitational acceleration or its frame here moves.
    pub fn keeps_body(&self, body: BodyId) -> bool {
        let numbers_move = |b: &crate::Body<S>| {
            b.mass.moves()
                || b.inertia.iter().any(|v| v.moves())
                || b.centre_of_mass.iter().any(|v| v.moves())
        };
        !self.moving_only
            || self.system.gravity.moves()
            || self.system.bodies.get(body).is_none_or(numbers_move)
            || self.frame_moves(body)
    }

    /// Whether a kind must build its terms of `spring`: always, unless the caller keeps
    /// only moving terms and none of the spring's numbers (end points and angles,
    /// stiffness, preload) or its end bodies' frames here moves.
    pub fn keeps_spring(&self, spring: &Spring<S>) -> bool {
        !self.moving_only
            || spring
                .ends
                .iter()
                .any(|e| e.point.iter().chain(&e.angles).any(|v| v.moves()))
            || spring
                .stiffness
                .iter()
                .chain(&spring.preload)
                .any(|v| v.moves())
            || spring.ends.iter().any(|e| self.frame_moves(e.body))
    }

    /// The frame (origin, m; rotation) of body `body` here, or [`EnergyError::Index`] for a
    /// body the system does not have. (Coordinates too short for a body's pose give its
    /// frame NaN entries, which the terms built on it report.)
    pub fn frame(&self, body: BodyId) -> Result<&Frame<S>, EnergyError> {
        let frames = self.frames.get_or_init(|| {
            self.system
                .bodies
                .iter()
                .map(|b| b.frame.eval(self.coords))
                .collect()
        });
        frames.get(body).ok_or_else(|| EnergyError::Index {
            item: "Reference::frame".into(),
            what: "body",
            index: body,
            len: frames.len(),
        })
    }

    /// The frame of the body at end `k` of `wire`, an error naming the wire for a body the
    /// system does not have.
    fn end_frame(&self, wire: &Wire<S>, k: usize) -> Result<&Frame<S>, EnergyError> {
        self.frame(wire.ends[k].body).map_err(|e| match e {
            EnergyError::Index {
                what, index, len, ..
            } => EnergyError::Index {
                item: format!("wire '{}'", wire.name),
                what,
                index,
                len,
            },
            e => e,
        })
    }

    /// Lab positions (m) of the two attachment points of `wire`; an error for an end on a
    /// body the system does not have.
    pub fn wire_points(&self, wire: &Wire<S>) -> Result<[Vector3<S>; 2], EnergyError> {
        let point = |k: usize| -> Result<Vector3<S>, EnergyError> {
            Ok(self.end_frame(wire, k)?.point(&wire.ends[k].point))
        };
        Ok([point(0)?, point(1)?])
    }

    /// Chord length (m) of `wire` (errors as [`Reference::wire_points`]).
    pub fn wire_length(&self, wire: &Wire<S>) -> Result<S, EnergyError> {
        let [p0, p1] = self.wire_points(wire)?;
        Ok(norm(&(p1 - p0)))
    }

    /// Static tension (N) of `wire`: k (l - l0) (errors as [`Reference::wire_points`]).
    pub fn wire_tension(&self, wire: &Wire<S>) -> Result<S, EnergyError> {
        Ok(wire.stiffness * (self.wire_length(wire)? - wire.unstretched_length))
    }

    /// Clamp direction of each end in that end's body coordinates, pointing into the wire;
    /// `Auto` ends get the direction of the chord here (straight wire); hinged ends give
    /// `None` (errors as [`Reference::wire_points`]).
    pub fn wire_end_directions(
        &self,
        wire: &Wire<S>,
    ) -> Result<[Option<Vector3<S>>; 2], EnergyError> {
        let [p0, p1] = self.wire_points(wire)?;
        let chord = p1 - p0;
        let chord = chord / norm(&chord);
        let direction = |k: usize| -> Result<Option<Vector3<S>>, EnergyError> {
            let end = &wire.ends[k];
            let rotation = self.end_frame(wire, k)?.rotation;
            let into_wire = if k == 0 { chord } else { -chord };
            Ok(match &end.direction {
                EndDirection::Hinged => None,
                EndDirection::Auto => Some(tr_mul_vec(&rotation, &into_wire)),
                EndDirection::Explicit(v) => Some(v / norm(v)),
            })
        };
        Ok([direction(0)?, direction(1)?])
    }
}

/// A kind of element: produces potential-energy terms for a model.
pub trait Element: Sync {
    /// Kind name, e.g. `wire-bending`.
    fn kind(&self) -> &'static str;
    /// The stage at which the kind's terms join the calculation.
    fn stage(&self) -> Stage;
    /// One line saying what the kind models.
    fn summary(&self) -> &'static str;
    /// What an instance of the kind needs (its value fields, bodies and points), for a kind
    /// whose terms come from [`PluginElement`](crate::PluginElement) instances: every
    /// instance is checked against it before any term is built
    /// ([`check_plugin_elements`](crate::check_plugin_elements)), so `terms` reads the
    /// values unchecked. `None` (the default): the kind owns no instances (wire bending and
    /// torsion act on every wire of a stage).
    fn instance_schema(&self) -> Option<crate::InstanceSchema> {
        None
    }
    /// Checks of an instance beyond its schema's per-field domains (fields that must agree
    /// with each other), given its values by name (SI units, defaults filled in): `Err`
    /// says what is wrong in one line. Called for every instance, after the schema's check
    /// and before any term is built. The default accepts every instance.
    fn check_instance(&self, _value: &dyn Fn(&str) -> f64) -> Result<(), String> {
        Ok(())
    }
    /// The kind's terms for `reference.system`, built around `reference`.
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError>;

    /// The kind's terms built from a model whose numbers, and around coordinates which,
    /// carry their derivatives with respect to one parameter: the terms' constants carry
    /// theirs, and [`TangentTerm::derivatives`] gives the energy's derivatives with their
    /// parameter derivatives (docs/exact-sensitivities.md). Energy bodies shared with other
    /// kinds built around the same reference are taken from (or put into) `shared`, as in
    /// [`Element::terms_shared`]. `None` (the default): the kind has no such terms, and the
    /// sensitivities fall back to differences. Around a [`Reference::moving_only`] the kind
    /// may leave out the terms of elements nothing of which moves
    /// ([`Reference::keeps_wire`] and its siblings); it need not.
    fn tangent_terms(
        &self,
        _reference: &Reference<Dual64>,
        _shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        Ok(None)
    }

    /// The kind's terms, with energy bodies shared with other kinds built around the same
    /// reference taken from (or put into) `shared`. Kinds that share nothing keep the
    /// default, which is [`Element::terms`]; the assembly always calls this one.
    fn terms_shared(
        &self,
        reference: &Reference,
        _shared: &SharedBodies,
    ) -> Result<Vec<Term>, EnergyError> {
        self.terms(reference)
    }
}

/// Energy bodies shared between the terms of different element kinds built around one
/// reference configuration, such as the beam of a wire: its bending strain energy is a
/// stage-1B term and its work against tension a stage-2 term of another kind, and both come
/// from one evaluation of the beam. The assembly passes one `SharedBodies` to every kind
/// it builds at a reference; a kind asks for a body by type and index (e.g. the wire's) and
/// gets the one another kind already built, or builds it.
///
/// Both are looked up by key (a model with n wires asks n times: a search through a list
/// made building the terms quadratic in the model's size).
#[derive(Default)]
pub struct SharedBodies {
    bodies: RefCell<HashMap<(TypeId, usize), SharedBody>>,
    frames: RefCell<HashMap<Vec<BodyId>, Arc<LocalFrames>>>,
}

/// One shared body, by its type and its index among bodies of that type.
type SharedBody = Arc<dyn Any + Send + Sync>;

impl SharedBodies {
    /// An empty collection.
    pub fn new() -> Self {
        SharedBodies::default()
    }

    /// A collection that starts with `frames`, the local frames of another build of a model
    /// whose bodies follow the coordinates as this one's do (the same poses: local frames
    /// depend on nothing else), so that this build does not make them again (the exact
    /// sensitivities build the terms of every parameter's model of one model).
    pub fn with_frames(frames: impl IntoIterator<Item = Arc<LocalFrames>>) -> Self {
        SharedBodies {
            bodies: RefCell::default(),
            frames: RefCell::new(frames.into_iter().map(|f| (f.bodies.clone(), f)).collect()),
        }
    }

    /// The frames of `bodies` of `system` over one local vector, shared by every term on
    /// the same bodies (a wire's torsion and beam); [`EnergyError::Index`] for a body the
    /// system does not have.
    pub fn frames<S: Constant>(
        &self,
        system: &System<S>,
        bodies: &[BodyId],
    ) -> Result<Arc<LocalFrames>, EnergyError> {
        let found = self.frames.borrow().get(bodies).cloned();
        match found {
            Some(frames) => Ok(frames),
            None => {
                let frames = Arc::new(LocalFrames::new(system, bodies)?);
                self.frames
                    .borrow_mut()
                    .insert(bodies.to_vec(), frames.clone());
                Ok(frames)
            }
        }
    }

    /// The body of type `T` with index `index`, built by `make` if nobody has yet.
    pub fn get_or_try_insert<T: Any + Send + Sync, E>(
        &self,
        index: usize,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let key = TypeId::of::<T>();
        let found = self.bodies.borrow().get(&(key, index)).cloned();
        if let Some(body) = found.and_then(|b| b.downcast::<T>().ok()) {
            return Ok(body);
        }
        let body = Arc::new(make()?);
        self.bodies.borrow_mut().insert((key, index), body.clone());
        Ok(body)
    }
}

/// A registry entry: an element kind and the crate that registered it. Submit one per kind
/// with [`register_element!`](crate::register_element), which fills in the crate's name.
pub struct Registration {
    /// The element kind.
    pub element: &'static dyn Element,
    /// The package name of the crate that registered it (`CARGO_PKG_NAME`).
    pub crate_name: &'static str,
}

inventory::collect!(Registration);

/// Registers an element kind (a `static` or constant implementing [`Element`]) in the
/// link-time registry, recording the registering crate's package name:
/// `pendkit_energy::register_element!(MyKind);`.
#[macro_export]
macro_rules! register_element {
    ($kind:expr) => {
        $crate::inventory::submit! {
            $crate::Registration {
                element: &$kind,
                crate_name: env!("CARGO_PKG_NAME"),
            }
        }
    };
}

/// The registry, collected from `inventory` and sorted once, on first use.
struct Registry {
    /// Every registration, ordered by stage, kind name, then crate.
    registrations: Vec<&'static Registration>,
    /// Their kinds, in the same order.
    kinds: Vec<&'static dyn Element>,
    /// Each kind name's first registration (an index into `kinds`).
    by_name: std::collections::HashMap<&'static str, usize>,
}

/// The registry of this program, built at the first call.
fn the_registry() -> &'static Registry {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    REGISTRY.get_or_init(|| {
        let mut registrations: Vec<&'static Registration> =
            inventory::iter::<Registration>.into_iter().collect();
        registrations.sort_by_key(|r| (r.element.stage(), r.element.kind(), r.crate_name));
        let kinds: Vec<&'static dyn Element> = registrations.iter().map(|r| r.element).collect();
        let mut by_name = std::collections::HashMap::with_capacity(kinds.len());
        for (k, kind) in kinds.iter().enumerate() {
            by_name.entry(kind.kind()).or_insert(k);
        }
        Registry {
            registrations,
            kinds,
            by_name,
        }
    })
}

/// Every registration linked into this program, ordered by stage, kind name, then crate
/// (collected once, at the first call).
pub fn registrations() -> &'static [&'static Registration] {
    &the_registry().registrations
}

/// Two registrations of one kind name: the second would be summed into every energy
/// beside the first (or, looked up by name, shadow it), so it is refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "element kind '{kind}' is registered twice, by crate {first} and by crate {second}: kind names must be unique (rename one)"
)]
pub struct DuplicateKind {
    /// The kind name.
    pub kind: &'static str,
    /// The crate of the first registration (in registry order).
    pub first: &'static str,
    /// The crate of the second.
    pub second: &'static str,
}

/// The first kind name that two of `registrations` share, if any.
pub fn duplicate_kind(registrations: &[&Registration]) -> Option<DuplicateKind> {
    let mut seen: std::collections::HashMap<&'static str, &'static str> =
        std::collections::HashMap::new();
    for r in registrations {
        if let Some(first) = seen.insert(r.element.kind(), r.crate_name) {
            return Some(DuplicateKind {
                kind: r.element.kind(),
                first,
                second: r.crate_name,
            });
        }
    }
    None
}

/// Checks that every kind name linked into this program is registered once (the check
/// itself runs once, at the first call).
pub fn check_registrations() -> Result<(), DuplicateKind> {
    static CHECKED: OnceLock<Option<DuplicateKind>> = OnceLock::new();
    CHECKED
        .get_or_init(|| duplicate_kind(registrations()))
        .clone()
        .map_or(Ok(()), Err)
}

/// All linked element kinds, ordered by stage then kind name (collected once).
pub fn registry() -> &'static [&'static dyn Element] {
    &the_registry().kinds
}

/// The registered kind called `name` (its first registration, if two crates register it:
/// [`check_registrations`] refuses that), found in constant time.
pub fn find_kind(name: &str) -> Option<&'static dyn Element> {
    let registry = the_registry();
    registry.by_name.get(name).map(|&k| registry.kinds[k])
}

/// A term's label, `<kind> <element name>` (e.g. `wire-stretch fibre1`), in one allocation
/// of the right size (`format!` guesses the size from the literal parts and grows the
/// string; the sensitivities build terms for every parameter).
pub fn term_label(kind: &str, name: &str) -> String {
    let mut label = String::with_capacity(kind.len() + 1 + name.len());
    label.push_str(kind);
    label.push(' ');
    label.push_str(name);
    label
}

/// Frames of several bodies over one shared local coordinate vector: the union of the
/// coordinates the bodies depend on, and each frame renumbered into it.
#[derive(Clone, Debug, Default)]
pub struct LocalFrames {
    /// Global indices of the local coordinates, ascending.
    pub coords: Vec<usize>,
    /// One frame per requested body, reading the local vector.
    pub frames: Vec<FrameMap>,
    /// The requested bodies, in order. The local frame of body `k` reads its coordinates
    /// at `frames[k].var_list()`, in the order of the body's own frame's coordinates: that
    /// is how a jet of the body's frame over the global coordinates maps into the local
    /// vector.
    pub bodies: Vec<BodyId>,
}

impl LocalFrames {
    /// Collects the frames of `bodies` of `system`; [`EnergyError::Index`] for a body the
    /// system does not have.
    pub fn new<S: Constant>(system: &System<S>, bodies: &[BodyId]) -> Result<Self, EnergyError> {
        let found = bodies
            .iter()
            .map(|&b| {
                system.bodies.get(b).ok_or_else(|| EnergyError::Index {
                    item: "LocalFrames::new".into(),
                    what: "body",
                    index: b,
                    len: system.bodies.len(),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut coords: Vec<usize> = found
            .iter()
            .flat_map(|b| b.frame.var_list().iter().copied())
            .collect();
        coords.sort_unstable();
        coords.dedup();
        // every variable of every frame is in `coords` by construction
        let local = |g: usize| coords.binary_search(&g).unwrap_or(0);
        let frames = found.iter().map(|b| b.frame.remap(&local)).collect();
        Ok(LocalFrames {
            coords,
            frames,
            bodies: bodies.to_vec(),
        })
    }
}
