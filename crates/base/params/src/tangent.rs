//! Every parameter's value and its exact derivatives with respect to one or a few of them,
//! as dual numbers: what a model built with dual numbers reads
//! (docs/exact-sensitivities.md, step 2).

use std::sync::Arc;

use num_dual::{Derivative, Dual64, DualNum, DualSVec64};

use crate::names::NameMap;
use crate::{ParamError, ParamSet, unknown};

/// How many parameters one vector-dual build carries ([`ChunkDual`]): a build over a chunk
/// costs about two `f64` builds (the quad: 0.33 ms against 0.17; the interpreter's work is
/// shared, its arithmetic grows with the chunk: 0.19 ms at 8, 0.6 ms at 32), so the
/// sensitivities build once per chunk instead of once per parameter.
pub const TANGENT_CHUNK: usize = 16;

/// A number with its derivatives with respect to up to [`TANGENT_CHUNK`] parameters at once
/// (direction k: the k-th seed of a [`Tangent`] from [`ParamSet::resolve_tangents`]).
pub type ChunkDual = DualSVec64<TANGENT_CHUNK>;

/// The values of a parameter set seeded in the direction of one parameter, the *seed*
/// (`S = Dual64`), or of several at once (`S = ChunkDual`, one direction each): each
/// value's dual part is its derivative with respect to the seeds (in its unit per unit of
/// the seed). A seed is moved as an override would move it: its own definition is replaced
/// by its value plus ε, and the parameters defined in terms of it follow.
#[derive(Debug, Clone)]
pub struct Tangent<S = Dual64> {
    seeds: Vec<Arc<str>>,
    values: Vec<(Arc<str>, S)>,
    index: Arc<NameMap<Arc<str>, usize>>,
}

impl<S: DualNum<Primitive = f64> + Copy> Tangent<S> {
    /// The parameters the derivatives are taken with respect to, in direction order.
    pub fn seeds(&self) -> &[Arc<str>] {
        &self.seeds
    }

    /// The value of `name` and its derivatives with respect to the seeds.
    pub fn get(&self, name: &str) -> Result<S, ParamError> {
        self.index
            .get(name)
            .map(|&i| self.values[i].1)
            .ok_or_else(|| unknown(name, self.values.iter().map(|(n, _)| &**n)))
    }

    /// Every parameter, in definition order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, S)> {
        self.values.iter().map(|(n, v)| (&**n, *v))
    }
}

impl Tangent<Dual64> {
    /// The parameter the derivatives are taken with respect to.
    pub fn seed(&self) -> &str {
        &self.seeds[0]
    }
}

impl ParamSet {
    /// The values with their derivatives with respect to `seed` (see [`Tangent`]). The set
    /// is resolved to numbers first, with every check of [`ParamSet::resolve`]; the real
    /// parts are those values.
    pub fn resolve_tangent(&self, seed: &str) -> Result<Tangent, ParamError> {
        self.resolve_seeded(&[seed], |_| Dual64::new(0.0, 1.0))
    }

    /// The values with their derivatives with respect to each of `seeds` at once (direction
    /// k of every value: its derivative with respect to `seeds[k]`); at most
    /// [`TANGENT_CHUNK`] seeds, each named once.
    pub fn resolve_tangents(&self, seeds: &[&str]) -> Result<Tangent<ChunkDual>, ParamError> {
        if seeds.len() > TANGENT_CHUNK {
            return Err(ParamError::Seeds {
                why: format!("{} seeded at once, at most {TANGENT_CHUNK}", seeds.len()),
            });
        }
        self.resolve_seeded(seeds, |k| ChunkDual::from_re(0.0).derivative(k))
    }

    /// [`ParamSet::resolve_tangent`] and [`ParamSet::resolve_tangents`]: `unit(k)` is the
    /// k-th seed's direction (real part 0, derivative 1 in direction k only).
    ///
    /// Each seed follows its definition in the other seeds' directions (moving another seed
    /// moves it as it moves any parameter defined in terms of it) and only in its own is it
    /// replaced by its value plus ε, as an override would replace it. Its definition has no
    /// derivative in its own direction (that would be a cycle), so the value is the
    /// definition's plus the unit.
    fn resolve_seeded<S: DualNum<Primitive = f64> + Copy>(
        &self,
        seeds: &[&str],
        unit: impl Fn(usize) -> S,
    ) -> Result<Tangent<S>, ParamError> {
        self.resolve()?;
        let mut direction: Vec<Option<S>> = vec![None; self.entries.len()];
        let mut names = Vec::with_capacity(seeds.len());
        for (k, &seed) in seeds.iter().enumerate() {
            let i = self.position(seed)?;
            if direction[i].is_some() {
                return Err(ParamError::Seeds {
                    why: format!("'{seed}' is seeded twice"),
                });
            }
            direction[i] = Some(unit(k));
            names.push(self.entries[i].name.clone());
        }
        let mut values: Vec<Option<S>> = vec![None; self.entries.len()];
        for i in 0..self.entries.len() {
            self.tangent_of(i, &direction, &mut values)?;
        }
        let values = self
            .entries
            .iter()
            .zip(values)
            .map(|(e, v)| (e.name.clone(), v.unwrap_or_else(|| S::from(0.0))))
            .collect();
        Ok(Tangent {
            seeds: names,
            values,
            index: self.index.clone(),
        })
    }

    /// Evaluates entry `i` over dual numbers after the entries it reads (the resolution
    /// has found no cycle and no unknown symbol, so the recursion ends), plus its own seed
    /// direction if it is a seed.
    fn tangent_of<S: DualNum<Primitive = f64> + Copy>(
        &self,
        i: usize,
        direction: &[Option<S>],
        values: &mut [Option<S>],
    ) -> Result<S, ParamError> {
        if let Some(v) = values[i] {
            return Ok(v);
        }
        let entry = &self.entries[i];
        for symbol in &entry.symbols {
            if let Some(&j) = self.index.get(symbol.as_str()) {
                self.tangent_of(j, direction, values)?;
            }
        }
        let lookup = |s: &str| self.index.get(s).and_then(|&j| values[j]);
        let mut value =
            entry
                .definition
                .expr
                .eval(&lookup)
                .map_err(|source| ParamError::Syntax {
                    name: entry.name.to_string(),
                    source,
                })?;
        if let Some(unit) = direction[i] {
            value += unit;
        }
        values[i] = Some(value);
        Ok(value)
    }
}

/// Parameter values of one scalar type, as a model's build reads them: the resolved
/// numbers (`f64`) or a [`Tangent`] (`Dual64`, or [`ChunkDual`] for several seeds).
pub trait Values<S> {
    /// The value of `name`, if it is a numeric parameter.
    fn value(&self, name: &str) -> Option<S>;
}

impl Values<f64> for crate::Resolved {
    fn value(&self, name: &str) -> Option<f64> {
        self.get(name).ok()
    }
}

impl<S: DualNum<Primitive = f64> + Copy> Values<S> for Tangent<S> {
    fn value(&self, name: &str) -> Option<S> {
        self.get(name).ok()
    }
}

/// One of the [`TANGENT_CHUNK`] directions of a [`ChunkDual`]: an index checked once, when
/// it is made, so that reading every number of a model along it needs no check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Direction(usize);

impl Direction {
    /// Direction `k` (the k-th seed), or [`ParamError::Seeds`] if `k` is not below
    /// [`TANGENT_CHUNK`].
    pub fn new(k: usize) -> Result<Direction, ParamError> {
        if k < TANGENT_CHUNK {
            Ok(Direction(k))
        } else {
            Err(ParamError::Seeds {
                why: format!(
                    "direction {k} is out of range: a chunk has {TANGENT_CHUNK} (0 to {})",
                    TANGENT_CHUNK - 1
                ),
            })
        }
    }

    /// Its index, below [`TANGENT_CHUNK`].
    pub fn index(self) -> usize {
        self.0
    }
}

/// Direction `k` of a chunk's number as a one-direction dual number (its derivative with
/// respect to the k-th seed).
pub fn chunk_direction(x: &ChunkDual, k: Direction) -> Dual64 {
    let Derivative(eps) = &x.eps;
    // a `Direction` is below TANGENT_CHUNK, the length of every chunk's vector
    Dual64::new(x.re, eps.as_ref().map_or(0.0, |v| v[k.0]))
}
