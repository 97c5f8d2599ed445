//! Named parameters bound to numbers or to expressions of other parameters, with case
//! overrides (`scale(x)`, `increment(x)`, new values) and order-independent resolution.
//!
//! ```
//! use pendkit_params::ParamSet;
//! let mut p = ParamSet::new();
//! p.define("k", "m*g/l").unwrap(); // may use names defined later
//! p.define_value("m", 2.0).unwrap();
//! p.define_value("g", 9.81).unwrap();
//! p.define_value("l", 0.5).unwrap();
//! p.apply_text("m", "scale(1.5)").unwrap();
//! let r = p.resolve().unwrap();
//! assert!((r.get("k").unwrap() - 3.0 * 9.81 / 0.5).abs() < 1e-12);
//! ```

mod domain;
mod names;
mod resolve;
mod tangent;

use std::sync::Arc;

use pendkit_expr::{BinOp, Expr, ExprError, is_symbol_name, parse};

use crate::names::NameMap;

pub use domain::Domain;
pub use resolve::Resolved;
pub use tangent::{ChunkDual, Direction, TANGENT_CHUNK, Tangent, Values, chunk_direction};

/// How a parameter is defined.
#[derive(Debug, Clone, PartialEq)]
pub struct Definition {
    /// The parsed definition.
    pub expr: Expr,
    /// The definition as text: what the user wrote, or the printed expression after a
    /// `scale`/`increment` override.
    pub source: String,
}

/// A case override of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Override {
    /// Replace the definition with a new value or expression.
    Expr(Expr),
    /// Multiply the current definition: `(old) * (x)`.
    Scale(Expr),
    /// Add to the current definition: `(old) + (x)`.
    Increment(Expr),
}

impl Override {
    /// Parses `scale(x)`, `increment(x)` or any other expression (a new definition).
    pub fn parse(text: &str) -> Result<Override, ExprError> {
        if let Some(inner) = keyword_argument(text, "scale") {
            Ok(Override::Scale(parse(inner)?))
        } else if let Some(inner) = keyword_argument(text, "increment") {
            Ok(Override::Increment(parse(inner)?))
        } else {
            Ok(Override::Expr(parse(text)?))
        }
    }
}

/// The `x` of `keyword(x)` when the whole (trimmed) text has that form.
fn keyword_argument<'a>(text: &'a str, keyword: &str) -> Option<&'a str> {
    let inner = text
        .trim()
        .strip_prefix(keyword)?
        .trim_start()
        .strip_prefix('(')?
        .strip_suffix(')')?;
    // The opening parenthesis must match the final one (rules out `scale(a) + (b)`).
    let mut depth = 0i32;
    for c in inner.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth == 0 => return None,
            ')' => depth -= 1,
            _ => {}
        }
    }
    Some(inner)
}

/// Errors from defining, overriding and resolving parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A name defined twice.
    #[error("duplicate parameter '{name}'")]
    Duplicate {
        /// The parameter name.
        name: String,
    },
    /// A name that is not an identifier, or is reserved (`pi`, function names).
    #[error("invalid parameter name '{name}'")]
    InvalidName {
        /// The rejected name.
        name: String,
    },
    /// A definition or override that does not parse.
    #[error("parameter '{name}': {source}")]
    Syntax {
        /// The parameter being defined.
        name: String,
        /// The parse error.
        source: ExprError,
    },
    /// An expression error outside any definition (e.g. in [`Resolved::eval_str`]).
    #[error(transparent)]
    Expr(#[from] ExprError),
    /// A name that is not a parameter.
    #[error(
        "unknown parameter '{name}'{}",
        suggestion.as_ref().map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default()
    )]
    Unknown {
        /// The name asked for.
        name: String,
        /// The closest existing name (edit distance at most 2), if any.
        suggestion: Option<String>,
    },
    /// Definitions that depend on each other; the chain starts and ends with the same name.
    #[error("parameter cycle: {}", chain.join(" -> "))]
    Cycle {
        /// E.g. `["a", "b", "a"]`.
        chain: Vec<String>,
    },
    /// A definition using a symbol that is neither a parameter nor free.
    #[error(
        "undefined symbol '{symbol}' in the definition of '{used_in}'{}",
        if chain.len() > 1 { format!(" (needed by {})", chain.join(" -> ")) } else { String::new() }
    )]
    Undefined {
        /// The undefined symbol.
        symbol: String,
        /// The parameter whose definition uses it.
        used_in: String,
        /// How resolution got there, ending with `used_in`.
        chain: Vec<String>,
    },
    /// A parameter evaluating to infinity or NaN.
    #[error("parameter '{name}' = {definition} is not a finite number")]
    NotFinite {
        /// The parameter name.
        name: String,
        /// Its definition text.
        definition: String,
        /// The value obtained.
        value: f64,
    },
    /// A parameter whose value its unit rules out (a frequency not positive), or a
    /// subnormal number (below 2.2e-308 in magnitude: never a physical value,
    /// and its reciprocal overflows).
    #[error("parameter '{name}' = {} {unit}: {why}", pendkit_expr::number_text(*value))]
    OutOfRange {
        /// The parameter name.
        name: String,
        /// The value obtained.
        value: f64,
        /// Its declared unit (empty if none).
        unit: String,
        /// What the value must be.
        why: String,
    },
    /// A numeric value asked of a parameter that depends on free symbols.
    #[error("parameter '{name}' has no numeric value: it depends on {}", free.join(", "))]
    Symbolic {
        /// The parameter name.
        name: String,
        /// The free symbols it depends on.
        free: Vec<String>,
    },
    /// Parameters seeded for derivatives that cannot be: more than [`TANGENT_CHUNK`] at
    /// once, or one of them twice.
    #[error("derivative seeds: {why}")]
    Seeds {
        /// What is wrong with them.
        why: String,
    },
}

/// One parameter of a [`ParamSet`]: its name, definition and the symbols the definition
/// uses (found once, when it is defined or overridden, rather than at every resolution).
#[derive(Debug, Clone)]
pub(crate) struct Entry {
    pub(crate) name: Arc<str>,
    pub(crate) definition: Definition,
    /// The symbols of `definition.expr`, sorted.
    pub(crate) symbols: Vec<String>,
}

impl Entry {
    fn new(name: Arc<str>, definition: Definition) -> Self {
        let symbols = definition.expr.symbols().into_iter().collect();
        Entry {
            name,
            definition,
            symbols,
        }
    }
}

/// An ordered set of parameter definitions.
///
/// Cloning is cheap: clones share their entries and name index until one of them changes an
/// entry (copy on write), so a model can parse its defaults once and hand each build a copy
/// to override.
#[derive(Debug, Clone, Default)]
pub struct ParamSet {
    entries: Vec<Arc<Entry>>,
    index: Arc<NameMap<Arc<str>, usize>>,
    /// Units of the parameters that declare one (for reports; not checked).
    units: Arc<NameMap<Arc<str>, Arc<str>>>,
    /// Domains of the parameters that declare one: every resolved value is checked.
    domains: Arc<NameMap<Arc<str>, Domain>>,
}

impl ParamSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Defines `name` by an expression, which may use parameters defined later.
    pub fn define(&mut self, name: &str, expr_text: &str) -> Result<(), ParamError> {
        self.check_new_name(name)?;
        let expr = parse(expr_text).map_err(|source| ParamError::Syntax {
            name: name.to_string(),
            source,
        })?;
        self.insert(name, expr, expr_text.trim().to_string());
        Ok(())
    }

    /// Defines `name` as `expr`, already parsed from `expr_text` (a reader that parsed the
    /// text to check it hands the tree over rather than having it parsed again).
    pub fn define_parsed(
        &mut self,
        name: &str,
        expr: Expr,
        expr_text: &str,
    ) -> Result<(), ParamError> {
        self.check_new_name(name)?;
        self.insert(name, expr, expr_text.trim().to_string());
        Ok(())
    }

    /// Defines `name` as a number.
    pub fn define_value(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        self.check_new_name(name)?;
        let expr = Expr::Num(value);
        let source = expr.to_string();
        self.insert(name, expr, source);
        Ok(())
    }

    fn check_new_name(&self, name: &str) -> Result<(), ParamError> {
        if self.contains(name) {
            return Err(ParamError::Duplicate { name: name.into() });
        }
        if is_symbol_name(name) {
            Ok(())
        } else {
            Err(ParamError::InvalidName { name: name.into() })
        }
    }

    fn insert(&mut self, name: &str, expr: Expr, source: String) {
        let name: Arc<str> = name.into();
        Arc::make_mut(&mut self.index).insert(name.clone(), self.entries.len());
        self.entries
            .push(Arc::new(Entry::new(name, Definition { expr, source })));
    }

    /// Declares the unit of an existing parameter, as text (`kg`, `m`, `kg m^2`, `Pa`,
    /// `1/K`; empty for a pure number). Units are for people: reports print them, nothing
    /// checks them. Overrides keep the unit.
    pub fn set_unit(&mut self, name: &str, unit: &str) -> Result<(), ParamError> {
        let i = self.position(name)?;
        let name = self.entries[i].name.clone();
        Arc::make_mut(&mut self.units).insert(name, unit.trim().into());
        Ok(())
    }

    /// Declares the domain of an existing parameter: every value it resolves to, with any
    /// override, must lie in it ([`ParamError::OutOfRange`] otherwise). Overrides keep it.
    pub fn set_domain(&mut self, name: &str, domain: Domain) -> Result<(), ParamError> {
        let i = self.position(name)?;
        let name = self.entries[i].name.clone();
        Arc::make_mut(&mut self.domains).insert(name, domain);
        Ok(())
    }

    /// The domain declared for `name`, if any.
    pub fn domain(&self, name: &str) -> Option<Domain> {
        self.domains.get(name).copied()
    }

    /// The unit declared for `name`, if any.
    pub fn unit(&self, name: &str) -> Option<&str> {
        self.units.get(name).map(|u| &**u)
    }

    /// Whether `name` is defined.
    pub fn contains(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// The parameter names in definition order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|e| &*e.name)
    }

    /// The definition of `name`.
    pub fn get(&self, name: &str) -> Option<&Definition> {
        self.index.get(name).map(|&i| &self.entries[i].definition)
    }

    /// The number of parameters.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are no parameters.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Applies a case override to an existing parameter. `Scale` and `Increment` wrap the
    /// current definition, so applying them repeatedly composes.
    pub fn apply(&mut self, name: &str, ov: Override) -> Result<(), ParamError> {
        self.apply_with_source(name, ov, None)
    }

    /// Parses an override (see [`Override::parse`]) and applies it.
    pub fn apply_text(&mut self, name: &str, text: &str) -> Result<(), ParamError> {
        self.position(name)?;
        let ov = Override::parse(text).map_err(|source| ParamError::Syntax {
            name: name.to_string(),
            source,
        })?;
        self.apply_with_source(name, ov, Some(text.trim()))
    }

    fn apply_with_source(
        &mut self,
        name: &str,
        ov: Override,
        text: Option<&str>,
    ) -> Result<(), ParamError> {
        let i = self.position(name)?;
        let def = &self.entries[i].definition;
        let old = Box::new(def.expr.clone());
        let (expr, written) = match ov {
            Override::Expr(e) => (e, true),
            Override::Scale(x) => (Expr::Binary(BinOp::Mul, old, Box::new(x)), false),
            Override::Increment(x) => (Expr::Binary(BinOp::Add, old, Box::new(x)), false),
        };
        let source = match text {
            Some(text) if written => text.to_string(),
            _ => expr.to_string(),
        };
        // only this entry is copied; the others stay shared with the set this was cloned from
        let name = self.entries[i].name.clone();
        self.entries[i] = Arc::new(Entry::new(name, Definition { expr, source }));
        Ok(())
    }

    fn position(&self, name: &str) -> Result<usize, ParamError> {
        self.index
            .get(name)
            .copied()
            .ok_or_else(|| unknown(name, self.names()))
    }

    /// Resolves every parameter to a number. See [`ParamSet::resolve_with_free`].
    pub fn resolve(&self) -> Result<Resolved, ParamError> {
        self.resolve_with_free(&[])
    }

    /// Resolves the parameters, leaving the symbols in `free` (e.g. `f`, a frequency)
    /// unevaluated: parameters that use them, directly or through other parameters, become
    /// expressions in the free symbols only (see [`Resolved::expression`]).
    ///
    /// Definition order does not matter. Problems are reported deterministically: the first
    /// one met when visiting parameters in definition order and, within a definition, its
    /// symbols in sorted order. A free symbol takes precedence over a parameter of the same
    /// name, which is then left out.
    pub fn resolve_with_free(&self, free: &[&str]) -> Result<Resolved, ParamError> {
        let resolved = resolve::resolve(&self.entries, &self.index, free)?;
        for (name, value) in resolved.iter() {
            self.check_range(name, value)?;
        }
        Ok(resolved)
    }

    /// The checks every resolved value passes: not subnormal; and by its declared unit, a
    /// frequency (`Hz`) positive (a frequency enters a stiffness squared, so a negative one
    /// would silently act as its absolute value). Masses are checked where a body reads
    /// them, naming the body.
    fn check_range(&self, name: &str, value: f64) -> Result<(), ParamError> {
        let unit = self.unit(name).unwrap_or_default();
        let why = if value != 0.0 && value.abs() < f64::MIN_POSITIVE {
            Some("subnormal (magnitude below 2.2e-308): not a physical value".to_string())
        } else if unit == "Hz" && value <= 0.0 {
            Some("a frequency must be positive".to_string())
        } else {
            self.domain(name)
                .filter(|domain| !domain.contains(value))
                .map(|domain| format!("outside its declared domain: must be {}", domain.describe()))
        };
        match why {
            Some(why) => Err(ParamError::OutOfRange {
                name: name.to_string(),
                value,
                unit: unit.to_string(),
                why,
            }),
            None => Ok(()),
        }
    }
}

/// An [`ParamError::Unknown`] for `name`, suggesting the closest of `names`: smallest edit
/// distance (at most 2), then longest common prefix (`m31` -> `m3` rather than `m1`), then
/// first in order.
fn unknown<'a>(name: &str, names: impl Iterator<Item = &'a str>) -> ParamError {
    let prefix = |c: &str| {
        name.chars()
            .zip(c.chars())
            .take_while(|(a, b)| a == b)
            .count()
    };
    let mut best: Option<((usize, usize), &str)> = None;
    for candidate in names {
        let key = (
            edit_distance(name, candidate),
            usize::MAX - prefix(candidate),
        );
        if key.0 <= 2 && best.is_none_or(|(k, _)| key < k) {
            best = Some((key, candidate));
        }
    }
    ParamError::Unknown {
        name: name.to_string(),
        suggestion: best.map(|(_, s)| s.to_string()),
    }
}

/// Levenshtein distance between two strings, counted in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distances() {
        assert_eq!(edit_distance("m31", "m3"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "ab"), 2);
        assert_eq!(edit_distance("ab", "ba"), 2);
    }

    #[test]
    fn keyword_arguments() {
        assert_eq!(
            keyword_argument(" scale ( 2*(a) ) ", "scale"),
            Some(" 2*(a) ")
        );
        assert_eq!(keyword_argument("scale(a) + (b)", "scale"), None);
        assert_eq!(keyword_argument("scaled(a)", "scale"), None);
        assert_eq!(keyword_argument("scale", "scale"), None);
    }
}
