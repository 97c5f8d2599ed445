//! Numbers as the command line prints them: never a negative zero (`-0.000`, `-0e0`), which
//! only says that a value rounded to zero from below.

/// `x` as plain-text Rust formatting would print it, with the sign dropped when every
/// printed digit is zero.
fn without_negative_zero(text: String) -> String {
    match text.strip_prefix('-') {
        Some(rest)
            if rest
                .split(['e', 'E'])
                .next()
                .is_some_and(|m| m.chars().all(|c| c == '0' || c == '.')) =>
        {
            rest.to_string()
        }
        _ => text,
    }
}

/// Fixed point with `precision` decimals, right-aligned in `width`.
pub fn fixed(x: f64, precision: usize, width: usize) -> String {
    let text = without_negative_zero(format!("{x:.precision$}"));
    format!("{text:>width$}")
}

/// Scientific with `precision` decimals, right-aligned in `width`.
pub fn sci(x: f64, precision: usize, width: usize) -> String {
    let text = without_negative_zero(format!("{x:.precision$e}"));
    format!("{text:>width$}")
}

/// Shortest exact form for CSV (every digit needed to read the same f64 back).
pub fn csv(x: f64) -> String {
    without_negative_zero(format!("{x:e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_zero_loses_its_sign_and_nothing_else_does() {
        assert_eq!(fixed(-0.0, 3, 0), "0.000");
        assert_eq!(fixed(-0.0001, 3, 0), "0.000");
        assert_eq!(fixed(-0.0006, 3, 0), "-0.001");
        assert_eq!(fixed(-12.5, 1, 6), " -12.5");
        assert_eq!(sci(-0.0, 3, 0), "0.000e0");
        assert_eq!(sci(-1e-300, 3, 0), "-1.000e-300");
        assert_eq!(csv(-0.0), "0e0");
        assert_eq!(csv(-2.5e-7), "-2.5e-7");
        assert_eq!(csv(0.1), "1e-1");
        // the CSV form reads back exactly
        for x in [0.1, 1.0 / 3.0, -6.02214076e23, 5e-324] {
            assert_eq!(csv(x).parse::<f64>().unwrap(), x);
        }
    }
}
