//! Damping tags (docs/physics.md §2): each term carries a tag, and each tag a complex multiplier
//! ε'(f) + i ε''(f) of its tension-off stiffness, a function of frequency f in Hz.

use std::collections::BTreeMap;

use pendkit_expr::Compiled;

/// ε'(f) + i ε''(f) of one tag, as compiled expressions whose variable 0 is f (Hz).
#[derive(Clone, Debug)]
pub struct TagDamping {
    /// Real multiplier ε'(f) (1 for ordinary elasticity).
    pub real: Compiled,
    /// Imaginary multiplier ε''(f) (the loss angle for structural damping).
    pub imag: Compiled,
}

impl TagDamping {
    /// The multiplier (ε', ε'') at frequency `f_hz`.
    pub fn at(&self, f_hz: f64) -> (f64, f64) {
        let f = [f_hz];
        (self.real.eval(&f), self.imag.eval(&f))
    }
}

/// The damping multipliers of a model, by tag; a tag not listed has ε' = 1, ε'' = 0.
#[derive(Clone, Debug, Default)]
pub struct Damping {
    tags: BTreeMap<String, TagDamping>,
}

impl Damping {
    /// Sets (or replaces) the multipliers of `tag`.
    pub fn set(&mut self, tag: &str, damping: TagDamping) {
        self.tags.insert(tag.to_string(), damping);
    }

    /// The multiplier (ε', ε'') of `tag` at `f_hz`.
    pub fn at(&self, tag: &str, f_hz: f64) -> (f64, f64) {
        self.tags.get(tag).map_or((1.0, 0.0), |d| d.at(f_hz))
    }

    /// The multipliers of `tag`, if it has explicit ones (a tag not listed has ε' = 1,
    /// ε'' = 0 at every frequency).
    pub fn get(&self, tag: &str) -> Option<&TagDamping> {
        self.tags.get(tag)
    }

    /// Tags with explicit multipliers.
    pub fn tags(&self) -> impl Iterator<Item = &str> {
        self.tags.keys().map(String::as_str)
    }
}
