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

use nalgebra::{DMatrix, DVector, Vector3};
use num_dual::{Dual, Dual64};
use pendkit_energy::{
    CoordKind, EarlyWireTerms, EnergyError, Reference, Stage, System, TangentTerm, registry,
    tangent_frames, tangent_frames_along,
};
use pendkit_rotations::{Constant, tr_mul, vee};

use crate::equilibrium::free_coordinates;
use crate::{AssemblyError, Layout};

/// dq*/dp, dK/dp and dM/dp of one stage with respect to one parameter.
#[derive(Clone, Debug)]
pub struct StageTangent {
    /// dq*/dp, one entry per coordinate (m or rad per unit of the parameter; 0 on the
    /// coordinates Newton does not move: parameters and pinned ones).
    pub equilibrium: Vec<f64>,
    /// dK/dp (tension on) along the moving equilibrium (N/m, N, N m/rad per unit of the
    /// parameter): over all coordinates, global order (n × n), or projected on the
    /// directions asked for ([`Along`]).
    pub stiffness: DMatrix<f64>,
    /// dM/dp over the layout's variables (kg, kg m, kg m² per unit of the parameter).
    pub mass: DMatrix<f64>,
    /// The largest |dg/dp| on a free coordinate once the equilibrium moves along δq (N or
    /// N m per unit of the parameter): the implicit function theorem's own check, zero but
    /// for rounding, which is measured against `forces`.
    pub residual: f64,
    /// The largest sum over the balanced terms of their |force| on one free coordinate at
    /// the equilibrium (N or N m): the scale of the forces' rounding.
    pub forces: f64,
}

/// The kinds' tangent terms whose stage passes `include`, built around `coords`; `None`
/// when some kind has none (the caller falls back to differences).
fn kind_tangent_terms(
    system: &System<Dual64>,
    coords: &[Dual64],
    include: impl Fn(Stage) -> bool,
) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
    let reference = Reference { system, coords };
    let mut terms = Vec::new();
    for kind in registry()
        .into_iter()
        .filter(|k| system.element_stage(*k).is_some_and(&include))
    {
        match kind.tangent_terms(&reference)? {
            Some(t) => terms.extend(t),
            None => return Ok(None),
        }
    }
    Ok(Some(terms))
}

/// Sums of the terms' derivatives over the full coordinate vector: Hessian and gradient
/// (value parts in `.re`, parameter derivatives in `.eps`), and per coordinate the sum of
/// the terms' |force|, the scale the sum's rounding is measured against.
struct Sums {
    hessian: DMatrix<Dual64>,
    gradient: DVector<Dual64>,
    magnitude: DVector<f64>,
}

impl Sums {
    fn new(n: usize) -> Self {
        let zero = Dual64::from_re(0.0);
        Sums {
            hessian: DMatrix::from_element(n, n, zero),
            gradient: DVector::from_element(n, zero),
            magnitude: DVector::zeros(n),
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
    for term in terms {
        let d = if hessian {
            term.derivatives(x)?
        } else {
            term.gradient(x)?
        };
        let m = term.coords.len();
        for (a, &ga) in term.coords.iter().enumerate() {
            sums.gradient[ga] += d.gradient[a];
            sums.magnitude[ga] += d.gradient[a].re.abs();
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
}

impl Balance {
    /// The balance of `system` at `equilibrium` (its full coordinate vector); `None` when the
    /// model has terms without parameter derivatives (see [`stage_tangent`]).
    pub fn new(system: &System, equilibrium: &[f64]) -> Result<Option<Balance>, AssemblyError> {
        let system = system.map_scalars(Dual64::from_re);
        check_equilibrium(&system, equilibrium)?;
        let Some(balanced) = balanced_terms(&system)? else {
            return Ok(None);
        };
        let n = system.coords.len();
        let at_rest: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
        let mut sums = Sums::new(n);
        accumulate(&balanced, &at_rest, &mut sums, true)?;
        let free = free_coordinates(&system);
        let k = DMatrix::from_fn(free.len(), free.len(), |a, b| {
            sums.hessian[(free[a], free[b])].re
        });
        let coords = system.coords.iter().map(|c| c.name.clone()).collect();
        Ok(Some(Balance {
            coords,
            free,
            lu: k.lu(),
        }))
    }
}

/// The terms Newton minimised: the stage-0A kinds' (their constants do not depend on the
/// configuration they are built around). `None` when some kind has no tangent terms, when
/// the model has user-written terms (text: whether their numbers move with the parameter
/// is unknown), or when plug-in terms join the equilibrium: those are built around the
/// start position, which moves with the parameters (the nominal geometry) but whose
/// derivative the model does not carry (`Coordinate::start` is a number, not a model
/// constant).
fn balanced_terms(system: &System<Dual64>) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
    if !system.extra_terms.is_empty() || system.early_wire_terms != EarlyWireTerms::No {
        return Ok(None);
    }
    let start: Vec<Dual64> = system.start().into_iter().map(Dual64::from_re).collect();
    kind_tangent_terms(system, &start, |s| s == Stage::S0A)
}

fn check_equilibrium(system: &System<Dual64>, equilibrium: &[f64]) -> Result<(), AssemblyError> {
    let n = system.coords.len();
    if equilibrium.len() != n {
        return Err(AssemblyError::Length {
            function: "stage_tangent",
            argument: "equilibrium",
            expected: n,
            given: equilibrium.len(),
        });
    }
    Ok(system.check_indices()?)
}

/// Which part of dK/dp [`stage_tangent`] computes.
#[derive(Clone, Copy, Debug)]
pub enum Along<'a> {
    /// Every entry (n × n, global order): one evaluation per entry of each term's upper
    /// triangle.
    Full,
    /// The entries (a, b) of Wᵀ (dK/dp) W listed in `pairs` (the rest 0), W's columns full
    /// coordinate vectors: one evaluation per pair and term, for the few directions a mode
    /// sensitivity needs (the modes, lifted to the floats).
    Pairs {
        /// The directions, one column each (n rows).
        vectors: &'a DMatrix<f64>,
        /// The entries wanted (a, b), a ≤ b.
        pairs: &'a [(usize, usize)],
    },
}

/// The exact derivatives of stage `stage`'s stiffness and mass with respect to the
/// parameter `system` was built with seeded, at the equilibrium `equilibrium` (the `f64`
/// model's, full coordinate vector) with the stage's `layout` and the equilibrium's
/// `balance` (from the `f64` model). `None` when the model has terms without such
/// derivatives (a kind without tangent terms, user-written terms, wire terms that join the
/// equilibrium), for which the caller keeps to differences.
pub fn stage_tangent(
    system: &System<Dual64>,
    stage: Stage,
    equilibrium: &[f64],
    layout: &Layout,
    balance: &Balance,
    along: Along,
) -> Result<Option<StageTangent>, AssemblyError> {
    check_equilibrium(system, equilibrium)?;
    crate::check_layout("stage_tangent", system, layout)?;
    let n = system.coords.len();
    let free = &balance.free;
    if !balance
        .coords
        .iter()
        .eq(system.coords.iter().map(|c| &c.name))
    {
        return Err(AssemblyError::ForeignBalance);
    }
    let Some(balanced) = balanced_terms(system)? else {
        return Ok(None);
    };
    // ∂g/∂p at the fixed equilibrium, and δq = −K⁻¹ ∂g/∂p
    let at_rest: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
    let mut rest = Sums::new(n);
    accumulate(&balanced, &at_rest, &mut rest, false)?;
    let dg_free = DVector::from_fn(free.len(), |a, _| rest.gradient[free[a]].eps);
    let forces = free.iter().map(|&g| rest.magnitude[g]).fold(0.0, f64::max);
    let delta_free = if dg_free.amax() == 0.0 {
        DVector::zeros(free.len())
    } else {
        balance
            .lu
            .solve(&(-&dg_free))
            .ok_or(AssemblyError::SingularEquilibrium)?
    };
    let mut delta = vec![0.0; n];
    for (a, &gi) in free.iter().enumerate() {
        delta[gi] = delta_free[a];
    }
    // the equilibrium moving with the parameter, and every term of the stage built there
    let moving: Vec<Dual64> = equilibrium
        .iter()
        .zip(&delta)
        .map(|(&v, &d)| Dual64::new(v, d))
        .collect();
    // the stage's plug-in terms, built around the moving equilibrium
    let Some(plugins) = kind_tangent_terms(system, &moving, |s| s != Stage::S0A && s <= stage)?
    else {
        return Ok(None);
    };
    let mut moved = Sums::new(n);
    accumulate(&balanced, &moving, &mut moved, false)?;
    let balanced_residual = free
        .iter()
        .map(|&g| moved.gradient[g].eps.abs())
        .fold(0.0, f64::max);
    let all = || balanced.iter().chain(&plugins);
    let stiffness = match along {
        Along::Full => {
            let mut sums = Sums::new(n);
            for term in all() {
                add_hessian(term, &moving, &mut sums)?;
            }
            sums.hessian.map(|v| v.eps)
        }
        Along::Pairs { vectors, pairs } => {
            if vectors.nrows() != n {
                return Err(AssemblyError::Length {
                    function: "stage_tangent",
                    argument: "along: vectors (rows)",
                    expected: n,
                    given: vectors.nrows(),
                });
            }
            let m = vectors.ncols();
            let mut out = DMatrix::zeros(m, m);
            let columns: Vec<Vec<f64>> = (0..m)
                .map(|a| vectors.column(a).iter().copied().collect())
                .collect();
            for &(a, b) in pairs {
                let (Some(u), Some(v)) = (columns.get(a), columns.get(b)) else {
                    return Err(AssemblyError::Length {
                        function: "stage_tangent",
                        argument: "along: pairs (a direction's index)",
                        expected: m,
                        given: a.max(b) + 1,
                    });
                };
                // each body's frame once for every term on it; along one direction the
                // cheaper second-order dual number
                let mut sum = 0.0;
                if a == b {
                    let frames = tangent_frames_along(system, &moving, u)?;
                    for term in all() {
                        sum += term.second_along_frames_once(&frames)?.eps;
                    }
                } else {
                    let frames = tangent_frames(system, &moving, u, v)?;
                    for term in all() {
                        sum += term.second_along_frames(&frames)?.eps;
                    }
                }
                out[(a, b)] = sum;
                out[(b, a)] = sum;
            }
            out
        }
    };
    Ok(Some(StageTangent {
        equilibrium: delta,
        stiffness,
        mass: mass_tangent(system, layout, &moving),
        residual: balanced_residual,
        forces,
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
        let vars: Vec<usize> = body
            .frame
            .var_list()
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
