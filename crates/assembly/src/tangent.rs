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
};
use pendkit_rotations::{Constant, tr_mul, vee};

use crate::{AssemblyError, Layout};

/// dq*/dp, dK/dp and dM/dp of one stage with respect to one parameter.
#[derive(Clone, Debug)]
pub struct StageTangent {
    /// dq*/dp, one entry per coordinate (m or rad per unit of the parameter; 0 on the
    /// coordinates Newton does not move: parameters and pinned ones).
    pub equilibrium: Vec<f64>,
    /// dK/dp (tension on) over all coordinates, global order (n × n), along the moving
    /// equilibrium (N/m, N, N m/rad per unit of the parameter).
    pub stiffness: DMatrix<f64>,
    /// dM/dp over the layout's variables (kg, kg m, kg m² per unit of the parameter).
    pub mass: DMatrix<f64>,
    /// The largest |dg/dp| on a free coordinate once the equilibrium moves along δq,
    /// relative to the largest |∂g/∂p|: the implicit function theorem's own check, zero
    /// but for rounding.
    pub residual: f64,
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

/// Adds each term's Hessian (or, when `hessian` is false, gradient) at `x` into `matrix`
/// (or `vector`), global order; value parts into `.re`, parameter derivatives into `.eps`.
fn accumulate(
    terms: &[TangentTerm],
    x: &[Dual64],
    matrix: &mut DMatrix<Dual64>,
    vector: &mut DVector<Dual64>,
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
            vector[ga] += d.gradient[a];
            if hessian {
                for (b, &gb) in term.coords.iter().enumerate() {
                    matrix[(ga, gb)] += d.hessian[a * m + b];
                }
            }
        }
    }
    Ok(())
}

/// The exact derivatives of stage `stage`'s stiffness and mass with respect to the
/// parameter `system` was built with seeded, at the equilibrium `equilibrium` (the `f64`
/// model's, full coordinate vector) with the stage's `layout`. `None` when the model has
/// terms without such derivatives (a kind without tangent terms, user-written terms),
/// for which the caller keeps to differences.
pub fn stage_tangent(
    system: &System<Dual64>,
    stage: Stage,
    equilibrium: &[f64],
    layout: &Layout,
) -> Result<Option<StageTangent>, AssemblyError> {
    let n = system.coords.len();
    if equilibrium.len() != n {
        return Err(AssemblyError::Length {
            function: "stage_tangent",
            argument: "equilibrium",
            expected: n,
            given: equilibrium.len(),
        });
    }
    system.check_indices()?;
    // user-written terms are text: whether their numbers move with the parameter is unknown
    if !system.extra_terms.is_empty() {
        return Ok(None);
    }
    let zero = Dual64::from_re(0.0);
    let start: Vec<Dual64> = system.start().into_iter().map(Dual64::from_re).collect();
    // the terms Newton minimised: stage-0A kinds (their constants do not depend on the
    // reference) and, when plug-in terms join early, all of those built around the start
    let early = system.early_wire_terms != EarlyWireTerms::No;
    let Some(balanced) = kind_tangent_terms(system, &start, |s| s == Stage::S0A || early)? else {
        return Ok(None);
    };
    let free: Vec<usize> = (0..n)
        .filter(|&g| {
            let c = &system.coords[g];
            c.kind != CoordKind::Parameter && !c.pinned
        })
        .collect();
    // ∂g/∂p and K at the fixed equilibrium
    let at_rest: Vec<Dual64> = equilibrium.iter().map(|&v| Dual64::from_re(v)).collect();
    let mut k = DMatrix::from_element(n, n, zero);
    let mut g = DVector::from_element(n, zero);
    accumulate(&balanced, &at_rest, &mut k, &mut g, true)?;
    let k_free = DMatrix::from_fn(free.len(), free.len(), |a, b| k[(free[a], free[b])].re);
    let dg_free = DVector::from_fn(free.len(), |a, _| g[free[a]].eps);
    let scale = dg_free.amax();
    let delta_free = if scale == 0.0 {
        DVector::zeros(free.len())
    } else {
        let Some(solved) = k_free.lu().solve(&(-&dg_free)) else {
            return Err(AssemblyError::SingularEquilibrium);
        };
        solved
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
    let stage_terms = if system.early_wire_terms == EarlyWireTerms::Yes {
        Some(Vec::new())
    } else {
        kind_tangent_terms(system, &moving, |s| s != Stage::S0A && s <= stage)?
    };
    let Some(stage_terms) = stage_terms else {
        return Ok(None);
    };
    let mut dk = DMatrix::from_element(n, n, zero);
    let mut dg = DVector::from_element(n, zero);
    accumulate(&balanced, &moving, &mut dk, &mut dg, true)?;
    let balanced_residual = free.iter().map(|&gi| dg[gi].eps.abs()).fold(0.0, f64::max);
    let mut unused = DVector::from_element(n, zero);
    accumulate(&stage_terms, &moving, &mut dk, &mut unused, true)?;
    Ok(Some(StageTangent {
        equilibrium: delta,
        stiffness: dk.map(|v| v.eps),
        mass: mass_tangent(system, layout, &moving),
        residual: if scale == 0.0 {
            balanced_residual
        } else {
            balanced_residual / scale
        },
    }))
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
