//! Sensitivities: the derivatives of a stage's mode frequencies, and of |transfer function|
//! and thermal-noise ASD at given frequencies, with respect to the model's parameters
//! (`pendkit sensitivity`).
//!
//! # Method, and what is exact
//!
//! **The exact route** (mode sensitivities; [`Sensitivities::exact`] says which parameters
//! took it). The build runs with the parameter a dual number, so every mass, inertia,
//! point, section constant, stiffness and unstretched length carries its exact derivative:
//! one build for each chunk of [`pendkit_params::TANGENT_CHUNK`] parameters, a vector dual
//! number with one direction per parameter ([`pendkit_model::build_tangent_chunk`], about
//! the cost of two `f64` builds), split into one model per parameter; the element terms are
//! built from that model with `Dual64` constants ([`pendkit_energy::TangentTerm`]); the
//! equilibrium's motion is δq = dq*/dp = −K⁻¹ ∂g/∂p by the implicit function theorem (∂g/∂p
//! the dual part of the balanced terms' gradient at the fixed equilibrium, K factorised
//! once per request); dK/dp is the total derivative along the moving equilibrium (third
//! derivatives of the energies along δq included), and likewise dM/dp
//! ([`pendkit_assembly::stage_tangent`]). Only what the modes need is differentiated: the
//! second derivatives along w = (v, −Q⁻¹C_QX v), the mode v lifted to the floats (then
//! wᵀ dK w = vᵀ dK_eff v), for each mode and each pair within a cluster, split by the chain
//! rule into the terms whose constants move with p at the fixed equilibrium and the
//! equilibrium's motion through coefficients computed once per request
//! ([`pendkit_assembly::Projection`]; the nominal stage is computed beside the parameters'
//! dual builds, [`pendkit_assembly::side_by_side`]). The coefficients are computed after the
//! columns, only along the coordinates some column's dq*/dp moves beyond its rounding
//! bound ([`pendkit_assembly::Projection::motion_along`]): a symmetric suspension's lateral
//! coordinates, which no parameter moves, cost nothing. No step, no difference. A parameter nothing reads,
//! or only the damping's loss angles and the temperature read (no real multiplier, no
//! switch), moves no mode: its derivatives are exactly 0, computed from nothing, and
//! called exact. The route is closed (and the parameter goes the difference route below) for
//! a parameter the dual build cannot follow (written into a pose's text, a count, a
//! switch), one read only by what the build adds (the damping, the temperature, the
//! "wire terms early" switch), a model with user-written terms or a kind
//! without tangent terms, plug-in terms that join the equilibrium (built around the start
//! position, whose derivative the model does not carry), a damping tag whose real
//! multiplier at DC is not 1, and for transfer-function and noise sensitivities, which
//! need the tension-off Hessians too (asked for with the modes, they are differenced
//! while the modes still take the exact route).
//!
//! **The difference route** (and what it shares with the exact one):
//!
//! 0. **The model's numbers, exactly where the build allows.** The build runs with the
//!    parameter a dual number (the chunk build above): the tangent of every
//!    mass, inertia, point, section constant, stiffness and unstretched length. The model
//!    at each step below is the nominal one moved along that tangent
//!    ([`pendkit_model::build_stepped`]), which has the same derivative at p₀ as the
//!    rebuilt one. A
//!    parameter the dual build cannot follow (written into a pose's text, a count, a
//!    switch) rebuilds the model at each step ([`Sensitivities::exact_build`]).
//! 1. **The stage's matrices, by a difference.** For each parameter p (value p₀, step h),
//!    the stage is built and re-solved at p₀ ± h and p₀ ± 2h: parameters,
//!    equilibrium (so the equilibrium's motion dq*/dp is included), Hessians of the stage,
//!    float elimination (K_eff = K_aa − K_af K_ff⁻¹ K_fa), mass matrix, damping. The
//!    derivatives dK_eff/dp, dM/dp and dP(f)/dp (the complex master matrix with damping)
//!    are the fourth-order central difference ([`pendkit_dynamics::difference`])
//!    (−X(p₀+2h) + 8X(p₀+h) − 8X(p₀−h) + X(p₀−2h)) / 12h, whose truncation error is
//!    h⁴ X⁽⁵⁾/30: with h = 10⁻³|p₀| ([`RELATIVE_STEP`]) that is ~10⁻¹³ of X for a smooth
//!    dependence on the scale of p₀, below the rounding of the matrices' entries
//!    (~10⁻¹⁶ |X| / h ≈ 10⁻¹³ relative). A parameter whose value is 0 is stepped by
//!    [`ZERO_STEP`] (in its own unit). dP(f)/dp is put together per frequency from the
//!    differences of P's frequency-independent parts, P(f) = L + Σ_tag ε_tag(f) P_tag (L
//!    the lossless part): ε dP_tag where a tag's multiplier does not move with p, the
//!    difference of ε P_tag point by point where it does (a loss angle); so one parameter's
//!    matrices are differenced once, not at every frequency, and a loss angle's derivative
//!    does not carry the rounding of the other tags' imaginary parts
//!    ([`pendkit_dynamics::difference::StageDerivative`], on the pattern that holds every
//!    point's, [`pendkit_dynamics::CommonPattern`]).
//! 2. **Everything after the matrices, exactly** (both routes). Mode frequencies: dω²/dp =
//!    vᵀ(dK_eff/dp − ω² dM/dp)v with the mass-normalised mode v (Hellmann–Feynman); for a
//!    cluster of (nearly) equal ω² the derivatives are the eigenvalues of that projected
//!    matrix over the cluster, so degenerate modes get the right derivatives. Transfer
//!    functions: dH = −cᵀA⁻¹(dA)A⁻¹b + (dc)ᵀA⁻¹b + cᵀA⁻¹(db), A = P(f) − ω²M over the
//!    unknowns, with the input's and output's vectors (which follow the equilibrium's
//!    geometry) differenced like the matrices. Thermal noise: PSD = 4k_BT/ω |Im R| with
//!    R = oᵀA⁻¹o, dR = 2(do)ᵀz − zᵀ(dA)z, z = A⁻¹o; where damping tags have their own
//!    temperatures, PSD = 4k_B/ω Σ_tag T_tag ε''_tag z̄ᵀP_tag z (the fluctuation–dissipation
//!    theorem per tag, as the noise is computed), differentiated term by term with
//!    dz = A⁻¹(do − dA z) and each tag's T_tag ε''_tag and P_tag differenced like the
//!    matrices.
//!
//!    The algebra is the engine's: the nominal responses are solved by
//!    [`pendkit_dynamics::Sweep`] over every unknown, and since A is complex symmetric
//!    every cᵀA⁻¹(·) is an adjoint response y = A⁻¹c solved once per frequency with the
//!    same factorisation ([`pendkit_dynamics::Sweep::solve_again`]), so a parameter costs
//!    no solve, only products dA w on the stage's pattern
//!    ([`pendkit_dynamics::StageModel::multiply`]); the float map of the exact route is
//!    [`pendkit_dynamics::FloatMap`], and the per-tag sum is the noise crate's
//!    ([`pendkit_noise::TagSum`]).
//!
//! Differencing the matrices, not the answers, keeps the results smooth where the answers
//! are not: a |TF| near a high-Q resonance moves by many line widths when p moves by
//! 10⁻³ p₀, but the matrices move by 10⁻³ of themselves. No mode has to be matched between
//! the rebuilt models either.
//!
//! Work skipped exactly: a parameter the model's build does not read (directly or through
//! the definitions of parameters it reads) changes nothing but the damping, so its stage
//! matrices are the nominal ones with its damping; if moreover no real multiplier ε' and
//! no switch reads it (a loss angle, the temperature), the modes' stiffness (the
//! tension-on Hessian with each tag's ε'(0)) and mass do not move with it, so its mode
//! sensitivities are exactly 0 and count as exact; a parameter read by nothing at all has
//! zero sensitivities and costs nothing.

use std::collections::BTreeSet;

use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;
use pendkit_assembly::{
    Along, AssemblyOptions, Balance, Projection, assemble_with, in_parallel, in_parallel_with,
    side_by_side,
};
use pendkit_dynamics::difference::{STENCIL, StageDerivative, difference, difference_of};
use pendkit_dynamics::{
    FloatMap, Input, Modes, Output, Solver, Stability, StageModel, StageRun, Sweep,
    eliminate_floats, validate::check_frequencies,
};
use pendkit_model::Defaults;
use pendkit_system::{Stage, System};

use crate::{Case, Error, StageResult, run_stage};

/// Step of a parameter for the difference of the stage's matrices, relative to its value.
pub const RELATIVE_STEP: f64 = 1e-3;

/// Step of a parameter whose value is exactly 0, in the parameter's own unit.
pub const ZERO_STEP: f64 = 1e-6;

/// Largest imbalance of the moved equilibrium per relative change of the parameter, as a
/// fraction of the forces, that the exact route accepts
/// ([`pendkit_assembly::StageTangent::residual`]).
const EXACT_RESIDUAL: f64 = 1e-6;

/// Relative gap of ω² below which modes are one cluster for their derivatives.
const CLUSTER_GAP: f64 = 1e-8;

/// What to differentiate, at which stage.
#[derive(Clone, Debug)]
pub struct SensitivityRequest {
    /// The stage whose modes and responses are differentiated.
    pub stage: Stage,
    /// Whether to compute the mode frequencies' sensitivities.
    pub modes: bool,
    /// A transfer function (input, output; names as [`StageResult::transfer`] takes them)
    /// whose |H| to differentiate at `freqs`.
    pub tf: Option<(String, String)>,
    /// A displacement output whose thermal-noise ASD to differentiate at `freqs`.
    pub noise: Option<String>,
    /// Frequencies (Hz) for `tf` and `noise`.
    pub freqs: Vec<f64>,
    /// The parameters to differentiate with respect to (`None`: every numeric parameter
    /// of the case, in definition order).
    pub parameters: Option<Vec<String>>,
    /// Go on when the equilibrium is unstable (the warning is in
    /// [`Sensitivities::warning`]); otherwise an unstable equilibrium is an error.
    pub allow_unstable: bool,
    /// Threads that compute the parameters' columns (0: as many as the machine has). The
    /// results do not depend on it.
    pub threads: usize,
    /// Difference the stage's matrices for every parameter, even where the exact route is
    /// open (to check one against the other, or to time them).
    pub differences: bool,
}

impl SensitivityRequest {
    /// Mode sensitivities at `stage` to every parameter, nothing else.
    pub fn modes(stage: Stage) -> SensitivityRequest {
        SensitivityRequest {
            stage,
            modes: true,
            tf: None,
            noise: None,
            freqs: Vec::new(),
            parameters: None,
            allow_unstable: false,
            threads: 0,
            differences: false,
        }
    }
}

/// Derivatives of a stage's answers with respect to the parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivities {
    /// Parameter names (the columns).
    pub parameters: Vec<String>,
    /// Their values, in their units.
    pub values: Vec<f64>,
    /// Their units (empty when the model declares none).
    pub units: Vec<String>,
    /// The steps used for the differences of the stage's matrices, in the parameters'
    /// units (0 for a parameter nothing reads).
    pub steps: Vec<f64>,
    /// Per parameter, whether the model's numbers were moved along their exact tangent (a
    /// dual-number build, [`pendkit_model::build_tangent_chunk`]) rather than rebuilt at each
    /// step (a parameter that reaches the model through a pose's text, a count or a
    /// switch, or one only the damping reads).
    pub exact_build: Vec<bool>,
    /// Per parameter, whether its mode sensitivities are exact, with no difference anywhere
    /// (`steps` then says what a difference would use): the stage's matrices
    /// differentiated by dual numbers through the build, the terms and the equilibrium
    /// (the implicit function theorem), or, for a parameter nothing reads or only the
    /// damping's loss angles and the temperature read, exactly 0 (see the module's
    /// documentation). Otherwise the
    /// matrices are differenced. The |H| and noise sensitivities are always differenced
    /// (this is false for every parameter of a request without the modes).
    pub exact: Vec<bool>,
    /// Mode frequencies (Hz), ascending in ω² (the rows of `dfdp`).
    pub modes_hz: Vec<f64>,
    /// Mode labels (dominant coordinate).
    pub mode_labels: Vec<String>,
    /// d(mode frequency)/d(parameter), `[mode][parameter]`, Hz per unit of the parameter
    /// (empty when the modes were not asked for).
    pub dfdp: Vec<Vec<f64>>,
    /// |H| at the requested frequencies and d|H|/dp `[freq][parameter]` (|H|'s unit per
    /// unit of the parameter).
    pub tf_abs: Option<(Vec<f64>, Vec<Vec<f64>>)>,
    /// Thermal-noise ASD (m/√Hz or rad/√Hz) at the requested frequencies and d(ASD)/dp
    /// `[freq][parameter]`.
    pub noise_asd: Option<(Vec<f64>, Vec<Vec<f64>>)>,
    /// Parameters left out of the columns, with why: switches and counts the model
    /// refuses to set to a value near theirs (only when every parameter was asked for; a
    /// parameter named in the request is an error instead).
    pub not_differentiable: Vec<(String, String)>,
    /// The stability warning when the equilibrium is unstable and the request allowed it.
    pub warning: Option<String>,
}

fn bad(message: impl Into<String>) -> Error {
    Error::Sensitivity(message.into())
}

/// One rebuilt stage: its matrices and what the input and output vectors need.
struct Point {
    result: StageResult,
    k_eff: DMatrix<f64>,
}

/// The stage's matrices for `system`: assembly, stage model and float elimination, without
/// the modes (the returned result has none).
fn stage_point(system: System, stage: Stage) -> Result<Point, Error> {
    let assembled = assemble_with(&system, stage, &AssemblyOptions::default(), None)?;
    let model = StageModel::new(&system, &assembled);
    matrices_point(system, assembled, model)
}

fn matrices_point(
    system: System,
    assembled: pendkit_assembly::Assembled,
    model: StageModel,
) -> Result<Point, Error> {
    model.check_damping_at_dc(&system.damping)?;
    let k_eff = eliminate_floats(
        &model.real_stiffness(&system.damping),
        &assembled.layout,
        &system,
    )?
    .k_eff;
    let modes = Modes {
        coordinates: model.variables.clone(),
        modes: Vec::new(),
    };
    let stability = Stability::assess(&modes, Default::default(), model.sizes.1, Vec::new());
    Ok(Point {
        result: StageRun {
            system,
            assembled,
            model,
            modes,
            stability,
        }
        .into(),
        k_eff,
    })
}

/// How each parameter enters the model.
#[derive(Clone, Copy, PartialEq)]
enum Reach {
    /// Read by the build of the mechanical model (and perhaps the damping).
    Mechanics,
    /// Read only by the damping (and temperature).
    DampingOnly,
    /// Read by nothing: every sensitivity is exactly zero.
    Nothing,
}

/// The input (none for noise) and output of one point, as the stage result parses them.
struct Ports {
    input: Option<Input>,
    output: Output,
}

fn ports(point: &Point, tf: &(String, String)) -> Result<Ports, Error> {
    Ok(Ports {
        input: Some(point.result.input(&tf.0)?),
        output: point.result.output(&tf.1)?,
    })
}

fn noise_port(point: &Point, name: &str) -> Result<Ports, Error> {
    match point.result.output(name)? {
        Output::Displacement(v) => Ok(Ports {
            input: None,
            output: Output::Displacement(v),
        }),
        Output::SupportForce(_) => Err(Error::Name {
            name: name.to_string(),
            message: "thermal noise needs a displacement output".into(),
        }),
    }
}

type C = faer::c64;

/// A vector padded with zeros to `n` entries.
fn padded(v: &DVector<f64>, n: usize) -> DVector<f64> {
    DVector::from_fn(n, |i, _| v.get(i).copied().unwrap_or(0.0))
}

/// The port vectors of one point as fixed-length real vectors (b, c): b over the unknowns
/// (a force input) or the parameters (a displacement input; empty without an input), c
/// over all master rows (a displacement output) or the parameters (a support force).
fn port_vectors(ports: &Ports, sizes: (usize, usize, usize)) -> (DVector<f64>, DVector<f64>) {
    let (nx, nq, ns) = sizes;
    let b = match &ports.input {
        Some(Input::Force(f)) => padded(f, nx + nq),
        Some(Input::Displacement(s)) => padded(s, ns),
        None => DVector::zeros(0),
    };
    let c = match &ports.output {
        Output::Displacement(o) => padded(o, nx + nq + ns),
        Output::SupportForce(o) => padded(o, ns),
    };
    (b, c)
}

fn same_kinds(a: &Ports, b: &Ports) -> bool {
    let input = matches!(
        (&a.input, &b.input),
        (Some(Input::Force(_)), Some(Input::Force(_)))
            | (Some(Input::Displacement(_)), Some(Input::Displacement(_)))
            | (None, None)
    );
    let output = matches!(
        (&a.output, &b.output),
        (Output::Displacement(_), Output::Displacement(_))
            | (Output::SupportForce(_), Output::SupportForce(_))
    );
    input && output
}

/// What every parameter's column reads: the request, the nominal stage and its modes, the
/// nominal responses' factorisations.
struct Shared<'a> {
    case: &'a Case,
    defaults: &'a Defaults,
    request: &'a SensitivityRequest,
    names: &'a [String],
    values: &'a [f64],
    reach: &'a [Reach],
    /// Whether the damping's real multipliers ε'(f) depend on each parameter.
    real_multiplier_reads: &'a [bool],
    /// Whether each parameter is read only by what moves no mode (the damping's loss
    /// angles, the temperature): its mode sensitivities are exactly 0.
    modes_blind: &'a [bool],
    base_point: &'a Point,
    base_ports: Option<&'a Ports>,
    nominal: &'a [Nominal<'a>],
    /// The nominal modes' vectors, one column per mode.
    vectors: &'a DMatrix<f64>,
    clusters: &'a [Vec<usize>],
    sizes: (usize, usize, usize),
    responses: bool,
    /// What the exact route shares between parameters; `None` when it is closed to all.
    exact: Option<ExactRoute>,
    /// Each parameter's model numbers along their exact tangent, where the build offers
    /// one (else each step of its difference rebuilds the model).
    tangents: &'a Tangents,
}

/// One parameter's derivatives (Hz, |H|'s unit, and the noise response per unit of the
/// parameter), or why the model refuses to move it.
struct Column {
    /// The step of the difference (the parameter's unit).
    step: f64,
    /// Whether the model's numbers moved along their exact tangent.
    exact_build: bool,
    /// Whether the stage's matrices were differentiated exactly (no difference at all).
    exact: bool,
    /// Why the model refuses values near the parameter's (a switch or a count).
    refused: Option<String>,
    /// d(mode frequency)/dp, one per mode (empty when the modes were not asked for).
    dfdp: Vec<f64>,
    /// The exact route's projections still without the equilibrium's motion, which
    /// [`finish_modes`] adds once the projection's coefficients are known (`dfdp` is then
    /// filled).
    pending: Option<Projections>,
    /// dH/dp, one per frequency.
    d_tf: Vec<C>,
    /// d(noise PSD)/dp, one per frequency.
    d_noise: Vec<f64>,
}

/// The dual builds of the parameters the mechanics read, where the model offers them: one
/// per chunk of [`pendkit_params::TANGENT_CHUNK`] parameters (about the cost of two `f64`
/// builds each), the chunks on `threads` threads; each parameter's model is taken from its
/// chunk by its own column ([`Tangents::of`]), on the column's thread.
struct Tangents {
    chunks: Vec<Option<pendkit_model::TangentChunk>>,
    /// Per parameter: its chunk and direction there.
    at: Vec<Option<(usize, usize)>>,
}

impl Tangents {
    fn build(
        case: &Case,
        names: &[String],
        reach: &[Reach],
        threads: usize,
    ) -> Result<Self, Error> {
        let mechanical: Vec<usize> = (0..names.len())
            .filter(|&j| reach[j] == Reach::Mechanics)
            .collect();
        let groups: Vec<&[usize]> = mechanical.chunks(pendkit_params::TANGENT_CHUNK).collect();
        // a model that offers no dual build leaves its parameters to rebuilds
        let chunks = in_parallel(groups.len(), threads, |c| {
            let chunk: Vec<&str> = groups[c].iter().map(|&j| names[j].as_str()).collect();
            Ok::<_, Error>(
                pendkit_model::build_tangent_chunk(&*case.model, &case.overrides, &chunk).ok(),
            )
        })?;
        let mut at = vec![None; names.len()];
        for (c, group) in groups.iter().enumerate() {
            for (k, &j) in group.iter().enumerate() {
                at[j] = Some((c, k));
            }
        }
        Ok(Tangents { chunks, at })
    }

    /// Parameter `j`'s model with the exact derivatives of its numbers, if it has them,
    /// written into `scratch` (a column's thread keeps one: the parameters of a chunk are
    /// its columns in order, so most models are rewritten in place rather than copied).
    fn of<'s>(
        &self,
        j: usize,
        scratch: &'s mut pendkit_model::DirectionScratch,
    ) -> Option<&'s System<Dual64>> {
        let (c, k) = self.at[j]?;
        self.chunks[c].as_ref()?.direction_in(k, scratch).ok()
    }
}

/// Parameter `j`'s column: the modes by the exact route where it is open, else (and for the
/// responses) the stage rebuilt at the stencil's points and differenced, then the exact
/// algebra of the module's documentation. `None` for a parameter nothing reads (every
/// derivative exactly 0, nothing computed: exact for the modes, as a loss angle's zero is,
/// where the exact route was asked for).
fn column(
    shared: &Shared,
    j: usize,
    scratch: &mut pendkit_model::DirectionScratch,
) -> Result<Option<Column>, Error> {
    if shared.reach[j] == Reach::Nothing {
        return Ok(None);
    }
    let h = step_of(shared.values[j]);
    // the model's numbers along their exact tangent, where the build offers one (else each
    // step rebuilds the model)
    let tangent = shared.tangents.of(j, scratch);
    let mut out = Column::new(shared, h, tangent.is_some());
    // the responses, if asked for, are differenced whatever the modes took
    if exact_modes(shared, j, tangent, &mut out)? && !shared.responses {
        return Ok(Some(out));
    }
    let points = match stencil_points(shared, j, h, tangent)? {
        Ok(points) => points,
        Err(why) => {
            out.refused = Some(why);
            return Ok(Some(out));
        }
    };
    if shared.request.modes && !out.exact {
        out.dfdp = differenced_modes(shared, &points, h)?;
    }
    if shared.responses {
        response_derivatives(shared, j, &points, h, &mut out)?;
    }
    Ok(Some(out))
}

/// The step of the difference for a parameter of value `p0` (its unit): [`RELATIVE_STEP`]
/// of it, or [`ZERO_STEP`] at 0.
fn step_of(p0: f64) -> f64 {
    if p0 == 0.0 {
        ZERO_STEP
    } else {
        RELATIVE_STEP * p0.abs()
    }
}

impl Column {
    /// A column of zeros with step `h`, nothing yet computed.
    fn new(shared: &Shared, h: f64, exact_build: bool) -> Column {
        let (request, nf) = (shared.request, shared.request.freqs.len());
        let modes = &shared.base_point.result.modes.modes;
        Column {
            step: h,
            exact_build,
            exact: false,
            refused: None,
            dfdp: vec![0.0; if request.modes { modes.len() } else { 0 }],
            pending: None,
            d_tf: vec![C::new(0.0, 0.0); nf],
            d_noise: vec![0.0; nf],
        }
    }
}

/// The modes of parameter `j` by the exact route, where the request asks for the modes, does
/// not ask for differences, and the route is open: exactly 0 for a parameter only what
/// moves no mode reads, else the projections of the stage's matrices differentiated by the
/// implicit function theorem (the equilibrium's motion added by [`finish_modes`]). Whether
/// they took it (`out.exact`).
fn exact_modes(
    shared: &Shared,
    j: usize,
    tangent: Option<&System<Dual64>>,
    out: &mut Column,
) -> Result<bool, Error> {
    if !shared.request.modes || shared.request.differences {
        return Ok(false);
    }
    if shared.modes_blind[j] {
        // a parameter only the damping's loss angles and the temperature read: the
        // modes' stiffness (the tension-on Hessian, each tag's times its ε'(0)) and the
        // mass do not move with it, so every mode's derivative is exactly 0, with
        // nothing computed
        out.exact = true;
    } else if let Some(dual) = tangent
        && let Some(projections) = exact_projections(shared, j, shared.values[j], out.step, dual)?
    {
        out.pending = Some(projections);
        out.exact = true;
    }
    Ok(out.exact)
}

/// The stage of parameter `j` at the stencil's points p₀ + k h, each model moved along the
/// exact tangent where there is one, else rebuilt; the inner error is why the model refuses
/// one of the values (a switch or a count), when every parameter was asked for (a parameter
/// named in the request is an error instead).
fn stencil_points(
    shared: &Shared,
    j: usize,
    h: f64,
    tangent: Option<&System<Dual64>>,
) -> Result<Result<[Point; 4], String>, Error> {
    let (case, request, name) = (shared.case, shared.request, &shared.names[j]);
    let p0 = shared.values[j];
    let mut points = Vec::with_capacity(STENCIL.len());
    for &(k, _) in &STENCIL {
        let value = p0 + k * h;
        let overrides = overridden(case, name, value);
        let built = match tangent {
            Some(dual) => pendkit_model::build_stepped(dual, k * h, shared.defaults, &overrides),
            None => pendkit_model::build_with(&*case.model, &overrides).map(|(system, _)| system),
        }
        .map_err(Error::from);
        let system = match built {
            Ok(system) => system,
            // a switch or a count: the model refuses any value near it
            Err(Error::Build(e)) => {
                let why = format!("the model refuses {name} = {value:e} ({e})");
                if request.parameters.is_some() {
                    return Err(bad(format!("'{name}' has no derivative: {why}")));
                }
                return Ok(Err(why));
            }
            Err(e) => return Err(e),
        };
        let base = &shared.base_point.result;
        points.push(match shared.reach[j] {
            Reach::Mechanics => stage_point(system, request.stage)?,
            _ => matrices_point(system, base.assembled.clone(), base.model.clone())?,
        });
    }
    if points.iter().any(|p| p.result.model.sizes != shared.sizes) {
        return Err(bad(format!(
            "changing '{name}' changes the model's coordinates: no derivative"
        )));
    }
    let points: [Point; 4] = points
        .try_into()
        .map_err(|_| bad("the stencil has four points"))?;
    Ok(Ok(points))
}

/// The modes' derivatives from the stage's matrices differenced over the stencil's points
/// (step `h`), projected on the nominal modes.
fn differenced_modes(shared: &Shared, points: &[Point; 4], h: f64) -> Result<Vec<f64>, Error> {
    let dk = difference(points, h, |p| p.k_eff.clone());
    let dm = difference(points, h, |p| p.result.assembled.mass.to_dense());
    let vectors = shared.vectors;
    let vk = vectors.transpose() * &dk * vectors;
    let vm = vectors.transpose() * &dm * vectors;
    mode_derivatives(shared, &vk, &vm)
}

/// The port vectors' derivatives over the stencil's points: the transfer function's input
/// (db) and output (dc) and the noise output's (do), each where asked for.
struct PortChanges {
    tf: Option<(DVector<f64>, DVector<f64>)>,
    noise: Option<DVector<f64>>,
}

impl PortChanges {
    /// The ports at each point, checked against the nominal's kinds, differenced (step `h`).
    fn new(shared: &Shared, name: &str, points: &[Point; 4], h: f64) -> Result<Self, Error> {
        let request = shared.request;
        let [p0, p1, p2, p3] = points;
        let at = |port: &dyn Fn(&Point) -> Result<Ports, Error>| -> Result<[Ports; 4], Error> {
            Ok([port(p0)?, port(p1)?, port(p2)?, port(p3)?])
        };
        let tf_ports = match &request.tf {
            Some(tf) => Some(at(&|p| ports(p, tf))?),
            None => None,
        };
        let noise_ports = match &request.noise {
            Some(output) => Some(at(&|p| noise_port(p, output))?),
            None => None,
        };
        if let (Some(b), Some(tf_ports)) = (shared.base_ports, &tf_ports)
            && tf_ports.iter().any(|p| !same_kinds(p, b))
        {
            return Err(bad(format!(
                "changing '{name}' changes the kind of the transfer function's input or output"
            )));
        }
        let sizes = shared.sizes;
        let tf = tf_ports.map(|ports| {
            let vectors = ports.each_ref().map(|p| port_vectors(p, sizes));
            (
                difference_of(vectors.each_ref().map(|v| &v.0), h),
                difference_of(vectors.each_ref().map(|v| &v.1), h),
            )
        });
        let noise = noise_ports.map(|ports| {
            let vectors = ports.each_ref().map(|p| port_vectors(p, sizes).1);
            difference_of(vectors.each_ref(), h)
        });
        Ok(PortChanges { tf, noise })
    }
}

/// Parameter `j`'s |H| and noise derivatives into `out`, one per frequency: the port
/// vectors' and the stage's dE(f) differenced over the stencil's points (the
/// frequency-independent parts once, dE(f) w per frequency from them), then the adjoint
/// algebra against the nominal responses.
fn response_derivatives(
    shared: &Shared,
    j: usize,
    points: &[Point; 4],
    h: f64,
    out: &mut Column,
) -> Result<(), Error> {
    let (name, sizes) = (&shared.names[j], shared.sizes);
    let ports = PortChanges::new(shared, name, points, h)?;
    let master = StageDerivative::new(
        points
            .each_ref()
            .map(|p| (&p.result.model, &p.result.system.damping)),
        h,
    )
    .ok_or_else(|| {
        bad(format!(
            "changing '{name}' changes which damping tags dissipate: no derivative"
        ))
    })?;
    let mut dew = vec![C::new(0.0, 0.0); sizes.0 + sizes.1 + sizes.2];
    let by_tag = &shared.base_point.result.model.by_tag;
    let mut buffer = Vec::new();
    for (i, &f) in shared.request.freqs.iter().enumerate() {
        let nominal = &shared.nominal[i];
        let change = master.at(f, std::mem::take(&mut buffer))?;
        if let (Some(tf), Some((db, dc))) = (&nominal.tf, &ports.tf) {
            dew.fill(C::new(0.0, 0.0));
            change.multiply(&tf.w, &mut dew)?;
            out.d_tf[i] = nominal.d_transfer(tf, &dew, db, dc, sizes)?;
        }
        if let (Some(d_o), Some(noise)) = (&ports.noise, &nominal.noise) {
            dew.fill(C::new(0.0, 0.0));
            change.multiply(&noise.w, &mut dew)?;
            out.d_noise[i] = noise.d_psd(points, (h, f), (&dew, d_o), &master, by_tag)?;
        }
        buffer = change.into_buffer();
    }
    Ok(())
}

/// The case's overrides with `name = value` last (the nominal build has checked that every
/// override is read; this one is, or it would have no derivative).
fn overridden(case: &Case, name: &str, value: f64) -> pendkit_model::Overrides {
    let mut overrides = case.overrides.clone();
    overrides
        .parameters
        .push((name.to_string(), format!("{value:e}")));
    overrides
}

/// The modes' projections Vᵀ(dK_eff/dp)V (without the equilibrium's motion) and
/// Vᵀ(dM/dp)V, and dq*/dp (full coordinate vector), from [`exact_projections`].
struct Projections {
    stiffness: DMatrix<f64>,
    mass: DMatrix<f64>,
    equilibrium: Vec<f64>,
    /// The rounding bound of each entry of `equilibrium`.
    equilibrium_rounding: Vec<f64>,
}

/// The modes' projections Vᵀ(dK_eff/dp)V and Vᵀ(dM/dp)V, exactly (docs/exact-sensitivities.md,
/// step 4): the equilibrium's motion by the implicit function theorem and the stage's
/// stiffness and mass differentiated along it ([`pendkit_assembly::stage_tangent`]) from
/// the model `dual` built with the parameter seeded. The float elimination's derivative
/// projected on a mode v is that of the full stiffness on w = (v, −X v) (X = Q⁻¹ C_QX):
/// vᵀ dK_eff v' = wᵀ dK w', so only the modes' directions (and the pairs within a cluster
/// of equal ω²) are differentiated. `None` where the route is closed: a kind without
/// tangent terms, user-written terms, or a damping tag whose real multiplier at DC is not
/// 1 at the nominal value and, where a real multiplier depends on p, at p₀ ± h.
fn exact_projections(
    shared: &Shared,
    j: usize,
    p0: f64,
    h: f64,
    dual: &System<num_dual::Dual64>,
) -> Result<Option<Projections>, Error> {
    let Some(exact) = &shared.exact else {
        return Ok(None);
    };
    let name = &shared.names[j];
    let base = &shared.base_point.result;
    // the real stiffness is the tension-on Hessian only while every ε'(0) is 1: true at the
    // nominal value (the route is open), so checked near it where an ε' depends on p
    let near = if shared.real_multiplier_reads[j] {
        &[-1.0, 1.0][..]
    } else {
        &[]
    };
    for &k in near {
        let overrides = overridden(shared.case, name, p0 + k * h);
        let Ok(system) = pendkit_model::build_stepped(dual, k * h, shared.defaults, &overrides)
        else {
            return Ok(None);
        };
        if base
            .model
            .by_tag
            .iter()
            .any(|(tag, _)| system.damping.at(tag, 0.0).0 != 1.0)
        {
            return Ok(None);
        }
    }
    let assembled = &base.assembled;
    let Some(tangent) = pendkit_assembly::stage_tangent(
        dual,
        shared.request.stage,
        &assembled.equilibrium.coords,
        &assembled.layout,
        &exact.balance,
        Along::Projected(&exact.projection),
    )?
    else {
        return Ok(None);
    };
    // the implicit function theorem's own check: the equilibrium moved along dq*/dp is
    // balanced to rounding (a relative change of p unbalances the forces by ≲ 1e-12 of
    // their size in every test; a parameter of value 0 is taken on the scale of its unit);
    // a model where it is not gets the difference route rather than a wrong number
    let p_scale = if p0 == 0.0 { 1.0 } else { p0.abs() };
    let imbalance = tangent.residual * p_scale;
    if imbalance.is_nan() || imbalance > EXACT_RESIDUAL * tangent.forces {
        return Ok(None);
    }
    let vectors = shared.vectors;
    Ok(Some(Projections {
        mass: vectors.transpose() * &tangent.mass * vectors,
        stiffness: tangent.stiffness,
        equilibrium: tangent.equilibrium,
        equilibrium_rounding: tangent.equilibrium_rounding,
    }))
}

/// The exact columns' mode derivatives: the coefficients of the equilibrium's motion along
/// the coordinates some column's dq*/dp moves beyond rounding (the lateral ones of a
/// symmetric suspension move no further: their coefficients are not computed), each
/// column's projection with the motion added, then [`mode_derivatives`].
fn finish_modes(shared: &Shared, columns: &mut [Option<Column>]) -> Result<(), Error> {
    let pending: Vec<&Projections> = columns
        .iter()
        .flatten()
        .filter_map(|c| c.pending.as_ref())
        .collect();
    let Some(first) = pending.first() else {
        return Ok(());
    };
    let mut moved = vec![false; first.equilibrium.len()];
    for p in &pending {
        for (i, m) in moved.iter_mut().enumerate() {
            *m |= pendkit_assembly::moves_beyond_rounding(
                p.equilibrium[i],
                p.equilibrium_rounding[i],
            );
        }
    }
    // a column took the exact route only where the route is open, and then the
    // coefficients exist: stage_tangent and Projection::motion refuse the same models
    let lost = || bad("the exact route lost the equilibrium's motion: no derivative");
    let route = shared.exact.as_ref().ok_or_else(lost)?;
    let motion = route
        .projection
        .motion_along(
            &shared.base_point.result.system,
            &route.balance,
            shared.request.threads,
            &moved,
        )?
        .ok_or_else(lost)?;
    for column in columns.iter_mut().flatten() {
        let Some(mut pending) = column.pending.take() else {
            continue;
        };
        route.projection.add_motion(
            &motion,
            &mut pending.stiffness,
            &pending.equilibrium,
            &pending.equilibrium_rounding,
        )?;
        column.dfdp = mode_derivatives(shared, &pending.stiffness, &pending.mass)?;
    }
    Ok(())
}

/// What the exact route shares between parameters: the equilibrium's factorised stiffness,
/// and the stiffness's projection on the modes lifted to the floats (full coordinate
/// vectors) for every mode and every pair of modes whose cross derivative a cluster needs.
struct ExactRoute {
    balance: Balance,
    projection: Projection,
}

impl ExactRoute {
    /// `None` when the route is closed to every parameter: a damping tag whose real
    /// multiplier at DC is not 1 (so the real stiffness the modes use is not the
    /// tension-on Hessian), a model with terms without parameter derivatives (found by
    /// each column's [`pendkit_assembly::stage_tangent`]), or a singular float block.
    fn new(
        base: &StageResult,
        stage: Stage,
        vectors: &DMatrix<f64>,
        clusters: &[Vec<usize>],
    ) -> Result<Option<ExactRoute>, Error> {
        let damping = &base.system.damping;
        if base
            .model
            .by_tag
            .iter()
            .any(|(tag, _)| damping.at(tag, 0.0).0 != 1.0)
        {
            return Ok(None);
        }
        let layout = &base.assembled.layout;
        // the floats' motion −Q⁻¹ C_QX v that follows the variables' v, from the engine
        let float_map = FloatMap::new(&base.model, damping);
        if float_map.is_singular() {
            return Ok(None);
        }
        let Some(balance) = Balance::new(&base.system, &base.assembled.equilibrium.coords)? else {
            return Ok(None);
        };
        let lifted = float_map.matrix() * vectors;
        let mut directions = DMatrix::zeros(base.system.coords.len(), vectors.ncols());
        for (row, &g) in layout.variables.iter().enumerate() {
            directions.row_mut(g).copy_from(&vectors.row(row));
        }
        for (row, &g) in layout.floats.iter().enumerate() {
            directions.row_mut(g).copy_from(&lifted.row(row));
        }
        let pairs: Vec<(usize, usize)> = clusters
            .iter()
            .flat_map(|c| {
                c.iter()
                    .enumerate()
                    .flat_map(move |(i, &a)| c[i..].iter().map(move |&b| (a, b)))
            })
            .collect();
        // without the equilibrium's motion, whose coefficients are computed beside the
        // parameters' columns
        let projection = Projection::at_rest(
            &base.system,
            stage,
            &base.assembled.equilibrium.coords,
            &balance,
            (&directions, &pairs),
        )?;
        Ok(Some(ExactRoute {
            balance,
            projection,
        }))
    }
}

/// d(mode frequency)/dp (Hz per unit of the parameter) of every mode from the modes'
/// projections vk = Vᵀ(dK_eff/dp)V and vm = Vᵀ(dM/dp)V (mass-normalised modes V; only the
/// entries within a cluster are read): dω² = vᵀ(dK_eff − ω² dM)v, or over a cluster of
/// (nearly) equal ω² the eigenvalues of that matrix projected on the cluster.
fn mode_derivatives(
    shared: &Shared,
    vk: &DMatrix<f64>,
    vm: &DMatrix<f64>,
) -> Result<Vec<f64>, Error> {
    let modes = &shared.base_point.result.modes.modes;
    let mut dfdp = vec![0.0; modes.len()];
    for cluster in shared.clusters {
        let w2: f64 =
            cluster.iter().map(|&k| modes[k].omega_squared).sum::<f64>() / cluster.len() as f64;
        let entry = |ka: usize, kb: usize| vk[(ka, kb)] - w2 * vm[(ka, kb)];
        let (alone, cluster_eigenvalues);
        let d: &[f64] = if let [k] = cluster[..] {
            // a mode alone (nearly every one): the matrix is its one entry
            alone = [entry(k, k)];
            &alone
        } else {
            let g = DMatrix::from_fn(cluster.len(), cluster.len(), |a, b| {
                entry(cluster[a], cluster[b])
            });
            let g = (&g + g.transpose()) * 0.5;
            let mut d: Vec<f64> = g.symmetric_eigenvalues().iter().copied().collect();
            d.sort_by(f64::total_cmp);
            cluster_eigenvalues = d;
            &cluster_eigenvalues
        };
        for (&k, &dw2) in cluster.iter().zip(d) {
            let mode = &modes[k];
            if mode.omega_squared == 0.0 {
                return Err(bad(format!(
                    "mode {} ({}) is neutral (ω² = 0): its frequency has no derivative",
                    k + 1,
                    mode.label
                )));
            }
            dfdp[k] = dw2 / (4.0 * std::f64::consts::PI * mode.omega_squared.abs().sqrt());
        }
    }
    Ok(dfdp)
}

/// Which parameters what reads, from the case's own builds.
struct ParameterReads {
    reach: Vec<Reach>,
    /// Whether the damping's real multipliers ε'(f) depend on each parameter.
    real_multiplier_reads: Vec<bool>,
    /// Whether each parameter is read only by what moves no mode.
    modes_blind: Vec<bool>,
}

impl ParameterReads {
    /// The reads of the parameters `names` of `case`, whose build resolved `resolved`, the
    /// model's own build (without the damping) reading `mechanical_reads` directly.
    fn new(
        case: &Case,
        defaults: &Defaults,
        resolved: &pendkit_params::Resolved,
        mechanical_reads: &[String],
        names: &[String],
    ) -> Result<Self, Error> {
        // which parameters the mechanical build reads (with the definitions they follow), and
        // which anything reads at all
        let read_all = case.parameters_read(resolved)?;
        let read_mechanics = case.parameters_behind(mechanical_reads.iter().cloned())?;
        // the parameters the damping's real multipliers ε' depend on: only those can move ε'(0)
        // away from 1 (the exact route's condition)
        let real_reads = case.parameters_behind(pendkit_model::damping_real_symbols(
            defaults,
            &case.overrides,
        ))?;
        let real_multiplier_reads: Vec<bool> =
            names.iter().map(|n| real_reads.contains(n)).collect();
        // what the build adds that can move the modes: the real multipliers, and the switch
        // that puts wire terms into the equilibrium; a parameter only the rest of the damping
        // (loss angles, their temperatures) and the temperature read moves no mode
        let switch_reads = case.parameters_behind([pendkit_model::WIRE_TERMS_EARLY.to_string()])?;
        let reach: Vec<Reach> = names
            .iter()
            .map(|n| {
                if read_mechanics.contains(n) {
                    Reach::Mechanics
                } else if read_all.contains(n) {
                    Reach::DampingOnly
                } else {
                    Reach::Nothing
                }
            })
            .collect();
        let modes_blind: Vec<bool> = (0..names.len())
            .map(|j| {
                reach[j] == Reach::DampingOnly
                    && !real_multiplier_reads[j]
                    && !switch_reads.contains(&names[j])
            })
            .collect();
        Ok(ParameterReads {
            reach,
            real_multiplier_reads,
            modes_blind,
        })
    }
}

/// The nominal stage, and what every parameter's column shares from it.
struct NominalStage {
    point: Point,
    /// The stability warning, where the request allows an unstable equilibrium.
    warning: Option<String>,
    /// The transfer function's ports and the noise output's, where asked for.
    ports: Option<Ports>,
    noise: Option<Ports>,
    /// The modes' vectors, one column per mode.
    vectors: DMatrix<f64>,
    clusters: Vec<Vec<usize>>,
    exact: Option<ExactRoute>,
}

impl NominalStage {
    /// `system`'s stage as `request` asks for it.
    fn new(system: System, request: &SensitivityRequest) -> Result<Self, Error> {
        let base = run_stage(system, request.stage)?;
        let warning = base.require_stable(request.allow_unstable)?;
        let base_real = base.model.real_stiffness(&base.system.damping);
        let base_k = eliminate_floats(&base_real, &base.assembled.layout, &base.system)?.k_eff;
        let base_point = Point {
            k_eff: base_k,
            result: base,
        };
        let sizes = base_point.result.model.sizes;
        let nx = sizes.0;

        let base_ports = match &request.tf {
            Some(tf) => Some(ports(&base_point, tf)?),
            None => None,
        };
        let base_noise = match &request.noise {
            Some(name) => Some(noise_port(&base_point, name)?),
            None => None,
        };

        let modes = &base_point.result.modes.modes;
        let vectors = DMatrix::from_fn(nx, modes.len(), |i, k| {
            modes[k].vector.get(i).copied().unwrap_or(0.0)
        });
        let clusters = mode_clusters(modes);
        let exact_route = if request.modes && !request.differences {
            ExactRoute::new(&base_point.result, request.stage, &vectors, &clusters)?
        } else {
            None
        };
        Ok(NominalStage {
            point: base_point,
            warning,
            ports: base_ports,
            noise: base_noise,
            vectors,
            clusters,
            exact: exact_route,
        })
    }

    /// The nominal responses at the request's frequencies (none without a response to
    /// differentiate: the request then has no frequencies), factorised once each.
    fn responses(&self, request: &SensitivityRequest) -> Result<Vec<Nominal<'_>>, Error> {
        let sizes = self.point.result.model.sizes;
        request
            .freqs
            .iter()
            .map(|&f| {
                Nominal::new(
                    &self.point,
                    f,
                    self.ports.as_ref(),
                    self.noise.as_ref(),
                    sizes,
                )
            })
            .collect()
    }
}

/// Sensitivities of `case` at the request's stage. See the module's documentation for the
/// method and its accuracy.
pub fn sensitivities(case: &Case, request: &SensitivityRequest) -> Result<Sensitivities, Error> {
    let responses = check_request(request)?;
    let (system, resolved, mechanical_reads) = case.build_with_mechanical_reads()?;
    let defaults = Defaults::of(&*case.model)?;
    let (names, values) = requested_parameters(case, request, &resolved)?;
    // the nominal stage (and what the exact route shares) beside which parameters what
    // reads and the parameters' dual builds: neither needs the other
    let (nominal_stage, reads) = side_by_side(
        request.threads,
        || NominalStage::new(system, request),
        || -> Result<_, Error> {
            let reads = ParameterReads::new(case, &defaults, &resolved, &mechanical_reads, &names)?;
            let tangents = Tangents::build(case, &names, &reads.reach, request.threads)?;
            Ok((reads, tangents))
        },
    );
    // a failing read comes first, as it would in order: the stage needs nothing read
    let (reads, tangents) = reads?;
    let mut nominal_stage = nominal_stage?;
    let exact = nominal_stage.exact.take();
    // the nominal responses' factorisations, once per frequency
    let nominal = nominal_stage.responses(request)?;
    let shared = Shared {
        case,
        defaults: &defaults,
        request,
        names: &names,
        values: &values,
        reach: &reads.reach,
        real_multiplier_reads: &reads.real_multiplier_reads,
        modes_blind: &reads.modes_blind,
        base_point: &nominal_stage.point,
        base_ports: nominal_stage.ports.as_ref(),
        nominal: &nominal,
        vectors: &nominal_stage.vectors,
        clusters: &nominal_stage.clusters,
        sizes: nominal_stage.point.result.model.sizes,
        responses,
        exact,
        tangents: &tangents,
    };
    // the columns, then the coefficients of the equilibrium's motion along the coordinates
    // their dq*/dp move (finish_modes)
    let mut columns = in_parallel_with(
        names.len(),
        request.threads,
        pendkit_model::DirectionScratch::default,
        |scratch, j| column(&shared, j, scratch),
    )?;
    finish_modes(&shared, &mut columns)?;
    let table = Table::new(&shared, columns);
    let out = table.into_sensitivities(&shared, nominal_stage.warning.clone())?;
    if !all_finite(&out) {
        return Err(bad("a sensitivity came out NaN or infinite"));
    }
    Ok(out)
}

/// Whether `request` asks for response sensitivities (|H| or noise); an error for a request
/// that asks for nothing, frequencies without a response to differentiate, or the reverse.
fn check_request(request: &SensitivityRequest) -> Result<bool, Error> {
    let responses = request.tf.is_some() || request.noise.is_some();
    if responses {
        if request.stage == Stage::S0A {
            return Err(Error::StageTooEarly);
        }
        if request.freqs.is_empty() {
            return Err(bad(
                "transfer-function and noise sensitivities need at least one frequency",
            ));
        }
        check_frequencies(&request.freqs)?;
    } else if !request.freqs.is_empty() {
        return Err(bad(
            "frequencies given without a transfer function or noise output to differentiate",
        ));
    }
    if !request.modes && !responses {
        return Err(bad(
            "nothing to differentiate: ask for the modes, a transfer function or noise",
        ));
    }
    Ok(responses)
}

/// The parameters `request` differentiates with respect to (every numeric parameter of the
/// case, in definition order, where it names none), with their values in `resolved`.
fn requested_parameters(
    case: &Case,
    request: &SensitivityRequest,
    resolved: &pendkit_params::Resolved,
) -> Result<(Vec<String>, Vec<f64>), Error> {
    let all: Vec<(String, f64)> = resolved.iter().map(|(n, v)| (n.to_string(), v)).collect();
    let names: Vec<String> = match &request.parameters {
        None => all.iter().map(|(n, _)| n.clone()).collect(),
        Some(list) => {
            if list.is_empty() {
                return Err(bad("an empty list of parameters"));
            }
            let mut seen = BTreeSet::new();
            for name in list {
                if !all.iter().any(|(n, _)| n == name) {
                    return Err(Error::Name {
                        name: name.clone(),
                        message: format!(
                            "not a numeric parameter of model '{}' (parameters: {})",
                            case.model.name(),
                            all.iter()
                                .map(|(n, _)| n.as_str())
                                .collect::<Vec<_>>()
                                .join(" ")
                        ),
                    });
                }
                if !seen.insert(name.as_str()) {
                    return Err(Error::Name {
                        name: name.clone(),
                        message: "listed twice".into(),
                    });
                }
            }
            list.clone()
        }
    };
    let values: Vec<f64> = names
        .iter()
        .map(|n| all.iter().find(|(m, _)| m == n).map_or(0.0, |(_, v)| *v))
        .collect();
    Ok((names, values))
}

/// The parameters' columns as the output's rows hold them, without the parameters the
/// model refuses to move (which lose their columns).
struct Table {
    /// The parameters kept (indices into the request's), and each one's step, build and
    /// route.
    kept: Vec<usize>,
    steps: Vec<f64>,
    exact_build: Vec<bool>,
    exact: Vec<bool>,
    /// `[mode][kept parameter]`.
    dfdp: Vec<Vec<f64>>,
    /// `[frequency][kept parameter]`: d of the TF and of the noise PSD.
    d_tf: Vec<Vec<C>>,
    d_noise: Vec<Vec<f64>>,
    /// The parameters refused, with why.
    not_differentiable: Vec<(String, String)>,
}

impl Table {
    fn new(shared: &Shared, columns: Vec<Option<Column>>) -> Table {
        let request = shared.request;
        let (nm, nf) = (
            if request.modes {
                shared.base_point.result.modes.modes.len()
            } else {
                0
            },
            request.freqs.len(),
        );
        let mut table = Table {
            kept: Vec::new(),
            steps: Vec::new(),
            exact_build: Vec::new(),
            exact: Vec::new(),
            dfdp: vec![Vec::new(); nm],
            d_tf: vec![Vec::new(); nf],
            d_noise: vec![Vec::new(); nf],
            not_differentiable: Vec::new(),
        };
        for (j, column) in columns.into_iter().enumerate() {
            let column = match column {
                Some(Column {
                    refused: Some(why), ..
                }) => {
                    table
                        .not_differentiable
                        .push((shared.names[j].clone(), why));
                    continue;
                }
                Some(column) => column,
                // nothing reads it: every derivative exactly 0 (exact where the exact route
                // was asked for), no step
                None => Column {
                    exact: request.modes && !request.differences,
                    ..Column::new(shared, 0.0, false)
                },
            };
            table.push(j, column);
        }
        table
    }

    fn push(&mut self, j: usize, column: Column) {
        self.kept.push(j);
        self.steps.push(column.step);
        self.exact_build.push(column.exact_build);
        self.exact.push(column.exact);
        for (row, d) in self.dfdp.iter_mut().zip(column.dfdp) {
            row.push(d);
        }
        for (row, d) in self.d_tf.iter_mut().zip(column.d_tf) {
            row.push(d);
        }
        for (row, d) in self.d_noise.iter_mut().zip(column.d_noise) {
            row.push(d);
        }
    }

    /// The request's answer: the kept parameters with their values and units, the modes, and
    /// |H| and the noise ASD with their derivatives from the nominal responses.
    fn into_sensitivities(
        self,
        shared: &Shared,
        warning: Option<String>,
    ) -> Result<Sensitivities, Error> {
        let (request, freqs) = (shared.request, &shared.request.freqs);
        let tf_abs = match &request.tf {
            Some(_) => Some(tf_abs(shared.nominal, &self.d_tf, freqs)?),
            None => None,
        };
        let noise_asd = match &request.noise {
            Some(_) => Some(noise_asd(shared.nominal, &self.d_noise, freqs)?),
            None => None,
        };
        let modes = &shared.base_point.result.modes.modes;
        let parameters: Vec<String> = self.kept.iter().map(|&j| shared.names[j].clone()).collect();
        let units = parameters
            .iter()
            .map(|n| {
                shared
                    .defaults
                    .params
                    .unit(n)
                    .unwrap_or_default()
                    .to_string()
            })
            .collect();
        Ok(Sensitivities {
            not_differentiable: self.not_differentiable,
            values: self.kept.iter().map(|&j| shared.values[j]).collect(),
            parameters,
            units,
            steps: self.steps,
            exact_build: self.exact_build,
            exact: self.exact,
            modes_hz: modes.iter().map(|m| m.hz).collect(),
            mode_labels: modes.iter().map(|m| m.label.clone()).collect(),
            dfdp: self.dfdp,
            tf_abs,
            noise_asd,
            warning,
        })
    }
}

/// |H| at each frequency, and d|H|/dp = Re(H̄ dH)/|H| from each parameter's dH; an error
/// where |H| is 0 (a corner: no derivative) or not finite.
fn tf_abs(
    nominal: &[Nominal],
    d_tf: &[Vec<C>],
    freqs: &[f64],
) -> Result<(Vec<f64>, Vec<Vec<f64>>), Error> {
    let mut abs = Vec::with_capacity(freqs.len());
    let mut d = Vec::with_capacity(freqs.len());
    for (i, n) in nominal.iter().enumerate() {
        let h = n.tf.as_ref().map_or(C::new(f64::NAN, 0.0), |t| t.value);
        let a = h.norm();
        if a == 0.0 {
            // |H| has a corner at 0: no derivative (the input does not reach the
            // output at this frequency)
            return Err(bad(format!(
                "|H| is exactly 0 at {} Hz (the input does not reach the output): \
                 it has no derivative there",
                freqs[i]
            )));
        }
        if !a.is_finite() {
            return Err(Error::NotFinite {
                what: "|H|".into(),
                f_hz: freqs[i],
            });
        }
        abs.push(a);
        d.push(
            d_tf[i]
                .iter()
                .map(|dh| (h.conj() * dh).re / a)
                .collect::<Vec<f64>>(),
        );
    }
    Ok((abs, d))
}

/// The thermal-noise ASD at each frequency, and d(ASD)/dp = d(PSD)/dp / 2 ASD from each
/// parameter's d(PSD); an error where the ASD is 0 (no derivative) or not finite.
fn noise_asd(
    nominal: &[Nominal],
    d_noise: &[Vec<f64>],
    freqs: &[f64],
) -> Result<(Vec<f64>, Vec<Vec<f64>>), Error> {
    let mut asd = Vec::with_capacity(freqs.len());
    let mut d = Vec::with_capacity(freqs.len());
    for (i, n) in nominal.iter().enumerate() {
        let f = freqs[i];
        let a = n.noise.as_ref().map_or(f64::NAN, NoiseNominal::psd).sqrt();
        if a == 0.0 {
            // √PSD has no derivative at 0
            return Err(bad(format!(
                "the thermal-noise ASD is exactly 0 at {f} Hz (nothing on the output's \
                 path dissipates): it has no derivative there"
            )));
        }
        if !a.is_finite() {
            return Err(Error::NotFinite {
                what: "the thermal-noise ASD".into(),
                f_hz: f,
            });
        }
        asd.push(a);
        d.push(d_noise[i].iter().map(|dpsd| dpsd / (2.0 * a)).collect());
    }
    Ok((asd, d))
}

/// Whether every derivative and value of `out` is finite.
fn all_finite(out: &Sensitivities) -> bool {
    out.dfdp.iter().flatten().all(|x| x.is_finite())
        && [&out.tf_abs, &out.noise_asd]
            .iter()
            .filter_map(|x| x.as_ref())
            .all(|(v, d)| v.iter().chain(d.iter().flatten()).all(|x| x.is_finite()))
}

/// Modes grouped into clusters of (nearly) equal ω², each ascending.
fn mode_clusters(modes: &[pendkit_dynamics::Mode]) -> Vec<Vec<usize>> {
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    for (k, m) in modes.iter().enumerate() {
        let joins = clusters.last().and_then(|c| c.last()).is_some_and(|&l| {
            let prev = &modes[l];
            let gap = (m.omega_squared - prev.omega_squared).abs();
            let scale = m.omega_squared.abs().max(prev.omega_squared.abs());
            gap <= CLUSTER_GAP * scale + m.omega_squared_error + prev.omega_squared_error
        });
        match clusters.last_mut() {
            Some(c) if joins => c.push(k),
            _ => clusters.push(vec![k]),
        }
    }
    clusters
}

/// The nominal model's responses at one frequency, solved by the engine's sweep
/// ([`Sweep`], every unknown), with the adjoint responses that turn each parameter's
/// dE(f) w into the derivatives without a solve of its own (E(f) is complex symmetric, so
/// cᵀE⁻¹r = (E⁻¹c)ᵀr).
struct Nominal<'a> {
    /// The nominal stage model and E(f) on its pattern ([`StageModel::dynamic_parts`]
    /// summed by [`StageModel::sum_parts`]).
    model: &'a StageModel,
    e: Vec<C>,
    /// The transfer function, when asked for.
    tf: Option<TfNominal>,
    /// The thermal noise of the noise output, when asked for.
    noise: Option<NoiseNominal>,
}

/// What the transfer function's derivative needs at one frequency.
struct TfNominal {
    /// H.
    value: C,
    /// The output's vector c over all master rows (a displacement output) or the
    /// parameters (a support force).
    c: DVector<f64>,
    force_in: bool,
    force_out: bool,
    /// w = [z; s]: the response over every master row to the input (s its displacement,
    /// 0 for a force).
    w: Vec<C>,
    /// E(f) w over every master row (the support force reads its parameters' rows).
    e_w: Vec<C>,
    /// y = E_uu⁻¹ g over the unknowns, g = ∂H/∂z (c over the unknowns for a displacement
    /// output, −E_us c for a support force): dH ∋ yᵀ(d rhs − dE w).
    adjoint: Vec<C>,
}

/// What the noise's derivative needs at one frequency: the response z = E⁻¹o over the
/// unknowns to a unit force along the output o, and the dissipation it meets.
struct NoiseNominal {
    /// [z; 0] over every master row.
    w: Vec<C>,
    /// R = oᵀz: with one temperature T, PSD = 4 k_B T/ω |Im R|.
    response: C,
    /// 4 k_B/ω ([`pendkit_noise::fd_scale`]).
    scale: f64,
    /// The model's temperature T (K).
    temperature: f64,
    /// Where some damping tag has its own temperature: the fluctuation–dissipation sum
    /// per tag (as the noise is computed), with each tag's adjoint E⁻¹ conj(P_tag z).
    tags: Option<(pendkit_noise::TagSum, Vec<Vec<C>>)>,
}

impl NoiseNominal {
    fn psd(&self) -> f64 {
        match &self.tags {
            None => self.scale * self.temperature * self.response.im.abs(),
            Some((sum, _)) => sum.psd(),
        }
    }

    /// d(PSD)/dp at `f_hz` from the stencil's `points` (step `h`), dE z (`dez`, over every
    /// master row), the output vector's derivative `d_o` and the parameter's stage
    /// derivative (for each tag's dP_tag). One temperature: dPSD = 4k_B/ω (dT |Im R| +
    /// T sign(Im R) Im dR), dR = 2(do)ᵀz − zᵀ(dE)z. Per tag: the sum's change
    /// ([`pendkit_noise::TagSum::change`]) with d(T_tag ε''_tag) differenced like the
    /// matrices and dE_tag = z̄ᵀ dP_tag z + 2 Re yᵀ(do − dE z), y the tag's adjoint.
    fn d_psd(
        &self,
        points: &[Point; 4],
        (h, f_hz): (f64, f64),
        (dez, d_o): (&[C], &DVector<f64>),
        master: &StageDerivative<'_>,
        by_tag: &[(String, Vec<f64>)],
    ) -> Result<f64, Error> {
        let u = points[0].result.model.unknowns();
        let z = &self.w[..u];
        let Some((sum, adjoints)) = &self.tags else {
            let d_t = difference(points, h, |p| p.result.system.temperature);
            let dr: C = (0..u).map(|i| z[i] * (2.0 * d_o[i]) - z[i] * dez[i]).sum();
            let im = self.response.im;
            return Ok(self.scale * (d_t * im.abs() + self.temperature * im.signum() * dr.im));
        };
        let rhs: Vec<C> = (0..u).map(|i| C::new(d_o[i], 0.0) - dez[i]).collect();
        let mut d_weights = Vec::with_capacity(by_tag.len());
        let mut d_energies = Vec::with_capacity(by_tag.len());
        for ((tag, _), adjoint) in by_tag.iter().zip(adjoints) {
            // the nominal's tags are the points' (StageDerivative::new checked them)
            let part = master.tag(tag).ok_or_else(|| {
                bad(format!(
                    "damping tag '{tag}' dissipates at the nominal value only: no derivative"
                ))
            })?;
            d_weights.push(difference(points, h, |p| {
                let system = &p.result.system;
                pendkit_noise::tag_weight(&system.damping, tag, system.temperature, f_hz)
            }));
            let along: C = adjoint.iter().zip(&rhs).map(|(y, r)| y * r).sum();
            let form = |model: &StageModel, values: &[f64]| {
                pendkit_noise::dissipation_form(model, values, z)
            };
            d_energies.push(part.linear(h, form)? + 2.0 * along.re);
        }
        Ok(sum.change(&d_weights, &d_energies))
    }
}

/// The transfer function's nominal at one frequency: the response w to the input over every
/// master row, E w, and the adjoint y (Eᵀ y = c over the unknowns) from the same factors.
fn tf_nominal(
    model: &StageModel,
    damping: &pendkit_system::Damping,
    e: &[C],
    ports: &Ports,
    sizes: (usize, usize, usize),
    f_hz: f64,
) -> Result<TfNominal, Error> {
    let (nx, nq, ns) = sizes;
    let (u, n) = (nx + nq, nx + nq + ns);
    let zero = C::new(0.0, 0.0);
    let input = ports
        .input
        .as_ref()
        .ok_or_else(|| bad("a transfer function without an input"))?;
    let (b, c) = port_vectors(ports, sizes);
    let force_in = matches!(input, Input::Force(_));
    let force_out = matches!(ports.output, Output::SupportForce(_));
    let mut sweep = Sweep::new(model, damping, input, &ports.output, Solver::Full)?;
    let value = sweep.at(f_hz)?;
    let mut w = vec![zero; n];
    w[..u].copy_from_slice(sweep.response());
    if !force_in {
        for (x, &s) in w[u..].iter_mut().zip(b.iter()) {
            *x = C::new(s, 0.0);
        }
    }
    let mut e_w = vec![zero; n];
    model.multiply(e, &w, &mut e_w)?;
    let mut adjoint: Vec<C> = if force_out {
        let mut on_support = vec![zero; n];
        for (x, &ck) in on_support[u..].iter_mut().zip(c.iter()) {
            *x = C::new(ck, 0.0);
        }
        let mut e_c = vec![zero; n];
        model.multiply(e, &on_support, &mut e_c)?;
        e_c[..u].iter().map(|x| -x).collect()
    } else {
        c.iter().take(u).map(|&x| C::new(x, 0.0)).collect()
    };
    sweep.solve_again(&mut adjoint)?;
    Ok(TfNominal {
        value,
        c,
        force_in,
        force_out,
        w,
        e_w,
        adjoint,
    })
}

/// The noise's nominal at one frequency: the response w to a unit force along the output,
/// its value, and per tag (only where some tag has its own temperature) the sum and the
/// adjoints of each tag's dissipation.
fn noise_nominal(
    model: &StageModel,
    system: &System,
    ports: &Ports,
    sizes: (usize, usize, usize),
    f_hz: f64,
) -> Result<NoiseNominal, Error> {
    let (nx, nq, ns) = sizes;
    let (u, n) = (nx + nq, nx + nq + ns);
    let zero = C::new(0.0, 0.0);
    let damping = &system.damping;
    let o = port_vectors(ports, sizes).1.rows(0, u).into_owned();
    let mut sweep = Sweep::new(
        model,
        damping,
        &Input::Force(o.clone()),
        &Output::Displacement(o),
        Solver::Full,
    )?;
    let response = sweep.at(f_hz)?;
    let mut w = vec![zero; n];
    w[..u].copy_from_slice(sweep.response());
    let temperature = system.temperature;
    // per tag only where some tag has its own temperature: otherwise the
    // one-temperature form, as the noise itself is computed
    let tags = if model
        .by_tag
        .iter()
        .any(|(t, _)| damping.temperature(t).is_some())
    {
        let sum = pendkit_noise::TagSum::new(model, damping, temperature, f_hz, &w[..u])?;
        let mut adjoints = Vec::with_capacity(model.by_tag.len());
        let mut p = vec![zero; model.pattern.len()];
        for (_, values) in &model.by_tag {
            model.sum_parts(&[(C::new(1.0, 0.0), values)], &mut p)?;
            let mut p_w = vec![zero; n];
            model.multiply(&p, &w, &mut p_w)?;
            let mut y: Vec<C> = p_w[..u].iter().map(|x| x.conj()).collect();
            sweep.solve_again(&mut y)?;
            adjoints.push(y);
        }
        Some((sum, adjoints))
    } else {
        None
    };
    Ok(NoiseNominal {
        w,
        response,
        scale: pendkit_noise::fd_scale(f_hz),
        temperature,
        tags,
    })
}

impl<'a> Nominal<'a> {
    fn new(
        point: &'a Point,
        f_hz: f64,
        tf: Option<&Ports>,
        noise: Option<&Ports>,
        sizes: (usize, usize, usize),
    ) -> Result<Nominal<'a>, Error> {
        let model = &point.result.model;
        let system = &point.result.system;
        let damping = &system.damping;
        // the multipliers `pendkit tf` and `noise` refuse (a negative loss, a non-finite
        // value) are refused here too, not differentiated
        model.check_damping_at(damping, f_hz)?;
        let zero = C::new(0.0, 0.0);
        let mut e = vec![zero; model.pattern.len()];
        model.sum_parts(&model.dynamic_parts(damping, f_hz), &mut e)?;
        let tf = tf
            .map(|ports| tf_nominal(model, damping, &e, ports, sizes, f_hz))
            .transpose()?;
        let noise = noise
            .map(|ports| noise_nominal(model, system, ports, sizes, f_hz))
            .transpose()?;
        Ok(Nominal {
            model,
            e,
            tf,
            noise,
        })
    }

    /// dH for dE w (`dew`, over every master row) and the derivatives `db`, `dc` of the
    /// port vectors: yᵀ r' with r' = d rhs − (dE w)_u (d rhs = db for a force input,
    /// −E_us db for a displacement), plus, for a displacement output, dcᵀw + c_sᵀ db; for a
    /// support force, −(dcᵀ(E w)_s + cᵀ(dE w)_s + cᵀ E_ss db).
    fn d_transfer(
        &self,
        tf: &TfNominal,
        dew: &[C],
        db: &DVector<f64>,
        dc: &DVector<f64>,
        sizes: (usize, usize, usize),
    ) -> Result<C, Error> {
        let (nx, nq, ns) = sizes;
        let u = nx + nq;
        let zero = C::new(0.0, 0.0);
        let mut rhs: Vec<C> = dew[..u].iter().map(|x| -x).collect();
        // E [0; db]: the displacement input's change through the stage
        let mut e_db = Vec::new();
        if tf.force_in {
            for (r, &x) in rhs.iter_mut().zip(db.iter()) {
                *r += x;
            }
        } else {
            let mut on_support = vec![zero; u + ns];
            for (x, &d) in on_support[u..].iter_mut().zip(db.iter()) {
                *x = C::new(d, 0.0);
            }
            e_db = vec![zero; u + ns];
            self.model.multiply(&self.e, &on_support, &mut e_db)?;
            for (r, x) in rhs.iter_mut().zip(&e_db) {
                *r -= x;
            }
        }
        let through: C = tf.adjoint.iter().zip(&rhs).map(|(y, r)| y * r).sum();
        Ok(if tf.force_out {
            let direct: C = (0..ns)
                .map(|k| {
                    let from_input = e_db.get(u + k).copied().unwrap_or(zero);
                    tf.e_w[u + k] * dc[k] + (dew[u + k] + from_input) * tf.c[k]
                })
                .sum();
            through - direct
        } else {
            let from_dc: C = dc.iter().zip(&tf.w).map(|(&d, w)| w * d).sum();
            let from_input: f64 = if tf.force_in {
                0.0
            } else {
                (0..ns).map(|k| tf.c[u + k] * db[k]).sum()
            };
            through + from_dc + from_input
        })
    }
}
