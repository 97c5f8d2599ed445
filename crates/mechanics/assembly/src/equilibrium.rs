//! Equilibrium by minimising the potential over the free variables and floats: Newton's
//! method with exact gradient and Hessian, a diagonal shift that makes indefinite Hessians
//! usable as a descent direction, and a backtracking line search on the energy.
//!
//! Each iterate is first checked on its forces alone (no Hessian): a model that starts at
//! its equilibrium costs one gradient evaluation. The Hessian is evaluated only when a
//! step is needed, at the same point and from the same frame jets, with the tension-off
//! Hessians alongside, so that when that point is the equilibrium the assembly takes it
//! over instead of evaluating again.

use nalgebra::{DMatrix, DVector};
use pendkit_energy::Term;
use pendkit_system::{CoordKind, System};

use crate::AssemblyError;
use crate::evaluate::{DerivativePath, Evaluator};
use crate::sparse::{DENSE_EQUILIBRIUM_LIMIT, SparseHessian};

/// Controls of the equilibrium search.
#[derive(Clone, Debug)]
pub struct EquilibriumOptions {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when every residual force (N) or torque (N m) is below this fraction of
    /// the largest force any single term exerts (the weight, a wire tension).
    pub force_tolerance: f64,
    /// ... and the last Newton step moved no coordinate by more than this (m or rad).
    pub step_tolerance: f64,
    /// Residual forces (N) or torques (N m) below this count as zero whatever the scale
    /// (a model without loads, g = 0, is in equilibrium where it starts).
    pub force_floor: f64,
    /// Residual forces below this many machine epsilons of the forces that make them up
    /// are rounding and count as zero: per coordinate, the sum over terms of each term's
    /// force and of the larger forces it is a difference of (a stiff wire's force is k
    /// times a small difference of lengths of size l, so its rounding is about k l ε; on
    /// the reference path, ε Σ_b |H_ab| |x_b|). So stiffness ratios of 1e8 between wires
    /// converge instead of hunting below rounding.
    pub rounding_factor: f64,
    /// A coordinate moving further than this from its start (m or rad) means the
    /// potential has no minimum nearby (a model without support, a wrong sign).
    pub max_excursion: f64,
    /// Largest number of free coordinates whose Newton step uses a dense Hessian and a
    /// dense Cholesky factorisation; larger searches sum the Hessian on the terms' sparsity
    /// pattern and factorise it sparse (memory and time near-linear in the number of bodies
    /// for chains and trees). Default [`DENSE_EQUILIBRIUM_LIMIT`].
    pub dense_limit: usize,
}

impl Default for EquilibriumOptions {
    fn default() -> Self {
        EquilibriumOptions {
            max_iterations: 200,
            force_tolerance: 1e-11,
            step_tolerance: 1e-12,
            force_floor: 1e-9,
            rounding_factor: 4.0,
            max_excursion: 100.0,
            dense_limit: DENSE_EQUILIBRIUM_LIMIT,
        }
    }
}

/// A converged equilibrium.
#[derive(Clone, Debug)]
pub struct Equilibrium {
    /// Full coordinate vector at equilibrium (m, rad); parameters at nominal.
    pub coords: Vec<f64>,
    /// Newton iterations used.
    pub iterations: usize,
    /// Largest residual generalised force (N or N m) on a free coordinate.
    pub max_residual: f64,
    /// Potential energy at equilibrium (J).
    pub energy: f64,
}

/// The Hessian of the sum of the terms over the free coordinates: a dense matrix up to
/// [`EquilibriumOptions::dense_limit`] coordinates, the terms' sparsity pattern above.
enum Hessian {
    Dense(DMatrix<f64>),
    Sparse(SparseHessian),
}

/// Energy, gradient and Hessian of the sum of the terms over the free coordinates, plus
/// the largest single-term force (a scale for the convergence test) and, per free
/// coordinate, the rounding floor of its residual force.
struct Evaluation {
    energy: f64,
    gradient: DVector<f64>,
    hessian: Hessian,
    force_scale: f64,
    rounding: DVector<f64>,
}

impl Evaluation {
    /// Nothing summed yet, over the `n` free coordinates of the evaluator's terms (`slot`
    /// maps a global coordinate to its free index). The Hessian's storage is made here,
    /// once per search: dense for small models, on the terms' pattern for large ones.
    fn zeros(ev: &Evaluator, slot: &[Option<usize>], n: usize, dense_limit: usize) -> Self {
        let hessian = if n <= dense_limit {
            Hessian::Dense(DMatrix::zeros(n, n))
        } else {
            Hessian::Sparse(SparseHessian::new(ev, slot, n))
        };
        Evaluation {
            energy: 0.0,
            gradient: DVector::zeros(n),
            hessian,
            force_scale: 0.0,
            rounding: DVector::zeros(n),
        }
    }
}

/// The position of each of `n` global coordinates among `free` (None for the coordinates
/// Newton does not move).
pub(crate) fn free_slots(n: usize, free: &[usize]) -> Vec<Option<usize>> {
    let mut slot = vec![None; n];
    for (k, &i) in free.iter().enumerate() {
        slot[i] = Some(k);
    }
    slot
}

/// Sums the evaluator's per-term values and gradients at its current point over the free
/// coordinates (`slot` maps a global index to its free index).
fn gradient_sums(ev: &Evaluator, slot: &[Option<usize>], out: &mut Evaluation) {
    out.energy = 0.0;
    out.gradient.fill(0.0);
    out.rounding.fill(0.0);
    out.force_scale = 0.0;
    for (t, term) in ev.terms().iter().enumerate() {
        out.energy += ev.value(t);
        let (g, scale) = (ev.gradient(t), ev.force_scale(t));
        for (a, &ga) in term.coords.iter().enumerate() {
            let Some(i) = slot[ga] else { continue };
            out.gradient[i] += g[a];
            out.rounding[i] += g[a].abs() + scale[a];
            out.force_scale = out.force_scale.max(g[a].abs());
        }
    }
}

/// Sums the per-term tension-on Hessians over the free coordinates into a dense matrix.
pub(crate) fn hessian_sum(ev: &Evaluator, slot: &[Option<usize>], out: &mut DMatrix<f64>) {
    out.fill(0.0);
    for (t, term) in ev.terms().iter().enumerate() {
        let (h, m) = (ev.on(t), term.coords.len());
        for (a, &ga) in term.coords.iter().enumerate() {
            let Some(i) = slot[ga] else { continue };
            for (b, &gb) in term.coords.iter().enumerate() {
                if let Some(j) = slot[gb] {
                    out[(i, j)] += h[a * m + b];
                }
            }
        }
    }
}

/// Sums the per-term tension-on Hessians into the evaluation's storage, dense or sparse.
fn hessian_sums(ev: &Evaluator, slot: &[Option<usize>], out: &mut Evaluation) {
    match &mut out.hessian {
        Hessian::Dense(h) => hessian_sum(ev, slot, h),
        Hessian::Sparse(h) => h.sum(ev, slot),
    }
}

fn total_energy(terms: &[Term], x: &[f64]) -> f64 {
    // every term reads coordinates of `x` (checked at the entry); NaN would end the search
    terms.iter().map(|t| t.energy(x).unwrap_or(f64::NAN)).sum()
}

/// Solves (H + μ D) dx = -g with the smallest μ (from 0 up) for which the shifted matrix is
/// positive definite; D is the Hessian's diagonal magnitude, so the shift respects the
/// different units of lengths and angles.
fn descent_step(ev: &Evaluation) -> Option<(DVector<f64>, bool)> {
    let n = ev.gradient.len();
    let scale: DVector<f64> = DVector::from_fn(n, |i, _| {
        let h = match &ev.hessian {
            Hessian::Dense(h) => h[(i, i)],
            Hessian::Sparse(h) => h.diagonal(i),
        }
        .abs();
        if h > 0.0 { h } else { 1.0 }
    });
    let mut mu = 0.0;
    for _ in 0..40 {
        let dx = match &ev.hessian {
            Hessian::Dense(hessian) => {
                let mut h = hessian.clone();
                for i in 0..n {
                    h[(i, i)] += mu * scale[i];
                }
                h.cholesky().map(|chol| chol.solve(&(-&ev.gradient)))
            }
            Hessian::Sparse(h) => {
                let shift: Vec<f64> = scale.iter().map(|s| mu * s).collect();
                h.solve_shifted(&shift, &(-&ev.gradient))
            }
        };
        if let Some(dx) = dx
            && dx.iter().all(|v| v.is_finite())
        {
            return Some((dx, mu == 0.0));
        }
        mu = if mu == 0.0 { 1e-8 } else { mu * 10.0 };
    }
    None
}

/// Minimises the total potential of `terms` over the variables and floats of `system` that
/// are not pinned, starting from `start` (a full coordinate vector).
pub fn find_equilibrium(
    system: &System,
    terms: &[Term],
    start: &[f64],
    options: &EquilibriumOptions,
) -> Result<Equilibrium, AssemblyError> {
    system.check_indices()?;
    let n = system.coords.len();
    if start.len() != n {
        return Err(AssemblyError::Length {
            function: "find_equilibrium",
            argument: "start",
            expected: n,
            given: start.len(),
        });
    }
    if let Some(t) = terms.iter().find(|t| t.needs() > n) {
        return Err(AssemblyError::Energy(pendkit_energy::EnergyError::Index {
            item: format!("term '{}'", t.label),
            what: "coordinate",
            index: t.needs() - 1,
            len: n,
        }));
    }
    let mut evaluator = Evaluator::new(system, DerivativePath::Fast);
    evaluator.extend(terms.iter().cloned());
    newton(&mut evaluator, system, start, options)
}

/// Newton's method over the terms of `evaluator`, which is left holding its evaluation at
/// the equilibrium.
pub(crate) fn newton(
    evaluator: &mut Evaluator,
    system: &System,
    start: &[f64],
    options: &EquilibriumOptions,
) -> Result<Equilibrium, AssemblyError> {
    let free = free_coordinates(system);
    let slot = free_slots(system.coords.len(), &free);
    let n = free.len();
    let mut x = start.to_vec();
    let name = |k: usize| system.coords[free[k]].name.clone();
    let mut ev = Evaluation::zeros(evaluator, &slot, n, options.dense_limit);
    let mut trial = x.clone();

    let mut iteration = 0;
    let mut stall = Stall::default();
    loop {
        evaluator.evaluate(&x, false);
        gradient_sums(evaluator, &slot, &mut ev);
        if !ev.energy.is_finite() || ev.gradient.iter().any(|g| !g.is_finite()) {
            return Err(AssemblyError::NotFinite {
                iteration,
                coords: free
                    .iter()
                    .map(|&i| (system.coords[i].name.clone(), x[i]))
                    .collect(),
            });
        }
        let (worst, max_residual) =
            ev.gradient
                .iter()
                .enumerate()
                .fold((0, 0.0f64), |acc, (k, g)| {
                    if g.abs() > acc.1 { (k, g.abs()) } else { acc }
                });
        let not_converged = || AssemblyError::NotConverged {
            iterations: iteration,
            residual: max_residual,
            coordinate: name(worst),
        };
        let equilibrium = |x: Vec<f64>, energy: f64| Equilibrium {
            coords: x,
            iterations: iteration,
            max_residual,
            energy,
        };
        // Converged on forces alone: every residual is below the absolute floor or within
        // the rounding of the forces that make it up.
        let rounding = options.rounding_factor * f64::EPSILON;
        let at_rounding = ev
            .gradient
            .iter()
            .zip(ev.rounding.iter())
            .all(|(g, r)| g.abs() <= options.force_floor.max(rounding * r));
        if n == 0 || at_rounding {
            return Ok(equilibrium(x, ev.energy));
        }
        // a search that no longer moves ends now, not after the iteration limit: each
        // iteration costs the whole model's Hessian
        if stall.stalled(ev.energy, max_residual, energy_rounding(&ev)) {
            return Err(AssemblyError::Stalled {
                iterations: iteration,
                window: STALL_WINDOW,
                residual: max_residual,
                coordinate: name(worst),
            });
        }
        evaluator.evaluate(&x, true);
        hessian_sums(evaluator, &slot, &mut ev);
        let forces_ok = max_residual <= options.force_tolerance * ev.force_scale;
        let (dx, newton) = descent_step(&ev).ok_or_else(not_converged)?;
        // Converged on forces and on the size of the step that would still be taken.
        if forces_ok && dx.amax() <= options.step_tolerance {
            return Ok(equilibrium(x, ev.energy));
        }
        if iteration == options.max_iterations {
            return Err(not_converged());
        }
        // Backtracking on the energy. Near convergence the predicted decrease is below the
        // rounding of the energy itself; a pure Newton step is then taken as it is.
        let slope = ev.gradient.dot(&dx);
        let mut alpha = 1.0;
        let rounding = energy_rounding(&ev);
        if !(newton && -slope < rounding) {
            loop {
                trial.copy_from_slice(&x);
                for (k, &i) in free.iter().enumerate() {
                    trial[i] += alpha * dx[k];
                }
                let e = total_energy(evaluator.terms(), &trial);
                if e.is_finite() && e <= ev.energy + 1e-4 * alpha * slope {
                    break;
                }
                alpha *= 0.5;
                if alpha < 1e-12 {
                    return Err(not_converged());
                }
            }
        }
        for (k, &i) in free.iter().enumerate() {
            x[i] += alpha * dx[k];
            if (x[i] - start[i]).abs() > options.max_excursion {
                return Err(AssemblyError::Runaway {
                    coordinate: system.coords[i].name.clone(),
                    value: x[i],
                });
            }
        }
        iteration += 1;
    }
}

/// The rounding of the total energy (J) at an evaluation: a change below it is no change.
fn energy_rounding(ev: &Evaluation) -> f64 {
    1e-13 * ev.energy.abs().max(ev.force_scale * 1e-3)
}

/// Iterations without progress after which the search stops ([`Stall`]).
const STALL_WINDOW: usize = 10;

/// The energies and largest residuals of the last [`STALL_WINDOW`] + 1 iterations: the
/// search has stalled when, over the window, the energy fell by no more than its rounding
/// and the largest residual not by half. A converging search does one or the other every
/// few iterations (the energy falls while far off, the residual falls quadratically near
/// the minimum); one that has stopped moving (a body hung from one point far off its
/// centre of mass, whose minimum double precision does not resolve to the tolerance) would
/// otherwise run to the iteration limit, each iteration costing the whole model's Hessian.
#[derive(Default)]
struct Stall {
    history: std::collections::VecDeque<(f64, f64)>,
}

impl Stall {
    /// Records an iteration's `energy` (J) and largest residual (N or N m), `rounding` the
    /// energy's rounding now; true when the window shows no progress.
    fn stalled(&mut self, energy: f64, residual: f64, rounding: f64) -> bool {
        self.history.push_back((energy, residual));
        if self.history.len() <= STALL_WINDOW {
            return false;
        }
        let Some((energy_before, residual_before)) = self.history.pop_front() else {
            return false;
        };
        energy_before - energy <= rounding && residual > 0.5 * residual_before
    }
}

/// The coordinates Newton moves: neither parameters (fixed by the caller) nor pinned.
pub(crate) fn free_coordinates<S: pendkit_rotations::Real>(system: &System<S>) -> Vec<usize> {
    (0..system.coords.len())
        .filter(|&i| {
            let c = &system.coords[i];
            c.kind != CoordKind::Parameter && !c.pinned
        })
        .collect()
}
