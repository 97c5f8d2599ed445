//! The values a quantity may physically take: a parameter's declared domain, and the
//! domain of each settable field of the model's schema.

use pendkit_expr::number_text;

/// The values a field may physically take. Every domain also excludes non-finite values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Domain {
    /// Any finite number.
    Finite,
    /// Strictly positive: a density, a modulus, a temperature, a length.
    Positive,
    /// Zero or positive: a loss angle, a conductivity, a depth.
    NonNegative,
    /// Strictly between the two bounds: a Poisson's ratio lies in (−1, 0.5).
    Between(f64, f64),
}

impl Domain {
    /// Whether `value` lies in the domain (never for NaN or ±∞).
    pub fn contains(self, value: f64) -> bool {
        value.is_finite()
            && match self {
                Domain::Finite => true,
                Domain::Positive => value > 0.0,
                Domain::NonNegative => value >= 0.0,
                Domain::Between(low, high) => low < value && value < high,
            }
    }

    /// `Ok` when `value` lies in the domain; otherwise the one-line reason, naming the field
    /// `name`, the value with its SI `unit` (`-` for a pure number) and the domain, with
    /// the field's `meaning`: `specific_heat = -486 J/(kg K) is outside its domain:
    /// specific heat must be > 0`. The one wording of every schema's refusals.
    pub fn check(self, name: &str, unit: &str, meaning: &str, value: f64) -> Result<(), String> {
        if self.contains(value) {
            return Ok(());
        }
        let unit = match unit {
            "-" => String::new(),
            unit => format!(" {unit}"),
        };
        if !value.is_finite() {
            return Err(format!(
                "{name} = {}{unit} is not a finite number",
                number_text(value)
            ));
        }
        Err(format!(
            "{name} = {}{unit} is outside its domain: {meaning} must be {}",
            number_text(value),
            self.describe()
        ))
    }

    /// The domain as an error message, a table or a file states it: `finite`, `> 0`,
    /// `>= 0`, `in (-1, 0.5)` (what [`Domain::from_str`](std::str::FromStr) reads back).
    pub fn describe(self) -> String {
        match self {
            Domain::Finite => "finite".to_string(),
            Domain::Positive => "> 0".to_string(),
            Domain::NonNegative => ">= 0".to_string(),
            Domain::Between(low, high) => {
                format!("in ({}, {})", number_text(low), number_text(high))
            }
        }
    }
}

impl std::str::FromStr for Domain {
    type Err = String;

    /// Reads `finite`, `> 0`, `>= 0` or `in (low, high)` (the `in` may be left out).
    fn from_str(text: &str) -> Result<Domain, String> {
        let compact: String = text.split_whitespace().collect();
        let bounds = compact.strip_prefix("in").unwrap_or(&compact);
        let open = bounds
            .strip_prefix('(')
            .and_then(|b| b.strip_suffix(')'))
            .and_then(|b| b.split_once(','));
        match (compact.as_str(), open) {
            ("finite", _) => Ok(Domain::Finite),
            (">0", _) => Ok(Domain::Positive),
            (">=0", _) => Ok(Domain::NonNegative),
            (_, Some((low, high))) => {
                let bound = |b: &str| pendkit_expr::number_literal(b).map_err(|e| e.to_string());
                let (low, high) = (bound(low)?, bound(high)?);
                if low < high {
                    Ok(Domain::Between(low, high))
                } else {
                    Err(format!(
                        "an interval needs low < high, got ({}, {})",
                        number_text(low),
                        number_text(high)
                    ))
                }
            }
            _ => Err(format!(
                "unknown domain '{text}' (finite, > 0, >= 0, or in (low, high))"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_domain_reads_back_what_it_describes() {
        for domain in [
            Domain::Finite,
            Domain::Positive,
            Domain::NonNegative,
            Domain::Between(-1.0, 0.5),
        ] {
            assert_eq!(domain.describe().parse::<Domain>(), Ok(domain));
        }
        assert_eq!("(0, 1)".parse::<Domain>(), Ok(Domain::Between(0.0, 1.0)));
        assert!("in (1, 0)".parse::<Domain>().is_err());
        assert!("< 0".parse::<Domain>().is_err());
    }
}
