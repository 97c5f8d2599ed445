//! Collects a model's potential terms for a calculation stage, finds the equilibrium by
//! Newton minimisation, differentiates each term twice over its own coordinates (tension on
//! and off) and assembles the master stiffness matrix (blocks K, C_XQ, C_XS, Q, C_QS, S) and
//! the mass matrix from the bodies.

mod equilibrium;

use std::collections::BTreeMap;

use nalgebra::DMatrix;
use pendkit_energy::{
    CoordKind, EarlyWireTerms, EnergyError, ExtraPhase, Reference, Stage, System, TensionOff, Term,
    constraint_terms, extra_terms, registry,
};

pub use equilibrium::{Equilibrium, EquilibriumOptions, find_equilibrium};

/// Errors of the equilibrium search and assembly.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssemblyError {
    /// A model element could not produce its terms.
    #[error(transparent)]
    Energy(#[from] EnergyError),
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
    /// A float moves a body with mass or inertia (floats must be massless).
    #[error("float '{float}' moves body '{body}', which has mass: make it a variable")]
    MassiveFloat {
        /// Float name.
        float: String,
        /// Body name.
        body: String,
    },
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
    /// Master-matrix row of each global coordinate.
    pub position: Vec<usize>,
}

impl Layout {
    /// The layout of `system`'s coordinates.
    pub fn new(system: &System) -> Self {
        let variables = system.coords_of(CoordKind::Variable);
        let floats = system.coords_of(CoordKind::Float);
        let parameters = system.coords_of(CoordKind::Parameter);
        let mut position = vec![0; system.coords.len()];
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

    /// Total number of coordinates.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether the model has no coordinates.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
}

/// The tension-off part of one term's Hessian (DESIGN.md §4).
#[derive(Clone, Debug)]
pub enum OffHessian {
    /// Equal to the tension-on Hessian: all of the term's stiffness is lossy.
    Same,
    /// Zero: all of the term's stiffness is lossless.
    Zero,
    /// A different matrix (row-major, over the term's coordinates).
    Matrix(Vec<f64>),
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
    pub mass: DMatrix<f64>,
}

impl Assembled {
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

/// Checks that every plug-in element instance names a registered kind.
fn check_plugin_kinds(system: &System) -> Result<(), EnergyError> {
    let kinds = registry();
    for e in &system.plugin_elements {
        if !kinds.iter().any(|k| k.kind() == e.kind) {
            return Err(EnergyError::UnknownKind {
                element: e.name.clone(),
                kind: e.kind.clone(),
                known: kinds
                    .iter()
                    .map(|k| k.kind())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    }
    Ok(())
}

/// Terms of every registered kind whose stage passes `include`, built around `x`.
fn kind_terms(
    system: &System,
    x: &[f64],
    include: impl Fn(Stage) -> bool,
) -> Result<Vec<Term>, EnergyError> {
    let reference = Reference { system, coords: x };
    let mut terms = Vec::new();
    for kind in registry().into_iter().filter(|k| include(k.stage())) {
        terms.extend(kind.terms(&reference)?);
    }
    Ok(terms)
}

/// Terms minimised for the equilibrium: stage-0A kinds, the user's pre-equilibrium terms and,
/// when asked for, the plug-in terms built around `x`.
fn equilibrium_terms(system: &System, x: &[f64]) -> Result<Vec<Term>, EnergyError> {
    let early = system.early_wire_terms != EarlyWireTerms::No;
    let mut terms = kind_terms(system, x, |s| s == Stage::S0A || early)?;
    terms.extend(extra_terms(system, ExtraPhase::BeforeEquilibrium, None)?);
    Ok(terms)
}

/// Finds the equilibrium of `system`. Plug-in terms that join early are built around the
/// start position (their auto clamp angles and tensions), as in the source (§9.2.6): the
/// start is meant to be the drawing's nominal geometry, which is where clamps are aligned.
pub fn solve_equilibrium(
    system: &System,
    options: &EquilibriumOptions,
) -> Result<Equilibrium, AssemblyError> {
    check_plugin_kinds(system)?;
    let start = system.start();
    find_equilibrium(system, &equilibrium_terms(system, &start)?, &start, options)
}

/// Finds the equilibrium and differentiates every term of `stage` there.
pub fn assemble(
    system: &System,
    stage: Stage,
    options: &EquilibriumOptions,
) -> Result<Assembled, AssemblyError> {
    let equilibrium = solve_equilibrium(system, options)?;
    assemble_at(system, stage, equilibrium)
}

/// Differentiates every term of `stage` at a known equilibrium (reused across stages).
pub fn assemble_at(
    system: &System,
    stage: Stage,
    equilibrium: Equilibrium,
) -> Result<Assembled, AssemblyError> {
    let x = &equilibrium.coords;
    let mut terms = kind_terms(system, x, |s| s == Stage::S0A)?;
    // plug-in terms: those of the stage, built around the equilibrium; or, when they joined
    // the equilibrium for good, all of them, built around the start as they were there
    let plugins = if system.early_wire_terms == EarlyWireTerms::Yes {
        kind_terms(system, &system.start(), |s| s != Stage::S0A)?
    } else {
        kind_terms(system, x, |s| s != Stage::S0A && s <= stage)?
    };
    terms.extend(plugins);
    terms.extend(extra_terms(system, ExtraPhase::BeforeEquilibrium, None)?);
    terms.extend(extra_terms(system, ExtraPhase::AfterEquilibrium, Some(x))?);
    terms.extend(constraint_terms(system, x));
    let matrices = terms
        .iter()
        .map(|t| {
            let off = match t.tension_off(x) {
                TensionOff::Unchanged => OffHessian::Same,
                TensionOff::Vanishes => OffHessian::Zero,
                TensionOff::Replaced(t_off) => OffHessian::Matrix(t_off.derivatives(x).hessian),
            };
            TermMatrices {
                label: t.label.clone(),
                kind: t.kind,
                tag: t.tag.clone(),
                coords: t.coords.clone(),
                on: t.derivatives(x).hessian,
                off,
            }
        })
        .collect();
    let layout = Layout::new(system);
    let mass = mass_matrix(system, &layout, x)?;
    Ok(Assembled {
        stage,
        layout,
        equilibrium,
        terms: matrices,
        mass,
    })
}

/// M = Σ_b J_bᵀ diag(m, m, m, I_b) J_b over the variables, with J_b the Jacobian of the
/// body's centre-of-mass velocity and body-axis angular velocity (DESIGN.md §4).
pub fn mass_matrix(
    system: &System,
    layout: &Layout,
    x: &[f64],
) -> Result<DMatrix<f64>, AssemblyError> {
    let nx = layout.variables.len();
    let mut m = DMatrix::zeros(nx, nx);
    for body in &system.bodies {
        if body.mass == 0.0 && body.inertia.iter().all(|&v| v == 0.0) {
            continue;
        }
        let jac = body.frame.jacobian(x, &body.centre_of_mass);
        for g in body.frame.vars() {
            if system.coords[g].kind == CoordKind::Float {
                let moves =
                    jac.position.column(g).norm() > 0.0 || jac.omega_body.column(g).norm() > 0.0;
                if moves {
                    return Err(AssemblyError::MassiveFloat {
                        float: system.coords[g].name.clone(),
                        body: body.name.clone(),
                    });
                }
            }
        }
        let vars: Vec<usize> = body
            .frame
            .vars()
            .into_iter()
            .filter(|&g| system.coords[g].kind == CoordKind::Variable)
            .collect();
        for &gi in &vars {
            let (pi, wi) = (jac.position.column(gi), jac.omega_body.column(gi));
            for &gj in &vars {
                let (pj, wj) = (jac.position.column(gj), jac.omega_body.column(gj));
                let value = body.mass * pi.dot(&pj) + wi.dot(&(body.inertia * wj));
                m[(layout.position[gi], layout.position[gj])] += value;
            }
        }
    }
    Ok(m)
}
