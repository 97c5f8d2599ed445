//! Number literals as users write them (`2.5`, `.5`, `1e-3`, `-4E+2`): read to an `f64` only
//! when the `f64` is the number written, to within rounding. Every reader of numbers typed by
//! a user (expressions, case and suspension files, command-line options, CSV files) goes
//! through [`number_literal`], so a literal that does not fit an `f64` is named where it is
//! written instead of silently becoming 0 or infinity and failing later, or not at all.

/// Why a number literal is refused: each message is one line and quotes the literal.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NumberError {
    /// The text is not a decimal number.
    #[error("'{0}' is not a number")]
    NotANumber(String),
    /// `inf`, `infinity` or `nan` (in any case): not a value any quantity can take.
    #[error("'{0}' is not a finite number")]
    NotFinite(String),
    /// The literal's magnitude is above the largest `f64` (about 1.8e308): it would read as
    /// infinity.
    #[error("number '{0}' is too large (overflows to infinity; the largest is 1.8e308)")]
    Overflow(String),
    /// A nonzero literal whose magnitude is below the smallest normal `f64` (about
    /// 2.2e-308): it would read as 0, or as a subnormal number that has lost most of its
    /// digits.
    #[error(
        "number '{0}' is too small (a nonzero number below 2.2e-308 underflows to 0 or to a subnormal that has lost digits)"
    )]
    Underflow(String),
}

/// Reads a decimal number literal (surrounding white space ignored; a leading sign,
/// a fraction and an exponent allowed, as Rust's `f64` parser takes them) and refuses one whose
/// value an `f64` cannot hold: `inf`/`nan`, a literal that overflows to infinity, and a
/// nonzero literal that underflows to zero or to a subnormal number. Zero written any way
/// (`0`, `-0.0`, `0e-999`) is zero.
///
/// ```
/// use pendkit_expr::{NumberError, number_literal};
/// assert_eq!(number_literal(" 1e-3 "), Ok(1e-3));
/// assert_eq!(number_literal("0e-999"), Ok(0.0));
/// assert!(matches!(number_literal("1e-400"), Err(NumberError::Underflow(_))));
/// assert!(matches!(number_literal("1e400"), Err(NumberError::Overflow(_))));
/// assert!(matches!(number_literal("nan"), Err(NumberError::NotFinite(_))));
/// ```
pub fn number_literal(text: &str) -> Result<f64, NumberError> {
    let text = text.trim();
    let Ok(value) = text.parse::<f64>() else {
        return Err(NumberError::NotANumber(text.to_string()));
    };
    // Rust's parser also takes `inf`, `infinity` and `nan`: the only spellings without a
    // digit
    if !text.bytes().any(|b| b.is_ascii_digit()) {
        return Err(NumberError::NotFinite(text.to_string()));
    }
    if value.is_infinite() {
        return Err(NumberError::Overflow(text.to_string()));
    }
    // the digits before the exponent say whether the literal is zero
    let mantissa = text.split(['e', 'E']).next().unwrap_or(text);
    let written_nonzero = mantissa.bytes().any(|b| (b'1'..=b'9').contains(&b));
    if written_nonzero && !value.is_normal() {
        return Err(NumberError::Underflow(text.to_string()));
    }
    Ok(value)
}

/// `x` for a message: every digit needed to read it back, in plain decimals from 10⁻⁴ up
/// to 10⁷ and in scientific notation outside (Rust's `{}` would print 1e-300 as 301
/// decimals).
///
/// ```
/// use pendkit_expr::number_text;
/// assert_eq!(number_text(0.3085), "0.3085");
/// assert_eq!(number_text(1e-300), "1e-300");
/// assert_eq!(number_text(-2.5e12), "-2.5e12");
/// assert_eq!(number_text(0.0), "0");
/// ```
pub fn number_text(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn representable_literals_read_as_rust_reads_them() {
        for text in [
            "0",
            "-0.0",
            "0e-999",
            "000.000e+5000",
            "1",
            "+2.5",
            ".5",
            "5.",
            "1e-3",
            "-4E+2",
            // the extremes of the normal range (f64::MAX and f64::MIN_POSITIVE, printed by Rust)
            "1.7976931348623157e308",
            "2.2250738585072014e-308",
        ] {
            assert_eq!(
                number_literal(text),
                Ok(text.parse::<f64>().unwrap()),
                "{text}"
            );
        }
    }

    #[test]
    fn literals_an_f64_cannot_hold_are_refused() {
        for text in ["1e400", "-1e309", "1.8e308"] {
            assert!(
                matches!(number_literal(text), Err(NumberError::Overflow(_))),
                "{text}"
            );
        }
        // below f64::MIN_POSITIVE: subnormal (4.9e-324 is the smallest) or zero
        for text in ["1e-400", "-1e-400", "4.9e-324", "1e-310", "0.0001e-305"] {
            assert!(
                matches!(number_literal(text), Err(NumberError::Underflow(_))),
                "{text}"
            );
        }
        for text in ["inf", "-inf", "NaN", "infinity", "+Infinity"] {
            assert!(
                matches!(number_literal(text), Err(NumberError::NotFinite(_))),
                "{text}"
            );
        }
        for text in ["", "1e", "e5", "1,5", "0x10", "1 2", "--1"] {
            assert!(
                matches!(number_literal(text), Err(NumberError::NotANumber(_))),
                "{text}"
            );
        }
    }
}
