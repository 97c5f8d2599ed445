//! Every parameter's value and its exact derivative with respect to one of them, as dual
//! numbers: what a model built with dual numbers reads (docs/exact-sensitivities.md, step 2).

use std::collections::HashMap;
use std::sync::Arc;

use num_dual::Dual64;

use crate::{ParamError, ParamSet, unknown};

/// The values of a parameter set seeded in the direction of one parameter, the *seed*:
/// each value's dual part is its derivative with respect to the seed (in its unit per unit
/// of the seed). The seed is moved as an override would move it: its own definition is
/// replaced by its value plus ε, and the parameters defined in terms of it follow.
#[derive(Debug, Clone)]
pub struct Tangent {
    seed: Arc<str>,
    values: Vec<(Arc<str>, Dual64)>,
    index: Arc<HashMap<Arc<str>, usize>>,
}

impl Tangent {
    /// The parameter the derivatives are taken with respect to.
    pub fn seed(&self) -> &str {
        &self.seed
    }

    /// The value of `name` and its derivative with respect to the seed.
    pub fn get(&self, name: &str) -> Result<Dual64, ParamError> {
        self.index
            .get(name)
            .map(|&i| self.values[i].1)
            .ok_or_else(|| unknown(name, self.values.iter().map(|(n, _)| &**n)))
    }

    /// Every parameter, in definition order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, Dual64)> {
        self.values.iter().map(|(n, v)| (&**n, *v))
    }
}

impl ParamSet {
    /// The values with their derivatives with respect to `seed` (see [`Tangent`]). The set
    /// is resolved to numbers first, with every check of [`ParamSet::resolve`]; the real
    /// parts are those values.
    pub fn resolve_tangent(&self, seed: &str) -> Result<Tangent, ParamError> {
        let resolved = self.resolve()?;
        let seed_index = self.position(seed)?;
        let mut values: Vec<Option<Dual64>> = vec![None; self.entries.len()];
        values[seed_index] = Some(Dual64::new(resolved.get(seed)?, 1.0));
        for i in 0..self.entries.len() {
            self.tangent_of(i, &mut values)?;
        }
        let values = self
            .entries
            .iter()
            .zip(values)
            .map(|(e, v)| (e.name.clone(), v.unwrap_or(Dual64::from(0.0))))
            .collect();
        Ok(Tangent {
            seed: self.entries[seed_index].name.clone(),
            values,
            index: self.index.clone(),
        })
    }

    /// Evaluates entry `i` over dual numbers after the entries it reads (the resolution
    /// has found no cycle and no unknown symbol, so the recursion ends).
    fn tangent_of(&self, i: usize, values: &mut [Option<Dual64>]) -> Result<Dual64, ParamError> {
        if let Some(v) = values[i] {
            return Ok(v);
        }
        let entry = &self.entries[i];
        for symbol in &entry.symbols {
            if let Some(&j) = self.index.get(symbol.as_str()) {
                self.tangent_of(j, values)?;
            }
        }
        let lookup = |s: &str| self.index.get(s).and_then(|&j| values[j]);
        let value = entry
            .definition
            .expr
            .eval(&lookup)
            .map_err(|source| ParamError::Syntax {
                name: entry.name.to_string(),
                source,
            })?;
        values[i] = Some(value);
        Ok(value)
    }
}

/// Parameter values of one scalar type, as a model's build reads them: the resolved
/// numbers (`f64`) or a [`Tangent`] (`Dual64`).
pub trait Values<S> {
    /// The value of `name`, if it is a numeric parameter.
    fn value(&self, name: &str) -> Option<S>;
}

impl Values<f64> for crate::Resolved {
    fn value(&self, name: &str) -> Option<f64> {
        self.get(name).ok()
    }
}

impl Values<Dual64> for Tangent {
    fn value(&self, name: &str) -> Option<Dual64> {
        self.get(name).ok()
    }
}
