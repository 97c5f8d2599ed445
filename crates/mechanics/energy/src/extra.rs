//! User-written potential terms (before or after the equilibrium) and the per-coordinate
//! debugging constraint springs of the source (`preeqtermlist`, `posteqtermlist`, `kcon`).

use pendkit_expr::{Compiled, Slot};
use pendkit_rotations::Real;

use crate::{CONSTRAINT_TAG, EnergyError, ExtraPhase, Potential, System, Term};

/// Energy given by a compiled expression of the term's local coordinates.
#[derive(Clone, Debug)]
struct ExpressionEnergy {
    energy: Compiled,
}

impl Potential for ExpressionEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        // compiled over the term's own coordinates, which `x` holds
        self.energy.eval(x).unwrap_or(D::from(f64::NAN))
    }
}

/// Terms for the user's extra potential terms of `phase`. After the equilibrium, the symbol
/// `<coordinate>.eq` stands for that coordinate's equilibrium value `x_eq`, a full
/// coordinate vector ([`EnergyError::Length`] if shorter than the system's coordinates).
pub fn extra_terms(
    system: &System,
    phase: ExtraPhase,
    x_eq: Option<&[f64]>,
) -> Result<Vec<Term>, EnergyError> {
    if let Some(x) = x_eq {
        check_full("extra_terms", system, x)?;
    }
    system
        .extra_terms
        .iter()
        .filter(|t| t.phase == phase)
        .map(|t| {
            let mut coords: Vec<usize> = t
                .energy
                .symbols()
                .iter()
                .filter_map(|s| system.coord(s))
                .collect();
            coords.sort_unstable();
            let slot = |name: &str| -> Option<Slot> {
                if let Some(i) = system.coord(name) {
                    return coords.binary_search(&i).ok().map(Slot::Var);
                }
                let base = name.strip_suffix(".eq")?;
                let i = system.coord(base)?;
                x_eq.map(|x| Slot::Const(x[i]))
            };
            let energy = t
                .energy
                .compile(&slot)
                .map_err(|e| EnergyError::ExtraTerm {
                    term: t.name.clone(),
                    message: e.to_string(),
                })?;
            Ok(Term::new(
                format!("extra {}", t.name),
                "extra",
                t.tag.clone(),
                coords,
                ExpressionEnergy { energy },
            ))
        })
        .collect()
}

/// Energy ½ k (x - x_eq)² tying one coordinate to its equilibrium value.
#[derive(Clone, Debug)]
struct ConstraintEnergy {
    stiffness: f64,
    at: f64,
}

impl Potential for ConstraintEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        let d = x[0] - self.at;
        d * d * (0.5 * self.stiffness)
    }
}

/// The debugging constraint springs with non-zero stiffness, about the equilibrium `x_eq`
/// (a full coordinate vector): [`EnergyError::Length`] if it is shorter than the system's
/// coordinates, [`EnergyError::Index`] for a constraint on a coordinate the system does not
/// have.
pub fn constraint_terms(system: &System, x_eq: &[f64]) -> Result<Vec<Term>, EnergyError> {
    check_full("constraint_terms", system, x_eq)?;
    system
        .constraint_stiffness
        .iter()
        .filter(|(_, k)| **k != 0.0)
        .map(|(&i, &k)| {
            let coordinate = system.coords.get(i).ok_or_else(|| EnergyError::Index {
                item: "constraint".into(),
                what: "coordinate",
                index: i,
                len: system.coords.len(),
            })?;
            Ok(Term::new(
                format!("constraint {}", coordinate.name),
                "constraint",
                CONSTRAINT_TAG,
                vec![i],
                ConstraintEnergy {
                    stiffness: k,
                    at: x_eq[i],
                },
            ))
        })
        .collect()
}

/// `x` holds a value for every coordinate of `system` (`function` names the caller).
fn check_full(function: &'static str, system: &System, x: &[f64]) -> Result<(), EnergyError> {
    if x.len() < system.coords.len() {
        return Err(EnergyError::Length {
            function,
            argument: "x_eq",
            expected: system.coords.len(),
            given: x.len(),
        });
    }
    Ok(())
}
