//! Order-independent resolution of a parameter set (depth-first, with cycle detection).

use std::collections::BTreeSet;
use std::sync::Arc;

use pendkit_expr::{Expr, parse};

use crate::names::NameMap;
use crate::{Entry, ParamError, unknown};

/// A resolved value: a number, or an expression in the free symbols only.
#[derive(Debug, Clone, PartialEq)]
enum Value {
    Number(f64),
    Symbolic(Expr),
}

/// The outcome of [`crate::ParamSet::resolve_with_free`]: numeric values of all parameters
/// that do not depend on free symbols, and expressions for those that do.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    entries: Vec<(Arc<str>, Value)>,
    /// Position of each name in `entries`; shared with the parameter set when no parameter
    /// is left out as free (the usual case), so resolving does not rebuild it.
    index: Arc<NameMap<Arc<str>, usize>>,
    /// Which entries have been looked up (by [`Resolved::get`], [`Resolved::expression`],
    /// [`Resolved::eval`], ...): what a model's build reads, so that an override of a
    /// parameter nothing reads can be refused. Clones share it.
    reads: Arc<ReadLog>,
}

/// One flag per entry of a [`Resolved`], set when it is looked up. Not part of the value:
/// two resolutions are equal whatever has been read from them.
#[derive(Debug, Default)]
struct ReadLog(std::sync::Mutex<Vec<bool>>);

impl PartialEq for ReadLog {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl ReadLog {
    fn mark(&self, i: usize) {
        let mut flags = self
            .0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(flag) = flags.get_mut(i) {
            *flag = true;
        }
    }

    fn flags(&self) -> Vec<bool> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .clone()
    }
}

#[derive(Clone, Copy, PartialEq)]
enum State {
    New,
    Active,
    Done,
}

struct Resolver<'a> {
    defs: &'a [Arc<Entry>],
    index: &'a NameMap<Arc<str>, usize>,
    free: &'a [&'a str],
    state: Vec<State>,
    values: Vec<Option<Value>>,
    /// The parameters being resolved, outermost first.
    stack: Vec<usize>,
}

pub(crate) fn resolve(
    defs: &[Arc<Entry>],
    index: &Arc<NameMap<Arc<str>, usize>>,
    free: &[&str],
) -> Result<Resolved, ParamError> {
    let mut r = Resolver {
        defs,
        index,
        free,
        state: vec![State::New; defs.len()],
        values: vec![None; defs.len()],
        stack: Vec::new(),
    };
    let mut entries = Vec::with_capacity(defs.len());
    for (i, entry) in defs.iter().enumerate() {
        if free.contains(&&*entry.name) {
            continue;
        }
        r.visit(i)?;
        if let Some(value) = r.values[i].clone() {
            entries.push((entry.name.clone(), value));
        }
    }
    let index = if entries.len() == defs.len() {
        index.clone()
    } else {
        Arc::new(
            entries
                .iter()
                .enumerate()
                .map(|(i, (name, _))| (name.clone(), i))
                .collect(),
        )
    };
    let reads = Arc::new(ReadLog(std::sync::Mutex::new(vec![false; entries.len()])));
    Ok(Resolved {
        entries,
        index,
        reads,
    })
}

impl Resolver<'_> {
    fn name(&self, i: usize) -> String {
        self.defs[i].name.to_string()
    }

    fn visit(&mut self, i: usize) -> Result<(), ParamError> {
        match self.state[i] {
            State::Done => return Ok(()),
            State::Active => {
                let start = self.stack.iter().position(|&j| j == i).unwrap_or(0);
                let mut chain: Vec<String> =
                    self.stack[start..].iter().map(|&j| self.name(j)).collect();
                chain.push(self.name(i));
                return Err(ParamError::Cycle { chain });
            }
            State::New => {}
        }
        self.state[i] = State::Active;
        self.stack.push(i);

        let defs = self.defs;
        let Entry {
            name,
            definition: def,
            symbols,
        } = &*defs[i];
        let mut symbolic = false;
        for sym in symbols {
            if self.free.contains(&sym.as_str()) {
                symbolic = true;
                continue;
            }
            let Some(&j) = self.index.get(sym.as_str()) else {
                return Err(ParamError::Undefined {
                    symbol: sym.clone(),
                    used_in: name.to_string(),
                    chain: self.stack.iter().map(|&j| self.name(j)).collect(),
                });
            };
            self.visit(j)?;
            symbolic |= matches!(self.values[j], Some(Value::Symbolic(_)));
        }

        let value_of = |s: &str| self.index.get(s).and_then(|&j| self.values[j].as_ref());
        let value = if symbolic {
            Value::Symbolic(def.expr.substitute(&|s| match value_of(s)? {
                Value::Number(x) => Some(Expr::Num(*x)),
                Value::Symbolic(e) => Some(e.clone()),
            }))
        } else {
            let lookup = |s: &str| match value_of(s)? {
                Value::Number(x) => Some(*x),
                Value::Symbolic(_) => None,
            };
            let x = def
                .expr
                .eval(&lookup)
                .map_err(|source| ParamError::Syntax {
                    name: name.to_string(),
                    source,
                })?;
            if !x.is_finite() {
                return Err(ParamError::NotFinite {
                    name: name.to_string(),
                    definition: def.source.clone(),
                    value: x,
                });
            }
            Value::Number(x)
        };
        self.values[i] = Some(value);
        self.state[i] = State::Done;
        self.stack.pop();
        Ok(())
    }
}

impl Resolved {
    fn lookup(&self, name: &str) -> Result<&Value, ParamError> {
        match self.index.get(name) {
            Some(&i) => {
                self.reads.mark(i);
                Ok(&self.entries[i].1)
            }
            None => Err(unknown(name, self.entries.iter().map(|(n, _)| &**n))),
        }
    }

    /// The numeric value of `name`, if it has one, without recording a read: for checks
    /// that look at every value whether or not anything uses it (a domain check must not
    /// make an override count as read).
    pub fn peek(&self, name: &str) -> Option<f64> {
        match &self.entries[*self.index.get(name)?].1 {
            Value::Number(x) => Some(*x),
            Value::Symbolic(_) => None,
        }
    }

    /// The numeric value of `name`. Fails if it is unknown or depends on free symbols.
    pub fn get(&self, name: &str) -> Result<f64, ParamError> {
        match self.lookup(name)? {
            Value::Number(x) => Ok(*x),
            Value::Symbolic(e) => Err(ParamError::Symbolic {
                name: name.to_string(),
                free: e.symbols().into_iter().collect(),
            }),
        }
    }

    /// The value of `name` as an expression: a number, or for a parameter that depends on
    /// free symbols, its definition with every numeric parameter substituted, so that only
    /// free symbols are left (compile it with [`Expr::compile`] for fast evaluation).
    pub fn expression(&self, name: &str) -> Result<Expr, ParamError> {
        Ok(match self.lookup(name)? {
            Value::Number(x) => Expr::Num(*x),
            Value::Symbolic(e) => e.clone(),
        })
    }

    /// Whether `name` depends on free symbols (and so has no numeric value).
    pub fn is_symbolic(&self, name: &str) -> bool {
        matches!(self.lookup(name), Ok(Value::Symbolic(_)))
    }

    /// The numeric parameters and their values, in definition order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> {
        self.entries.iter().filter_map(|(name, v)| match v {
            Value::Number(x) => Some((&**name, *x)),
            Value::Symbolic(_) => None,
        })
    }

    /// The parameters that depend on free symbols, with their expressions, in definition order.
    pub fn symbolic(&self) -> impl Iterator<Item = (&str, &Expr)> {
        self.entries.iter().filter_map(|(name, v)| match v {
            Value::Symbolic(e) => Some((&**name, e)),
            Value::Number(_) => None,
        })
    }

    /// The number of numeric parameters (those yielded by [`Resolved::iter`]).
    pub fn len(&self) -> usize {
        self.iter().count()
    }

    /// Whether there are no numeric parameters.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The parameters looked up so far ([`Resolved::get`], [`Resolved::expression`],
    /// [`Resolved::eval`] and the like), in definition order: after a model's build, those
    /// it reads directly (add what their definitions refer to for all it depends on).
    pub fn read_names(&self) -> Vec<&str> {
        let flags = self.reads.flags();
        self.entries
            .iter()
            .zip(flags)
            .filter(|(_, read)| *read)
            .map(|((name, _), _)| &**name)
            .collect()
    }

    /// Evaluates an expression of the numeric parameters.
    pub fn eval(&self, expr: &Expr) -> Result<f64, ParamError> {
        let symbols: BTreeSet<String> = expr.symbols();
        for s in &symbols {
            self.get(s)?;
        }
        let lookup = |s: &str| self.get(s).ok();
        Ok(expr.eval(&lookup)?)
    }

    /// Parses and evaluates an expression of the numeric parameters.
    pub fn eval_str(&self, text: &str) -> Result<f64, ParamError> {
        self.eval(&parse(text)?)
    }
}
