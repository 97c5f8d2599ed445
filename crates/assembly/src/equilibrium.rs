//! Equilibrium by minimising the potential over the free variables and floats: Newton's
//! method with exact gradient and Hessian, a diagonal shift that makes indefinite Hessians
//! usable as a descent direction, and a backtracking line search on the energy.

use nalgebra::{DMatrix, DVector};
use pendkit_energy::{CoordKind, System, Term};

use crate::AssemblyError;

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
    /// A coordinate moving further than this from its start (m or rad) means the
    /// potential has no minimum nearby (a model without support, a wrong sign).
    pub max_excursion: f64,
}

impl Default for EquilibriumOptions {
    fn default() -> Self {
        EquilibriumOptions {
            max_iterations: 200,
            force_tolerance: 1e-11,
            step_tolerance: 1e-12,
            force_floor: 1e-9,
            max_excursion: 100.0,
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

/// Energy, gradient and Hessian of the sum of `terms` over the free coordinates `free`,
/// plus the largest single-term force (a scale for the convergence test).
struct Evaluation {
    energy: f64,
    gradient: DVector<f64>,
    hessian: DMatrix<f64>,
    force_scale: f64,
}

fn evaluate(terms: &[Term], x: &[f64], slot: &[Option<usize>], n: usize) -> Evaluation {
    let mut ev = Evaluation {
        energy: 0.0,
        gradient: DVector::zeros(n),
        hessian: DMatrix::zeros(n, n),
        force_scale: 0.0,
    };
    for term in terms {
        let d = term.derivatives(x);
        let m = term.coords.len();
        ev.energy += d.value;
        for (a, &ga) in term.coords.iter().enumerate() {
            let Some(i) = slot[ga] else { continue };
            ev.gradient[i] += d.gradient[a];
            ev.force_scale = ev.force_scale.max(d.gradient[a].abs());
            for (b, &gb) in term.coords.iter().enumerate() {
                if let Some(j) = slot[gb] {
                    ev.hessian[(i, j)] += d.hessian[a * m + b];
                }
            }
        }
    }
    ev
}

fn total_energy(terms: &[Term], x: &[f64]) -> f64 {
    terms.iter().map(|t| t.energy(x)).sum()
}

/// Solves (H + μ D) dx = -g with the smallest μ (from 0 up) for which the shifted matrix is
/// positive definite; D is the Hessian's diagonal magnitude, so the shift respects the
/// different units of lengths and angles.
fn descent_step(ev: &Evaluation) -> Option<(DVector<f64>, bool)> {
    let n = ev.gradient.len();
    let scale: DVector<f64> = DVector::from_fn(n, |i, _| {
        let h = ev.hessian[(i, i)].abs();
        if h > 0.0 { h } else { 1.0 }
    });
    let mut mu = 0.0;
    for _ in 0..40 {
        let mut h = ev.hessian.clone();
        for i in 0..n {
            h[(i, i)] += mu * scale[i];
        }
        if let Some(chol) = h.cholesky() {
            let dx = chol.solve(&(-&ev.gradient));
            if dx.iter().all(|v| v.is_finite()) {
                return Some((dx, mu == 0.0));
            }
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
    let free: Vec<usize> = (0..system.coords.len())
        .filter(|&i| {
            let c = &system.coords[i];
            c.kind != CoordKind::Parameter && !c.pinned
        })
        .collect();
    let mut slot = vec![None; system.coords.len()];
    for (k, &i) in free.iter().enumerate() {
        slot[i] = Some(k);
    }
    let n = free.len();
    let mut x = start.to_vec();
    let name = |k: usize| system.coords[free[k]].name.clone();

    let mut iteration = 0;
    loop {
        let ev = evaluate(terms, &x, &slot, n);
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
        let forces_ok = max_residual <= options.force_tolerance * ev.force_scale;
        if n == 0 || max_residual <= options.force_floor {
            return Ok(Equilibrium {
                coords: x,
                iterations: iteration,
                max_residual,
                energy: ev.energy,
            });
        }
        let (dx, newton) = descent_step(&ev).ok_or_else(not_converged)?;
        // Converged on forces and on the size of the step that would still be taken.
        if forces_ok && dx.amax() <= options.step_tolerance {
            return Ok(Equilibrium {
                coords: x,
                iterations: iteration,
                max_residual,
                energy: ev.energy,
            });
        }
        if iteration == options.max_iterations {
            return Err(not_converged());
        }
        // Backtracking on the energy. Near convergence the predicted decrease is below the
        // rounding of the energy itself; a pure Newton step is then taken as it is.
        let slope = ev.gradient.dot(&dx);
        let mut alpha = 1.0;
        let rounding = 1e-13 * ev.energy.abs().max(ev.force_scale * 1e-3);
        if !(newton && -slope < rounding) {
            loop {
                let mut trial = x.clone();
                for (k, &i) in free.iter().enumerate() {
                    trial[i] += alpha * dx[k];
                }
                let e = total_energy(terms, &trial);
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
