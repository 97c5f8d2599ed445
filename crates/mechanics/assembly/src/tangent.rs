//! The derivatives of a stage's stiffness and mass matrices with respect to one parameter,
//! exact: the model built with the parameter seeded (`System<Dual64>`), the equilibrium's
//! motion by the implicit function theorem, and the matrices differentiated along it
//! (step 4 of docs/exact-sensitivities.md).
//!
//! The equilibrium q*(p) solves g(q*, p) = 0 over the free coordinates, g the gradient of
//! the terms Newton minimises. Differentiating, K δq + ∂g/∂p = 0: δq = dq*/dp =
//! −K⁻¹ ∂g/∂p, with ∂g/∂p the dual part of the gradient at fixed q* (the terms' constants
//! carry their derivatives). The stage's stiffness is then differentiated along the
//! moving equilibrium: every term is built around q* + ε δq (a plug-in term's reference is
//! the equilibrium, so its clamp directions and tensions move with it) and its Hessian
//! evaluated there, whose dual part is the total dK/dp = ∂K/∂p + ∂K/∂q · δq (the third
//! derivatives of the energies along δq included). The mass matrix likewise, from the
//! bodies' velocity Jacobians at q* + ε δq and their dual masses and inertias.
//!
//! Projected on a few directions (the modes), the total derivative splits by the chain
//! rule: Wᵀ(dK/dp)W = Wᵀ(∂K/∂p)W + Σᵢ δqᵢ Wᵀ(∂K/∂qᵢ)W, the first at the fixed
//! equilibrium, the second with the terms rebuilt around q* + ε eᵢ. The second's
//! coefficients do not depend on the parameter: a [`Projection`] computes them once per
//! stage (one pass per free coordinate, over the terms on it; or only along the
//! coordinates some parameter moves beyond rounding, [`Projection::motion_along`]), and
//! each parameter then evaluates only the terms whose constants move with it
//! ([`TangentTerm::moves`]).

use nalgebra::{DMatrix, DVector, Vector3};
use num_dual::{Dual, Dual64};
use pendkit_energy::{
    EnergyError, GradientFrames, HyperTangent, LocalFrames, Reference, SharedBodies,
    TangentDerivatives, TangentSum, TangentTerm, check_plugin_elements, registry,
};
use pendkit_geometry::Frame;
use pendkit_rotations::{
    Constant, LANES, Real, SecondLanes, second_lanes_moving, second_lanes_seed, tr_mul, vee,
};
use pendkit_system::{CoordKind, EarlyWireTerms, Stage, System};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::equilibrium::{free_coordinates, free_slots, hessian_sum};
use crate::evaluate::Evaluator;
use crate::{AssemblyError, Layout};
use crate::{DerivativePath, in_parallel};

/// dq*/dp, dK/dp and dM/dp of one stage with respect to one parameter.
#[derive(Clone, Debug)]
pub struct StageTangent {
    /// dq*/dp, one entry per coordinate (m or rad per unit of the parameter; 0 on the
    /// coordinates Newton does not move: parameters and pinned ones).
    pub equilibrium: Vec<f64>,
    /// A bound on the rounding of each entry of `equilibrium` (same units; 0 on the
    /// coordinates Newton does not move): ε (|K⁻¹| (|K| |δq| + Σₜ |∂gₜ/∂p|)) with Σₜ over the
    /// balanced terms' forces, from the rounding of the sum ∂g/∂p (terms' forces that cancel)
    /// and of the solve. An entry within a small multiple of it is 0 but for rounding: the
    /// lateral coordinates of a suspension symmetric about its longitudinal plane, whose
    /// wires' lateral forces cancel. [`Projection::motion_along`] leaves such coordinates out.
    pub equilibrium_rounding: Vec<f64>,
    /// dK/dp (tension on) along the moving equilibrium (N/m, N, N m/rad per unit of the
    /// parameter): over all coordinates, global order (n × n), or projected on the
    /// directions asked for ([`Along`]).
    pub stiffness: DMatrix<f64>,
    /// dM/dp over the layout's variables (kg, kg m, kg m² per unit of the parameter).
    pub mass: DMatrix<f64>,
    /// |zᵀ dg/dp| once the equilibrium moves along δq, the larger of two fixed weightings z
    /// of the free coordinates with |zᵢ| in [½, 1] and mixed signs (N or N m per unit of
    /// the parameter; at most the sum of |dg/dp| over the free coordinates): the implicit
    /// function theorem's own check, zero but for rounding, which is measured against
    /// `forces`. By linearity zᵀ dg/dp = zᵀ ∂g/∂p + (H z)ᵀ δq, with H the balanced terms'
    /// stiffness from their dual forms (not the fast `f64` Hessians the equilibrium's motion
    /// was solved with), H z worked out once per stage ([`Balance`]): two dot products per
    /// parameter. An imbalance hides only if it is orthogonal to both weightings.
    pub residual: f64,
    /// The largest sum over the balanced terms of their |force| on one free coordinate at
    /// the equilibrium (N or N m): the scale of the forces' rounding.
    pub forces: f64,
}

/// The kinds' tangent terms whose stage passes `include`, built around `coords`; `None`
/// when some kind has none (the caller falls back to differences). With `moving_only` the
/// caller keeps only the terms whose constants move, and the kinds may leave out the
/// others ([`Reference::moving_only`]). `frames`: local frames of another build of the same
/// model, taken instead of made again ([`SharedBodies::with_frames`]).
fn kind_tangent_terms(
    system: &System<Dual64>,
    coords: &[Dual64],
    include: impl Fn(Stage) -> bool,
    moving_only: bool,
    frames: &[Arc<LocalFrames>],
) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
    // the seeded build is checked as the f64 one is (`terms_before`): every instance fits
    // its kind's schema before any term is built, so a kind reads its values unchecked on
    // this path too (a handful of instances: cheap next to building the terms)
    check_plugin_elements(system)?;
    let reference = if moving_only {
        Reference::moving_only(system, coords)
    } else {
        Reference::new(system, coords)
    };
    // one beam per wire for its bending and extra-stretch terms, as in the f64 assembly;
    // the local frames another build of the model made, where the caller has them
    let shared = SharedBodies::with_frames(frames.iter().cloned());
    let mut terms = Vec::new();
    for kind in registry().iter().filter(|k| {
        system
            .element_stage(k.kind(), k.stage())
            .is_some_and(&include)
    }) {
        match kind.tangent_terms(&reference, &shared)? {
            Some(t) => terms.extend(t),
            None => return Ok(None),
        }
    }
    Ok(Some(terms))
}

/// Sums of the terms' derivatives over the full coordinate vector: Hessian and gradient
/// (value parts in `.re`, parameter derivatives in `.eps`), and where asked for the sums of
/// the gradients' |parameter derivatives| (the scale of the sum's rounding).
struct Sums {
    hessian: DMatrix<Dual64>,
    gradient: DVector<Dual64>,
    /// Σₜ |∂gₜ/∂p| per coordinate, or empty (not kept).
    magnitudes: Vec<f64>,
}

impl Sums {
    fn new(n: usize) -> Self {
        let zero = Dual64::from_re(0.0);
        Sums {
            hessian: DMatrix::from_element(n, n, zero),
            gradient: DVector::from_element(n, zero),
            magnitudes: Vec::new(),
        }
    }

    /// Sums that hold the gradient only (for [`accumulate`] without the Hessian: no n × n
    /// matrix allocated once per parameter for nothing).
    fn gradient_only(n: usize) -> Self {
        Sums {
            hessian: DMatrix::from_element(0, 0, Dual64::from_re(0.0)),
            gradient: DVector::from_element(n, Dual64::from_re(0.0)),
            magnitudes: Vec::new(),
        }
    }

    /// [`Sums::gradient_only`] that also keeps Σₜ |∂gₜ/∂p| per coordinate.
    fn gradient_with_magnitudes(n: usize) -> Self {
        Sums {
            magnitudes: vec![0.0; n],
            ..Sums::gradient_only(n)
        }
    }
}

/// Adds each term's Hessian (or, when `hessian` is false, its gradient only) at `x`.
fn accumulate<'t>(
    terms: impl IntoIterator<Item = &'t TangentTerm>,
    x: &[Dual64],
    sums: &mut Sums,
    hessian: bool,
) -> Result<(), EnergyError> {
    add_derivatives(terms, sums, |term| {
        if hessian {
            term.derivatives(x)
        } else {
            term.gradient(x)
        }
    })
}

/// Adds each term's derivatives `derive(term)` (their gradient, and their Hessian where
/// they have one) into `sums`.
fn add_derivatives<'t>(
    terms: impl IntoIterator<Item = &'t TangentTerm>,
    sums: &mut Sums,
    derive: impl Fn(&TangentTerm) -> Result<TangentDerivatives, EnergyError>,
) -> Result<(), EnergyError> {
    for term in terms {
        let d = derive(term)?;
        let hessian = !d.hessian.is_empty();
        let m = term.coords.len();
        let magnitudes = !sums.magnitudes.is_empty();
        for (a, &ga) in term.coords.iter().enumerate() {
            sums.gradient[ga] += d.gradient[a];
            if magnitudes {
                sums.magnitudes[ga] += d.gradient[a].eps.abs();
            }
            if hessian {
                for (b, &gb) in term.coords.iter().enumerate() {
                    sums.hessian[(ga, gb)] += d.hessian[a * m + b];
                }
            }
        }
    }
    Ok(())
}

/// The stiffness of the terms Newton balances, over the free coordinates (not parameters,
/// not pinned), at the equilibrium, factorised: the same for every parameter, so built
/// once per stage ([`Balance::new`]) and shared by [`stage_tangent`]'s calls.
pub struct Balance {
    /// The model's coordinate names (a balance belongs to one model).
    coords: Vec<String>,
    free: Vec<usize>,
    lu: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    /// |K| and |K⁻¹| entry by entry over the free coordinates, for the rounding bound of
    /// δq ([`StageTangent::equilibrium_rounding`]); `None` when K has no inverse.
    abs_stiffness_and_inverse: Option<(DMatrix<f64>, DMatrix<f64>)>,
    /// The largest sum over the balanced terms of their |force| on one free coordinate
    /// (N or N m).
    forces: f64,
    /// The implicit function theorem's check ([`StageTangent::residual`]): each weighting z
    /// of the free coordinates ([`weightings`]) and H z, the balanced terms' stiffness
    /// along it from their dual forms, both over the free coordinates.
    checks: [(Vec<f64>, Vec<f64>); 2],
    /// The balanced terms of the model with constants that carry no derivative (the
    /// projection's motion passes over them too).
    balanced: Vec<TangentTerm>,
    /// Every body's frame at the equilibrium, with its moves along each coordinate: what
    /// each parameter's ∂g/∂p reads ([`stage_tangent`]).
    frames: GradientFrames,
    /// The local frames of the balanced terms, one per set of bodies: the terms of every
    /// parameter's model are built on them ([`SharedBodies::with_frames`]).
    local_frames: Vec<Arc<LocalFrames>>,
}

impl Balance {
    /// The balance of `system` at `equilibrium` (its full coordinate vector); `None` when the
    /// model has terms without parameter derivatives (see [`stage_tangent`]).
    pub fn new(system: &System, equilibrium: &[f64]) -> Result<Option<Balance>, AssemblyError> {
        let lifted = system.map_scalars(Dual64::from_re);
        check_equilibrium("Balance::new", &lifted, equilibrium)?;
        let Some(balanced) = balanced_terms(&lifted, false, &[])? else {
            return Ok(None);
        };
        // the local frames of its terms, one per set of bodies, for the builds of every
        // parameter's model
        let mut local_frames: Vec<Arc<LocalFrames>> = Vec::new();
        for term in &balanced {
            let frames = term.local_frames();
            if !local_frames.iter().any(|f| f.bodies == frames.bodies) {
                local_frames.push(frames.clone());
            }
        }
        let lifted_equilibrium: Vec<Dual64> =
            equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
        // the same terms in f64 (the stage-0A kinds built around the start), whose fast
        // Hessians are the stiffness: the dual forms would give it too, at ten times the
        // cost, to rounding
        let terms = crate::kind_terms(system, &system.start(), &SharedBodies::new(), |s| {
            s == Stage::S0A
        })?;
        let mut evaluator = Evaluator::new(system, DerivativePath::Fast);
        evaluator.extend(terms);
        evaluator.evaluate(equilibrium, true);
        let free = free_coordinates(system);
        let slot = free_slots(system.coords.len(), &free);
        let mut stiffness = DMatrix::zeros(free.len(), free.len());
        hessian_sum(&evaluator, &slot, &mut stiffness);
        // the scale of the forces' rounding: per free coordinate, Σ over the terms of |force|
        let mut magnitude = vec![0.0; free.len()];
        for (t, term) in evaluator.terms().iter().enumerate() {
            for (&g, force) in term.coords.iter().zip(evaluator.gradient(t)) {
                if let Some(k) = slot[g] {
                    magnitude[k] += force.abs();
                }
            }
        }
        let forces = magnitude.iter().copied().fold(0.0, f64::max);
        // H z from the dual terms: their gradient at the equilibrium moved along z (the
        // lifted model's constants carry no derivative, so the dual parts are H z)
        let checks = weightings(equilibrium.len(), &free).map(|z| {
            let along: Vec<Dual64> = equilibrium
                .iter()
                .zip(&z)
                .map(|(&v, &d)| Dual64::new(v, d))
                .collect();
            let frames = GradientFrames::new(system, &along)?;
            let mut sums = Sums::gradient_only(equilibrium.len());
            add_derivatives(&balanced, &mut sums, |t| t.gradient_from(&frames))?;
            let weights = free.iter().map(|&i| z[i]).collect();
            let stiffness = free.iter().map(|&i| sums.gradient[i].eps).collect();
            Ok::<_, EnergyError>((weights, stiffness))
        });
        let [first, second] = checks;
        let lu = stiffness.clone().lu();
        let abs_stiffness_and_inverse = lu
            .try_inverse()
            .map(|inverse| (stiffness.map(f64::abs), inverse.map(f64::abs)));
        Ok(Some(Balance {
            coords: coordinate_names(system),
            free,
            lu,
            abs_stiffness_and_inverse,
            forces,
            checks: [first?, second?],
            balanced,
            frames: GradientFrames::new(system, &lifted_equilibrium)?,
            local_frames,
        }))
    }

    /// The implicit function theorem's check ([`StageTangent::residual`]) of the motion
    /// `delta` (dq*/dp) against the forces' parameter derivative `dg` at fixed
    /// coordinates, both over the free coordinates: the larger |zᵀ dg + (H z)ᵀ delta| of
    /// the two weightings z (NaN if either is).
    fn imbalance(&self, dg: &[f64], delta: &[f64]) -> f64 {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        self.checks.iter().fold(0.0, |worst: f64, (z, hz)| {
            let sum = dot(z, dg) + dot(hz, delta);
            // NaN kept (max would drop it): the caller refuses it
            if sum.is_nan() || worst.is_nan() {
                f64::NAN
            } else {
                worst.max(sum.abs())
            }
        })
    }

    /// The rounding bound of the motion `delta` solved from the forces' derivative whose
    /// terms' |parts| sum to `magnitudes` (both over the free coordinates):
    /// ε (|K⁻¹| (|K| |δq| + magnitudes)), the first-order bound of the sum's rounding and the
    /// solve's carried through K⁻¹ ([`StageTangent::equilibrium_rounding`]). 0 (nothing is
    /// rounding) when K has no inverse, and for an entry whose bound is not finite.
    fn motion_rounding(&self, delta: &DVector<f64>, magnitudes: &DVector<f64>) -> DVector<f64> {
        match &self.abs_stiffness_and_inverse {
            Some((stiffness, inverse)) => {
                let bound = inverse * (stiffness * delta.map(f64::abs) + magnitudes);
                bound.map(|b| if b.is_finite() { b * f64::EPSILON } else { 0.0 })
            }
            None => DVector::zeros(delta.len()),
        }
    }

    /// The local frames a build of `system` may take from the balance's model: all of
    /// them when its bodies read the same coordinates, else none.
    fn local_frames_for<S: Real>(&self, system: &System<S>) -> &[Arc<LocalFrames>] {
        if self.frames.have_bodies_of(system) {
            &self.local_frames
        } else {
            &[]
        }
    }

    /// Whether `system` has the coordinates this balance was built for.
    fn fits<S: Real>(&self, system: &System<S>) -> bool {
        self.coords.iter().eq(system.coords.iter().map(|c| &c.name))
    }
}

fn coordinate_names<S: Real>(system: &System<S>) -> Vec<String> {
    system.coords.iter().map(|c| c.name.clone()).collect()
}

/// The terms Newton minimised: the stage-0A kinds' (their constants do not depend on the
/// configuration they are built around). `None` when some kind has no tangent terms, when
/// the model has user-written terms (text: whether their numbers move with the parameter
/// is unknown), or when plug-in terms join the equilibrium: those are built around the
/// start position, which moves with the parameters (the nominal geometry) but whose
/// derivative the model does not carry (`Coordinate::start` is a number, not a model
/// constant). With `moving_only` the kinds may leave out terms whose constants do not move
/// ([`kind_tangent_terms`]).
fn balanced_terms(
    system: &System<Dual64>,
    moving_only: bool,
    frames: &[Arc<LocalFrames>],
) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
    if !system.extra_terms.is_empty() || system.early_wire_terms != EarlyWireTerms::No {
        return Ok(None);
    }
    let start: Vec<Dual64> = system.start().into_iter().map(Dual64::from_re).collect();
    kind_tangent_terms(system, &start, |s| s == Stage::S0A, moving_only, frames)
}

/// `equilibrium` is a finite full coordinate vector of `system`, whose indices are valid.
fn check_equilibrium<S: Real>(
    function: &'static str,
    system: &System<S>,
    equilibrium: &[f64],
) -> Result<(), AssemblyError> {
    let n = system.coords.len();
    if equilibrium.len() != n {
        return Err(AssemblyError::Length {
            function,
            argument: "equilibrium",
            expected: n,
            given: equilibrium.len(),
        });
    }
    check_finite(function, "equilibrium", equilibrium)?;
    Ok(system.check_indices()?)
}

/// Every entry of `values` is finite.
fn check_finite(
    function: &'static str,
    argument: &'static str,
    values: &[f64],
) -> Result<(), AssemblyError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(AssemblyError::NotFiniteInput {
            function,
            argument,
            index,
        }),
        None => Ok(()),
    }
}

/// Which part of dK/dp [`stage_tangent`] computes.
#[derive(Clone, Copy, Debug)]
pub enum Along<'a> {
    /// Every entry (n × n, global order): one evaluation per entry of each term's upper
    /// triangle.
    Full,
    /// The entries (a, b) of Wᵀ (dK/dp) W that `projection` lists (the rest 0): one
    /// evaluation per term whose constants move with the parameter for every group of up
    /// to [`LANES`] pairs along one direction and for every pair across two, the rest from
    /// the projection's coefficients (left out for a projection without them,
    /// [`Projection::at_rest`]: [`Projection::add_motion`] adds them afterwards).
    Projected(&'a Projection),
}

/// Pairs of directions evaluated together, with their seeds (every coordinate at the
/// equilibrium along the pairs) and every body's frame there: what the entries of
/// Wᵀ(dK/dp)W for those pairs evaluate the terms on. Up to [`LANES`] pairs along one
/// direction each (a = b) share one evaluation, one lane each ([`SecondLanes`]); a pair
/// across two directions (a ≠ b, within a cluster of equal ω²) takes the hyper-dual
/// number alone.
#[derive(Debug)]
struct PairGroup<T> {
    /// The pairs, as indices into the projection's list, in lane order.
    pairs: Vec<usize>,
    seeds: Vec<T>,
    frames: Vec<Frame<T>>,
}

/// A [`PairGroup`] of either kind.
#[derive(Debug)]
enum Group {
    Along(PairGroup<SecondLanes>),
    Across(PairGroup<HyperTangent>),
}

/// The scalars of a [`PairGroup`]: a seed moved along its own coordinate, and the second
/// derivatives of terms along the group's pairs.
trait PairScalar: Real {
    /// The seed of coordinate i at x + ε eᵢ: its value's derivative set to 1 (the
    /// directions' entries do not move with it).
    fn moving(self) -> Self;
    /// Σ of the terms' second derivatives along each of the group's `count` pairs, each
    /// with its derivative.
    fn seconds(
        terms: &TangentSum,
        frames: &[Frame<Self>],
        count: usize,
    ) -> Result<Vec<Dual64>, EnergyError>;
}

impl PairScalar for SecondLanes {
    fn moving(self) -> Self {
        second_lanes_moving(self)
    }
    fn seconds(
        terms: &TangentSum,
        frames: &[Frame<Self>],
        count: usize,
    ) -> Result<Vec<Dual64>, EnergyError> {
        let lanes = terms.second_along_frames_lanes(frames)?;
        Ok(lanes[..count].to_vec())
    }
}

impl PairScalar for HyperTangent {
    fn moving(self) -> Self {
        HyperTangent::new(
            Dual64::new(self.re.re, 1.0),
            self.eps1,
            self.eps2,
            self.eps1eps2,
        )
    }
    fn seconds(
        terms: &TangentSum,
        frames: &[Frame<Self>],
        _count: usize,
    ) -> Result<Vec<Dual64>, EnergyError> {
        Ok(vec![terms.second_along_frames(frames)?])
    }
}

impl<T: PairScalar> PairGroup<T> {
    /// The group of `pairs` (indices into the projection's list) with the seeds `seed(j)`.
    fn new(system: &System, n: usize, pairs: Vec<usize>, seed: impl Fn(usize) -> T) -> Self {
        let seeds: Vec<T> = (0..n).map(seed).collect();
        let frames = system.bodies.iter().map(|b| b.frame.eval(&seeds)).collect();
        PairGroup {
            pairs,
            seeds,
            frames,
        }
    }

    /// Σ `terms` along the group's pairs at the equilibrium: one value per pair.
    fn seconds(&self, terms: &TangentSum) -> Result<Vec<Dual64>, EnergyError> {
        T::seconds(terms, &self.frames, self.pairs.len())
    }

    /// Wᵀ(∂K/∂qᵢ)W for the group's pairs and each free coordinate i of `coordinates` (each
    /// with the bodies it moves and the terms whose energy it changes: the terms on it,
    /// and the terms built around x + ε eᵢ whose constants moved with it): the group's
    /// frames with those bodies re-evaluated at x + ε eᵢ, and the terms summed there. One
    /// (coordinate, value per pair) per coordinate.
    fn geometric_rows(
        &self,
        system: &System,
        coordinates: &[(usize, Vec<usize>, TangentSum)],
    ) -> Result<Vec<(usize, Vec<f64>)>, EnergyError> {
        // copies in which one coordinate at a time moves, with the bodies on it
        let mut frames = self.frames.clone();
        let mut seeds = self.seeds.clone();
        let mut rows = Vec::with_capacity(coordinates.len());
        let mut moved: &[usize] = &[];
        for (i, bodies, terms) in coordinates {
            let i = *i;
            // the bodies the coordinate before moved go back to rest, but for those this one
            // moves (re-evaluated below): consecutive coordinates are mostly on the same
            // bodies, whose frames are then not copied back only to be evaluated again
            for &b in moved.iter().filter(|b| !bodies.contains(b)) {
                frames[b] = self.frames[b].clone();
            }
            seeds[i] = self.seeds[i].moving();
            for &b in bodies {
                frames[b] = system.bodies[b].frame.eval(&seeds);
            }
            seeds[i] = self.seeds[i];
            moved = bodies;
            let sums = T::seconds(terms, &frames, self.pairs.len())?;
            rows.push((i, sums.iter().map(|v| v.eps).collect()));
        }
        Ok(rows)
    }
}

impl Group {
    fn pairs(&self) -> &[usize] {
        match self {
            Group::Along(g) => &g.pairs,
            Group::Across(g) => &g.pairs,
        }
    }
    fn seconds(&self, terms: &TangentSum) -> Result<Vec<Dual64>, EnergyError> {
        match self {
            Group::Along(g) => g.seconds(terms),
            Group::Across(g) => g.seconds(terms),
        }
    }
    fn geometric_rows(
        &self,
        system: &System,
        coordinates: &[(usize, Vec<usize>, TangentSum)],
    ) -> Result<Vec<(usize, Vec<f64>)>, EnergyError> {
        match self {
            Group::Along(g) => g.geometric_rows(system, coordinates),
            Group::Across(g) => g.geometric_rows(system, coordinates),
        }
    }
}

/// How many free coordinates one unit of the projection's parallel work takes: enough
/// units for the threads when there are only a few groups and coordinates (the quad's 24
/// modes make four groups, and the 12 coordinates its parameters move three blocks), few
/// enough that each unit's copy of the frames is small beside its passes.
const COORDINATES_PER_UNIT: usize = 4;

/// What the directional derivatives Wᵀ(dK/dp)W of one stage share between parameters:
/// the directions W (full coordinate vectors, e.g. the modes lifted to the floats), the
/// pairs (a, b) wanted, every body's frame at the equilibrium along each group of pairs
/// (up to [`LANES`] pairs along one direction each, or one pair across two), and the
/// coefficients Wₐᵀ(∂K/∂qᵢ)W_b of the equilibrium's motion, one per pair and free
/// coordinate (the terms rebuilt around q* + ε eᵢ: their dependence on the configuration
/// they are built around included).
#[derive(Debug)]
pub struct Projection {
    coords: Vec<String>,
    stage: Stage,
    equilibrium: Vec<f64>,
    pairs: Vec<(usize, usize)>,
    directions: usize,
    groups: Vec<Group>,
    /// The equilibrium's motion, once computed ([`Projection::at_rest`] has none).
    motion: Option<Motion>,
    /// This projection among the projections made by the process (a motion belongs to one).
    id: u64,
}

/// The coefficients Wₐᵀ(∂K/∂qᵢ)W_b of a [`Projection`]'s pairs, one row per pair and one
/// column per coordinate (0 on the coordinates that are not free): what the equilibrium's
/// motion δq adds to each pair's entry of Wᵀ(dK/dp)W, Σᵢ δqᵢ Wₐᵀ(∂K/∂qᵢ)W_b.
#[derive(Debug)]
pub struct Motion {
    geometric: DMatrix<f64>,
    /// Per coordinate, whether its column was computed ([`Projection::motion_along`]).
    covered: Vec<bool>,
    /// The projection it was computed for.
    projection: u64,
}

/// How many times its rounding bound ([`StageTangent::equilibrium_rounding`]) an entry of
/// dq*/dp may be and still count as 0. The entries of the quad and the triple that are
/// rounding (lateral coordinates no parameter moves) measure at up to ≈ 65 times the bound
/// over every parameter (below 10² on every bundled model), and most entries that move 10¹⁰ times it and more (in the
/// beaded models, whose stiffness is ill-conditioned, a few entries fall between, 10²–10⁵
/// times their bound). Leaving out a coordinate within the margin changes the result by at most this
/// many times the rounding the coordinate's motion already carries, so the margin is kept
/// small: 10² leaves out the same coordinates as 10³ on every bundled model.
pub const ROUNDING_MARGIN: f64 = 1e2;

/// Whether an entry `delta` of dq*/dp moves beyond its `rounding` bound (by more than
/// [`ROUNDING_MARGIN`] times it; a NaN entry or bound does).
pub fn moves_beyond_rounding(delta: f64, rounding: f64) -> bool {
    delta.is_nan() || rounding.is_nan() || delta.abs() > ROUNDING_MARGIN * rounding
}

impl Projection {
    /// The projection of `system`'s stage `stage` at `equilibrium` (its full coordinate
    /// vector, with the equilibrium's `balance`) on the directions `vectors` (one column
    /// each, n rows) for the entries `pairs` (a ≤ b), computed on `threads` threads (0: as
    /// many as the machine has; the numbers do not depend on it). `None` when the model has
    /// terms without parameter derivatives (see [`stage_tangent`]). Costs one build of the
    /// plug-in terms and one pass over the terms on it per free coordinate, for every group
    /// of up to [`LANES`] pairs along one direction and every pair across two: what
    /// [`Projection::at_rest`] and [`Projection::motion`] cost together.
    pub fn new(
        system: &System,
        stage: Stage,
        equilibrium: &[f64],
        balance: &Balance,
        directions: (&DMatrix<f64>, &[(usize, usize)]),
        threads: usize,
    ) -> Result<Option<Projection>, AssemblyError> {
        let projection = Projection::at_rest(system, stage, equilibrium, balance, directions)?;
        let Some(motion) = projection.motion(system, balance, threads)? else {
            return Ok(None);
        };
        Ok(Some(projection.with_motion(motion)?))
    }

    /// The projection without the equilibrium's motion: the pairs' groups and every body's
    /// frame along them (what each parameter's terms at the fixed equilibrium are evaluated
    /// on), cheap beside the motion's coefficients ([`Projection::motion`]), which a caller
    /// may compute beside the parameters' passes and add afterwards
    /// ([`Projection::add_motion`]). The arguments are [`Projection::new`]'s; a model with
    /// terms without parameter derivatives is found by [`Projection::motion`] and
    /// [`stage_tangent`] (`None`).
    pub fn at_rest(
        system: &System,
        stage: Stage,
        equilibrium: &[f64],
        balance: &Balance,
        (vectors, pairs): (&DMatrix<f64>, &[(usize, usize)]),
    ) -> Result<Projection, AssemblyError> {
        check_equilibrium("Projection::new", system, equilibrium)?;
        if !balance.fits(system) {
            return Err(AssemblyError::ForeignBalance);
        }
        let n = system.coords.len();
        if vectors.nrows() != n {
            return Err(AssemblyError::Length {
                function: "Projection::new",
                argument: "vectors (rows)",
                expected: n,
                given: vectors.nrows(),
            });
        }
        check_finite("Projection::new", "vectors", vectors.as_slice())?;
        let m = vectors.ncols();
        if let Some(&(a, b)) = pairs.iter().find(|&&(a, b)| a.max(b) >= m) {
            return Err(AssemblyError::Length {
                function: "Projection::new",
                argument: "pairs (a direction's index)",
                expected: m,
                given: a.max(b) + 1,
            });
        }
        let columns: Vec<Vec<f64>> = (0..m)
            .map(|a| vectors.column(a).iter().copied().collect())
            .collect();
        let at_rest = |j: usize| Dual64::from_re(equilibrium[j]);
        // the pairs along one direction in groups of LANES, each pair across two alone
        let (along, across): (Vec<usize>, Vec<usize>) =
            (0..pairs.len()).partition(|&k| pairs[k].0 == pairs[k].1);
        let mut groups: Vec<Group> = along
            .chunks(LANES)
            .map(|chunk| {
                let group = PairGroup::new(system, n, chunk.to_vec(), |j| {
                    second_lanes_seed(
                        at_rest(j),
                        std::array::from_fn(|l| {
                            chunk.get(l).map_or(0.0, |&k| columns[pairs[k].0][j])
                        }),
                    )
                });
                Group::Along(group)
            })
            .collect();
        groups.extend(across.into_iter().map(|k| {
            let (u, v) = (&columns[pairs[k].0], &columns[pairs[k].1]);
            let zero = Dual64::from_re(0.0);
            Group::Across(PairGroup::new(system, n, vec![k], |j| {
                HyperTangent::new(
                    at_rest(j),
                    Dual64::from_re(u[j]),
                    Dual64::from_re(v[j]),
                    zero,
                )
            }))
        }));
        static PROJECTIONS_MADE: AtomicU64 = AtomicU64::new(0);
        Ok(Projection {
            coords: coordinate_names(system),
            stage,
            equilibrium: equilibrium.to_vec(),
            pairs: pairs.to_vec(),
            directions: m,
            groups,
            motion: None,
            id: PROJECTIONS_MADE.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// The coefficients of the equilibrium's motion for this projection of `system` (the
    /// model [`Projection::at_rest`] was given, with its `balance`), on `threads` threads:
    /// one build of the plug-in terms and one pass over the terms on it per free
    /// coordinate, for every group of pairs. `None` when the model has terms without
    /// parameter derivatives.
    pub fn motion(
        &self,
        system: &System,
        balance: &Balance,
        threads: usize,
    ) -> Result<Option<Motion>, AssemblyError> {
        self.motion_along(system, balance, threads, &vec![true; self.coords.len()])
    }

    /// [`Projection::motion`] for the free coordinates `moved` marks (one flag per
    /// coordinate) only: the others' coefficients are not computed, and
    /// [`Projection::add_motion`] refuses a motion δq that moves along one of them beyond
    /// rounding. For a request whose parameters' motions are known first: the lateral
    /// coordinates of a symmetric suspension, which no parameter moves, cost nothing.
    pub fn motion_along(
        &self,
        system: &System,
        balance: &Balance,
        threads: usize,
        moved: &[bool],
    ) -> Result<Option<Motion>, AssemblyError> {
        if !balance.fits(system) || self.coords != balance.coords {
            return Err(AssemblyError::ForeignBalance);
        }
        if moved.len() != self.coords.len() {
            return Err(AssemblyError::Length {
                function: "Projection::motion_along",
                argument: "moved",
                expected: self.coords.len(),
                given: moved.len(),
            });
        }
        let free: Vec<usize> = balance.free.iter().copied().filter(|&i| moved[i]).collect();
        // the plug-in terms are built around x + ε eᵢ below; the balanced ones, whose
        // constants do not depend on where they are built, are the balance's
        let lifted = system.map_scalars(Dual64::from_re);
        let balanced = &balance.balanced;
        let (equilibrium, stage, n) = (&self.equilibrium, self.stage, self.coords.len());
        // per free coordinate: the bodies it moves, and the terms whose energy it changes
        // (the terms on it, and the plug-in terms built around x + ε eᵢ whose constants
        // moved with it)
        // (with no coordinate, one build at rest still finds a kind without tangent terms)
        let builds = free.len().max(1);
        let plugins = in_parallel(builds, threads, |a| {
            let mut moved: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
            if let Some(&i) = free.get(a) {
                moved[i].eps = 1.0;
            }
            // kept below: the terms whose constants moved with the coordinate, and the terms
            // on it, whose bodies' frames move with it; no other term is needed
            kind_tangent_terms(
                &lifted,
                &moved,
                |s| s != Stage::S0A && s <= stage,
                true,
                balance.local_frames_for(system),
            )
        })?;
        let Some(plugins) = plugins.into_iter().collect::<Option<Vec<_>>>() else {
            return Ok(None);
        };
        let coordinates: Vec<(usize, Vec<usize>, TangentSum)> = free
            .iter()
            .zip(&plugins)
            .map(|(&i, plugins)| {
                let bodies = (0..system.bodies.len())
                    .filter(|&b| system.bodies[b].frame.var_list().contains(&i))
                    .collect();
                let terms = TangentSum::new(
                    balanced.iter().filter(|t| t.coords.contains(&i)).chain(
                        plugins
                            .iter()
                            .filter(|t| t.moves() || t.coords.contains(&i)),
                    ),
                );
                (i, bodies, terms)
            })
            .collect();
        // one unit of work per group and block of free coordinates
        let blocks: Vec<&[(usize, Vec<usize>, TangentSum)]> =
            coordinates.chunks(COORDINATES_PER_UNIT).collect();
        let units = in_parallel(self.groups.len() * blocks.len(), threads, |u| {
            self.groups[u / blocks.len()].geometric_rows(system, blocks[u % blocks.len()])
        })?;
        let mut geometric = DMatrix::zeros(self.pairs.len(), n);
        for (u, rows) in units.into_iter().enumerate() {
            let group = &self.groups[u / blocks.len()];
            for (i, values) in rows {
                for (&k, value) in group.pairs().iter().zip(values) {
                    geometric[(k, i)] = value;
                }
            }
        }
        let mut covered = vec![false; n];
        for &i in &free {
            covered[i] = true;
        }
        Ok(Some(Motion {
            geometric,
            covered,
            projection: self.id,
        }))
    }

    /// This projection with the equilibrium's `motion` (from [`Projection::motion`] of this
    /// projection, else an error): [`stage_tangent`] then adds it itself.
    pub fn with_motion(self, motion: Motion) -> Result<Projection, AssemblyError> {
        if motion.projection != self.id {
            return Err(AssemblyError::ForeignMotion);
        }
        Ok(Projection {
            motion: Some(motion),
            ..self
        })
    }

    /// Adds the equilibrium's motion `delta` (dq*/dp, full coordinate vector, as
    /// [`StageTangent::equilibrium`], with its `rounding`, [`StageTangent::equilibrium_rounding`])
    /// through `motion` (this projection's) to `stiffness`, a [`StageTangent::stiffness`]
    /// computed with the projection at rest: the pairs' entries and their mirrors. Another
    /// projection's motion, inputs of other sizes, or a δq that moves beyond rounding along a
    /// coordinate the motion left out ([`Projection::motion_along`]) are errors.
    pub fn add_motion(
        &self,
        motion: &Motion,
        stiffness: &mut DMatrix<f64>,
        delta: &[f64],
        rounding: &[f64],
    ) -> Result<(), AssemblyError> {
        if motion.projection != self.id {
            return Err(AssemblyError::ForeignMotion);
        }
        let length = |argument, expected, given| AssemblyError::Length {
            function: "Projection::add_motion",
            argument,
            expected,
            given,
        };
        for (argument, given) in [("delta", delta.len()), ("rounding", rounding.len())] {
            if given != self.coords.len() {
                return Err(length(argument, self.coords.len(), given));
            }
        }
        if let Some(i) = (0..delta.len())
            .find(|&i| !motion.covered[i] && moves_beyond_rounding(delta[i], rounding[i]))
        {
            return Err(AssemblyError::MotionLeftOut {
                coordinate: self.coords[i].clone(),
            });
        }
        for (argument, given) in [
            ("stiffness (rows)", stiffness.nrows()),
            ("stiffness (columns)", stiffness.ncols()),
        ] {
            if given != self.directions {
                return Err(length(argument, self.directions, given));
            }
        }
        let moved = &motion.geometric * DVector::from_column_slice(delta);
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            stiffness[(a, b)] += moved[k];
            if a != b {
                stiffness[(b, a)] = stiffness[(a, b)];
            }
        }
        Ok(())
    }

    /// Wᵀ(dK/dp)W (directions × directions, the pairs' entries and their mirrors, the rest
    /// 0): the terms whose constants move evaluated at the fixed equilibrium, plus the
    /// coefficients times the equilibrium's motion `delta` when the projection has them.
    fn derivative(
        &self,
        moving: &TangentSum,
        delta: &[f64],
        rounding: &[f64],
    ) -> Result<DMatrix<f64>, AssemblyError> {
        let mut out = DMatrix::zeros(self.directions, self.directions);
        for group in &self.groups {
            for (&k, partial) in group.pairs().iter().zip(group.seconds(moving)?) {
                let (a, b) = self.pairs[k];
                out[(a, b)] = partial.eps;
                out[(b, a)] = partial.eps;
            }
        }
        if let Some(motion) = &self.motion {
            self.add_motion(motion, &mut out, delta, rounding)?;
        }
        Ok(out)
    }
}

/// Two fixed weightings of the free coordinates, |zᵢ| in [½, 1] with mixed signs (a
/// low-discrepancy sequence, so that no structured residual is orthogonal to both).
fn weightings(n: usize, free: &[usize]) -> [Vec<f64>; 2] {
    let golden = 0.618_033_988_749_894_9;
    let root_half = std::f64::consts::FRAC_1_SQRT_2;
    std::array::from_fn(|w| {
        let mut z = vec![0.0; n];
        for (k, &i) in free.iter().enumerate() {
            let step = if w == 0 { golden } else { root_half };
            let size = 0.5 + 0.5 * ((k as f64 + 1.0) * step).fract();
            let sign = if (k + w) % 2 == 0 || (k % 3 == 1 && w == 1) {
                1.0
            } else {
                -1.0
            };
            z[i] = sign * size;
        }
        z
    })
}

/// The exact derivatives of stage `stage`'s stiffness and mass with respect to the
/// parameter `system` was built with seeded, at the equilibrium `equilibrium` (the `f64`
/// model's, full coordinate vector) with the stage's `layout` and the equilibrium's
/// `balance` (from the `f64` model). `None` when the model has terms without such
/// derivatives (a kind without tangent terms, user-written terms, wire terms that join the
/// equilibrium), for which the caller keeps to differences. The balance and a projection
/// must be those of the model whose value part `system` is (what [`Balance::new`] and
/// [`Projection::new`] were given): only their coordinates, stage and equilibrium are
/// checked against it.
pub fn stage_tangent(
    system: &System<Dual64>,
    stage: Stage,
    equilibrium: &[f64],
    layout: &Layout,
    balance: &Balance,
    along: Along,
) -> Result<Option<StageTangent>, AssemblyError> {
    check_equilibrium("stage_tangent", system, equilibrium)?;
    crate::check_layout("stage_tangent", system, layout)?;
    let n = system.coords.len();
    let free = &balance.free;
    if !balance.fits(system) {
        return Err(AssemblyError::ForeignBalance);
    }
    if let Along::Projected(p) = along
        && (p.coords != balance.coords || p.stage != stage || p.equilibrium != equilibrium)
    {
        return Err(AssemblyError::ForeignProjection);
    }
    // the projected route evaluates only the terms whose constants move at the fixed
    // equilibrium (the equilibrium's motion is the projection's), so only those are built
    let moving_only = matches!(along, Along::Projected(_));
    let local_frames = balance.local_frames_for(system);
    let Some(balanced) = balanced_terms(system, moving_only, local_frames)? else {
        return Ok(None);
    };
    // ∂g/∂p at the fixed equilibrium (only the terms whose constants move have one), and
    // δq = −K⁻¹ ∂g/∂p
    let at_rest: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
    let mut rest = Sums::gradient_with_magnitudes(n);
    let moving_balanced = balanced.iter().filter(|t| t.moves());
    if balance.frames.are_at(&at_rest) && balance.frames.have_bodies_of(system) {
        // the bodies' frames the balance evaluated at the equilibrium, shared by every term
        // (and every parameter): the same numbers as each term's own
        add_derivatives(moving_balanced, &mut rest, |t| {
            t.gradient_from(&balance.frames)
        })?;
    } else {
        accumulate(moving_balanced, &at_rest, &mut rest, false)?;
    }
    let dg_free = DVector::from_fn(free.len(), |a, _| rest.gradient[free[a]].eps);
    let delta_free = if dg_free.amax() == 0.0 {
        DVector::zeros(free.len())
    } else {
        balance
            .lu
            .solve(&(-&dg_free))
            .ok_or(AssemblyError::SingularEquilibrium)?
    };
    let magnitudes_free = DVector::from_fn(free.len(), |a, _| rest.magnitudes[free[a]]);
    let rounding_free = balance.motion_rounding(&delta_free, &magnitudes_free);
    let mut delta = vec![0.0; n];
    let mut equilibrium_rounding = vec![0.0; n];
    for (a, &gi) in free.iter().enumerate() {
        delta[gi] = delta_free[a];
        equilibrium_rounding[gi] = rounding_free[a];
    }
    // the equilibrium moving with the parameter
    let moving: Vec<Dual64> = equilibrium
        .iter()
        .zip(&delta)
        .map(|(&v, &d)| Dual64::new(v, d))
        .collect();
    let residual = balance.imbalance(dg_free.as_slice(), delta_free.as_slice());
    let plugin_stage = |s: Stage| s != Stage::S0A && s <= stage;
    let stiffness = match along {
        Along::Full => {
            // the stage's plug-in terms built around the moving equilibrium, and every
            // term's Hessian there
            let Some(plugins) =
                kind_tangent_terms(system, &moving, plugin_stage, false, local_frames)?
            else {
                return Ok(None);
            };
            let mut sums = Sums::new(n);
            for term in balanced.iter().chain(&plugins) {
                add_hessian(term, &moving, &mut sums)?;
            }
            sums.hessian.map(|v| v.eps)
        }
        Along::Projected(projection) => {
            // the plug-in terms built around the fixed equilibrium: the parameter's own
            // part; the equilibrium's motion is the projection's
            let Some(plugins) =
                kind_tangent_terms(system, &at_rest, plugin_stage, true, local_frames)?
            else {
                return Ok(None);
            };
            let moving_terms =
                TangentSum::new(balanced.iter().chain(&plugins).filter(|t| t.moves()));
            projection.derivative(&moving_terms, &delta, &equilibrium_rounding)?
        }
    };
    Ok(Some(StageTangent {
        equilibrium: delta,
        equilibrium_rounding,
        stiffness,
        mass: mass_tangent(system, layout, &moving),
        residual,
        forces: balance.forces,
    }))
}

/// Adds one term's Hessian at `x` into `sums`.
fn add_hessian(term: &TangentTerm, x: &[Dual64], sums: &mut Sums) -> Result<(), EnergyError> {
    accumulate([term], x, sums, true)
}

/// dM/dp over the layout's variables: M = Σ_b m J_pᵀ J_p + J_ωᵀ I J_ω with the velocity
/// Jacobians of each body's centre of mass (J_p) and body-axis angular velocity (J_ω,
/// Rᵀ ∂R/∂q = [ω]×) at `x`, all carrying their parameter derivatives.
fn mass_tangent(system: &System<Dual64>, layout: &Layout, x: &[Dual64]) -> DMatrix<f64> {
    let nx = layout.variables.len();
    let mut m = DMatrix::from_element(nx, nx, Dual64::from_re(0.0));
    let mut seeded: Vec<Dual<Dual64>> = x.iter().map(|&v| Dual::from_re(v)).collect();
    for body in &system.bodies {
        if body.mass.is_exactly_zero() && body.inertia.iter().all(|v| v.is_exactly_zero()) {
            continue;
        }
        let reads = body.frame.var_list();
        // a body whose numbers do not move, on coordinates that do not move, adds exactly 0
        let numbers_move = body.mass.moves()
            || body
                .inertia
                .iter()
                .chain(&body.centre_of_mass)
                .any(|v| v.moves());
        if !numbers_move && reads.iter().all(|&g| !x[g].moves()) {
            continue;
        }
        let vars: Vec<usize> = reads
            .iter()
            .copied()
            .filter(|&g| system.coords[g].kind == CoordKind::Variable)
            .collect();
        let columns: Vec<(usize, Vector3<Dual64>, Vector3<Dual64>)> = vars
            .iter()
            .map(|&g| {
                seeded[g].eps = Dual64::from_re(1.0);
                let frame = body.frame.eval(&seeded);
                seeded[g].eps = Dual64::from_re(0.0);
                let point = frame.point(&body.centre_of_mass);
                let dr = frame.rotation.map(|v| v.eps);
                let r = frame.rotation.map(|v| v.re);
                (g, point.map(|v| v.eps), vee(&tr_mul(&r, &dr)))
            })
            .collect();
        for (gi, pi, wi) in &columns {
            for (gj, pj, wj) in &columns {
                let iw = body.inertia * wj;
                let value = body.mass * pi.dot(pj) + wi.dot(&iw);
                m[(layout.position[*gi], layout.position[*gj])] += value;
            }
        }
    }
    m.map(|v| v.eps)
}
