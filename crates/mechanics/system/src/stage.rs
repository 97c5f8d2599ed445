//! Calculation stages (docs/physics.md §2): each adds terms or processing to the one before.

use std::fmt;
use std::str::FromStr;

/// A calculation stage of the source's Mathematica toolkit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// Gravity, springs and wire stretch; equilibrium, real stiffness, modes.
    S0A,
    /// Stage 0A with dissipation dilution: damping, transfer functions, noise.
    S0B,
    /// + wire torsion.
    S1A,
    /// + wire bending.
    S1B,
    /// + wire extra stretch.
    S2,
}

impl Stage {
    /// All stages in order.
    pub const ALL: [Stage; 5] = [Stage::S0A, Stage::S0B, Stage::S1A, Stage::S1B, Stage::S2];

    /// The stage's name as the source writes it (`0A`, `0B`, `1A`, `1B`, `2`).
    pub fn name(self) -> &'static str {
        match self {
            Stage::S0A => "0A",
            Stage::S0B => "0B",
            Stage::S1A => "1A",
            Stage::S1B => "1B",
            Stage::S2 => "2",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A stage name that is not one of `0a 0b 1a 1b 2`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown stage '{0}' (expected one of 0a, 0b, 1a, 1b, 2)")]
pub struct UnknownStage(pub String);

impl FromStr for Stage {
    type Err = UnknownStage;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stage::ALL
            .into_iter()
            .find(|st| st.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownStage(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_order() {
        for st in Stage::ALL {
            assert_eq!(st.name().to_lowercase().parse::<Stage>().unwrap(), st);
        }
        assert!(Stage::S0A < Stage::S0B && Stage::S1B < Stage::S2);
        assert!("3".parse::<Stage>().is_err());
    }
}
