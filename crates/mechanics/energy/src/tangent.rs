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
//! the terms on it ([`tangent_frames`]). A pass along several modes evaluates each term
//! once for up to [`LANES`] of them ([`SecondLanes`], [`tangent_frames_along_lanes`]).

use std::sync::Arc;

use num_dual::{Dual, Dual64, HyperDual};
use pendkit_geometry::Frame;
use pendkit_rotations::{LANES, Lift, Real, SecondLanes, second_lanes_parts, second_lanes_seed};

use crate::{BodyId, EnergyError, LocalFrames, MAX_FRAMES, MAX_PARTS};

/// The scalar of the parameter-derivative Hessian pass: second derivatives over two
/// coordinates, each part carrying its derivative with respect to the parameter. The one
/// pass with cross derivatives (a pair across two modes, every entry of dK/dp); along one
/// mode at a time it is also the lanes' reference ([`SecondLanes`]).
pub type HyperTangent = HyperDual<Dual64>;

/// The scalar of the parameter-derivative gradient pass (∂g/∂p). `cargo bench -p
/// pendkit-benches --bench scalars -- gradient`: the quad's terms' gradients 21× faster
/// (median of three runs, 14–74×) than by the hyper-dual pass that also gives them
/// ([`TangentTerm::derivatives`]), at least 2× per evaluation.
pub type DualTangent = Dual<Dual64>;

/// An energy body whose constants are `Dual64` (a value and its derivative with respect to
/// one parameter), written once over every scalar that can take such constants, as a
/// function of its bodies' frames: so that one evaluation of each body's frame serves
/// every term on it ([`TangentTerm::second_along_frames`]).
pub trait TangentPotential: Send + Sync + 'static {
    /// Potential energy (J) with the term's bodies at `frames` (in the order of its
    /// [`LocalFrames::bodies`]).
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D;

    /// Whether any of the term's constants moves with the parameter
    /// ([`pendkit_rotations::Constant::moves`]). A term that says no has no derivative at
    /// fixed coordinates, which the exact sensitivities then skip; the default, yes, is
    /// always right, only slower.
    fn moves(&self) -> bool {
        true
    }
}

/// A [`TangentPotential`] that yields several energies in one evaluation, each that of its
/// own term (see [`crate::SharedPotential`]).
pub trait TangentSharedPotential: Send + Sync + 'static {
    /// Number of energy parts.
    fn parts(&self) -> usize;
    /// The energy (J) of every part with the bodies at `frames`, written into `out`.
    fn energies_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>], out: &mut [D]);

    /// Whether any constant moves with the parameter (see [`TangentPotential::moves`]).
    fn moves(&self) -> bool {
        true
    }
}

/// Object-safe view of the three scalars the passes use (the gradient's, the hyper-dual
/// one's and the lanes'). `parts` lists the energy parts summed (a body with one part
/// ignores it).
trait DynTangent: Send + Sync {
    fn moves(&self) -> bool;
    /// The shared body's address, for a part of a shared body.
    fn shared(&self) -> Option<usize>;
    fn value_d(&self, frames: &[&Frame<DualTangent>], parts: &[usize]) -> DualTangent;
    fn value_hd(&self, frames: &[&Frame<HyperTangent>], parts: &[usize]) -> HyperTangent;
    fn value_lanes(&self, frames: &[&Frame<SecondLanes>], parts: &[usize]) -> SecondLanes;
}

impl<P: TangentPotential> DynTangent for P {
    fn moves(&self) -> bool {
        TangentPotential::moves(self)
    }
    fn shared(&self) -> Option<usize> {
        None
    }
    fn value_d(&self, frames: &[&Frame<DualTangent>], _parts: &[usize]) -> DualTangent {
        self.energy_on_frames(frames)
    }
    fn value_hd(&self, frames: &[&Frame<HyperTangent>], _parts: &[usize]) -> HyperTangent {
        self.energy_on_frames(frames)
    }
    fn value_lanes(&self, frames: &[&Frame<SecondLanes>], _parts: &[usize]) -> SecondLanes {
        self.energy_on_frames(frames)
    }
}

/// One part of a shared body (a wire's beam: its bending and its extra stretch). A pass
/// that sums several parts of one body evaluates it once for all of them
/// ([`TangentSum`]).
struct PartOf<S> {
    shared: Arc<S>,
}

impl<S: TangentSharedPotential> PartOf<S> {
    /// The sum of the parts listed in `parts`, all parts evaluated at once.
    fn value<D: Lift<Dual64>>(&self, frames: &[&Frame<D>], parts: &[usize]) -> D {
        let count = self.shared.parts();
        // a part the body does not have adds nothing (TangentTerm::part checks it)
        let sum = |out: &[D]| {
            parts
                .iter()
                .filter_map(|&p| out.get(p))
                .fold(D::from(0.0), |acc, &v| acc + v)
        };
        if count <= MAX_PARTS {
            // on the stack: this runs once per term and direction
            let mut out = [D::from(0.0); MAX_PARTS];
            self.shared.energies_on_frames(frames, &mut out[..count]);
            return sum(&out[..count]);
        }
        let mut out = vec![D::from(0.0); count];
        self.shared.energies_on_frames(frames, &mut out);
        sum(&out)
    }
}

impl<S: TangentSharedPotential> DynTangent for PartOf<S> {
    fn moves(&self) -> bool {
        self.shared.moves()
    }
    fn shared(&self) -> Option<usize> {
        Some(Arc::as_ptr(&self.shared) as *const () as usize)
    }
    fn value_d(&self, frames: &[&Frame<DualTangent>], parts: &[usize]) -> DualTangent {
        self.value(frames, parts)
    }
    fn value_hd(&self, frames: &[&Frame<HyperTangent>], parts: &[usize]) -> HyperTangent {
        self.value(frames, parts)
    }
    fn value_lanes(&self, frames: &[&Frame<SecondLanes>], parts: &[usize]) -> SecondLanes {
        self.value(frames, parts)
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
    frames: Arc<LocalFrames>,
    body: Arc<dyn DynTangent>,
    /// The term's part of its body (0 for a body with one part).
    part: usize,
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
        frames: impl Into<Arc<LocalFrames>>,
        body: P,
    ) -> Self {
        let frames = frames.into();
        TangentTerm {
            label: label.into(),
            kind,
            tag: tag.into(),
            coords: frames.coords.clone(),
            frames,
            body: Arc::new(body),
            part: 0,
        }
    }

    /// A term whose energy is part `part` of a shared body that reads the frames `frames`
    /// (the body and frames shared by its other parts' terms); a part the body does not
    /// have is an error.
    pub fn part<S: TangentSharedPotential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        frames: Arc<LocalFrames>,
        shared: Arc<S>,
        part: usize,
    ) -> Result<Self, EnergyError> {
        let label = label.into();
        crate::check_part(&label, part, shared.parts())?;
        Ok(TangentTerm {
            label,
            kind,
            tag: tag.into(),
            coords: frames.coords.clone(),
            frames,
            body: Arc::new(PartOf { shared }),
            part,
        })
    }

    /// The bodies the term reads, in the order its energy takes their frames.
    pub fn bodies(&self) -> &[BodyId] {
        &self.frames.bodies
    }

    /// The term's own part (0 for a body with one part).
    fn own_part(&self) -> &[usize] {
        std::slice::from_ref(&self.part)
    }

    /// Whether any of the term's constants moves with the parameter: if not, its energy
    /// at coordinates that carry no derivative has none either (every dual part exactly
    /// 0), so a pass at fixed coordinates can skip it. A kind that does not say counts as
    /// moving.
    pub fn moves(&self) -> bool {
        self.body.moves()
    }

    /// The term's frames at local coordinates `x`, and `f` of them.
    fn on_local_frames<D: Real, R>(&self, x: &[D], f: impl FnOnce(&[&Frame<D>]) -> R) -> R {
        let frames: Vec<Frame<D>> = self.frames.frames.iter().map(|m| m.eval(x)).collect();
        let refs: Vec<&Frame<D>> = frames.iter().collect();
        f(&refs)
    }

    /// `x_global` covers every coordinate of the term.
    fn check_length(&self, function: &'static str, given: usize) -> Result<(), EnergyError> {
        let expected = self.coords.iter().max().map_or(0, |&i| i + 1);
        if given < expected {
            return Err(EnergyError::Length {
                function,
                argument: "x_global (coordinates)",
                expected,
                given,
            });
        }
        Ok(())
    }

    /// The frames of the term's bodies over its local coordinate vector.
    pub fn local_frames(&self) -> &Arc<LocalFrames> {
        &self.frames
    }

    /// A term on more bodies than the dual passes take ([`MAX_FRAMES`]) is an error.
    fn check_frame_count(&self, bodies: usize) -> Result<(), EnergyError> {
        if bodies > MAX_FRAMES {
            return Err(EnergyError::Element {
                kind: self.kind,
                element: self.label.clone(),
                message: format!(
                    "reads {bodies} bodies; a term's derivatives with respect to a parameter \
                     take at most {MAX_FRAMES}"
                ),
            });
        }
        Ok(())
    }

    /// Value and gradient over the term's own coordinates at `x_global`, by one dual
    /// evaluation per coordinate: the gradient's dual parts are its derivatives with respect
    /// to the parameter (at fixed coordinates when `x_global` carries no derivative). Each
    /// frame is evaluated once, and again only for the coordinates it reads.
    pub fn gradient(&self, x_global: &[Dual64]) -> Result<TangentDerivatives, EnergyError> {
        self.check_length("TangentTerm::gradient", x_global.len())?;
        let maps = &self.frames.frames;
        self.check_frame_count(maps.len())?;
        let mut x: Vec<DualTangent> = self
            .coords
            .iter()
            .map(|&i| DualTangent::from_re(x_global[i]))
            .collect();
        let zero = Dual64::from_re(0.0);
        let at_x: Vec<Frame<DualTangent>> = maps.iter().map(|m| m.eval(&x)).collect();
        let mut frames = at_x.clone();
        // the energy at `frames` (at most MAX_FRAMES, checked above), by reference
        let energy = |frames: &[Frame<DualTangent>]| match frames.first() {
            None => self.body.value_d(&[], self.own_part()),
            Some(first) => {
                let mut refs = [first; MAX_FRAMES];
                for (slot, frame) in refs.iter_mut().zip(frames) {
                    *slot = frame;
                }
                self.body.value_d(&refs[..frames.len()], self.own_part())
            }
        };
        let mut out = TangentDerivatives {
            value: energy(&at_x).re,
            gradient: vec![zero; x.len()],
            hessian: Vec::new(),
        };
        for i in 0..x.len() {
            // the frames that read coordinate i, moved along it and put back after
            let reads = |map: &&pendkit_geometry::FrameMap| map.var_list().contains(&i);
            x[i].eps = Dual64::from_re(1.0);
            for (k, _) in maps.iter().enumerate().filter(|(_, m)| reads(m)) {
                frames[k] = maps[k].eval(&x);
            }
            x[i].eps = zero;
            out.gradient[i] = energy(&frames).eps;
            for (k, _) in maps.iter().enumerate().filter(|(_, m)| reads(m)) {
                frames[k] = at_x[k].clone();
            }
        }
        Ok(out)
    }

    /// [`TangentTerm::gradient`] at the configuration of `frames`, from every body's frames
    /// evaluated there once for all the terms ([`GradientFrames`]) instead of per term and
    /// per coordinate: the same numbers, bit for bit.
    pub fn gradient_from(
        &self,
        frames: &GradientFrames,
    ) -> Result<TangentDerivatives, EnergyError> {
        self.check_length("TangentTerm::gradient_from", frames.x.len())?;
        let bodies = &self.frames.bodies;
        self.check_frame_count(bodies.len())?;
        if let Some(&index) = bodies.iter().find(|&&b| b >= frames.at_x.len()) {
            return Err(EnergyError::Index {
                item: format!("term '{}'", self.label),
                what: "body (gradient frames)",
                index,
                len: frames.at_x.len(),
            });
        }
        let zero = Dual64::from_re(0.0);
        // the energy with each body at rest, or moved along `moved` (a global coordinate)
        let energy = |moved: Option<usize>| {
            let Some(&first) = bodies.first() else {
                return self.body.value_d(&[], self.own_part());
            };
            let pick = |b: BodyId| {
                moved
                    .and_then(|g| frames.reads[b].iter().position(|&v| v == g))
                    .map_or(&frames.at_x[b], |r| &frames.moved[b][r])
            };
            let mut refs = [pick(first); MAX_FRAMES];
            for (slot, &b) in refs.iter_mut().zip(bodies) {
                *slot = pick(b);
            }
            self.body.value_d(&refs[..bodies.len()], self.own_part())
        };
        let mut out = TangentDerivatives {
            value: energy(None).re,
            gradient: vec![zero; self.coords.len()],
            hessian: Vec::new(),
        };
        for (slot, &g) in out.gradient.iter_mut().zip(&self.coords) {
            *slot = energy(Some(g)).eps;
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
        self.second_of_parts(frames, self.own_part())
    }

    /// [`TangentTerm::second_along_frames`] with u = v along [`LANES`] directions at once,
    /// given every body's frame at x + Σₖ εₖuₖ ([`tangent_frames_along_lanes`]): each lane's
    /// uₖᵀ H uₖ with its derivative, equal to the one-direction pass's to rounding (the
    /// tests compare each lane with it).
    pub fn second_along_frames_lanes(
        &self,
        frames: &[Frame<SecondLanes>],
    ) -> Result<[Dual64; LANES], EnergyError> {
        Ok(second_lanes_parts(
            &self.second_lanes_of_parts(frames, self.own_part())?,
        ))
    }

    /// [`TangentTerm::second_along_frames`] of the sum of the body's parts `parts`.
    fn second_of_parts(
        &self,
        frames: &[Frame<HyperTangent>],
        parts: &[usize],
    ) -> Result<Dual64, EnergyError> {
        self.with_frames(frames, |mine| self.body.value_hd(mine, parts).eps1eps2)
    }

    /// [`TangentTerm::second_along_frames_lanes`] of the sum of the body's parts `parts`,
    /// every part of the number kept.
    fn second_lanes_of_parts(
        &self,
        frames: &[Frame<SecondLanes>],
        parts: &[usize],
    ) -> Result<SecondLanes, EnergyError> {
        self.with_frames(frames, |mine| self.body.value_lanes(mine, parts))
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
        self.check_length("TangentTerm::derivatives", x_global.len())?;
        let n = self.coords.len();
        let mut x: Vec<HyperTangent> = self
            .coords
            .iter()
            .map(|&i| HyperTangent::from_re(x_global[i]))
            .collect();
        let (zero, one) = (Dual64::from_re(0.0), Dual64::from_re(1.0));
        let mut out = TangentDerivatives {
            value: self
                .on_local_frames(&x, |f| self.body.value_hd(f, self.own_part()))
                .re,
            gradient: vec![zero; n],
            hessian: vec![zero; n * n],
        };
        for i in 0..n {
            x[i].eps1 = one;
            for j in i..n {
                x[j].eps2 = one;
                let r = self.on_local_frames(&x, |f| self.body.value_hd(f, self.own_part()));
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

/// Terms summed by a pass along given directions, the parts of one shared body among them
/// evaluated together (a wire's beam once for its bending and its extra-stretch term).
pub struct TangentSum<'t> {
    /// One term per body, with the parts of it summed (a term listed twice counts twice).
    groups: Vec<(&'t TangentTerm, Vec<usize>)>,
}

impl<'t> TangentSum<'t> {
    /// The sum of `terms`.
    pub fn new(terms: impl IntoIterator<Item = &'t TangentTerm>) -> Self {
        let mut groups: Vec<(&'t TangentTerm, Vec<usize>)> = Vec::new();
        for term in terms {
            let joined = term.body.shared().and_then(|address| {
                groups.iter_mut().find(|(t, _)| {
                    t.body.shared() == Some(address) && t.frames.bodies == term.frames.bodies
                })
            });
            match joined {
                Some((_, parts)) => parts.push(term.part),
                None => groups.push((term, vec![term.part])),
            }
        }
        TangentSum { groups }
    }

    /// How many evaluations a pass makes (one per body: a shared body's parts together).
    pub fn len(&self) -> usize {
        self.groups.len()
    }

    /// Whether there is no term to sum.
    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }

    /// Σ [`TangentTerm::second_along_frames`].
    pub fn second_along_frames(
        &self,
        frames: &[Frame<HyperTangent>],
    ) -> Result<Dual64, EnergyError> {
        self.sum(|(t, parts)| t.second_of_parts(frames, parts))
    }

    /// Σ [`TangentTerm::second_along_frames_lanes`].
    pub fn second_along_frames_lanes(
        &self,
        frames: &[Frame<SecondLanes>],
    ) -> Result<[Dual64; LANES], EnergyError> {
        let mut total = SecondLanes::from(0.0);
        for (term, parts) in &self.groups {
            total += term.second_lanes_of_parts(frames, parts)?;
        }
        Ok(second_lanes_parts(&total))
    }

    fn sum(
        &self,
        each: impl Fn((&TangentTerm, &[usize])) -> Result<Dual64, EnergyError>,
    ) -> Result<Dual64, EnergyError> {
        let mut total = Dual64::from_re(0.0);
        for (term, parts) in &self.groups {
            total += each((term, parts))?;
        }
        Ok(total)
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

/// Every body's frame at a configuration x, and that frame moved along each coordinate it
/// reads (dual part 1 on it): what [`TangentTerm::gradient_from`] reads. Evaluated once,
/// they serve every term, where [`TangentTerm::gradient`] evaluates its bodies' frames per
/// term and per coordinate; at an x that carries no parameter derivative they serve every
/// parameter's model too (whose frames are the nominal model's: a parameter moves the
/// points on a body, not how its frame follows the coordinates).
#[derive(Clone, Debug)]
pub struct GradientFrames {
    /// The configuration, with its derivatives.
    x: Vec<Dual64>,
    /// Per body: its frame at x.
    at_x: Vec<Frame<DualTangent>>,
    /// Per body: the coordinates its frame reads, and the frame moved along each.
    reads: Vec<Vec<usize>>,
    moved: Vec<Vec<Frame<DualTangent>>>,
}

impl GradientFrames {
    /// The frames of `system`'s bodies at `x` (a full coordinate vector, each coordinate
    /// with its derivative).
    pub fn new<S: Real>(system: &crate::System<S>, x: &[Dual64]) -> Result<Self, EnergyError> {
        let zero = Dual64::from_re(0.0);
        let at_x = frames_at(system, [("x", x.len())], |i| DualTangent::from_re(x[i]))?;
        let mut seeds: Vec<DualTangent> = x.iter().map(|&v| DualTangent::from_re(v)).collect();
        let reads: Vec<Vec<usize>> = system
            .bodies
            .iter()
            .map(|b| b.frame.var_list().to_vec())
            .collect();
        let moved = system
            .bodies
            .iter()
            .zip(&reads)
            .map(|(body, reads)| {
                reads
                    .iter()
                    .map(|&g| {
                        seeds[g].eps = Dual64::from_re(1.0);
                        let frame = body.frame.eval(&seeds);
                        seeds[g].eps = zero;
                        frame
                    })
                    .collect()
            })
            .collect();
        Ok(GradientFrames {
            x: x.to_vec(),
            at_x,
            reads,
            moved,
        })
    }

    /// Whether these are the frames at `x` (values and derivatives, bit for bit).
    pub fn are_at(&self, x: &[Dual64]) -> bool {
        let bits = |v: &Dual64| (v.re.to_bits(), v.eps.to_bits());
        self.x.iter().map(bits).eq(x.iter().map(bits))
    }

    /// Whether `system` has the bodies these frames are of, each reading the same
    /// coordinates (what a term's gradient picks its frames by).
    pub fn have_bodies_of<S: Real>(&self, system: &crate::System<S>) -> bool {
        self.reads.len() == system.bodies.len()
            && self
                .reads
                .iter()
                .zip(&system.bodies)
                .all(|(reads, body)| reads.as_slice() == body.frame.var_list())
    }
}

/// Every body's frame of `system` at x + Σₖ εₖuₖ for up to [`LANES`] directions `u` (the
/// lanes past them along no direction): the frames
/// [`TangentTerm::second_along_frames_lanes`] reads. More directions than lanes is an
/// error.
pub fn tangent_frames_along_lanes<S: Real>(
    system: &crate::System<S>,
    x: &[Dual64],
    u: &[&[f64]],
) -> Result<Vec<Frame<SecondLanes>>, EnergyError> {
    if u.len() > LANES {
        return Err(EnergyError::Length {
            function: "tangent_frames_along_lanes",
            argument: "u (directions, at most LANES)",
            expected: LANES,
            given: u.len(),
        });
    }
    let shortest = u.iter().map(|d| d.len()).min().unwrap_or(usize::MAX);
    frames_at(system, [("x", x.len()), ("u", shortest)], |i| {
        second_lanes_seed(
            x[i],
            std::array::from_fn(|k| u.get(k).map_or(0.0, |d| d[i])),
        )
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A body of two constant parts, 1 J and 2 J.
    struct TwoParts;

    impl TangentSharedPotential for TwoParts {
        fn parts(&self) -> usize {
            2
        }
        fn energies_on_frames<D: Lift<Dual64>>(&self, _frames: &[&Frame<D>], out: &mut [D]) {
            out[0] = D::from(1.0);
            out[1] = D::from(2.0);
        }
    }

    #[test]
    fn a_part_the_body_does_not_have_is_an_error_and_parts_sum_in_one_evaluation() {
        let frames = Arc::new(LocalFrames::default());
        let body = Arc::new(TwoParts);
        let first = TangentTerm::part("one", "k", "t", frames.clone(), body.clone(), 0).unwrap();
        let second = TangentTerm::part("two", "k", "t", frames.clone(), body.clone(), 1).unwrap();
        let e = TangentTerm::part("three", "k", "t", frames, body, 2).unwrap_err();
        assert!(e.to_string().contains("energy part"), "{e}");
        // the two parts of one body fold into one evaluation; their sum is 3 J
        let sum = TangentSum::new([&first, &second]);
        assert_eq!(sum.len(), 1);
        let value = sum.groups[0].0.body.value_d(&[], &sum.groups[0].1);
        assert_eq!(value.re.re, 3.0);
    }
}
