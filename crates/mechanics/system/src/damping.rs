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
    /// The multiplier (ε', ε'') at frequency `f_hz`. Both are expressions of `f` alone;
    /// one that reads more variables gives NaN, which every calculation refuses
    /// (`pendkit_dynamics::check_damping`).
    pub fn at(&self, f_hz: f64) -> (f64, f64) {
        let f = [f_hz];
        let value = |e: &Compiled| e.eval(&f).unwrap_or(f64::NAN);
        (value(&self.real), value(&self.imag))
    }
}

/// The damping multipliers of a model, by tag; a tag not listed has ε' = 1, ε'' = 0.
#[derive(Clone, Debug, Default)]
pub struct Damping {
    tags: BTreeMap<String, TagDamping>,
    /// Tags whose terms sit at their own temperature (K) for thermal noise.
    temperatures: BTreeMap<String, f64>,
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

    /// Sets the noise temperature (K) of the terms tagged `tag` (their fluctuation–
    /// dissipation share is 4 k_B T_tag/ω times their loss); others use the model's.
    pub fn set_temperature(&mut self, tag: &str, kelvin: f64) {
        self.temperatures.insert(tag.to_string(), kelvin);
    }

    /// The noise temperature (K) of `tag`, if it has its own.
    pub fn temperature(&self, tag: &str) -> Option<f64> {
        self.temperatures.get(tag).copied()
    }

    /// Tags with explicit multipliers.
    pub fn tags(&self) -> impl Iterator<Item = &str> {
        self.tags.keys().map(String::as_str)
    }
}
