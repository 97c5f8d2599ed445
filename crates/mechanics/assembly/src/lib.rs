//! Collects a model's potential terms for a calculation stage, finds the equilibrium by
//! Newton minimisation, differentiates each term twice over its own coordinates (tension on
//! and off) and assembles the master stiffness matrix (blocks K, C_XQ, C_XS, Q, C_QS, S) and
//! the mass matrix from the bodies.
//!
//! Nothing is done twice: the terms are built once (the stage-0A terms Newton minimises
//! are the ones assembled), every body's frame jet is computed once per configuration and
//! shared by its terms and the mass matrix, shared energy bodies (a wire's beam) are
//! evaluated once for all their terms, and Newton's last evaluation is taken over when it
//! was made at the equilibrium. [`assemble_with`] can record the time of each phase.

mod equilibrium;
mod evaluate;
mod parallel;
mod redundant;
mod sparse;
mod tangent;
mod timing;

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, Vector3};
use pendkit_energy::{
    EnergyError, Reference, SharedBodies, Term, constraint_terms, extra_terms, registry,
};
use pendkit_geometry::FrameJet;
use pendkit_system::{CoordKind, EarlyWireTerms, ExtraPhase, Stage, System};

pub use equilibrium::{Equilibrium, EquilibriumOptions, find_equilibrium};
pub use evaluate::DerivativePath;
pub use parallel::{
    MAX_THREADS_PER_CORE, in_parallel, in_parallel_with, side_by_side, thread_count,
};
pub use pendkit_energy::OffHessian;
pub use sparse::{DENSE_EQUILIBRIUM_LIMIT, MassMatrix};
pub use tangent::{
    Along, Balance, Motion, Projection, ROUNDING_MARGIN, StageTangent, moves_beyond_rounding,
    stage_tangent,
};
pub use timing::{Phase, PhaseTimes, timed};

use evaluate::Evaluator;

/// Errors of the equilibrium search and assembly.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssemblyError {
    /// A model element could not produce its terms.
    #[error(transparent)]
    Energy(#[from] EnergyError),
    /// Two element crates register the same kind, so a kind's name would not say which
    /// energy its instances get.
    #[error(transparent)]
    Registry(#[from] pendkit_energy::DuplicateKind),
    /// Newton's method did not converge.
    #[error(
        "equilibrium search did not converge after {iterations} iterations: residual force {residual:.3e} on '{coordinate}'"
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Largest residual force or torque (N or N m).
        residual: f64,
        /// The coordinate it acts on.
        coordinate: String,
    },
    /// Newton's method stopped making progress: over its last iterations neither the
    /// energy fell beyond its rounding nor the largest residual by half.
    #[error(
        "equilibrium search stalled: no progress in the last {window} of {iterations} iterations, residual force {residual:.3e} on '{coordinate}' (no minimum the search reaches from the start, or none double precision resolves)"
    )]
    Stalled {
        /// Iterations done.
        iterations: usize,
        /// Iterations without progress.
        window: usize,
        /// Largest residual force or torque (N or N m).
        residual: f64,
        /// The coordinate it acts on.
        coordinate: String,
    },
    /// The search ran away: the potential has no minimum near the start.
    #[error(
        "equilibrium search ran away: '{coordinate}' reached {value:.4e} (is the model supported, is the start position near the equilibrium?)"
    )]
    Runaway {
        /// The coordinate that ran away.
        coordinate: String,
        /// Its value (m or rad).
        value: f64,
    },
    /// The potential or its gradient is not finite at a point of the search.
    #[error("potential is not finite at iteration {iteration} (coordinates {coords:?})")]
    NotFinite {
        /// Iteration.
        iteration: usize,
        /// Coordinates there.
        coords: Vec<(String, f64)>,
    },
    /// A coordinate vector of the wrong length for the system it is used with.
    #[error("{function}: {argument} has {given} entries, the system has {expected} coordinates")]
    Length {
        /// The function called, e.g. `mass_matrix`.
        function: &'static str,
        /// The argument of the wrong length.
        argument: &'static str,
        /// The system's number of coordinates.
        expected: usize,
        /// The length given.
        given: usize,
    },
    /// The equilibrium's stiffness over the free coordinates is singular, so the
    /// equilibrium's motion with a parameter is not defined.
    #[error(
        "the equilibrium is neutral (its stiffness over the free coordinates is singular): it has no derivative with respect to a parameter"
    )]
    SingularEquilibrium,
    /// A [`Balance`] used with a model whose coordinates are not those it was built for.
    #[error("stage_tangent: the balance was built for a model with other coordinates")]
    ForeignBalance,
    /// An input with a NaN or infinite entry.
    #[error("{function}: {argument} entry {index} is not finite")]
    NotFiniteInput {
        /// The function called, e.g. `stage_tangent`.
        function: &'static str,
        /// The argument, e.g. `equilibrium`.
        argument: &'static str,
        /// The first entry that is not finite.
        index: usize,
    },
    /// A [`Projection`] used with another model, stage or equilibrium than its own.
    #[error("stage_tangent: the projection was built for another model, stage or equilibrium")]
    ForeignProjection,
    /// A [`Motion`] used with another [`Projection`] than the one it was computed for.
    #[error("Projection::add_motion: the motion was computed for another projection")]
    ForeignMotion,
    /// A [`Motion`] without the coefficients of a coordinate the equilibrium moves along.
    #[error(
        "Projection::add_motion: the equilibrium moves along '{coordinate}', which the motion \
         left out (Projection::motion_along)"
    )]
    MotionLeftOut {
        /// The coordinate's name.
        coordinate: String,
    },
    /// A float moves a body with mass or inertia (floats must be massless).
    #[error("float '{float}' moves body '{body}', which has mass: make it a variable")]
    MassiveFloat {
        /// Float name.
        float: String,
        /// Body name.
        body: String,
    },
}

/// A hand-built system's bad index is an energy error, as it was before the data model had
/// its own crate (callers match `AssemblyError::Energy(EnergyError::Index { .. })`).
impl From<pendkit_system::IndexError> for AssemblyError {
    fn from(e: pendkit_system::IndexError) -> Self {
        AssemblyError::Energy(e.into())
    }
}

/// Order of the coordinates in the master matrix: variables (x), then floats (q), then
/// parameters (s), each in definition order.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Global indices of the variables.
    pub variables: Vec<usize>,
    /// Global indices of the floats.
    pub floats: Vec<usize>,
    /// Global indices of the parameters.
    pub parameters: Vec<usize>,
    /// Master-matrix row of each global coordinate ([`Layout::NO_ROW`] for a float left
    /// out of the stage).
    pub position: Vec<usize>,
}

impl Layout {
    /// The layout of `system`'s coordinates.
    pub fn new(system: &System) -> Self {
        Layout::without(system, &[])
    }

    /// The layout of `system`'s coordinates less the floats `idle` (global indices), which
    /// get no row ([`Layout::NO_ROW`]).
    pub fn without(system: &System, idle: &[usize]) -> Self {
        let variables = system.coords_of(CoordKind::Variable);
        let floats: Vec<usize> = system
            .coords_of(CoordKind::Float)
            .into_iter()
            .filter(|g| !idle.contains(g))
            .collect();
        let parameters = system.coords_of(CoordKind::Parameter);
        let mut position = vec![Layout::NO_ROW; system.coords.len()];
        for (row, &g) in variables
            .iter()
            .chain(&floats)
            .chain(&parameters)
            .enumerate()
        {
            position[g] = row;
        }
        Layout {
            variables,
            floats,
            parameters,
            position,
        }
    }

    /// Number of variables, floats and parameters.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (
            self.variables.len(),
            self.floats.len(),
            self.parameters.len(),
        )
    }

    /// The row of a coordinate that has none (an idle float).
    pub const NO_ROW: usize = usize::MAX;

    /// Number of rows of the master matrix (variables, floats and parameters).
    pub fn len(&self) -> usize {
        self.variables.len() + self.floats.len() + self.parameters.len()
    }

    /// Whether the master matrix is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One term differentiated at the equilibrium.
#[derive(Clone, Debug)]
pub struct TermMatrices {
    /// Term name.
    pub label: String,
    /// Element kind.
    pub kind: &'static str,
    /// Damping tag.
    pub tag: String,
    /// Global coordinate indices of the local matrices.
    pub coords: Vec<usize>,
    /// Hessian with tensions on (row-major).
    pub on: Vec<f64>,
    /// Hessian with tensions off.
    pub off: OffHessian,
}

/// Everything later stages need from one stage: equilibrium, per-term stiffness and mass.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// Stage whose terms are included.
    pub stage: Stage,
    /// Coordinate order of the master matrices.
    pub layout: Layout,
    /// The equilibrium.
    pub equilibrium: Equilibrium,
    /// Per-term Hessians.
    pub terms: Vec<TermMatrices>,
    /// Mass matrix over the variables (kg, kg m, kg m^2).
    pub mass: MassMatrix,
}

/// A point on a body as the linearised geometry at equilibrium sees it: how far it moves
/// along a lab direction per unit of each unknown (variables, then floats) and of each
/// parameter ([`Assembled::point_weights`]). The same weights are the generalised force of a
/// unit force there.
#[derive(Clone, Debug, PartialEq)]
pub struct PointWeights {
    /// Per unit of each variable, then each float (m/m or m/rad).
    pub unknowns: DVector<f64>,
    /// Per unit of each parameter coordinate (the support's pose).
    pub parameters: DVector<f64>,
}

impl Assembled {
    /// How far `point` (m, body coordinates) on body `body` of `system` moves along
    /// `direction` (lab axes, normalised here) per unit of every unknown (variables, then
    /// floats) and every parameter coordinate: the linearised geometry at this equilibrium.
    /// `None` when a weight is not finite, the body index is out of range, or `system` has
    /// fewer coordinates than this assembly's (a different model).
    pub fn point_weights(
        &self,
        system: &System,
        body: usize,
        point: &Vector3<f64>,
        direction: &Vector3<f64>,
    ) -> Option<PointWeights> {
        let jac = system
            .bodies
            .get(body)?
            .frame
            .try_jacobian(&self.equilibrium.coords, point)
            .ok()?;
        let layout = &self.layout;
        let all = layout.variables.iter().chain(&layout.floats);
        if all
            .chain(&layout.parameters)
            .any(|&g| g >= jac.position.ncols())
        {
            return None;
        }
        let d = direction.normalize();
        let along = |ids: &mut dyn Iterator<Item = &usize>| {
            DVector::from_vec(ids.map(|&g| jac.position.column(g).dot(&d)).collect())
        };
        let weights = PointWeights {
            unknowns: along(&mut layout.variables.iter().chain(&layout.floats)),
            parameters: along(&mut layout.parameters.iter()),
        };
        let finite = weights
            .unknowns
            .iter()
            .chain(weights.parameters.iter())
            .all(|x| x.is_finite());
        finite.then_some(weights)
    }

    /// Scatters per-term local matrices, each chosen by `pick` (None = skip), into one
    /// master matrix in layout order.
    pub fn scatter(&self, pick: impl Fn(&TermMatrices) -> Option<&[f64]>) -> DMatrix<f64> {
        let n = self.layout.len();
        let mut p = DMatrix::zeros(n, n);
        for t in &self.terms {
            let Some(h) = pick(t) else { continue };
            let m = t.coords.len();
            for (a, &ga) in t.coords.iter().enumerate() {
                for (b, &gb) in t.coords.iter().enumerate() {
                    p[(self.layout.position[ga], self.layout.position[gb])] += h[a * m + b];
                }
            }
        }
        p
    }

    /// Master stiffness matrix with tensions on (N/m, N/rad, N m/rad), layout order.
    pub fn stiffness(&self) -> DMatrix<f64> {
        self.scatter(|t| Some(&t.on))
    }

    /// Split for dissipation dilution: the lossless part Σ(P_on − P_off) and, per damping
    /// tag, the part Σ P_off that the tag's complex multiplier scales.
    pub fn dilution_parts(&self) -> (DMatrix<f64>, BTreeMap<String, DMatrix<f64>>) {
        let mut lossless = self.scatter(|t| match t.off {
            OffHessian::Zero => Some(&t.on),
            _ => None,
        });
        let mut by_tag: BTreeMap<String, DMatrix<f64>> = BTreeMap::new();
        for tag in self.terms.iter().map(|t| &t.tag) {
            if by_tag.contains_key(tag) {
                continue;
            }
            let off = self.scatter(|t| match (&t.off, &t.tag == tag) {
                (OffHessian::Same, true) => Some(&t.on),
                (OffHessian::Matrix(m), true) => Some(m),
                _ => None,
            });
            by_tag.insert(tag.clone(), off);
        }
        // tension-dependent remainder of the replaced terms: P_on − P_off
        let on_replaced = self.scatter(|t| match t.off {
            OffHessian::Matrix(_) => Some(&t.on),
            _ => None,
        });
        let off_replaced = self.scatter(|t| match &t.off {
            OffHessian::Matrix(m) => Some(m),
            _ => None,
        });
        lossless += on_replaced - off_replaced;
        (lossless, by_tag)
    }
}

/// How to assemble: the equilibrium search's controls and the derivative path.
#[derive(Clone, Debug, Default)]
pub struct AssemblyOptions {
    /// Controls of the equilibrium search.
    pub equilibrium: EquilibriumOptions,
    /// Fast (default) or reference derivatives.
    pub derivatives: DerivativePath,
}

/// Terms of every registered kind whose stage in `system` passes `include`, built around `x`, with
/// bodies shared between kinds taken from `shared`.
fn kind_terms(
    system: &System,
    x: &[f64],
    shared: &SharedBodies,
    include: impl Fn(Stage) -> bool,
) -> Result<Vec<Term>, EnergyError> {
    let reference = Reference::new(system, x);
    let mut terms = Vec::new();
    // a model may move a kind to another stage or switch it off (System::element_stages)
    for kind in registry().iter().filter(|k| {
        system
            .element_stage(k.kind(), k.stage())
            .is_some_and(&include)
    }) {
        terms.extend(kind.terms_shared(&reference, shared)?);
    }
    Ok(terms)
}

/// How the terms built before the equilibrium sit in an evaluator: stage-0A kinds first,
/// then the user's pre-equilibrium terms, then any plug-in terms built around the start.
#[derive(Clone, Copy, Debug)]
struct Before {
    /// Number of stage-0A kind terms.
    kinds_0a: usize,
    /// ... plus pre-equilibrium user terms.
    core: usize,
}

/// An evaluator with the terms built before the equilibrium: the stage-0A kinds (around
/// the start; they do not depend on it), the user's pre-equilibrium terms and, when `early`,
/// the plug-in terms built around the start (all stages, as the source does).
fn terms_before(
    system: &System,
    path: DerivativePath,
    early: bool,
) -> Result<(Evaluator<'_>, Before), AssemblyError> {
    system.check_indices()?;
    // every instance fits its kind's schema before any term is built
    pendkit_energy::check_plugin_elements(system)?;
    let start = system.start();
    let shared = SharedBodies::new();
    let mut evaluator = Evaluator::new(system, path);
    evaluator.extend(kind_terms(system, &start, &shared, |s| s == Stage::S0A)?);
    let kinds_0a = evaluator.terms().len();
    evaluator.extend(extra_terms(system, ExtraPhase::BeforeEquilibrium, None)?);
    let core = evaluator.terms().len();
    if early {
        evaluator.extend(kind_terms(system, &start, &shared, |s| s != Stage::S0A)?);
    }
    Ok((evaluator, Before { kinds_0a, core }))
}

/// Newton over the terms minimised for the equilibrium; the evaluator is left holding its
/// last evaluation, at the equilibrium.
fn equilibrium_search<'s>(
    system: &'s System,
    options: &AssemblyOptions,
) -> Result<(Evaluator<'s>, Before, Equilibrium), AssemblyError> {
    let early = system.early_wire_terms != EarlyWireTerms::No;
    let (mut evaluator, before) = terms_before(system, options.derivatives, early)?;
    let equilibrium = equilibrium::newton(
        &mut evaluator,
        system,
        &system.start(),
        &options.equilibrium,
    )?;
    Ok((evaluator, before, equilibrium))
}

/// Finds the equilibrium of `system`. Plug-in terms that join early are built around the
/// start position (their auto clamp angles and tensions), as in the source (§9.2.6): the
/// start is meant to be the drawing's nominal geometry, which is where clamps are aligned.
pub fn solve_equilibrium(
    system: &System,
    options: &EquilibriumOptions,
) -> Result<Equilibrium, AssemblyError> {
    let options = AssemblyOptions {
        equilibrium: options.clone(),
        ..AssemblyOptions::default()
    };
    Ok(equilibrium_search(system, &options)?.2)
}

/// Finds the equilibrium and differentiates every term of `stage` there.
pub fn assemble(
    system: &System,
    stage: Stage,
    options: &EquilibriumOptions,
) -> Result<Assembled, AssemblyError> {
    let options = AssemblyOptions {
        equilibrium: options.clone(),
        ..AssemblyOptions::default()
    };
    assemble_with(system, stage, &options, None)
}

/// [`assemble`] with a choice of derivative path, recording the time of each phase
/// (`terms`: building them, `equilibrium`: Newton, `hessian:<kind>`, `mass`) into `times`
/// when given. The terms Newton minimised and its last evaluation at the equilibrium are
/// reused.
pub fn assemble_with(
    system: &System,
    stage: Stage,
    options: &AssemblyOptions,
    mut times: Option<&mut PhaseTimes>,
) -> Result<Assembled, AssemblyError> {
    pendkit_energy::check_registrations()?;
    let early = system.early_wire_terms != EarlyWireTerms::No;
    let (mut evaluator, before) = timed(&mut times, "terms", 1, || {
        terms_before(system, options.derivatives, early)
    })?;
    let equilibrium = timed(&mut times, "equilibrium", 1, || {
        equilibrium::newton(
            &mut evaluator,
            system,
            &system.start(),
            &options.equilibrium,
        )
    })?;
    // plug-in terms that joined the equilibrium only are not part of the matrices
    if system.early_wire_terms != EarlyWireTerms::Yes {
        evaluator.truncate(before.core);
    }
    finish(system, stage, evaluator, before, equilibrium, times)
}

/// Differentiates every term of `stage` at a known equilibrium (reused across stages).
pub fn assemble_at(
    system: &System,
    stage: Stage,
    equilibrium: Equilibrium,
) -> Result<Assembled, AssemblyError> {
    assemble_at_with(system, stage, equilibrium, DerivativePath::Fast)
}

/// [`assemble_at`] with a choice of derivative path.
pub fn assemble_at_with(
    system: &System,
    stage: Stage,
    equilibrium: Equilibrium,
    path: DerivativePath,
) -> Result<Assembled, AssemblyError> {
    check_length(
        system,
        "assemble_at",
        "equilibrium.coords",
        &equilibrium.coords,
    )?;
    let early = system.early_wire_terms == EarlyWireTerms::Yes;
    let (evaluator, before) = terms_before(system, path, early)?;
    finish(system, stage, evaluator, before, equilibrium, None)
}

/// Adds the terms built at the equilibrium to `evaluator` (which holds the stage-0A and
/// pre-equilibrium terms, then any plug-in terms kept from the start), differentiates
/// whatever is not known there yet and collects the matrices in the order: stage-0A kinds,
/// plug-ins, user terms before and after the equilibrium, constraints.
fn finish(
    system: &System,
    stage: Stage,
    mut evaluator: Evaluator,
    before: Before,
    equilibrium: Equilibrium,
    mut times: Option<&mut PhaseTimes>,
) -> Result<Assembled, AssemblyError> {
    let x = &equilibrium.coords;
    let Before { kinds_0a, core } = before;
    let kept_plugins = evaluator.terms().len() - core;
    let new_plugins = timed(
        &mut times,
        "terms",
        0,
        || -> Result<usize, AssemblyError> {
            let shared = SharedBodies::new();
            let plugins = if system.early_wire_terms == EarlyWireTerms::Yes {
                Vec::new()
            } else {
                kind_terms(system, x, &shared, |s| s != Stage::S0A && s <= stage)?
            };
            let count = plugins.len();
            evaluator.extend(plugins);
            evaluator.extend(extra_terms(system, ExtraPhase::AfterEquilibrium, Some(x))?);
            evaluator.extend(constraint_terms(system, x)?);
            Ok(count)
        },
    )?;
    evaluator.timing = times.is_some();
    evaluator.evaluate(x, true);
    if let Some(t) = times.as_deref_mut() {
        for (phase, time, calls) in evaluator.take_times() {
            t.add(&phase, time, calls);
        }
    }
    // output order: 0A kinds, plug-ins (kept or new), pre-equilibrium, the rest
    let total = evaluator.terms().len();
    let plugin_range = if kept_plugins > 0 {
        core..core + kept_plugins
    } else {
        core + kept_plugins..core + kept_plugins + new_plugins
    };
    let order: Vec<usize> = (0..kinds_0a)
        .chain(plugin_range.clone())
        .chain(kinds_0a..core)
        .chain((core..total).filter(|t| !plugin_range.contains(t)))
        .collect();
    let matrices: Vec<TermMatrices> = order
        .into_iter()
        .map(|t| {
            let (on, off) = evaluator.take_hessians(t);
            let term = &evaluator.terms()[t];
            TermMatrices {
                label: term.label.clone(),
                kind: term.kind,
                tag: term.tag.clone(),
                coords: term.coords.clone(),
                on,
                off,
            }
        })
        .collect();
    let mut idle = idle_floats(system, &matrices);
    // pinned floats the stage holds about some axes only (a clamped bead joint on a slanted
    // fibre before bending turns about the fibre only): the rest is held at zero
    // (redundant.rs)
    let held: Vec<usize> = system
        .coords_of(CoordKind::Float)
        .into_iter()
        .filter(|g| system.coords[*g].pinned && !idle.contains(g))
        .collect();
    idle.extend(redundant::redundant_floats(&matrices, &held));
    idle.sort_unstable();
    let matrices = if idle.is_empty() {
        matrices
    } else {
        matrices.into_iter().map(|t| t.without(&idle)).collect()
    };
    let layout = Layout::without(system, &idle);
    let mass = timed(&mut times, "mass", 1, || {
        mass_at(system, &layout, &mut evaluator, x)
    })?;
    Ok(Assembled {
        stage,
        layout,
        equilibrium,
        terms: matrices,
        mass,
    })
}

/// The pinned floats (held at their start in the equilibrium) that no term of this stage
/// holds or couples: every Hessian entry on their rows, tension on and off, is exactly
/// zero (a violin bead's joint rotations before the stage that adds bending: only the
/// bending term turns them). Such a float carries no energy in the stage and moves
/// nothing, so leaving it out is the exact elimination; keeping it would make the float
/// block singular. A free float that nothing holds (a mistake in a model, e.g. the toy's
/// junction between two springs of zero stiffness) is still reported by the elimination.
fn idle_floats(system: &System, terms: &[TermMatrices]) -> Vec<usize> {
    let mut touched = vec![false; system.coords.len()];
    for t in terms {
        let m = t.coords.len();
        let off = match &t.off {
            OffHessian::Matrix(off) => Some(off.as_slice()),
            _ => None,
        };
        for (a, &g) in t.coords.iter().enumerate() {
            let row = a * m..(a + 1) * m;
            let nonzero = |h: &[f64]| h[row.clone()].iter().any(|&v| v != 0.0);
            if nonzero(&t.on) || off.is_some_and(nonzero) {
                touched[g] = true;
            }
        }
    }
    system
        .coords_of(CoordKind::Float)
        .into_iter()
        .filter(|&g| !touched[g] && system.coords[g].pinned)
        .collect()
}

impl TermMatrices {
    /// The term without the coordinates `idle` (whose rows and columns are zero).
    fn without(self, idle: &[usize]) -> TermMatrices {
        let keep: Vec<usize> = (0..self.coords.len())
            .filter(|&a| !idle.contains(&self.coords[a]))
            .collect();
        if keep.len() == self.coords.len() {
            return self;
        }
        let m = self.coords.len();
        let pick = |h: &[f64]| -> Vec<f64> {
            keep.iter()
                .flat_map(|&a| keep.iter().map(move |&b| h[a * m + b]))
                .collect()
        };
        TermMatrices {
            coords: keep.iter().map(|&a| self.coords[a]).collect(),
            on: pick(&self.on),
            off: match &self.off {
                OffHessian::Matrix(off) => OffHessian::Matrix(pick(off)),
                other => other.clone(),
            },
            label: self.label,
            kind: self.kind,
            tag: self.tag,
        }
    }
}

/// M = Σ_b J_bᵀ diag(m, m, m, I_b) J_b over the variables, with J_b the Jacobian of the
/// body's centre-of-mass velocity and body-axis angular velocity (docs/physics.md §2).
pub fn mass_matrix(
    system: &System,
    layout: &Layout,
    x: &[f64],
) -> Result<MassMatrix, AssemblyError> {
    check_length(system, "mass_matrix", "x", x)?;
    system.check_indices()?;
    check_layout("mass_matrix", system, layout)?;
    let mut jet = FrameJet::new();
    mass_from(system, layout, |b, columns| {
        // cannot fail: every frame reads coordinates of `x` (checked above)
        match system.bodies[b]
            .frame
            .jet(x, pendkit_geometry::JetOrder::First, &mut jet)
        {
            Ok(()) => jet_columns(&jet, &system.bodies[b].centre_of_mass, columns),
            Err(_) => columns.clear(),
        }
    })
}

/// `x`, argument `argument` of `function`, has one entry per coordinate of `system`.
fn check_length(
    system: &System,
    function: &'static str,
    argument: &'static str,
    x: &[f64],
) -> Result<(), AssemblyError> {
    if x.len() != system.coords.len() {
        return Err(AssemblyError::Length {
            function,
            argument,
            expected: system.coords.len(),
            given: x.len(),
        });
    }
    Ok(())
}

/// `layout` is one of `system`: a row for every coordinate, and variables of the system.
pub(crate) fn check_layout<S: pendkit_rotations::Real>(
    function: &'static str,
    system: &System<S>,
    layout: &Layout,
) -> Result<(), AssemblyError> {
    let n = system.coords.len();
    if layout.position.len() != n {
        return Err(AssemblyError::Length {
            function,
            argument: "layout.position",
            expected: n,
            given: layout.position.len(),
        });
    }
    if let Some(&bad) = layout
        .variables
        .iter()
        .chain(&layout.floats)
        .chain(&layout.parameters)
        .find(|&&g| g >= n)
    {
        return Err(AssemblyError::Energy(EnergyError::Index {
            item: "layout".into(),
            what: "coordinate",
            index: bad,
            len: n,
        }));
    }
    // every variable of the system has a row of the mass matrix
    let nx = layout.variables.len();
    if let Some(g) =
        (0..n).find(|&g| system.coords[g].kind == CoordKind::Variable && layout.position[g] >= nx)
    {
        return Err(AssemblyError::Energy(EnergyError::Index {
            item: format!("layout: variable '{}'", system.coords[g].name),
            what: "row of the mass matrix",
            index: layout.position[g],
            len: nx,
        }));
    }
    Ok(())
}

/// The velocity columns (∂p_com/∂q_i, ω_B per unit rate) of a body from its jet, in the
/// order of its frame's coordinates.
fn jet_columns(jet: &FrameJet, com: &Vector3<f64>, columns: &mut Vec<[Vector3<f64>; 2]>) {
    columns.clear();
    columns.extend(jet.velocities(com).map(|[p, w, _]| [p, w]));
}

/// The mass matrix at the evaluator's equilibrium: from the shared jets on the fast path,
/// from forward-mode dual numbers on the reference path (an independent route).
fn mass_at(
    system: &System,
    layout: &Layout,
    evaluator: &mut Evaluator,
    x: &[f64],
) -> Result<MassMatrix, AssemblyError> {
    let reference = evaluator.path() == DerivativePath::Reference;
    mass_from(system, layout, |b, columns| {
        let body = &system.bodies[b];
        if reference {
            columns.clear();
            // cannot fail: the equilibrium has one entry per coordinate of the checked system
            let Ok(jac) = body.frame.reference_jacobian(x, &body.centre_of_mass) else {
                return;
            };
            columns.extend(body.frame.var_list().iter().map(|&g| {
                [
                    jac.position.column(g).into_owned(),
                    jac.omega_body.column(g).into_owned(),
                ]
            }));
        } else {
            jet_columns(evaluator.jet(b), &body.centre_of_mass, columns);
        }
    })
}

/// M from each massive body's velocity columns, given by `columns(body, out)` in the
/// order of the body's frame coordinates.
fn mass_from(
    system: &System,
    layout: &Layout,
    mut columns: impl FnMut(usize, &mut Vec<[Vector3<f64>; 2]>),
) -> Result<MassMatrix, AssemblyError> {
    let nx = layout.variables.len();
    // entries in the order a dense scatter adds them (bodies in order): the same sums
    let mut entries = Vec::new();
    let mut cols = Vec::new();
    for (b, body) in system.bodies.iter().enumerate() {
        if body.mass == 0.0 && body.inertia.iter().all(|&v| v == 0.0) {
            continue;
        }
        columns(b, &mut cols);
        let vars = body.frame.var_list();
        for (&g, [p, w]) in vars.iter().zip(&cols) {
            if system.coords[g].kind == CoordKind::Float && (p.norm() > 0.0 || w.norm() > 0.0) {
                return Err(AssemblyError::MassiveFloat {
                    float: system.coords[g].name.clone(),
                    body: body.name.clone(),
                });
            }
        }
        for (&gi, [pi, wi]) in vars.iter().zip(&cols) {
            if system.coords[gi].kind != CoordKind::Variable {
                continue;
            }
            for (&gj, [pj, wj]) in vars.iter().zip(&cols) {
                if system.coords[gj].kind != CoordKind::Variable {
                    continue;
                }
                let value = body.mass * pi.dot(pj) + wi.dot(&(body.inertia * wj));
                entries.push((layout.position[gi], layout.position[gj], value));
            }
        }
    }
    Ok(MassMatrix::from_entries(nx, &entries))
}
